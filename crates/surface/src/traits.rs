//! The capability traits every curve and surface implements.

use glam::DVec3;

/// A parametric curve in 3D (plane curves use z = 0).
pub trait ParamCurve: Send + Sync + std::fmt::Debug {
    /// The parameter interval `(t0, t1)`.
    fn domain(&self) -> (f64, f64);
    /// The point at parameter `t`.
    fn eval(&self, t: f64) -> DVec3;
    /// The `k`-th derivative with respect to the parameter (`k = 0` is the point itself).
    fn deriv(&self, t: f64, k: usize) -> DVec3;
}

/// A rectangular parameter domain `[u0, u1] × [v0, v1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Domain2 {
    /// The u interval `(u0, u1)`, `u0 < u1`.
    pub u: (f64, f64),
    /// The v interval `(v0, v1)`, `v0 < v1`.
    pub v: (f64, f64),
}

impl Domain2 {
    /// The unit square `[0, 1] × [0, 1]`.
    pub const UNIT: Self = Self {
        u: (0.0, 1.0),
        v: (0.0, 1.0),
    };
}

/// Position and partial derivatives up to second order at one (u, v).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SurfaceDerivs {
    /// The point `r(u, v)` (mm).
    pub p: DVec3,
    /// `∂r/∂u`.
    pub su: DVec3,
    /// `∂r/∂v`.
    pub sv: DVec3,
    /// `∂²r/∂u²`.
    pub suu: DVec3,
    /// `∂²r/∂u∂v`.
    pub suv: DVec3,
    /// `∂²r/∂v²`.
    pub svv: DVec3,
}

/// The shape of a patch's parameter domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DomainKind {
    /// The rectangle `[u0, u1] × [v0, v1]` given by [`ParamSurface::domain`].
    #[default]
    Rectangle,
    /// The triangle `u ≥ 0, v ≥ 0, u + v ≤ 1` (barycentric coordinates (u, v, 1 − u − v));
    /// [`ParamSurface::domain`] then returns the unit square that contains it.
    Triangle,
}

/// A parametric surface patch.
pub trait ParamSurface: Send + Sync + std::fmt::Debug {
    /// The parameter domain (its bounding rectangle for a triangular patch).
    fn domain(&self) -> Domain2;
    /// Whether the domain is the rectangle or the unit triangle.
    fn domain_kind(&self) -> DomainKind {
        DomainKind::Rectangle
    }
    /// The point at (u, v).
    fn eval(&self, u: f64, v: f64) -> DVec3;
    /// Point and first partials `(p, s_u, s_v)`; the hot path for tessellation and benchmarks.
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3);
    /// Point with first and second partials (fundamental forms, curvature, geodesics).
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs;
}
