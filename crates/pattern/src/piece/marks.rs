//! Marks on a piece: notches cut through the allowance at match marks, drill holes, drawn
//! reference points, internal lines, and the checks on the grain line.

use super::edges::OutlineEdges;
use super::outline::{Outline, WELD};
use super::{MarkKind, NotchStyle, PatternError, PieceInput, PieceOptions, invalid, non_finite};
use crate::poly;
use flatcut_geom::DVec2;

/// Depth of a notch on an edge cut raw (mm): a nick a cutter sees, shallow enough not to show
/// on the top piece of a lapped seam.
const RAW_NICK_MM: f64 = 1.0;

/// The marks of a piece as they are cut and drawn.
pub(super) struct PlacedMarks {
    /// Notch strokes (open polylines through the allowance).
    pub notches: Vec<Vec<DVec2>>,
    /// The name of each notch (empty when unnamed), in the order of `notches`.
    pub notch_names: Vec<String>,
    /// Drill holes: centre and diameter.
    pub drills: Vec<(DVec2, f64)>,
    /// Reference points.
    pub points: Vec<DVec2>,
}

/// Places every mark: notches where their vertex meets the sew line, drill holes (which must lie
/// inside the sew line) and reference points.
pub(super) fn place_marks(
    input: &PieceInput,
    outline: &Outline,
    edges: &OutlineEdges,
    sew: &[DVec2],
    cut: &[DVec2],
    opts: &PieceOptions,
) -> Result<PlacedMarks, PatternError> {
    let mut out = PlacedMarks {
        notches: Vec::new(),
        notch_names: Vec::new(),
        drills: Vec::new(),
        points: Vec::new(),
    };
    for (k, m) in input.marks.iter().enumerate() {
        match m.kind {
            MarkKind::Notch => {
                let v = edges.mark_vertex[k]
                    .map(|i| outline.points[i])
                    .unwrap_or(m.pos);
                out.notches.push(notch(sew, cut, v, opts));
                out.notch_names
                    .push(input.mark_names.get(k).cloned().unwrap_or_default());
            }
            MarkKind::Drill => {
                if !poly::contains(sew, m.pos) {
                    return Err(invalid(
                        &input.name,
                        format!(
                            "drill hole {k} at ({:.2}, {:.2}) lies outside the piece",
                            m.pos.x, m.pos.y
                        ),
                    ));
                }
                out.drills.push((m.pos, opts.drill_diameter));
            }
            MarkKind::Point => out.points.push(m.pos),
        }
    }
    Ok(out)
}

/// The notch at the sew-line point nearest `v`: a slit or a V from the cut line inward along the
/// outward normal (the bisector at a vertex), as deep as asked but at most 3/4 of the allowance.
fn notch(sew: &[DVec2], cut: &[DVec2], v: DVec2, opts: &PieceOptions) -> Vec<DVec2> {
    let (i, t, p, _) = poly::nearest_on_closed(sew, v);
    let ns = sew.len();
    let (a, b) = (sew[i], sew[(i + 1) % ns]);
    let tangent = if t > 1e-9 && t < 1.0 - 1e-9 {
        (b - a).normalize_or_zero()
    } else {
        // at a vertex: bisect the two edges
        let j = if t <= 1e-9 { i } else { (i + 1) % ns };
        let (pa, pb, pc) = (sew[(j + ns - 1) % ns], sew[j], sew[(j + 1) % ns]);
        ((pb - pa).normalize_or_zero() + (pc - pb).normalize_or_zero()).normalize_or_zero()
    };
    let out = DVec2::new(tangent.y, -tangent.x);
    let reach = poly::ray_hit(cut, p - out * 1e-9, out).unwrap_or(0.0);
    let at_cut = p + out * reach;
    // a notch on an edge cut raw (no allowance) is only nicked into the piece
    let depth = if reach > 1e-6 {
        opts.notch_depth.min(0.75 * reach)
    } else {
        opts.notch_depth.min(RAW_NICK_MM)
    };
    let tip = at_cut - out * depth;
    match opts.notch_style {
        NotchStyle::Slit => vec![at_cut, tip],
        NotchStyle::V => {
            let h = tangent * (opts.notch_width * 0.5);
            vec![at_cut + h, tip, at_cut - h]
        }
    }
}

/// The internal lines, each checked (finite, two distinct points, inside the cut line) and
/// simplified within the chord tolerance.
pub(super) fn internal_lines(
    input: &PieceInput,
    cut: &[DVec2],
    chord_tol: f64,
) -> Result<Vec<Vec<DVec2>>, PatternError> {
    let name = &input.name;
    let mut lines = Vec::with_capacity(input.lines.len());
    for (k, l) in input.lines.iter().enumerate() {
        if l.iter().any(|p| !flatcut_geom::finite2(*p)) {
            return Err(non_finite(name, &format!("internal line {}", k + 1)));
        }
        let mut l = l.clone();
        l.dedup_by(|a, b| a.distance(*b) < WELD);
        if l.len() < 2 {
            return Err(invalid(
                name,
                format!("internal line {} has fewer than two distinct points", k + 1),
            ));
        }
        if let Some(p) = l.iter().find(|p| {
            !poly::contains(cut, **p) && poly::nearest_on_closed(cut, **p).2.distance(**p) > WELD
        }) {
            return Err(invalid(
                name,
                format!(
                    "internal line {} leaves the piece at ({:.2}, {:.2})",
                    k + 1,
                    p.x,
                    p.y
                ),
            ));
        }
        lines.push(simplify_line(&l, chord_tol));
    }
    Ok(lines)
}

/// The inner sew lines (a folded dart's legs), each of two distinct finite points at least,
/// simplified within the chord tolerance.
pub(super) fn inner_sew_lines(
    input: &PieceInput,
    chord_tol: f64,
) -> Result<Vec<Vec<DVec2>>, PatternError> {
    let mut out = Vec::with_capacity(input.sew_lines.len());
    for (k, l) in input.sew_lines.iter().enumerate() {
        let mut l = l.clone();
        l.dedup_by(|a, b| a.distance(*b) < WELD);
        if l.len() < 2 || l.iter().any(|p| !flatcut_geom::finite2(*p)) {
            return Err(invalid(
                &input.name,
                format!(
                    "inner sew line {} has fewer than two distinct finite points",
                    k + 1
                ),
            ));
        }
        out.push(simplify_line(&l, chord_tol));
    }
    Ok(out)
}

/// Refuses a grain line with a non-finite end or of zero length.
pub(super) fn check_grain(input: &PieceInput) -> Result<(), PatternError> {
    if let Some((a, b)) = input.grain {
        if !(flatcut_geom::finite2(a) && flatcut_geom::finite2(b)) {
            return Err(non_finite(&input.name, "grain line"));
        }
        if a.distance(b) < WELD {
            return Err(invalid(&input.name, "grain line has zero length".into()));
        }
    }
    Ok(())
}

/// Drops the points of an open polyline that lie within `tol` of the simplified line
/// (Ramer–Douglas–Peucker, geo's implementation): lines carried through a map arrive sampled
/// every millimetre, and a straight ruling needs only its ends.
fn simplify_line(l: &[DVec2], tol: f64) -> Vec<DVec2> {
    use geo::Simplify;
    let ls: geo::LineString<f64> = l.iter().map(|p| geo::Coord { x: p.x, y: p.y }).collect();
    ls.simplify(tol)
        .0
        .iter()
        .map(|c| DVec2::new(c.x, c.y))
        .collect()
}
