//! Surfaces interpolating boundary curves: Coons patches (bilinearly and bicubically blended,
//! Salomon §3.7, Hartmann §10.4), Gordon surfaces over curve networks (Salomon §3.8) and ruled
//! surfaces between two curves (Salomon §2.4, Hartmann §10.2).
//!
//! Curves are taken as `Arc<dyn ParamCurve>`; each curve's own parameter interval is mapped
//! linearly onto `[0, 1]`, so the chain rule multiplies its k-th derivative by `(t1 − t0)^k`.

use crate::{Domain2, ParamCurve, ParamSurface, SurfaceDerivs, SurfaceError};
use glam::DVec3;
use std::sync::Arc;

/// Relative tolerance for the corner/intersection checks: points must agree within this
/// fraction of the network's size (plus an absolute floor for degenerate data), so that
/// curves sampled from the same CAD edges pass while genuinely open networks are rejected.
pub const DEFAULT_MATCH_REL: f64 = 1e-7;
/// Absolute floor (mm) of the corner match tolerance.
pub const DEFAULT_MATCH_ABS_MM: f64 = 1e-9;

/// A curve reparametrized onto `[0, 1]`.
#[derive(Clone, Debug)]
struct UnitCurve {
    c: Arc<dyn ParamCurve>,
    t0: f64,
    span: f64,
}

impl UnitCurve {
    fn new(c: Arc<dyn ParamCurve>, name: &str) -> Result<Self, SurfaceError> {
        let (t0, t1) = c.domain();
        if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
            return Err(SurfaceError::EmptyCurveDomain {
                name: name.to_string(),
                t0,
                t1,
            });
        }
        Ok(Self {
            c,
            t0,
            span: t1 - t0,
        })
    }
    /// Point, first and second derivative at `s ∈ [0, 1]`.
    fn d2(&self, s: f64) -> [DVec3; 3] {
        let t = self.t0 + s * self.span;
        [
            self.c.eval(t),
            self.c.deriv(t, 1) * self.span,
            self.c.deriv(t, 2) * (self.span * self.span),
        ]
    }
    fn at(&self, s: f64) -> DVec3 {
        self.c.eval(self.t0 + s * self.span)
    }
}

fn match_tol(pts: &[DVec3]) -> f64 {
    let bb = flatcut_geom::Aabb3::from_points(pts.iter().copied());
    DEFAULT_MATCH_ABS_MM + DEFAULT_MATCH_REL * bb.diagonal()
}

/// Blending functions with first and second derivatives: `f0(t)` (1 at 0) and `f1(t)` (1 at 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Blend {
    /// `1 − t`, `t`.
    Linear,
    /// Hermite cubics `1 − 3t² + 2t³`, `3t² − 2t³` (S (3.31)): zero slope at both ends, so
    /// cross-boundary derivatives depend only on the boundary curves.
    Cubic,
}

impl Blend {
    fn eval(self, t: f64) -> [[f64; 3]; 2] {
        match self {
            Blend::Linear => [[1.0 - t, -1.0, 0.0], [t, 1.0, 0.0]],
            Blend::Cubic => {
                let h1 = [
                    3.0 * t * t - 2.0 * t * t * t,
                    6.0 * t - 6.0 * t * t,
                    6.0 - 12.0 * t,
                ];
                [[1.0 - h1[0], -h1[1], -h1[2]], h1]
            }
        }
    }
}

/// A Coons patch on the unit square interpolating four boundary curves:
/// `P(u, 0) = c_v0(u)`, `P(u, 1) = c_v1(u)`, `P(0, v) = c_u0(v)`, `P(1, v) = c_u1(v)`.
#[derive(Clone, Debug)]
pub struct CoonsPatch {
    c_v0: UnitCurve,
    c_v1: UnitCurve,
    c_u0: UnitCurve,
    c_u1: UnitCurve,
    corners: [[DVec3; 2]; 2],
    blend: Blend,
}

impl CoonsPatch {
    /// The bilinearly blended Coons patch `P_a + P_b − P_ab` (S (3.28)–(3.29)).
    pub fn bilinear(
        c_v0: Arc<dyn ParamCurve>,
        c_v1: Arc<dyn ParamCurve>,
        c_u0: Arc<dyn ParamCurve>,
        c_u1: Arc<dyn ParamCurve>,
    ) -> Result<Self, SurfaceError> {
        Self::build(c_v0, c_v1, c_u0, c_u1, Blend::Linear)
    }

    /// The bicubically blended Coons patch (Hermite blends, S (3.31)–(3.32)).
    pub fn bicubic(
        c_v0: Arc<dyn ParamCurve>,
        c_v1: Arc<dyn ParamCurve>,
        c_u0: Arc<dyn ParamCurve>,
        c_u1: Arc<dyn ParamCurve>,
    ) -> Result<Self, SurfaceError> {
        Self::build(c_v0, c_v1, c_u0, c_u1, Blend::Cubic)
    }

    fn build(
        c_v0: Arc<dyn ParamCurve>,
        c_v1: Arc<dyn ParamCurve>,
        c_u0: Arc<dyn ParamCurve>,
        c_u1: Arc<dyn ParamCurve>,
        blend: Blend,
    ) -> Result<Self, SurfaceError> {
        let c_v0 = UnitCurve::new(c_v0, "Coons boundary v=0")?;
        let c_v1 = UnitCurve::new(c_v1, "Coons boundary v=1")?;
        let c_u0 = UnitCurve::new(c_u0, "Coons boundary u=0")?;
        let c_u1 = UnitCurve::new(c_u1, "Coons boundary u=1")?;
        // Corner (i, j) = P(i, j) as seen from the two curves through it.
        let pairs = [
            ((0, 0), c_v0.at(0.0), c_u0.at(0.0)),
            ((1, 0), c_v0.at(1.0), c_u1.at(0.0)),
            ((0, 1), c_v1.at(0.0), c_u0.at(1.0)),
            ((1, 1), c_v1.at(1.0), c_u1.at(1.0)),
        ];
        let all: Vec<DVec3> = pairs.iter().flat_map(|p| [p.1, p.2]).collect();
        if let Some(i) = all.iter().position(|p| !flatcut_geom::finite3(*p)) {
            return Err(SurfaceError::NonFinite {
                what: "Coons corner",
                index: i / 2,
            });
        }
        let tol = match_tol(&all);
        let mut corners = [[DVec3::ZERO; 2]; 2];
        for ((i, j), a, b) in pairs {
            let gap = a.distance(b);
            if gap > tol {
                return Err(SurfaceError::CoonsCorner { i, j, gap, tol });
            }
            corners[i][j] = (a + b) * 0.5;
        }
        Ok(Self {
            c_v0,
            c_v1,
            c_u0,
            c_u1,
            corners,
            blend,
        })
    }
}

impl ParamSurface for CoonsPatch {
    fn domain(&self) -> Domain2 {
        Domain2::UNIT
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.deriv2(u, v).p
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let d = self.deriv2(u, v);
        (d.p, d.su, d.sv)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        let [fu0, fu1] = self.blend.eval(u);
        let [fv0, fv1] = self.blend.eval(v);
        let a = self.c_v0.d2(u);
        let b = self.c_v1.d2(u);
        let c = self.c_u0.d2(v);
        let d = self.c_u1.d2(v);
        let k = &self.corners;
        // Ruled part in v: fv0(v) a(u) + fv1(v) b(u); its (m, n)-th partial is fv^(n) · curve^(m).
        let rv = |m: usize, n: usize| a[m] * fv0[n] + b[m] * fv1[n];
        // Ruled part in u: fu0(u) c(v) + fu1(u) d(v).
        let ru = |m: usize, n: usize| c[n] * fu0[m] + d[n] * fu1[m];
        // Tensor-product correction from the corners.
        let rc = |m: usize, n: usize| {
            (k[0][0] * fv0[n] + k[0][1] * fv1[n]) * fu0[m]
                + (k[1][0] * fv0[n] + k[1][1] * fv1[n]) * fu1[m]
        };
        let t = |m: usize, n: usize| rv(m, n) + ru(m, n) - rc(m, n);
        SurfaceDerivs {
            p: t(0, 0),
            su: t(1, 0),
            sv: t(0, 1),
            suu: t(2, 0),
            suv: t(1, 1),
            svv: t(0, 2),
        }
    }
}

/// Lagrange basis polynomials over `nodes` with first and second derivatives at `t`.
fn lagrange_d2(nodes: &[f64], t: f64) -> Vec<[f64; 3]> {
    let n = nodes.len();
    (0..n)
        .map(|i| {
            // L_i(t) = Π_{k≠i} (t − x_k)/(x_i − x_k); derivatives by the product rule over factors.
            let denom: f64 = (0..n)
                .filter(|&k| k != i)
                .map(|k| nodes[i] - nodes[k])
                .product();
            let others: Vec<f64> = (0..n).filter(|&k| k != i).map(|k| t - nodes[k]).collect();
            let m = others.len();
            let val: f64 = others.iter().product();
            let mut d1 = 0.0;
            let mut d2 = 0.0;
            for a in 0..m {
                let pa: f64 = (0..m).filter(|&k| k != a).map(|k| others[k]).product();
                d1 += pa;
                for b in 0..m {
                    if b != a {
                        let pab: f64 = (0..m)
                            .filter(|&k| k != a && k != b)
                            .map(|k| others[k])
                            .product();
                        d2 += pab;
                    }
                }
            }
            [val / denom, d1 / denom, d2 / denom]
        })
        .collect()
}

/// A Gordon surface interpolating a network of curves with Lagrange blending (S §3.8):
/// `P = Σ_i U_i(v) L_i(u) + Σ_j V_j(u) L_j(v) − Σ_ij P_ij L_i(u) L_j(v)`,
/// where `U_i` is the curve at `u = u_params[i]` (running in v) and `V_j` the curve at
/// `v = v_params[j]` (running in u). With two curves per direction it is the bilinear Coons patch.
///
/// Lagrange blending oscillates for many curves; keep networks small (the usual fix, spline
/// blending, needs curve-network compatibility beyond this construction).
#[derive(Clone, Debug)]
pub struct GordonSurface {
    u_curves: Vec<UnitCurve>,
    v_curves: Vec<UnitCurve>,
    u_params: Vec<f64>,
    v_params: Vec<f64>,
    grid: Vec<DVec3>,
}

fn check_params(p: &[f64], what: &'static str) -> Result<(), SurfaceError> {
    if p.len() < 2 {
        return Err(SurfaceError::GordonTooFew { what });
    }
    for (i, w) in p.windows(2).enumerate() {
        // `partial_cmp` rejects NaN too (it is not `Less`).
        if w[0].partial_cmp(&w[1]) != Some(std::cmp::Ordering::Less) {
            return Err(SurfaceError::GordonOrder { what, index: i + 1 });
        }
    }
    if !(p[0] >= 0.0 && p[p.len() - 1] <= 1.0) {
        return Err(SurfaceError::GordonRange { what });
    }
    Ok(())
}

impl GordonSurface {
    /// Builds the surface; `u_curves[i]` lies at `u = u_params[i]`, `v_curves[j]` at
    /// `v = v_params[j]`, and the curves must meet at every grid point `(u_i, v_j)`.
    pub fn new(
        u_curves: Vec<Arc<dyn ParamCurve>>,
        v_curves: Vec<Arc<dyn ParamCurve>>,
        u_params: Vec<f64>,
        v_params: Vec<f64>,
    ) -> Result<Self, SurfaceError> {
        check_params(&u_params, "u parameters")?;
        check_params(&v_params, "v parameters")?;
        if u_curves.len() != u_params.len() || v_curves.len() != v_params.len() {
            return Err(SurfaceError::GordonCount {
                u_curves: u_curves.len(),
                u_params: u_params.len(),
                v_curves: v_curves.len(),
                v_params: v_params.len(),
            });
        }
        let u_curves = u_curves
            .into_iter()
            .enumerate()
            .map(|(i, c)| UnitCurve::new(c, &format!("Gordon u-curve {i}")))
            .collect::<Result<Vec<_>, _>>()?;
        let v_curves = v_curves
            .into_iter()
            .enumerate()
            .map(|(j, c)| UnitCurve::new(c, &format!("Gordon v-curve {j}")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut a = Vec::new();
        let mut b = Vec::new();
        for (i, cu) in u_curves.iter().enumerate() {
            for (j, cv) in v_curves.iter().enumerate() {
                a.push(cu.at(v_params[j]));
                b.push(cv.at(u_params[i]));
            }
        }
        let all: Vec<DVec3> = a.iter().chain(&b).copied().collect();
        if let Some(k) = all.iter().position(|p| !flatcut_geom::finite3(*p)) {
            return Err(SurfaceError::NonFinite {
                what: "Gordon grid point",
                index: k % a.len(),
            });
        }
        let tol = match_tol(&all);
        let nv = v_curves.len();
        let mut grid = Vec::with_capacity(a.len());
        for (k, (p, q)) in a.iter().zip(&b).enumerate() {
            let gap = p.distance(*q);
            if gap > tol {
                return Err(SurfaceError::GordonMiss {
                    u: k / nv,
                    v: k % nv,
                    gap,
                });
            }
            grid.push((*p + *q) * 0.5);
        }
        Ok(Self {
            u_curves,
            v_curves,
            u_params,
            v_params,
            grid,
        })
    }
}

impl ParamSurface for GordonSurface {
    fn domain(&self) -> Domain2 {
        Domain2::UNIT
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.deriv2(u, v).p
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let d = self.deriv2(u, v);
        (d.p, d.su, d.sv)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        let lu = lagrange_d2(&self.u_params, u);
        let lv = lagrange_d2(&self.v_params, v);
        let mut out = [DVec3::ZERO; 6];
        const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)];
        for (i, c) in self.u_curves.iter().enumerate() {
            let d = c.d2(v);
            for (o, &(m, n)) in out.iter_mut().zip(&PAIRS) {
                *o += d[n] * lu[i][m];
            }
        }
        for (j, c) in self.v_curves.iter().enumerate() {
            let d = c.d2(u);
            for (o, &(m, n)) in out.iter_mut().zip(&PAIRS) {
                *o += d[m] * lv[j][n];
            }
        }
        let nv = self.v_params.len();
        for i in 0..self.u_params.len() {
            for j in 0..nv {
                let p = self.grid[i * nv + j];
                for (o, &(m, n)) in out.iter_mut().zip(&PAIRS) {
                    *o -= p * (lu[i][m] * lv[j][n]);
                }
            }
        }
        let [p, su, sv, suu, suv, svv] = out;
        SurfaceDerivs {
            p,
            su,
            sv,
            suu,
            suv,
            svv,
        }
    }
}

/// The ruled surface `P(u, v) = (1 − v) c0(u) + v c1(u)` between two curves (both mapped to
/// `u ∈ [0, 1]`).
#[derive(Clone, Debug)]
pub struct RuledSurface {
    c0: UnitCurve,
    c1: UnitCurve,
}

impl RuledSurface {
    /// Builds the ruled surface joining equal parameters of `c0` and `c1`.
    pub fn new(c0: Arc<dyn ParamCurve>, c1: Arc<dyn ParamCurve>) -> Result<Self, SurfaceError> {
        Ok(Self {
            c0: UnitCurve::new(c0, "ruled surface rail 0")?,
            c1: UnitCurve::new(c1, "ruled surface rail 1")?,
        })
    }
}

impl ParamSurface for RuledSurface {
    fn domain(&self) -> Domain2 {
        Domain2::UNIT
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.c0.at(u).lerp(self.c1.at(u), v)
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let d = self.deriv2(u, v);
        (d.p, d.su, d.sv)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        let a = self.c0.d2(u);
        let b = self.c1.d2(u);
        SurfaceDerivs {
            p: a[0].lerp(b[0], v),
            su: a[1].lerp(b[1], v),
            sv: b[0] - a[0],
            suu: a[2].lerp(b[2], v),
            suv: b[1] - a[1],
            svv: DVec3::ZERO,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::patch::testutil::check_derivs_fd;
    use std::f64::consts::PI;

    /// A closure-defined analytic curve for tests (derivatives by the closure).
    pub(crate) struct FnCurve {
        pub(crate) dom: (f64, f64),
        pub(crate) f: Box<dyn Fn(f64, usize) -> DVec3 + Send + Sync>,
    }
    impl std::fmt::Debug for FnCurve {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "FnCurve{:?}", self.dom)
        }
    }
    impl ParamCurve for FnCurve {
        fn domain(&self) -> (f64, f64) {
            self.dom
        }
        fn eval(&self, t: f64) -> DVec3 {
            (self.f)(t, 0)
        }
        fn deriv(&self, t: f64, k: usize) -> DVec3 {
            (self.f)(t, k)
        }
    }
    pub(crate) fn curve(
        dom: (f64, f64),
        f: impl Fn(f64, usize) -> DVec3 + Send + Sync + 'static,
    ) -> Arc<dyn ParamCurve> {
        Arc::new(FnCurve {
            dom,
            f: Box::new(f),
        })
    }

    /// d^k/dt^k sin(π t).
    fn dsin(t: f64, k: usize) -> f64 {
        let w = PI.powi(k as i32);
        match k % 4 {
            0 => w * (PI * t).sin(),
            1 => w * (PI * t).cos(),
            2 => -w * (PI * t).sin(),
            _ => -w * (PI * t).cos(),
        }
    }

    /// TV23 boundaries: (u,0,sin πu), (u,1,sin πu), (0,w,sin πw), (1,w,sin πw).
    fn tv23() -> [Arc<dyn ParamCurve>; 4] {
        let lin = |k: usize, t: f64| {
            if k == 0 {
                t
            } else if k == 1 {
                1.0
            } else {
                0.0
            }
        };
        let cst = |k: usize, c: f64| if k == 0 { c } else { 0.0 };
        [
            curve((0.0, 1.0), move |t, k| {
                DVec3::new(lin(k, t), cst(k, 0.0), dsin(t, k))
            }),
            curve((0.0, 1.0), move |t, k| {
                DVec3::new(lin(k, t), cst(k, 1.0), dsin(t, k))
            }),
            curve((0.0, 1.0), move |t, k| {
                DVec3::new(cst(k, 0.0), lin(k, t), dsin(t, k))
            }),
            curve((0.0, 1.0), move |t, k| {
                DVec3::new(cst(k, 1.0), lin(k, t), dsin(t, k))
            }),
        ]
    }

    #[test]
    fn tv23_coons_bilinear_and_bicubic() {
        let [a, b, c, d] = tv23();
        let lin = CoonsPatch::bilinear(a.clone(), b.clone(), c.clone(), d.clone()).unwrap();
        let cub = CoonsPatch::bicubic(a, b, c, d).unwrap();
        for p in [&lin, &cub] {
            for &(u, w) in &[(0.5, 0.5), (0.2, 0.9), (0.0, 0.3), (0.7, 1.0)] {
                let exact = DVec3::new(u, w, (PI * u).sin() + (PI * w).sin());
                assert!((p.eval(u, w) - exact).length() < 1e-14, "({u},{w})");
            }
            assert!((p.eval(0.5, 0.5) - DVec3::new(0.5, 0.5, 2.0)).length() < 1e-14);
            check_derivs_fd(p, 1e-6);
        }
    }

    #[test]
    fn bicubic_coons_reproduces_boundaries_of_a_general_patch() {
        // Boundaries of a curved patch whose interior a Coons patch does not reproduce.
        let f = |u: f64, v: f64| DVec3::new(u + 0.2 * v * v, v, (u * v).sin() + u * u * v);
        let c_v0 = curve((0.0, 2.0), move |t, k| match k {
            0 => f(t / 2.0, 0.0),
            _ => {
                let h = 1e-4;
                (f((t + h) / 2.0, 0.0) - f((t - h) / 2.0, 0.0)) / (2.0 * h)
            }
        });
        // Derivatives are irrelevant to the boundary check; use eval only.
        let c_v1 = curve((0.0, 1.0), move |t, _| f(t, 1.0));
        let c_u0 = curve((0.0, 1.0), move |t, _| f(0.0, t));
        let c_u1 = curve((0.0, 1.0), move |t, _| f(1.0, t));
        let p = CoonsPatch::bicubic(c_v0, c_v1, c_u0, c_u1).unwrap();
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            assert!((p.eval(t, 0.0) - f(t, 0.0)).length() < 1e-14);
            assert!((p.eval(t, 1.0) - f(t, 1.0)).length() < 1e-14);
            assert!((p.eval(0.0, t) - f(0.0, t)).length() < 1e-14);
            assert!((p.eval(1.0, t) - f(1.0, t)).length() < 1e-14);
        }
    }

    #[test]
    fn coons_rejects_open_corners() {
        let [a, b, c, _] = tv23();
        let bad = curve((0.0, 1.0), |t, _| DVec3::new(1.0, t, 0.1 + (PI * t).sin()));
        let e = CoonsPatch::bilinear(a, b, c, bad).unwrap_err();
        assert!(e.to_string().contains("corner (1,0)"), "{e}");
    }

    #[test]
    fn gordon_reduces_to_coons_and_interpolates_the_network() {
        let [a, b, c, d] = tv23();
        let g = GordonSurface::new(
            vec![c.clone(), d.clone()],
            vec![a.clone(), b.clone()],
            vec![0.0, 1.0],
            vec![0.0, 1.0],
        )
        .unwrap();
        let coons = CoonsPatch::bilinear(a, b, c, d).unwrap();
        for &(u, v) in &[(0.3, 0.4), (0.9, 0.1)] {
            assert!((g.eval(u, v) - coons.eval(u, v)).length() < 1e-14);
        }
        check_derivs_fd(&g, 1e-6);
        // A 3×3 network cut from z = sin(πu)·cos(πv)/2 + u v: Gordon interpolates every curve.
        let f = |u: f64, v: f64| DVec3::new(u, v, 0.5 * (PI * u).sin() * (PI * v).cos() + u * v);
        let ps = [0.0, 0.4, 1.0];
        let ucs: Vec<Arc<dyn ParamCurve>> = ps
            .iter()
            .map(|&u| curve((0.0, 1.0), move |t, k| fd_curve(move |s| f(u, s), t, k)))
            .collect();
        let vcs: Vec<Arc<dyn ParamCurve>> = ps
            .iter()
            .map(|&v| curve((0.0, 1.0), move |t, k| fd_curve(move |s| f(s, v), t, k)))
            .collect();
        let g = GordonSurface::new(ucs, vcs, ps.to_vec(), ps.to_vec()).unwrap();
        for &p in &ps {
            for k in 0..=8 {
                let t = k as f64 / 8.0;
                assert!((g.eval(p, t) - f(p, t)).length() < 1e-13);
                assert!((g.eval(t, p) - f(t, p)).length() < 1e-13);
            }
        }
    }

    /// Derivatives of a closure curve by high-order central differences (test helper only).
    fn fd_curve(f: impl Fn(f64) -> DVec3, t: f64, k: usize) -> DVec3 {
        let h = 1e-3;
        match k {
            0 => f(t),
            1 => (f(t - 2.0 * h) - f(t + 2.0 * h) + (f(t + h) - f(t - h)) * 8.0) / (12.0 * h),
            _ => (f(t + h) - f(t) * 2.0 + f(t - h)) / (h * h),
        }
    }

    #[test]
    fn tv22_lofted_surface() {
        // P(u,0) = (2u−1, −2u(1−u), 0), P(u,1) = (2u−1, 4u(u−1), 1) → normal (2(2u−1)(1+w), −2, 4u(u−1)).
        let c0 = curve((0.0, 1.0), |u, k| match k {
            0 => DVec3::new(2.0 * u - 1.0, -2.0 * u * (1.0 - u), 0.0),
            1 => DVec3::new(2.0, -2.0 + 4.0 * u, 0.0),
            2 => DVec3::new(0.0, 4.0, 0.0),
            _ => DVec3::ZERO,
        });
        let c1 = curve((0.0, 1.0), |u, k| match k {
            0 => DVec3::new(2.0 * u - 1.0, 4.0 * u * (u - 1.0), 1.0),
            1 => DVec3::new(2.0, 8.0 * u - 4.0, 0.0),
            2 => DVec3::new(0.0, 8.0, 0.0),
            _ => DVec3::ZERO,
        });
        let s = RuledSurface::new(c0, c1).unwrap();
        for &(u, w) in &[(0.0, 0.0), (0.5, 0.0), (1.0, 1.0), (0.3, 0.6)] {
            let (p, su, sv) = s.deriv1(u, w);
            assert!(
                (p - DVec3::new(2.0 * u - 1.0, 2.0 * u * (u - 1.0) * (1.0 + w), w)).length()
                    < 1e-14
            );
            let n = su.cross(sv);
            let e = DVec3::new(2.0 * (2.0 * u - 1.0) * (1.0 + w), -2.0, 4.0 * u * (u - 1.0));
            assert!((n - e).length() < 1e-13, "{n} vs {e}");
        }
        assert!(
            (s.deriv1(1.0, 1.0).1.cross(s.deriv1(1.0, 1.0).2) - DVec3::new(4.0, -2.0, 0.0))
                .length()
                < 1e-13
        );
        check_derivs_fd(&s, 1e-6);
    }
}
