//! Bicubic Hermite (Ferguson/Coons corner-data) patches (Salomon §4.8–4.9 (4.35), Duncan Def 3.1).
//!
//! The patch is stored as its exact bicubic Bézier form: along each parameter a cubic Hermite
//! segment `(p0, p1, m0, m1)` is the Bézier curve `(p0, p0 + m0/3, p1 − m1/3, p1)`, and the
//! tensor product of that linear map takes the 4×4 geometry matrix `B` of (4.35) to the Bézier
//! net. Evaluation then uses the allocation-free bicubic path of [`BezierPatch`].

use super::BezierPatch;
use crate::{Domain2, ParamSurface, SurfaceDerivs, SurfaceError};
use glam::DVec3;

/// A bicubic Hermite patch on the unit square, defined by corner data.
#[derive(Clone, Debug, PartialEq)]
pub struct HermitePatch {
    bezier: BezierPatch,
}

impl HermitePatch {
    /// Builds the patch from corner points `corners[i][j] = P(i, j)`, u-tangents
    /// `P_u(i, j)`, v-tangents `P_v(i, j)` and twists `P_uv(i, j)` (`i, j ∈ {0, 1}`).
    pub fn new(
        corners: [[DVec3; 2]; 2],
        tangents_u: [[DVec3; 2]; 2],
        tangents_v: [[DVec3; 2]; 2],
        twists: [[DVec3; 2]; 2],
    ) -> Result<Self, SurfaceError> {
        for (what, arr) in [
            ("Hermite corner", &corners),
            ("Hermite u-tangent", &tangents_u),
            ("Hermite v-tangent", &tangents_v),
            ("Hermite twist", &twists),
        ] {
            let flat = [arr[0][0], arr[0][1], arr[1][0], arr[1][1]];
            super::check_finite(&flat, what)?;
        }
        // Geometry matrix G[a][b]: a = (P(0,·), P(1,·), P_u(0,·), P_u(1,·)),
        // b = (value at v=0, value at v=1, v-derivative at 0, v-derivative at 1).
        let g = |a: usize, b: usize| -> DVec3 {
            let (src_pt, src_v) = if a < 2 {
                (&corners[a], &tangents_v[a])
            } else {
                (&tangents_u[a - 2], &twists[a - 2])
            };
            if b < 2 { src_pt[b] } else { src_v[b - 2] }
        };
        let hermite_to_bezier =
            |p0: DVec3, p1: DVec3, m0: DVec3, m1: DVec3| [p0, p0 + m0 / 3.0, p1 - m1 / 3.0, p1];
        let mut t = [[DVec3::ZERO; 4]; 4];
        for (a, row) in t.iter_mut().enumerate() {
            *row = hermite_to_bezier(g(a, 0), g(a, 1), g(a, 2), g(a, 3));
        }
        let mut pts = vec![DVec3::ZERO; 16];
        for j in 0..4 {
            let col = hermite_to_bezier(t[0][j], t[1][j], t[2][j], t[3][j]);
            for i in 0..4 {
                pts[4 * i + j] = col[i];
            }
        }
        Ok(Self {
            bezier: BezierPatch::new(3, 3, pts)?,
        })
    }

    /// A Ferguson patch: Hermite data with zero twists (S (4.34)).
    pub fn ferguson(
        corners: [[DVec3; 2]; 2],
        tangents_u: [[DVec3; 2]; 2],
        tangents_v: [[DVec3; 2]; 2],
    ) -> Result<Self, SurfaceError> {
        Self::new(corners, tangents_u, tangents_v, [[DVec3::ZERO; 2]; 2])
    }

    /// The equivalent bicubic Bézier patch.
    pub fn to_bezier(&self) -> &BezierPatch {
        &self.bezier
    }
}

impl ParamSurface for HermitePatch {
    fn domain(&self) -> Domain2 {
        Domain2::UNIT
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.bezier.eval(u, v)
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        self.bezier.deriv1(u, v)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        self.bezier.deriv2(u, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::testutil::check_derivs_fd;

    fn sample() -> HermitePatch {
        let c = [
            [DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.5)],
            [DVec3::new(3.0, 0.0, 1.0), DVec3::new(3.0, 2.0, -0.5)],
        ];
        let tu = [
            [DVec3::new(3.0, 0.5, 1.0), DVec3::new(2.0, 0.0, -1.0)],
            [DVec3::new(4.0, 0.0, 0.0), DVec3::new(3.0, 0.3, 0.2)],
        ];
        let tv = [
            [DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.5, 2.0, 1.0)],
            [DVec3::new(0.0, 1.5, -1.0), DVec3::new(-0.2, 2.5, 0.0)],
        ];
        let tw = [
            [DVec3::new(0.1, 0.2, 0.3), DVec3::new(-0.4, 0.0, 0.5)],
            [DVec3::new(0.0, 0.7, -0.2), DVec3::new(0.3, -0.3, 0.9)],
        ];
        HermitePatch::new(c, tu, tv, tw).unwrap()
    }

    #[test]
    fn reproduces_the_corner_data() {
        let h = sample();
        let c = [
            [DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.5)],
            [DVec3::new(3.0, 0.0, 1.0), DVec3::new(3.0, 2.0, -0.5)],
        ];
        let tu01 = DVec3::new(2.0, 0.0, -1.0);
        let tv10 = DVec3::new(0.0, 1.5, -1.0);
        let tw11 = DVec3::new(0.3, -0.3, 0.9);
        for i in 0..2 {
            for j in 0..2 {
                assert!((h.eval(i as f64, j as f64) - c[i][j]).length() < 1e-14);
            }
        }
        assert!((h.deriv1(0.0, 1.0).1 - tu01).length() < 1e-13);
        assert!((h.deriv1(1.0, 0.0).2 - tv10).length() < 1e-13);
        assert!((h.deriv2(1.0, 1.0).suv - tw11).length() < 1e-12);
    }

    #[test]
    fn matches_the_hermite_basis_form() {
        // P(u,v) = Σ_ab H_a(u) H_b(v) G_ab with H = (1−3t²+2t³, 3t²−2t³, t−2t²+t³, −t²+t³).
        let hb = |t: f64| {
            [
                1.0 - 3.0 * t * t + 2.0 * t * t * t,
                3.0 * t * t - 2.0 * t * t * t,
                t - 2.0 * t * t + t * t * t,
                -t * t + t * t * t,
            ]
        };
        let h = sample();
        let (u, v) = (0.3, 0.8);
        let b = h.to_bezier();
        let mut g = [[DVec3::ZERO; 4]; 4];
        for a in 0..2 {
            for bb in 0..2 {
                let (uu, vv) = (a as f64, bb as f64);
                let d = b.deriv2(uu, vv);
                g[a][bb] = d.p;
                g[a][bb + 2] = d.sv;
                g[a + 2][bb] = d.su;
                g[a + 2][bb + 2] = d.suv;
            }
        }
        let (hu, hv) = (hb(u), hb(v));
        let mut p = DVec3::ZERO;
        for a in 0..4 {
            for bb in 0..4 {
                p += g[a][bb] * hu[a] * hv[bb];
            }
        }
        assert!((p - h.eval(u, v)).length() < 1e-13);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        check_derivs_fd(&sample(), 1e-6);
    }

    #[test]
    fn rejects_non_finite_twist() {
        let z = [[DVec3::ZERO; 2]; 2];
        let mut tw = z;
        tw[1][0].x = f64::INFINITY;
        let e = HermitePatch::new(z, z, z, tw).unwrap_err();
        assert!(e.to_string().contains("Hermite twist 2"), "{e}");
    }
}
