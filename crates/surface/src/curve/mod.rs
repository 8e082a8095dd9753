//! Curves: Bézier, B-spline/NURBS, Hermite, interpolating splines, polylines, arc length,
//! curvature and Frenet frames.
//!
//! Every curve type implements [`crate::ParamCurve`]; the measurements that work for any curve
//! (arc length and its inverse, curvature, torsion, Frenet frame, closest point, flattening to a
//! polyline within a chordal tolerance) live in the blanket extension trait [`CurveExt`].
//! Piecewise types (B-spline, NURBS, spline, polyline) also have inherent `flatten`/`nearest`
//! that start from their breakpoints; the [`Curve`] enum keeps that knowledge for mixed
//! collections, where `dyn ParamCurve` would hide it.
//!
//! The B-spline basis kernels in [`basis`] are shared with the tensor-product patches.
//!
//! ```
//! use flatcut_surface::ParamCurve;
//! use flatcut_surface::curve::{CurveExt, CubicSpline, Nurbs, SplineEnds, SplineParam};
//! use glam::DVec3;
//!
//! // An exact 90° arc of radius 40 mm, flattened for a 0.05 mm chordal tolerance.
//! let arc = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 40.0, 0.0, std::f64::consts::FRAC_PI_2)?;
//! assert!((arc.arclen(1e-9) - 20.0 * std::f64::consts::PI).abs() < 1e-9);
//! let polyline = arc.flatten(0.05);
//! assert!(polyline.len() > 2);
//!
//! // A closed seam through digitised points, parametrised by chord length (mm).
//! let pts = [DVec3::new(0., 0., 0.), DVec3::new(50., 0., 5.), DVec3::new(50., 30., 0.), DVec3::new(0., 30., 5.)];
//! let seam = CubicSpline::interpolate(&pts, SplineEnds::Closed, SplineParam::ChordLength)?;
//! let p = DVec3::new(25.0, -3.0, 0.0);
//! let (t, dist) = seam.nearest(p, 1e-9);
//! let (a, b) = seam.domain();
//! assert!((0..=1000).all(|i| seam.eval(a + (b - a) * i as f64 / 1000.0).distance(p) >= dist - 1e-9));
//! assert!(seam.curvature(t).is_some());
//! # Ok::<(), flatcut_surface::SurfaceError>(())
//! ```

pub mod any;
pub mod basis;
pub mod bezier;
pub mod bspline;
pub mod conic;
pub mod ext;
pub mod fit;
pub mod hermite;
pub mod polyline;
pub mod rational;
pub mod spline;

pub use any::Curve;
pub use bezier::Bezier;
pub use bspline::{BSpline, Nurbs};
pub use conic::{Ellipse, Frame, Line};
pub use ext::{CurveExt, Frenet, flatten_with_breaks, nearest_from_samples};
pub use fit::{Fit, fit_bspline};
pub use hermite::{
    Hermite, HermiteSpline, SpeedRule, manning_cubic, manning_speeds, min_energy_cubic,
    min_energy_speeds,
};
pub use polyline::Polyline;
pub use rational::RationalBezier;
pub use spline::{CubicSpline, SplineEnds, SplineParam};
