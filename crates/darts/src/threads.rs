//! Limits per thread direction, for a woven or knitted material (or a leather with a stretchier
//! direction): the warp, the weft and the two 45° bias threads each have their own stretch and
//! compression limits, held in the solve instead of the tightest of them on the principal
//! stretches.
//!
//! The threads are straight in the cut piece: the warp runs along the pattern's grain `u` (a unit
//! vector of the plane the darts are solved in), the weft along `u⊥`, the bias along
//! `(u ± u⊥)/√2`. A thread along the 2D direction `d` lies on the surface along `F⁻¹d` (F: the
//! triangle's map, rest frame → plane), so its stretch factor is `s_d = 1/|F⁻¹d|`, the
//! definition the report checks ([`flatcut_mesh::grain_strain`]). In logs,
//!
//! ℓ_d = ln s_d = ln det F − ½ ln |adj(F) d|²,
//!
//! a log-determinant minus the log of a quadratic form in F's entries: its derivatives are
//! closed-form (the module's tests check them by finite differences). Unlike the principal
//! stretches, the thread stretches depend on how the map is turned in the plane, so a solve with
//! these limits keeps the grain where it was put.
//!
//! The energies are those of [`crate::limits`] with the excess of each thread instead of each
//! principal stretch: the p-norm continuation Σ e^{p(ℓ_d − ln S_d)} + e^{p(ln C_d − ℓ_d)} and the
//! log barrier −ln(w + ln S_d − ℓ_d) − ln(w − ln C_d + ℓ_d), each plus reg·δ2 (symmetric
//! Dirichlet) that keeps faces far from the limits well-conditioned.

use flatcut_flatten::nonlinear::kernel::{
    IsoEnergy, Projection, RestTri, SymDirichlet, TriEnergy, TriEval, add_jacobian_terms,
    tri_eval_projected,
};
use flatcut_flatten::nonlinear::newton::DirectionTerm;
use flatcut_geom::{DMat2, DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_mesh::distortion::local_frame;
use flatcut_mesh::grain_strain::DirectionalLimits;
use nalgebra::{Matrix4, Vector4};

use crate::band::Band;

/// Faces within this distance (mm) of a grain line's middle hold its direction.
pub const ANCHOR_RADIUS_MM: f64 = 10.0;
/// Stiffness of the grain line's hold per mm² of face: k·|F a|² sin²θ for a warp turned by θ
/// from the line, 0.3 per mm² at 1°. On a woven 100° cap the warp then runs within 0.6° of a
/// design's grain line around it (at a tenth of it, within 2.6°), with the same darts.
const ANCHOR_STIFFNESS: f64 = 1000.0;

/// Stretch and compression limits of the four threads, as log stretch factors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Threads {
    /// Warp, weft and the two bias directions in the plane (unit vectors).
    pub dirs: [DVec2; 4],
    /// ln S per thread (+∞: not limited).
    pub ln_s: [f64; 4],
    /// ln C per thread (−∞: not limited).
    pub ln_c: [f64; 4],
    /// Where the design fixes the grain on the surface: the warp must run along `dir` at `at`
    /// (a grain line's middle and direction, 3D). `None`: the grain goes where the solve puts it.
    pub anchor: Option<GrainAnchor>,
}

/// A grain line on the surface: the warp runs along `dir` at `at`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrainAnchor {
    /// A point of the grain line on the surface (3D, mm).
    pub at: DVec3,
    /// The warp's direction there (3D, unit).
    pub dir: DVec3,
}

impl Threads {
    /// The limits of a material (percent along, across and on the bias) with the warp along the
    /// unit pattern direction `u`.
    pub fn new(limits: &DirectionalLimits, u: DVec2) -> Self {
        let u = u.normalize();
        let w = u.perp();
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let (s, c) = (limits.stretch_pct, limits.compress_pct);
        let ln_s = |p: f64| (1.0 + p / 100.0).ln();
        let ln_c = |p: f64| (1.0 - p / 100.0).ln();
        Self {
            dirs: [u, w, (u + w) * r, (u - w) * r],
            ln_s: [ln_s(s.along), ln_s(s.across), ln_s(s.bias), ln_s(s.bias)],
            ln_c: [ln_c(c.along), ln_c(c.across), ln_c(c.bias), ln_c(c.bias)],
            anchor: None,
        }
    }

    /// The same limits with the warp held along the grain line `dir` at `at` on the surface.
    pub fn with_anchor(mut self, at: DVec3, dir: DVec3) -> Self {
        self.anchor = Some(GrainAnchor { at, dir });
        self
    }

    /// The terms that hold the anchor on `mesh` (with rest frames `rest`, one per face): on
    /// each face within [`ANCHOR_RADIUS_MM`] of the grain line's middle (the nearest face when
    /// none is), the image F a of the grain's direction a in the face is turned towards the
    /// warp, weighted by the face's area. Empty without an anchor.
    pub fn anchor_terms(&self, mesh: &TriMesh, rest: &[RestTri]) -> Vec<DirectionTerm> {
        let Some(an) = self.anchor else {
            return Vec::new();
        };
        let centroid = |t: usize| {
            let c = mesh.corners(t);
            (c[0] + c[1] + c[2]) / 3.0
        };
        let mut near: Vec<usize> = (0..mesh.triangles.len())
            .filter(|&t| centroid(t).distance(an.at) <= ANCHOR_RADIUS_MM)
            .collect();
        if near.is_empty() {
            near.extend((0..mesh.triangles.len()).min_by(|&a, &b| {
                centroid(a)
                    .distance_squared(an.at)
                    .total_cmp(&centroid(b).distance_squared(an.at))
            }));
        }
        near.into_iter()
            .filter_map(|t| {
                let c = mesh.corners(t);
                let (_, ex, ey) = local_frame(c[0], c[1], c[2])?;
                let a = DVec2::new(an.dir.dot(ex), an.dir.dot(ey)).try_normalize()?;
                let g = rest[t].g();
                Some(DirectionTerm {
                    verts: rest[t].v,
                    coef: g.map(|gi| gi.dot(a)),
                    t: self.grain(),
                    k: ANCHOR_STIFFNESS * rest[t].area,
                })
            })
            .collect()
    }

    /// The warp's direction in the plane.
    pub fn grain(&self) -> DVec2 {
        self.dirs[0]
    }

    /// The tightest principal-stretch band of the threads' limits (a band that, held on the
    /// principal stretches, holds every thread's limits).
    pub fn tightest(&self) -> Band {
        Band {
            ln_s: self.ln_s.iter().copied().fold(f64::INFINITY, f64::min),
            ln_c: self.ln_c.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// The band of the loosest limits on either side: the most any thread may stretch, and
    /// compress.
    pub fn loosest(&self) -> Band {
        Band {
            ln_s: self.ln_s.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ln_c: self.ln_c.iter().copied().fold(f64::INFINITY, f64::min),
        }
    }

    /// The largest excess over a thread's limit (log strain; negative inside them) of the map
    /// `f`; +∞ for a degenerate or inverted map.
    pub fn excess(&self, f: DMat2) -> f64 {
        let det = f.determinant();
        if det.is_nan() || det <= 0.0 {
            return f64::INFINITY;
        }
        let mut e = f64::NEG_INFINITY;
        for k in 0..4 {
            let l = log_stretch(f, det, self.dirs[k]);
            e = e.max(l - self.ln_s[k]).max(self.ln_c[k] - l);
        }
        if e.is_nan() { f64::INFINITY } else { e }
    }
}

/// ln s_d = ln det F − ½ ln |adj(F) d|² for a map with determinant `det` > 0.
fn log_stretch(f: DMat2, det: f64, d: DVec2) -> f64 {
    det.ln() - 0.5 * adj_times(f, d).length_squared().ln()
}

/// adj(F)·d, adj(F) = [[F₂₂, −F₁₂], [−F₂₁, F₁₁]].
fn adj_times(f: DMat2, d: DVec2) -> DVec2 {
    let (f11, f21, f12, f22) = (f.x_axis.x, f.x_axis.y, f.y_axis.x, f.y_axis.y);
    DVec2::new(f22 * d.x - f12 * d.y, -f21 * d.x + f11 * d.y)
}

/// F's entries column by column, (F₁₁, F₂₁, F₁₂, F₂₂): the order of
/// [`add_jacobian_terms`]' Hessian.
fn entries(f: DMat2) -> Vector4<f64> {
    Vector4::new(f.x_axis.x, f.x_axis.y, f.y_axis.x, f.y_axis.y)
}

/// ℓ_d, its gradient and its Hessian in F's entries.
fn log_stretch_derivs(f: DMat2, d: DVec2) -> (f64, Vector4<f64>, Matrix4<f64>) {
    let v = entries(f);
    let det = f.determinant();
    // ∇ det and the (constant) Hessian of det = F₁₁F₂₂ − F₁₂F₂₁.
    let gdet = Vector4::new(v[3], -v[2], -v[1], v[0]);
    let mut hdet = Matrix4::zeros();
    hdet[(0, 3)] = 1.0;
    hdet[(3, 0)] = 1.0;
    hdet[(1, 2)] = -1.0;
    hdet[(2, 1)] = -1.0;
    // adj(F)·d = A f: its rows in F's entries.
    let a0 = Vector4::new(0.0, 0.0, -d.y, d.x);
    let a1 = Vector4::new(d.y, -d.x, 0.0, 0.0);
    let m = a0 * a0.transpose() + a1 * a1.transpose();
    let mv = m * v;
    let q = v.dot(&mv);
    let l = det.ln() - 0.5 * q.ln();
    let grad = gdet / det - mv / q;
    let hess = hdet / det - gdet * gdet.transpose() / (det * det) - m / q
        + 2.0 * mv * mv.transpose() / (q * q);
    (l, grad, hess)
}

/// δ2 (symmetric Dirichlet) times a weight: the regulariser of the thread energies.
#[derive(Clone, Copy, Debug)]
struct Weighted(f64);

impl IsoEnergy for Weighted {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        self.0 * SymDirichlet.psi(s1, s2)
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        SymDirichlet.grad(s1, s2).map(|g| self.0 * g)
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        SymDirichlet.hess(s1, s2).map(|r| r.map(|h| self.0 * h))
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// A function of one thread's log stretch ℓ and its limits: value, first and second derivative.
trait ThreadTerm {
    fn term(&self, l: f64, ln_s: f64, ln_c: f64) -> (f64, f64, f64);
}

/// reg·δ2 + Σ over the threads of `T::term(ℓ_d)`.
fn thread_energy<T: ThreadTerm>(
    t: &T,
    threads: &Threads,
    reg: f64,
    r: &RestTri,
    x: &[DVec2],
) -> f64 {
    let f = r.jacobian(x);
    let det = f.determinant();
    if det.is_nan() || det <= 0.0 {
        return f64::INFINITY;
    }
    let mut psi = 0.0;
    for k in 0..4 {
        let l = log_stretch(f, det, threads.dirs[k]);
        psi += t.term(l, threads.ln_s[k], threads.ln_c[k]).0;
    }
    if !psi.is_finite() {
        return f64::INFINITY;
    }
    Weighted(reg).tri_energy(r, x) + r.area * psi
}

/// [`thread_energy`] with its gradient and Hessian (projected by `proj`).
fn thread_eval<T: ThreadTerm>(
    t: &T,
    threads: &Threads,
    reg: f64,
    r: &RestTri,
    x: &[DVec2],
    proj: Option<Projection>,
) -> TriEval {
    let mut out = tri_eval_projected(&Weighted(reg), r, x, proj);
    let f = r.jacobian(x);
    let det = f.determinant();
    if det.is_nan() || det <= 0.0 {
        out.energy = f64::INFINITY;
        return out;
    }
    let (mut psi, mut grad, mut hess) = (0.0, Vector4::zeros(), Matrix4::zeros());
    for k in 0..4 {
        let (l, gl, hl) = log_stretch_derivs(f, threads.dirs[k]);
        let (v, d1, d2) = t.term(l, threads.ln_s[k], threads.ln_c[k]);
        psi += v;
        grad += d1 * gl;
        hess += d2 * gl * gl.transpose() + d1 * hl;
    }
    if !psi.is_finite() {
        out.energy = f64::INFINITY;
        return out;
    }
    out.energy += r.area * psi;
    let p = DMat2::from_cols(DVec2::new(grad[0], grad[1]), DVec2::new(grad[2], grad[3]));
    add_jacobian_terms(&mut out, r, p, proj.map(|_| hess), proj);
    out
}

/// The p-norm stand-in for the largest thread excess (phase 0 of [`crate::limits::reach`]).
#[derive(Clone, Copy, Debug)]
pub struct ThreadPower {
    /// The limits per thread.
    pub threads: Threads,
    /// The exponent (larger: closer to the min-max).
    pub p: f64,
    /// The weight of δ2.
    pub reg: f64,
}

/// Exponents above this make a power overflow: such a map is infinitely far from the limits.
const EXP_CAP: f64 = 700.0;

impl ThreadTerm for ThreadPower {
    fn term(&self, l: f64, ln_s: f64, ln_c: f64) -> (f64, f64, f64) {
        let p = self.p;
        let (mut v, mut d1, mut d2) = (0.0, 0.0, 0.0);
        for (a, sign) in [(p * (l - ln_s), 1.0), (p * (ln_c - l), -1.0)] {
            if a.is_nan() || a == f64::NEG_INFINITY {
                continue;
            }
            if a > EXP_CAP {
                return (f64::INFINITY, 0.0, 0.0);
            }
            let e = a.exp();
            v += e;
            d1 += sign * p * e;
            d2 += p * p * e;
        }
        (v, d1, d2)
    }
}

impl TriEnergy for ThreadPower {
    fn tri_energy(&self, r: &RestTri, x: &[DVec2]) -> f64 {
        thread_energy(self, &self.threads, self.reg, r, x)
    }
    fn tri_eval(&self, r: &RestTri, x: &[DVec2], proj: Option<Projection>) -> TriEval {
        thread_eval(self, &self.threads, self.reg, r, x, proj)
    }
}

/// Log barriers at walls `wall` (log strain) beyond each thread's limits, weighted by `mu`
/// (phases 1 and 2 of [`crate::limits`]).
#[derive(Clone, Copy, Debug)]
pub struct ThreadBarrier {
    /// The limits per thread.
    pub threads: Threads,
    /// How far beyond each thread's limits the walls stand (log strain).
    pub wall: f64,
    /// The barriers' weight.
    pub mu: f64,
    /// The weight of δ2.
    pub reg: f64,
}

impl ThreadTerm for ThreadBarrier {
    fn term(&self, l: f64, ln_s: f64, ln_c: f64) -> (f64, f64, f64) {
        let (mut v, mut d1, mut d2) = (0.0, 0.0, 0.0);
        if ln_s.is_finite() {
            let y = self.wall + ln_s - l;
            if y.is_nan() || y <= 0.0 {
                return (f64::INFINITY, 0.0, 0.0);
            }
            v -= y.ln();
            d1 += 1.0 / y;
            d2 += 1.0 / (y * y);
        }
        if ln_c.is_finite() {
            let y = self.wall - ln_c + l;
            if y.is_nan() || y <= 0.0 {
                return (f64::INFINITY, 0.0, 0.0);
            }
            v -= y.ln();
            d1 -= 1.0 / y;
            d2 += 1.0 / (y * y);
        }
        (self.mu * v, self.mu * d1, self.mu * d2)
    }
}

impl TriEnergy for ThreadBarrier {
    fn tri_energy(&self, r: &RestTri, x: &[DVec2]) -> f64 {
        thread_energy(self, &self.threads, self.reg, r, x)
    }
    fn tri_eval(&self, r: &RestTri, x: &[DVec2], proj: Option<Projection>) -> TriEval {
        thread_eval(self, &self.threads, self.reg, r, x, proj)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_flatten::nonlinear::kernel::check_derivatives;
    use flatcut_mesh::grain_strain::{ByDirection, grain_strain_of};

    fn woven() -> DirectionalLimits {
        DirectionalLimits {
            stretch_pct: ByDirection {
                along: 2.0,
                across: 3.0,
                bias: 15.0,
            },
            compress_pct: ByDirection {
                along: 1.0,
                across: 1.5,
                bias: 15.0,
            },
        }
    }

    fn one_triangle() -> (RestTri, Vec<DVec2>) {
        let m = flatcut_flatten::testmesh::skew_triangle();
        let rest = flatcut_flatten::nonlinear::kernel::rest_frames(&m).unwrap()[0];
        // A map near the rest shape, sheared on the bias.
        let dm = rest.dm_inv.inverse();
        let shear = DMat2::from_cols(DVec2::new(1.01, 0.06), DVec2::new(0.05, 0.995));
        let x = vec![
            DVec2::new(0.3, -0.2),
            DVec2::new(0.3, -0.2) + shear * dm.x_axis,
            DVec2::new(0.3, -0.2) + shear * dm.y_axis,
        ];
        (rest, x)
    }

    #[test]
    fn thread_stretches_are_the_reports() {
        let (r, x) = one_triangle();
        let u = DVec2::new(0.8, 0.6);
        let t = Threads::new(&woven(), u);
        let f = r.jacobian(&x);
        let g = grain_strain_of(f, u).unwrap();
        let det = f.determinant();
        let s: Vec<f64> = t
            .dirs
            .iter()
            .map(|d| log_stretch(f, det, *d).exp())
            .collect();
        assert!((s[0] - g.along).abs() < 1e-13, "{s:?} {g:?}");
        assert!((s[1] - g.across).abs() < 1e-13);
        assert!((s[2].max(s[3]) - g.bias_max).abs() < 1e-13);
        assert!((s[2].min(s[3]) - g.bias_min).abs() < 1e-13);
        // The excess is the report's, in log strain.
        let l = woven();
        let want = [
            (g.along.ln() - (1.0 + l.stretch_pct.along / 100.0).ln()),
            ((1.0 - l.compress_pct.along / 100.0).ln() - g.along.ln()),
            (g.across.ln() - (1.0 + l.stretch_pct.across / 100.0).ln()),
            ((1.0 - l.compress_pct.across / 100.0).ln() - g.across.ln()),
            (g.bias_max.ln() - (1.0 + l.stretch_pct.bias / 100.0).ln()),
            ((1.0 - l.compress_pct.bias / 100.0).ln() - g.bias_min.ln()),
        ]
        .into_iter()
        .fold(f64::NEG_INFINITY, f64::max);
        assert!((t.excess(f) - want).abs() < 1e-13);
    }

    #[test]
    fn energies_match_finite_differences() {
        let (r, x) = one_triangle();
        let t = Threads::new(&woven(), DVec2::new(0.8, 0.6));
        check_derivatives(
            &ThreadBarrier {
                threads: t,
                wall: 0.1,
                mu: 0.7,
                reg: 0.3,
            },
            &r,
            &x,
        );
        check_derivatives(
            &ThreadPower {
                threads: t,
                p: 40.0,
                reg: 0.3,
            },
            &r,
            &x,
        );
    }

    #[test]
    fn the_barrier_is_infinite_beyond_a_threads_wall_and_its_hessian_projects() {
        let (r, x) = one_triangle();
        // Along the warp the map stretches by about 1 %; a wall at 0.5 % is crossed.
        let mut l = woven();
        l.stretch_pct.along = 0.5;
        l.compress_pct.along = 5.0;
        let t = Threads::new(&l, DVec2::X);
        let f = r.jacobian(&x);
        assert!(t.excess(f) > 0.0);
        let b = ThreadBarrier {
            threads: t,
            wall: 0.0,
            mu: 1.0,
            reg: 1.0,
        };
        assert!(b.tri_energy(&r, &x).is_infinite());
        let inside = ThreadBarrier { wall: 0.05, ..b };
        let h = inside.tri_eval(&r, &x, Some(Projection::Clamp)).hess;
        let m = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, j| h[i][j]);
        let ev = m.symmetric_eigenvalues();
        assert!(ev.iter().all(|v| *v >= -1e-9 * ev.amax()), "{ev}");
    }
}
