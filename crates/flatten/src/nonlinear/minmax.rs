//! Min-max global distortion: Duncan's δ0 = log(s2/s1), where s1 and s2 are the smallest and the
//! largest ratio (distance in the plane) / (geodesic distance on the surface) over all pairs of
//! points. On a spherical cap of geodesic radius α the optimum is Milnor's: the azimuthal
//! equidistant map, δ0 = log(α / sin α).
//!
//! The method:
//! 1. **Start**: the discrete azimuthal-equidistant map (log map) about the geodesic centre (the
//!    vertex of least eccentricity): radius = geodesic distance from the centre
//!    ([`flatcut_mesh::geodesic`]), angle = the harmonic angle of the Tutte embedding about the
//!    centre. The isometric (δ2) solution (flip-free by construction) is the other candidate; the
//!    one with the lower δ0 is the start.
//! 2. **Descent** on a smooth surrogate of δ0: log-sum-exp (sharpness p, annealed) of log σ1 over
//!    every face and log r over sampled far pairs (farthest-point sources × all vertices), plus the
//!    log-sum-exp of −log σ2 and −log r. For the polyhedral surface the faces' σ are exact for
//!    short pairs (within a flat face geodesics are straight). The minimiser is a limited-memory
//!    BFGS with a flip-free line search (steps are bounded by the first inversion, as in
//!    [`super::newton`]), and the iterate with the best measured δ0 is kept, so the result is
//!    never worse than the start.
//! 3. **Scale**: δ0 does not fix a scale; the result is scaled so that s1·s2 = 1 (every distance
//!    is off by at most a factor e^{±δ0/2}).
//!
//! Our own L-BFGS (≈60 lines) rather than argmin's: argmin's line searches cannot be bounded by
//! the inversion step, and an unbounded trial step can jump over the log barrier.

use std::collections::VecDeque;

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use super::kernel::{RestTri, max_step_tri, singular_values, svd2};
use super::newton::{Budget, EarlyStop};
use crate::{FlattenError, FlattenInfo, FlattenParams, FlattenProgress, Flattening, Method};

/// Far-pair sources: farthest-point samples whose geodesic distances to every vertex enter the
/// surrogate and the measure (the report's default is 12; a few more steady the optimum).
pub const DEFAULT_SOURCES: usize = 16;
/// Pairs shorter than this fraction of the bounding-box diagonal are left to the faces' σ (as the
/// report does): short geodesics on a coarse mesh carry its discretisation error.
pub const MIN_PAIR_FRACTION: f64 = 0.05;
/// Sharpness schedule of the log-sum-exp (in units of 1/log-stretch): the surrogate exceeds the
/// true maximum by at most ln(N)/p, so the last stage is within ~0.5 % of δ0 for 10⁵ terms.
const SHARPNESS: [f64; 5] = [30.0, 100.0, 300.0, 1000.0, 3000.0];
/// L-BFGS memory (pairs of steps kept).
const LBFGS_MEMORY: usize = 12;
/// Fraction of the distance to the first inversion taken as the largest trial step.
const INVERSION_STEP_FRACTION: f64 = 0.9;
/// Armijo sufficient-decrease constant.
const ARMIJO_C: f64 = 1e-4;
/// Backtracking halvings before a stage gives up.
const MAX_HALVINGS: usize = 40;
/// A stage ends when the surrogate decreases by less than this (absolute, in log-stretch units:
/// 1e-7 of δ0 is far below what the geodesics resolve).
const STAGE_TOLERANCE: f64 = 1e-9;

/// δ0 and its two extreme scale factors, measured on faces and sampled pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Delta0 {
    /// log(s_max / s_min); +∞ if a triangle is inverted or degenerate.
    pub delta0: f64,
    /// Smallest scale factor (face σ2 or pair ratio).
    pub s_min: f64,
    /// Largest scale factor (face σ1 or pair ratio).
    pub s_max: f64,
    /// Number of sampled pairs that entered the measure.
    pub pairs: usize,
}

/// Sampled far pairs: (source vertex, other vertex, geodesic distance in mm).
#[derive(Clone, Debug, Default)]
pub struct PairSet {
    /// The sampled pairs (0-based vertex indices, distance in mm), in sampling order.
    pub pairs: Vec<(u32, u32, f64)>,
}

impl PairSet {
    /// Farthest-point-sampled sources (by geodesic distance, the first one farthest from vertex
    /// 0) and their pairs with every vertex farther than [`MIN_PAIR_FRACTION`] of the diagonal.
    /// Also returns the geodesic distance fields, one per source.
    pub fn sample(mesh: &TriMesh, sources: usize) -> (Self, Vec<(u32, Vec<f64>)>) {
        let n = mesh.positions.len();
        let mut fields: Vec<(u32, Vec<f64>)> = Vec::new();
        if n == 0 || sources == 0 {
            return (Self::default(), fields);
        }
        let used = crate::ops::used_mask(mesh);
        let Some(start) = (0..n).find(|&v| used[v]) else {
            return (Self::default(), fields);
        };
        let d0 = flatcut_mesh::geodesic::distances_from(mesh, start as u32);
        let mut nearest = vec![f64::INFINITY; n];
        let mut next = argmax_finite(&d0).unwrap_or(start);
        for _ in 0..sources.min(n) {
            let d = flatcut_mesh::geodesic::distances_from(mesh, next as u32);
            for (m, &g) in nearest.iter_mut().zip(&d) {
                *m = m.min(g);
            }
            fields.push((next as u32, d));
            match argmax_finite(&nearest) {
                Some(v) if nearest[v] > 0.0 => next = v,
                _ => break,
            }
        }
        let min_len = MIN_PAIR_FRACTION * mesh.bbox().diagonal();
        let mut pairs = Vec::new();
        for (s, d) in &fields {
            for (v, &g) in d.iter().enumerate() {
                if g.is_finite() && g > min_len && used[v] {
                    pairs.push((*s, v as u32, g));
                }
            }
        }
        (Self { pairs }, fields)
    }
}

fn argmax_finite(d: &[f64]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (i, &g) in d.iter().enumerate() {
        if g.is_finite() && best.is_none_or(|b| g > d[b]) {
            best = Some(i);
        }
    }
    best
}

/// Measures δ0 of the map `uv`: every face's σ1, σ2 and the ratio of plane to geodesic distance of
/// every pair in `pairs`.
pub fn measure(rest: &[RestTri], uv: &[DVec2], pairs: &PairSet) -> Delta0 {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for r in rest {
        let f = r.jacobian(uv);
        if f.determinant().is_nan() || f.determinant() <= 0.0 {
            return Delta0 {
                delta0: f64::INFINITY,
                s_min: 0.0,
                s_max: f64::INFINITY,
                pairs: 0,
            };
        }
        let (s1, s2) = singular_values(f);
        lo = lo.min(s2);
        hi = hi.max(s1);
    }
    for &(a, b, g) in &pairs.pairs {
        let q = uv[a as usize].distance(uv[b as usize]) / g;
        lo = lo.min(q);
        hi = hi.max(q);
    }
    Delta0 {
        delta0: (hi / lo).ln(),
        s_min: lo,
        s_max: hi,
        pairs: pairs.pairs.len(),
    }
}

/// The smooth surrogate: LSE_p(log σ1, log r) + LSE_p(−log σ2, −log r).
struct Surrogate<'a> {
    rest: &'a [RestTri],
    pairs: &'a PairSet,
    p: f64,
    /// Scratch: the terms (value) of the two maxima.
    up: Vec<f64>,
    down: Vec<f64>,
}

impl Surrogate<'_> {
    /// Value (+∞ if a triangle is inverted) and, if `grad` is given, the gradient into it.
    fn eval(&mut self, x: &[DVec2], grad: Option<&mut [DVec2]>) -> f64 {
        let nf = self.rest.len();
        self.up.clear();
        self.down.clear();
        let mut svds = Vec::with_capacity(if grad.is_some() { nf } else { 0 });
        for r in self.rest {
            let f = r.jacobian(x);
            if f.determinant().is_nan() || f.determinant() <= 0.0 {
                return f64::INFINITY;
            }
            let s = svd2(f);
            self.up.push(s.s1.ln());
            self.down.push(-s.s2.ln());
            if grad.is_some() {
                svds.push(s);
            }
        }
        for &(a, b, g) in &self.pairs.pairs {
            let l = (x[a as usize].distance(x[b as usize]) / g).ln();
            self.up.push(l);
            self.down.push(-l);
        }
        let (vu, wu) = lse(&mut self.up, self.p);
        let (vd, wd) = lse(&mut self.down, self.p);
        if let Some(gr) = grad {
            gr.iter_mut().for_each(|v| *v = DVec2::ZERO);
            for (t, r) in self.rest.iter().enumerate() {
                let s = &svds[t];
                // ∂ log σ_k/∂F = u_k v_kᵀ / σ_k; ∂F/∂x_v contracts with g_v.
                let vt = s.v.transpose();
                let c1 = wu[t] / s.s1;
                let c2 = -wd[t] / s.s2;
                let p = s.u * flatcut_geom::DMat2::from_diagonal(DVec2::new(c1, c2)) * vt;
                let g = r.g();
                for k in 0..3 {
                    gr[r.v[k]] += p * g[k];
                }
            }
            for (k, &(a, b, _)) in self.pairs.pairs.iter().enumerate() {
                let d = x[a as usize] - x[b as usize];
                let w = wu[nf + k] - wd[nf + k];
                let gd = w * d / d.length_squared();
                gr[a as usize] += gd;
                gr[b as usize] -= gd;
            }
        }
        vu + vd
    }
}

/// log-sum-exp max_p(a) = m + ln Σ exp(p(a_k − m))/p, overwriting `a` with the softmax weights.
fn lse(a: &mut [f64], p: f64) -> (f64, &[f64]) {
    let m = a.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut s = 0.0;
    for v in a.iter_mut() {
        *v = (p * (*v - m)).exp();
        s += *v;
    }
    for v in a.iter_mut() {
        *v /= s;
    }
    (m + s.ln() / p, a)
}

fn dot(a: &[DVec2], b: &[DVec2]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.dot(*q)).sum()
}

/// One annealing stage of L-BFGS on the surrogate; updates `x` and `best` (the map with the
/// lowest measured δ0). Returns the number of iterations, and why the stage stopped early if
/// the caller asked it to (cancel flag, time limit); `done` counts the iterations of the
/// earlier stages for the progress reports.
fn lbfgs_stage(
    s: &mut Surrogate<'_>,
    x: &mut Vec<DVec2>,
    best: &mut (f64, Vec<DVec2>),
    max_iters: usize,
    budget: &Budget,
    (done, total): (usize, usize),
) -> (usize, Option<EarlyStop>) {
    let n = x.len();
    let mut g = vec![DVec2::ZERO; n];
    let mut f = s.eval(x, Some(&mut g));
    if !f.is_finite() {
        return (0, None);
    }
    let mut hist: VecDeque<(Vec<DVec2>, Vec<DVec2>, f64)> = VecDeque::new();
    let mut xn = x.clone();
    let mut gn = vec![DVec2::ZERO; n];
    let mut iters = 0;
    for _ in 0..max_iters {
        if budget.hooks.cancelled() {
            return (iters, Some(EarlyStop::Cancelled));
        }
        if budget.expired() {
            return (iters, Some(EarlyStop::TimeLimit));
        }
        iters += 1;
        // Two-loop recursion.
        let mut d: Vec<DVec2> = g.iter().map(|v| -*v).collect();
        let mut alpha = Vec::with_capacity(hist.len());
        for (sk, yk, rho) in hist.iter().rev() {
            let a = rho * dot(sk, &d);
            for (di, yi) in d.iter_mut().zip(yk) {
                *di -= a * *yi;
            }
            alpha.push(a);
        }
        if let Some((sk, yk, _)) = hist.back() {
            let gamma = dot(sk, yk) / dot(yk, yk);
            d.iter_mut().for_each(|v| *v *= gamma);
        } else {
            // First step: move the fastest vertex by 1 % of the mesh's extent scale (the
            // gradient is in 1/mm, so scale by a length²).
            let gmax = g.iter().map(|v| v.length()).fold(0.0, f64::max);
            let ext = extent(x);
            if gmax > 0.0 {
                let c = 1e-3 * ext / gmax;
                d.iter_mut().for_each(|v| *v *= c);
            }
        }
        for ((sk, yk, rho), a) in hist.iter().zip(alpha.iter().rev()) {
            let b = rho * dot(yk, &d);
            for (di, si) in d.iter_mut().zip(sk) {
                *di += (a - b) * *si;
            }
        }
        let mut gd = dot(&g, &d);
        if gd.is_nan() || gd >= 0.0 {
            hist.clear();
            d = g.iter().map(|v| -*v).collect();
            gd = dot(&g, &d);
            if gd.is_nan() || gd >= 0.0 {
                break;
            }
        }
        let tmax = s
            .rest
            .iter()
            .map(|r| max_step_tri(r, x, &d))
            .fold(f64::INFINITY, f64::min);
        let mut t = (INVERSION_STEP_FRACTION * tmax).min(1.0);
        let mut fnew = f64::INFINITY;
        let mut ok = false;
        for _ in 0..MAX_HALVINGS {
            for k in 0..n {
                xn[k] = x[k] + t * d[k];
            }
            fnew = s.eval(&xn, Some(&mut gn));
            if fnew.is_finite() && fnew <= f + ARMIJO_C * t * gd {
                ok = true;
                break;
            }
            t *= 0.5;
        }
        if !ok {
            break;
        }
        let sk: Vec<DVec2> = (0..n).map(|k| xn[k] - x[k]).collect();
        let yk: Vec<DVec2> = (0..n).map(|k| gn[k] - g[k]).collect();
        let sy = dot(&sk, &yk);
        if sy > 0.0 {
            if hist.len() == LBFGS_MEMORY {
                hist.pop_front();
            }
            hist.push_back((sk, yk, 1.0 / sy));
        }
        std::mem::swap(x, &mut xn);
        std::mem::swap(&mut g, &mut gn);
        let decrease = f - fnew;
        f = fnew;
        let m = measure(s.rest, x, s.pairs).delta0;
        if m < best.0 {
            best.0 = m;
            best.1.clone_from(x);
        }
        budget.hooks.report(&FlattenProgress {
            stage: budget.stage,
            iteration: done + iters,
            max_iterations: total,
            energy: best.0,
            elapsed: budget.started.elapsed(),
        });
        if decrease < STAGE_TOLERANCE {
            break;
        }
    }
    (iters, None)
}

/// Largest coordinate extent of a point set.
fn extent(x: &[DVec2]) -> f64 {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in x {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).max_element().max(f64::MIN_POSITIVE)
}

/// The azimuthal-equidistant start about the geodesic centre (the vertex minimising the largest
/// distance to the sampled sources). `None` if it inverts a triangle.
pub fn log_map_start(
    mesh: &TriMesh,
    topo: &Topology,
    rest: &[RestTri],
    fields: &[(u32, Vec<f64>)],
) -> Result<Option<Vec<DVec2>>, FlattenError> {
    let n = mesh.positions.len();
    let used = crate::ops::used_mask(mesh);
    let ecc = |v: usize| fields.iter().map(|(_, d)| d[v]).fold(0.0, f64::max);
    let Some(centre) = (0..n)
        .filter(|&v| used[v])
        .min_by(|&a, &b| ecc(a).total_cmp(&ecc(b)))
    else {
        return Ok(None);
    };
    let radial = flatcut_mesh::geodesic::distances_from(mesh, centre as u32);
    let tutte = crate::tutte::tutte(mesh, topo)?;
    let c = tutte[centre];
    let mut uv = vec![DVec2::ZERO; n];
    for v in 0..n {
        if v == centre || !used[v] {
            continue;
        }
        let dir = tutte[v] - c;
        let r = radial[v];
        if !r.is_finite() || dir.length_squared() == 0.0 {
            return Ok(None);
        }
        uv[v] = r * dir.normalize();
    }
    if rest.iter().all(|r| r.jacobian(&uv).determinant() > 0.0) {
        Ok(Some(uv))
    } else {
        Ok(None)
    }
}

/// Min-max δ0 flattening (see the module doc).
pub fn minmax(
    mesh: &TriMesh,
    topo: &Topology,
    rest: &[RestTri],
    x0: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let (pairs, fields) = PairSet::sample(mesh, DEFAULT_SOURCES);
    let mut warnings = Vec::new();
    // Two flip-free candidates; the descent starts from the one with the lower δ0, so the result
    // is never worse than the isometric map (which wins on nearly developable surfaces, where the
    // log map's harmonic angle is only approximate).
    let start_stage = budget.next("min-max start", params.time_limit);
    let iso = {
        let p = FlattenParams::new(Method::Isometric).with_max_iters(params.max_iters);
        super::isometric(mesh, rest, x0, &p, &start_stage)
            .map_err(|e| match e {
                FlattenError::Cancelled { .. } => FlattenError::Cancelled {
                    method: Method::Minmax,
                },
                e => e,
            })?
            .uv
    };
    let mut x = iso;
    let mut start = measure(rest, &x, &pairs);
    if let Some(lm) = log_map_start(mesh, topo, rest, &fields)? {
        let m = measure(rest, &lm, &pairs);
        if m.delta0 < start.delta0 {
            x = lm;
            start = m;
        }
    }
    if !start.delta0.is_finite() {
        return Err(FlattenError::NoConvergence {
            method: Method::Minmax,
            reason: "no flip-free starting map (both the log map and the isometric map invert a triangle)".into(),
        });
    }
    let mut best = (start.delta0, x.clone());
    let mut sur = Surrogate {
        rest,
        pairs: &pairs,
        p: SHARPNESS[0],
        up: Vec::new(),
        down: Vec::new(),
    };
    // The descent is one stage of the flattening: `max_iters` caps the L-BFGS iterations of all
    // its sharpness steps together, each taking its share of what the earlier ones left.
    let descent = budget.next("minmax", params.time_limit);
    let mut iterations = 0;
    let mut early = None;
    for (k, p) in SHARPNESS.into_iter().enumerate() {
        let share = descent.left().div_ceil(SHARPNESS.len() - k);
        if share == 0 || early.is_some() {
            break;
        }
        sur.p = p;
        let (it, stop) = lbfgs_stage(
            &mut sur,
            &mut x,
            &mut best,
            descent.allow(share),
            &descent,
            (iterations, descent.cap()),
        );
        descent.spend(it);
        iterations += it;
        early = stop;
        // Continue each stage from the best map so far: a sharper surrogate only refines it.
        x.clone_from(&best.1);
    }
    match early {
        Some(EarlyStop::Cancelled) => {
            return Err(FlattenError::Cancelled {
                method: Method::Minmax,
            });
        }
        Some(EarlyStop::TimeLimit) => {
            warnings.push(super::time_limit_warning(Method::Minmax, iterations));
        }
        None => {}
    }
    let mut uv = best.1;
    let m = measure(rest, &uv, &pairs);
    let f = 1.0 / (m.s_min * m.s_max).sqrt();
    let mut c = DVec2::ZERO;
    for p in &uv {
        c += *p;
    }
    c /= uv.len().max(1) as f64;
    for p in uv.iter_mut() {
        *p = (*p - c) * f;
    }
    Ok(Flattening {
        info: FlattenInfo {
            iterations: start_stage.used() + iterations,
            final_energy: m.delta0,
            warnings,
            stages: vec![start_stage.count(), descent.count()],
            ..Default::default()
        },
        uv,
    })
}
