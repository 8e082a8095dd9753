//! A pattern piece as a cutting room uses it: the fitted sew line, the cut line with seam
//! allowance, notches at match marks, drill holes, the grain line and a label.
//!
//! Input is a flattened boundary (closed polyline in mm, counter-clockwise) with marks; the
//! piece is built by [`Piece::build`] and turned into a [`Drawing`] by [`Piece::to_drawing`].
//! Seam segments: the boundary is divided at the marks that carry a `boundary_index`, in
//! boundary order; segment `j` runs from the `j`-th such mark to the next (with none, the whole
//! boundary is segment 0). `seam_widths` gives one width per segment (or one for all).

use crate::PatternError;
use crate::drawing::{Drawing, Layer, PieceInfo, Stroke, StrokeKind};
use crate::fit::{self, PathSeg};
use crate::font;
use crate::poly;
use crate::seam::{self, CornerStyle, SeamFailure};
use flatcut_geom::{Aabb2, DVec2};
use serde::{Deserialize, Serialize};

/// What a mark is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MarkKind {
    /// A match mark on the boundary: cut as a notch so pieces are sewn in register.
    Notch,
    /// A drill hole (pocket corners, dart ends): punched/cut as a small circle.
    Drill,
    /// A drawn reference point (button, placement): a small cross on the draw layer.
    Point,
}

/// A mark on the piece.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mark {
    pub kind: MarkKind,
    /// Position in the piece's flat frame (mm).
    pub pos: DVec2,
    /// Index of the outline vertex the mark sits on, when it lies on the boundary (notches,
    /// seam ends). Notches without it snap to the nearest outline vertex.
    pub boundary_index: Option<usize>,
}

/// Label content.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LabelInfo {
    pub name: String,
    pub size: String,
    pub material: String,
    pub quantity: u32,
    /// One-line distortion summary from the flattening report (e.g. "AREA 1.2% MAX 3.4%").
    pub distortion: Option<String>,
}

/// Everything a piece is built from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PieceInput {
    /// Piece name; used in ids and error messages.
    pub name: String,
    /// Sew line, closed (first point not repeated), counter-clockwise, mm.
    pub outline: Vec<DVec2>,
    pub marks: Vec<Mark>,
    /// Drawn internal lines (stitch lines, placement lines, dart legs), open polylines in the
    /// flat frame (mm), each of at least two points.
    #[serde(default)]
    pub lines: Vec<Vec<DVec2>>,
    /// Grain line as two points in the flat frame (direction carried through the map).
    pub grain: Option<(DVec2, DVec2)>,
    /// Seam width per seam segment (see the module doc); empty = the default width everywhere,
    /// one value = that width everywhere; 0 on a folded edge.
    pub seam_widths: Vec<f64>,
    pub corner_style: CornerStyle,
    pub label: LabelInfo,
    /// Names of the notch marks, by mark index (a mating seam's notch carries the seam's name
    /// into the notch's id); marks past its end, and empty names, are unnamed.
    #[serde(default)]
    pub mark_names: Vec<String>,
}

impl PieceInput {
    /// A piece with an outline only; everything else default.
    pub fn new(name: impl Into<String>, outline: Vec<DVec2>) -> Self {
        let name = name.into();
        Self {
            label: LabelInfo {
                name: name.clone(),
                quantity: 1,
                ..LabelInfo::default()
            },
            name,
            outline,
            marks: Vec::new(),
            lines: Vec::new(),
            grain: None,
            seam_widths: Vec::new(),
            corner_style: CornerStyle::default(),
            mark_names: Vec::new(),
        }
    }
}

/// Notch shape.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NotchStyle {
    /// A single slit perpendicular to the cut line (knife cutters).
    #[default]
    Slit,
    /// A V (laser, scissors).
    V,
}

/// Options of [`Piece::build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PieceOptions {
    /// Outline fitting tolerance (mm).
    pub fit_tol: f64,
    /// Chordal tolerance when curves become polylines (mm).
    pub chord_tol: f64,
    /// Turn (degrees) above which a boundary vertex is kept as a corner.
    pub corner_deg: f64,
    /// Seam width used when `seam_widths` is empty (mm).
    pub default_seam: f64,
    /// Mitre limit in widths.
    pub mitre_limit: f64,
    pub notch_style: NotchStyle,
    /// Notch depth (mm), clipped to 3/4 of the local allowance.
    pub notch_depth: f64,
    /// Opening of a V notch (mm).
    pub notch_width: f64,
    /// Drill-hole diameter (mm).
    pub drill_diameter: f64,
    /// Maximum label cap height (mm); smaller when the piece is small.
    pub label_height: f64,
}

impl PieceOptions {
    /// 0.1 mm: below what knife or laser reproduces, well above mesh facet noise.
    pub const DEFAULT_FIT_TOL: f64 = 0.1;
    /// 0.02 mm chordal error on exported polylines.
    pub const DEFAULT_CHORD_TOL: f64 = 0.02;
    /// 10 mm: the usual garment seam allowance (3/8").
    pub const DEFAULT_SEAM: f64 = 10.0;
    /// 4 mm notch: visible on the cut piece, short of a 10 mm seam.
    pub const DEFAULT_NOTCH_DEPTH: f64 = 4.0;
    /// 2 mm V opening.
    pub const DEFAULT_NOTCH_WIDTH: f64 = 2.0;
    /// 3 mm drill (a common awl/punch size).
    pub const DEFAULT_DRILL_DIAMETER: f64 = 3.0;
    /// 6 mm cap height reads well on fabric and leather.
    pub const DEFAULT_LABEL_HEIGHT: f64 = 6.0;
    pub const DEFAULT: Self = Self {
        fit_tol: Self::DEFAULT_FIT_TOL,
        chord_tol: Self::DEFAULT_CHORD_TOL,
        corner_deg: fit::DEFAULT_CORNER_DEG,
        default_seam: Self::DEFAULT_SEAM,
        mitre_limit: seam::DEFAULT_MITRE_LIMIT,
        notch_style: NotchStyle::Slit,
        notch_depth: Self::DEFAULT_NOTCH_DEPTH,
        notch_width: Self::DEFAULT_NOTCH_WIDTH,
        drill_diameter: Self::DEFAULT_DRILL_DIAMETER,
        label_height: Self::DEFAULT_LABEL_HEIGHT,
    };
    pub fn with_fit_tol(mut self, v: f64) -> Self {
        self.fit_tol = v;
        self
    }
    pub fn with_chord_tol(mut self, v: f64) -> Self {
        self.chord_tol = v;
        self
    }
    pub fn with_default_seam(mut self, v: f64) -> Self {
        self.default_seam = v;
        self
    }
    pub fn with_notch_style(mut self, v: NotchStyle) -> Self {
        self.notch_style = v;
        self
    }
    pub fn with_notch_depth(mut self, v: f64) -> Self {
        self.notch_depth = v;
        self
    }
    pub fn with_corner_deg(mut self, v: f64) -> Self {
        self.corner_deg = v;
        self
    }
    pub fn with_label_height(mut self, v: f64) -> Self {
        self.label_height = v;
        self
    }
}

impl Default for PieceOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A built piece, in its own flat frame (mm, y up).
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    pub name: String,
    /// Fitted sew line: lines, arcs, cubics, closed.
    pub sew: Vec<PathSeg>,
    /// Sew line flattened within the chord tolerance (CCW).
    pub sew_polyline: Vec<DVec2>,
    /// Cut line (sew line plus allowance), CCW, closed.
    pub cut: Vec<DVec2>,
    /// Notch strokes (open polylines cut through the allowance).
    pub notches: Vec<Vec<DVec2>>,
    /// The name of each notch (empty when unnamed), in the order of `notches`.
    pub notch_names: Vec<String>,
    /// Drill holes: centre and diameter.
    pub drills: Vec<(DVec2, f64)>,
    /// Reference points (drawn crosses).
    pub points: Vec<DVec2>,
    /// Internal lines (stitch and placement lines), drawn, open.
    pub lines: Vec<Vec<DVec2>>,
    /// Grain line end points.
    pub grain: Option<(DVec2, DVec2)>,
    pub label: LabelInfo,
    /// Label text strokes (open polylines).
    pub label_strokes: Vec<Vec<DVec2>>,
    chord_tol: f64,
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

/// A piece name made safe for element ids and file names: ASCII letters, digits, `-` and `_`
/// kept, everything else `_`; an empty name is `piece`. Two pieces of a design must not share
/// it (the facade refuses such a design).
pub fn safe_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() { "piece".into() } else { s }
}

impl Piece {
    /// Builds a piece; errors name the piece and what is wrong.
    pub fn build(input: &PieceInput, opts: &PieceOptions) -> Result<Piece, PatternError> {
        let name = input.name.clone();
        let inv = |reason: String| PatternError::InvalidInput {
            piece: name.clone(),
            reason,
        };
        let nonfinite = |what: &str| PatternError::NonFinite {
            piece: name.clone(),
            what: what.into(),
        };
        if !input.outline.iter().all(|p| flatcut_geom::finite2(*p)) {
            return Err(nonfinite("outline"));
        }
        if !input.marks.iter().all(|m| flatcut_geom::finite2(m.pos)) {
            return Err(nonfinite("marks"));
        }
        if input.seam_widths.iter().any(|w| !w.is_finite()) {
            return Err(nonfinite("seam widths"));
        }
        for (what, v) in [
            ("fit tolerance", opts.fit_tol),
            ("chord tolerance", opts.chord_tol),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(inv(format!("{what} must be positive, got {v}")));
            }
        }
        // 1. clean outline: weld duplicates, keep an index map for boundary marks
        let weld = flatcut_geom::Tolerances::DEFAULT_WELD_MM;
        let mut outline: Vec<DVec2> = Vec::with_capacity(input.outline.len());
        let mut map = vec![0usize; input.outline.len()];
        for (i, &q) in input.outline.iter().enumerate() {
            if outline.last().is_none_or(|l: &DVec2| l.distance(q) > weld) {
                outline.push(q);
            }
            map[i] = outline.len() - 1;
        }
        while outline.len() > 1 && outline[0].distance(outline[outline.len() - 1]) <= weld {
            outline.pop();
            let last = outline.len();
            map.iter_mut().for_each(|m| {
                if *m >= last {
                    *m = 0
                }
            });
        }
        if outline.len() < 3 {
            return Err(PatternError::DegenerateOutline {
                piece: name.clone(),
                reason: format!("{} distinct points, need at least 3", outline.len()),
            });
        }
        if let Some((a, b, x)) = poly::first_self_intersection(&outline) {
            return Err(PatternError::SelfIntersecting {
                piece: name.clone(),
                edge_a: a,
                edge_b: b,
                x: x.x,
                y: x.y,
            });
        }
        let area = poly::signed_area(&outline);
        if area.abs() < weld * weld {
            return Err(PatternError::DegenerateOutline {
                piece: name.clone(),
                reason: "zero area".into(),
            });
        }
        let n = outline.len();
        if area < 0.0 {
            // accept clockwise input: reverse, keeping vertex 0 first
            outline[1..].reverse();
            map.iter_mut().for_each(|m| {
                if *m != 0 {
                    *m = n - *m
                }
            });
        }
        if let Some((a, b, x)) = poly::first_self_intersection(&outline) {
            return Err(PatternError::SelfIntersecting {
                piece: name.clone(),
                edge_a: a,
                edge_b: b,
                x: x.x,
                y: x.y,
            });
        }
        // 2. boundary marks → vertex indices (corners of the fit, seam segment ends)
        let mut mark_vertex: Vec<Option<usize>> = Vec::with_capacity(input.marks.len());
        for (k, m) in input.marks.iter().enumerate() {
            let v = match (m.boundary_index, m.kind) {
                (Some(i), _) if i < map.len() => Some(map[i]),
                (Some(i), _) => {
                    return Err(inv(format!("mark {k}: boundary index {i} out of range")));
                }
                (None, MarkKind::Notch) => {
                    let (i, t, _, _) = poly::nearest_on_closed(&outline, m.pos);
                    Some(if t < 0.5 { i } else { (i + 1) % n })
                }
                _ => None,
            };
            mark_vertex.push(v);
        }
        let mut seam_marks: Vec<usize> = input
            .marks
            .iter()
            .zip(&mark_vertex)
            .filter(|(m, _)| m.boundary_index.is_some())
            .filter_map(|(_, v)| *v)
            .collect();
        seam_marks.sort_unstable();
        seam_marks.dedup();
        let n_seg = seam_marks.len().max(1);
        let widths: Vec<f64> = match input.seam_widths.len() {
            0 => vec![opts.default_seam; n_seg],
            1 => vec![input.seam_widths[0]; n_seg],
            k if k == n_seg => input.seam_widths.clone(),
            k => {
                return Err(inv(format!(
                    "{k} seam widths for {n_seg} seam segments (between boundary marks)"
                )));
            }
        };
        if let Some(w) = widths.iter().find(|w| **w < 0.0 || !w.is_finite()) {
            return Err(PatternError::AllowanceTooLarge {
                piece: name.clone(),
                reason: format!("negative width {w} mm"),
            });
        }
        let seg_of_vertex = |v: usize| -> usize {
            if seam_marks.is_empty() {
                return 0;
            }
            match seam_marks.iter().rposition(|&m| m <= v) {
                Some(j) => j,
                None => seam_marks.len() - 1,
            }
        };
        // 3. fit
        let forced: Vec<usize> = mark_vertex.iter().filter_map(|v| *v).collect();
        let corners = fit::find_corners(&outline, &forced, opts.corner_deg);
        let spans = fit::fit_closed_spans(&outline, &corners, opts.fit_tol);
        // 4. flatten with per-edge widths
        let mut sew_poly: Vec<DVec2> = Vec::new();
        let mut edge_w: Vec<f64> = Vec::new();
        let mut sew: Vec<PathSeg> = Vec::new();
        for (start, segs) in &spans {
            let w = widths[seg_of_vertex(*start)];
            let mut pts = Vec::new();
            for s in segs {
                s.flatten(opts.chord_tol, &mut pts);
            }
            pts.pop(); // the next span starts there
            edge_w.extend(std::iter::repeat_n(w, pts.len()));
            sew_poly.extend(pts);
            sew.extend(segs.iter().copied());
        }
        let sew_poly_clean = poly::dedup_closed(&sew_poly, weld);
        if sew_poly_clean.len() != sew_poly.len() {
            // keep widths aligned: rebuild by nearest original edge
            let mut w2 = Vec::with_capacity(sew_poly_clean.len());
            for q in &sew_poly_clean {
                let (i, _, _, _) = poly::nearest_on_closed(&sew_poly, *q);
                w2.push(edge_w[i]);
            }
            edge_w = w2;
        }
        let sew_poly = sew_poly_clean;
        if let Some((a, b, x)) = poly::first_self_intersection(&sew_poly) {
            return Err(PatternError::SelfIntersecting {
                piece: name.clone(),
                edge_a: a,
                edge_b: b,
                x: x.x,
                y: x.y,
            });
        }
        // 5. allowance
        let cut = match seam::allowance(
            &sew_poly,
            &edge_w,
            input.corner_style,
            opts.mitre_limit,
            opts.chord_tol.max(1e-6),
        ) {
            Ok(r) => r.cut,
            Err(SeamFailure::TooLarge(reason)) => {
                return Err(PatternError::AllowanceTooLarge {
                    piece: name,
                    reason,
                });
            }
            Err(SeamFailure::Engine(reason)) => {
                return Err(PatternError::OffsetFailed {
                    piece: name,
                    reason,
                });
            }
        };
        // 6. marks
        let mut notches = Vec::new();
        let mut notch_names = Vec::new();
        let mut drills = Vec::new();
        let mut points = Vec::new();
        for (k, m) in input.marks.iter().enumerate() {
            match m.kind {
                MarkKind::Notch => {
                    let v = mark_vertex[k].map(|i| outline[i]).unwrap_or(m.pos);
                    let (i, t, p, _) = poly::nearest_on_closed(&sew_poly, v);
                    let ns = sew_poly.len();
                    let (a, b) = (sew_poly[i], sew_poly[(i + 1) % ns]);
                    let tangent = if t > 1e-9 && t < 1.0 - 1e-9 {
                        (b - a).normalize_or_zero()
                    } else {
                        // at a vertex: bisect the two edges
                        let j = if t <= 1e-9 { i } else { (i + 1) % ns };
                        let (pa, pb, pc) = (
                            sew_poly[(j + ns - 1) % ns],
                            sew_poly[j],
                            sew_poly[(j + 1) % ns],
                        );
                        ((pb - pa).normalize_or_zero() + (pc - pb).normalize_or_zero())
                            .normalize_or_zero()
                    };
                    let out = DVec2::new(tangent.y, -tangent.x);
                    let reach = poly::ray_hit(&cut, p - out * 1e-9, out).unwrap_or(0.0);
                    let at_cut = p + out * reach;
                    let depth = if reach > 1e-6 {
                        opts.notch_depth.min(0.75 * reach)
                    } else {
                        opts.notch_depth
                    };
                    let tip = at_cut - out * depth;
                    notches.push(match opts.notch_style {
                        NotchStyle::Slit => vec![at_cut, tip],
                        NotchStyle::V => {
                            let h = tangent * (opts.notch_width * 0.5);
                            vec![at_cut + h, tip, at_cut - h]
                        }
                    });
                    notch_names.push(input.mark_names.get(k).cloned().unwrap_or_default());
                }
                MarkKind::Drill => {
                    if !poly::contains(&sew_poly, m.pos) {
                        return Err(inv(format!(
                            "drill hole {k} at ({:.2}, {:.2}) lies outside the piece",
                            m.pos.x, m.pos.y
                        )));
                    }
                    drills.push((m.pos, opts.drill_diameter));
                }
                MarkKind::Point => points.push(m.pos),
            }
        }
        let mut lines = Vec::with_capacity(input.lines.len());
        for (k, l) in input.lines.iter().enumerate() {
            if l.iter().any(|p| !flatcut_geom::finite2(*p)) {
                return Err(nonfinite(&format!("internal line {}", k + 1)));
            }
            let mut l = l.clone();
            l.dedup_by(|a, b| a.distance(*b) < weld);
            if l.len() < 2 {
                return Err(inv(format!(
                    "internal line {} has fewer than two distinct points",
                    k + 1
                )));
            }
            if let Some(p) = l.iter().find(|p| {
                !poly::contains(&cut, **p)
                    && poly::nearest_on_closed(&cut, **p).2.distance(**p) > weld
            }) {
                return Err(inv(format!(
                    "internal line {} leaves the piece at ({:.2}, {:.2})",
                    k + 1,
                    p.x,
                    p.y
                )));
            }
            lines.push(simplify_line(&l, opts.chord_tol));
        }
        if let Some((a, b)) = input.grain {
            if !(flatcut_geom::finite2(a) && flatcut_geom::finite2(b)) {
                return Err(nonfinite("grain line"));
            }
            if a.distance(b) < weld {
                return Err(inv("grain line has zero length".into()));
            }
        }
        // 7. label
        let mut piece = Piece {
            name: input.name.clone(),
            sew,
            sew_polyline: sew_poly,
            cut,
            notches,
            notch_names,
            drills,
            points,
            lines,
            grain: input.grain,
            label: input.label.clone(),
            label_strokes: Vec::new(),
            chord_tol: opts.chord_tol,
        };
        piece.label_strokes = piece.layout_label(opts.label_height);
        Ok(piece)
    }

    /// Text lines of the label.
    pub fn label_lines(&self) -> Vec<String> {
        let l = &self.label;
        let mut v = vec![if l.name.is_empty() {
            self.name.clone()
        } else {
            l.name.clone()
        }];
        if !l.size.is_empty() {
            v.push(format!("SIZE {}", l.size));
        }
        if !l.material.is_empty() {
            v.push(l.material.clone());
        }
        if l.quantity > 0 {
            v.push(format!("CUT {}", l.quantity));
        }
        if let Some(d) = &l.distortion {
            v.push(d.clone());
        }
        v
    }

    /// Places the label at the most interior point of the sew polygon, along the grain line
    /// when there is one, shrinking the text until the block fits the inscribed circle.
    fn layout_label(&self, max_height: f64) -> Vec<Vec<DVec2>> {
        let lines = self.label_lines();
        let poly = &self.sew_polyline;
        let bb = Aabb2::from_points(poly.iter().copied());
        // pole of inaccessibility by a grid search refined twice
        let mut best = (bb.min + bb.max) * 0.5;
        let mut best_d = -1.0;
        let mut span = bb.max - bb.min;
        let mut center = best;
        const GRID: usize = 24;
        for _ in 0..3 {
            for i in 0..=GRID {
                for j in 0..=GRID {
                    let q = center - span * 0.5
                        + DVec2::new(
                            span.x * i as f64 / GRID as f64,
                            span.y * j as f64 / GRID as f64,
                        );
                    if !poly::contains(poly, q) {
                        continue;
                    }
                    let d = poly::dist_to_closed(poly, q);
                    if d > best_d {
                        best_d = d;
                        best = q;
                    }
                }
            }
            center = best;
            span *= 2.0 / GRID as f64 * 2.0;
        }
        if best_d <= 0.0 {
            return Vec::new();
        }
        let dir = self
            .grain
            .map(|(a, b)| (b - a).normalize())
            .unwrap_or(DVec2::X);
        // block of width W = max chars, height H = lines × spacing at cap height h
        let widest = lines
            .iter()
            .map(|l| font::text_width(l, 1.0))
            .fold(0.0, f64::max);
        let rows = lines.len() as f64;
        let block = |h: f64| DVec2::new(widest * h, (rows - 1.0) * font::LINE_SPACING * h + h);
        let unit = block(1.0);
        let h = max_height.min(2.0 * best_d / unit.length());
        let size = block(h);
        let up = DVec2::new(-dir.y, dir.x);
        let mut out = Vec::new();
        for (k, line) in lines.iter().enumerate() {
            let w = font::text_width(line, h);
            let y = size.y * 0.5 - h - k as f64 * font::LINE_SPACING * h;
            let origin = best + dir * (-w * 0.5) + up * y;
            out.extend(font::text_strokes(line, origin, h, dir));
        }
        out
    }

    /// Bounding box of the cut line.
    pub fn bbox(&self) -> Aabb2 {
        Aabb2::from_points(self.cut.iter().copied())
    }

    /// Area enclosed by the cut line (mm²).
    pub fn cut_area(&self) -> f64 {
        poly::signed_area(&self.cut)
    }

    /// Length of the cut line (mm).
    pub fn cut_length(&self) -> f64 {
        let n = self.cut.len();
        (0..n)
            .map(|i| self.cut[i].distance(self.cut[(i + 1) % n]))
            .sum()
    }

    /// Id prefix of instance `instance` of this piece, e.g. `vamp-1`.
    pub fn instance_id(&self, instance: u32) -> String {
        format!("{}-{}", safe_name(&self.name), instance)
    }

    /// The piece as strokes: cut line (Boundary), drill holes and notches (Cut), sew line, points,
    /// internal and grain lines (Draw), label (Engrave). Ids are `{name}-{instance}-{what}`; the
    /// drawing's [`PieceInfo`] carries the label fields and the grain line.
    pub fn to_drawing(&self, instance: u32) -> Drawing {
        let id = self.instance_id(instance);
        let pid = Some(instance);
        let mk = |kind: StrokeKind, points: Vec<DVec2>, closed, what: String| Stroke {
            layer: match kind {
                StrokeKind::Boundary
                | StrokeKind::InnerCut
                | StrokeKind::Notch
                | StrokeKind::Drill => Layer::Cut,
                StrokeKind::Text => Layer::Engrave,
                _ => Layer::Draw,
            },
            points,
            closed,
            piece: pid,
            kind,
            id: format!("{id}-{what}"),
        };
        let mut s = Vec::new();
        for (k, (c, d)) in self.drills.iter().enumerate() {
            let r = d * 0.5;
            let step = 2.0 * (1.0 - (self.chord_tol / r).min(1.0)).acos();
            let m = ((std::f64::consts::TAU / step.max(1e-3)).ceil() as usize).clamp(8, 256);
            let pts = (0..m)
                .map(|i| *c + r * DVec2::from_angle(i as f64 * std::f64::consts::TAU / m as f64))
                .collect();
            s.push(mk(StrokeKind::Drill, pts, true, format!("drill-{}", k + 1)));
        }
        for (k, nt) in self.notches.iter().enumerate() {
            // A named notch (a mating seam's) says which: `notch-<seam>_<n>`, with the name's
            // dashes and spaces as underscores so the id still splits into piece and notch.
            let what = match self.notch_names.get(k).filter(|n| !n.is_empty()) {
                Some(n) => format!("notch-{}", safe_name(n).replace('-', "_")),
                None => format!("notch-{}", k + 1),
            };
            s.push(mk(StrokeKind::Notch, nt.clone(), false, what));
        }
        s.push(mk(
            StrokeKind::Boundary,
            self.cut.clone(),
            true,
            "cut".into(),
        ));
        s.push(mk(
            StrokeKind::Sew,
            self.sew_polyline.clone(),
            true,
            "sew".into(),
        ));
        for (k, p) in self.points.iter().enumerate() {
            const CROSS: f64 = 1.5; // half-size of a point cross (mm)
            s.push(mk(
                StrokeKind::Internal,
                vec![*p - DVec2::X * CROSS, *p + DVec2::X * CROSS],
                false,
                format!("point-{}-a", k + 1),
            ));
            s.push(mk(
                StrokeKind::Internal,
                vec![*p - DVec2::Y * CROSS, *p + DVec2::Y * CROSS],
                false,
                format!("point-{}-b", k + 1),
            ));
        }
        for (k, l) in self.lines.iter().enumerate() {
            s.push(mk(
                StrokeKind::Internal,
                l.clone(),
                false,
                format!("line-{}", k + 1),
            ));
        }
        if let Some((a, b)) = self.grain {
            let d = (b - a).normalize();
            let nrm = DVec2::new(-d.y, d.x);
            let head = (a.distance(b) * 0.1).min(8.0);
            s.push(mk(StrokeKind::Grain, vec![a, b], false, "grain".into()));
            s.push(mk(
                StrokeKind::Grain,
                vec![
                    b - d * head + nrm * head * 0.4,
                    b,
                    b - d * head - nrm * head * 0.4,
                ],
                false,
                "grain-head".into(),
            ));
            s.push(mk(
                StrokeKind::Grain,
                vec![
                    a + d * head + nrm * head * 0.4,
                    a,
                    a + d * head - nrm * head * 0.4,
                ],
                false,
                "grain-tail".into(),
            ));
        }
        for (k, st) in self.label_strokes.iter().enumerate() {
            s.push(mk(
                StrokeKind::Text,
                st.clone(),
                false,
                format!("label-{}", k + 1),
            ));
        }
        Drawing {
            strokes: s,
            pieces: vec![PieceInfo {
                piece: instance,
                label: self.label_with_name(),
                grain: self.grain,
            }],
        }
    }

    /// The label fields with the piece's name filled in where the label has none.
    pub fn label_with_name(&self) -> LabelInfo {
        let mut l = self.label.clone();
        if l.name.is_empty() {
            l.name = self.name.clone();
        }
        l
    }
}

/// A rigid placement of a piece instance: optional mirror (x → −x), then rotation, then
/// translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub rotation: f64,
    pub mirror: bool,
    pub translation: DVec2,
}

impl Placement {
    pub const IDENTITY: Self = Self {
        rotation: 0.0,
        mirror: false,
        translation: DVec2::ZERO,
    };

    /// Maps a point of the piece frame to the sheet.
    pub fn apply(&self, p: DVec2) -> DVec2 {
        let q = if self.mirror {
            DVec2::new(-p.x, p.y)
        } else {
            p
        };
        self.translation + DVec2::from_angle(self.rotation).rotate(q)
    }
}

/// A piece instance placed on a sheet.
#[derive(Clone, Copy, Debug)]
pub struct PlacedPiece<'a> {
    pub piece: &'a Piece,
    pub instance: u32,
    pub placement: Placement,
}

impl PlacedPiece<'_> {
    /// The instance's drawing in sheet coordinates (closed strokes stay CCW under mirroring).
    pub fn to_drawing(&self) -> Drawing {
        let mut d = self.piece.to_drawing(self.instance);
        for s in &mut d.strokes {
            for p in &mut s.points {
                *p = self.placement.apply(*p);
            }
            if self.placement.mirror && s.closed {
                s.points[1..].reverse();
            }
        }
        for info in &mut d.pieces {
            info.grain = info
                .grain
                .map(|(a, b)| (self.placement.apply(a), self.placement.apply(b)));
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: f64, h: f64, per_side: usize) -> Vec<DVec2> {
        let c = [
            DVec2::ZERO,
            DVec2::new(w, 0.),
            DVec2::new(w, h),
            DVec2::new(0., h),
        ];
        (0..4)
            .flat_map(|k| {
                (0..per_side).map(move |j| c[k].lerp(c[(k + 1) % 4], j as f64 / per_side as f64))
            })
            .collect()
    }

    #[test]
    fn stitch_lines_are_drawn_as_polylines_and_checked() {
        let mut input = PieceInput::new("quarter", rect(200., 100., 20));
        let stitch = vec![
            DVec2::new(10., 10.),
            DVec2::new(100., 12.),
            DVec2::new(100., 12.), // repeated point: dropped
            DVec2::new(190., 10.),
        ];
        input.lines.push(stitch);
        let p = Piece::build(&input, &PieceOptions::default()).unwrap();
        assert_eq!(
            p.lines,
            vec![vec![
                DVec2::new(10., 10.),
                DVec2::new(100., 12.),
                DVec2::new(190., 10.)
            ]]
        );
        let d = p.to_drawing(1);
        let line: Vec<_> = d
            .strokes
            .iter()
            .filter(|s| s.id == "quarter-1-line-1")
            .collect();
        assert_eq!(line.len(), 1);
        assert_eq!(line[0].layer, Layer::Draw);
        assert!(!line[0].closed && line[0].points.len() == 3);
        // a straight line sampled densely keeps only its ends
        let mut straight = input.clone();
        straight.lines[0] = (0..=50)
            .map(|k| DVec2::new(10. + 3.0 * k as f64, 50.))
            .collect();
        let q = Piece::build(&straight, &PieceOptions::default()).unwrap();
        assert_eq!(
            q.lines[0],
            vec![DVec2::new(10., 50.), DVec2::new(160., 50.)]
        );
        // within the allowance is fine (a topstitch on the seam); beyond the cut line is not
        input.lines[0].push(DVec2::new(205., 10.));
        assert!(Piece::build(&input, &PieceOptions::default()).is_ok());
        input.lines[0].push(DVec2::new(260., 10.));
        let e = Piece::build(&input, &PieceOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("quarter") && e.contains("internal line 1 leaves the piece"),
            "{e}"
        );
        input.lines[0] = vec![DVec2::new(10., 10.), DVec2::new(f64::NAN, 1.)];
        let e = Piece::build(&input, &PieceOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("internal line 1"), "{e}");
        input.lines[0] = vec![DVec2::new(10., 10.)];
        let e = Piece::build(&input, &PieceOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("fewer than two"), "{e}");
    }

    #[test]
    fn rectangle_piece_has_allowance_notches_label() {
        let mut input = PieceInput::new("vamp", rect(200., 100., 20));
        input.marks.push(Mark {
            kind: MarkKind::Notch,
            pos: DVec2::new(100., 0.),
            boundary_index: None,
        });
        input.marks.push(Mark {
            kind: MarkKind::Drill,
            pos: DVec2::new(50., 50.),
            boundary_index: None,
        });
        input.grain = Some((DVec2::new(20., 20.), DVec2::new(180., 20.)));
        input.label.size = "42".into();
        let p = Piece::build(&input, &PieceOptions::default()).unwrap();
        // four straight seams, the bottom one split at the notch (marks are kept as corners)
        assert_eq!(p.sew.len(), 5, "{:?}", p.sew);
        assert!(p.sew.iter().all(|s| matches!(s, PathSeg::Line { .. })));
        assert!(p.sew.iter().any(|s| s.end() == DVec2::new(100., 0.)));
        assert!((p.cut_area() - 220.0 * 120.0).abs() < 1e-6);
        assert_eq!(p.notches.len(), 1);
        let nt = &p.notches[0];
        assert!(nt[0].distance(DVec2::new(100., -10.)) < 1e-6, "{:?}", nt);
        assert!(nt[1].distance(DVec2::new(100., -6.)) < 1e-6);
        assert!(!p.label_strokes.is_empty());
        let d = p.to_drawing(1);
        assert!(
            d.strokes
                .iter()
                .any(|s| s.id == "vamp-1-cut" && s.is_outer())
        );
        assert!(d.strokes.iter().any(|s| s.id == "vamp-1-notch-1"));
        // label inside the sew line
        for st in &p.label_strokes {
            for q in st {
                assert!(poly::contains(&p.sew_polyline, *q));
            }
        }
    }

    #[test]
    fn per_segment_widths_between_marks_and_fold() {
        // marks at the corners (0,0) [idx 0] and (200,0) [idx 20]: segment 0 is the bottom edge,
        // segment 1 the rest; fold (0 mm) on the bottom
        let mut input = PieceInput::new("front", rect(200., 100., 20));
        input.marks.push(Mark {
            kind: MarkKind::Point,
            pos: DVec2::ZERO,
            boundary_index: Some(0),
        });
        input.marks.push(Mark {
            kind: MarkKind::Point,
            pos: DVec2::new(200., 0.),
            boundary_index: Some(20),
        });
        input.seam_widths = vec![0.0, 15.0];
        let p = Piece::build(&input, &PieceOptions::default()).unwrap();
        let bb = p.bbox();
        assert!((bb.min.y - 0.0).abs() < 1e-9 && (bb.max.y - 115.0).abs() < 1e-9);
        assert!((bb.min.x + 15.0).abs() < 1e-9 && (bb.max.x - 215.0).abs() < 1e-9);
    }

    #[test]
    fn self_intersecting_outline_is_rejected_naming_the_piece() {
        let bow = vec![
            DVec2::ZERO,
            DVec2::new(50., 50.),
            DVec2::new(50., 0.),
            DVec2::new(0., 50.),
        ];
        let e =
            Piece::build(&PieceInput::new("quarter-L", bow), &PieceOptions::default()).unwrap_err();
        assert!(matches!(e, PatternError::SelfIntersecting { .. }));
        assert!(e.to_string().contains("quarter-L"), "{e}");
    }

    #[test]
    fn allowance_too_large_names_the_piece() {
        let u = vec![
            DVec2::new(0., 0.),
            DVec2::new(60., 0.),
            DVec2::new(60., 80.),
            DVec2::new(32., 80.),
            DVec2::new(32., 10.),
            DVec2::new(28., 10.),
            DVec2::new(28., 80.),
            DVec2::new(0., 80.),
        ];
        let e = Piece::build(
            &PieceInput::new("tongue", u.clone()),
            &PieceOptions::default(),
        )
        .unwrap_err();
        assert!(matches!(e, PatternError::AllowanceTooLarge { .. }), "{e}");
        assert!(e.to_string().contains("tongue"));
        let mut neg = PieceInput::new("heel", u);
        neg.seam_widths = vec![-1.0];
        assert!(matches!(
            Piece::build(&neg, &PieceOptions::default()),
            Err(PatternError::AllowanceTooLarge { .. })
        ));
    }

    #[test]
    fn non_finite_and_degenerate_input_errors() {
        let e = Piece::build(
            &PieceInput::new("a", vec![DVec2::ZERO, DVec2::new(f64::NAN, 0.), DVec2::ONE]),
            &PieceOptions::default(),
        );
        assert!(matches!(e, Err(PatternError::NonFinite { .. })));
        let e = Piece::build(
            &PieceInput::new("b", vec![DVec2::ZERO, DVec2::ONE]),
            &PieceOptions::default(),
        );
        assert!(matches!(e, Err(PatternError::DegenerateOutline { .. })));
    }

    #[test]
    fn clockwise_input_is_accepted_and_mirror_keeps_ccw() {
        let mut r = rect(80., 40., 4);
        r.reverse();
        let p = Piece::build(&PieceInput::new("cw", r), &PieceOptions::default()).unwrap();
        assert!(p.cut_area() > 0.0);
        let pp = PlacedPiece {
            piece: &p,
            instance: 1,
            placement: Placement {
                rotation: 0.3,
                mirror: true,
                translation: DVec2::new(5., 5.),
            },
        };
        let d = pp.to_drawing();
        let cut = d.strokes.iter().find(|s| s.is_outer()).unwrap();
        assert!((poly::signed_area(&cut.points) - p.cut_area()).abs() < 1e-6);
    }
}
