//! Differential geometry of surfaces through [`ParamSurface`]: normals, fundamental forms,
//! curvatures, Christoffel symbols, geodesics and developability tests.
//!
//! Conventions: `N = r_u × r_v / |r_u × r_v|` (the signs of L, M, N, H and of the principal
//! curvatures follow it; K does not). Christoffel symbols use the corrected Duncan formulas
//! (ERRATA E1, E2). Every function returns `None` (or a typed error) at singular points where
//! `r_u × r_v` vanishes, never NaN.

use crate::{Domain2, DomainKind, ParamSurface, SurfaceDerivs};
use glam::{DVec2, DVec3};

/// `|r_u × r_v|` below this fraction of `|r_u| |r_v|` (a sine) counts as a singular point:
/// the tangent plane is undefined to better than ~1e-12 rad.
pub const SINGULAR_SIN: f64 = 1e-12;

/// The unit normal `r_u × r_v / |r_u × r_v|`, or `None` at a singular point.
pub fn normal(s: &dyn ParamSurface, u: f64, v: f64) -> Option<DVec3> {
    let (_, su, sv) = s.deriv1(u, v);
    unit_normal(su, sv)
}

fn unit_normal(su: DVec3, sv: DVec3) -> Option<DVec3> {
    let n = su.cross(sv);
    let l = n.length();
    (l > SINGULAR_SIN * su.length() * sv.length() && l.is_finite() && l > 0.0).then(|| n / l)
}

/// First (E, F, G) and second (L, M, N) fundamental forms at one point, with the unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FundamentalForms {
    /// `E = r_u · r_u`.
    pub e: f64,
    /// `F = r_u · r_v`.
    pub f: f64,
    /// `G = r_v · r_v`.
    pub g: f64,
    /// `L = r_uu · N`.
    pub l: f64,
    /// `M = r_uv · N`.
    pub m: f64,
    /// `N = r_vv · N`.
    pub n: f64,
    /// The unit normal `N = r_u × r_v / |r_u × r_v|`.
    pub normal: DVec3,
}

impl FundamentalForms {
    /// From precomputed derivatives; `None` at a singular point.
    pub fn from_derivs(d: &SurfaceDerivs) -> Option<Self> {
        let nrm = unit_normal(d.su, d.sv)?;
        Some(Self {
            e: d.su.dot(d.su),
            f: d.su.dot(d.sv),
            g: d.sv.dot(d.sv),
            l: d.suu.dot(nrm),
            m: d.suv.dot(nrm),
            n: d.svv.dot(nrm),
            normal: nrm,
        })
    }
    /// `EG − F²` (> 0 at regular points).
    pub fn det_first(&self) -> f64 {
        self.e * self.g - self.f * self.f
    }
    /// Gaussian curvature `K = (LN − M²)/(EG − F²)`.
    pub fn gaussian(&self) -> f64 {
        (self.l * self.n - self.m * self.m) / self.det_first()
    }
    /// Mean curvature `H = (GL − 2FM + EN) / (2(EG − F²))`.
    pub fn mean(&self) -> f64 {
        (self.g * self.l - 2.0 * self.f * self.m + self.e * self.n) / (2.0 * self.det_first())
    }
    /// Normal curvature `II/I` in the parameter direction `(du, dv)`; `None` for a zero direction.
    pub fn normal_curvature(&self, d: DVec2) -> Option<f64> {
        let i = self.e * d.x * d.x + 2.0 * self.f * d.x * d.y + self.g * d.y * d.y;
        let ii = self.l * d.x * d.x + 2.0 * self.m * d.x * d.y + self.n * d.y * d.y;
        (i > 0.0).then(|| ii / i)
    }
}

/// The fundamental forms at `(u, v)`, or `None` at a singular point.
pub fn fundamental_forms(s: &dyn ParamSurface, u: f64, v: f64) -> Option<FundamentalForms> {
    FundamentalForms::from_derivs(&s.deriv2(u, v))
}

/// Curvature at a point: Gaussian `K`, mean `H`, principal curvatures `k1 ≥ k2` and their
/// directions (in the parameter plane and as unit 3D tangents).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    /// Gaussian curvature `K = k1 k2` (1/mm²).
    pub gaussian: f64,
    /// Mean curvature `H = (k1 + k2) / 2` (1/mm), signed by the normal.
    pub mean: f64,
    /// The larger principal curvature (1/mm).
    pub k1: f64,
    /// The smaller principal curvature (1/mm).
    pub k2: f64,
    /// Direction of `k1` in the parameter plane.
    pub dir1_uv: DVec2,
    /// Direction of `k2` in the parameter plane.
    pub dir2_uv: DVec2,
    /// Direction of `k1` as a unit 3D tangent.
    pub dir1: DVec3,
    /// Direction of `k2` as a unit 3D tangent.
    pub dir2: DVec3,
}

/// Curvatures at `(u, v)` (G Prop 4.28, Thm 4.24), or `None` at a singular point.
///
/// At an umbilic (`k1 = k2`) every direction is principal; the returned pair is then the
/// orthonormal frame built from `r_u`.
pub fn curvature(s: &dyn ParamSurface, u: f64, v: f64) -> Option<Curvature> {
    let d = s.deriv2(u, v);
    let ff = FundamentalForms::from_derivs(&d)?;
    let k = ff.gaussian();
    let h = ff.mean();
    // Shape operator in an orthonormal tangent frame (t1, t2) is the symmetric matrix
    // [[a, b], [b, c]]: exact eigen-decomposition without the ill-conditioned √(H² − K).
    let t1 = d.su.normalize();
    let t2 = ff.normal.cross(t1);
    // Express t1, t2 in parameter coordinates: r_u x + r_v y = t.
    let det = ff.det_first();
    let to_uv = |t: DVec3| {
        let (a, b) = (t.dot(d.su), t.dot(d.sv));
        DVec2::new((ff.g * a - ff.f * b) / det, (ff.e * b - ff.f * a) / det)
    };
    let (p1, p2) = (to_uv(t1), to_uv(t2));
    let ii =
        |x: DVec2, y: DVec2| ff.l * x.x * y.x + ff.m * (x.x * y.y + x.y * y.x) + ff.n * x.y * y.y;
    let (a, b, c) = (ii(p1, p1), ii(p1, p2), ii(p2, p2));
    let half_diff = 0.5 * (a - c);
    let rad = half_diff.hypot(b);
    let mid = 0.5 * (a + c);
    let (k1, k2) = (mid + rad, mid - rad);
    // Eigenvector of k1: angle θ with tan 2θ = 2b/(a − c).
    let theta = 0.5 * b.atan2(half_diff);
    let (cs, sn) = (theta.cos(), theta.sin());
    let dir1 = t1 * cs + t2 * sn;
    let dir2 = ff.normal.cross(dir1);
    let out = Curvature {
        gaussian: k,
        mean: h,
        k1,
        k2,
        dir1_uv: to_uv(dir1),
        dir2_uv: to_uv(dir2),
        dir1,
        dir2,
    };
    [k, h, k1, k2].iter().all(|x| x.is_finite()).then_some(out)
}

/// Christoffel symbols of the second kind, `gamma[k][i][j] = Γ^k_ij` (indices 0 = u, 1 = v).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Christoffel {
    /// `gamma[k][i][j] = Γ^k_ij`; symmetric in `i`, `j`.
    pub gamma: [[[f64; 2]; 2]; 2],
}

/// Christoffel symbols at `(u, v)` by Duncan's formulas with the corrections E1/E2:
/// with `D = 2(EG − F²)`,
/// `Γ¹₁₁ = (G E_u − 2F F_u + F E_v)/D`, `Γ¹₁₂ = (G E_v − F G_u)/D`, `Γ¹₂₂ = (2G F_v − G G_u − F G_v)/D`,
/// `Γ²₁₁ = (2E F_u − E E_v − F E_u)/D`, `Γ²₁₂ = (E G_u − F E_v)/D`, `Γ²₂₂ = (E G_v − 2F F_v + F G_u)/D`.
pub fn christoffel(s: &dyn ParamSurface, u: f64, v: f64) -> Option<Christoffel> {
    christoffel_from(&s.deriv2(u, v))
}

fn christoffel_from(d: &SurfaceDerivs) -> Option<Christoffel> {
    unit_normal(d.su, d.sv)?;
    let (e, f, g) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
    let eu = 2.0 * d.suu.dot(d.su);
    let ev = 2.0 * d.suv.dot(d.su);
    let fu = d.suu.dot(d.sv) + d.su.dot(d.suv);
    let fv = d.suv.dot(d.sv) + d.su.dot(d.svv);
    let gu = 2.0 * d.suv.dot(d.sv);
    let gv = 2.0 * d.svv.dot(d.sv);
    let dd = 2.0 * (e * g - f * f);
    let g111 = (g * eu - 2.0 * f * fu + f * ev) / dd;
    let g112 = (g * ev - f * gu) / dd;
    let g122 = (2.0 * g * fv - g * gu - f * gv) / dd;
    let g211 = (2.0 * e * fu - e * ev - f * eu) / dd;
    let g212 = (e * gu - f * ev) / dd;
    let g222 = (e * gv - 2.0 * f * fv + f * gu) / dd;
    Some(Christoffel {
        gamma: [[[g111, g112], [g112, g122]], [[g211, g212], [g212, g222]]],
    })
}

/// Why a geodesic could not be traced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GeodesicError {
    /// The start point or direction is unusable.
    #[error("geodesic start: {0}")]
    BadStart(String),
    /// The surface is singular (r_u × r_v = 0) at the given parameters on the path.
    #[error("geodesic reaches a singular point at (u, v) = ({u:.6}, {v:.6}) after length {s:.6}")]
    Singular {
        /// Parameter u of the singular point.
        u: f64,
        /// Parameter v of the singular point.
        v: f64,
        /// Arc length traced before it (mm).
        s: f64,
    },
    /// The step size fell below the minimum without meeting the tolerance.
    #[error("geodesic step control failed at length {s:.6} (step {h:.3e})")]
    StepUnderflow {
        /// Arc length traced when the control failed (mm).
        s: f64,
        /// The last step size tried.
        h: f64,
    },
}

/// Options for [`geodesic`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeodesicOptions {
    /// Local error tolerance per step on the parameter state (step doubling estimate).
    pub tol: f64,
    /// Initial and largest step, as a fraction of the requested length.
    pub max_step_frac: f64,
    /// Smallest step, as a fraction of the requested length, before giving up.
    pub min_step_frac: f64,
}

impl GeodesicOptions {
    /// 1e-12 local error keeps ~1e-10 global error over hundreds of steps.
    pub const DEFAULT_TOL: f64 = 1e-12;
    /// At least 50 steps so the returned polyline resolves the curve.
    pub const DEFAULT_MAX_STEP_FRAC: f64 = 0.02;
    /// 1e-9 of the length: below this the surface is too rough for the tolerance.
    pub const DEFAULT_MIN_STEP_FRAC: f64 = 1e-9;
    /// The defaults above.
    pub const DEFAULT: Self = Self {
        tol: Self::DEFAULT_TOL,
        max_step_frac: Self::DEFAULT_MAX_STEP_FRAC,
        min_step_frac: Self::DEFAULT_MIN_STEP_FRAC,
    };
    /// Sets the local tolerance.
    pub fn with_tol(mut self, tol: f64) -> Self {
        self.tol = tol;
        self
    }
    /// Sets the largest step fraction.
    pub fn with_max_step_frac(mut self, f: f64) -> Self {
        self.max_step_frac = f;
        self
    }
}

impl Default for GeodesicOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A traced geodesic: parameter points, surface points and arc lengths, plus whether it
/// stopped at the domain boundary before the requested length.
#[derive(Clone, Debug, PartialEq)]
pub struct Geodesic {
    /// Parameter points along the path, the start first.
    pub uv: Vec<DVec2>,
    /// The surface points at `uv` (mm).
    pub points: Vec<DVec3>,
    /// Arc length from the start to each point (mm), increasing from 0.
    pub arclen: Vec<f64>,
    /// True when the path left the domain before the requested length.
    pub hit_boundary: bool,
}

type State = [f64; 4];

/// Minimum-size steps accepted above the tolerance before tracing fails: each one crosses a
/// curvature discontinuity; many in a row mean the surface is too rough for the tolerance.
const MAX_FORCED_STEPS: usize = 64;

fn geo_rhs(s: &dyn ParamSurface, y: &State) -> Option<State> {
    let d = s.deriv2(y[0], y[1]);
    let c = christoffel_from(&d)?;
    let (du, dv) = (y[2], y[3]);
    let acc = |k: usize| {
        let g = &c.gamma[k];
        -(g[0][0] * du * du + 2.0 * g[0][1] * du * dv + g[1][1] * dv * dv)
    };
    Some([du, dv, acc(0), acc(1)])
}

fn rk4_step(s: &dyn ParamSurface, y: &State, h: f64) -> Option<State> {
    let add = |a: &State, b: &State, f: f64| {
        [
            a[0] + f * b[0],
            a[1] + f * b[1],
            a[2] + f * b[2],
            a[3] + f * b[3],
        ]
    };
    let k1 = geo_rhs(s, y)?;
    let k2 = geo_rhs(s, &add(y, &k1, 0.5 * h))?;
    let k3 = geo_rhs(s, &add(y, &k2, 0.5 * h))?;
    let k4 = geo_rhs(s, &add(y, &k3, h))?;
    let mut out = *y;
    for i in 0..4 {
        out[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    Some(out)
}

fn inside(dom: &Domain2, kind: DomainKind, p: DVec2) -> bool {
    let ok = p.x >= dom.u.0 && p.x <= dom.u.1 && p.y >= dom.v.0 && p.y <= dom.v.1;
    match kind {
        DomainKind::Triangle => ok && p.x + p.y <= 1.0,
        _ => ok,
    }
}

/// Traces the geodesic from `start` in the parameter direction `dir` for surface length
/// `length`, integrating `ü^k + Γ^k_ij u̇^i u̇^j = 0` in arc length (D L1904–L1912) with RK4 and
/// step-doubling error control. The direction is normalized so that `|r_u u̇ + r_v v̇| = 1`.
/// Stops early (with `hit_boundary`) when the path leaves the domain.
pub fn geodesic(
    s: &dyn ParamSurface,
    start: DVec2,
    dir: DVec2,
    length: f64,
    opts: GeodesicOptions,
) -> Result<Geodesic, GeodesicError> {
    if !(length.is_finite() && length > 0.0) {
        return Err(GeodesicError::BadStart(format!(
            "length {length} must be finite and > 0"
        )));
    }
    let dom = s.domain();
    let kind = s.domain_kind();
    if !flatcut_geom::finite2(start) || !inside(&dom, kind, start) {
        return Err(GeodesicError::BadStart(format!(
            "start {start} is outside the domain"
        )));
    }
    let (p0, su, sv) = s.deriv1(start.x, start.y);
    if unit_normal(su, sv).is_none() {
        return Err(GeodesicError::Singular {
            u: start.x,
            v: start.y,
            s: 0.0,
        });
    }
    let speed = (su * dir.x + sv * dir.y).length();
    if !(speed.is_finite() && speed > 0.0) {
        return Err(GeodesicError::BadStart(format!(
            "direction {dir} is zero or not finite"
        )));
    }
    let d0 = dir / speed;
    let mut y: State = [start.x, start.y, d0.x, d0.y];
    let mut out = Geodesic {
        uv: vec![start],
        points: vec![p0],
        arclen: vec![0.0],
        hit_boundary: false,
    };
    let hmax = opts.max_step_frac * length;
    let hmin = opts.min_step_frac * length;
    let mut h = hmax;
    let mut sl = 0.0;
    let mut forced = 0usize;
    let singular = |y: &State, sl: f64| GeodesicError::Singular {
        u: y[0],
        v: y[1],
        s: sl,
    };
    while sl < length {
        let step = h.min(length - sl);
        let full = rk4_step(s, &y, step);
        let half = rk4_step(s, &y, 0.5 * step).and_then(|m| rk4_step(s, &m, 0.5 * step));
        let (full, fine) = match (full, half) {
            (Some(a), Some(b)) => (a, b),
            _ => {
                if step <= hmin {
                    return Err(singular(&y, sl));
                }
                h = step * 0.5;
                continue;
            }
        };
        let scale = 1.0 + y[0].abs().max(y[1].abs());
        let err = (0..4)
            .map(|i| (full[i] - fine[i]).abs())
            .fold(0.0, f64::max)
            / 15.0;
        if err > opts.tol * scale && step > hmin {
            h = step * (0.9 * (opts.tol * scale / err).powf(0.2)).clamp(0.1, 0.5);
            continue;
        }
        if err > opts.tol * scale {
            // A minimum-size step straddles a derivative discontinuity (e.g. a C¹ knot of a
            // NURBS): its error is O(h_min · jump), so accept it, but not indefinitely.
            forced += 1;
            if forced > MAX_FORCED_STEPS {
                return Err(GeodesicError::StepUnderflow { s: sl, h: step });
            }
        }
        // Richardson extrapolation of the two estimates (5th order).
        let mut next = fine;
        for i in 0..4 {
            next[i] += (fine[i] - full[i]) / 15.0;
        }
        let p = DVec2::new(next[0], next[1]);
        if !inside(&dom, kind, p) {
            if step <= hmin {
                out.hit_boundary = true;
                break;
            }
            h = step * 0.5;
            continue;
        }
        y = next;
        sl += step;
        out.uv.push(p);
        out.points.push(s.eval(p.x, p.y));
        out.arclen.push(sl);
        let grow = if err > 0.0 {
            (0.9 * (opts.tol * scale / err).powf(0.2)).min(4.0)
        } else {
            4.0
        };
        h = (step * grow).min(hmax);
    }
    Ok(out)
}

/// Result of [`developability`]: the largest `|K|` over a sample grid, made dimensionless by
/// the square of the patch's bounding-box diagonal, and where it occurs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DevelopabilityReport {
    /// `max |K| · diag²`: 0 for a developable; ~10 for a hemisphere-like patch.
    pub max_scaled_k: f64,
    /// The parameters of the worst sample.
    pub at: DVec2,
    /// Bounding-box diagonal of the samples (mm) used for scaling.
    pub diagonal: f64,
    /// Samples skipped as singular (r_u × r_v = 0).
    pub singular_samples: usize,
}

/// Samples `K` on an `n × n` grid (interior of each cell centre, so edges and poles are avoided)
/// and reports the largest scaled `|K|`. `n` is clamped to at least 2.
pub fn developability(s: &dyn ParamSurface, n: usize) -> DevelopabilityReport {
    let n = n.max(2);
    let dom = s.domain();
    let tri = s.domain_kind() == DomainKind::Triangle;
    let mut bb = flatcut_geom::Aabb3::EMPTY;
    let mut worst = (0.0f64, DVec2::new(dom.u.0, dom.v.0));
    let mut singular = 0;
    for i in 0..n {
        for j in 0..n {
            let (a, b) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            if tri && a + b >= 1.0 {
                continue;
            }
            let p = DVec2::new(
                dom.u.0 + a * (dom.u.1 - dom.u.0),
                dom.v.0 + b * (dom.v.1 - dom.v.0),
            );
            let d = s.deriv2(p.x, p.y);
            bb.add(d.p);
            match FundamentalForms::from_derivs(&d) {
                Some(ff) => {
                    let k = ff.gaussian().abs();
                    if k > worst.0 {
                        worst = (k, p);
                    }
                }
                None => singular += 1,
            }
        }
    }
    let diag = bb.diagonal();
    DevelopabilityReport {
        max_scaled_k: worst.0 * diag * diag,
        at: worst.1,
        diagonal: diag,
        singular_samples: singular,
    }
}

/// Duncan's two-rail test value `[R(u,1) − R(u,0), R_u(u,0), R_u(u,1)]` (D L1748) for a surface
/// ruled in v (`v` spanning its domain); identically zero iff the ruled surface is developable.
pub fn ruled_triple(s: &dyn ParamSurface, u: f64) -> f64 {
    let dom = s.domain();
    let (p0, r0, _) = s.deriv1(u, dom.v.0);
    let (p1, r1, _) = s.deriv1(u, dom.v.1);
    (p1 - p0).dot(r0.cross(r1))
}

/// The largest `|ruled_triple|` over `n + 1` samples in u and the u where it occurs.
pub fn ruled_developability(s: &dyn ParamSurface, n: usize) -> (f64, f64) {
    let dom = s.domain();
    let n = n.max(1);
    let mut worst = (0.0f64, dom.u.0);
    for i in 0..=n {
        let u = dom.u.0 + (dom.u.1 - dom.u.0) * i as f64 / n as f64;
        let t = ruled_triple(s, u).abs();
        if t > worst.0 {
            worst = (t, u);
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::{BSplinePatch, BezierPatch};
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    /// An analytic surface from a closure returning second-order derivatives.
    struct Analytic<F: Fn(f64, f64) -> SurfaceDerivs + Send + Sync> {
        dom: Domain2,
        f: F,
    }
    impl<F: Fn(f64, f64) -> SurfaceDerivs + Send + Sync> std::fmt::Debug for Analytic<F> {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "Analytic")
        }
    }
    impl<F: Fn(f64, f64) -> SurfaceDerivs + Send + Sync> ParamSurface for Analytic<F> {
        fn domain(&self) -> Domain2 {
            self.dom
        }
        fn eval(&self, u: f64, v: f64) -> DVec3 {
            (self.f)(u, v).p
        }
        fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
            let d = (self.f)(u, v);
            (d.p, d.su, d.sv)
        }
        fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
            (self.f)(u, v)
        }
    }

    /// Sphere of radius r in colatitude u, longitude v.
    fn sphere(r: f64) -> impl ParamSurface {
        Analytic {
            dom: Domain2 {
                u: (0.0, PI),
                v: (-PI, PI),
            },
            f: move |u: f64, v: f64| {
                let (su, cu, sv, cv) = (u.sin(), u.cos(), v.sin(), v.cos());
                SurfaceDerivs {
                    p: DVec3::new(su * cv, su * sv, cu) * r,
                    su: DVec3::new(cu * cv, cu * sv, -su) * r,
                    sv: DVec3::new(-su * sv, su * cv, 0.0) * r,
                    suu: DVec3::new(-su * cv, -su * sv, -cu) * r,
                    suv: DVec3::new(-cu * sv, cu * cv, 0.0) * r,
                    svv: DVec3::new(-su * cv, -su * sv, 0.0) * r,
                }
            },
        }
    }

    fn torus() -> impl ParamSurface {
        // TV26: ((2 + cos u) cos v, (2 + cos u) sin v, sin u).
        Analytic {
            dom: Domain2 {
                u: (-PI, PI),
                v: (-PI, PI),
            },
            f: |u: f64, v: f64| {
                let (su, cu, sv, cv) = (u.sin(), u.cos(), v.sin(), v.cos());
                let a = 2.0 + cu;
                SurfaceDerivs {
                    p: DVec3::new(a * cv, a * sv, su),
                    su: DVec3::new(-su * cv, -su * sv, cu),
                    sv: DVec3::new(-a * sv, a * cv, 0.0),
                    suu: DVec3::new(-cu * cv, -cu * sv, -su),
                    suv: DVec3::new(su * sv, -su * cv, 0.0),
                    svv: DVec3::new(-a * cv, -a * sv, 0.0),
                }
            },
        }
    }

    #[test]
    fn tv26_torus() {
        let t = torus();
        let ff = fundamental_forms(&t, 0.7, 0.3).unwrap();
        let a = 2.0 + 0.7f64.cos();
        assert!((ff.e - 1.0).abs() < 1e-14 && ff.f.abs() < 1e-14 && (ff.g - a * a).abs() < 1e-13);
        // With N = r_u × r_v/|·| pointing inward here, L = 1, N = (2 + cos u) cos u (G Ex 4.8).
        assert!((ff.l - 1.0).abs() < 1e-14 && ff.m.abs() < 1e-14);
        assert!((ff.n - a * 0.7f64.cos()).abs() < 1e-13);
        for &(u, k, h) in &[
            (0.0, 1.0 / 3.0, 2.0 / 3.0),
            (FRAC_PI_2, 0.0, 0.5),
            (PI, -1.0, 0.0),
            (PI / 3.0, 0.2, 0.6),
        ] {
            let c = curvature(&t, u, 0.4).unwrap();
            assert!((c.gaussian - k).abs() < 1e-13, "K({u}) = {}", c.gaussian);
            assert!((c.mean - h).abs() < 1e-13, "H({u}) = {}", c.mean);
            assert!((c.k1 - 1.0).abs() < 1e-13);
            assert!((c.k2 - u.cos() / (2.0 + u.cos())).abs() < 1e-13);
            // Principal directions: k1 along the meridian (r_u).
            assert!(c.dir1.cross(t.deriv1(u, 0.4).1.normalize()).length() < 1e-12);
        }
    }

    #[test]
    fn nurbs_primitives_have_analytic_curvature() {
        let s = BSplinePatch::sphere(DVec3::new(1.0, 2.0, 3.0), 3.0).unwrap();
        let cyl = BSplinePatch::cylinder(DVec3::ZERO, 2.0, 5.0).unwrap();
        let cone = BSplinePatch::cone(DVec3::ZERO, 4.0, 0.0, 4.0).unwrap();
        let tor = BSplinePatch::torus(DVec3::ZERO, 2.0, 1.0).unwrap();
        for i in 1..10 {
            for j in 0..10 {
                let (u, v) = (i as f64 / 10.0, j as f64 / 10.0 + 0.03);
                let c = curvature(&s, u, v).unwrap();
                assert!((c.gaussian - 1.0 / 9.0).abs() < 1e-12);
                assert!((c.mean.abs() - 1.0 / 3.0).abs() < 1e-12);
                let c = curvature(&cyl, u, v).unwrap();
                assert!(c.gaussian.abs() < 1e-12 && (c.mean.abs() - 0.25).abs() < 1e-12);
                // Cone z = 4 − r (half-angle 45°): H = cos45°/(2 r) at radius r = 4(1 − u).
                let c = curvature(&cone, u, v).unwrap();
                let r = 4.0 * (1.0 - u);
                assert!(c.gaussian.abs() < 1e-12);
                assert!((c.mean.abs() - FRAC_PI_4.cos() / (2.0 * r)).abs() < 1e-12);
                // TV26 form: K = cos θ/(r (R + r cos θ)) with θ the tube angle of the point.
                let p = tor.eval(u, v);
                let th = p.z.atan2(p.truncate().length() - 2.0);
                let c = curvature(&tor, u, v).unwrap();
                assert!((c.gaussian - th.cos() / (2.0 + th.cos())).abs() < 1e-11);
            }
        }
        // TV28: at the cone's u = 1/2 (r = 2) H = 0.1767766953.
        assert!((curvature(&cone, 0.5, 0.2).unwrap().mean.abs() - 0.1767766953).abs() < 1e-10);
        // The apex is singular: None, not NaN.
        assert!(curvature(&cone, 1.0, 0.2).is_none());
        assert!(normal(&cone, 1.0, 0.2).is_none());
    }

    #[test]
    fn saddle_and_helicoid() {
        // TV21 (H L4996): bilinear (u, v, uv): K = −1/(1 + u² + v²)².
        let b = BezierPatch::new(1, 1, vec![DVec3::ZERO, DVec3::Y, DVec3::X, DVec3::ONE]).unwrap();
        let c = curvature(&b, 0.0, 0.0).unwrap();
        assert!((c.gaussian + 1.0).abs() < 1e-14 && c.mean.abs() < 1e-14);
        let c = curvature(&b, 0.5, 0.5).unwrap();
        assert!((c.gaussian + 4.0 / 9.0).abs() < 1e-14);
        assert!((c.mean + 0.1360827635).abs() < 1e-10);
        for &(x, y) in &[(0.3, 0.9), (0.7, 0.2)] {
            let k = curvature(&b, x, y).unwrap().gaussian;
            let e = -1.0 / (1.0 + x * x + y * y).powi(2);
            assert!((k - e).abs() < 1e-14);
        }
        // TV28 helicoid (v cos u, v sin u, u): K = −1/(1 + v²)², H = 0.
        let h = Analytic {
            dom: Domain2 {
                u: (0.0, 6.0),
                v: (-2.0, 2.0),
            },
            f: |u: f64, v: f64| SurfaceDerivs {
                p: DVec3::new(v * u.cos(), v * u.sin(), u),
                su: DVec3::new(-v * u.sin(), v * u.cos(), 1.0),
                sv: DVec3::new(u.cos(), u.sin(), 0.0),
                suu: DVec3::new(-v * u.cos(), -v * u.sin(), 0.0),
                suv: DVec3::new(-u.sin(), u.cos(), 0.0),
                svv: DVec3::ZERO,
            },
        };
        let c = curvature(&h, 1.0, 0.5).unwrap();
        assert!((c.gaussian + 0.64).abs() < 1e-14 && c.mean.abs() < 1e-14);
        assert!((c.k1 + c.k2).abs() < 1e-14 && (c.k1 * c.k2 + 0.64).abs() < 1e-14);
    }

    #[test]
    fn tv29_duncan_bicubic_corner_formulas() {
        // K, H at (0,0) from the net alone (D L1178–L1200) equal the general formulas.
        for seed in 1..20u64 {
            let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
            let mut rnd = move || {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            let pts: Vec<DVec3> = (0..16)
                .map(|k| {
                    DVec3::new(
                        (k / 4) as f64 + 0.4 * rnd(),
                        (k % 4) as f64 + 0.4 * rnd(),
                        rnd(),
                    )
                })
                .collect();
            let b = BezierPatch::new(3, 3, pts).unwrap();
            let d = |i, j| b.point(i, j);
            let (a, bb) = (d(1, 0) - d(0, 0), d(0, 1) - d(0, 0));
            let nh = a.cross(bb).normalize();
            let n1 = (d(0, 0) - 2.0 * d(1, 0) + d(2, 0)).dot(nh);
            let n2 = (d(0, 0) - 2.0 * d(0, 1) + d(0, 2)).dot(nh);
            let n3 = (d(0, 0) - d(0, 1) + d(1, 1) - d(1, 0)).dot(nh);
            let n4 = a.length_squared() * bb.length_squared() - a.dot(bb).powi(2);
            let k = (4.0 * n1 * n2 - 9.0 * n3 * n3) / (9.0 * n4);
            let h = (n2 * a.length_squared() + n1 * bb.length_squared() - 3.0 * n3 * a.dot(bb))
                / (3.0 * n4);
            let c = curvature(&b, 0.0, 0.0).unwrap();
            assert!(
                (c.gaussian - k).abs() < 1e-12 * (1.0 + k.abs()),
                "seed {seed}"
            );
            assert!((c.mean - h).abs() < 1e-12 * (1.0 + h.abs()), "seed {seed}");
        }
    }

    #[test]
    fn tv27_stereographic_sphere() {
        // (2u, 2v, u² + v² − 1)/(u² + v² + 1): E = G = L = N = 4/(1+u²+v²)², F = M = 0 (up to
        // the sign of the normal); every normal curvature is 1.
        let st = Analytic {
            dom: Domain2 {
                u: (-2.0, 2.0),
                v: (-2.0, 2.0),
            },
            f: |u: f64, v: f64| {
                // Derivatives by automatic-free closed forms of x/w with w = 1 + u² + v².
                let w = 1.0 + u * u + v * v;
                let num = DVec3::new(2.0 * u, 2.0 * v, u * u + v * v - 1.0);
                let (nu, nv) = (DVec3::new(2.0, 0.0, 2.0 * u), DVec3::new(0.0, 2.0, 2.0 * v));
                let (nuu, nvv) = (DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.0, 0.0, 2.0));
                let (wu, wv) = (2.0 * u, 2.0 * v);
                let p = num / w;
                let su = (nu - p * wu) / w;
                let sv = (nv - p * wv) / w;
                SurfaceDerivs {
                    p,
                    su,
                    sv,
                    suu: (nuu - su * (2.0 * wu) - p * 2.0) / w,
                    suv: (-(sv * wu) - su * wv) / w,
                    svv: (nvv - sv * (2.0 * wv) - p * 2.0) / w,
                }
            },
        };
        for &(u, v) in &[(0.0, 0.0), (0.3, -0.7), (1.5, 0.2)] {
            let ff = fundamental_forms(&st, u, v).unwrap();
            let e = 4.0 / (1.0f64 + u * u + v * v).powi(2);
            assert!((ff.e - e).abs() < 1e-14 && (ff.g - e).abs() < 1e-14 && ff.f.abs() < 1e-14);
            assert!(
                (ff.l.abs() - e).abs() < 1e-14
                    && (ff.n.abs() - e).abs() < 1e-14
                    && ff.m.abs() < 1e-14
            );
            let c = curvature(&st, u, v).unwrap();
            assert!((c.gaussian - 1.0).abs() < 1e-13 && (c.mean.abs() - 1.0).abs() < 1e-13);
            let kn = ff.normal_curvature(DVec2::new(0.3, 0.9)).unwrap();
            assert!((kn.abs() - 1.0).abs() < 1e-13);
        }
    }

    #[test]
    fn principal_directions_diagonalize_the_second_form() {
        let pts: Vec<DVec3> = (0..16)
            .map(|k| {
                DVec3::new(
                    (k / 4) as f64,
                    (k % 4) as f64 + 0.2 * (k / 4) as f64,
                    ((k * 5) % 7) as f64 * 0.3,
                )
            })
            .collect();
        let b = BezierPatch::new(3, 3, pts).unwrap();
        for &(u, v) in &[(0.2, 0.3), (0.6, 0.8), (0.45, 0.1)] {
            let c = curvature(&b, u, v).unwrap();
            let ff = fundamental_forms(&b, u, v).unwrap();
            assert!((c.k1 * c.k2 - c.gaussian).abs() < 1e-12 * (1.0 + c.gaussian.abs()));
            assert!((0.5 * (c.k1 + c.k2) - c.mean).abs() < 1e-12 * (1.0 + c.mean.abs()));
            assert!((ff.normal_curvature(c.dir1_uv).unwrap() - c.k1).abs() < 1e-11);
            assert!((ff.normal_curvature(c.dir2_uv).unwrap() - c.k2).abs() < 1e-11);
            assert!(c.dir1.dot(c.dir2).abs() < 1e-12 && c.dir1.dot(ff.normal).abs() < 1e-12);
            let (_, su, sv) = b.deriv1(u, v);
            assert!((su * c.dir1_uv.x + sv * c.dir1_uv.y - c.dir1).length() < 1e-12);
        }
    }

    #[test]
    fn christoffel_matches_metric_inverse_form() {
        // Γ^k_ij = g^{kl} (r_ij · r_l): an independent derivation to check E1/E2 on a general patch.
        let pts: Vec<DVec3> = (0..16)
            .map(|k| {
                DVec3::new(
                    (k / 4) as f64,
                    (k % 4) as f64 + 0.3 * (k / 4) as f64,
                    ((k * 5) % 7) as f64 * 0.2,
                )
            })
            .collect();
        let b = BezierPatch::new(3, 3, pts).unwrap();
        for &(u, v) in &[(0.2, 0.3), (0.6, 0.8)] {
            let d = b.deriv2(u, v);
            let c = christoffel(&b, u, v).unwrap();
            let g = glam::DMat2::from_cols(
                DVec2::new(d.su.dot(d.su), d.su.dot(d.sv)),
                DVec2::new(d.su.dot(d.sv), d.sv.dot(d.sv)),
            );
            let gi = g.inverse();
            let rij = [[d.suu, d.suv], [d.suv, d.svv]];
            for i in 0..2 {
                for j in 0..2 {
                    let x = gi * DVec2::new(rij[i][j].dot(d.su), rij[i][j].dot(d.sv));
                    assert!((c.gamma[0][i][j] - x.x).abs() < 1e-12 * (1.0 + x.x.abs()));
                    assert!((c.gamma[1][i][j] - x.y).abs() < 1e-12 * (1.0 + x.y.abs()));
                }
            }
        }
        // Sphere (TV40 setting): Γ¹₂₂ = −sin u cos u, Γ²₁₂ = cot u.
        let s = sphere(1.0);
        let c = christoffel(&s, 1.0, 0.2).unwrap();
        assert!((c.gamma[0][1][1] + 1f64.sin() * 1f64.cos()).abs() < 1e-14);
        assert!((c.gamma[1][0][1] - 1.0 / 1f64.tan()).abs() < 1e-14);
        assert!(c.gamma[0][0][0].abs() < 1e-14 && c.gamma[1][0][0].abs() < 1e-14);
    }

    #[test]
    fn tv40_sphere_geodesic() {
        let s = sphere(1.0);
        // Start on the equator heading 45° north-east: du = −1/√2 (north), dv = +1/√2.
        let g = geodesic(
            &s,
            DVec2::new(FRAC_PI_2, 0.0),
            DVec2::new(-1.0, 1.0),
            FRAC_PI_2,
            GeodesicOptions::DEFAULT,
        )
        .unwrap();
        let end = *g.points.last().unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((end - DVec3::new(0.0, h, h)).length() < 1e-10, "{end}");
        assert!((g.arclen.last().unwrap() - FRAC_PI_2).abs() < 1e-15);
        for p in &g.points {
            assert!((p.y - p.z).abs() < 1e-10, "off the great circle: {p}");
        }
        assert!(!g.hit_boundary);
        // Arc length of the polyline is close to the requested length (chords are shorter).
        let poly: f64 = g.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        assert!((poly - FRAC_PI_2).abs() < 1e-3);
    }

    #[test]
    fn geodesic_on_a_cylinder_is_a_helix_and_stops_at_the_boundary() {
        let c = BSplinePatch::cylinder(DVec3::ZERO, 2.0, 5.0).unwrap();
        let g = geodesic(
            &c,
            DVec2::new(0.0, 0.05),
            DVec2::new(1.0, 1.0),
            100.0,
            GeodesicOptions::DEFAULT,
        )
        .unwrap();
        assert!(g.hit_boundary);
        // Unrolled, a geodesic is straight: the angle between successive 3D steps and the axis is constant.
        let first = g.points[1] - g.points[0];
        let ratio = first.z / first.length();
        for w in g.points.windows(2).skip(1) {
            let d = w[1] - w[0];
            assert!((d.z / d.length() - ratio).abs() < 1e-4);
        }
        assert!(
            geodesic(
                &c,
                DVec2::new(2.0, 0.5),
                DVec2::X,
                1.0,
                GeodesicOptions::DEFAULT
            )
            .is_err()
        );
        assert!(
            geodesic(
                &c,
                DVec2::new(0.5, 0.5),
                DVec2::ZERO,
                1.0,
                GeodesicOptions::DEFAULT
            )
            .is_err()
        );
    }

    #[test]
    fn tv30_rail_test_and_curvature_developability() {
        let frustum = Analytic {
            dom: Domain2 {
                u: (0.0, 6.0),
                v: (0.0, 1.0),
            },
            f: |u: f64, v: f64| {
                let (c, s) = (u.cos(), u.sin());
                SurfaceDerivs {
                    p: DVec3::new((1.0 + v) * c, (1.0 + v) * s, v),
                    su: DVec3::new(-(1.0 + v) * s, (1.0 + v) * c, 0.0),
                    sv: DVec3::new(c, s, 1.0),
                    suu: DVec3::new(-(1.0 + v) * c, -(1.0 + v) * s, 0.0),
                    suv: DVec3::new(-s, c, 0.0),
                    svv: DVec3::ZERO,
                }
            },
        };
        assert!(ruled_developability(&frustum, 50).0 < 1e-14);
        assert!(developability(&frustum, 12).max_scaled_k < 1e-12);
        let hyper = Analytic {
            dom: Domain2 {
                u: (0.0, 6.0),
                v: (0.0, 1.0),
            },
            f: |u: f64, v: f64| {
                let (a, b) = (
                    DVec3::new(u.cos(), u.sin(), 0.0),
                    DVec3::new((u + 0.5).cos(), (u + 0.5).sin(), 1.0),
                );
                let (da, db) = (
                    DVec3::new(-u.sin(), u.cos(), 0.0),
                    DVec3::new(-(u + 0.5).sin(), (u + 0.5).cos(), 0.0),
                );
                SurfaceDerivs {
                    p: a.lerp(b, v),
                    su: da.lerp(db, v),
                    sv: b - a,
                    suu: -(a.lerp(b, v) - DVec3::new(0.0, 0.0, v)),
                    suv: db - da,
                    svv: DVec3::ZERO,
                }
            },
        };
        for &u in &[0.0, 1.3, 4.0] {
            assert!((ruled_triple(&hyper, u) - 0.4794255386).abs() < 1e-10);
        }
        let rep = developability(&hyper, 12);
        assert!(rep.max_scaled_k > 0.1, "{rep:?}");
        let sph = BSplinePatch::sphere(DVec3::ZERO, 5.0).unwrap();
        let rep = developability(&sph, 10);
        // |K| = 1/25, diagonal of the sample box < 10√3 ⇒ scaled value about 4–12.
        assert!(rep.max_scaled_k > 3.0 && rep.max_scaled_k < 12.0, "{rep:?}");
    }
}
