//! The nonlinear, flip-free methods: isometric (δ2), conformal (δ1), min-max (δ0) and
//! boundary-isometric (Duncan's f1); isometric with material stretch limits ([`crate::limits`]).
//!
//! All of them start from a flip-free map (LSCM when it is flip-free for isometric, else Tutte,
//! [`init`]) and keep every iterate flip-free
//! with a line search bounded by the first inversion ([`newton`]). Results are at true scale in
//! mm: isometric and boundary-isometric fix the scale by their energies; conformal is scaled to
//! the 3D area (the only free parameter of a conformal map's scale).

pub mod boundary;
pub mod grain;
pub mod init;
pub mod kernel;
pub mod minmax;
pub mod newton;
pub mod orthotropic;
pub mod spd;

use crate::internal::InternalError;
use std::time::{Duration, Instant};

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use crate::limits::{EnergySolve, Limits};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method};
use kernel::{IsoEnergy, Mips, RestTri, SymDirichlet, TriEnergy};
use newton::{Budget, EarlyStop};

/// Newton decrement (energy units per mm² of surface) below which a solve has converged: far
/// below any distortion a pattern maker can see (δ2 ~ 1e-12).
pub(crate) const ABS_DECREMENT_PER_AREA: f64 = 1e-15;

/// Solves one of the nonlinear methods (`Isometric`, `Conformal`, `Minmax`, `BoundaryIsometric`).
pub fn solve(
    mesh: &TriMesh,
    topo: &Topology,
    params: &FlattenParams,
) -> Result<Flattening, FlattenError> {
    let started = Instant::now();
    // The method's own stage (its start map included); the methods of several stages make
    // their budgets from it ([`Budget::next`]).
    let budget = params.budget(params.method.name(), started);
    let mut out = match params.method {
        // f1 decides on its own start (see its module).
        Method::BoundaryIsometric => boundary::boundary_isometric(mesh, topo, params, &budget)?,
        Method::Isometric => {
            let n = mesh.positions.len();
            let ahead = start_beside_analysis(mesh, topo);
            let x0 = ahead.x0?;
            // After the start, as for the other methods.
            let rest = rest_frames(mesh)?;
            let sys = ahead.system.map_err(|reason| FlattenError::Solver {
                stage: "newton",
                reason,
            })?;
            let problem = newton::MapProblem::on_system(&rest, n, SymDirichlet, None, sys);
            let analysis = problem.timings().ordering;
            let mut out = isometric_with(mesh, problem, x0, params, &budget)?;
            // The analysis ran beside the start map: the ordering's wall time is what it kept
            // the Newton solve waiting.
            let t = &mut out.info.timings;
            t.ordering = t.ordering.saturating_sub(analysis) + ahead.waited;
            t.start += ahead.start;
            out
        }
        method => {
            // The start before the rest frames: LSCM's factor is the memory peak of a large
            // map, and the frames (64 MB at a million faces) are not needed until the descent.
            let x0 = match method {
                Method::Conformal => init::tutte(mesh, topo)?,
                _ => init::lscm_or_tutte(mesh, topo)?,
            };
            let start = started.elapsed();
            let rest = rest_frames(mesh)?;
            let mut out = match method {
                Method::Conformal => conformal(mesh, &rest, x0, params, &budget)?,
                Method::Minmax => minmax::minmax(mesh, topo, &rest, x0, params, &budget)?,
                Method::Orthotropic => grain::orthotropic(mesh, &rest, x0, params, &budget)?,
                m => {
                    return Err(FlattenError::Internal(InternalError::NotNonlinear {
                        method: m,
                    }));
                }
            };
            out.info.timings.start += start;
            out
        }
    };
    check_flip_free(mesh, &out.uv, params.method)?;
    apply_pins(&mut out, mesh, params)?;
    Ok(out)
}

/// An isometric map's start ([`init::lscm_or_tutte`]) and the analysis of its Newton system
/// ([`newton::analyse`]: the pattern, its order and symbolic factorisation), made side by side.
struct StartAndAnalysis {
    /// The start map, or why there is none.
    x0: Result<Vec<DVec2>, FlattenError>,
    /// The Newton solve's system ([`newton::analyse`]), or why there is none.
    system: Result<spd::SpdSystem, String>,
    /// Wall time until the start map was made.
    start: Duration,
    /// Wall time the analysis took beyond the start map.
    waited: Duration,
}

/// Makes the start map of an isometric solve on this thread while another one analyses the
/// Newton system after it (its pattern, order and symbolic factorisation). Both depend on the
/// mesh alone, and the analysis (0.5–1 s at a million faces) fits beside the start map's
/// factorisation, which leaves the second core idle; it takes the nested-dissection order the
/// start map makes of the same vertex graph ([`crate::ordering::shared_dissection`] waits for
/// it rather than ordering the graph twice). The map is the same bits as when they run one
/// after the other. The rest frames (64 MB at a million faces) are left until after the start:
/// its factor is the memory peak.
///
/// On one of rayon's worker threads (a map flattened inside a parallel loop) the two run here
/// one after the other ([`crate::beside::beside`]): a worker blocked joining a thread whose
/// work waits for rayon's pool waits forever once every worker is so blocked.
fn start_beside_analysis(mesh: &TriMesh, topo: &Topology) -> StartAndAnalysis {
    let started = Instant::now();
    let n = mesh.positions.len();
    let triangles = || mesh.triangles.iter().map(|t| t.map(|v| v as usize));
    let mut start = Duration::ZERO;
    let (system, x0) = crate::beside::beside(
        || newton::analyse(triangles(), n, None),
        || {
            let x0 = init::lscm_or_tutte(mesh, topo);
            start = started.elapsed();
            x0
        },
    );
    StartAndAnalysis {
        x0,
        system,
        start,
        waited: started.elapsed().saturating_sub(start),
    }
}

/// The rest frames of a mesh that passed the disk check.
pub(crate) fn rest_frames(mesh: &TriMesh) -> Result<Vec<RestTri>, FlattenError> {
    kernel::rest_frames(mesh)
        .map_err(|t| FlattenError::Internal(InternalError::DegenerateTriangle { triangle: t }))
}

/// Runs projected Newton on `energy` from `x0` (flat, [`newton::to_flat`]). A cancelled run is
/// an error; a run stopped by the time limit returns its last (flip-free) iterate with `early`
/// set.
pub(crate) fn newton_solve<E: TriEnergy>(
    rest: &[RestTri],
    n: usize,
    energy: E,
    x0: Vec<f64>,
    params: &FlattenParams,
    method: Method,
    budget: &Budget,
) -> Result<newton::NewtonRun, FlattenError> {
    let problem =
        newton::MapProblem::new(rest, n, energy, None).map_err(|reason| FlattenError::Solver {
            stage: "newton",
            reason,
        })?;
    newton_solve_on(problem, x0, params, method, budget)
}

/// [`newton_solve`] of a problem already made.
fn newton_solve_on<E: TriEnergy>(
    problem: newton::MapProblem<'_, E>,
    x0: Vec<f64>,
    params: &FlattenParams,
    method: Method,
    budget: &Budget,
) -> Result<newton::NewtonRun, FlattenError> {
    let abs = ABS_DECREMENT_PER_AREA * problem.total_area;
    let (run, _) = newton::run_flat(
        problem,
        x0,
        params.max_iters,
        params.rel_tolerance,
        abs,
        budget,
    )
    .map_err(|reason| FlattenError::NoConvergence { method, reason })?;
    if run.early == Some(EarlyStop::Cancelled) {
        return Err(FlattenError::Cancelled { method });
    }
    Ok(run)
}

/// The warning of a solve stopped by the caller's time limit.
pub(crate) fn time_limit_warning(method: Method, iterations: usize) -> String {
    format!(
        "{method} stopped at the time limit after {iterations} iterations: the map is flip-free but not fully converged"
    )
}

/// The Newton solve of one piece ([`newton_solve`]) within the limits stage's
/// budget; `early` records a solve the time limit stopped.
pub(crate) struct OnePiece<'a> {
    pub rest: &'a [RestTri],
    pub n: usize,
    pub params: &'a FlattenParams,
    pub budget: &'a Budget,
    pub early: Option<EarlyStop>,
    /// Where the solves' time went.
    pub timings: crate::Timings,
}

impl EnergySolve for OnePiece<'_> {
    fn solve<E: IsoEnergy + Copy>(
        &mut self,
        energy: E,
        x: &[DVec2],
    ) -> Result<(Vec<DVec2>, usize), FlattenError> {
        let r = newton_solve(
            self.rest,
            self.n,
            energy,
            newton::to_flat(x),
            self.params,
            crate::Method::Isometric,
            self.budget,
        )?;
        self.early = self.early.or(r.early);
        self.timings.add(&r.timings);
        Ok((r.x, r.iterations))
    }
    fn stopped(&self) -> bool {
        self.early.is_some() || self.budget.spent()
    }
}

/// Duncan's isometric distortion δ2 (symmetric Dirichlet) from the flip-free map `x0`, with
/// material limits if asked.
pub(crate) fn isometric(
    mesh: &TriMesh,
    rest: &[RestTri],
    x0: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let n = mesh.positions.len();
    let problem = newton::MapProblem::new(rest, n, SymDirichlet, None).map_err(|reason| {
        FlattenError::Solver {
            stage: "newton",
            reason,
        }
    })?;
    isometric_with(mesh, problem, x0, params, budget)
}

/// [`isometric`] with its Newton problem already made (on its rest frames).
fn isometric_with(
    mesh: &TriMesh,
    problem: newton::MapProblem<'_, SymDirichlet>,
    x0: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let (rest, n) = (problem.rest, mesh.positions.len());
    let flat = newton::to_flat(&x0);
    drop(x0);
    let run = newton_solve_on(problem, flat, params, Method::Isometric, budget)?;
    let mut info = FlattenInfo {
        iterations: run.iterations,
        final_energy: run.energy / total_area(rest),
        warnings: Vec::new(),
        stages: vec![budget.count()],
        timings: run.timings,
    };
    let mut early = run.early;
    let mut x = run.x;
    if let Some(limits) = Limits::of(params)? {
        let stage = budget.next_capped("limits", params.stage_iters, params.time_limit);
        let mut one = OnePiece {
            rest,
            n,
            params,
            budget: &stage,
            early: None,
            timings: crate::Timings::default(),
        };
        let r = crate::limits::enforce(&mut one, rest, x, limits)?;
        info.iterations += r.iterations;
        info.stages.push(stage.count());
        info.timings.add(&one.timings);
        early = early.or(one.early);
        x = r.x;
        info.final_energy = mean_density(rest, &x, &SymDirichlet);
        info.warnings
            .extend(crate::limits::violations(mesh, &x, limits));
    }
    if early == Some(EarlyStop::TimeLimit) {
        info.warnings
            .push(time_limit_warning(Method::Isometric, info.iterations));
    }
    Ok(Flattening { uv: x, info })
}

/// The unconstrained δ2 solve on `n` vertices from `x0` (LSCM, or Tutte where LSCM flips:
/// [`init::lscm_or_tutte`]), for `method`'s messages.
pub(crate) fn isometric_run(
    rest: &[RestTri],
    n: usize,
    x0: Vec<DVec2>,
    params: &FlattenParams,
    method: Method,
    budget: &Budget,
) -> Result<newton::NewtonRun, FlattenError> {
    let flat = newton::to_flat(&x0);
    drop(x0);
    newton_solve(rest, n, SymDirichlet, flat, params, method, budget)
}

/// Duncan's conformal distortion δ1 via the MIPS energy from the flip-free map `x0` (Tutte's),
/// scaled to the 3D area.
fn conformal(
    mesh: &TriMesh,
    rest: &[RestTri],
    x0: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let n = mesh.positions.len();
    let run = newton_solve(
        rest,
        n,
        Mips,
        newton::to_flat(&x0),
        params,
        Method::Conformal,
        budget,
    )?;
    let mut x = run.x;
    init::scale_to_area(mesh, &mut x);
    let mut warnings = Vec::new();
    if run.early == Some(EarlyStop::TimeLimit) {
        warnings.push(time_limit_warning(Method::Conformal, run.iterations));
    }
    Ok(Flattening {
        info: FlattenInfo {
            iterations: run.iterations,
            final_energy: mean_density(rest, &x, &Mips),
            warnings,
            stages: vec![budget.count()],
            timings: run.timings,
        },
        uv: x,
    })
}

/// Σ A_t.
pub(crate) fn total_area(rest: &[RestTri]) -> f64 {
    rest.iter().map(|r| r.area).sum()
}

/// Area-weighted mean of an energy density.
pub(crate) fn mean_density<E: IsoEnergy>(rest: &[RestTri], x: &[DVec2], e: &E) -> f64 {
    let s: f64 = rest.iter().map(|r| kernel::tri_energy(e, r, x)).sum();
    s / total_area(rest)
}

/// Refuses a result with a non-finite coordinate or an inverted triangle.
fn check_flip_free(mesh: &TriMesh, uv: &[DVec2], method: Method) -> Result<(), FlattenError> {
    if let Some(v) = uv.iter().position(|p| !p.is_finite()) {
        return Err(FlattenError::NoConvergence {
            method,
            reason: format!("vertex {v} has a non-finite position"),
        });
    }
    if let Some(t) = (0..mesh.triangles.len()).find(|&t| {
        let a = init::signed_area(mesh, uv, t);
        a.is_nan() || a <= 0.0
    }) {
        return Err(FlattenError::NoConvergence {
            method,
            reason: format!("triangle {t} is inverted in the result"),
        });
    }
    Ok(())
}

/// Places the result by the pins with a rigid motion (the shape is never distorted to meet
/// them): one pin fixes the position, a second one the direction. A second pin whose distance
/// differs from the flattened one is reported; further pins are reported with their errors.
fn apply_pins(
    out: &mut Flattening,
    mesh: &TriMesh,
    params: &FlattenParams,
) -> Result<(), FlattenError> {
    let n = mesh.positions.len();
    for (i, p) in params.pins.iter().enumerate() {
        if p.vertex as usize >= n {
            return Err(FlattenError::BadPin {
                index: i,
                reason: format!("vertex {} does not exist (mesh has {n})", p.vertex),
            });
        }
        if !p.position.is_finite() {
            return Err(FlattenError::BadPin {
                index: i,
                reason: "position is not finite".into(),
            });
        }
    }
    let Some(first) = params.pins.first() else {
        return Ok(());
    };
    let a = out.uv[first.vertex as usize];
    let mut rot = flatcut_geom::DMat2::IDENTITY;
    if let Some(second) = params.pins.get(1) {
        let d_have = out.uv[second.vertex as usize] - a;
        let d_want = second.position - first.position;
        if d_have.length() > 0.0 && d_want.length() > 0.0 {
            let ang = d_want.y.atan2(d_want.x) - d_have.y.atan2(d_have.x);
            rot = flatcut_geom::DMat2::from_angle(ang);
        }
    }
    for p in out.uv.iter_mut() {
        *p = first.position + rot * (*p - a);
    }
    for (i, p) in params.pins.iter().enumerate().skip(1) {
        let err = (out.uv[p.vertex as usize] - p.position).length();
        if err > 1e-6 {
            out.info.warnings.push(format!(
                "pin {i} (vertex {}) is {err:.3} mm from its target: pins only place the pattern rigidly",
                p.vertex
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::spherical_cap;

    /// The isometric solve with its Newton analysis made beside the start map gives the map of
    /// the start and the solve made one after the other, bit for bit, on one rayon thread and
    /// on two.
    #[test]
    fn the_analysis_beside_the_start_gives_the_sequential_map_with_any_threads() {
        let mesh = spherical_cap(40.0, 1.2, 30);
        let topo = flatcut_mesh::check_disk(&mesh).unwrap();
        let params = FlattenParams::new(Method::Isometric);
        let one_after = {
            let budget = params.budget(params.method.name(), Instant::now());
            let x0 = init::lscm_or_tutte(&mesh, &topo).unwrap();
            let rest = rest_frames(&mesh).unwrap();
            isometric(&mesh, &rest, x0, &params, &budget).unwrap()
        };
        assert!(one_after.info.iterations > 1);
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let side_by_side = pool.install(|| solve(&mesh, &topo, &params)).unwrap();
            assert_eq!(side_by_side.info.iterations, one_after.info.iterations);
            assert!(
                side_by_side
                    .uv
                    .iter()
                    .zip(&one_after.uv)
                    .all(|(a, b)| a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits()),
                "{threads} thread(s): the maps differ"
            );
        }
    }
}
