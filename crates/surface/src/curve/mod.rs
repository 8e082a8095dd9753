//! Curves: Bézier, B-spline/NURBS, Hermite, interpolating splines, polylines, arc length,
//! curvature and Frenet frames.
//!
//! Every curve type implements [`crate::ParamCurve`]; the measurements that work for any curve
//! (arc length and its inverse, curvature, torsion, Frenet frame, closest point, flattening to a
//! polyline within a chordal tolerance) live in the blanket extension trait [`CurveExt`].
//! Piecewise types (B-spline, NURBS, spline, polyline) also have inherent `flatten`/`nearest`
//! that start from their breakpoints.
//!
//! The B-spline basis kernels in [`basis`] are shared with the tensor-product patches.

pub mod basis;
pub mod bezier;
pub mod bspline;
pub mod ext;
pub mod hermite;
pub mod polyline;
pub mod rational;
pub mod spline;

pub use bezier::Bezier;
pub use bspline::{BSpline, Nurbs};
pub use ext::{CurveExt, Frenet, flatten_with_breaks, nearest_from_samples};
pub use hermite::{
    Hermite, HermiteSpline, SpeedRule, manning_cubic, manning_speeds, min_energy_cubic,
    min_energy_speeds,
};
pub use polyline::Polyline;
pub use rational::RationalBezier;
pub use spline::{CubicSpline, SplineEnds, SplineParam};
