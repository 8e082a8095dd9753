//! The independent checks a tessellation passes before it is returned: every face's area, and
//! every edge's length, computed a second way that shares nothing with the triangulation.
//!
//! - **Face area on the trimmed domain** ([`trim_area`]): Green's theorem turns the area
//!   `∬ |S_u × S_v| du dv` over the region the trim loops bound into the loop integral
//!   `∮ F(u, v) dv` with `F(u, v) = ∫_{u₀}^{u} |S_u × S_v|(s, v) ds`, evaluated by Gauss–Legendre
//!   quadrature along each loop segment (and along u for `F`; in closed form for the surfaces of
//!   revolution, whose area element does not depend on u). It sees only the loops, not the
//!   triangles: a triangulation that covers another region than the loops bound (a wrong side
//!   of a pole, a hole filled, a band taken for its complement) disagrees with it.
//! - The exact area of the triangles' (u, v) (their cover) must agree with it within
//!   [`AREA_REL`]; the flat triangles' area must too, but for the chordal deficit a mesh within
//!   the tolerance δ of a surface of curvature κ may have (`2 δ κ` of the area at most).
//! - **Edge length**: the polyline an edge is sampled to against the curve's arc length
//!   (adaptive Gauss–Legendre), within [`AREA_REL`] and the chords' deficit `8 h² / 3c` for a
//!   chord `c` of sag `h ≤ δ`.

use flatcut_geom::DVec2;
use flatcut_geom::num::gauss16;
use flatcut_surface::curve::CurveExt;
use flatcut_surface::patch::AnalyticKind;
use flatcut_surface::{ParamCurve, ParamSurface};

use crate::geom::Surface;

/// The largest relative disagreement accepted (0.1 %).
pub const AREA_REL: f64 = 1e-3;
/// Gauss–Legendre nodes and weights on [0, 1], 3 points: exact for quintics along a segment.
const GL3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];
/// Pieces a loop segment as long as the loops' whole v extent is split into (3 Gauss points
/// each).
const OUTER_PIECES: usize = 16;
/// Pieces the inner integral along u is split into over a whole period or domain width (and at
/// every knot of a patch).
const INNER_PIECES: usize = 4;

/// The area element `|S_u × S_v|` (0 where it is not finite: a pole).
fn element(s: &Surface, u: f64, v: f64) -> f64 {
    let (_, su, sv) = s.deriv1(u, v);
    let a = su.cross(sv).length();
    if a.is_finite() { a } else { 0.0 }
}

/// True when the area element does not depend on u (planes and surfaces of revolution).
fn rotational(s: &Surface) -> bool {
    matches!(s, Surface::Analytic(a) if !matches!(a.kind, AnalyticKind::Extrusion { .. }))
}

/// Where the inner integral along u from `u0` to `u1` is split: the knots of a patch between
/// them, and every `1 / INNER_PIECES` of the period or domain width.
fn inner_breaks(s: &Surface, u0: f64, u1: f64) -> Vec<f64> {
    let (lo, hi) = (u0.min(u1), u0.max(u1));
    let d = s.domain();
    let width = s.periods()[0].unwrap_or(d.u.1 - d.u.0);
    let h = (width / INNER_PIECES as f64).max(f64::MIN_POSITIVE);
    let n = ((hi - lo) / h).ceil().clamp(1.0, 1e6) as usize;
    let mut out: Vec<f64> = (0..=n)
        .map(|k| lo + (hi - lo) * k as f64 / n as f64)
        .collect();
    if let Surface::Spline(sp) = s {
        let per = sp.period[0];
        let (ku, _) = sp.patch.knots();
        for &k in ku {
            match per {
                // Knots repeat every period.
                Some(p) => {
                    let mut x = k + p * ((lo - k) / p).ceil();
                    while x < hi {
                        out.push(x);
                        x += p;
                    }
                }
                None if k > lo && k < hi => out.push(k),
                None => {}
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out.dedup_by(|a, b| (*a - *b).abs() <= 1e-14 * (1.0 + b.abs()));
    out
}

/// `F(u, v) = ∫_{u0}^{u} |S_u × S_v|(s, v) ds`.
fn inner(s: &Surface, u0: f64, u: f64, v: f64) -> f64 {
    if rotational(s) {
        return (u - u0) * element(s, u0, v);
    }
    let br = inner_breaks(s, u0, u);
    let sum: f64 = br
        .windows(2)
        .map(|w| gauss16(|x| element(s, x, v), w[0], w[1]))
        .sum();
    if u >= u0 { sum } else { -sum }
}

/// The area (mm²) of the region the loops bound in the surface's (u, v), by Green's theorem
/// (see the module documentation): positive for counter-clockwise outer loops. Consecutive
/// points are joined by straight lines in (u, v).
pub fn trim_area(s: &Surface, loops: &[Vec<DVec2>]) -> f64 {
    let nodes: Vec<Vec<(DVec2, bool)>> = loops
        .iter()
        .map(|lp| lp.iter().map(|&p| (p, false)).collect())
        .collect();
    trim_area_curved(s, &nodes)
}

/// [`trim_area`] on loops whose points are `(uv, mid)`: a point marked `mid` is the (u, v) of
/// the curve halfway between its two neighbours, and the loop runs from one neighbour to the
/// other along the parabola through the three. An edge's curve is then followed to the fourth
/// order in its samples' spacing instead of the second (a chord's sliver is `4 s / 3 r` of a
/// disk of radius r sampled to sag s: 1e-3 for a 10 mm fillet sampled to 7 µm).
pub fn trim_area_curved(s: &Surface, loops: &[Vec<(DVec2, bool)>]) -> f64 {
    let all = || loops.iter().flatten().map(|n| n.0);
    let u0 = all().map(|p| p.x).fold(f64::INFINITY, f64::min);
    if !u0.is_finite() {
        return 0.0;
    }
    let (vlo, vhi) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        (a.min(p.y), b.max(p.y))
    });
    let vspan = (vhi - vlo).max(f64::MIN_POSITIVE);
    let mut total = 0.0;
    for lp in loops {
        let n = lp.len();
        for k in (0..n).filter(|&k| !lp[k].1) {
            let next = lp[(k + 1) % n];
            let (mid, b) = if next.1 && n > 2 {
                (Some(next.0), lp[(k + 2) % n].0)
            } else {
                (None, next.0)
            };
            total += segment_integral(s, u0, vspan, lp[k].0, mid, b);
        }
    }
    total
}

/// `∫ F dv` from `a` to `b`: along the straight line, or along the parabola through `mid`.
fn segment_integral(
    s: &Surface,
    u0: f64,
    vspan: f64,
    a: DVec2,
    mid: Option<DVec2>,
    b: DVec2,
) -> f64 {
    // The path q(σ) and its derivative on σ ∈ [0, 1].
    let q = |x: f64| match mid {
        None => (a + (b - a) * x, b - a),
        Some(m) => (
            a * ((1.0 - x) * (1.0 - 2.0 * x))
                + m * (4.0 * x * (1.0 - x))
                + b * (x * (2.0 * x - 1.0)),
            a * (4.0 * x - 3.0) + m * (4.0 - 8.0 * x) + b * (4.0 * x - 1.0),
        ),
    };
    let reach = match mid {
        None => (b.y - a.y).abs(),
        Some(m) => (m.y - a.y).abs() + (b.y - m.y).abs(),
    };
    if reach == 0.0 {
        return 0.0;
    }
    // Long segments (pole runs, coarse loops) in pieces of at most 1/OUTER_PIECES of the v
    // extent.
    let pieces = ((reach / vspan) * OUTER_PIECES as f64)
        .ceil()
        .clamp(1.0, 1e4) as usize;
    let mut sum = 0.0;
    for piece in 0..pieces {
        for (t, w) in GL3 {
            let (p, dp) = q((piece as f64 + t) / pieces as f64);
            sum += w * inner(s, u0, p.x, p.y) * dp.y;
        }
    }
    sum / pieces as f64
}

/// The allowance for the chordal deficit of a face's flat triangles: `2 δ κ` (δ the chordal
/// tolerance, κ the largest principal curvature at the mesh's (u, v)).
pub fn chordal_allowance(s: &Surface, uv: &[DVec2], chord: f64) -> f64 {
    let mut kappa: f64 = 0.0;
    for q in uv {
        let d = s.deriv2(q.x, q.y);
        let n = d.su.cross(d.sv);
        let Some(n) = n.try_normalize() else { continue };
        let (e, f, g) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
        let (l, m, nn) = (d.suu.dot(n), d.suv.dot(n), d.svv.dot(n));
        let det = e * g - f * f;
        if !(det.is_finite() && det > 0.0) {
            continue;
        }
        let h = (e * nn - 2.0 * f * m + g * l) / (2.0 * det);
        let k = (l * nn - m * m) / det;
        let disc = (h * h - k).max(0.0).sqrt();
        let km = h.abs() + disc;
        if km.is_finite() {
            kappa = kappa.max(km);
        }
    }
    2.0 * chord * kappa
}

/// Checks an edge's polyline against its curve: `None` when they agree, else the message.
pub fn edge_length(
    curve: &dyn ParamCurve,
    ts: &[f64],
    pts: &[flatcut_geom::DVec3],
    chord: f64,
) -> Result<(), String> {
    let (Some(&a), Some(&b)) = (ts.first(), ts.last()) else {
        return Ok(());
    };
    let poly: f64 = pts.windows(2).map(|w| w[0].distance(w[1])).sum();
    let arc = curve.arclen_range(a.min(b), a.max(b), 1e-9 * (1.0 + poly));
    let deficit: f64 = pts
        .windows(2)
        .map(|w| {
            let c = w[0].distance(w[1]);
            if c > 0.0 {
                8.0 * chord * chord / (3.0 * c)
            } else {
                0.0
            }
        })
        .sum();
    let allowed = AREA_REL * arc + deficit.min(arc) + 1e-9;
    if (arc - poly).abs() > allowed {
        return Err(format!(
            "its points run {poly:.4} mm but its curve is {arc:.4} mm long ({:+.3} %)",
            100.0 * (poly - arc) / arc.max(f64::MIN_POSITIVE)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_surface::curve::Frame;
    use flatcut_surface::patch::Analytic;
    use std::f64::consts::{PI, TAU};

    fn rect(u0: f64, u1: f64, v0: f64, v1: f64, n: usize) -> Vec<DVec2> {
        let mut out = Vec::new();
        let corners = [
            DVec2::new(u0, v0),
            DVec2::new(u1, v0),
            DVec2::new(u1, v1),
            DVec2::new(u0, v1),
        ];
        for k in 0..4 {
            for m in 0..n {
                out.push(corners[k] + (corners[(k + 1) % 4] - corners[k]) * (m as f64 / n as f64));
            }
        }
        out
    }

    #[test]
    fn a_spherical_zone_and_a_hole() {
        let s = Surface::Analytic(Analytic::sphere(Frame::WORLD, 40.0).unwrap());
        let zone = rect(0.0, 1.5, -0.3, 1.1, 6);
        let exact = 1600.0 * 1.5 * (1.1f64.sin() - (-0.3f64).sin());
        let a = trim_area(&s, std::slice::from_ref(&zone));
        assert!((a - exact).abs() < 1e-9 * exact, "{a} vs {exact}");
        // The whole sphere, and with the zone as a clockwise hole.
        let all = rect(0.0, TAU, -0.5 * PI, 0.5 * PI, 4);
        let mut hole = zone;
        hole.reverse();
        let a = trim_area(&s, &[all, hole]);
        let want = 4.0 * PI * 1600.0 - exact;
        assert!((a - want).abs() < 1e-9 * want, "{a} vs {want}");
    }

    #[test]
    fn a_swept_surface_by_the_general_rule() {
        // An extrusion of a circle of radius 20 (its area element depends on u only).
        let c = flatcut_surface::curve::Ellipse::circle(Frame::WORLD, 20.0).unwrap();
        let s = Surface::Analytic(
            Analytic::extrusion(std::sync::Arc::new(c), flatcut_geom::DVec3::Z * 30.0).unwrap(),
        );
        let a = trim_area(&s, &[rect(0.2, 2.2, 0.0, 1.0, 3)]);
        let want = 20.0 * 2.0 * 30.0;
        assert!((a - want).abs() < 1e-9 * want, "{a} vs {want}");
    }
}
