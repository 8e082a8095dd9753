//! Curves: Bézier, B-spline/NURBS, Hermite, interpolating splines, arc length, Frenet frames.
//!
//! Every curve type implements [`crate::ParamCurve`]; the measurements that work for any curve
//! (arc length, curvature, torsion, Frenet frame, closest point, flattening to a polyline) live in
//! the blanket extension trait [`CurveExt`].

pub mod basis;
pub mod bezier;
pub mod bspline;

pub use bezier::Bezier;
pub use bspline::{BSpline, Nurbs};
