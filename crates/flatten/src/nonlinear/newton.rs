//! Flip-free projected Newton for isotropic distortion energies, as an argmin [`Solver`].
//!
//! Each iteration assembles the area-weighted gradient and the per-triangle analytically
//! eigen-projected Hessian (see [`super::kernel`]) into a fixed-pattern sparse matrix, solves the
//! Newton system with a sparse Cholesky whose symbolic factorisation is computed once
//! ([`super::spd`]), bounds the step before the first triangle inverts (smallest positive root
//! of det J(t) = 0 per triangle, Smith & Schaefer 2015) and backtracks to an Armijo decrease.
//! Every iterate is therefore flip-free if the start is.
//!
//! argmin drives the loop (termination, iteration cap, observers); the heavy work is our own on
//! `Vec<f64>` parameters (crates.md §2: argmin has no sparse Hessians).

use argmin::core::{
    Error as ArgminError, Executor, IterState, KV, Problem, Solver, State, TerminationReason,
    TerminationStatus, observers::Observe, observers::ObserverMode,
};
use flatcut_geom::DVec2;

use super::kernel::{IsoEnergy, RestTri, max_step_tri, tri_energy, tri_eval};
use super::spd::SpdSystem;

/// Fraction of the distance to the first inversion taken as the largest trial step
/// (SLIM uses 0.8; closer than that, the barrier makes the energy explode anyway).
pub(crate) const INVERSION_STEP_FRACTION: f64 = 0.9;
/// Armijo sufficient-decrease constant.
pub(crate) const ARMIJO_C: f64 = 1e-4;
/// Backtracking halvings before the line search gives up (step 2⁻⁶⁰ is below round-off).
pub(crate) const MAX_HALVINGS: usize = 60;
/// Diagonal regularisation relative to the mean Hessian diagonal: removes the rigid-motion null
/// space of the projected Hessian without changing the step measurably.
pub(crate) const REG_REL: f64 = 1e-9;

/// A boundary-length term for the augmented Lagrangian of the boundary-isometric method:
/// L²·(λ c + w c²/2) with c = (|x_b − x_a|² − L²)/L².
#[derive(Clone, Debug)]
pub struct EdgeTerms {
    /// (a, b, rest length L).
    pub edges: Vec<(usize, usize, f64)>,
    /// Lagrange multipliers, one per edge.
    pub lambda: Vec<f64>,
    /// Penalty weight w.
    pub weight: f64,
}

impl EdgeTerms {
    /// Constraint value c_e.
    pub fn constraint(&self, e: usize, x: &[DVec2]) -> f64 {
        let (a, b, l) = self.edges[e];
        ((x[b] - x[a]).length_squared() - l * l) / (l * l)
    }
    fn energy(&self, x: &[DVec2]) -> f64 {
        let mut s = 0.0;
        for e in 0..self.edges.len() {
            let l = self.edges[e].2;
            let c = self.constraint(e, x);
            s += l * l * (self.lambda[e] * c + 0.5 * self.weight * c * c);
        }
        s
    }
}

/// The energy of a map: Σ_t A_t Ψ(σ(J_t)) (+ optional boundary-length terms), with the sparse
/// Newton system.
pub struct MapProblem<'a, E> {
    pub rest: &'a [RestTri],
    pub energy: E,
    pub edges: Option<EdgeTerms>,
    n: usize,
    sys: SpdSystem,
    /// Per triangle: slot of local dof pair (p, q) in `sys.values`, `u32::MAX` if mirrored.
    tri_slots: Vec<[u32; 36]>,
    edge_slots: Vec<[u32; 16]>,
    /// Σ A_t, to report mean densities.
    pub total_area: f64,
}

fn slots_for(sys: &SpdSystem, dofs: &[usize]) -> Vec<u32> {
    let k = dofs.len();
    let mut out = vec![u32::MAX; k * k];
    for p in 0..k {
        for q in 0..k {
            let (r, c) = (dofs[p], dofs[q]);
            // Each unordered pair is added once, from its upper-triangle (row ≤ col) side; the
            // dofs of one element are distinct, so r == c only on the diagonal.
            if r <= c {
                if let Some(s) = sys.slot(r, c) {
                    out[p * k + q] = s as u32;
                }
            }
        }
    }
    out
}

impl<'a, E: IsoEnergy> MapProblem<'a, E> {
    /// Builds the problem and the symbolic factorisation for `n` vertices.
    pub fn new(
        rest: &'a [RestTri],
        n: usize,
        energy: E,
        edges: Option<EdgeTerms>,
    ) -> Result<Self, String> {
        let mut entries = Vec::with_capacity(rest.len() * 21);
        for r in rest {
            for &a in &r.v {
                for &b in &r.v {
                    for i in 0..2 {
                        for j in 0..2 {
                            entries.push((2 * a + i, 2 * b + j));
                        }
                    }
                }
            }
        }
        let sys = SpdSystem::new(2 * n, entries)?;
        let tri_slots = rest
            .iter()
            .map(|r| {
                let d = [
                    2 * r.v[0],
                    2 * r.v[0] + 1,
                    2 * r.v[1],
                    2 * r.v[1] + 1,
                    2 * r.v[2],
                    2 * r.v[2] + 1,
                ];
                let s = slots_for(&sys, &d);
                let mut a = [u32::MAX; 36];
                a.copy_from_slice(&s);
                a
            })
            .collect();
        let edge_slots = edges
            .as_ref()
            .map(|e| {
                e.edges
                    .iter()
                    .map(|&(a, b, _)| {
                        let s = slots_for(&sys, &[2 * a, 2 * a + 1, 2 * b, 2 * b + 1]);
                        let mut o = [u32::MAX; 16];
                        o.copy_from_slice(&s);
                        o
                    })
                    .collect()
            })
            .unwrap_or_default();
        let total_area = rest.iter().map(|r| r.area).sum();
        Ok(Self {
            rest,
            energy,
            edges,
            n,
            sys,
            tri_slots,
            edge_slots,
            total_area,
        })
    }

    /// Total energy (+∞ if a barrier energy sees an inverted triangle).
    pub fn total_energy(&self, x: &[DVec2]) -> f64 {
        let mut s = 0.0;
        for r in self.rest {
            s += tri_energy(&self.energy, r, x);
        }
        if let Some(e) = &self.edges {
            s += e.energy(x);
        }
        s
    }

    /// Largest step along `d` before any triangle inverts.
    pub fn max_step(&self, x: &[DVec2], d: &[DVec2]) -> f64 {
        self.rest
            .iter()
            .map(|r| max_step_tri(r, x, d))
            .fold(f64::INFINITY, f64::min)
    }

    /// Assembles gradient (returned) and the projected Hessian (into the system); returns the
    /// energy too.
    fn assemble(&mut self, x: &[DVec2]) -> (f64, Vec<f64>) {
        let mut g = vec![0.0; 2 * self.n];
        self.sys.clear();
        let mut en = 0.0;
        for (t, r) in self.rest.iter().enumerate() {
            let ev = tri_eval(&self.energy, r, x, true);
            en += ev.energy;
            for k in 0..3 {
                g[2 * r.v[k]] += ev.grad[k].x;
                g[2 * r.v[k] + 1] += ev.grad[k].y;
            }
            let slots = &self.tri_slots[t];
            for p in 0..6 {
                for q in 0..6 {
                    let s = slots[p * 6 + q];
                    if s != u32::MAX {
                        self.sys.values[s as usize] += ev.hess[p][q];
                    }
                }
            }
        }
        if let Some(e) = &self.edges {
            for (k, &(a, b, l)) in e.edges.iter().enumerate() {
                let d = x[b] - x[a];
                let c = e.constraint(k, x);
                en += l * l * (e.lambda[k] * c + 0.5 * e.weight * c * c);
                let m = e.lambda[k] + e.weight * c;
                let gd = 2.0 * m * d;
                g[2 * a] -= gd.x;
                g[2 * a + 1] -= gd.y;
                g[2 * b] += gd.x;
                g[2 * b + 1] += gd.y;
                // Hessian w.r.t. d: 4w d dᵀ/L² + 2 max(m, 0) I.
                let dd = [d.x, d.y];
                let mut h = [[0.0; 2]; 2];
                for i in 0..2 {
                    for j in 0..2 {
                        h[i][j] = 4.0 * e.weight * dd[i] * dd[j] / (l * l)
                            + if i == j { 2.0 * m.max(0.0) } else { 0.0 };
                    }
                }
                let slots = &self.edge_slots[k];
                for p in 0..4 {
                    for q in 0..4 {
                        let s = slots[p * 4 + q];
                        if s != u32::MAX {
                            let sign = if (p < 2) == (q < 2) { 1.0 } else { -1.0 };
                            self.sys.values[s as usize] += sign * h[p % 2][q % 2];
                        }
                    }
                }
            }
        }
        (en, g)
    }
}

/// Converts interleaved coordinates to points.
pub fn to_points(p: &[f64]) -> Vec<DVec2> {
    p.chunks_exact(2).map(|c| DVec2::new(c[0], c[1])).collect()
}

/// Converts points to interleaved coordinates.
pub fn to_flat(x: &[DVec2]) -> Vec<f64> {
    x.iter().flat_map(|p| [p.x, p.y]).collect()
}

/// Projected Newton with the flip-free line search.
#[derive(Clone, Debug)]
pub struct ProjectedNewton {
    /// Stop when the energy decreases by less than this fraction in one iteration.
    pub rel_tolerance: f64,
    /// Stop when the Newton decrement −g·d/2 falls below this (absolute, energy units).
    pub abs_tolerance: f64,
    last_decrease: f64,
    last_decrement: f64,
    stalled: bool,
}

impl ProjectedNewton {
    pub fn new(rel_tolerance: f64, abs_tolerance: f64) -> Self {
        Self {
            rel_tolerance,
            abs_tolerance,
            last_decrease: f64::INFINITY,
            last_decrement: f64::INFINITY,
            stalled: false,
        }
    }
}

type NState = IterState<Vec<f64>, (), (), (), (), f64>;

impl<E: IsoEnergy> Solver<MapProblem<'_, E>, NState> for ProjectedNewton {
    fn name(&self) -> &str {
        "flip-free projected Newton"
    }

    fn init(
        &mut self,
        problem: &mut Problem<MapProblem<'_, E>>,
        state: NState,
    ) -> Result<(NState, Option<KV>), ArgminError> {
        let p = problem
            .problem
            .as_ref()
            .ok_or_else(|| argmin::core::Error::msg("no problem"))?;
        let x0 = state
            .get_param()
            .ok_or_else(|| argmin::core::Error::msg("no initial map"))?;
        let e = p.total_energy(&to_points(x0));
        if !e.is_finite() {
            return Err(argmin::core::Error::msg(
                "the initial map has an inverted or degenerate triangle",
            ));
        }
        Ok((state.cost(e), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<MapProblem<'_, E>>,
        mut state: NState,
    ) -> Result<(NState, Option<KV>), ArgminError> {
        let p = problem
            .problem
            .as_mut()
            .ok_or_else(|| argmin::core::Error::msg("no problem"))?;
        let xf = state
            .take_param()
            .ok_or_else(|| argmin::core::Error::msg("no parameter"))?;
        let x = to_points(&xf);
        let (e0, g) = p.assemble(&x);
        let ndof = g.len();
        let mean_diag = (0..ndof)
            .map(|i| p.sys.values[p.sys.diag_slot(i)])
            .sum::<f64>()
            / ndof as f64;
        let base: Vec<f64> = p.sys.values.clone();
        let mut reg = REG_REL * mean_diag.max(f64::MIN_POSITIVE);
        let mut dir = Vec::new();
        for _ in 0..8 {
            p.sys.values.copy_from_slice(&base);
            for i in 0..ndof {
                let s = p.sys.diag_slot(i);
                p.sys.values[s] += reg;
            }
            let mut rhs: Vec<f64> = g.iter().map(|v| -v).collect();
            if p.sys.factor_solve(&mut rhs).is_ok() && rhs.iter().all(|v| v.is_finite()) {
                dir = rhs;
                break;
            }
            reg *= 100.0;
        }
        let mut gd: f64 = g.iter().zip(&dir).map(|(a, b)| a * b).sum();
        if dir.is_empty() || !(gd < 0.0) {
            // Fall back to steepest descent (should not happen with a PSD Hessian).
            dir = g.iter().map(|v| -v).collect();
            gd = -g.iter().map(|v| v * v).sum::<f64>();
        }
        let d = to_points(&dir);
        let tmax = p.max_step(&x, &d);
        let mut t = (INVERSION_STEP_FRACTION * tmax).min(1.0);
        let mut xn = x.clone();
        let mut en = f64::INFINITY;
        let mut accepted = false;
        for _ in 0..MAX_HALVINGS {
            for (k, q) in xn.iter_mut().enumerate() {
                *q = x[k] + t * d[k];
            }
            en = p.total_energy(&xn);
            if en.is_finite() && en <= e0 + ARMIJO_C * t * gd {
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        self.last_decrement = -0.5 * gd;
        if !accepted || !(en < e0) {
            self.stalled = true;
            return Ok((state.param(xf).cost(e0), None));
        }
        self.last_decrease = e0 - en;
        // argmin's key-value record is a HashMap inside argmin; only observers read it, never
        // the iterates, so its order cannot reach any output.
        #[allow(clippy::disallowed_types)]
        let kv = argmin::kv!("step" => t; "tmax" => tmax; "decrement" => self.last_decrement;);
        Ok((state.param(to_flat(&xn)).cost(en), Some(kv)))
    }

    fn terminate(&mut self, state: &NState) -> TerminationStatus {
        if self.stalled {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        let e = state.get_cost();
        if state.get_iter() > 0
            && (self.last_decrease <= self.rel_tolerance * e.abs()
                || self.last_decrement <= self.abs_tolerance)
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

/// Logs the progress of a solve through `tracing` (debug level).
#[derive(Clone, Copy, Debug, Default)]
pub struct TraceObserver;

impl Observe<NState> for TraceObserver {
    fn observe_iter(&mut self, state: &NState, kv: &KV) -> Result<(), ArgminError> {
        tracing::debug!(
            iter = state.get_iter(),
            energy = state.get_cost(),
            ?kv,
            "newton"
        );
        Ok(())
    }
}

/// Result of a Newton run.
pub struct NewtonRun {
    pub x: Vec<DVec2>,
    pub energy: f64,
    pub iterations: usize,
}

/// Runs projected Newton from the flip-free map `x0`.
pub fn run<'a, E: IsoEnergy>(
    problem: MapProblem<'a, E>,
    x0: &[DVec2],
    max_iters: usize,
    rel_tolerance: f64,
    abs_tolerance: f64,
) -> Result<(NewtonRun, MapProblem<'a, E>), String> {
    let solver = ProjectedNewton::new(rel_tolerance, abs_tolerance);
    let res = Executor::new(problem, solver)
        .configure(|s| s.param(to_flat(x0)).max_iters(max_iters as u64))
        .add_observer(TraceObserver, ObserverMode::Always)
        .timer(false)
        .run()
        .map_err(|e| e.to_string())?;
    let state = res.state();
    let iterations = state.get_iter() as usize;
    let energy = state.get_cost();
    let x = state
        .get_param()
        .map(|p| to_points(p))
        .ok_or_else(|| "no result".to_string())?;
    let mut res = res;
    let problem = res
        .problem
        .take_problem()
        .ok_or_else(|| "problem lost".to_string())?;
    Ok((
        NewtonRun {
            x,
            energy,
            iterations,
        },
        problem,
    ))
}
