//! Tensor-product B-spline and NURBS patches (Gravesen §3.3, Salomon §7.15, Piegl–Tiller A2.1–A2.3),
//! with exact rational quadric and torus pieces built as surfaces of revolution (digest B3).
//!
//! Evaluation finds the knot span by binary search, computes the `p + 1` nonzero basis functions
//! with derivatives by the triangular Cox–de Boor scheme (all in fixed-size stack arrays, so no
//! allocation per evaluation), and contracts them with the `(p + 1) × (q + 1)` active poles.
//! Rational patches contract homogeneous poles `(w P, w)` and apply the quotient rule:
//! `S = A/w`, `S_u = (A_u − w_u S)/w`, `S_uu = (A_uu − 2 w_u S_u − w_uu S)/w`,
//! `S_uv = (A_uv − w_uv S − w_u S_v − w_v S_u)/w`.
//!
//! Written here rather than taken from a crate: the NURBS crates available (curvo, truck) bring
//! a second linear-algebra stack or lack a no-allocation `D1` hot path; this file is ~400 lines.

use crate::curve::basis;
use crate::{Domain2, ParamSurface, SurfaceDerivs, SurfaceError};
use glam::{DVec3, DVec4};
use std::ops::{Add, AddAssign, Mul};

/// Highest supported degree (the same limit as OpenCASCADE's `Geom_BSplineSurface::MaxDegree`);
/// it bounds the stack arrays of the basis evaluation.
pub const MAX_DEGREE: usize = 25;

/// `cos 45°`, the middle weight of a rational quadratic quarter circle.
const QUARTER_WEIGHT: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A (rational) tensor-product B-spline patch.
///
/// Poles `P_ij`, `i < count_u`, `j < count_v`, are stored with **v varying fastest**
/// (`points[i * count_v + j]`); knot vectors have `count + degree + 1` entries (clamped or not);
/// the domain is `[knots_u[p], knots_u[count_u]] × [knots_v[q], knots_v[count_v]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplinePatch {
    degree_u: usize,
    degree_v: usize,
    knots_u: Vec<f64>,
    knots_v: Vec<f64>,
    count_u: usize,
    count_v: usize,
    points: Vec<DVec3>,
    weights: Option<Vec<f64>>,
    /// Homogeneous poles `(w x, w y, w z, w)`; filled only for rational patches.
    hpoints: Vec<DVec4>,
    /// Per-span Bézier patches for degrees ≤ 3 (the fast evaluation path).
    cache: Option<SpanCache>,
}

/// Largest number of cached Bézier poles (24–32 bytes each): ~32 MB at most.
const MAX_CACHED_POLES: usize = 1 << 20;

/// The patch cut into Bézier pieces by knot insertion (Boehm), one block of `(p+1)(q+1)` poles
/// per span pair (v fastest within a block, blocks ordered u-span-major). Evaluation then needs
/// a span search and a Bernstein contraction only: the idea of OpenCASCADE's span cache, with
/// every span precomputed so evaluation stays `&self` and thread-safe.
#[derive(Clone, Debug, PartialEq)]
struct SpanCache {
    breaks_u: Breaks,
    breaks_v: Breaks,
    poles: Vec<DVec3>,
    hpoles: Vec<DVec4>,
}

/// Inserts `t` once into the curve (`knots`, `pts`) of degree `p` (Boehm's algorithm).
fn insert_knot<T: Pole>(knots: &mut Vec<f64>, p: usize, pts: &mut Vec<T>, t: f64) {
    let n = pts.len();
    // Span k with knots[k] ≤ t < knots[k+1], or the last span with knots[k] < t at the end.
    let k = if t < knots[n] {
        basis::find_span(n, p, t, knots)
    } else {
        let mut k = n - 1;
        while knots[k] >= t {
            k -= 1;
        }
        k
    };
    let mut q = Vec::with_capacity(n + 1);
    for i in 0..=n {
        if i + p <= k {
            q.push(pts[i]);
        } else if i <= k {
            let a = (t - knots[i]) / (knots[i + p] - knots[i]);
            q.push(pts[i - 1] * (1.0 - a) + pts[i] * a);
        } else {
            q.push(pts[i - 1]);
        }
    }
    knots.insert(k + 1, t);
    *pts = q;
}

/// Refines a knot vector so that every breakpoint of the domain has multiplicity ≥ p; returns
/// the insertion sequence and the breakpoints.
fn bezier_insertions(knots: &[f64], p: usize, count: usize) -> (Vec<f64>, Vec<f64>) {
    let mut breaks: Vec<f64> = Vec::new();
    for &k in &knots[p..=count] {
        if breaks.last() != Some(&k) {
            breaks.push(k);
        }
    }
    let mut ins = Vec::new();
    for &x in &breaks {
        let mult = knots.iter().filter(|&&k| k == x).count();
        for _ in mult..p {
            ins.push(x);
        }
    }
    (ins, breaks)
}

/// Applies the insertions along u (`dir_u`) or v to a v-fastest grid of poles.
fn refine_grid<T: Pole>(
    grid: &[T],
    count_u: usize,
    count_v: usize,
    dir_u: bool,
    knots: &[f64],
    p: usize,
    ins: &[f64],
) -> (Vec<T>, Vec<f64>, usize) {
    let (lines, len) = if dir_u {
        (count_v, count_u)
    } else {
        (count_u, count_v)
    };
    let mut out_lines = Vec::with_capacity(lines);
    let mut new_knots = knots.to_vec();
    for l in 0..lines {
        let mut pts: Vec<T> = (0..len)
            .map(|k| {
                if dir_u {
                    grid[k * count_v + l]
                } else {
                    grid[l * count_v + k]
                }
            })
            .collect();
        let mut kn = knots.to_vec();
        for &t in ins {
            insert_knot(&mut kn, p, &mut pts, t);
        }
        new_knots = kn;
        out_lines.push(pts);
    }
    let new_len = len + ins.len();
    let (cu, cv) = if dir_u {
        (new_len, count_v)
    } else {
        (count_u, new_len)
    };
    let mut out = vec![T::default(); cu * cv];
    for (l, pts) in out_lines.iter().enumerate() {
        for (k, &q) in pts.iter().enumerate() {
            if dir_u {
                out[k * cv + l] = q;
            } else {
                out[l * cv + k] = q;
            }
        }
    }
    (out, new_knots, new_len)
}

/// Bernstein basis of degree `N − 1 ≤ 3` with first and second derivatives.
#[inline(always)]
fn bern<const N: usize>(t: f64) -> ([f64; N], [f64; N], [f64; N]) {
    let mut b = [0.0; N];
    let mut d = [0.0; N];
    let mut dd = [0.0; N];
    let s = 1.0 - t;
    match N {
        2 => {
            b[..2].copy_from_slice(&[s, t]);
            d[..2].copy_from_slice(&[-1.0, 1.0]);
        }
        3 => {
            b[..3].copy_from_slice(&[s * s, 2.0 * t * s, t * t]);
            d[..3].copy_from_slice(&[-2.0 * s, 2.0 * (s - t), 2.0 * t]);
            dd[..3].copy_from_slice(&[2.0, -4.0, 2.0]);
        }
        _ => {
            let (cb, cd) = super::bernstein::cubic_d1(t);
            let cdd = super::bernstein::cubic_d2(t);
            let m = N.min(4);
            b[..m].copy_from_slice(&cb[..m]);
            d[..m].copy_from_slice(&cd[..m]);
            dd[..m].copy_from_slice(&cdd[..m]);
        }
    }
    (b, d, dd)
}

/// Sorted breakpoints of one direction with reciprocal span lengths, for O(1) span lookup.
#[derive(Clone, Debug, PartialEq)]
struct Breaks {
    at: Vec<f64>,
    inv_len: Vec<f64>,
    /// `spans / (last − first)`: the index guess for uniform knots.
    guess_scale: f64,
}

impl Breaks {
    fn new(at: Vec<f64>) -> Self {
        let inv_len = at.windows(2).map(|w| 1.0 / (w[1] - w[0])).collect();
        let guess_scale = (at.len() - 1) as f64 / (at[at.len() - 1] - at[0]);
        Self {
            at,
            inv_len,
            guess_scale,
        }
    }

    /// Index of the span containing `t` (clamped), local parameter and reciprocal span length.
    /// Guesses the span as if the knots were uniform, then walks to the right one.
    #[inline(always)]
    fn locate(&self, t: f64) -> (usize, f64, f64) {
        let b = &self.at;
        let last = b.len() - 2;
        let mut i = (((t - b[0]) * self.guess_scale) as usize).min(last);
        while i > 0 && t < b[i] {
            i -= 1;
        }
        while i < last && t >= b[i + 1] {
            i += 1;
        }
        let inv = self.inv_len[i];
        (i, (t - b[i]) * inv, inv)
    }

    fn spans(&self) -> usize {
        self.at.len() - 1
    }
}

impl SpanCache {
    fn build(s: &BSplinePatch) -> Option<Self> {
        let (p, q) = (s.degree_u, s.degree_v);
        if p > 3 || q > 3 {
            return None;
        }
        let (ins_u, breaks_u) = bezier_insertions(&s.knots_u, p, s.count_u);
        let (ins_v, breaks_v) = bezier_insertions(&s.knots_v, q, s.count_v);
        let blocks = (breaks_u.len() - 1) * (breaks_v.len() - 1);
        if blocks * (p + 1) * (q + 1) > MAX_CACHED_POLES {
            return None;
        }
        fn extract<T: Pole>(s: &BSplinePatch, grid: &[T], ins_u: &[f64], ins_v: &[f64]) -> Vec<T> {
            let (p, q) = (s.degree_u, s.degree_v);
            let (g1, ku, nu) = refine_grid(grid, s.count_u, s.count_v, true, &s.knots_u, p, ins_u);
            let (g2, kv, nv) = refine_grid(&g1, nu, s.count_v, false, &s.knots_v, q, ins_v);
            let spans = |k: &[f64], deg: usize, n: usize| -> Vec<usize> {
                (deg..n).filter(|&i| k[i] < k[i + 1]).collect()
            };
            let mut out = Vec::new();
            for &su in &spans(&ku, p, nu) {
                for &sv in &spans(&kv, q, nv) {
                    for i in su - p..=su {
                        for j in sv - q..=sv {
                            out.push(g2[i * nv + j]);
                        }
                    }
                }
            }
            out
        }
        let (poles, hpoles) = if s.weights.is_some() {
            (Vec::new(), extract(s, &s.hpoints, &ins_u, &ins_v))
        } else {
            (extract(s, &s.points, &ins_u, &ins_v), Vec::new())
        };
        Some(Self {
            breaks_u: Breaks::new(breaks_u),
            breaks_v: Breaks::new(breaks_v),
            poles,
            hpoles,
        })
    }

    /// Local contraction over one Bézier block of degree (P−1, Q−1), scaled to global partials.
    #[inline(always)]
    fn eval<T: Pole, const P: usize, const Q: usize, const K: usize>(
        &self,
        poles: &[T],
        u: f64,
        v: f64,
        pairs: &[(usize, usize); K],
    ) -> [T; K] {
        let (iu, su, inv_u) = self.breaks_u.locate(u);
        let (iv, sv, inv_v) = self.breaks_v.locate(v);
        let nsv = self.breaks_v.spans();
        let base = (iu * nsv + iv) * P * Q;
        let block = &poles[base..base + P * Q];
        let (bu0, bu1, bu2) = bern::<P>(su);
        let (bv0, bv1, bv2) = bern::<Q>(sv);
        let bu = [bu0, bu1, bu2];
        let bv = [bv0, bv1, bv2];
        let scale_u = [1.0, inv_u, inv_u * inv_u];
        let scale_v = [1.0, inv_v, inv_v * inv_v];
        let mut out = [T::default(); K];
        for i in 0..P {
            let row = &block[i * Q..i * Q + Q];
            let mut rv = [T::default(); 3];
            for j in 0..Q {
                rv[0] += row[j] * bv[0][j];
                if K > 1 {
                    rv[1] += row[j] * bv[1][j];
                }
                if K > 3 {
                    rv[2] += row[j] * bv[2][j];
                }
            }
            for (o, &(a, b)) in out.iter_mut().zip(pairs.iter()) {
                *o += rv[b] * bu[a][i];
            }
        }
        for (o, &(a, b)) in out.iter_mut().zip(pairs.iter()) {
            *o = *o * (scale_u[a] * scale_v[b]);
        }
        out
    }

    /// Point and first partials of a non-rational bicubic block, written out like
    /// [`super::BezierPatch`]'s fast path.
    #[inline(always)]
    fn bicubic_d1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let (iu, su, inv_u) = self.breaks_u.locate(u);
        let (iv, sv, inv_v) = self.breaks_v.locate(v);
        let nsv = self.breaks_v.spans();
        let base = (iu * nsv + iv) * 16;
        let p = &self.poles[base..base + 16];
        let (bu, du) = super::bernstein::cubic_d1(su);
        let (bv, dv) = super::bernstein::cubic_d1(sv);
        let mut s = DVec3::ZERO;
        let mut s_u = DVec3::ZERO;
        let mut s_v = DVec3::ZERO;
        for i in 0..4 {
            let r = &p[4 * i..4 * i + 4];
            let row = r[0] * bv[0] + r[1] * bv[1] + r[2] * bv[2] + r[3] * bv[3];
            let rowv = r[0] * dv[0] + r[1] * dv[1] + r[2] * dv[2] + r[3] * dv[3];
            s += row * bu[i];
            s_u += row * du[i];
            s_v += rowv * bu[i];
        }
        (s, s_u * inv_u, s_v * inv_v)
    }

    fn dispatch<T: Pole, const K: usize>(
        &self,
        poles: &[T],
        p: usize,
        q: usize,
        u: f64,
        v: f64,
        pairs: &[(usize, usize); K],
    ) -> [T; K] {
        match (p, q) {
            (3, 3) => self.eval::<T, 4, 4, K>(poles, u, v, pairs),
            (1, 1) => self.eval::<T, 2, 2, K>(poles, u, v, pairs),
            (1, 2) => self.eval::<T, 2, 3, K>(poles, u, v, pairs),
            (1, 3) => self.eval::<T, 2, 4, K>(poles, u, v, pairs),
            (2, 1) => self.eval::<T, 3, 2, K>(poles, u, v, pairs),
            (2, 2) => self.eval::<T, 3, 3, K>(poles, u, v, pairs),
            (2, 3) => self.eval::<T, 3, 4, K>(poles, u, v, pairs),
            (3, 1) => self.eval::<T, 4, 2, K>(poles, u, v, pairs),
            _ => self.eval::<T, 4, 3, K>(poles, u, v, pairs),
        }
    }
}

fn check_knots(
    knots: &[f64],
    degree: usize,
    count: usize,
    dir: &'static str,
) -> Result<(), SurfaceError> {
    if degree == 0 {
        return Err(SurfaceError::BadDegree {
            degree,
            reason: "B-spline patch degrees must be at least 1",
        });
    }
    if degree > MAX_DEGREE {
        return Err(SurfaceError::BadDegree {
            degree,
            reason: "above the supported maximum of 25",
        });
    }
    // Length, finiteness, order and a non-empty domain: the same rules as a curve's.
    basis::check_knots(count, degree, knots)?;
    // Interior multiplicity above the degree would make the patch discontinuous.
    let mut i = degree + 1;
    while i < count {
        let mut j = i;
        while j + 1 < count && knots[j + 1] == knots[i] {
            j += 1;
        }
        let mult = j - i + 1;
        if mult > degree {
            return Err(SurfaceError::InteriorKnotMultiplicity {
                dir,
                index: i,
                knot: knots[i],
                multiplicity: mult,
                degree,
            });
        }
        i = j + 1;
    }
    Ok(())
}

/// Partial sums of a tensor contraction: `out[a][b] = Σ_ij N_u^(a)_i N_v^(b)_j P_ij`
/// for the derivative orders the caller needs.
trait Pole: Copy + Default + Mul<f64, Output = Self> + AddAssign + Add<Output = Self> {}
impl Pole for DVec3 {}
impl Pole for DVec4 {}

/// Derivative pairs (order in u, order in v) requested by `deriv1` and `deriv2`.
const D1_PAIRS: [(usize, usize); 3] = [(0, 0), (1, 0), (0, 1)];
const D2_PAIRS: [(usize, usize); 6] = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)];

impl BSplinePatch {
    /// Builds a B-spline (`weights = None`) or NURBS patch; poles v fastest.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        degree_u: usize,
        degree_v: usize,
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        count_u: usize,
        count_v: usize,
        points: Vec<DVec3>,
        weights: Option<Vec<f64>>,
    ) -> Result<Self, SurfaceError> {
        check_knots(&knots_u, degree_u, count_u, "u")?;
        check_knots(&knots_v, degree_v, count_v, "v")?;
        if points.len() != count_u * count_v {
            return Err(SurfaceError::ControlPointCount {
                expected: count_u * count_v,
                got: points.len(),
            });
        }
        super::check_finite(&points, "B-spline pole")?;
        let mut hpoints = Vec::new();
        if let Some(w) = &weights {
            if w.len() != points.len() {
                return Err(SurfaceError::PoleWeightCount {
                    weights: w.len(),
                    poles: points.len(),
                });
            }
            if let Some(index) = w.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(SurfaceError::BadWeight {
                    index,
                    value: w[index],
                });
            }
            hpoints = points
                .iter()
                .zip(w)
                .map(|(p, &wi)| (*p * wi).extend(wi))
                .collect();
        }
        let mut patch = Self {
            degree_u,
            degree_v,
            knots_u,
            knots_v,
            count_u,
            count_v,
            points,
            weights,
            hpoints,
            cache: None,
        };
        patch.cache = SpanCache::build(&patch);
        Ok(patch)
    }

    /// Degrees `(p, q)`.
    pub fn degrees(&self) -> (usize, usize) {
        (self.degree_u, self.degree_v)
    }
    /// Pole counts `(count_u, count_v)`.
    pub fn counts(&self) -> (usize, usize) {
        (self.count_u, self.count_v)
    }
    /// Knot vectors `(u, v)`.
    pub fn knots(&self) -> (&[f64], &[f64]) {
        (&self.knots_u, &self.knots_v)
    }
    /// Poles, v fastest.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }
    /// Weights of a NURBS patch.
    pub fn weights(&self) -> Option<&[f64]> {
        self.weights.as_deref()
    }
    /// The same patch evaluated by de Boor only (reference for the span cache).
    #[cfg(test)]
    fn without_cache(&self) -> Self {
        Self {
            cache: None,
            ..self.clone()
        }
    }

    /// The same surface with its parameters turned a quarter: `S'(s, t) = S(a + b − t, s)`
    /// (`[a, b]` the u domain), so the new u runs along the old v and the normal
    /// `S'_s × S'_t = S_u × S_v` is unchanged. A surface closed in v only is read this way round,
    /// so that its closed direction is u.
    pub fn turned(&self) -> Result<Self, SurfaceError> {
        let (nu, nv) = (self.count_u, self.count_v);
        let (a, b) = (self.knots_u[0], self.knots_u[self.knots_u.len() - 1]);
        let knots_v: Vec<f64> = self.knots_u.iter().rev().map(|&k| a + b - k).collect();
        // New pole (i', j') — i' along the new u (old v), j' along the new v (old u reversed).
        let at = |ip: usize, jp: usize| (nu - 1 - jp) * nv + ip;
        let points = (0..nv)
            .flat_map(|ip| (0..nu).map(move |jp| (ip, jp)))
            .map(|(ip, jp)| self.points[at(ip, jp)])
            .collect();
        let weights = self.weights.as_ref().map(|w| {
            (0..nv)
                .flat_map(|ip| (0..nu).map(move |jp| (ip, jp)))
                .map(|(ip, jp)| w[at(ip, jp)])
                .collect()
        });
        Self::new(
            self.degree_v,
            self.degree_u,
            self.knots_v.clone(),
            knots_v,
            nv,
            nu,
            points,
            weights,
        )
    }

    /// True for a rational patch.
    pub fn is_rational(&self) -> bool {
        self.weights.is_some()
    }

    /// Contracts the active poles with the basis derivatives for each requested (a, b) pair.
    #[inline(always)]
    fn contract<T: Pole, const N: usize, const K: usize>(
        &self,
        poles: &[T],
        u: f64,
        v: f64,
        nd: usize,
        pairs: &[(usize, usize); K],
    ) -> [T; K] {
        let (p, q) = (self.degree_u, self.degree_v);
        let su = basis::find_span(self.count_u, p, u, &self.knots_u);
        let sv = basis::find_span(self.count_v, q, v, &self.knots_v);
        let mut nu = [[0.0; N]; 3];
        let mut nv = [[0.0; N]; 3];
        basis::ders_basis_funs_fixed::<N>(&self.knots_u, su, p, u, nd, &mut nu);
        basis::ders_basis_funs_fixed::<N>(&self.knots_v, sv, q, v, nd, &mut nv);
        let mut out = [T::default(); K];
        // For each row i, the v-contractions of order 0..=nd, then blend along u.
        for i in 0..=p {
            let base = (su - p + i) * self.count_v + (sv - q);
            let row = &poles[base..base + q + 1];
            let mut rv = [T::default(); 3];
            for (j, pt) in row.iter().enumerate() {
                for b in 0..=nd {
                    rv[b] += *pt * nv[b][j];
                }
            }
            for (o, &(a, b)) in out.iter_mut().zip(pairs.iter()) {
                *o += rv[b] * nu[a][i];
            }
        }
        out
    }

    fn eval_pairs<const K: usize>(
        &self,
        u: f64,
        v: f64,
        nd: usize,
        pairs: &[(usize, usize); K],
    ) -> [DVec3; K] {
        let pmax = self.degree_u.max(self.degree_v);
        let (p, q) = (self.degree_u, self.degree_v);
        if self.weights.is_none() {
            if let Some(c) = &self.cache {
                if K == 3 && p == 3 && q == 3 {
                    // The tessellation hot path: straight-line bicubic point + first partials.
                    let (pt, su, sv) = c.bicubic_d1(u, v);
                    let mut out = [DVec3::ZERO; K];
                    out[0] = pt;
                    out[1] = su;
                    out[2] = sv;
                    return out;
                }
                return c.dispatch::<DVec3, K>(&c.poles, p, q, u, v, pairs);
            }
            return if pmax < 4 {
                self.contract::<DVec3, 4, K>(&self.points, u, v, nd, pairs)
            } else if pmax < 8 {
                self.contract::<DVec3, 8, K>(&self.points, u, v, nd, pairs)
            } else {
                self.contract::<DVec3, { MAX_DEGREE + 1 }, K>(&self.points, u, v, nd, pairs)
            };
        }
        let h: [DVec4; K] = if let Some(c) = &self.cache {
            c.dispatch::<DVec4, K>(&c.hpoles, p, q, u, v, pairs)
        } else if pmax < 4 {
            self.contract::<DVec4, 4, K>(&self.hpoints, u, v, nd, pairs)
        } else if pmax < 8 {
            self.contract::<DVec4, 8, K>(&self.hpoints, u, v, nd, pairs)
        } else {
            self.contract::<DVec4, { MAX_DEGREE + 1 }, K>(&self.hpoints, u, v, nd, pairs)
        };
        // Quotient rule; pairs are ordered (0,0),(1,0),(0,1)[,(2,0),(1,1),(0,2)].
        let mut out = [DVec3::ZERO; K];
        let w = h[0].w;
        let inv = 1.0 / w;
        let s = h[0].truncate() * inv;
        out[0] = s;
        if K >= 3 {
            let (wu, wv) = (h[1].w, h[2].w);
            let su = (h[1].truncate() - s * wu) * inv;
            let sv = (h[2].truncate() - s * wv) * inv;
            out[1] = su;
            out[2] = sv;
            if K >= 6 {
                let (wuu, wuv, wvv) = (h[3].w, h[4].w, h[5].w);
                out[3] = (h[3].truncate() - su * (2.0 * wu) - s * wuu) * inv;
                out[4] = (h[4].truncate() - s * wuv - sv * wu - su * wv) * inv;
                out[5] = (h[5].truncate() - sv * (2.0 * wv) - s * wvv) * inv;
            }
        }
        out
    }

    /// A surface of revolution about the z axis through `center`: the rational profile
    /// `(r_i, z_i)` with weights `pw_i` in u, revolved by the full rational quadratic circle in v
    /// (nine poles, weights 1, √2/2, …). Poles `P_ij = center + (r_i x_j, r_i y_j, z_i)`,
    /// weights `pw_i · cw_j`.
    pub fn revolve(
        center: DVec3,
        degree_u: usize,
        knots_u: Vec<f64>,
        profile: &[(f64, f64)],
        profile_weights: &[f64],
    ) -> Result<Self, SurfaceError> {
        let s = QUARTER_WEIGHT;
        let circle: [(f64, f64, f64); 9] = [
            (1.0, 0.0, 1.0),
            (1.0, 1.0, s),
            (0.0, 1.0, 1.0),
            (-1.0, 1.0, s),
            (-1.0, 0.0, 1.0),
            (-1.0, -1.0, s),
            (0.0, -1.0, 1.0),
            (1.0, -1.0, s),
            (1.0, 0.0, 1.0),
        ];
        let knots_v = vec![
            0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
        ];
        Self::revolve_with(
            center,
            degree_u,
            knots_u,
            profile,
            profile_weights,
            &circle,
            knots_v,
        )
    }

    fn revolve_with(
        center: DVec3,
        degree_u: usize,
        knots_u: Vec<f64>,
        profile: &[(f64, f64)],
        profile_weights: &[f64],
        circle: &[(f64, f64, f64)],
        knots_v: Vec<f64>,
    ) -> Result<Self, SurfaceError> {
        if profile.len() != profile_weights.len() {
            return Err(SurfaceError::ProfileWeightCount {
                points: profile.len(),
                weights: profile_weights.len(),
            });
        }
        let mut pts = Vec::with_capacity(profile.len() * circle.len());
        let mut w = Vec::with_capacity(pts.capacity());
        for (&(r, z), &pw) in profile.iter().zip(profile_weights) {
            for &(x, y, cw) in circle {
                pts.push(center + DVec3::new(r * x, r * y, z));
                w.push(pw * cw);
            }
        }
        Self::new(
            degree_u,
            2,
            knots_u,
            knots_v,
            profile.len(),
            circle.len(),
            pts,
            Some(w),
        )
    }

    fn check_positive(what: &'static str, x: f64) -> Result<(), SurfaceError> {
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(SurfaceError::NotPositive {
                what: what.to_string(),
                value: x,
            })
        }
    }

    /// The exact sphere: u runs from the south pole (u = 0) to the north pole (u = 1) along a
    /// rational semicircle, v once around the z axis.
    pub fn sphere(center: DVec3, radius: f64) -> Result<Self, SurfaceError> {
        Self::check_positive("sphere radius", radius)?;
        let r = radius;
        let s = QUARTER_WEIGHT;
        Self::revolve(
            center,
            2,
            vec![0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0],
            &[(0.0, -r), (r, -r), (r, 0.0), (r, r), (0.0, r)],
            &[1.0, s, 1.0, s, 1.0],
        )
    }

    /// The exact first octant of a sphere as one biquadratic rational Bézier patch (TV37): u from
    /// the equator to the north pole, v from the +x to the +y direction.
    pub fn sphere_octant(center: DVec3, radius: f64) -> Result<Self, SurfaceError> {
        Self::check_positive("sphere radius", radius)?;
        let r = radius;
        let s = QUARTER_WEIGHT;
        let quarter = [(1.0, 0.0, 1.0), (1.0, 1.0, s), (0.0, 1.0, 1.0)];
        Self::revolve_with(
            center,
            2,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            &[(r, 0.0), (r, r), (0.0, r)],
            &[1.0, s, 1.0],
            &quarter,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        )
    }

    /// The exact circular cylinder of the given radius around the z axis through `base`, from
    /// `z = base.z` (u = 0) to `z = base.z + height` (u = 1).
    pub fn cylinder(base: DVec3, radius: f64, height: f64) -> Result<Self, SurfaceError> {
        Self::check_positive("cylinder radius", radius)?;
        Self::check_positive("cylinder height", height)?;
        Self::revolve(
            base,
            1,
            vec![0.0, 0.0, 1.0, 1.0],
            &[(radius, 0.0), (radius, height)],
            &[1.0, 1.0],
        )
    }

    /// The exact right circular cone (frustum) around the z axis through `base`: radius
    /// `base_radius` at u = 0 (z = base.z), `top_radius` at u = 1 (z = base.z + height). A zero
    /// top radius gives the cone with its apex (a degenerate, singular edge).
    pub fn cone(
        base: DVec3,
        base_radius: f64,
        top_radius: f64,
        height: f64,
    ) -> Result<Self, SurfaceError> {
        Self::check_positive("cone base radius", base_radius)?;
        Self::check_positive("cone height", height)?;
        if !(top_radius.is_finite() && top_radius >= 0.0) {
            return Err(SurfaceError::Negative {
                what: "cone top radius",
                value: top_radius,
            });
        }
        Self::revolve(
            base,
            1,
            vec![0.0, 0.0, 1.0, 1.0],
            &[(base_radius, 0.0), (top_radius, height)],
            &[1.0, 1.0],
        )
    }

    /// The exact torus around the z axis through `center`: tube of radius `minor` whose centre
    /// circle has radius `major > minor`. u runs around the tube starting on the outer equator,
    /// v around the axis.
    pub fn torus(center: DVec3, major: f64, minor: f64) -> Result<Self, SurfaceError> {
        Self::check_positive("torus major radius", major)?;
        Self::check_positive("torus minor radius", minor)?;
        if minor >= major {
            return Err(SurfaceError::TorusRadii { major, minor });
        }
        let s = QUARTER_WEIGHT;
        let c: [(f64, f64); 9] = [
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (-1.0, 1.0),
            (-1.0, 0.0),
            (-1.0, -1.0),
            (0.0, -1.0),
            (1.0, -1.0),
            (1.0, 0.0),
        ];
        let profile: Vec<(f64, f64)> = c
            .iter()
            .map(|&(x, y)| (major + minor * x, minor * y))
            .collect();
        Self::revolve(
            center,
            2,
            vec![
                0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
            ],
            &profile,
            &[1.0, s, 1.0, s, 1.0, s, 1.0, s, 1.0],
        )
    }
}

impl ParamSurface for BSplinePatch {
    fn domain(&self) -> Domain2 {
        Domain2 {
            u: (self.knots_u[self.degree_u], self.knots_u[self.count_u]),
            v: (self.knots_v[self.degree_v], self.knots_v[self.count_v]),
        }
    }

    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.eval_pairs(u, v, 0, &[(0, 0)])[0]
    }

    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let [p, su, sv] = self.eval_pairs(u, v, 1, &D1_PAIRS);
        (p, su, sv)
    }

    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        let [p, su, sv, suu, suv, svv] = self.eval_pairs(u, v, 2, &D2_PAIRS);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::BezierPatch;
    use crate::patch::testutil::check_derivs_fd;
    use proptest::prelude::*;

    fn wavy() -> BSplinePatch {
        // The 10×10 bicubic patch of the OpenCASCADE benchmark (surfaces_def.py).
        let xs: Vec<f64> = (0..10).map(|i| -100.0 + 200.0 * i as f64 / 9.0).collect();
        let mut pts = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                let z = 20.0
                    * (std::f64::consts::PI * i as f64 / 3.0).sin()
                    * (std::f64::consts::PI * j as f64 / 4.0).cos();
                pts.push(DVec3::new(xs[i], xs[j], z));
            }
        }
        let mut k = vec![0.0; 3];
        k.extend((0..8).map(|i| i as f64 / 7.0));
        k.extend([1.0; 3]);
        BSplinePatch::new(3, 3, k.clone(), k, 10, 10, pts, None).unwrap()
    }

    #[test]
    fn validation_names_the_problem() {
        let pts = vec![DVec3::ZERO; 9];
        let k = vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let e = BSplinePatch::new(
            2,
            2,
            vec![0.0, 0.0, 0.0, 1.0, 1.0],
            k.clone(),
            3,
            3,
            pts.clone(),
            None,
        )
        .unwrap_err();
        assert_eq!(
            e,
            SurfaceError::KnotCount {
                expected: 6,
                got: 5
            }
        );
        let e = BSplinePatch::new(
            2,
            2,
            vec![0.0, 0.0, 0.5, 0.2, 1.0, 1.0],
            k.clone(),
            3,
            3,
            pts.clone(),
            None,
        )
        .unwrap_err();
        assert!(matches!(e, SurfaceError::DecreasingKnots { index: 3, .. }));
        let mut w = vec![1.0; 9];
        w[5] = 0.0;
        let e =
            BSplinePatch::new(2, 2, k.clone(), k.clone(), 3, 3, pts.clone(), Some(w)).unwrap_err();
        assert_eq!(
            e,
            SurfaceError::BadWeight {
                index: 5,
                value: 0.0
            }
        );
        let e = BSplinePatch::new(
            0,
            2,
            vec![0.0, 1.0, 2.0, 3.0],
            k.clone(),
            3,
            3,
            pts.clone(),
            None,
        )
        .unwrap_err();
        assert!(matches!(e, SurfaceError::BadDegree { degree: 0, .. }));
        let e = BSplinePatch::sphere(DVec3::ZERO, -1.0).unwrap_err();
        assert!(e.to_string().contains("sphere radius"));
        let e = BSplinePatch::torus(DVec3::ZERO, 1.0, 2.0).unwrap_err();
        assert!(e.to_string().contains("minor radius"));
    }

    #[test]
    fn tv24_uniform_biquadratic() {
        let mut pts = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                let z = if i == 1 && j == 1 { 1.0 } else { 0.0 };
                pts.push(DVec3::new(i as f64, j as f64, z));
            }
        }
        let k: Vec<f64> = (0..6).map(|x| x as f64).collect();
        let s = BSplinePatch::new(2, 2, k.clone(), k, 3, 3, pts, None).unwrap();
        assert_eq!(
            s.domain(),
            Domain2 {
                u: (2.0, 3.0),
                v: (2.0, 3.0)
            }
        );
        let exact = |u: f64, w: f64| {
            DVec3::new(
                u + 0.5,
                w + 0.5,
                (2.0 * u * u - 2.0 * u - 1.0) * (2.0 * w * w - 2.0 * w - 1.0) / 4.0,
            )
        };
        for &(u, w) in &[
            (0.0, 0.0),
            (0.0, 1.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.5, 0.5),
            (0.3, 0.8),
        ] {
            assert!(
                (s.eval(2.0 + u, 2.0 + w) - exact(u, w)).length() < 1e-14,
                "({u},{w})"
            );
        }
        assert!((s.eval(2.5, 2.5) - DVec3::new(1.0, 1.0, 9.0 / 16.0)).length() < 1e-15);
        assert!((s.eval(2.0, 2.0) - DVec3::new(0.5, 0.5, 0.25)).length() < 1e-15);
        check_derivs_fd(&s, 1e-6);
    }

    #[test]
    fn tv37_sphere_octant_is_exact() {
        let s = BSplinePatch::sphere_octant(DVec3::ZERO, 1.0).unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((s.eval(0.5, 0.5) - DVec3::new(0.5, 0.5, h)).length() < 1e-10);
        let q = DVec3::new(0.8645062848, 0.3422501546, 0.3680947096);
        assert!((s.eval(0.25, 0.25) - q).length() < 1e-10);
        for i in 0..=20 {
            for j in 0..=20 {
                let p = s.eval(i as f64 / 20.0, j as f64 / 20.0);
                assert!((p.length() - 1.0).abs() < 1e-14);
            }
        }
        check_derivs_fd(&s, 1e-6);
    }

    #[test]
    fn exact_primitives_lie_on_their_quadrics() {
        let c = DVec3::new(1.0, -2.0, 3.0);
        let sphere = BSplinePatch::sphere(c, 2.5).unwrap();
        let cyl = BSplinePatch::cylinder(c, 2.0, 5.0).unwrap();
        let cone = BSplinePatch::cone(c, 3.0, 1.0, 4.0).unwrap();
        let torus = BSplinePatch::torus(c, 5.0, 1.5).unwrap();
        for i in 0..=16 {
            for j in 0..=16 {
                let (u, v) = (i as f64 / 16.0, j as f64 / 16.0);
                let p = sphere.eval(u, v) - c;
                assert!((p.length() - 2.5).abs() < 1e-13);
                let p = cyl.eval(u, v) - c;
                assert!((p.truncate().length() - 2.0).abs() < 1e-13);
                assert!((p.z - 5.0 * u).abs() < 1e-13);
                let p = cone.eval(u, v) - c;
                assert!((p.truncate().length() - (3.0 - 2.0 * p.z / 4.0)).abs() < 1e-13);
                let p = torus.eval(u, v) - c;
                let rho = p.truncate().length() - 5.0;
                assert!((rho.hypot(p.z) - 1.5).abs() < 1e-13);
            }
        }
        // Ends: poles of the sphere.
        assert!((sphere.eval(0.0, 0.3) - (c - DVec3::Z * 2.5)).length() < 1e-13);
        assert!((sphere.eval(1.0, 0.7) - (c + DVec3::Z * 2.5)).length() < 1e-13);
        for s in [&sphere, &cyl, &cone, &torus] {
            check_derivs_fd(s, 1e-6);
        }
    }

    #[test]
    fn bspline_with_bezier_knots_is_the_bezier_patch() {
        let bz = BezierPatch::new(
            3,
            2,
            (0..12)
                .map(|k| DVec3::new((k / 3) as f64, (k % 3) as f64, ((k * 7) % 5) as f64 * 0.3))
                .collect(),
        )
        .unwrap();
        let bs = BSplinePatch::new(
            3,
            2,
            vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            4,
            3,
            bz.points().to_vec(),
            None,
        )
        .unwrap();
        for &(u, v) in &[(0.0, 0.0), (0.3, 0.6), (1.0, 1.0), (0.99, 0.01)] {
            let (a, b) = (bz.deriv2(u, v), bs.deriv2(u, v));
            assert!((a.p - b.p).length() < 1e-13);
            assert!((a.su - b.su).length() < 1e-12);
            assert!((a.suv - b.suv).length() < 1e-11);
            assert!((a.svv - b.svv).length() < 1e-11);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        check_derivs_fd(&wavy(), 1e-5);
        // A rational patch with non-uniform weights and a degree-5 direction.
        let mut pts = Vec::new();
        let mut w = Vec::new();
        for i in 0..7 {
            for j in 0..4 {
                pts.push(DVec3::new(i as f64, j as f64, ((i * j) % 3) as f64));
                w.push(0.5 + ((i + 2 * j) % 4) as f64 * 0.4);
            }
        }
        let ku = vec![
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.4, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
        ];
        let kv = vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0];
        let s = BSplinePatch::new(5, 2, ku, kv, 7, 4, pts, Some(w)).unwrap();
        check_derivs_fd(&s, 1e-5);
    }

    fn assert_cache_matches(s: &BSplinePatch) {
        let r = s.without_cache();
        let d = s.domain();
        for i in 0..=13 {
            for j in 0..=11 {
                let u = d.u.0 + (d.u.1 - d.u.0) * i as f64 / 13.0;
                let v = d.v.0 + (d.v.1 - d.v.0) * j as f64 / 11.0;
                let (a, b) = (s.deriv2(u, v), r.deriv2(u, v));
                let sc = 1.0 + b.p.length() + b.su.length() + b.sv.length();
                let sc2 = sc + b.suu.length() + b.suv.length() + b.svv.length();
                assert!(
                    (a.p - b.p).length() < 1e-12 * sc,
                    "p at ({u},{v}): {} vs {}",
                    a.p,
                    b.p
                );
                assert!((a.su - b.su).length() < 1e-11 * sc);
                assert!((a.sv - b.sv).length() < 1e-11 * sc);
                assert!((a.suu - b.suu).length() < 1e-10 * sc2);
                assert!((a.suv - b.suv).length() < 1e-10 * sc2);
                assert!((a.svv - b.svv).length() < 1e-10 * sc2);
                let (p1, su1, sv1) = s.deriv1(u, v);
                assert!((p1 - a.p).length() < 1e-12 * sc && (su1 - a.su).length() < 1e-11 * sc);
                assert!((sv1 - a.sv).length() < 1e-11 * sc);
            }
        }
    }

    #[test]
    fn span_cache_equals_de_boor() {
        assert!(wavy().cache.is_some());
        assert_cache_matches(&wavy());
        for s in [
            BSplinePatch::sphere(DVec3::ONE, 2.0).unwrap(),
            BSplinePatch::torus(DVec3::ZERO, 3.0, 1.0).unwrap(),
            BSplinePatch::cone(DVec3::ZERO, 3.0, 1.0, 2.0).unwrap(),
        ] {
            assert!(s.cache.is_some());
            assert_cache_matches(&s);
        }
        // Unclamped uniform knots (TV24) and repeated interior knots, mixed degrees.
        let pts: Vec<DVec3> = (0..30)
            .map(|k| DVec3::new((k / 5) as f64, (k % 5) as f64, ((k * 7) % 11) as f64 * 0.1))
            .collect();
        let ku = vec![0.0, 0.5, 1.0, 2.0, 2.0, 3.0, 4.5, 5.0, 6.0];
        let kv = vec![0.0, 0.0, 0.0, 0.0, 0.3, 1.0, 1.0, 1.0, 1.0];
        let s = BSplinePatch::new(2, 3, ku.clone(), kv.clone(), 6, 5, pts.clone(), None).unwrap();
        assert_cache_matches(&s);
        let w: Vec<f64> = (0..30).map(|k| 0.5 + (k % 4) as f64 * 0.3).collect();
        let s = BSplinePatch::new(2, 3, ku, kv, 6, 5, pts, Some(w)).unwrap();
        assert_cache_matches(&s);
        let k1 = vec![0.0, 0.0, 0.4, 0.7, 1.0, 1.0];
        let pts: Vec<DVec3> = (0..16)
            .map(|k| DVec3::new((k / 4) as f64, (k % 4) as f64, (k % 3) as f64))
            .collect();
        let s = BSplinePatch::new(1, 1, k1.clone(), k1, 4, 4, pts, None).unwrap();
        assert_cache_matches(&s);
    }

    proptest! {
        #[test]
        fn partition_of_unity_and_affine_invariance(u in 0.0f64..1.0, v in 0.0f64..1.0, dz in -10.0f64..10.0) {
            // Translating every pole (equal weights per row are irrelevant: rational basis also sums to 1).
            let s = BSplinePatch::torus(DVec3::ZERO, 4.0, 1.0).unwrap();
            let t = BSplinePatch::torus(DVec3::new(0.0, 0.0, dz), 4.0, 1.0).unwrap();
            prop_assert!((t.eval(u, v) - s.eval(u, v) - DVec3::new(0.0, 0.0, dz)).length() < 1e-12);
            let w = wavy();
            let shifted = BSplinePatch::new(3, 3, w.knots_u.clone(), w.knots_v.clone(), 10, 10,
                w.points.iter().map(|p| *p + DVec3::new(1.0, 2.0, dz)).collect(), None).unwrap();
            prop_assert!((shifted.eval(u, v) - w.eval(u, v) - DVec3::new(1.0, 2.0, dz)).length() < 1e-11);
        }
    }
    #[test]
    fn a_turned_patch_is_the_same_surface_with_the_same_normal() {
        // A bicubic NURBS patch with uneven knots: S'(s, t) = S(a + b - t, s).
        let (nu, nv) = (5, 4);
        let points: Vec<DVec3> = (0..nu)
            .flat_map(|i| (0..nv).map(move |j| (i, j)))
            .map(|(i, j)| {
                DVec3::new(
                    i as f64 * 10.0,
                    j as f64 * 7.0,
                    ((i * 3 + j * 5) % 7) as f64,
                )
            })
            .collect();
        let weights: Vec<f64> = (0..nu * nv).map(|k| 1.0 + 0.1 * (k % 3) as f64).collect();
        let p = BSplinePatch::new(
            3,
            2,
            vec![0.0, 0.0, 0.0, 0.0, 0.3, 1.0, 1.0, 1.0, 1.0],
            vec![2.0, 2.0, 2.0, 2.5, 3.0, 3.0, 3.0],
            nu,
            nv,
            points,
            Some(weights),
        )
        .unwrap();
        let q = p.turned().unwrap();
        for (u, v) in [(0.1, 2.2), (0.5, 2.9), (0.95, 2.5), (0.3, 2.0)] {
            let (s, t) = (v, 1.0 - u);
            assert!(q.eval(s, t).distance(p.eval(u, v)) < 1e-12);
            let (_, pu, pv) = p.deriv1(u, v);
            let (_, qs, qt) = q.deriv1(s, t);
            assert!((qs.cross(qt) - pu.cross(pv)).length() < 1e-9 * pu.cross(pv).length());
        }
    }
}
