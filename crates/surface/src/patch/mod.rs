//! Patches: tensor-product Bézier, Hermite, B-spline/NURBS, Coons, Gordon, ruled, developable,
//! triangular, and the elementary and swept surfaces of STEP files.
//!
//! Every patch implements [`crate::ParamSurface`]. Constructors validate their input (counts,
//! knots, weights, finite coordinates, matching corners) and return [`crate::SurfaceError`]
//! naming the offending element, so evaluation afterwards is total and allocation-light.
//!
//! The multi-patch [`Model`] records which patch edges coincide so that a tessellator can
//! produce crack-free meshes.

pub mod analytic;
mod bernstein;
pub mod bezier;
pub mod bspline;
pub mod coons;
pub mod developable;
pub mod hermite;
pub mod model;
pub mod tri;

pub use analytic::{Analytic, AnalyticKind};
pub use bezier::BezierPatch;
pub use bspline::BSplinePatch;
pub use coons::{CoonsPatch, GordonSurface, RuledSurface};
pub use developable::{DevelopableOptions, DevelopableSurface, unfold_triangle};
pub use hermite::HermitePatch;
pub use model::{Model, SharedEdge, Side};
pub use tri::TriBezierPatch;

use crate::SurfaceError;
use glam::DVec3;

/// Checks that every point is finite; `what` names the kind of point in the error.
pub(crate) fn check_finite(points: &[DVec3], what: &'static str) -> Result<(), SurfaceError> {
    match points.iter().position(|p| !flatcut_geom::finite3(*p)) {
        Some(index) => Err(SurfaceError::NonFinite { what, index }),
        None => Ok(()),
    }
}

#[cfg(test)]
pub(crate) mod testutil {
    //! Shared test helpers: derivatives against central finite differences.
    use crate::ParamSurface;

    /// Checks `deriv1`/`deriv2` against central differences of `eval`/`deriv1` at interior points,
    /// and that `eval` equals the point of `deriv2`. `tol` is relative to the derivative size.
    pub(crate) fn check_derivs_fd(s: &dyn ParamSurface, tol: f64) {
        let d = s.domain();
        let tri = s.domain_kind() == crate::DomainKind::Triangle;
        let (du, dv) = (d.u.1 - d.u.0, d.v.1 - d.v.0);
        let h = 1e-5 * du.max(dv);
        for &(a, b) in &[(0.21, 0.33), (0.47, 0.29), (0.13, 0.71), (0.62, 0.37)] {
            let (a, b) = if tri && a + b > 0.95 {
                (a * 0.5, b * 0.5)
            } else {
                (a, b)
            };
            let (u, v) = (d.u.0 + a * du, d.v.0 + b * dv);
            let k = s.deriv2(u, v);
            let scale = 1.0 + k.su.length() + k.sv.length();
            let scale2 = scale + k.suu.length() + k.svv.length() + k.suv.length();
            assert!(
                (s.eval(u, v) - k.p).length() < 1e-12 * scale,
                "eval vs deriv2 at ({u},{v})"
            );
            let (p1, su1, sv1) = s.deriv1(u, v);
            assert!((p1 - k.p).length() < 1e-12 * scale);
            assert!((su1 - k.su).length() < 1e-11 * scale, "deriv1 su vs deriv2");
            assert!((sv1 - k.sv).length() < 1e-11 * scale, "deriv1 sv vs deriv2");
            let fu = (s.eval(u + h, v) - s.eval(u - h, v)) / (2.0 * h);
            let fv = (s.eval(u, v + h) - s.eval(u, v - h)) / (2.0 * h);
            assert!(
                (fu - k.su).length() < tol * scale,
                "su {} vs fd {} at ({u},{v})",
                k.su,
                fu
            );
            assert!(
                (fv - k.sv).length() < tol * scale,
                "sv {} vs fd {} at ({u},{v})",
                k.sv,
                fv
            );
            let (_, sup, svp) = s.deriv1(u + h, v);
            let (_, sum, svm) = s.deriv1(u - h, v);
            let (_, _, svq) = s.deriv1(u, v + h);
            let (_, _, svr) = s.deriv1(u, v - h);
            let fuu = (sup - sum) / (2.0 * h);
            let fuv = (svp - svm) / (2.0 * h);
            let fvv = (svq - svr) / (2.0 * h);
            assert!(
                (fuu - k.suu).length() < tol * scale2,
                "suu {} vs fd {}",
                k.suu,
                fuu
            );
            assert!(
                (fuv - k.suv).length() < tol * scale2,
                "suv {} vs fd {}",
                k.suv,
                fuv
            );
            assert!(
                (fvv - k.svv).length() < tol * scale2,
                "svv {} vs fd {}",
                k.svv,
                fvv
            );
        }
    }
}
