//! Cubic Hermite (Ferguson) segments, and the two rules for choosing their end speeds from unit
//! end tangents: Duncan's minimum-energy cubic and Manning's circular-arc speeds (digest A7, A10,
//! A15; errata E7, E8, E12, E22).
//!
//! **Minimum-energy cubic, derived here** (the thesis's intermediate expressions carry errata).
//! Write `d = r1 − r0`, `W = |d|`, speeds `a = ṡ(0)`, `b = ṡ(1)`, `c = t0·t1`. The Hermite
//! derivative is `r'(u) = 6u(1−u) d + a (3u²−4u+1) t0 + b (3u²−2u) t1`, and the basis integrals
//! `∫(6u−6u²)² = 6/5`, `∫(3u²−4u+1)² = ∫(3u²−2u)² = 2/15`, `∫(3u²−4u+1)(3u²−2u) = −1/30`,
//! `∫(6u−6u²)(3u²−4u+1) = ∫(6u−6u²)(3u²−2u) = −1/10` give
//!
//! `E(a, b) = ∫₀¹|r'|² = 6W²/5 + 2(a² + b²)/15 − abc/15 − (a d·t0 + b d·t1)/5`.
//!
//! `E` is a convex quadratic (Hessian `[[4, −c], [−c, 4]]/15`, positive definite since `|c| ≤ 1`),
//! and `∇E = 0` is the 2×2 system `4a − cb = 3 d·t0`, `−ca + 4b = 3 d·t1`, so
//! `a = 3(4 d·t0 + c d·t1)/(16 − c²)`, `b = 3(4 d·t1 + c d·t0)/(16 − c²)` — Duncan's optimum
//! speeds (digest A10), valid in 3D with `c` the independent value `t0·t1`.
//!
//! **Manning's circular-arc speeds.** If the end data lie on a circle, the chord `d` makes the
//! angle α with both tangents and the arc angle is `Θ = 2α`; the cubic Bézier that best matches
//! the arc has handles `(4/3) tan(Θ/4) R` (errata E22) with `R = W / (2 sin(Θ/2))`, i.e. speed
//! `3 · handle = W / cos²(Θ/4) = 2W / (1 + cos α)`. We apply this per end with `cos α_i = d·t_i/W`,
//! which is exact for circular data and tends to `W` (the straight line) as the tangents align
//! with the chord.

use glam::DVec3;

use super::bezier::Bezier;
use crate::{ParamCurve, SurfaceError};

/// A cubic Hermite segment on `[0, 1]`: `r(0) = p0`, `r'(0) = t0`, `r(1) = p1`, `r'(1) = t1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hermite {
    /// Start point.
    pub p0: DVec3,
    /// Start derivative (tangent times speed).
    pub t0: DVec3,
    /// End point.
    pub p1: DVec3,
    /// End derivative.
    pub t1: DVec3,
}

impl Hermite {
    /// Builds a Hermite segment from end points and end derivatives (all finite).
    pub fn new(p0: DVec3, t0: DVec3, p1: DVec3, t1: DVec3) -> Result<Self, SurfaceError> {
        super::bezier::check_finite(&[p0, t0, p1, t1], "Hermite datum (p0, t0, p1, t1)")?;
        Ok(Self { p0, t0, p1, t1 })
    }

    /// Power-basis coefficients `[a0, a1, a2, a3]` with `r(u) = Σ a_j u^j`.
    pub fn to_power(&self) -> [DVec3; 4] {
        let d = self.p1 - self.p0;
        [
            self.p0,
            self.t0,
            3.0 * d - 2.0 * self.t0 - self.t1,
            -2.0 * d + self.t0 + self.t1,
        ]
    }

    /// The same cubic as a Bézier curve: `b1 = p0 + t0/3`, `b2 = p1 − t1/3`.
    pub fn to_bezier(&self) -> Bezier {
        Bezier::from_points_unchecked(vec![
            self.p0,
            self.p0 + self.t0 / 3.0,
            self.p1 - self.t1 / 3.0,
            self.p1,
        ])
    }

    /// The same segment traversed backwards (`u ↦ 1 − u`).
    pub fn reversed(&self) -> Hermite {
        Hermite {
            p0: self.p1,
            t0: -self.t1,
            p1: self.p0,
            t1: -self.t0,
        }
    }

    /// The energy `∫₀¹ |r'(u)|² du` minimised by [`min_energy_cubic`] (exact: the integrand is a
    /// quartic, integrated by 16-point Gauss–Legendre).
    pub fn energy(&self) -> f64 {
        flatcut_geom::num::gauss16(|u| self.deriv(u, 1).length_squared(), 0.0, 1.0)
    }
}

impl ParamCurve for Hermite {
    fn domain(&self) -> (f64, f64) {
        (0.0, 1.0)
    }

    fn eval(&self, u: f64) -> DVec3 {
        let [a0, a1, a2, a3] = self.to_power();
        ((a3 * u + a2) * u + a1) * u + a0
    }

    fn deriv(&self, u: f64, k: usize) -> DVec3 {
        let [a0, a1, a2, a3] = self.to_power();
        match k {
            0 => ((a3 * u + a2) * u + a1) * u + a0,
            1 => (3.0 * a3 * u + 2.0 * a2) * u + a1,
            2 => 6.0 * a3 * u + 2.0 * a2,
            3 => 6.0 * a3,
            _ => DVec3::ZERO,
        }
    }
}

/// Normalises an end tangent, naming it in the error.
fn unit_tangent(t: DVec3, which: &'static str) -> Result<DVec3, SurfaceError> {
    let u = t.normalize_or_zero();
    if !flatcut_geom::finite3(t) || u == DVec3::ZERO {
        return Err(SurfaceError::EndTangent { which, tangent: t });
    }
    Ok(u)
}

/// Validated end data: unit tangents, chord and its length.
fn end_data(
    r0: DVec3,
    t0: DVec3,
    r1: DVec3,
    t1: DVec3,
) -> Result<(DVec3, DVec3, DVec3, f64), SurfaceError> {
    super::bezier::check_finite(&[r0, r1], "end point (r0, r1)")?;
    let u0 = unit_tangent(t0, "t0")?;
    let u1 = unit_tangent(t1, "t1")?;
    let d = r1 - r0;
    let w = d.length();
    if w == 0.0 || !w.is_finite() {
        return Err(SurfaceError::EndsCoincide { r0, r1 });
    }
    Ok((u0, u1, d, w))
}

/// The end speeds `(ṡ(0), ṡ(1))` of the minimum-energy cubic through `r0`, `r1` with unit
/// tangent directions `t0`, `t1` (normalised here): the solution of
/// `4a − c b = 3 d·t0`, `−c a + 4b = 3 d·t1` (see the module docs).
///
/// Errors when the points coincide, a tangent is zero, or an optimal speed is not positive:
/// Duncan's claim that the speed is positive iff `d·t_i > 0` fails in 3D (errata E12), and a
/// non-positive speed would reverse the designer's tangent.
pub fn min_energy_speeds(
    r0: DVec3,
    t0: DVec3,
    r1: DVec3,
    t1: DVec3,
) -> Result<(f64, f64), SurfaceError> {
    let (u0, u1, d, _) = end_data(r0, t0, r1, t1)?;
    let c = u0.dot(u1);
    let (g0, g1) = (d.dot(u0), d.dot(u1));
    let det = 16.0 - c * c;
    let a = 3.0 * (4.0 * g0 + c * g1) / det;
    let b = 3.0 * (4.0 * g1 + c * g0) / det;
    for (speed, which) in [(a, "start"), (b, "end")] {
        if speed.is_nan() || speed <= 0.0 {
            return Err(SurfaceError::ReversedSpeed { which, speed });
        }
    }
    Ok((a, b))
}

/// Duncan's minimum-energy cubic: among the cubics through `r0`, `r1` with end tangent directions
/// `t0`, `t1`, the one minimising `∫₀¹|r'(u)|² du` (digest A10, TV41). Tangents are normalised;
/// see [`min_energy_speeds`] for the errors.
pub fn min_energy_cubic(
    r0: DVec3,
    t0: DVec3,
    r1: DVec3,
    t1: DVec3,
) -> Result<Hermite, SurfaceError> {
    let (a, b) = min_energy_speeds(r0, t0, r1, t1)?;
    let (u0, u1) = (t0.normalize(), t1.normalize());
    Hermite::new(r0, a * u0, r1, b * u1)
}

/// Smallest `1 + cos α` accepted by [`manning_cubic`]: a tangent turned more than ~154° away from
/// the chord asks for an arc of over 300°, which a single cubic cannot follow (speed > 20 W).
const MANNING_MIN_ONE_PLUS_COS: f64 = 0.1;

/// The end speeds of Manning's circular-arc rule: `ṡ_i = 2W / (1 + cos α_i)` with
/// `cos α_i = (r1 − r0)·t_i / W` (see the module docs; exact handle `(4/3) tan(Θ/4) R` on
/// circular data, errata E22).
pub fn manning_speeds(
    r0: DVec3,
    t0: DVec3,
    r1: DVec3,
    t1: DVec3,
) -> Result<(f64, f64), SurfaceError> {
    let (u0, u1, d, w) = end_data(r0, t0, r1, t1)?;
    let mut out = [0.0; 2];
    for (i, (u, which)) in [(u0, "t0"), (u1, "t1")].into_iter().enumerate() {
        let one_plus_cos = 1.0 + (d.dot(u) / w).clamp(-1.0, 1.0);
        if one_plus_cos < MANNING_MIN_ONE_PLUS_COS {
            return Err(SurfaceError::TangentBackwards {
                which,
                one_plus_cos,
            });
        }
        out[i] = 2.0 * w / one_plus_cos;
    }
    Ok((out[0], out[1]))
}

/// The cubic with Manning's circular-arc end speeds ([`manning_speeds`]): for end data taken from
/// a circle it is the standard cubic arc approximation (quarter circle radius error 2.7e-4,
/// TV20).
pub fn manning_cubic(r0: DVec3, t0: DVec3, r1: DVec3, t1: DVec3) -> Result<Hermite, SurfaceError> {
    let (a, b) = manning_speeds(r0, t0, r1, t1)?;
    Hermite::new(r0, a * t0.normalize(), r1, b * t1.normalize())
}

/// How a [`HermiteSpline`] chooses the end speeds of each segment from unit tangents.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SpeedRule {
    /// Duncan's minimum-energy speeds ([`min_energy_speeds`]).
    MinimumEnergy,
    /// Manning's circular-arc speeds ([`manning_speeds`]): reproduces circles closely, the
    /// usual choice for pattern outlines.
    #[default]
    Manning,
}

/// A G¹ chain of cubic Hermite segments through points with given (or estimated) unit tangent
/// directions, each segment's end speeds chosen by a [`SpeedRule`] — Duncan's practical advice
/// (digest A11): relax C² and control the speeds instead. Segment `i` covers `[i, i + 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct HermiteSpline {
    segments: Vec<Hermite>,
}

impl HermiteSpline {
    /// Through `points` with unit tangent directions `tangents` (normalised here; one per point).
    pub fn new(
        points: &[DVec3],
        tangents: &[DVec3],
        rule: SpeedRule,
    ) -> Result<Self, SurfaceError> {
        if points.len() < 2 {
            return Err(SurfaceError::ControlPointCount {
                expected: 2,
                got: points.len(),
            });
        }
        if tangents.len() != points.len() {
            return Err(SurfaceError::TangentCount {
                points: points.len(),
                tangents: tangents.len(),
            });
        }
        let mut segments = Vec::with_capacity(points.len() - 1);
        for i in 0..points.len() - 1 {
            let (r0, t0, r1, t1) = (points[i], tangents[i], points[i + 1], tangents[i + 1]);
            let seg = match rule {
                SpeedRule::MinimumEnergy => min_energy_cubic(r0, t0, r1, t1),
                SpeedRule::Manning => manning_cubic(r0, t0, r1, t1),
            }
            .map_err(|e| SurfaceError::Segment {
                index: i,
                next: i + 1,
                source: Box::new(e),
            })?;
            segments.push(seg);
        }
        Ok(Self { segments })
    }

    /// Through `points` with tangent directions estimated by Bessel's rule (the tangent of the
    /// chord-length parabola through each point and its neighbours; at open ends the parabola's
    /// end tangent). `closed` joins the last point back to the first (a repeated closing point is
    /// dropped).
    pub fn through(points: &[DVec3], closed: bool, rule: SpeedRule) -> Result<Self, SurfaceError> {
        super::bezier::check_finite(points, "spline point")?;
        let mut pts = points.to_vec();
        if closed && pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        let m = pts.len();
        if m < 2 || (closed && m < 3) {
            return Err(SurfaceError::ControlPointCount {
                expected: if closed { 3 } else { 2 },
                got: m,
            });
        }
        // Tangent of the parabola through (a, b, c) at parameters (0, h0, h0 + h1), at `which`.
        let bessel = |a: DVec3, b: DVec3, c: DVec3, which: usize| -> DVec3 {
            let (h0, h1) = (a.distance(b), b.distance(c));
            if h0 == 0.0 || h1 == 0.0 {
                return c - a;
            }
            let (d01, d12) = ((b - a) / h0, (c - b) / h1);
            let dd = (d12 - d01) / (h0 + h1);
            match which {
                0 => d01 - h0 * dd,
                1 => d01 + h0 * dd,
                _ => d01 + (h0 + 2.0 * h1) * dd,
            }
        };
        let mut tangents = Vec::with_capacity(m + 1);
        for i in 0..m {
            let t = if closed {
                bessel(pts[(i + m - 1) % m], pts[i], pts[(i + 1) % m], 1)
            } else if m == 2 {
                pts[1] - pts[0]
            } else if i == 0 {
                bessel(pts[0], pts[1], pts[2], 0)
            } else if i == m - 1 {
                bessel(pts[m - 3], pts[m - 2], pts[m - 1], 2)
            } else {
                bessel(pts[i - 1], pts[i], pts[i + 1], 1)
            };
            tangents.push(t);
        }
        if closed {
            pts.push(pts[0]);
            tangents.push(tangents[0]);
        }
        Self::new(&pts, &tangents, rule)
    }

    /// The same chain traversed backwards (`t ↦ n − t`).
    pub fn reversed(&self) -> HermiteSpline {
        HermiteSpline {
            segments: self.segments.iter().rev().map(Hermite::reversed).collect(),
        }
    }

    /// The segments; segment `i` covers `[i, i + 1]`.
    pub fn segments(&self) -> &[Hermite] {
        &self.segments
    }

    fn locate(&self, t: f64) -> (usize, f64) {
        let n = self.segments.len();
        let i = if t.is_nan() {
            0
        } else {
            (t.floor().max(0.0) as usize).min(n - 1)
        };
        (i, t - i as f64)
    }
}

impl ParamCurve for HermiteSpline {
    fn domain(&self) -> (f64, f64) {
        (0.0, self.segments.len() as f64)
    }

    fn eval(&self, t: f64) -> DVec3 {
        let (i, u) = self.locate(t);
        self.segments[i].eval(u)
    }

    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        let (i, u) = self.locate(t);
        self.segments[i].deriv(u, k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CurveExt;
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, SQRT_2};

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).abs().max_element() <= tol
    }

    fn v2(x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, 0.0)
    }

    #[test]
    fn tv6_and_tv7_hermite_power_forms() {
        let h = Hermite::new(v2(0., 0.), v2(1., 1.), v2(1., 0.), v2(0., -1.)).unwrap();
        let p = h.to_power();
        assert!(close(p[3], v2(-1., 0.), 1e-15));
        assert!(close(p[2], v2(1., -1.), 1e-15));
        assert!(close(p[1], v2(1., 1.), 1e-15));
        // Unnormalised principal normal N = P'' − (P''·P'/|P'|²) P'.
        let n = |t: f64| {
            let (d1, d2) = (h.deriv(t, 1), h.deriv(t, 2));
            d2 - d2.dot(d1) / d1.length_squared() * d1
        };
        assert!(close(n(0.0), v2(2., -2.), 1e-14));
        assert!(close(n(0.5), v2(0., -2.), 1e-14));
        assert!(close(n(1.0), v2(-4., 0.), 1e-14));
        let g = Hermite::new(DVec3::ZERO, DVec3::X, DVec3::ONE, DVec3::Y).unwrap();
        for t in [0.0, 0.3, 0.8, 1.0] {
            let want = DVec3::new(
                -t * t * t + t * t + t,
                -t * t * t + 2.0 * t * t,
                -2.0 * t * t * t + 3.0 * t * t,
            );
            assert!(close(g.eval(t), want, 1e-15));
            assert!(close(g.to_bezier().eval(t), want, 1e-15));
        }
    }

    #[test]
    fn tv41_quarter_circle_minimum_energy() {
        let (r0, r1) = (DVec3::X, DVec3::Y);
        let (t0, t1) = (DVec3::Y, -DVec3::X);
        let (a, b) = min_energy_speeds(r0, t0, r1, t1).unwrap();
        assert!((a - 0.75).abs() < 1e-15 && (b - 0.75).abs() < 1e-15);
        let h = min_energy_cubic(r0, t0, r1, t1).unwrap();
        assert!((h.energy() - 2.25).abs() < 1e-14);
        assert!((h.curvature(0.0).unwrap() - 8.0).abs() < 1e-12);
        assert!((h.curvature(1.0).unwrap() - 8.0).abs() < 1e-12);
        // Manning's speeds on the same data: 2W/(1 + cos 45°) = 4 − 4/(2+√2)·… ≈ 1.657.
        let (ma, mb) = manning_speeds(r0, t0, r1, t1).unwrap();
        assert!((ma - 2.0 * SQRT_2 / (1.0 + SQRT_2 / 2.0)).abs() < 1e-15);
        assert!((ma - 1.6568542495).abs() < 1e-9 && (ma - mb).abs() < 1e-15);
    }

    #[test]
    fn straight_line_speed_is_the_chord_length() {
        let (r0, r1) = (DVec3::new(1., 2., 3.), DVec3::new(4., -2., 3.));
        let t = (r1 - r0).normalize();
        let (a, b) = min_energy_speeds(r0, t, r1, t).unwrap();
        assert!((a - 5.0).abs() < 1e-14 && (b - 5.0).abs() < 1e-14);
        let (ma, mb) = manning_speeds(r0, t, r1, t).unwrap();
        assert!((ma - 5.0).abs() < 1e-14 && (mb - 5.0).abs() < 1e-14);
        // Energy of the uniformly traversed segment is W².
        assert!((min_energy_cubic(r0, t, r1, t).unwrap().energy() - 25.0).abs() < 1e-12);
    }

    #[test]
    fn tv20_manning_quarter_circle_is_the_standard_cubic_arc() {
        let h = manning_cubic(DVec3::X, DVec3::Y, DVec3::Y, -DVec3::X).unwrap();
        let b = h.to_bezier();
        let k = 4.0 * (SQRT_2 - 1.0) / 3.0;
        assert!(close(b.points()[1], v2(1.0, k), 1e-15));
        assert!(close(b.points()[2], v2(k, 1.0), 1e-15));
        let mut worst: f64 = 0.0;
        for i in 0..=2000 {
            worst = worst.max((h.eval(i as f64 / 2000.0).length() - 1.0).abs());
        }
        assert!(worst <= 2.8e-4, "radius error {worst}");
        let tmax = (3.0 - 3f64.sqrt()) / 6.0;
        assert!((h.eval(tmax).length() - 1.00027253).abs() < 1e-8);
    }

    #[test]
    fn manning_handles_follow_errata_e22_for_any_arc() {
        for theta in [0.2, 1.0, FRAC_PI_2, 2.5, 3.0] {
            let r = 7.0;
            let on = |a: f64| DVec3::new(r * a.cos(), r * a.sin(), 0.0);
            let tan = |a: f64| DVec3::new(-a.sin(), a.cos(), 0.0);
            let h = manning_cubic(on(0.0), tan(0.0), on(theta), tan(theta)).unwrap();
            let handle = h.t0.length() / 3.0;
            let want = 4.0 / 3.0 * (theta / 4.0).tan() * r;
            assert!((handle - want).abs() < 1e-12 * r, "Θ={theta}");
        }
        assert!(manning_speeds(DVec3::ZERO, -DVec3::X, DVec3::X, DVec3::X).is_err());
    }

    #[test]
    fn rejects_degenerate_end_data() {
        assert!(min_energy_cubic(DVec3::X, DVec3::Y, DVec3::X, DVec3::Y).is_err());
        assert!(min_energy_cubic(DVec3::ZERO, DVec3::ZERO, DVec3::X, DVec3::Y).is_err());
        assert!(min_energy_cubic(DVec3::ZERO, DVec3::NAN, DVec3::X, DVec3::Y).is_err());
        // Errata E12 counterexample: cos θ = 0.0262 > 0, yet the optimal start speed is negative.
        let d = DVec3::X;
        let t0 = DVec3::new(0.0262, (1.0 - 0.0262f64 * 0.0262).sqrt(), 0.0);
        // Choose t1 with d·t1 = −0.327 and t0·t1 = 0.747.
        let y = (0.747 - 0.0262 * -0.327) / t0.y;
        let t1 = DVec3::new(-0.327, y, (1.0 - 0.327f64 * 0.327 - y * y).sqrt());
        assert!((t0.dot(t1) - 0.747).abs() < 1e-12);
        assert!(min_energy_speeds(DVec3::ZERO, t0, d, t1).is_err());
    }

    #[test]
    fn hermite_spline_through_circle_points() {
        let r = 80.0;
        let m = 8;
        let pts: Vec<DVec3> = (0..m)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / m as f64;
                DVec3::new(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect();
        let s = HermiteSpline::through(&pts, true, SpeedRule::Manning).unwrap();
        assert_eq!(s.domain(), (0.0, 8.0));
        let mut worst: f64 = 0.0;
        for i in 0..=8000 {
            worst = worst.max((s.eval(i as f64 / 1000.0).length() - r).abs());
        }
        // 45° cubic arcs: relative radius error 4.2e-6.
        assert!(worst / r < 5e-6, "relative radius error {}", worst / r);
        for i in 1..8 {
            let t = i as f64;
            assert!((s.eval(t - 1e-12) - s.eval(t)).length() < 1e-9);
            let (a, b) = (s.deriv(t - 1e-12, 1).normalize(), s.deriv(t, 1).normalize());
            assert!((a - b).length() < 1e-9, "G1 at joint {i}");
        }
        let e = HermiteSpline::through(&pts, false, SpeedRule::MinimumEnergy).unwrap();
        assert_eq!(e.segments().len(), 7);
        for (i, p) in pts.iter().enumerate() {
            assert!((e.eval(i as f64) - *p).length() < 1e-12);
        }
        assert!(HermiteSpline::through(&pts[..1], false, SpeedRule::Manning).is_err());
        assert!(HermiteSpline::new(&pts, &pts[..3], SpeedRule::Manning).is_err());
    }

    proptest! {
        #[test]
        fn optimum_minimises_energy_and_matches_duncan(
            r1 in (-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0),
            t0 in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            t1 in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            da in -0.3f64..0.3, db in -0.3f64..0.3,
        ) {
            let r0 = DVec3::new(0.5, -0.2, 0.1);
            let r1 = DVec3::new(r1.0, r1.1, r1.2);
            let (t0, t1) = (DVec3::new(t0.0, t0.1, t0.2), DVec3::new(t1.0, t1.1, t1.2));
            prop_assume!(t0.length() > 0.1 && t1.length() > 0.1 && (r1 - r0).length() > 0.1);
            if let Ok(h) = min_energy_cubic(r0, t0, r1, t1) {
                let (u0, u1) = (t0.normalize(), t1.normalize());
                let (a, b) = (h.t0.length(), h.t1.length());
                // Closed-form energy (digest A10) equals the integral.
                let d = r1 - r0;
                let w = d.length();
                let (ct, cp, c) = (d.dot(u0) / w, d.dot(u1) / w, u0.dot(u1));
                let e = w * (6.0 * w - a * ct - b * cp) / 5.0 + (2.0 * a * a + 2.0 * b * b - a * b * c) / 15.0;
                prop_assert!((e - h.energy()).abs() < 1e-10 * (1.0 + e));
                // Any other speeds cost more.
                let other = Hermite::new(r0, (a + da) * u0, r1, (b + db) * u1).unwrap();
                prop_assert!(other.energy() >= h.energy() - 1e-12);
                // End curvature by Duncan's corrected formula (errata E7).
                let f = |ang_a: f64, ang_b: f64, alpha: f64| {
                    let (sa, ca, cb) = (ang_a.sin(), ang_a.cos(), ang_b.cos());
                    3.0 * w * (3.0 * w * sa * sa - 2.0 * alpha * (cb - ca * c)) + alpha * alpha * (1.0 - c * c)
                };
                let (th, ph) = (ct.clamp(-1.0, 1.0).acos(), cp.clamp(-1.0, 1.0).acos());
                let k0 = 2.0 * f(th, ph, b).max(0.0).sqrt() / (a * a);
                let k1 = 2.0 * f(ph, th, a).max(0.0).sqrt() / (b * b);
                let g0 = h.curvature(0.0).unwrap();
                let g1 = h.curvature(1.0).unwrap();
                prop_assert!((k0 - g0).abs() < 1e-6 * (1.0 + g0), "κ0 {} vs {}", k0, g0);
                prop_assert!((k1 - g1).abs() < 1e-6 * (1.0 + g1), "κ1 {} vs {}", k1, g1);
                // Torsion at the start (errata E7): τ(0) = 3ṡ(1)[t0, d, t1]/(ṡ(0) f(θ, φ, ṡ(1))).
                let ff = f(th, ph, b);
                if ff > 1e-6 {
                    let tau0 = 3.0 * b * u0.dot(d.cross(u1)) / (a * ff);
                    if let Some(g) = h.torsion(0.0) {
                        prop_assert!((tau0 - g).abs() < 1e-6 * (1.0 + g.abs()), "τ0 {} vs {}", tau0, g);
                    }
                }
            }
        }
    }
}
