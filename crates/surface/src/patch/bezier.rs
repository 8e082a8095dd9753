//! Tensor-product Bézier patches of any degree (Gravesen §3.2, Hartmann §13.1–13.4).
//!
//! Points are evaluated by de Casteljau (columns, then the resulting row); partial derivatives
//! up to second order contract the net with Bernstein bases and their derivatives, which is the
//! same arithmetic as the difference form (G (3.7)). Bicubic patches take an allocation-free fast
//! path because they are the hot case of tessellation and of the OpenCASCADE benchmark.

use super::bernstein;
use crate::{Domain2, ParamSurface, SurfaceDerivs, SurfaceError};
use glam::DVec3;

/// A tensor-product Bézier patch on the unit square.
///
/// Control points `b_ij`, `i = 0..=degree_u`, `j = 0..=degree_v`, are stored with **v varying
/// fastest**: `points[i * (degree_v + 1) + j]`.
#[derive(Clone, Debug, PartialEq)]
pub struct BezierPatch {
    degree_u: usize,
    degree_v: usize,
    points: Vec<DVec3>,
}

impl BezierPatch {
    /// Builds a patch from its control net (`(degree_u + 1) * (degree_v + 1)` points, v fastest).
    pub fn new(degree_u: usize, degree_v: usize, points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        let expected = (degree_u + 1) * (degree_v + 1);
        if points.len() != expected {
            return Err(SurfaceError::ControlPointCount {
                expected,
                got: points.len(),
            });
        }
        super::check_finite(&points, "Bézier control point")?;
        Ok(Self {
            degree_u,
            degree_v,
            points,
        })
    }

    /// Degree in u.
    pub fn degree_u(&self) -> usize {
        self.degree_u
    }

    /// Degree in v.
    pub fn degree_v(&self) -> usize {
        self.degree_v
    }

    /// The control net, v varying fastest.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Control point `b_ij`.
    pub fn point(&self, i: usize, j: usize) -> DVec3 {
        self.points[i * (self.degree_v + 1) + j]
    }

    fn bicubic(&self) -> Option<&[DVec3; 16]> {
        if self.degree_u == 3 && self.degree_v == 3 {
            <&[DVec3; 16]>::try_from(self.points.as_slice()).ok()
        } else {
            None
        }
    }

    /// Splits the patch at `u = t` into the patches over `[0, t]` and `[t, 1]` (in u), each
    /// reparametrized to the unit square.
    pub fn subdivide_u(&self, t: f64) -> (Self, Self) {
        let (n, m) = (self.degree_u, self.degree_v);
        let mut left = self.points.clone();
        let mut right = self.points.clone();
        for j in 0..=m {
            let col: Vec<DVec3> = (0..=n).map(|i| self.point(i, j)).collect();
            let (l, r) = split_curve(&col, t);
            for i in 0..=n {
                left[i * (m + 1) + j] = l[i];
                right[i * (m + 1) + j] = r[i];
            }
        }
        (
            Self {
                degree_u: n,
                degree_v: m,
                points: left,
            },
            Self {
                degree_u: n,
                degree_v: m,
                points: right,
            },
        )
    }

    /// Splits the patch at `v = t` into the patches over `[0, t]` and `[t, 1]` (in v).
    pub fn subdivide_v(&self, t: f64) -> (Self, Self) {
        let (n, m) = (self.degree_u, self.degree_v);
        let mut left = Vec::with_capacity(self.points.len());
        let mut right = Vec::with_capacity(self.points.len());
        for i in 0..=n {
            let row = &self.points[i * (m + 1)..(i + 1) * (m + 1)];
            let (l, r) = split_curve(row, t);
            left.extend(l);
            right.extend(r);
        }
        (
            Self {
                degree_u: n,
                degree_v: m,
                points: left,
            },
            Self {
                degree_u: n,
                degree_v: m,
                points: right,
            },
        )
    }

    /// The same surface with the degree in u raised by one (H (13.3) applied per column).
    pub fn elevate_u(&self) -> Self {
        let (n, m) = (self.degree_u, self.degree_v);
        let mut out = vec![DVec3::ZERO; (n + 2) * (m + 1)];
        for j in 0..=m {
            let col: Vec<DVec3> = (0..=n).map(|i| self.point(i, j)).collect();
            for (i, p) in elevate_curve(&col).into_iter().enumerate() {
                out[i * (m + 1) + j] = p;
            }
        }
        Self {
            degree_u: n + 1,
            degree_v: m,
            points: out,
        }
    }

    /// The same surface with the degree in v raised by one.
    pub fn elevate_v(&self) -> Self {
        let (n, m) = (self.degree_u, self.degree_v);
        let mut out = Vec::with_capacity((n + 1) * (m + 2));
        for i in 0..=n {
            out.extend(elevate_curve(&self.points[i * (m + 1)..(i + 1) * (m + 1)]));
        }
        Self {
            degree_u: n,
            degree_v: m + 1,
            points: out,
        }
    }

    /// Applies an affine map `p ↦ a p + t` (given as a closure) to the control net; Bézier
    /// patches are affinely invariant, so this maps the surface.
    pub fn map_points(&self, f: impl Fn(DVec3) -> DVec3) -> Self {
        Self {
            degree_u: self.degree_u,
            degree_v: self.degree_v,
            points: self.points.iter().map(|&p| f(p)).collect(),
        }
    }

    fn contract(&self, bu: &[f64], bv: &[f64]) -> DVec3 {
        let m = self.degree_v + 1;
        let mut acc = DVec3::ZERO;
        for (i, &a) in bu.iter().enumerate() {
            if a == 0.0 {
                continue;
            }
            let row = &self.points[i * m..(i + 1) * m];
            let mut r = DVec3::ZERO;
            for (p, &b) in row.iter().zip(bv) {
                r += *p * b;
            }
            acc += r * a;
        }
        acc
    }
}

/// de Casteljau split of a Bézier curve at `t`.
pub(crate) fn split_curve(pts: &[DVec3], t: f64) -> (Vec<DVec3>, Vec<DVec3>) {
    let n = pts.len();
    let mut work = pts.to_vec();
    let mut left = Vec::with_capacity(n);
    let mut right = vec![DVec3::ZERO; n];
    left.push(work[0]);
    right[n - 1] = work[n - 1];
    for r in 1..n {
        for i in 0..n - r {
            work[i] = work[i].lerp(work[i + 1], t);
        }
        left.push(work[0]);
        right[n - 1 - r] = work[n - 1 - r];
    }
    (left, right)
}

/// Degree elevation of a Bézier curve by one.
pub(crate) fn elevate_curve(pts: &[DVec3]) -> Vec<DVec3> {
    let n = pts.len() - 1;
    let mut out = Vec::with_capacity(n + 2);
    out.push(pts[0]);
    for i in 1..=n {
        let a = i as f64 / (n + 1) as f64;
        out.push(pts[i - 1] * a + pts[i] * (1.0 - a));
    }
    out.push(pts[n]);
    out
}

/// de Casteljau evaluation of a Bézier curve (in place on a scratch copy).
fn de_casteljau(work: &mut [DVec3], t: f64) -> DVec3 {
    let n = work.len();
    for r in 1..n {
        for i in 0..n - r {
            work[i] = work[i].lerp(work[i + 1], t);
        }
    }
    work[0]
}

impl ParamSurface for BezierPatch {
    fn domain(&self) -> Domain2 {
        Domain2::UNIT
    }

    fn eval(&self, u: f64, v: f64) -> DVec3 {
        if let Some(p) = self.bicubic() {
            let (bu, _) = bernstein::cubic_d1(u);
            let (bv, _) = bernstein::cubic_d1(v);
            let mut acc = DVec3::ZERO;
            for i in 0..4 {
                acc += (p[4 * i] * bv[0]
                    + p[4 * i + 1] * bv[1]
                    + p[4 * i + 2] * bv[2]
                    + p[4 * i + 3] * bv[3])
                    * bu[i];
            }
            return acc;
        }
        let m = self.degree_v + 1;
        let mut col: Vec<DVec3> = Vec::with_capacity(self.degree_u + 1);
        let mut row = vec![DVec3::ZERO; m];
        for i in 0..=self.degree_u {
            row.copy_from_slice(&self.points[i * m..(i + 1) * m]);
            col.push(de_casteljau(&mut row, v));
        }
        de_casteljau(&mut col, u)
    }

    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        if let Some(p) = self.bicubic() {
            let (bu, du) = bernstein::cubic_d1(u);
            let (bv, dv) = bernstein::cubic_d1(v);
            let mut s = DVec3::ZERO;
            let mut su = DVec3::ZERO;
            let mut sv = DVec3::ZERO;
            for i in 0..4 {
                let r = &p[4 * i..4 * i + 4];
                let row = r[0] * bv[0] + r[1] * bv[1] + r[2] * bv[2] + r[3] * bv[3];
                let rowv = r[0] * dv[0] + r[1] * dv[1] + r[2] * dv[2] + r[3] * dv[3];
                s += row * bu[i];
                su += row * du[i];
                sv += rowv * bu[i];
            }
            return (s, su, sv);
        }
        let [bu, du, _] = bernstein::basis_d2(self.degree_u, u);
        let [bv, dv, _] = bernstein::basis_d2(self.degree_v, v);
        (
            self.contract(&bu, &bv),
            self.contract(&du, &bv),
            self.contract(&bu, &dv),
        )
    }

    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        if let Some(p) = self.bicubic() {
            let (bu, du) = bernstein::cubic_d1(u);
            let (bv, dv) = bernstein::cubic_d1(v);
            let (duu, dvv) = (bernstein::cubic_d2(u), bernstein::cubic_d2(v));
            let mut d = SurfaceDerivs::default();
            for i in 0..4 {
                let r = &p[4 * i..4 * i + 4];
                let row = r[0] * bv[0] + r[1] * bv[1] + r[2] * bv[2] + r[3] * bv[3];
                let rowv = r[0] * dv[0] + r[1] * dv[1] + r[2] * dv[2] + r[3] * dv[3];
                let rowvv = r[0] * dvv[0] + r[1] * dvv[1] + r[2] * dvv[2] + r[3] * dvv[3];
                d.p += row * bu[i];
                d.su += row * du[i];
                d.sv += rowv * bu[i];
                d.suu += row * duu[i];
                d.suv += rowv * du[i];
                d.svv += rowvv * bu[i];
            }
            return d;
        }
        let [bu, du, duu] = bernstein::basis_d2(self.degree_u, u);
        let [bv, dv, dvv] = bernstein::basis_d2(self.degree_v, v);
        SurfaceDerivs {
            p: self.contract(&bu, &bv),
            su: self.contract(&du, &bv),
            sv: self.contract(&bu, &dv),
            suu: self.contract(&duu, &bv),
            suv: self.contract(&du, &dv),
            svv: self.contract(&bu, &dvv),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::testutil::check_derivs_fd;
    use proptest::prelude::*;

    fn net(n: usize, m: usize, seed: u64) -> Vec<DVec3> {
        // Deterministic pseudo-random net (xorshift) for coverage of general shapes.
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        (0..(n + 1) * (m + 1))
            .map(|k| {
                let (i, j) = (k / (m + 1), k % (m + 1));
                DVec3::new(i as f64 + 0.3 * rnd(), j as f64 + 0.3 * rnd(), rnd())
            })
            .collect()
    }

    #[test]
    fn rejects_bad_input_naming_the_element() {
        let e = BezierPatch::new(2, 2, vec![DVec3::ZERO; 8]).unwrap_err();
        assert_eq!(
            e,
            SurfaceError::ControlPointCount {
                expected: 9,
                got: 8
            }
        );
        let mut pts = vec![DVec3::ZERO; 9];
        pts[4].y = f64::NAN;
        let e = BezierPatch::new(2, 2, pts).unwrap_err();
        assert!(e.to_string().contains("control point 4"), "{e}");
    }

    #[test]
    fn tv21_bilinear_patch() {
        // S (2.10): P00=(0,0,1), P10=(1,0,0), P01=(1,1,1), P11=(0,1,0) → (u+w−2uw, w, 1−u).
        let p = BezierPatch::new(
            1,
            1,
            vec![
                DVec3::new(0.0, 0.0, 1.0),
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ],
        )
        .unwrap();
        for &(u, w) in &[(0.2, 0.7), (0.5, 0.5), (0.9, 0.1)] {
            let (s, su, sv) = p.deriv1(u, w);
            assert!((s - DVec3::new(u + w - 2.0 * u * w, w, 1.0 - u)).length() < 1e-15);
            assert!((su - DVec3::new(1.0 - 2.0 * w, 0.0, -1.0)).length() < 1e-15);
            assert!((sv - DVec3::new(1.0 - 2.0 * u, 1.0, 0.0)).length() < 1e-15);
        }
        // S (2.11)–(2.13): normal (1−w, 0.5(1−u), 1−0.5w).
        let p = BezierPatch::new(
            1,
            1,
            vec![
                DVec3::new(0.0, 0.0, 1.0),
                DVec3::new(0.5, 1.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
            ],
        )
        .unwrap();
        let (u, w) = (0.3, 0.6);
        let (s, su, sv) = p.deriv1(u, w);
        assert!(
            (s - DVec3::new(0.5 * (1.0 - u) * w + u, w, (1.0 - u) * (1.0 - w))).length() < 1e-15
        );
        let n = su.cross(sv);
        assert!((n - DVec3::new(1.0 - w, 0.5 * (1.0 - u), 1.0 - 0.5 * w)).length() < 1e-15);
    }

    #[test]
    fn bicubic_corner_identities() {
        // Duncan L1132–L1176.
        let pts = net(3, 3, 3);
        let p = BezierPatch::new(3, 3, pts).unwrap();
        let d = |i, j| p.point(i, j);
        let c00 = p.deriv2(0.0, 0.0);
        assert!((c00.su - 3.0 * (d(1, 0) - d(0, 0))).length() < 1e-13);
        assert!((c00.suu - 6.0 * (d(0, 0) - 2.0 * d(1, 0) + d(2, 0))).length() < 1e-12);
        assert!((c00.suv - 9.0 * (d(0, 0) - d(0, 1) + d(1, 1) - d(1, 0))).length() < 1e-12);
        let c11 = p.deriv2(1.0, 1.0);
        assert!((c11.suv - 9.0 * (d(3, 3) - d(3, 2) + d(2, 2) - d(2, 3))).length() < 1e-12);
        let c01 = p.deriv2(0.0, 1.0);
        assert!((c01.svv - 6.0 * (d(0, 1) - 2.0 * d(0, 2) + d(0, 3))).length() < 1e-12);
    }

    #[test]
    fn fast_path_equals_general_path() {
        let pts = net(3, 3, 11);
        let p = BezierPatch::new(3, 3, pts.clone()).unwrap();
        // The same surface as a degree-(4,3) patch goes through the general path.
        let q = p.elevate_u();
        for &(u, v) in &[(0.1, 0.2), (0.5, 0.9), (0.77, 0.33)] {
            let a = p.deriv2(u, v);
            let b = q.deriv2(u, v);
            assert!((a.p - b.p).length() < 1e-13);
            assert!((a.su - b.su).length() < 1e-12);
            assert!((a.sv - b.sv).length() < 1e-12);
            assert!((a.suu - b.suu).length() < 1e-11);
            assert!((a.suv - b.suv).length() < 1e-11);
            assert!((a.svv - b.svv).length() < 1e-11);
            assert!((p.eval(u, v) - q.eval(u, v)).length() < 1e-13);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for (n, m, seed) in [(3, 3, 1), (2, 4, 2), (5, 1, 3), (1, 1, 4)] {
            let p = BezierPatch::new(n, m, net(n, m, seed)).unwrap();
            check_derivs_fd(&p, 1e-6);
        }
    }

    proptest! {
        #[test]
        fn subdivision_and_elevation_leave_the_surface_unchanged(
            seed in 0u64..1000, n in 1usize..5, m in 1usize..5,
            t in 0.05f64..0.95, u in 0.0f64..1.0, v in 0.0f64..1.0,
        ) {
            let p = BezierPatch::new(n, m, net(n, m, seed)).unwrap();
            let x = p.eval(u, v);
            let (l, r) = p.subdivide_u(t);
            let y = if u <= t { l.eval(u / t, v) } else { r.eval((u - t) / (1.0 - t), v) };
            prop_assert!((x - y).length() < 1e-12);
            let (l, r) = p.subdivide_v(t);
            let y = if v <= t { l.eval(u, v / t) } else { r.eval(u, (v - t) / (1.0 - t)) };
            prop_assert!((x - y).length() < 1e-12);
            prop_assert!((p.elevate_u().eval(u, v) - x).length() < 1e-12);
            prop_assert!((p.elevate_v().elevate_u().eval(u, v) - x).length() < 1e-12);
        }

        #[test]
        fn affine_invariance_and_partition_of_unity(
            seed in 0u64..1000, u in 0.0f64..1.0, v in 0.0f64..1.0, dx in -5.0f64..5.0,
        ) {
            let p = BezierPatch::new(3, 2, net(3, 2, seed)).unwrap();
            let a = glam::DMat3::from_cols(
                DVec3::new(1.0, 0.2, 0.0), DVec3::new(-0.3, 2.0, 0.1), DVec3::new(0.0, 0.5, 1.0));
            let t = DVec3::new(dx, 1.0, -2.0);
            let q = p.map_points(|x| a * x + t);
            prop_assert!((q.eval(u, v) - (a * p.eval(u, v) + t)).length() < 1e-12);
            // Translating the net translates the surface only if the weights sum to one.
            let r = p.map_points(|x| x + DVec3::X);
            prop_assert!((r.eval(u, v) - p.eval(u, v) - DVec3::X).length() < 1e-12);
        }
    }
}
