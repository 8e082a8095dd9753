//! As-rigid-as-possible flattening (Liu, Zhang, Xu, Gotsman & Gortler 2008), local/global,
//! free boundary, flip-free.
//!
//! Energy `E = Σ_T A_T ‖J_T − R_T‖²_F` with `R_T` the rotation nearest the triangle's Jacobian.
//! The local step picks `R_T` in closed form (2×2 polar decomposition); the global step solves
//! the cotangent-Laplacian system `L u = b(R)`, whose matrix never changes, so it is factored
//! once. The start is LSCM (at true scale, honouring the pins), or Tutte's embedding when LSCM
//! folds. Every global step is a convex quadratic minimization, so any step `t ∈ (0, 1]`
//! towards its minimizer lowers the energy: when the full step would flip a triangle it is
//! halved until no triangle flips. Every iterate, and so the result, is flip-free.
//!
//! The loop runs as an argmin [`Solver`] under an argmin `Executor` (termination on the
//! relative energy decrease and the iteration cap); each iteration emits a `tracing` debug event
//! (target `flatcut_flatten`, fields `method`, `iteration`, `energy`) for progress display.

use crate::internal::InternalError;
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    Error, Executor, IterState, KV, Problem, Solver, State, TerminationReason, TerminationStatus,
};
use flatcut_geom::{DMat2, DVec2};
use flatcut_mesh::distortion::local_frame;
use flatcut_mesh::{Topology, TriMesh};

use crate::ops::{Reduced, corner_cotans, count_flips, laplace, orient2, used_mask};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method};

/// Halvings of the step before a global step is given up as stalled (2⁻⁴⁰ of a step is far
/// below round-off of any coordinate).
const MAX_HALVINGS: usize = 40;

type ArapState = IterState<Vec<f64>, (), (), (), (), f64>;

/// The fixed data of an ARAP problem: rest shapes, cotangent weights and areas.
#[derive(Debug)]
pub struct ArapProblem {
    triangles: Vec<[u32; 3]>,
    /// Rest corners of each triangle in its own orthonormal frame.
    rest: Vec<[DVec2; 3]>,
    /// Inverse of the rest edge matrix `[p1 − p0, p2 − p0]`.
    rest_inv: Vec<DMat2>,
    /// Cotangent of each corner (weight of the opposite edge).
    cot: Vec<[f64; 3]>,
    area: Vec<f64>,
}

impl ArapProblem {
    /// Precomputes the rest data of `mesh`.
    pub fn new(mesh: &TriMesh) -> Result<Self, FlattenError> {
        let mut rest = Vec::with_capacity(mesh.triangles.len());
        let mut rest_inv = Vec::with_capacity(mesh.triangles.len());
        for t in 0..mesh.triangles.len() {
            let p = mesh.corners(t);
            let (loc, _, _) = local_frame(p[0], p[1], p[2]).ok_or(FlattenError::Internal(
                InternalError::DegenerateTriangle { triangle: t },
            ))?;
            rest.push(loc);
            rest_inv.push(DMat2::from_cols(loc[1] - loc[0], loc[2] - loc[0]).inverse());
        }
        Ok(Self {
            triangles: mesh.triangles.clone(),
            rest,
            rest_inv,
            cot: corner_cotans(&mesh.positions, &mesh.triangles),
            area: (0..mesh.triangles.len())
                .map(|t| mesh.triangle_area(t))
                .collect(),
        })
    }

    fn jacobian(&self, t: usize, uv: &[f64]) -> DMat2 {
        let tri = self.triangles[t];
        let q = tri.map(|v| DVec2::new(uv[2 * v as usize], uv[2 * v as usize + 1]));
        DMat2::from_cols(q[1] - q[0], q[2] - q[0]) * self.rest_inv[t]
    }

    /// The rotation nearest each triangle's Jacobian (local step).
    pub fn rotations(&self, uv: &[f64]) -> Vec<DMat2> {
        (0..self.triangles.len())
            .map(|t| {
                let j = self.jacobian(t, uv);
                // argmax_θ tr(R(θ)ᵀ J) = atan2(J₁₀ − J₀₁, J₀₀ + J₁₁).
                let th = (j.x_axis.y - j.y_axis.x).atan2(j.x_axis.x + j.y_axis.y);
                DMat2::from_angle(th)
            })
            .collect()
    }

    /// `Σ_T A_T ‖J_T − R_T‖²_F` with the nearest rotations.
    pub fn energy(&self, uv: &[f64]) -> f64 {
        let rots = self.rotations(uv);
        (0..self.triangles.len())
            .map(|t| {
                let d = self.jacobian(t, uv) - rots[t];
                self.area[t] * (d.x_axis.length_squared() + d.y_axis.length_squared())
            })
            .sum()
    }

    /// Right-hand sides `b(R)` of the global step, per vertex, for x and y.
    fn rhs(&self, n: usize, rots: &[DMat2]) -> [Vec<f64>; 2] {
        let mut bx = vec![0.0; n];
        let mut by = vec![0.0; n];
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (ka, kb) = ((k + 1) % 3, (k + 2) % 3);
                let r = self.cot[t][k] * (rots[t] * (self.rest[t][ka] - self.rest[t][kb]));
                let (a, b) = (tri[ka] as usize, tri[kb] as usize);
                bx[a] += r.x;
                by[a] += r.y;
                bx[b] -= r.x;
                by[b] -= r.y;
            }
        }
        [bx, by]
    }

    fn flip_free(&self, uv: &[f64]) -> bool {
        self.triangles.iter().all(|t| {
            let p = t.map(|v| DVec2::new(uv[2 * v as usize], uv[2 * v as usize + 1]));
            orient2(p[0], p[1], p[2]) > 0.0
        })
    }
}

/// The local/global iteration as an argmin solver. Parameters are interleaved `[x0, y0, x1, …]`.
pub struct ArapSolver {
    sys: Reduced,
    /// Dirichlet values (pins) at fixed vertices, per coordinate.
    fixed_vals: [Vec<f64>; 2],
    rel_tolerance: f64,
    /// Global steps that had to be shortened to stay flip-free.
    pub shortened_steps: usize,
    /// True when a step could not be taken at all without a flip.
    pub stalled: bool,
    /// The stage's cap, time limit and cancel flag.
    budget: crate::Budget,
    /// True when the time limit (or the cancel flag) stopped the loop.
    pub timed_out: bool,
}

impl Solver<ArapProblem, ArapState> for ArapSolver {
    fn name(&self) -> &str {
        "arap local/global"
    }

    fn init(
        &mut self,
        problem: &mut Problem<ArapProblem>,
        state: ArapState,
    ) -> Result<(ArapState, Option<KV>), Error> {
        let p = problem_ref(problem)?;
        let x = state
            .param
            .as_deref()
            .ok_or(FlattenError::Internal(InternalError::ArapNoStartMap))?;
        let e = p.energy(x);
        Ok((state.cost(e), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<ArapProblem>,
        mut state: ArapState,
    ) -> Result<(ArapState, Option<KV>), Error> {
        let p = problem_ref(problem)?;
        let uv = state
            .take_param()
            .ok_or(FlattenError::Internal(InternalError::ArapNoCurrentMap))?;
        let n = uv.len() / 2;
        let rots = p.rotations(&uv);
        let [bx, by] = p.rhs(n, &rots);
        let mut fields = self.fixed_vals.clone();
        self.sys.solve(&mut fields, Some(&[bx, by]))?;
        let target: Vec<f64> = (0..2 * n).map(|i| fields[i % 2][i / 2]).collect();
        let mut t = 1.0;
        let mut next = target.clone();
        let mut ok = p.flip_free(&next);
        let mut halvings = 0;
        while !ok && halvings < MAX_HALVINGS {
            t *= 0.5;
            halvings += 1;
            for i in 0..2 * n {
                next[i] = uv[i] + t * (target[i] - uv[i]);
            }
            ok = p.flip_free(&next);
        }
        if halvings > 0 {
            self.shortened_steps += 1;
        }
        let (param, e) = if ok {
            let e = p.energy(&next);
            (next, e)
        } else {
            self.stalled = true;
            let e = state.get_cost();
            (uv, e)
        };
        Ok((state.param(param).cost(e), None))
    }

    fn terminate(&mut self, state: &ArapState) -> TerminationStatus {
        let (prev, cur) = (state.get_prev_cost(), state.get_cost());
        if self.stalled {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "no flip-free step".into(),
            ));
        }
        if self.budget.hooks.cancelled() || self.budget.expired() {
            self.timed_out = true;
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "time limit".into(),
            ));
        }
        if state.get_iter() > 0 && prev.is_finite() && prev - cur <= self.rel_tolerance * prev {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

fn problem_ref(problem: &Problem<ArapProblem>) -> Result<&ArapProblem, FlattenError> {
    problem
        .problem
        .as_ref()
        .ok_or(FlattenError::Internal(InternalError::ArapProblemMoved))
}

/// Emits one `tracing` debug event per iteration (progress for the command line).
struct TraceObserver;

impl Observe<ArapState> for TraceObserver {
    fn observe_iter(&mut self, state: &ArapState, _kv: &KV) -> Result<(), Error> {
        tracing::debug!(
            target: "flatcut_flatten",
            method = "arap",
            iteration = state.get_iter(),
            energy = state.get_cost(),
            "iteration"
        );
        Ok(())
    }
}

/// Flattens the disk `mesh` with ARAP (see the module docs). Pins are hard constraints.
pub fn arap(
    mesh: &TriMesh,
    topo: &Topology,
    params: &FlattenParams,
) -> Result<Flattening, FlattenError> {
    let n = mesh.positions.len();
    let budget = params.budget("arap", std::time::Instant::now());
    let mut warnings = Vec::new();
    let init = crate::lscm::lscm(mesh, topo, &params.pins)?;
    let mut uv0 = init.uv;
    if count_flips(&mesh.triangles, &uv0) > 0 {
        uv0 = crate::tutte::tutte(mesh, topo)?;
        let a2 = crate::ops::uv_area(&mesh.triangles, &uv0);
        let s = (mesh.area() / a2).sqrt();
        uv0.iter_mut().for_each(|p| *p *= s);
        crate::ops::fit_rigid_to_pins(&mut uv0, &params.pins);
        warnings.push("arap: LSCM folded this surface; started from Tutte's embedding".into());
    }
    let mut fixed = vec![false; n];
    let mut fx = vec![0.0; n];
    let mut fy = vec![0.0; n];
    for (v, used) in used_mask(mesh).into_iter().enumerate() {
        if !used {
            fixed[v] = true;
            fx[v] = uv0[v].x;
            fy[v] = uv0[v].y;
        }
    }
    if params.pins.is_empty() {
        // Only the translation is free: hold one boundary vertex where LSCM put it.
        let v = topo
            .boundary_loops
            .first()
            .and_then(|l| l.first())
            .copied()
            .unwrap_or(0) as usize;
        fixed[v] = true;
        fx[v] = uv0[v].x;
        fy[v] = uv0[v].y;
    }
    for p in &params.pins {
        let v = p.vertex as usize;
        fixed[v] = true;
        fx[v] = p.position.x;
        fy[v] = p.position.y;
    }
    let problem = ArapProblem::new(mesh)?;
    let w: Vec<[f64; 3]> = problem.cot.clone();
    let sys = laplace(&mesh.triangles, &w, &fixed, "arap global step")?;
    let solver = ArapSolver {
        sys,
        fixed_vals: [fx, fy],
        rel_tolerance: params.rel_tolerance,
        shortened_steps: 0,
        stalled: false,
        budget: budget.clone(),
        timed_out: false,
    };
    let x0: Vec<f64> = uv0.iter().flat_map(|p| [p.x, p.y]).collect();
    let max_iters = budget.allow(params.max_iters);
    let res = Executor::new(problem, solver)
        .configure(|s| s.param(x0).max_iters(max_iters as u64))
        .add_observer(TraceObserver, ObserverMode::Always)
        .run()
        .map_err(|e| match e.downcast::<FlattenError>() {
            Ok(fe) => fe,
            Err(e) => FlattenError::NoConvergence {
                method: Method::Arap,
                reason: e.to_string(),
            },
        })?;
    let mut state = res.state;
    let iterations = state.get_iter() as usize;
    budget.spend(iterations);
    if budget.hooks.cancelled() {
        return Err(FlattenError::Cancelled {
            method: Method::Arap,
        });
    }
    if res.solver.timed_out {
        warnings.push(crate::nonlinear::time_limit_warning(
            Method::Arap,
            iterations,
        ));
    }
    let energy = state.get_best_cost();
    let x = state
        .take_best_param()
        .ok_or(FlattenError::Internal(InternalError::ArapNoResult))?;
    let uv: Vec<DVec2> = (0..n).map(|v| DVec2::new(x[2 * v], x[2 * v + 1])).collect();
    if count_flips(&mesh.triangles, &uv) > 0 {
        return Err(FlattenError::Internal(InternalError::ArapFlipSurvived));
    }
    if res.solver.shortened_steps > 0 {
        warnings.push(format!(
            "arap: {} global step(s) shortened to avoid folding",
            res.solver.shortened_steps
        ));
    }
    if let Some(p) = params
        .pins
        .iter()
        .find(|p| (uv[p.vertex as usize] - p.position).length() > 1e-9 * mesh.bbox().diagonal())
    {
        warnings.push(format!(
            "arap: pinned vertex {} ended {:.3} mm from its pin (the start map folded)",
            p.vertex,
            (uv[p.vertex as usize] - p.position).length()
        ));
    }
    Ok(Flattening {
        uv,
        info: FlattenInfo {
            iterations,
            final_energy: energy / mesh.area(),
            warnings,
            stages: vec![budget.count()],
            ..Default::default()
        },
    })
}
