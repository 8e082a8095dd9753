//! Boundary-isometric flattening (Duncan's f1, issue 10): every boundary edge keeps its 3D
//! length, the interior minimises Duncan's pointwise deviation Σ(λi − 1)² (λi = σi², the
//! Green–Lagrange strain norm).
//!
//! Duncan builds f1 in two steps: a conformal map whose boundary keeps its lengths (step 1),
//! then, keeping that boundary, the map of least deviation (step 2). f1 lets the outline move
//! with its lengths held instead (`free_outline`), which can only do better: on the bench's
//! 20k toe mean δ2 0.9518 against 0.9534 with step 1's outline held (on the caps and the
//! hemisphere the two agree to 5 digits: the outline is a circle either way). That holds while
//! the rim is no longer than the interior can take flat. Where it is longer, step 1's conformal
//! metric has more area than the surface (`rim_too_long`; negative curvature stretches it,
//! positive curvature shrinks it), and a free outline has no smooth minimiser: it crimps at the
//! scale of the mesh (the bench's 200k saddle: a sawtooth rim after 881 Newton steps and 357 s,
//! 119× the isometric time), and a piece cut from it has a ragged edge. There f1 is Duncan's
//! two steps: step 1's outline, closed with every edge at its 3D length, held while the
//! interior relaxes (`held_outline`): 3 Newton steps to a smooth outline on the saddle.
//!
//! The free outline: start from the isometric (δ2) map (the `isometric` method's own solve, from LSCM,
//! cut short after `START_ITERS` steps: it is only where the length phase starts), which is
//! flip-free and already close, on the same problem (its pattern and symbolic factorisation
//! serve every later solve: the boundary edges are mesh edges); then an augmented Lagrangian on
//! the boundary lengths (c_e = (|e|² − L²)/L² = 0) solved by the flip-free projected Newton of
//! [`super::newton`]. Once the lengths are within `INEXACT_ABOVE`, every Newton step moves the
//! multipliers too (the SQP step of the constrained problem, `EdgeTerms::follow`): the lengths
//! converge with the map. Between solves the multipliers are updated λ ← λ + w c and the
//! weight raised ×10 while the violation does not shrink fast enough; the solves before that
//! stop at the looser `INEXACT_REL_TOLERANCE`.
//!
//! The interior energy is Duncan's with a collapse guard ([`GuardedGreen`]): below σ = 1/√3 the
//! Green–Lagrange term turns concave and bounded ((0 − 1)² per direction), so a growing boundary
//! weight would otherwise squeeze a few triangles flat instead of compressing many. The guard
//! starts at σ = [`GUARD_FLOOR`] with zero slope and curvature ([`GuardShape::Cubic`]), where
//! the Green term is still convex, so the guarded term's curvature is continuous and positive
//! for every stretch: compressed interiors converge in tens of Newton steps (the 20k hemisphere
//! in 22 with the SQP steps; with a guard starting at 1/√3, whose curvature jumped there, and
//! one multiplier update per solve, it took 549). The guard
//! is zero wherever every stretch stays above the floor, so pieces compressed by less than 30 %
//! (developables, shallow caps) get Duncan's f1 unchanged; with it the hemisphere, saddle and toe
//! of the bench keep their boundaries to 1e-10 without a fold (Green's term alone collapsed
//! triangles there).
//!
//! Infeasibility: where the rim is far too short for the interior (a cap deeper than a
//! hemisphere), the lengths cannot be met by any non-degenerate interior. The guard is infinite at
//! σ = [`DEGENERATE_STRETCH`] (a triangle crushed to a fifth of its size), so as the weight grows
//! the solve tends to the flip-free map with the smallest boundary violation among those whose
//! stretches all stay above it. The weight stops growing when a tenfold raise gains less than
//! [`STALL_GAIN`] of the violation after a converged inner solve while the guard is active (some
//! σ below its floor): the multipliers are fighting the interior, not round-off (below
//! [`REPORT_REL_ERROR`] a stall is taken as inner-solve precision, and the weight keeps growing).
//! The best iterate (smallest largest relative boundary error) is returned with a warning naming
//! the worst edges.

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use super::kernel::{GuardShape, GuardedGreen, RestTri, SymDirichlet, singular_values};
use super::newton::{Budget, EarlyStop, EdgeTerms, MapProblem, NewtonRun, run, run_flat, to_flat};
use super::{ABS_DECREMENT_PER_AREA, mean_density, time_limit_warning, total_area};
use crate::conformal_boundary::{Closing, conformal_map, log_scale_factors};
use crate::ops::{angle_sums, boundary_mask, corner_angles, count_flips, flat_corner_angles};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method};

/// Target relative boundary-length error.
pub const BOUNDARY_REL_TOLERANCE: f64 = 1e-10;
/// Outer augmented-Lagrangian iterations.
const MAX_OUTER: usize = 14;
/// Initial penalty weight (relative to the strain density). The multipliers' SQP step is a
/// proximal one whose lengths converge by about 1/(1 + w·μ) per step (μ: the boundary's
/// stiffness against the interior); at 10 they crept, 9 % per step on a shallow cap, and at
/// 10⁴ the saddle's penalty crawled along the constraints.
const INITIAL_WEIGHT: f64 = 1e3;
/// Weight growth when the violation shrank by less than [`REQUIRED_SHRINK`].
const WEIGHT_GROWTH: f64 = 10.0;
/// Factor by which one outer iteration must shrink the violation to count as progress.
const REQUIRED_SHRINK: f64 = 0.1;
/// Largest violation at which the multipliers follow every Newton step and the inner solve runs
/// to convergence; above it the solves hold the multipliers, stop after [`INEXACT_INNER_ITERS`]
/// Newton steps or at [`INEXACT_REL_TOLERANCE`] (an inexact augmented Lagrangian). The first
/// penalty solve leaves the bench's 200k toe and hemisphere at 9e-2 and 6e-2: from there the
/// SQP steps hold the lengths to 1e-10 in 4 Newton steps, where at 1e-3 two more penalty solves
/// came first (5 steps on the toe, and 4 more factorisations in all).
const INEXACT_ABOVE: f64 = 1e-1;
/// Relative energy decrease at which the penalty solves above [`INEXACT_ABOVE`] stop: their
/// multipliers are only estimates, and the tail of a solve to the method's own tolerance was
/// one Newton step each that moved the lengths by a thousandth of their error.
const INEXACT_REL_TOLERANCE: f64 = 1e-5;
/// Newton steps of the isometric start. Its energy is not f1's: its first step from LSCM takes
/// most of its gain (the 200k toe: 1.00 → 0.736, the optimum 0.715), and the three more of a
/// solve to convergence saved the length phase nothing. Where the start still has a stretch
/// below `DEGENERATE_STRETCH / START_COLLAPSE_FRACTION` after them, the guard would be loosened
/// from it, and the start is solved out.
const START_ITERS: usize = 1;
/// Newton steps per inner solve while the violation is above [`INEXACT_ABOVE`].
const INEXACT_INNER_ITERS: usize = 30;
/// Relative length error above which an edge is reported as not kept.
pub const REPORT_REL_ERROR: f64 = 1e-6;
/// Guard stiffness k of [`GuardedGreen`]: with k = 1 the guarded term's curvature stays positive
/// for every collapse stretch from 0 to [`DEGENERATE_STRETCH`] (at σ = 1/√3, where the Green
/// term's curvature is 0, the cubic guard's is already 5k or more; below, it outgrows the Green
/// term's −4).
const GUARD_STIFFNESS: f64 = 1.0;
/// Stretch below which the guard acts: the Green term's curvature 12σ² − 4 is 1.88 there, so
/// the cubic guard, whose curvature starts at 0, keeps the sum positive and continuous.
pub const GUARD_FLOOR: f64 = 0.7;
/// Principal stretch below which a triangle counts as crushed: a fifth of its 3D size (δ2 ≥ 12
/// there), no longer a faithful piece of the pattern.
pub const DEGENERATE_STRETCH: f64 = 0.2;
/// Where the isometric start itself compresses below [`DEGENERATE_STRETCH`], the guard's collapse
/// stretch is set to this fraction of the start's smallest stretch.
const START_COLLAPSE_FRACTION: f64 = 0.5;
/// Relative gain in the violation below which an outer step counts as stalled. The gains of a
/// stalled solve shrink geometrically (×0.4–0.5 per tenfold weight on the deep-cap test), so
/// once one tenfold weight gains under 1 %, all further ones together gain about as much again.
pub const STALL_GAIN: f64 = 0.01;
/// Edges named in the infeasibility warning.
const WORST_EDGES_REPORTED: usize = 3;

/// Largest relative boundary-length error |ℓ − L|/L and its edge.
pub fn max_boundary_error(edges: &[(usize, usize, f64)], x: &[DVec2]) -> (f64, usize) {
    let mut worst = (0.0, 0);
    for (k, &(a, b, l)) in edges.iter().enumerate() {
        let r = ((x[b] - x[a]).length() - l).abs() / l;
        if r > worst.0 {
            worst = (r, k);
        }
    }
    worst
}

/// Boundary edges of the (single) boundary loop with their 3D lengths.
pub fn boundary_edges(mesh: &TriMesh, topo: &Topology) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    for lp in &topo.boundary_loops {
        for i in 0..lp.len() {
            let (a, b) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
            out.push((a, b, (mesh.positions[b] - mesh.positions[a]).length()));
        }
    }
    out
}

/// Smallest principal stretch σ2 over the triangles and its triangle (σ2 ≤ 0 for an inverted
/// one).
pub fn min_stretch(rest: &[RestTri], x: &[DVec2]) -> (f64, usize) {
    let mut worst = (f64::INFINITY, 0);
    for (t, r) in rest.iter().enumerate() {
        let s = singular_values(r.jacobian(x)).1;
        if s < worst.0 {
            worst = (s, t);
        }
    }
    worst
}

/// Why the outer loop stopped short of the tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stop {
    /// The violation stalled against the active guard.
    Stalled,
    /// An outer step crushed triangle `t` to stretch `s`; the previous iterate was kept.
    Crushed { t: usize, s: f64 },
}

/// How much more area (relative) step 1's conformal metric must have than the surface for the
/// rim to count as too long ([`rim_too_long`]): on developables the discretisation gives about
/// a ten thousandth, always less (the bench's cylinder and cone: 5e-5 and 1.2e-4 less at 2k
/// faces, 5e-6 and 1.4e-5 at 20k); the saddle has 0.204 more, the caps and the toe 0.06–0.56
/// less.
const RIM_TOO_LONG_AREA: f64 = 1e-3;

/// Duncan's f1 (see the module docs for the two problems it solves).
pub fn boundary_isometric(
    mesh: &TriMesh,
    topo: &Topology,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let started = std::time::Instant::now();
    if let Some(outline) = step_one_outline(mesh, topo) {
        let start = started.elapsed();
        let rest = super::rest_frames(mesh)?;
        let mut out = held_outline(mesh, topo, &rest, outline, params, budget)?;
        out.info.timings.start += start;
        return Ok(out);
    }
    let x0 = super::init::lscm_or_tutte(mesh, topo)?;
    let start = started.elapsed();
    let rest = super::rest_frames(mesh)?;
    let mut out = free_outline(mesh, topo, &rest, x0, params, budget)?;
    out.info.timings.start += start;
    Ok(out)
}

/// Step 1's map, closed with every boundary edge at its 3D length, where the rim is too long
/// for the interior ([`rim_too_long`]) and the map is flip-free; `None` otherwise (the free
/// outline is solved instead).
fn step_one_outline(mesh: &TriMesh, topo: &Topology) -> Option<Vec<DVec2>> {
    if topo.boundary_loops.len() != 1 {
        return None;
    }
    let u = log_scale_factors(mesh, topo).ok()?;
    if !rim_too_long(mesh, &u) {
        return None;
    }
    let x = conformal_map(mesh, topo, &u, Closing::Turns).ok()?;
    (count_flips(&mesh.triangles, &x) == 0).then_some(x)
}

/// Whether the conformal metric e^{2u}·g with an isometric rim (u = 0 there) has more area
/// than the surface by [`RIM_TOO_LONG_AREA`]: the interior must then be stretched for the rim
/// to keep its length, and a free outline ruffles instead.
fn rim_too_long(mesh: &TriMesh, u: &[f64]) -> bool {
    let (mut conformal, mut surface) = (0.0, 0.0);
    for (k, t) in mesh.triangles.iter().enumerate() {
        let area = mesh.triangle_area(k);
        let mean_u = t.iter().map(|&v| u[v as usize]).sum::<f64>() / 3.0;
        surface += area;
        conformal += area * (2.0 * mean_u).exp();
    }
    conformal > (1.0 + RIM_TOO_LONG_AREA) * surface
}

/// Step 2 on step 1's outline `x`: the map of least guarded deviation with every boundary
/// vertex held where `x` puts it (its edges at their 3D lengths), from `x` itself.
fn held_outline(
    mesh: &TriMesh,
    topo: &Topology,
    rest: &[RestTri],
    x: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let n = mesh.positions.len();
    let method = Method::BoundaryIsometric;
    let energy = guarded_green(min_stretch(rest, &x).0);
    let problem = MapProblem::new(rest, n, energy, None)
        .map_err(|reason| FlattenError::Solver {
            stage: "boundary-isometric",
            reason,
        })?
        .with_fixed(&boundary_mask(n, topo));
    let abs = ABS_DECREMENT_PER_AREA * total_area(rest);
    let budget = budget.labelled("interior of the kept outline");
    let (r, _) = run(
        problem,
        &x,
        params.max_iters,
        params.rel_tolerance,
        abs,
        &budget,
    )
    .map_err(|reason| FlattenError::NoConvergence { method, reason })?;
    let mut warnings = Vec::new();
    match r.early {
        Some(EarlyStop::Cancelled) => return Err(FlattenError::Cancelled { method }),
        Some(EarlyStop::TimeLimit) => warnings.push(time_limit_warning(method, r.iterations)),
        None => {}
    }
    let edges = boundary_edges(mesh, topo);
    let (viol, _) = max_boundary_error(&edges, &r.x);
    if viol > REPORT_REL_ERROR {
        warnings.push(format!(
            "boundary lengths not all kept: largest relative length error {viol:.2e}"
        ));
    }
    Ok(Flattening {
        info: FlattenInfo {
            iterations: r.iterations,
            final_energy: mean_density(rest, &r.x, &energy),
            warnings,
            stages: vec![budget.count()],
            timings: r.timings,
        },
        uv: r.x,
    })
}

/// Duncan's deviation with the collapse guard, its collapse stretch below `start_min`, the
/// smallest stretch of the start, so the start is admissible.
fn guarded_green(start_min: f64) -> GuardedGreen {
    GuardedGreen {
        floor: GUARD_FLOOR,
        collapse: DEGENERATE_STRETCH.min(START_COLLAPSE_FRACTION * start_min),
        k: GUARD_STIFFNESS,
        shape: GuardShape::Cubic,
    }
}

/// f1 with a free outline: the lengths held by an augmented Lagrangian, from the isometric map
/// solved from the flip-free map `x0`.
fn free_outline(
    mesh: &TriMesh,
    topo: &Topology,
    rest: &[RestTri],
    x0: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let n = mesh.positions.len();
    let method = Method::BoundaryIsometric;
    let start = budget.next("isometric start", params.time_limit);
    // One problem, one pattern and one symbolic factorisation for the isometric start and every
    // outer iteration: the boundary edges are mesh edges, so the pattern is the same; only the
    // energy, the multipliers and the weight change.
    let iso_problem =
        MapProblem::new(rest, n, SymDirichlet, None).map_err(|reason| FlattenError::Solver {
            stage: "boundary-isometric",
            reason,
        })?;
    let abs = ABS_DECREMENT_PER_AREA * total_area(rest);
    let flat = to_flat(&x0);
    drop(x0);
    let (mut iso, mut iso_problem) = run_flat(
        iso_problem,
        flat,
        START_ITERS.min(params.max_iters),
        params.rel_tolerance,
        abs,
        &start,
    )
    .map_err(|reason| FlattenError::NoConvergence { method, reason })?;
    if iso.early.is_none()
        && min_stretch(rest, &iso.x).0 < DEGENERATE_STRETCH / START_COLLAPSE_FRACTION
    {
        // The short start still crushes triangles beyond what the guard admits (a cap deeper
        // than a hemisphere): the guard would be set from it, so the start is solved out.
        let (more, p) = run(
            iso_problem,
            &iso.x,
            params.max_iters.saturating_sub(iso.iterations),
            params.rel_tolerance,
            abs,
            &start,
        )
        .map_err(|reason| FlattenError::NoConvergence { method, reason })?;
        iso_problem = p;
        let mut timings = iso.timings;
        timings.add(&more.timings);
        iso = NewtonRun {
            iterations: iso.iterations + more.iterations,
            timings,
            ..more
        };
    }
    if iso.early == Some(EarlyStop::Cancelled) {
        return Err(FlattenError::Cancelled { method });
    }
    let mut timings = iso.timings;
    let mut early = iso.early;
    let mut iterations = iso.iterations;
    let mut x = iso.x;
    let edges = boundary_edges(mesh, topo);
    let energy = guarded_green(min_stretch(rest, &x).0);
    let terms = EdgeTerms {
        lambda: vec![0.0; edges.len()],
        edges: edges.clone(),
        weight: INITIAL_WEIGHT,
        hold: None,
        align: Vec::new(),
        pulls: Vec::new(),
    };
    let mut problem = Some(iso_problem.with_energy(energy).with_edges(Some(terms)));
    let mut viol = max_boundary_error(&edges, &x).0;
    // The closest non-degenerate map so far: (largest relative boundary error, map).
    let mut best = (viol, x.clone());
    let mut stop = None;
    let lengths = budget.next("boundary lengths", params.time_limit);
    for _ in 0..MAX_OUTER {
        if viol <= BOUNDARY_REL_TOLERANCE || early.is_some() || lengths.spent() {
            break;
        }
        let Some(mut pb) = problem.take() else { break };
        // Inexact inner solves with fixed multipliers while the boundary is far off (the
        // multipliers will move the target anyway, and where the lengths cannot be met at all
        // the solves must converge for the stall to show); near the end, the multipliers move
        // with every step and the solve goes on until the lengths are held.
        let far = viol > INEXACT_ABOVE;
        let iters = if far {
            INEXACT_INNER_ITERS.min(params.max_iters)
        } else {
            params.max_iters
        };
        if let Some(t) = pb.edges.as_mut() {
            t.hold = (!far).then_some(BOUNDARY_REL_TOLERANCE);
        }
        let iters = lengths.allow(iters);
        let tolerance = if far {
            params.rel_tolerance.max(INEXACT_REL_TOLERANCE)
        } else {
            params.rel_tolerance
        };
        let (r, mut p) = run(pb, &x, iters, tolerance, abs, &lengths)
            .map_err(|reason| FlattenError::NoConvergence { method, reason })?;
        iterations += r.iterations;
        timings.add(&r.timings);
        early = r.early;
        if early == Some(EarlyStop::Cancelled) {
            return Err(FlattenError::Cancelled { method });
        }
        // A stall only proves anything after an inner solve that converged.
        let converged = r.iterations < iters;
        let (s_min, t_min) = min_stretch(rest, &r.x);
        // The guard keeps every stretch above its collapse stretch; this only catches round-off.
        if s_min.is_nan() || s_min <= energy.collapse {
            stop = Some(Stop::Crushed { t: t_min, s: s_min });
            break;
        }
        x = r.x;
        let Some(terms) = p.edges.as_mut() else {
            break;
        };
        for k in 0..terms.edges.len() {
            terms.lambda[k] += terms.weight * terms.constraint(k, &x);
        }
        let v = max_boundary_error(&edges, &x).0;
        if v < best.0 {
            best = (v, x.clone());
        }
        if v > REQUIRED_SHRINK * viol {
            if converged
                && v > REPORT_REL_ERROR
                && s_min < energy.floor
                && v > (1.0 - STALL_GAIN) * viol
            {
                stop = Some(Stop::Stalled);
                break;
            }
            terms.weight *= WEIGHT_GROWTH;
        }
        viol = v;
        problem = Some(p);
    }
    let (viol, x) = best;
    let mut warnings = Vec::new();
    if early == Some(EarlyStop::TimeLimit) {
        warnings.push(time_limit_warning(method, iterations));
        if viol > REPORT_REL_ERROR {
            warnings.push(format!(
                "boundary lengths not all kept yet: largest relative length error {viol:.2e}"
            ));
        }
    } else if viol > REPORT_REL_ERROR {
        warnings.push(infeasible_warning(mesh, rest, &edges, &x, viol, stop));
    } else if let Some(r) = ruffled_rim(mesh, topo, &x) {
        warnings.push(format!(
            "the boundary ruffles: at {} of its {} vertices the flat outline turns alternately against the surface by more than {:.0}° (up to {:.0}°, near ({:.2}, {:.2}, {:.2})): the rim is longer than the interior can take flat, so keeping its lengths crimps it at the scale of the mesh and a piece cut from it has a ragged edge; `conformal-boundary` keeps the rim's lengths with a smooth outline (its interior conformal), `isometric` lets them go",
            r.count,
            r.vertices,
            RUFFLE_ANGLE.to_degrees(),
            r.worst.to_degrees(),
            r.at.x,
            r.at.y,
            r.at.z
        ));
    }
    Ok(Flattening {
        info: FlattenInfo {
            iterations,
            final_energy: mean_density(rest, &x, &energy),
            warnings,
            stages: vec![start.count(), lengths.count()],
            timings,
        },
        uv: x,
    })
}

/// Turn (radians) of the flat outline against the surface's at a boundary vertex beyond which,
/// alternating in sign with its neighbour's, the rim counts as ruffled there. A smooth kept rim
/// differs from the surface by its share of the total turning, 0.02 rad per vertex on the 20k
/// hemisphere; the saddle's ruffled one by up to 1.7 rad.
const RUFFLE_ANGLE: f64 = 0.1;
/// Share of the boundary vertices that must be ruffled (and at least [`RUFFLE_MIN_VERTICES`])
/// for the warning: a few crimps at corners are the pattern's, not a ruffle.
const RUFFLE_SHARE: f64 = 0.02;
const RUFFLE_MIN_VERTICES: usize = 3;

/// A rim that ruffles: how many of its vertices, out of how many, the largest turn against the
/// surface, and where (3D).
struct Ruffle {
    count: usize,
    vertices: usize,
    worst: f64,
    at: flatcut_geom::DVec3,
}

/// Where the kept boundary of the map `x` ruffles: boundary vertices at which the flat outline
/// turns against the surface (flat angle sum − 3D angle sum) by more than [`RUFFLE_ANGLE`],
/// alternating in sign with the next vertex's. A rim longer than its interior can take flat
/// buckles that way, at the scale of the mesh (the bench's saddle).
fn ruffled_rim(mesh: &TriMesh, topo: &Topology, x: &[DVec2]) -> Option<Ruffle> {
    let s3 = angle_sums(mesh, &corner_angles(mesh));
    let s2 = angle_sums(mesh, &flat_corner_angles(&mesh.triangles, x));
    let mut r = Ruffle {
        count: 0,
        vertices: 0,
        worst: 0.0,
        at: flatcut_geom::DVec3::ZERO,
    };
    for lp in &topo.boundary_loops {
        let turn = |i: usize| {
            let v = lp[i % lp.len()] as usize;
            s2[v] - s3[v]
        };
        r.vertices += lp.len();
        for i in 0..lp.len() {
            let (a, b) = (turn(i), turn(i + 1));
            if a * b < 0.0 && a.abs() > RUFFLE_ANGLE && b.abs() > RUFFLE_ANGLE {
                r.count += 1;
                if a.abs() > r.worst {
                    r.worst = a.abs();
                    r.at = mesh.positions[lp[i] as usize];
                }
            }
        }
    }
    let enough = (RUFFLE_SHARE * r.vertices as f64).max(RUFFLE_MIN_VERTICES as f64);
    (r.count as f64 >= enough).then_some(r)
}

/// The warning for boundary lengths that were not kept: the largest error, the worst edges with
/// their vertices, 3D midpoints and relative errors, and why the solver stopped.
fn infeasible_warning(
    mesh: &TriMesh,
    rest: &[RestTri],
    edges: &[(usize, usize, f64)],
    x: &[DVec2],
    viol: f64,
    stop: Option<Stop>,
) -> String {
    let mut errs: Vec<(f64, usize)> = edges
        .iter()
        .enumerate()
        .map(|(k, &(a, b, l))| (((x[b] - x[a]).length() - l).abs() / l, k))
        .collect();
    errs.sort_by(|p, q| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)));
    let worst: Vec<String> = errs
        .iter()
        .take(WORST_EDGES_REPORTED)
        .map(|&(r, k)| {
            let (a, b, l) = edges[k];
            let m = 0.5 * (mesh.positions[a] + mesh.positions[b]);
            let l2 = (x[b] - x[a]).length();
            format!(
                "{a}–{b} near ({:.2}, {:.2}, {:.2}): {l:.3} mm in 3D, {l2:.3} mm flat ({:.2e})",
                m.x, m.y, m.z, r
            )
        })
        .collect();
    let (s_min, _) = min_stretch(rest, x);
    let (head, why) = match stop {
        Some(Stop::Stalled) => (
            "boundary lengths cannot all be kept without a fold",
            format!(
                "keeping them would crush the interior (smallest stretch already {s_min:.3}, limit {DEGENERATE_STRETCH})"
            ),
        ),
        Some(Stop::Crushed { t, s }) => (
            "boundary lengths cannot all be kept without a fold",
            format!(
                "keeping them crushed triangle {t} to stretch {s:.2e}; kept the last map with every stretch above it"
            ),
        ),
        None => (
            "boundary lengths not all kept",
            format!("the solver stopped after {MAX_OUTER} outer iterations, still converging"),
        ),
    };
    format!(
        "{head}: {why}; returned the closest flip-free map, largest relative length error {viol:.2e}; worst edges {}",
        worst.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh;

    /// A saddle's rim is longer than its interior can take flat. With the outline free and the
    /// lengths held it crimps at the scale of the mesh (flat turns alternating against the
    /// surface's, up to 100° on the bench's saddle), and the free solve says so, naming where.
    /// f1 does not solve the free problem there (`rim_too_long`); the warning guards pieces
    /// whose rim is too long only in part.
    #[test]
    fn a_crimped_free_outline_is_reported() {
        // The bench's saddle, z = (x² − y²)/2 over [−1, 1]², at 100 mm.
        let mesh = testmesh::saddle_of_radius(100.0, 50.0, 24);
        let topo = Topology::build(&mesh).unwrap();
        let u = log_scale_factors(&mesh, &topo).unwrap();
        assert!(rim_too_long(&mesh, &u));
        let params = FlattenParams::new(Method::BoundaryIsometric);
        let x0 = super::super::init::lscm_or_tutte(&mesh, &topo).unwrap();
        let rest = super::super::rest_frames(&mesh).unwrap();
        let budget = Budget::none("test");
        let f = free_outline(&mesh, &topo, &rest, x0, &params, &budget).unwrap();
        let edges = boundary_edges(&mesh, &topo);
        assert!(max_boundary_error(&edges, &f.uv).0 <= REPORT_REL_ERROR);
        assert_eq!(f.info.warnings.len(), 1, "{:?}", f.info.warnings);
        assert!(
            f.info.warnings[0].contains("the boundary ruffles"),
            "{}",
            f.info.warnings[0]
        );
    }

    /// Domes and developables keep the free outline: the conformal metric with an isometric
    /// rim has less area than the surface (a cap) or the same (a cylinder).
    #[test]
    fn only_a_rim_too_long_is_held() {
        for (name, mesh, long) in [
            ("saddle", testmesh::saddle_of_radius(100.0, 50.0, 12), true),
            ("cap", testmesh::spherical_cap(50.0, 1.0, 12), false),
            (
                "cylinder",
                testmesh::cylinder_patch(40.0, 2.5, 60.0, 14, 6),
                false,
            ),
        ] {
            let topo = Topology::build(&mesh).unwrap();
            let u = log_scale_factors(&mesh, &topo).unwrap();
            assert_eq!(rim_too_long(&mesh, &u), long, "{name}");
        }
    }
}
