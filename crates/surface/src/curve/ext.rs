//! Measurements that work for any [`ParamCurve`]: arc length and its inverse, curvature,
//! torsion, the Frenet frame, the closest point, and flattening to a polyline within a chordal
//! tolerance (digest A16–A20).
//!
//! All of them are default methods of the blanket extension trait [`CurveExt`], so every curve
//! type (and `dyn ParamCurve`) gets them.

use glam::DVec3;

use crate::ParamCurve;
use flatcut_geom::num::integrate;

/// The Frenet frame: unit tangent `t`, principal normal `n`, binormal `b = t × n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frenet {
    /// Unit tangent.
    pub t: DVec3,
    /// Unit principal normal (towards the centre of curvature).
    pub n: DVec3,
    /// Unit binormal.
    pub b: DVec3,
}

/// Default accuracy of the arc-length integrals used by [`CurveExt::flatten`] and friends, in mm.
pub const DEFAULT_ARCLEN_ACCURACY: f64 = 1e-9;

/// Equal parameter panels an arc length is split into before adaptive refinement (see
/// `arclen_range`); 8 panels cost 192 speed evaluations at the first level, nothing next to
/// the refinement a tight turn needs anyway.
const ARCLEN_MIN_PANELS: usize = 8;

/// Samples per curve for the global phase of [`CurveExt::nearest`]: enough to separate the
/// distance minima of design curves (a cubic has at most 3, a spline a few per span).
const NEAREST_SAMPLES: usize = 128;
/// Newton iterations per candidate in [`CurveExt::nearest`]; quadratic convergence needs < 10.
const NEAREST_MAX_ITER: usize = 60;
/// Initial uniform intervals of [`CurveExt::flatten`], so that features narrower than the whole
/// domain are not skipped by the first chord test.
const FLATTEN_INITIAL_INTERVALS: usize = 16;
/// Subdivision depth limit of [`CurveExt::flatten`] below each initial interval (≥ 2^24 pieces).
const FLATTEN_MAX_DEPTH: u32 = 24;
/// Most pieces an interval is split into at once; larger predicted counts are approached in
/// two steps, so a poor estimate on a long interval cannot explode the output.
const FLATTEN_MAX_SPLIT: f64 = 64.0;
/// The deviation estimate of [`CurveExt::flatten`] (samples plus the sagitta bound) must stay
/// below this fraction of the tolerance: the estimate is not an upper bound in general (it
/// misses by < 0.1 % on random cubics), and the margin costs only ~12 % more vertices since the
/// count grows as `tol^(-1/2)`.
const FLATTEN_SAFETY: f64 = 0.8;
/// Sine of the angle between `r'` and `r''` below which the osculating plane is undefined
/// (straight or inflection point): no principal normal, torsion undefined.
const COLLINEAR_SINE: f64 = 1e-12;

/// Arc length, curvature, Frenet frame, closest point and flattening for every [`ParamCurve`].
pub trait CurveExt: ParamCurve {
    /// Arc length over the whole domain, to absolute `accuracy` (mm), by adaptive
    /// Gauss–Legendre quadrature of `|r'|`.
    fn arclen(&self, accuracy: f64) -> f64 {
        let (a, b) = self.domain();
        self.arclen_range(a, b, accuracy)
    }

    /// Arc length from `t0` to `t1` (negative when `t1 < t0`), to absolute `accuracy`.
    fn arclen_range(&self, t0: f64, t1: f64, accuracy: f64) -> f64 {
        // The adaptive rule's error estimate (8- vs 16-point Gauss on a panel) can agree by
        // coincidence on a speed with sharp dips, as a wiggly quartic's has at its tight turns;
        // starting from [`ARCLEN_MIN_PANELS`] panels leaves each at most one such turn.
        let n = ARCLEN_MIN_PANELS;
        let h = (t1 - t0) / n as f64;
        (0..n)
            .map(|i| {
                let a = t0 + h * i as f64;
                let b = if i + 1 == n { t1 } else { a + h };
                integrate(|t| self.deriv(t, 1).length(), a, b, accuracy / n as f64)
            })
            .sum()
    }

    /// The parameter at arc length `s` from the domain start, to absolute arc-length `accuracy`
    /// (safeguarded Newton steps on `s(t) − s`, bisection when a step leaves the bracket).
    /// `s` is clamped to `[0, arclen]`.
    fn inv_arclen(&self, s: f64, accuracy: f64) -> f64 {
        let (a, b) = self.domain();
        let piece_acc = accuracy / 16.0;
        if s <= 0.0 {
            return a;
        }
        let total = self.arclen_range(a, b, piece_acc);
        if s >= total {
            return b;
        }
        let t = a + (b - a) * (s / total);
        let cur = self.arclen_range(a, t, piece_acc);
        seek_arclen(self, s, (t, cur), (a, b), accuracy).0
    }

    /// The parameters at the given arc lengths from the domain start (sorted ascending, clamped
    /// to `[0, arclen]`), each to absolute arc-length `accuracy`: equal spacing of notches,
    /// stitch marks or drill holes along a seam. One sweep, integrating only between
    /// consecutive targets.
    fn params_at_arclens(&self, lengths: &[f64], accuracy: f64) -> Vec<f64> {
        let (a, b) = self.domain();
        let mut out = Vec::with_capacity(lengths.len());
        let (mut t, mut cur) = (a, 0.0);
        for &s in lengths {
            (t, cur) = seek_arclen(self, s, (t, cur), (t, b), accuracy);
            out.push(t);
        }
        out
    }

    /// Curvature `|r' × r''| / |r'|³`; `None` where the parametrisation is singular (`r' = 0`).
    fn curvature(&self, t: f64) -> Option<f64> {
        let d1 = self.deriv(t, 1);
        let d2 = self.deriv(t, 2);
        let s = d1.length();
        if s.is_nan() || s <= 0.0 {
            return None;
        }
        let k = d1.cross(d2).length() / (s * s * s);
        k.is_finite().then_some(k)
    }

    /// Signed curvature of the projection to the xy plane, `(x'y'' − y'x'')/|r'_xy|³`: positive
    /// for left turns (the left-normal convention of digest A17). `None` where `r'_xy = 0`.
    fn curvature_xy(&self, t: f64) -> Option<f64> {
        let d1 = self.deriv(t, 1).truncate();
        let d2 = self.deriv(t, 2).truncate();
        let s = d1.length();
        if s.is_nan() || s <= 0.0 {
            return None;
        }
        let k = d1.perp_dot(d2) / (s * s * s);
        k.is_finite().then_some(k)
    }

    /// Torsion `[r', r'', r'''] / |r' × r''|²`; `None` where the osculating plane is undefined
    /// (`r'` and `r''` parallel, e.g. on a straight piece).
    fn torsion(&self, t: f64) -> Option<f64> {
        let d1 = self.deriv(t, 1);
        let d2 = self.deriv(t, 2);
        let c = d1.cross(d2);
        let c2 = c.length_squared();
        if c2.is_nan() || c2.sqrt() <= COLLINEAR_SINE * d1.length() * d2.length() {
            return None;
        }
        let tau = c.dot(self.deriv(t, 3)) / c2;
        tau.is_finite().then_some(tau)
    }

    /// The Frenet frame `(T, N, B)`; `None` where it is undefined (`r' = 0` or `r' ∥ r''`).
    fn frenet(&self, t: f64) -> Option<Frenet> {
        let d1 = self.deriv(t, 1);
        let d2 = self.deriv(t, 2);
        let c = d1.cross(d2);
        if c.is_nan() || c.length() <= COLLINEAR_SINE * d1.length() * d2.length() {
            return None;
        }
        let tt = d1.normalize();
        let b = c.normalize();
        let n = b.cross(tt);
        flatcut_geom::finite3(tt + n + b).then_some(Frenet { t: tt, n, b })
    }

    /// The closest point of the curve to `p`: returns `(t, distance)`. Global: the curve is
    /// sampled, every sampled distance minimum is refined by safeguarded Newton iteration on
    /// `(r(t) − p)·r'(t) = 0` until the step moves the point less than `accuracy` (mm), and the
    /// domain ends are candidates too.
    fn nearest(&self, p: DVec3, accuracy: f64) -> (f64, f64) {
        let (a, b) = self.domain();
        let ts: Vec<f64> = (0..=NEAREST_SAMPLES)
            .map(|i| a + (b - a) * (i as f64 / NEAREST_SAMPLES as f64))
            .collect();
        nearest_from_samples(self, p, accuracy, &ts)
    }

    /// Flattens the curve to a polyline whose chordal deviation from the curve is at most `tol`
    /// (mm); returns `(parameter, point)` pairs including both ends, in parameter order.
    fn flatten(&self, tol: f64) -> Vec<(f64, DVec3)> {
        let (a, b) = self.domain();
        let breaks: Vec<f64> = (0..=FLATTEN_INITIAL_INTERVALS)
            .map(|i| a + (b - a) * (i as f64 / FLATTEN_INITIAL_INTERVALS as f64))
            .collect();
        flatten_with_breaks(self, tol, &breaks)
    }
}

impl<C: ParamCurve + ?Sized> CurveExt for C {}

/// [`CurveExt::nearest`] with caller-chosen sample parameters (sorted); piecewise curves pass
/// their breakpoints refined, so that every span is sampled.
pub fn nearest_from_samples<C: ParamCurve + ?Sized>(
    c: &C,
    p: DVec3,
    accuracy: f64,
    ts: &[f64],
) -> (f64, f64) {
    let dist2: Vec<f64> = ts.iter().map(|&t| c.eval(t).distance_squared(p)).collect();
    let mut best = (ts[0], dist2[0]);
    let last = ts.len() - 1;
    if dist2[last] < best.1 {
        best = (ts[last], dist2[last]);
    }
    for i in 0..=last {
        let left = if i > 0 { dist2[i - 1] } else { f64::INFINITY };
        let right = if i < last {
            dist2[i + 1]
        } else {
            f64::INFINITY
        };
        if dist2[i] <= left && dist2[i] <= right {
            let lo = ts[i.saturating_sub(1)];
            let hi = ts[(i + 1).min(last)];
            let t = refine_nearest(c, p, accuracy, ts[i], lo, hi);
            let d = c.eval(t).distance_squared(p);
            if d < best.1 {
                best = (t, d);
            }
        }
        if dist2[i] < best.1 {
            best = (ts[i], dist2[i]);
        }
    }
    (best.0, best.1.sqrt())
}

/// Safeguarded Newton on `g(t) = (r − p)·r'` inside `[lo, hi]`.
fn refine_nearest<C: ParamCurve + ?Sized>(
    c: &C,
    p: DVec3,
    accuracy: f64,
    t0: f64,
    mut lo: f64,
    mut hi: f64,
) -> f64 {
    let mut t = t0;
    for _ in 0..NEAREST_MAX_ITER {
        let r = c.eval(t) - p;
        let d1 = c.deriv(t, 1);
        let d2 = c.deriv(t, 2);
        let g = r.dot(d1);
        if g == 0.0 {
            break;
        }
        // The distance decreases towards larger t when g < 0.
        if g < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let gp = d1.length_squared() + r.dot(d2);
        let mut next = if gp > 0.0 { t - g / gp } else { f64::NAN };
        if !(next >= lo && next <= hi) {
            next = 0.5 * (lo + hi);
        }
        let moved = (next - t).abs() * d1.length();
        t = next;
        if moved <= accuracy || hi - lo <= f64::EPSILON * t.abs().max(1.0) {
            break;
        }
    }
    t
}

/// Distance from `q` to the segment `a`–`b`.
fn dist_to_segment(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return q.distance(a);
    }
    let s = ((q - a).dot(ab) / l2).clamp(0.0, 1.0);
    q.distance(a + s * ab)
}

/// [`CurveExt::flatten`] starting from the given sorted breakpoints (knots of piecewise curves,
/// where derivatives may jump). The deviation of the curve from each chord is estimated from
/// three interior samples and the parabolic sagitta `h²|r''_⊥|/8` at the midpoint; an interval
/// whose estimate exceeds 0.8·`tol` (a safety margin) is split into `⌈√(err/tol)⌉` equal pieces
/// (deviation shrinks quadratically with chord length) and each piece is checked again.
pub fn flatten_with_breaks<C: ParamCurve + ?Sized>(
    c: &C,
    tol: f64,
    breaks: &[f64],
) -> Vec<(f64, DVec3)> {
    let tol = if tol.is_finite() && tol > 0.0 {
        tol
    } else {
        flatcut_geom::Tolerances::DEFAULT_CHORD_MM
    };
    let mut out = Vec::new();
    if breaks.is_empty() {
        return out;
    }
    let tol = FLATTEN_SAFETY * tol;
    out.push((breaks[0], c.eval(breaks[0])));
    for w in breaks.windows(2) {
        if w[1] > w[0] {
            flatten_rec(c, tol, w[0], c.eval(w[0]), w[1], c.eval(w[1]), 0, &mut out);
        }
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn flatten_rec<C: ParamCurve + ?Sized>(
    c: &C,
    tol: f64,
    a: f64,
    pa: DVec3,
    b: f64,
    pb: DVec3,
    depth: u32,
    out: &mut Vec<(f64, DVec3)>,
) {
    let m = 0.5 * (a + b);
    let mut err = dist_to_segment(c.eval(m), pa, pb);
    for f in [0.25, 0.75] {
        err = err.max(dist_to_segment(c.eval(a + f * (b - a)), pa, pb));
    }
    let chord = pb - pa;
    let d2 = c.deriv(m, 2) * (b - a) * (b - a);
    let perp = if chord.length_squared() > 0.0 {
        d2 - d2.dot(chord) / chord.length_squared() * chord
    } else {
        d2
    };
    err = err.max(perp.length() / 8.0);
    if err > tol && depth < FLATTEN_MAX_DEPTH && m > a && m < b {
        // The deviation of a chord shrinks with the square of its length: split into as many
        // equal pieces as that predicts (10 % more, so uneven parametric speed rarely forces a
        // second split) instead of halving, which overshoots up to 2×.
        let want = (err / tol).sqrt() * 1.1;
        // Far too coarse (or a poor estimate): split into √want pieces and predict again on
        // each, so a cap never forces a doubling of the final count.
        let k = if want <= FLATTEN_MAX_SPLIT {
            want.ceil().max(2.0)
        } else {
            want.sqrt().ceil()
        } as usize;
        let (mut t0, mut p0) = (a, pa);
        for j in 1..=k {
            let (t1, p1) = if j == k {
                (b, pb)
            } else {
                let t = a + (b - a) * (j as f64 / k as f64);
                (t, c.eval(t))
            };
            flatten_rec(c, tol, t0, p0, t1, p1, depth + 1, out);
            (t0, p0) = (t1, p1);
        }
    } else {
        out.push((b, pb));
    }
}

/// Safeguarded Newton search for the parameter where the arc length from the domain start is
/// `s`, starting at `t` (whose arc length is `cur`) inside the bracket `(lo, hi)`: Newton steps on
/// `s(t) − s`, bisection whenever a step leaves the bracket. Returns the parameter and its arc
/// length. Shared by `inv_arclen` and `params_at_arclens`.
fn seek_arclen<C: ParamCurve + ?Sized>(
    c: &C,
    s: f64,
    (mut t, mut cur): (f64, f64),
    (mut lo, mut hi): (f64, f64),
    accuracy: f64,
) -> (f64, f64) {
    let (a, b) = c.domain();
    let piece_acc = accuracy / 16.0;
    for _ in 0..100 {
        let err = cur - s;
        if err.abs() <= accuracy {
            break;
        }
        if err > 0.0 {
            hi = t;
        } else {
            lo = t;
        }
        if hi - lo <= f64::EPSILON * (b - a).abs().max(1.0) {
            break;
        }
        let speed = c.deriv(t, 1).length();
        let mut next = if speed > 0.0 {
            t - err / speed
        } else {
            f64::NAN
        };
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        cur += integrate(|x| c.deriv(x, 1).length(), t, next, piece_acc);
        t = next;
    }
    (t, cur)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::{Bezier, Nurbs};
    use std::f64::consts::{FRAC_PI_2, PI, TAU};

    /// (t, t²) on [a, b].
    #[derive(Debug)]
    struct Parabola(f64, f64);
    impl ParamCurve for Parabola {
        fn domain(&self) -> (f64, f64) {
            (self.0, self.1)
        }
        fn eval(&self, t: f64) -> DVec3 {
            DVec3::new(t, t * t, 0.0)
        }
        fn deriv(&self, t: f64, k: usize) -> DVec3 {
            match k {
                0 => self.eval(t),
                1 => DVec3::new(1.0, 2.0 * t, 0.0),
                2 => DVec3::new(0.0, 2.0, 0.0),
                _ => DVec3::ZERO,
            }
        }
    }

    /// Helix (R cos t, R sin t, a t).
    #[derive(Debug)]
    struct Helix(f64, f64);
    impl ParamCurve for Helix {
        fn domain(&self) -> (f64, f64) {
            (0.0, 4.0 * PI)
        }
        fn eval(&self, t: f64) -> DVec3 {
            self.deriv(t, 0)
        }
        fn deriv(&self, t: f64, k: usize) -> DVec3 {
            let (s, c) = t.sin_cos();
            let r = self.0;
            let (x, y) = match k % 4 {
                0 => (c, s),
                1 => (-s, c),
                2 => (-c, -s),
                _ => (s, -c),
            };
            let z = match k {
                0 => self.1 * t,
                1 => self.1,
                _ => 0.0,
            };
            DVec3::new(r * x, r * y, z)
        }
    }

    #[test]
    fn tv38_arclen_sweep_parabola_helix_circle() {
        let exact = (2.0 * 5f64.sqrt() + 2f64.asinh()) / 4.0;
        assert!((exact - 1.4789428575446).abs() < 1e-12);
        let hx = Helix(2.0, 0.5);
        let hx_exact = 4.0 * PI * (4.0f64 + 0.25).sqrt();
        let circ = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 3.0, 0.0, TAU).unwrap();
        let mut acc = 1e-3;
        while acc >= 1e-11 {
            let v = Parabola(0.0, 1.0).arclen(acc);
            assert!(
                (v - exact).abs() <= acc,
                "parabola acc {acc}: err {}",
                v - exact
            );
            let v = hx.arclen(acc);
            assert!(
                (v - hx_exact).abs() <= acc,
                "helix acc {acc}: err {}",
                v - hx_exact
            );
            let v = circ.arclen(acc);
            assert!(
                (v - 6.0 * PI).abs() <= acc,
                "circle acc {acc}: err {}",
                v - 6.0 * PI
            );
            acc /= 10.0;
        }
        // TV38: the cubic quarter circle is 1.5710166981 long; TV1 length 6.979054670.
        let k = 4.0 * (2f64.sqrt() - 1.0) / 3.0;
        let q = Bezier::new(vec![
            DVec3::X,
            DVec3::new(1.0, k, 0.0),
            DVec3::new(k, 1.0, 0.0),
            DVec3::Y,
        ])
        .unwrap();
        assert!((q.arclen(1e-12) - 1.5710166981).abs() < 1e-10);
        let tv1 = Bezier::new(vec![
            DVec3::ZERO,
            DVec3::new(1., 2., 0.),
            DVec3::new(4., 2., 0.),
            DVec3::new(6., 0., 0.),
        ])
        .unwrap();
        assert!((tv1.arclen(1e-12) - 6.979054670).abs() < 1e-9);
        assert!((tv1.arclen_range(1.0, 0.0, 1e-12) + tv1.arclen(1e-12)).abs() < 1e-11);
    }

    #[test]
    fn inverse_arclen_roundtrips() {
        let c = Parabola(-1.0, 2.0);
        let total = c.arclen(1e-12);
        for frac in [0.0, 0.1, 0.5, 0.77, 1.0] {
            let s = frac * total;
            let t = c.inv_arclen(s, 1e-10);
            assert!(
                (c.arclen_range(-1.0, t, 1e-12) - s).abs() <= 1e-9,
                "frac {frac}"
            );
        }
        assert_eq!(c.inv_arclen(-1.0, 1e-9), -1.0);
        assert_eq!(c.inv_arclen(total + 1.0, 1e-9), 2.0);
        // Circle: arc length is linear in angle, so s = r·θ.
        let circ = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 2.0, 0.0, PI).unwrap();
        let t = circ.inv_arclen(2.0 * 1.0, 1e-11);
        let p = circ.eval(t);
        assert!((p - DVec3::new(2.0 * 1f64.cos(), 2.0 * 1f64.sin(), 0.0)).length() < 1e-10);
    }

    #[test]
    fn equal_arclength_division() {
        let h = Helix(2.0, 0.5);
        let total = h.arclen(1e-12);
        let targets: Vec<f64> = (0..=10).map(|i| total * i as f64 / 10.0).collect();
        let ts = h.params_at_arclens(&targets, 1e-10);
        // Helix speed is constant: equal lengths are equal parameter steps.
        for (i, t) in ts.iter().enumerate() {
            assert!((t - 4.0 * PI * i as f64 / 10.0).abs() < 1e-9, "{i}: {t}");
        }
        let c = Parabola(-1.0, 2.0);
        let total = c.arclen(1e-12);
        let targets = [0.0, 0.3, 1.0, 2.5, total, total + 5.0];
        let ts = c.params_at_arclens(&targets, 1e-10);
        for (s, t) in targets.iter().zip(&ts) {
            let got = c.arclen_range(-1.0, *t, 1e-12);
            assert!((got - s.min(total)).abs() < 1e-9, "{s}: {got}");
        }
    }

    #[test]
    fn tv39_helix_curvature_torsion_frame() {
        let h = Helix(2.0, 0.5);
        for t in [0.0, 1.0, 2.5] {
            assert!((h.curvature(t).unwrap() - 0.4705882353).abs() < 1e-10);
            assert!((h.torsion(t).unwrap() - 0.1176470588).abs() < 1e-10);
            let f = h.frenet(t).unwrap();
            // N points at the axis; T, N, B orthonormal and right-handed.
            let p = h.eval(t);
            let axis_dir = -DVec3::new(p.x, p.y, 0.0).normalize();
            assert!((f.n - axis_dir).length() < 1e-14);
            assert!(f.t.dot(f.n).abs() < 1e-15 && (f.t.cross(f.n) - f.b).length() < 1e-15);
        }
        // Frenet–Serret: dT/ds = κN, checked by finite differences.
        let (t, hh) = (0.7, 1e-6);
        let speed = h.deriv(t, 1).length();
        let dt = (h.frenet(t + hh).unwrap().t - h.frenet(t - hh).unwrap().t) / (2.0 * hh * speed);
        let f = h.frenet(t).unwrap();
        assert!((dt - h.curvature(t).unwrap() * f.n).length() < 1e-8);
        let db = (h.frenet(t + hh).unwrap().b - h.frenet(t - hh).unwrap().b) / (2.0 * hh * speed);
        assert!((db + h.torsion(t).unwrap() * f.n).length() < 1e-8);
    }

    #[test]
    fn tv1_tv5_curvatures_and_degenerate_cases() {
        let tv1 = Bezier::new(vec![
            DVec3::ZERO,
            DVec3::new(1., 2., 0.),
            DVec3::new(4., 2., 0.),
            DVec3::new(6., 0., 0.),
        ])
        .unwrap();
        assert!((tv1.curvature_xy(0.0).unwrap() + 0.8 / 5f64.sqrt()).abs() < 1e-15);
        assert!((tv1.curvature_xy(0.5).unwrap() + 64.0 / 243.0).abs() < 1e-15);
        assert!((tv1.curvature(0.5).unwrap() - 64.0 / 243.0).abs() < 1e-15);
        let tv5 = Bezier::new(vec![
            DVec3::ZERO,
            DVec3::new(1., 0., 0.),
            DVec3::new(2., 1., 0.),
            DVec3::new(3., 0., 1.),
        ])
        .unwrap();
        let cases = [
            (0.0, 2.0 / 3.0, 1.0 / 3.0),
            (0.5, 0.4190262407, 16.0 / 27.0),
            (1.0, 0.3142696805, 1.0 / 18.0),
        ];
        for (t, k, tau) in cases {
            assert!((tv5.curvature(t).unwrap() - k).abs() < 1e-10, "κ({t})");
            assert!((tv5.torsion(t).unwrap() - tau).abs() < 1e-14, "τ({t})");
        }
        // Errata E19: unnormalised normal at t = 1 is (−6, −6, 0); the frame's N is parallel.
        let n = tv5.frenet(1.0).unwrap().n;
        assert!((n - DVec3::new(-1.0, -1.0, 0.0).normalize()).length() < 1e-14);
        // Straight line: no torsion, no frame; stationary point: no curvature.
        let line = Bezier::new(vec![DVec3::ZERO, DVec3::X, 2.0 * DVec3::X]).unwrap();
        assert_eq!(line.curvature(0.3), Some(0.0));
        assert_eq!(line.torsion(0.3), None);
        assert_eq!(line.frenet(0.3), None);
        let cusp = Bezier::new(vec![DVec3::ZERO, DVec3::ZERO, DVec3::X]).unwrap();
        assert_eq!(cusp.curvature(0.0), None);
    }

    #[test]
    fn tv34_nearest_point_on_parabola() {
        let c = Parabola(-2.0, 2.0);
        let (t, d) = c.nearest(DVec3::new(0.0, 2.0, 0.0), 1e-12);
        assert!((t.abs() - 1.5f64.sqrt()).abs() < 1e-9, "t = {t}");
        assert!((d - 7f64.sqrt() / 2.0).abs() < 1e-12);
        // Endpoint wins when the foot point lies outside the domain.
        let c = Parabola(0.0, 1.0);
        let (t, d) = c.nearest(DVec3::new(5.0, 0.0, 0.0), 1e-12);
        assert_eq!(t, 1.0);
        assert!((d - 17f64.sqrt()).abs() < 1e-14);
        // Point on the curve.
        let (t, d) = c.nearest(DVec3::new(0.3, 0.09, 0.0), 1e-12);
        assert!((t - 0.3).abs() < 1e-9 && d < 1e-9);
    }

    fn arb_bezier() -> impl proptest::strategy::Strategy<Value = Bezier> {
        use proptest::prelude::*;
        proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0, -20.0f64..20.0), 2..7).prop_map(
            |v| Bezier::new(v.into_iter().map(|(x, y, z)| DVec3::new(x, y, z)).collect()).unwrap(),
        )
    }

    proptest::proptest! {
        #[test]
        fn nearest_is_global(c in arb_bezier(), q in (-60.0f64..60.0, -60.0f64..60.0, -20.0f64..20.0)) {
            let p = DVec3::new(q.0, q.1, q.2);
            let (t, d) = c.nearest(p, 1e-12);
            proptest::prop_assert!((c.eval(t).distance(p) - d).abs() < 1e-12);
            let dense = (0..=20_000).map(|i| c.eval(i as f64 / 20_000.0).distance(p)).fold(f64::INFINITY, f64::min);
            proptest::prop_assert!(d <= dense + 1e-9, "nearest {} vs dense {}", d, dense);
        }

        #[test]
        fn flatten_deviation_is_within_tolerance(c in arb_bezier(), tol in 0.001f64..1.0) {
            let pts = c.flatten(tol);
            for w in pts.windows(2) {
                let ((a, pa), (b, pb)) = (w[0], w[1]);
                for j in 1..40 {
                    let q = c.eval(a + (b - a) * j as f64 / 40.0);
                    let dev = dist_to_segment(q, pa, pb);
                    proptest::prop_assert!(dev <= tol * 1.0001, "dev {} > tol {}", dev, tol);
                }
            }
        }

        #[test]
        fn arclen_of_random_curves_meets_accuracy(c in arb_bezier(), e in 3i32..11) {
            let acc = 10f64.powi(-e);
            // Reference: 2048 fixed 16-point panels. 64 panels were not enough: at a tight turn
            // (speed dipping to ~1 between ~300) they were 4.6e-8 off the value of an
            // independent adaptive quadrature (QUADPACK), which this reference matches.
            let reference: f64 = (0..2048)
                .map(|i| flatcut_geom::num::gauss16(|t| c.deriv(t, 1).length(), i as f64 / 2048.0, (i + 1) as f64 / 2048.0))
                .sum();
            let minspeed = (0..=1000).map(|i| c.deriv(i as f64 / 1000.0, 1).length()).fold(f64::INFINITY, f64::min);
            proptest::prop_assume!(minspeed > 1.0);
            let v = c.arclen(acc);
            proptest::prop_assert!((v - reference).abs() <= acc, "acc {}: err {}", acc, v - reference);
        }
    }

    #[test]
    fn flatten_respects_the_chordal_tolerance() {
        let r = 50.0;
        let circ = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, r, 0.0, TAU).unwrap();
        for tol in [1.0, 0.05, 0.001] {
            let pts = circ.flatten(tol);
            assert_eq!(pts.first().unwrap().0, 0.0);
            assert_eq!(pts.last().unwrap().0, 1.0);
            let mut worst: f64 = 0.0;
            for w in pts.windows(2) {
                assert!(w[1].0 > w[0].0);
                // The sagitta of a chord of length L on radius r is r − √(r² − L²/4).
                let l = w[0].1.distance(w[1].1);
                worst = worst.max(r - (r * r - l * l / 4.0).sqrt());
            }
            assert!(worst <= tol, "tol {tol}: worst {worst}");
            // Not wasteful: within 1.35× the optimal segment count (plus the initial grid).
            let optimal = (PI / (1.0 - tol / r).acos()).ceil();
            assert!(
                (pts.len() - 1) as f64 <= 1.35 * optimal + 16.0,
                "{} vs {optimal}",
                pts.len()
            );
        }
        let half = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 1.0, 0.0, FRAC_PI_2).unwrap();
        let pts = half.flatten(0.0);
        assert!(
            pts.len() > 2,
            "non-positive tolerance falls back to the default"
        );
    }
}
