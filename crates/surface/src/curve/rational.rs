//! Rational Bézier curves on homogeneous control points, including points at infinity (weight 0),
//! with the projective de Casteljau algorithm, quotient-rule derivatives, subdivision, degree
//! elevation and the standard form `w_0 = w_n = 1` (digest A2, A3, A5, A14; TV17, TV18).

use glam::{DVec3, DVec4};

use super::bezier::binomial;
use crate::{ParamCurve, SurfaceError};

/// Homogeneous control points up to which evaluation stays on the stack (degree ≤ 7).
const STACK_POINTS: usize = 8;

#[inline]
fn with_scratch<R>(pts: &[DVec4], f: impl FnOnce(&mut [DVec4]) -> R) -> R {
    if pts.len() <= STACK_POINTS {
        let mut a = [DVec4::ZERO; STACK_POINTS];
        a[..pts.len()].copy_from_slice(pts);
        f(&mut a[..pts.len()])
    } else {
        let mut v = pts.to_vec();
        f(&mut v)
    }
}

/// `k`-th derivative of the homogeneous polynomial curve at `t`.
fn hom_deriv(b: &mut [DVec4], t: f64, k: usize) -> DVec4 {
    let n = b.len() - 1;
    if k > n {
        return DVec4::ZERO;
    }
    let mut scale = 1.0;
    for l in 0..k {
        scale *= (n - l) as f64;
        for i in 0..n - l {
            b[i] = b[i + 1] - b[i];
        }
    }
    let m = n - k + 1;
    let s = 1.0 - t;
    for l in 1..m {
        for i in 0..m - l {
            b[i] = s * b[i] + t * b[i + 1];
        }
    }
    scale * b[0]
}

/// A rational Bézier curve `r(t) = Σ w_i b_i B_i^n(t) / Σ w_i B_i^n(t)` on `[0, 1]`, stored as
/// homogeneous points `(w_i b_i, w_i)`. A homogeneous point with `w = 0` is a point at infinity
/// (a direction); the end weights must be positive, so the denominator is positive on `[0, 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct RationalBezier {
    hom: Vec<DVec4>,
}

impl RationalBezier {
    /// From Cartesian control points and weights (finite, `≥ 0`, end weights `> 0`). A zero
    /// interior weight removes that point's influence.
    pub fn new(points: &[DVec3], weights: &[f64]) -> Result<Self, SurfaceError> {
        if points.len() != weights.len() {
            return Err(SurfaceError::WeightCount {
                what: "rational Bézier",
                points: points.len(),
                weights: weights.len(),
            });
        }
        super::bezier::check_finite(points, "control point")?;
        Self::from_homogeneous(
            points
                .iter()
                .zip(weights)
                .map(|(p, &w)| (*p * w).extend(w))
                .collect(),
        )
    }

    /// From homogeneous control points `(x, y, z, w)`; `w = 0` is a point at infinity in the
    /// direction `(x, y, z)`. Weights must be finite and `≥ 0`, the end weights `> 0`.
    pub fn from_homogeneous(hom: Vec<DVec4>) -> Result<Self, SurfaceError> {
        if hom.is_empty() {
            return Err(SurfaceError::ControlPointCount {
                expected: 1,
                got: 0,
            });
        }
        if let Some(index) = hom.iter().position(|h| !h.is_finite()) {
            return Err(SurfaceError::NonFinite {
                what: "homogeneous control point",
                index,
            });
        }
        let last = hom.len() - 1;
        for (index, h) in hom.iter().enumerate() {
            let end = index == 0 || index == last;
            if h.w < 0.0 || (end && h.w <= 0.0) {
                return Err(SurfaceError::BadWeight { index, value: h.w });
            }
        }
        Ok(Self { hom })
    }

    /// The homogeneous control points.
    pub fn homogeneous(&self) -> &[DVec4] {
        &self.hom
    }

    /// The weights.
    pub fn weights(&self) -> Vec<f64> {
        self.hom.iter().map(|h| h.w).collect()
    }

    /// The same curve traversed backwards (`t ↦ 1 − t`).
    pub fn reversed(&self) -> RationalBezier {
        RationalBezier {
            hom: self.hom.iter().rev().copied().collect(),
        }
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.hom.len() - 1
    }

    /// Splits at `t ∈ (0, 1)` into the pieces on `[0, t]` and `[t, 1]` (homogeneous de
    /// Casteljau), each on `[0, 1]`.
    pub fn subdivide(&self, t: f64) -> (RationalBezier, RationalBezier) {
        let n = self.hom.len();
        let mut b = self.hom.clone();
        let mut left = vec![b[0]];
        let mut right = vec![DVec4::ZERO; n];
        right[n - 1] = b[n - 1];
        let s = 1.0 - t;
        for l in 1..n {
            for i in 0..n - l {
                b[i] = s * b[i] + t * b[i + 1];
            }
            left.push(b[0]);
            right[n - 1 - l] = b[n - 1 - l];
        }
        (RationalBezier { hom: left }, RationalBezier { hom: right })
    }

    /// Degree elevation of the homogeneous points: the same curve, one more control point.
    pub fn elevate(&self) -> RationalBezier {
        let n = self.degree();
        let m = (n + 1) as f64;
        let mut hom = vec![self.hom[0]];
        for k in 1..=n {
            let a = k as f64 / m;
            hom.push(a * self.hom[k - 1] + (1.0 - a) * self.hom[k]);
        }
        hom.push(self.hom[n]);
        RationalBezier { hom }
    }

    /// The standard form with end weights 1: the same point set under the Möbius
    /// reparametrisation that scales weight `i` by `c^i / w_0`, `c = (w_0 / w_n)^{1/n}`
    /// (digest A14). The parameter of a given point changes.
    pub fn standard_form(&self) -> RationalBezier {
        let n = self.degree();
        if n == 0 {
            return RationalBezier {
                hom: vec![self.hom[0] / self.hom[0].w],
            };
        }
        let (w0, wn) = (self.hom[0].w, self.hom[n].w);
        let c = (w0 / wn).powf(1.0 / n as f64);
        let hom = self
            .hom
            .iter()
            .enumerate()
            .map(|(i, h)| *h * (c.powi(i as i32) / w0))
            .collect();
        RationalBezier { hom }
    }
}

impl ParamCurve for RationalBezier {
    fn domain(&self) -> (f64, f64) {
        (0.0, 1.0)
    }

    fn eval(&self, t: f64) -> DVec3 {
        let h = with_scratch(&self.hom, |b| hom_deriv(b, t, 0));
        h.truncate() / h.w
    }

    /// Quotient rule: `r^(k) = (A^(k) − Σ_{i=1..k} C(k, i) w^(i) r^(k−i)) / w`.
    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        if k + 1 > STACK_POINTS {
            let hd: Vec<DVec4> = (0..=k)
                .map(|kk| with_scratch(&self.hom, |b| hom_deriv(b, t, kk)))
                .collect();
            let mut r = vec![DVec3::ZERO; k + 1];
            quotient_rule(&hd, &mut r);
            return r[k];
        }
        let mut hd = [DVec4::ZERO; STACK_POINTS];
        for (kk, h) in hd[..=k].iter_mut().enumerate() {
            *h = with_scratch(&self.hom, |b| hom_deriv(b, t, kk));
        }
        let mut r = [DVec3::ZERO; STACK_POINTS];
        quotient_rule(&hd[..=k], &mut r[..=k]);
        r[k]
    }
}

/// Cartesian derivatives `r` from homogeneous derivatives `hd` (same length).
fn quotient_rule(hd: &[DVec4], r: &mut [DVec3]) {
    let w0 = hd[0].w;
    for kk in 0..hd.len() {
        let mut v = hd[kk].truncate();
        for i in 1..=kk {
            v -= binomial(kk, i) * hd[i].w * r[kk - i];
        }
        r[kk] = v / w0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::Nurbs;
    use proptest::prelude::*;

    fn v2(x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, 0.0)
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).abs().max_element() <= tol
    }

    fn tv17() -> RationalBezier {
        RationalBezier::new(&[v2(0., -1.), v2(1., -1.), v2(1., 0.)], &[1., 1., 2.]).unwrap()
    }

    #[test]
    fn tv17_circle_and_standard_form() {
        let c = tv17();
        assert!(close(c.eval(0.5), v2(0.8, -0.6), 1e-15));
        assert!(close(c.eval(0.25), v2(8. / 17., -15. / 17.), 1e-15));
        let s = c.standard_form();
        let w = s.weights();
        assert!((w[0] - 1.0).abs() < 1e-15 && (w[2] - 1.0).abs() < 1e-15);
        assert!((w[1] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(close(s.eval(0.5), v2(h, -h), 1e-15));
        for i in 0..=10 {
            assert!((s.eval(i as f64 / 10.0).length() - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn tv18_semicircle_with_a_point_at_infinity() {
        let c = RationalBezier::from_homogeneous(vec![
            DVec4::new(-1., 0., 0., 1.),
            DVec4::new(0., 1., 0., 0.),
            DVec4::new(1., 0., 0., 1.),
        ])
        .unwrap();
        assert!(close(c.eval(0.25), v2(-0.8, 0.6), 1e-15));
        assert!(close(c.eval(0.5), v2(0.0, 1.0), 1e-15));
        assert!(close(c.eval(0.75), v2(0.8, 0.6), 1e-15));
        for i in 0..=20 {
            assert!((c.eval(i as f64 / 20.0).length() - 1.0).abs() < 1e-15);
        }
        // The hyperbola branch of TV18 has zero end weights: its ends are at infinity and the
        // curve cannot be evaluated on the closed domain, so it is rejected.
        assert!(matches!(
            RationalBezier::from_homogeneous(vec![
                DVec4::new(0., 1., 0., 0.),
                DVec4::new(0., 0., 0., 0.5),
                DVec4::new(1., 0., 0., 0.),
            ]),
            Err(SurfaceError::BadWeight { index: 0, .. })
        ));
        assert!(RationalBezier::new(&[v2(0., 0.), v2(1., 1.)], &[1.0, -1.0]).is_err());
    }

    #[test]
    fn agrees_with_nurbs_and_finite_differences() {
        let pts = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 2., 1.),
            DVec3::new(3., 2., -1.),
            DVec3::new(4., 0., 0.5),
        ];
        let w = [1.0, 3.0, 0.5, 2.0];
        let r = RationalBezier::new(&pts, &w).unwrap();
        let n = Nurbs::new(
            3,
            vec![0., 0., 0., 0., 1., 1., 1., 1.],
            pts.to_vec(),
            w.to_vec(),
        )
        .unwrap();
        for t in [0.0, 0.2, 0.6, 1.0] {
            for k in 0..5 {
                let (a, b) = (r.deriv(t, k), n.deriv(t, k));
                assert!(close(a, b, 1e-10 * (1.0 + b.length())), "t={t} k={k}");
            }
        }
    }

    proptest! {
        #[test]
        fn subdivision_and_elevation_leave_curve_unchanged(
            raw in proptest::collection::vec((-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0, 0.1f64..4.0), 2..7),
            s in 0.05f64..0.95, t in 0.0f64..1.0,
        ) {
            let pts: Vec<DVec3> = raw.iter().map(|r| DVec3::new(r.0, r.1, r.2)).collect();
            let w: Vec<f64> = raw.iter().map(|r| r.3).collect();
            let c = RationalBezier::new(&pts, &w).unwrap();
            let (l, r) = c.subdivide(s);
            let q = if t <= s { l.eval(t / s) } else { r.eval((t - s) / (1.0 - s)) };
            prop_assert!(close(c.eval(t), q, 1e-10));
            prop_assert!(close(c.eval(t), c.elevate().eval(t), 1e-10));
            // Standard form traces the same point set: same ends, and its point at t lies on the
            // original curve.
            let sf = c.standard_form();
            prop_assert!(close(sf.eval(0.0), c.eval(0.0), 1e-12));
            prop_assert!(close(sf.eval(1.0), c.eval(1.0), 1e-12));
            let (_, d) = crate::curve::CurveExt::nearest(&c, sf.eval(t), 1e-13);
            prop_assert!(d < 1e-8, "standard-form point off the curve by {}", d);
        }
    }
}
