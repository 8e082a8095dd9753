//! Curves: Bézier, B-spline/NURBS, Hermite, interpolating splines, arc length, Frenet frames.
//!
//! Every curve type implements [`crate::ParamCurve`]; the measurements that work for any curve
//! (arc length, curvature, torsion, Frenet frame, closest point, flattening to a polyline) live in
//! the blanket extension trait [`CurveExt`].

pub mod basis;
pub mod bezier;
pub mod bspline;
pub mod ext;
pub mod hermite;

pub use bezier::Bezier;
pub use bspline::{BSpline, Nurbs};
pub use ext::{CurveExt, Frenet};
pub use hermite::{
    Hermite, manning_cubic, manning_speeds, min_energy_cubic, min_energy_speeds,
};
