//! A dart on the pattern as a pattern maker draws it: its legs smooth, its mouth trued.
//!
//! * **Legs.** A dart's legs are the images of a geodesic of the surface; in the flat map they
//!   are polylines through the mesh's crossings, kinked where neighbouring triangles stretch
//!   differently. Each leg is drawn as the least-squares cubic from its mouth to its point
//!   through those crossings (a geodesic's image under a near-isometric map is nearly
//!   straight), flattened within the pattern's chord tolerance.
//! * **Mouth.** The folded dart's intake is pressed to one side (the design's `dart_press`:
//!   toward a point, or by default toward the piece's centre line). Folded, the intake lies on
//!   that side's material, so it must be cut along that side's outline: the mouth is closed by
//!   the dart cap, the side's outline reflected about the leg it is pressed against (the half
//!   of the intake next to that leg) and, mirrored about the dart's centre line, the other half.
//!   Unfolded, the cap is the peak a pattern maker gets by cutting with the dart folded. Where
//!   the outline beside the mouth gives no cap (it turns away before reaching the fold), the
//!   mouth is bridged straight.
//! * **Marks.** A notch at each mouth, a drill mark short of the point and a fold arrow inside
//!   the wedge pointing to the side the intake is pressed toward.

use flatcut_darts::Dart;
use flatcut_geom::DVec2;
use flatcut_pattern::{Mark, MarkKind, PathSeg, PieceInput};

/// Where a dart's fold arrow sits: this fraction of the way from the mouth to the point (at
/// most [`FOLD_ARROW_DEPTH_MM`] in), reaching this fraction of the way to the pressed leg.
const FOLD_ARROW_DEPTH: f64 = 0.25;
const FOLD_ARROW_DEPTH_MM: f64 = 15.0;
const FOLD_ARROW_REACH: f64 = 0.8;
/// Half-width of the fold arrow's head relative to its length.
const FOLD_HEAD: f64 = 0.3;
/// A leg whose fitted cubic strays farther than this share of its length from the crossings is
/// drawn through them as it is (the fit does not describe it).
const LEG_FIT_SHARE: f64 = 0.05;
/// Parameter corrections of the leg fit.
const LEG_FIT_ROUNDS: usize = 4;

/// A dart of the piece as the pattern draws it: its two legs (mouth to point, smooth) and the
/// side its intake is pressed toward (0 or 1: the leg).
pub struct DrawnDart {
    /// The two legs, each from the mouth to the point (mm, the piece's flat frame).
    pub legs: [Vec<DVec2>; 2],
    /// The leg the intake is pressed toward: 0 or 1.
    pub pressed: usize,
}

/// The outline of a darted piece with every dart's wedge replaced by its cap (or bridged),
/// and the vertex ids (`u32::MAX` for cap points) and per-vertex values (`tag`, of the edge a
/// vertex starts: a cap takes the tag of the edge that arrives at its mouth) carried along.
pub fn true_mouths<T: Clone>(
    outline: Vec<DVec2>,
    ids: Vec<u32>,
    tags: Vec<T>,
    darts: &[(&Dart, usize)],
    flat: &[DVec2],
) -> (Vec<DVec2>, Vec<u32>, Vec<T>) {
    let (mut outline, mut ids, mut tags) = (outline, ids, tags);
    for &(d, pressed) in darts {
        let n = ids.len();
        let at = |v: u32| ids.iter().position(|&i| i == v);
        let apex_v = *d.legs.sides[0].last().unwrap_or(&d.legs.sides[0][0]);
        let (Some(i0), Some(i1), Some(ia)) =
            (at(d.legs.sides[0][0]), at(d.legs.sides[1][0]), at(apex_v))
        else {
            continue;
        };
        // The stretch between the mouths that holds the point.
        let ahead = |from: usize, to: usize| (to + n - from) % n;
        let (from, to, from_leg) = if ahead(i0, ia) < ahead(i0, i1) {
            (i0, i1, 0)
        } else {
            (i1, i0, 1)
        };
        let apex = flat[apex_v as usize];
        let cap = cap(&outline, from, to, from_leg, pressed, apex).unwrap_or_default();
        let kept: Vec<usize> = (0..n)
            .filter(|&k| ahead(from, k) == 0 || ahead(from, k) >= ahead(from, to))
            .collect();
        let mut o = Vec::with_capacity(kept.len() + cap.len());
        let mut v = Vec::with_capacity(o.capacity());
        let mut t = Vec::with_capacity(o.capacity());
        for k in kept {
            o.push(outline[k]);
            v.push(ids[k]);
            t.push(tags[k].clone());
            if k == from {
                let tag = tags[(from + n - 1) % n].clone();
                for p in &cap {
                    o.push(*p);
                    v.push(u32::MAX);
                    t.push(tag.clone());
                }
            }
        }
        // a cap that would make the outline cross itself is bridged straight instead
        if !cap.is_empty() && flatcut_pattern::poly::first_self_intersection(&o).is_some() {
            let drop = cap.len();
            let k = o.iter().position(|p| *p == outline[from]).unwrap_or(0);
            o.drain(k + 1..k + 1 + drop);
            v.drain(k + 1..k + 1 + drop);
            t.drain(k + 1..k + 1 + drop);
        }
        outline = o;
        ids = v;
        tags = t;
    }
    (outline, ids, tags)
}

/// The cap closing the mouth between `outline[from]` and `outline[to]` (the wedge between them
/// holds the point `apex`; `from` is the mouth of leg `from_leg`) when the intake is pressed
/// toward leg `pressed`: the points strictly between the two mouths, in outline order.
fn cap(
    outline: &[DVec2],
    from: usize,
    to: usize,
    from_leg: usize,
    pressed: usize,
    apex: DVec2,
) -> Option<Vec<DVec2>> {
    let n = outline.len();
    let (ms, mo, back) = if pressed == from_leg {
        (outline[from], outline[to], true)
    } else {
        (outline[to], outline[from], false)
    };
    let us = (ms - apex).normalize_or_zero();
    let uo = (mo - apex).normalize_or_zero();
    let c = (us + uo).normalize_or_zero();
    if us == DVec2::ZERO || uo == DVec2::ZERO || c == DVec2::ZERO {
        return None;
    }
    let reflect = |p: DVec2, axis: DVec2| apex + 2.0 * (p - apex).dot(axis) * axis - (p - apex);
    // The fold of the intake's half next to the pressed leg, seen on the pressed side: the
    // centre line reflected about that leg.
    let fold = 2.0 * c.dot(us) * us - c;
    let mouth = ms.distance(mo);
    // The pressed side's outline, walked away from the mouth until it crosses that fold.
    let mut side = Vec::new();
    let mut prev = ms;
    let mut walked = 0.0;
    let start = if back { from } else { to };
    let mut reached = false;
    for k in 1..n {
        let i = if back {
            (start + n - k) % n
        } else {
            (start + k) % n
        };
        let p = outline[i];
        walked += prev.distance(p);
        if let Some(q) = ray_crossing(apex, fold, prev, p) {
            side.push(q);
            reached = true;
            break;
        }
        side.push(p);
        prev = p;
        if walked > 4.0 * mouth.max(1e-9) {
            break;
        }
    }
    if !reached {
        // the pressed side's outline turns away before it reaches the fold
        return None;
    }
    let half: Vec<DVec2> = side.iter().map(|p| reflect(*p, us)).collect();
    let mut cap = half.clone();
    cap.extend(half.iter().rev().skip(1).map(|p| reflect(*p, c)));
    // ms → mo; the outline runs from → to
    if !back {
        cap.reverse();
    }
    Some(cap)
}

/// Where the segment `a`–`b` crosses the ray from `o` along `d` (not at `a`).
fn ray_crossing(o: DVec2, d: DVec2, a: DVec2, b: DVec2) -> Option<DVec2> {
    let e = b - a;
    let den = d.perp_dot(e);
    if den.abs() < 1e-15 {
        return None;
    }
    let t = (a - o).perp_dot(e) / den; // along the ray
    let s = (a - o).perp_dot(d) / den; // along the segment
    (t > 0.0 && s > 1e-12 && s <= 1.0).then(|| a + e * s)
}

/// Which leg (0 or 1) a dart's intake is pressed toward: the one on the side of the dart's
/// centre line (from the point through the mouth's middle) that `target` is on (leg 0 when it
/// is on that line).
pub fn pressed_leg(legs: &[Vec<DVec2>; 2], target: DVec2) -> usize {
    let (Some(m0), Some(m1), Some(apex)) = (legs[0].first(), legs[1].first(), legs[0].last())
    else {
        return 0;
    };
    let axis = (*m0 + *m1) * 0.5 - *apex;
    let side = |p: DVec2| axis.perp_dot(p - *apex);
    let t = side(target);
    if t.abs() <= 1e-9 * axis.length_squared().max(1.0) {
        return 0;
    }
    usize::from((side(*m1) > 0.0) == (t > 0.0))
}

/// The point of the piece's centre line (through `centre` along `dir`) nearest the middle of a
/// dart's mouth: what a dart pressed toward the centre line is pressed toward.
pub fn toward_centre_line(legs: &[Vec<DVec2>; 2], centre: DVec2, dir: DVec2) -> DVec2 {
    let m = match (legs[0].first(), legs[1].first()) {
        (Some(a), Some(b)) => (*a + *b) * 0.5,
        _ => centre,
    };
    let d = dir.normalize_or_zero();
    centre + d * (m - centre).dot(d)
}

/// A leg (mouth to point) drawn smooth: the least-squares cubic with the leg's ends through its
/// points, flattened within `chord_tol`; the leg as it is where one cubic does not describe it.
pub fn smooth_leg(leg: &[DVec2], chord_tol: f64) -> Vec<DVec2> {
    if leg.len() < 3 {
        return leg.to_vec();
    }
    let (p0, p3) = (leg[0], leg[leg.len() - 1]);
    let mut t = chord_params(leg);
    let mut ctrl = None;
    for _ in 0..LEG_FIT_ROUNDS {
        let Some((c1, c2)) = fit_inner(leg, &t, p0, p3) else {
            return leg.to_vec();
        };
        ctrl = Some((c1, c2));
        for (ti, p) in t.iter_mut().zip(leg).skip(1).take(leg.len() - 2) {
            *ti = newton(*ti, *p, p0, c1, c2, p3);
        }
    }
    let Some((c1, c2)) = ctrl else {
        return leg.to_vec();
    };
    let length: f64 = leg.windows(2).map(|w| w[0].distance(w[1])).sum();
    let seg = PathSeg::Cubic { p0, c1, c2, p1: p3 };
    let worst = leg
        .iter()
        .zip(&t)
        .map(|(p, ti)| seg.eval(*ti).distance(*p))
        .fold(0.0, f64::max);
    if worst > LEG_FIT_SHARE * length {
        return leg.to_vec();
    }
    let mut out = Vec::new();
    seg.flatten(chord_tol, &mut out);
    out
}

/// Chord-length parameters of a polyline, 0 to 1.
fn chord_params(p: &[DVec2]) -> Vec<f64> {
    let mut acc = vec![0.0];
    for w in p.windows(2) {
        acc.push(acc[acc.len() - 1] + w[0].distance(w[1]));
    }
    let total = acc[acc.len() - 1].max(f64::MIN_POSITIVE);
    acc.iter().map(|s| s / total).collect()
}

/// The inner control points of the cubic from `p0` to `p3` nearest (least squares) to the
/// points `p` at parameters `t`.
fn fit_inner(p: &[DVec2], t: &[f64], p0: DVec2, p3: DVec2) -> Option<(DVec2, DVec2)> {
    let (mut a11, mut a12, mut a22) = (0.0, 0.0, 0.0);
    let (mut r1, mut r2) = (DVec2::ZERO, DVec2::ZERO);
    for (q, &ti) in p.iter().zip(t) {
        let s = 1.0 - ti;
        let (b0, b1, b2, b3) = (s * s * s, 3.0 * s * s * ti, 3.0 * s * ti * ti, ti * ti * ti);
        let rhs = *q - p0 * b0 - p3 * b3;
        a11 += b1 * b1;
        a12 += b1 * b2;
        a22 += b2 * b2;
        r1 += rhs * b1;
        r2 += rhs * b2;
    }
    let det = a11 * a22 - a12 * a12;
    if det.abs() < 1e-12 {
        return None;
    }
    Some(((r1 * a22 - r2 * a12) / det, (r2 * a11 - r1 * a12) / det))
}

/// One Newton step toward the parameter of the cubic's point nearest `p`.
fn newton(t: f64, p: DVec2, p0: DVec2, c1: DVec2, c2: DVec2, p3: DVec2) -> f64 {
    let s = 1.0 - t;
    let b = p0 * (s * s * s) + c1 * (3.0 * s * s * t) + c2 * (3.0 * s * t * t) + p3 * (t * t * t);
    let d1 = (c1 - p0) * (3.0 * s * s) + (c2 - c1) * (6.0 * s * t) + (p3 - c2) * (3.0 * t * t);
    let d2 = (c2 - 2.0 * c1 + p0) * (6.0 * s) + (p3 - 2.0 * c2 + c1) * (6.0 * t);
    let r = b - p;
    let num = r.dot(d1);
    let den = d1.dot(d1) + r.dot(d2);
    if den.abs() < 1e-15 {
        return t;
    }
    (t - num / den).clamp(0.0, 1.0)
}

/// The point a fraction `f` along a polyline's length.
fn along(line: &[DVec2], f: f64) -> DVec2 {
    let total: f64 = line.windows(2).map(|w| w[0].distance(w[1])).sum();
    let mut left = f.clamp(0.0, 1.0) * total;
    for w in line.windows(2) {
        let l = w[0].distance(w[1]);
        if left <= l && l > 0.0 {
            return w[0].lerp(w[1], left / l);
        }
        left -= l;
    }
    line.last().copied().unwrap_or(DVec2::ZERO)
}

/// A folded dart's marks on the pattern: its legs as a sew line inside the piece (mouth, point,
/// mouth), a notch at each leg's mouth (outline vertices by `ids`), the drill mark short of its
/// point and the fold arrow inside the wedge pointing to the pressed leg.
pub fn dart_marks(input: &mut PieceInput, d: &Dart, drawn: &DrawnDart, ids: &[u32]) {
    let legs = &drawn.legs;
    let mut sew = legs[0].clone();
    sew.extend(legs[1].iter().rev().skip(1));
    input.sew_lines.push(sew);
    for v in [d.legs.sides[0][0], d.legs.sides[1][0]] {
        if let Some(k) = ids.iter().position(|&i| i == v) {
            input.marks.push(Mark {
                kind: MarkKind::Notch,
                pos: input.outline[k],
                boundary_index: Some(k),
            });
        }
    }
    input.marks.push(Mark {
        kind: MarkKind::Drill,
        pos: d.drill_2d,
        boundary_index: None,
    });
    let leg_len = |l: &[DVec2]| l.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
    let l0 = leg_len(&legs[0]);
    let depth = (FOLD_ARROW_DEPTH * l0).min(FOLD_ARROW_DEPTH_MM);
    let f = depth / l0.max(f64::MIN_POSITIVE);
    let (q0, q1) = (along(&legs[0], f), along(&legs[1], f));
    let target = if drawn.pressed == 0 { q0 } else { q1 };
    let c = 0.5 * (q0 + q1);
    let len = FOLD_ARROW_REACH * c.distance(target);
    if len > 0.0 {
        let dir = (target - c).normalize_or_zero();
        let tip = c + dir * len;
        let side = dir.perp() * (FOLD_HEAD * len);
        let back = tip - dir * (FOLD_HEAD * len);
        input.lines.push(vec![c, tip]);
        input.lines.push(vec![back + side, tip, back - side]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn a_zigzag_leg_becomes_the_smooth_line_through_it() {
        // a straight 60 mm leg with 1 mm kinks every 5 mm
        let leg: Vec<DVec2> = (0..=12)
            .map(|k| {
                v(
                    5.0 * k as f64,
                    if k % 2 == 1 { 0.5 } else { -0.5 } * f64::from(k != 0 && k != 12),
                )
            })
            .collect();
        let s = smooth_leg(&leg, 0.02);
        assert_eq!(s[0], leg[0]);
        assert_eq!(*s.last().unwrap(), *leg.last().unwrap());
        // nearly straight: every point within 0.1 mm of the chord, no kink
        assert!(s.iter().all(|p| p.y.abs() < 0.1), "{s:?}");
    }

    #[test]
    fn a_dart_pressed_toward_a_side_is_capped_by_that_sides_outline_reflected() {
        // a dart in the bottom edge of a 100 × 60 rectangle: mouth 40–60 on y = 0, point (50, 40)
        let outline = vec![
            v(0., 0.),
            v(40., 0.),
            v(50., 40.),
            v(60., 0.),
            v(100., 0.),
            v(100., 60.),
            v(0., 60.),
        ];
        // pressed toward the leg at (40, 0): the outline there runs back along y = 0
        let c = cap(&outline, 1, 3, 0, 0, v(50., 40.)).unwrap();
        // the cap peaks on the dart's centre line, below the edge (outside the piece)
        let peak = c
            .iter()
            .copied()
            .fold(v(0., f64::INFINITY), |a, b| if b.y < a.y { b } else { a });
        assert!((peak.x - 50.0).abs() < 1e-9 && peak.y < 0.0, "{c:?}");
        // folded, the cap's first half lands back on the pressed side's edge y = 0
        let apex = v(50., 40.);
        let us = (v(40., 0.) - apex).normalize();
        for p in &c[..c.len() / 2 + 1] {
            let f = apex + 2.0 * (*p - apex).dot(us) * us - (*p - apex);
            assert!(f.y.abs() < 1e-9 && f.x < 40.0 + 1e-9, "{p} folds to {f}");
        }
        // symmetric about the centre line x = 50
        for (a, b) in c.iter().zip(c.iter().rev()) {
            assert!((a.x + b.x - 100.0).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9);
        }
    }

    #[test]
    fn an_oblique_darts_cap_peaks_and_folds_flat_onto_the_pressed_side() {
        // the point leans toward +x: the legs meet the edge y = 0 at 76° and 63°
        let apex = v(70., 40.);
        let outline = vec![
            v(0., 0.),
            v(40., 0.),
            apex,
            v(60., 0.),
            v(100., 0.),
            v(100., 60.),
            v(0., 60.),
        ];
        for pressed in [0, 1] {
            let c = cap(&outline, 1, 3, 0, pressed, apex).unwrap();
            let (ms, edge_x) = if pressed == 0 {
                (v(40., 0.), -1.0)
            } else {
                (v(60., 0.), 1.0)
            };
            let us = (ms - apex).normalize();
            // the half next to the pressed leg folds onto the pressed side's edge, y = 0 beyond
            // the mouth; the other half mirrors it about the dart's centre line
            let half = c.len() / 2 + 1;
            let near: Vec<DVec2> = if pressed == 0 {
                c[..half].to_vec()
            } else {
                c[c.len() - half..].to_vec()
            };
            for p in &near {
                let f = apex + 2.0 * (*p - apex).dot(us) * us - (*p - apex);
                assert!(
                    f.y.abs() < 1e-9 && (f.x - ms.x) * edge_x >= -1e-9,
                    "{p} folds to {f}"
                );
            }
            // pressed toward the leg the point leans to, the intake's edge dips into the piece
            // (cut away so the folded intake stays behind the edge); the other way it peaks
            let rise = c.iter().map(|p| -p.y).fold(f64::NEG_INFINITY, f64::max);
            let dip = c.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
            let (want, got) = if pressed == 0 {
                ("peak", rise)
            } else {
                ("dip", dip)
            };
            assert!(
                got > 1.0,
                "pressed {pressed}: the cap's {want} is {got} mm: {c:?}"
            );
        }
    }

    #[test]
    fn the_pressed_leg_is_the_one_facing_the_target() {
        let legs = [vec![v(40., 0.), v(50., 40.)], vec![v(60., 0.), v(50., 40.)]];
        assert_eq!(pressed_leg(&legs, v(0., 10.)), 0);
        assert_eq!(pressed_leg(&legs, v(100., 10.)), 1);
    }
}
