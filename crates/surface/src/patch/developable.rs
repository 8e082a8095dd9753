//! Developable surfaces between two rail curves (Duncan ch 6 L1736–L1852, Hartmann §10.3).
//!
//! Rulings join `λ(r)` on rail 0 to `μ(t)` on rail 1 where the tangent plane is common to both
//! ends, i.e. where `f(r, t) = [λ(r) − μ(t), λ'(r), μ'(t)] = 0`. Along rail 1 the matching rail-0
//! parameter obeys the ODE
//! `dr/dt = −f_t/f_r = −[λ−μ, λ', μ''] / [λ−μ, λ'', μ']` (ERRATA E3: the seed prints the
//! numerator `[λ−μ, λ', μ']`, which is `f` itself and vanishes on the solution).
//!
//! Integration is RK4 as a predictor with a Newton corrector on `f = 0` after every step (RK4
//! alone drifts off the constraint), and the step is halved when the corrector does not
//! converge. The surface is `X(t, s) = (1 − s) λ(r(t)) + s μ(t)`; between stored samples `r(t)`
//! is predicted by cubic Hermite interpolation and corrected by Newton, so evaluation is exact
//! to rounding. Where `f_r = [λ−μ, λ'', μ']` vanishes (a ruling tangent to a rail, a cone
//! vertex, a straight rail) the rails admit no developable through that ruling and
//! construction fails with the parameter where it happens.

use crate::{Domain2, ParamCurve, ParamSurface, SurfaceDerivs, SurfaceError};
use glam::{DVec2, DVec3};
use std::sync::Arc;

/// Places the third vertex of a 3D triangle `(p, q, r)` in the plane, given the developed
/// images `p_bar`, `q_bar` of its first edge (Hartmann §10.3, corrected per ERRATA E17):
/// `a = (|PQ|² + |PR|² − |QR|²)/(2|PQ|)`, `b = √(|PR|² − a²)`, `R̄ = P̄ + a e1 + b e2` with
/// `e1 = (Q̄ − P̄)/|Q̄ − P̄|` and `e2` its left normal when `left` is true (right otherwise).
/// `None` if the edge `PQ` or its image has zero length.
pub fn unfold_triangle(
    p_bar: DVec2,
    q_bar: DVec2,
    p: DVec3,
    q: DVec3,
    r: DVec3,
    left: bool,
) -> Option<DVec2> {
    let pq = p.distance(q);
    let e = q_bar - p_bar;
    if !(pq > 0.0 && e.length() > 0.0) {
        return None;
    }
    let (pr2, qr2) = (p.distance_squared(r), q.distance_squared(r));
    let a = (pq * pq + pr2 - qr2) / (2.0 * pq);
    // Rounding can make |PR|² − a² slightly negative for degenerate (collinear) triangles.
    let b = (pr2 - a * a).max(0.0).sqrt();
    let e1 = e.normalize();
    let e2 = if left { e1.perp() } else { -e1.perp() };
    Some(p_bar + e1 * a + e2 * b)
}

/// Options for [`DevelopableSurface::between_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DevelopableOptions {
    /// Number of integration steps over rail 1's parameter interval (before any halving).
    pub steps: usize,
    /// Newton tolerance on the normalized constraint `f / (|λ−μ| |λ'| |μ'|)` (a sine).
    pub tol: f64,
    /// `f_r` below this fraction of `|λ−μ| (|λ'| + |λ''|) |μ'|` counts as a vanishing denominator.
    pub degenerate_rel: f64,
    /// Largest accepted sine of the angle between the normals at the two ends of a ruling.
    pub max_ruling_twist: f64,
}

impl DevelopableOptions {
    /// 128 steps resolve typical rails (a few turns of curvature) with RK4 error far below `tol`.
    pub const DEFAULT_STEPS: usize = 128;
    /// Near machine precision for the normalized constraint (a sine of an angle).
    pub const DEFAULT_TOL: f64 = 1e-13;
    /// A denominator this small relative to its scale means the ruling is tangent to a rail.
    pub const DEFAULT_DEGENERATE_REL: f64 = 1e-9;
    /// Normals along a ruling parallel to 1e-8 rad: developable for any manufacturing purpose.
    pub const DEFAULT_MAX_RULING_TWIST: f64 = 1e-8;
    /// The defaults above.
    pub const DEFAULT: Self = Self {
        steps: Self::DEFAULT_STEPS,
        tol: Self::DEFAULT_TOL,
        degenerate_rel: Self::DEFAULT_DEGENERATE_REL,
        max_ruling_twist: Self::DEFAULT_MAX_RULING_TWIST,
    };
    /// Sets the number of integration steps.
    pub fn with_steps(mut self, steps: usize) -> Self {
        self.steps = steps;
        self
    }
    /// Sets the Newton tolerance.
    pub fn with_tol(mut self, tol: f64) -> Self {
        self.tol = tol;
        self
    }
}

impl Default for DevelopableOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A developable surface spanned by rulings between two rails; u is rail 1's parameter `t`,
/// v ∈ [0, 1] runs along the ruling from rail 0 to rail 1.
#[derive(Clone, Debug)]
pub struct DevelopableSurface {
    rail0: Arc<dyn ParamCurve>,
    rail1: Arc<dyn ParamCurve>,
    /// Samples `(t, r, dr/dt)` of the solution, t increasing.
    samples: Vec<(f64, f64, f64)>,
    opts: DevelopableOptions,
}

/// `f` and its partials at `(r, t)`.
struct Fjet {
    f: f64,
    fr: f64,
    ft: f64,
    scale: f64,
    scale_r: f64,
}

fn triple(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    a.dot(b.cross(c))
}

impl DevelopableSurface {
    /// The developable between `rail0` and `rail1`, starting at rail 1's first parameter with
    /// the ruling found by Newton from rail 0's first parameter.
    pub fn between(
        rail0: Arc<dyn ParamCurve>,
        rail1: Arc<dyn ParamCurve>,
    ) -> Result<Self, SurfaceError> {
        let r0 = rail0.domain().0;
        Self::between_with(rail0, rail1, r0, DevelopableOptions::DEFAULT)
    }

    /// As [`between`](Self::between), with a start guess `r_start` on rail 0 and options.
    pub fn between_with(
        rail0: Arc<dyn ParamCurve>,
        rail1: Arc<dyn ParamCurve>,
        r_start: f64,
        opts: DevelopableOptions,
    ) -> Result<Self, SurfaceError> {
        let (t0, t1) = rail1.domain();
        let (ra, rb) = rail0.domain();
        if !(t1 > t0 && rb > ra) || opts.steps == 0 {
            return Err(SurfaceError::DevelopableEmpty);
        }
        let mut s = Self {
            rail0,
            rail1,
            samples: Vec::new(),
            opts,
        };
        let r = s
            .correct(r_start, t0)
            .ok_or(SurfaceError::DevelopableNoRuling { r: r_start, t: t0 })?;
        s.integrate(r, t0, t1, ra, rb)?;
        s.validate()?;
        Ok(s)
    }

    fn jet(&self, r: f64, t: f64) -> Fjet {
        let (l, l1, l2) = (
            self.rail0.eval(r),
            self.rail0.deriv(r, 1),
            self.rail0.deriv(r, 2),
        );
        let (m, m1, m2) = (
            self.rail1.eval(t),
            self.rail1.deriv(t, 1),
            self.rail1.deriv(t, 2),
        );
        let d = l - m;
        Fjet {
            f: triple(d, l1, m1),
            fr: triple(d, l2, m1),
            ft: triple(d, l1, m2),
            scale: d.length() * l1.length() * m1.length(),
            scale_r: d.length() * (l1.length() + l2.length()) * m1.length(),
        }
    }

    /// Newton on `f(·, t) = 0` from `r`; `None` if the denominator vanishes or it diverges.
    fn correct(&self, mut r: f64, t: f64) -> Option<f64> {
        const MAX_NEWTON: usize = 12;
        for _ in 0..MAX_NEWTON {
            let j = self.jet(r, t);
            // Written so that a NaN denominator also counts as degenerate.
            if j.fr
                .abs()
                .partial_cmp(&(self.opts.degenerate_rel * j.scale_r))
                != Some(std::cmp::Ordering::Greater)
            {
                return None;
            }
            let dr = j.f / j.fr;
            r -= dr;
            if !r.is_finite() {
                return None;
            }
            if j.f.abs() <= self.opts.tol * j.scale || dr.abs() <= 1e-15 * (1.0 + r.abs()) {
                let j = self.jet(r, t);
                return (j.f.abs() <= 1e3 * self.opts.tol * j.scale.max(f64::MIN_POSITIVE))
                    .then_some(r);
            }
        }
        None
    }

    /// `dr/dt` at a point of the solution, or `None` where the denominator vanishes.
    fn slope(&self, r: f64, t: f64) -> Option<f64> {
        let j = self.jet(r, t);
        (j.fr.abs() > self.opts.degenerate_rel * j.scale_r).then(|| -j.ft / j.fr)
    }

    fn integrate(
        &mut self,
        r_init: f64,
        t0: f64,
        t1: f64,
        ra: f64,
        rb: f64,
    ) -> Result<(), SurfaceError> {
        const MAX_HALVINGS: u32 = 20;
        let h0 = (t1 - t0) / self.opts.steps as f64;
        let degenerate = |t: f64| SurfaceError::DevelopableDegenerate { t };
        let (mut t, mut r) = (t0, r_init);
        let k = self.slope(r, t).ok_or_else(|| degenerate(t))?;
        self.samples.push((t, r, k));
        let mut h = h0;
        let mut halvings = 0;
        while t < t1 {
            let step = h.min(t1 - t);
            let next = self
                .rk4(r, t, step)
                .and_then(|rp| self.correct(rp, t + step));
            match next {
                Some(rn) if rn >= ra - 1e-12 * (rb - ra) && rn <= rb + 1e-12 * (rb - ra) => {
                    let tn = if t1 - t <= h { t1 } else { t + step };
                    let kn = self.slope(rn, tn).ok_or_else(|| degenerate(tn))?;
                    // Reject steps whose Hermite interpolation would be poor (|Δr| vs slopes).
                    t = tn;
                    r = rn;
                    self.samples.push((t, r, kn));
                    h = (h * 2.0).min(h0);
                    halvings = 0;
                }
                Some(_) => break, // rail 0 ends: the surface stops at the last ruling inside it
                None => {
                    halvings += 1;
                    if halvings > MAX_HALVINGS {
                        return Err(degenerate(t + step));
                    }
                    h *= 0.5;
                }
            }
        }
        if self.samples.len() < 2 {
            return Err(SurfaceError::DevelopableRailEnds { t: t0 });
        }
        Ok(())
    }

    fn rk4(&self, r: f64, t: f64, h: f64) -> Option<f64> {
        let k1 = self.slope(r, t)?;
        let k2 = self.slope(r + 0.5 * h * k1, t + 0.5 * h)?;
        let k3 = self.slope(r + 0.5 * h * k2, t + 0.5 * h)?;
        let k4 = self.slope(r + h * k3, t + h)?;
        Some(r + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
    }

    /// Normals at both ends of every stored ruling must be parallel.
    fn validate(&self) -> Result<(), SurfaceError> {
        let worst = self.max_ruling_twist();
        if worst.0 > self.opts.max_ruling_twist {
            return Err(SurfaceError::DevelopableNormals {
                t: worst.1,
                sin: worst.0,
            });
        }
        Ok(())
    }

    /// The largest sine of the angle between the surface normals at the two ends of a stored
    /// ruling, with the rail-1 parameter where it occurs (0 for an exact developable).
    pub fn max_ruling_twist(&self) -> (f64, f64) {
        let mut worst = (0.0f64, self.samples[0].0);
        for &(t, _, _) in &self.samples {
            let a = self.deriv1(t, 0.0);
            let b = self.deriv1(t, 1.0);
            let (na, nb) = (a.1.cross(a.2), b.1.cross(b.2));
            let denom = na.length() * nb.length();
            if denom > 0.0 {
                let s = na.cross(nb).length() / denom;
                if s > worst.0 {
                    worst = (s, t);
                }
            }
        }
        worst
    }

    /// The rail-0 parameter `r(t)` of the ruling through rail 1's point `μ(t)`, if `t` is covered.
    pub fn rail0_param(&self, t: f64) -> Option<f64> {
        let (a, b) = (self.samples[0].0, self.samples[self.samples.len() - 1].0);
        if !(t >= a && t <= b) {
            return None;
        }
        let i = match self.samples.binary_search_by(|s| s.0.total_cmp(&t)) {
            Ok(i) => return Some(self.samples[i].1),
            Err(i) => i.clamp(1, self.samples.len() - 1),
        };
        let (ta, ra, ka) = self.samples[i - 1];
        let (tb, rb, kb) = self.samples[i];
        let h = tb - ta;
        let x = (t - ta) / h;
        let (x2, x3) = (x * x, x * x * x);
        let guess = (2.0 * x3 - 3.0 * x2 + 1.0) * ra
            + (x3 - 2.0 * x2 + x) * h * ka
            + (-2.0 * x3 + 3.0 * x2) * rb
            + (x3 - x2) * h * kb;
        Some(self.correct(guess, t).unwrap_or(guess))
    }

    /// Develops (unfolds) the surface into the plane as a triangle strip over `rulings ≥ 2`
    /// equally spaced rulings (Hartmann §10.3): returns the developed end points
    /// `[on rail 0, on rail 1]` of each ruling. Every strip triangle keeps its 3D edge lengths;
    /// for a developable the quads between rulings are planar, so the development is exact up
    /// to the chordal approximation of the rails. The first ruling lies on the +x axis from the
    /// origin and the strip unfolds to its left.
    pub fn develop(&self, rulings: usize) -> Result<Vec<[DVec2; 2]>, SurfaceError> {
        let rulings = rulings.max(2);
        let dom = self.domain().u;
        let pts: Vec<[DVec3; 2]> = (0..rulings)
            .map(|i| {
                let t = dom.0 + (dom.1 - dom.0) * i as f64 / (rulings - 1) as f64;
                [self.eval(t, 0.0), self.eval(t, 1.0)]
            })
            .collect();
        let len0 = pts[0][0].distance(pts[0][1]);
        let mut out = vec![[DVec2::ZERO, DVec2::new(len0, 0.0)]];
        let fail = |i: usize| SurfaceError::ZeroRuling { index: i };
        // Side of the previous apex relative to the edge we unfold across: the new vertex goes
        // to the other side so the strip never folds back.
        let side = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a) >= 0.0;
        let mut prev_third: Option<DVec2> = None;
        for i in 1..rulings {
            let [a0, b0] = out[i - 1];
            let [p0, q0] = pts[i - 1];
            let [p1, q1] = pts[i];
            // Triangle (A_{i−1}, B_{i−1}, A_i).
            let left = prev_third.is_none_or(|c| !side(a0, b0, c));
            let a1 = unfold_triangle(a0, b0, p0, q0, p1, left).ok_or_else(|| fail(i - 1))?;
            // Triangle (A_i, B_{i−1}, B_i), across the diagonal from A_{i−1}.
            let left = !side(a1, b0, a0);
            let b1 = unfold_triangle(a1, b0, p1, q0, q1, left).ok_or_else(|| fail(i))?;
            prev_third = Some(b0);
            out.push([a1, b1]);
        }
        Ok(out)
    }

    /// The stored samples `(t, r(t), r'(t))` of the integrated ruling correspondence.
    pub fn samples(&self) -> &[(f64, f64, f64)] {
        &self.samples
    }

    /// `r`, `r'` and `r''` at `t` (r'' by differentiating `−f_t/f_r` along the solution).
    fn r_jet(&self, t: f64) -> (f64, f64, f64) {
        let dom = self.domain().u;
        let r = self
            .rail0_param(t.clamp(dom.0, dom.1))
            .unwrap_or(self.samples[0].1);
        let (l, l1, l2, l3) = (
            self.rail0.eval(r),
            self.rail0.deriv(r, 1),
            self.rail0.deriv(r, 2),
            self.rail0.deriv(r, 3),
        );
        let (m, m1, m2, m3) = (
            self.rail1.eval(t),
            self.rail1.deriv(t, 1),
            self.rail1.deriv(t, 2),
            self.rail1.deriv(t, 3),
        );
        let d = l - m;
        let fr = triple(d, l2, m1);
        let ft = triple(d, l1, m2);
        if fr == 0.0 {
            return (r, 0.0, 0.0);
        }
        let r1 = -ft / fr;
        let frr = triple(l1, l2, m1) + triple(d, l3, m1);
        let frt = triple(-m1, l2, m1) + triple(d, l2, m2);
        let ftt = triple(-m1, l1, m2) + triple(d, l1, m3);
        let r2 = -(ftt + 2.0 * frt * r1 + frr * r1 * r1) / fr;
        (r, r1, r2)
    }
}

impl ParamSurface for DevelopableSurface {
    fn domain(&self) -> Domain2 {
        Domain2 {
            u: (self.samples[0].0, self.samples[self.samples.len() - 1].0),
            v: (0.0, 1.0),
        }
    }
    fn eval(&self, t: f64, s: f64) -> DVec3 {
        let (r, _, _) = self.r_jet(t);
        self.rail0.eval(r).lerp(self.rail1.eval(t), s)
    }
    fn deriv1(&self, t: f64, s: f64) -> (DVec3, DVec3, DVec3) {
        let d = self.deriv2(t, s);
        (d.p, d.su, d.sv)
    }
    fn deriv2(&self, t: f64, s: f64) -> SurfaceDerivs {
        let (r, r1, r2) = self.r_jet(t);
        let (l, l1, l2) = (
            self.rail0.eval(r),
            self.rail0.deriv(r, 1),
            self.rail0.deriv(r, 2),
        );
        let (m, m1, m2) = (
            self.rail1.eval(t),
            self.rail1.deriv(t, 1),
            self.rail1.deriv(t, 2),
        );
        let lt = l1 * r1;
        let ltt = l2 * (r1 * r1) + l1 * r2;
        SurfaceDerivs {
            p: l.lerp(m, s),
            su: lt.lerp(m1, s),
            sv: m - l,
            suu: ltt.lerp(m2, s),
            suv: m1 - lt,
            svv: DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::coons::tests::curve;
    use crate::patch::testutil::check_derivs_fd;

    fn circle(a: f64, b: f64, cx: f64, z: f64, zc: f64) -> Arc<dyn ParamCurve> {
        // (a cos t + cx, b sin t, z + zc cos t) and its derivatives.
        curve((0.0, 1.2), move |t, k| {
            let (c, s) = (t.cos(), t.sin());
            let (cc, ss) = match k % 4 {
                0 => (c, s),
                1 => (-s, c),
                2 => (-c, -s),
                _ => (s, -c),
            };
            let off = if k == 0 {
                DVec3::new(cx, 0.0, z)
            } else {
                DVec3::ZERO
            };
            DVec3::new(a * cc, b * ss, zc * cc) + off
        })
    }

    #[test]
    fn tv31_cone_frustum_solution_is_identity() {
        let s = DevelopableSurface::between(
            circle(1.0, 1.0, 0.0, 0.0, 0.0),
            circle(2.0, 2.0, 0.0, 1.0, 0.0),
        )
        .unwrap();
        for &t in &[0.0, 0.3, 0.77, 1.2] {
            assert!((s.rail0_param(t).unwrap() - t).abs() < 1e-12);
        }
        assert!(s.max_ruling_twist().0 < 1e-14);
    }

    #[test]
    fn tv31_non_trivial_rails() {
        let s = DevelopableSurface::between(
            circle(1.0, 1.0, 0.0, 0.0, 0.0),
            circle(1.5, 1.0, 0.3, 1.0, 0.2),
        )
        .unwrap();
        for &(t, r) in &[(0.1, 0.136315), (0.5, 0.644781), (0.9, 1.053776)] {
            let got = s.rail0_param(t).unwrap();
            assert!((got - r).abs() < 6e-7, "r({t}) = {got}, expected {r}");
        }
        assert!(s.max_ruling_twist().0 < 1e-12);
        // Gaussian curvature vanishes (developable): LN − M² = 0 with N = r_vv·n = 0 ⇒ M = 0.
        let d = s.deriv2(0.4, 0.5);
        let n = d.su.cross(d.sv).normalize();
        assert!(d.suv.dot(n).abs() < 1e-10);
        check_derivs_fd(&s, 1e-6);
    }

    #[test]
    fn tv33_triangle_development() {
        let (p, q, r) = (
            DVec3::ZERO,
            DVec3::new(3.0, 0.0, 1.0),
            DVec3::new(1.0, 2.0, 2.0),
        );
        let rb =
            unfold_triangle(DVec2::ZERO, DVec2::new(10f64.sqrt(), 0.0), p, q, r, true).unwrap();
        assert!((rb - DVec2::new(1.5811388301, 2.5495097568)).length() < 1e-10);
        assert!((rb.length() - 3.0).abs() < 1e-14);
        assert!((rb.distance(DVec2::new(10f64.sqrt(), 0.0)) - 3.0).abs() < 1e-14);
        assert!(unfold_triangle(DVec2::ZERO, DVec2::ZERO, p, q, r, true).is_none());
    }

    #[test]
    fn developing_a_cone_frustum_is_exact() {
        // Rails r = 1 at z = 0 and r = 2 at z = 1: the apex is at z = −1, each ruling's rail-0
        // end is the midpoint between the apex and its rail-1 end.
        let s = DevelopableSurface::between(
            circle(1.0, 1.0, 0.0, 0.0, 0.0),
            circle(2.0, 2.0, 0.0, 1.0, 0.0),
        )
        .unwrap();
        let dev = s.develop(25).unwrap();
        let apex = dev[0][0] * 2.0 - dev[0][1];
        for (i, [a, b]) in dev.iter().enumerate() {
            assert!((*a * 2.0 - *b - apex).length() < 1e-12, "ruling {i}");
            assert!((a.distance(apex) - 2f64.sqrt()).abs() < 1e-12);
        }
        // The developed sector angle is the rail length over the slant radius: 1.2 · 1/√2.
        let ang = (dev[0][0] - apex).angle_to(dev[24][0] - apex).abs();
        let chord_angle = 24.0 * 2.0 * ((1.2f64 / 48.0).sin() / 2f64.sqrt()).asin();
        assert!((ang - chord_angle).abs() < 1e-12, "{ang} vs {chord_angle}");
        // Non-trivial rails: ruling and rail chord lengths are preserved.
        let s = DevelopableSurface::between(
            circle(1.0, 1.0, 0.0, 0.0, 0.0),
            circle(1.5, 1.0, 0.3, 1.0, 0.2),
        )
        .unwrap();
        let dev = s.develop(40).unwrap();
        let d = s.domain().u;
        for i in 1..40 {
            let t0 = d.0 + (d.1 - d.0) * (i - 1) as f64 / 39.0;
            let t1 = d.0 + (d.1 - d.0) * i as f64 / 39.0;
            let l3 = s.eval(t0, 1.0).distance(s.eval(t1, 1.0));
            assert!((dev[i - 1][1].distance(dev[i][1]) - l3).abs() < 1e-12);
            let r3 = s.eval(t1, 0.0).distance(s.eval(t1, 1.0));
            assert!((dev[i][0].distance(dev[i][1]) - r3).abs() < 1e-12);
            // The unused diagonal is preserved too (planar quads) up to the integration error.
            let diag3 = s.eval(t0, 0.0).distance(s.eval(t1, 1.0));
            assert!((dev[i - 1][0].distance(dev[i][1]) - diag3).abs() < 1e-9);
        }
    }

    #[test]
    fn straight_rail_has_no_developable() {
        let line = curve((0.0, 1.0), |t, k| match k {
            0 => DVec3::new(t, 0.0, 0.0),
            1 => DVec3::X,
            _ => DVec3::ZERO,
        });
        let e = DevelopableSurface::between(line, circle(1.5, 1.0, 0.3, 1.0, 0.2)).unwrap_err();
        assert!(e.to_string().contains("developable"), "{e}");
    }
}
