//! Parametric curves and surfaces in millimetres, and their differential geometry.
//!
//! The two capability traits are [`ParamCurve`] and [`ParamSurface`]; every curve and patch type
//! implements one of them, and everything downstream (differential geometry, tessellation,
//! flattening) works through them.
//!
//! Vocabulary (shared with the rest of flatcut): `eval` (a point), `deriv` (derivatives),
//! `subdivide`, `nearest` (closest point), `arclen`.
//!
//! Patches ([`patch`]): [`BezierPatch`], [`HermitePatch`], [`BSplinePatch`] (with exact sphere,
//! cylinder, cone and torus pieces), [`CoonsPatch`], [`GordonSurface`], [`RuledSurface`],
//! [`DevelopableSurface`], [`TriBezierPatch`], the multi-patch [`Model`], and the elementary and
//! swept surfaces of STEP files in their own parametrisation ([`patch::Analytic`]). Differential
//! geometry ([`diffgeom`]): normals, fundamental forms, curvatures, Christoffel symbols,
//! geodesics, developability tests.
//!
//! **Architecture invariant:** evaluators are pure and total on their domain; construction
//! validates (knots non-decreasing, weights positive, counts consistent, coordinates finite) and
//! returns [`SurfaceError`] rather than panicking later.
#![warn(missing_docs)]

pub mod curve;
pub mod diffgeom;
pub mod error;
pub mod patch;
pub mod traits;

pub use error::SurfaceError;
pub use patch::{
    BSplinePatch, BezierPatch, CoonsPatch, DevelopableOptions, DevelopableSurface, GordonSurface,
    HermitePatch, Model, RuledSurface, SharedEdge, Side, TriBezierPatch,
};
pub use traits::{Domain2, DomainKind, ParamCurve, ParamSurface, SurfaceDerivs};
