//! Pieces sewn together, flattened together from maps they already have: the joint solve of
//! [`crate::assembly`] warm-started. A split (`flatcut_darts::split`) solves its pieces
//! jointly again after every cut, and each time all but the two new pieces already lie flat
//! within the limits, their seams equal from the last solve; starting those solves from scratch
//! (each piece's own δ2 optimum, then the seams, then the limits brought in from the softest
//! stage) spent most of the split's time undoing and redoing that.
//!
//! Method: the pieces' maps (flip-free) are the start, as they are. With material limits, the
//! seams are brought equal under the feasibility penalty, at its highest stiffness
//! ([`crate::limits::PENALTY_STIFFNESS`]) from a start within the limits (from the softest
//! when beyond them), its aim drawn further inside while the map breaks a limit
//! ([`crate::limits::MARGIN_SHRINK`]); once within them, the barrier stages
//! ([`crate::limits::BARRIER_WEIGHTS`]) optimise δ2 there, each keeping the seams equal. Every
//! solve is the joint problem's augmented Lagrangian ([`crate::assembly::joint`]): Newton solves
//! of the energy plus the pair terms, multipliers λ ← λ + w c, the weight ×10 while the mismatch
//! does not shrink fast enough (the loop of the cold solve, its inner solves cut short while the
//! seams are far apart), until every pair agrees to
//! [`crate::assembly::SEAM_REL_TOLERANCE`]. Without limits, one solve of δ2 and the seams.
//! The limits are checked and reported as by [`crate::assembly::flatten_assembly`]; a start
//! that is missing, of the wrong size or not flip-free is flattened from scratch by it instead.

use std::time::Instant;

use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::MatingSeam;

use crate::assembly::joint::Joint;
use crate::assembly::{
    AssemblyError, GroupSolve, INITIAL_WEIGHT, SEAM_REL_TOLERANCE, edge_pairs, flatten_assembly,
    group_warnings,
};
use crate::limits::{BARRIER_WEIGHTS, Barrier, Limits, MARGIN_SHRINK, PENALTY_STIFFNESS};
use crate::nonlinear::kernel::{RestTri, SymDirichlet, WithLimits};
use crate::nonlinear::{ABS_DECREMENT_PER_AREA, mean_density, rest_frames};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method, Timings};

/// Flattens the pieces together as [`flatten_assembly`] does, starting from `starts` (one map
/// per mesh, flip-free). Falls back to [`flatten_assembly`] when a start is unusable, the
/// method is not isometric or pins are given.
pub fn flatten_assembly_from(
    meshes: &[&TriMesh],
    seams: &[MatingSeam],
    starts: &[&[DVec2]],
    params: &FlattenParams,
) -> Result<Vec<Flattening>, AssemblyError> {
    for s in seams {
        s.check(meshes)?;
    }
    let usable = params.method == Method::Isometric
        && params.pins.is_empty()
        && starts.len() == meshes.len()
        && meshes
            .iter()
            .zip(starts)
            .all(|(m, x)| x.len() == m.positions.len());
    if !usable {
        return flatten_assembly(meshes, seams, params);
    }
    let mut offset = Vec::with_capacity(meshes.len());
    let mut rest: Vec<RestTri> = Vec::new();
    let mut x: Vec<DVec2> = Vec::new();
    for (p, (m, s)) in meshes.iter().zip(starts).enumerate() {
        let r = rest_frames(m).map_err(|source| AssemblyError::Piece { piece: p, source })?;
        offset.push(x.len());
        rest.extend(r.into_iter().map(|mut t| {
            t.v = t.v.map(|v| v + offset[p]);
            t
        }));
        x.extend_from_slice(s);
    }
    let seam_refs: Vec<&MatingSeam> = seams.iter().collect();
    let pairs = edge_pairs(meshes, &seam_refs, &offset);
    let fail = |source: FlattenError| AssemblyError::Piece { piece: 0, source };
    let joint = Joint::new(&rest, &pairs, x.len()).map_err(|reason| {
        fail(FlattenError::Solver {
            stage: "assembly",
            reason,
        })
    })?;
    if !joint.total_energy(&SymDirichlet, &x).is_finite() {
        return flatten_assembly(meshes, seams, params);
    }
    let started = Instant::now();
    let area: f64 = rest.iter().map(|r| r.area).sum();
    let mut solve = GroupSolve {
        joint,
        params,
        abs: ABS_DECREMENT_PER_AREA * area,
        iterations: 0,
        budget: params.stage_budget("seams", started),
    };
    solve.joint.weight = INITIAL_WEIGHT;
    let limits = Limits::of(params).map_err(fail)?;
    let no_convergence = |reason: String| {
        fail(FlattenError::NoConvergence {
            method: Method::Isometric,
            reason,
        })
    };
    let mut stages = Vec::new();
    match limits {
        None => {
            x = solve.run(&SymDirichlet, x).map_err(no_convergence)?;
            stages.push(solve.budget.count());
        }
        Some(l) => {
            x = within_limits(&mut solve, &rest, x, l).map_err(no_convergence)?;
            stages.push(solve.budget.count());
            solve.budget =
                solve
                    .budget
                    .next_capped("limits", params.stage_iters, params.time_limit);
            x = optimise_within(&mut solve, &rest, x, l).map_err(no_convergence)?;
            stages.push(solve.budget.count());
        }
    }
    if params.hooks.cancelled() {
        return Err(fail(FlattenError::Cancelled {
            method: Method::Isometric,
        }));
    }
    let timed_out = stages.iter().any(|s| s.stopped);
    let mismatch = solve.joint.max_mismatch(&x);
    Ok(meshes
        .iter()
        .enumerate()
        .map(|(p, m)| {
            let uv = x[offset[p]..offset[p] + m.positions.len()].to_vec();
            let warnings = group_warnings(m, &uv, limits, mismatch, timed_out);
            let frames = rest_frames(m).unwrap_or_default();
            Flattening {
                info: FlattenInfo {
                    iterations: stages.iter().map(|s| s.iterations).sum(),
                    final_energy: mean_density(&frames, &uv, &SymDirichlet),
                    warnings,
                    stages: stages.clone(),
                    timings: Timings::default(),
                },
                uv,
            }
        })
        .collect())
}

/// The seams brought equal under the feasibility penalty, its aim drawn further inside while
/// the map breaks a limit; the map as far as it came when it still does (reported by the
/// caller). From a start within the limits the penalty starts at its highest stiffness; from
/// one beyond them it rises through every stiffness first, as from scratch.
fn within_limits(
    solve: &mut GroupSolve,
    rest: &[RestTri],
    mut x: Vec<DVec2>,
    l: Limits,
) -> Result<Vec<DVec2>, String> {
    let last = PENALTY_STIFFNESS.len() - 1;
    let from = if l.hold(rest, &x) { last } else { 0 };
    let stages = PENALTY_STIFFNESS[from..]
        .iter()
        .map(|&k| (k, 1.0))
        .chain(MARGIN_SHRINK.iter().map(|&f| (PENALTY_STIFFNESS[last], f)));
    for (k, factor) in stages {
        let aim = l.aim(factor);
        let e = WithLimits {
            inner: SymDirichlet,
            s_max: aim.hi,
            s_min: aim.lo,
            k,
        };
        x = solve.run(&e, x)?;
        if l.hold(rest, &x) || solve.budget.spent() {
            break;
        }
    }
    Ok(x)
}

/// δ2 optimised within the limits by the barrier stages, the seams kept equal; a stage whose
/// result breaks a limit or the seams is not taken.
fn optimise_within(
    solve: &mut GroupSolve,
    rest: &[RestTri],
    mut x: Vec<DVec2>,
    l: Limits,
) -> Result<Vec<DVec2>, String> {
    if !l.hold(rest, &x) {
        return Ok(x);
    }
    let before = solve.joint.max_mismatch(&x);
    for mu in BARRIER_WEIGHTS {
        if solve.budget.spent() {
            break;
        }
        let e = Barrier {
            inner: SymDirichlet,
            limits: l,
            mu,
        };
        let y = solve.run(&e, x.clone())?;
        if l.hold(rest, &y) && solve.joint.max_mismatch(&y) <= before.max(SEAM_REL_TOLERANCE) {
            x = y;
        }
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Budget;
    use crate::assembly::{SEAM_REPORT_REL, STAGE_WEIGHT};
    use crate::testmesh::spherical_cap;
    use crate::{flatten, nonlinear::kernel::singular_values};
    use flatcut_mesh::mating::coincident_seams;

    /// The triangles of `mesh` whose centroids lie on one side of x = 0, as a mesh of their
    /// own (vertices renumbered, coordinates kept: the cut's vertices are on both sides).
    fn side(mesh: &TriMesh, left: bool) -> TriMesh {
        let tris: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .filter(|t| {
                (t.iter().map(|&v| mesh.positions[v as usize].x).sum::<f64>() < 0.0) == left
            })
            .copied()
            .collect();
        let mut index = vec![u32::MAX; mesh.positions.len()];
        let mut positions = Vec::new();
        let tris = tris
            .iter()
            .map(|t| {
                t.map(|v| {
                    if index[v as usize] == u32::MAX {
                        index[v as usize] = positions.len() as u32;
                        positions.push(mesh.positions[v as usize]);
                    }
                    index[v as usize]
                })
            })
            .collect();
        TriMesh::new(positions, tris)
    }

    /// The two halves of a 100 mm ball's cap, each flattened alone within ±5 % (their seam's
    /// sides then differ), the seam between them and the parameters that hold ±5 %.
    fn halves() -> (
        Vec<TriMesh>,
        Vec<Vec<DVec2>>,
        Vec<MatingSeam>,
        FlattenParams,
    ) {
        let cap = spherical_cap(50.0, 0.8, 12);
        let pieces = vec![side(&cap, true), side(&cap, false)];
        let params = FlattenParams::new(Method::Isometric)
            .with_max_stretch_pct(Some(5.0))
            .with_max_compress_pct(Some(5.0));
        let starts = pieces
            .iter()
            .map(|p| flatten(p, &params).unwrap().uv)
            .collect();
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        let seams = coincident_seams(&refs, &["1", "2"]);
        (pieces, starts, seams, params)
    }

    /// The largest relative difference of two sewn edges' flat lengths.
    fn seam_mismatch(pieces: &[TriMesh], x: &[&[DVec2]], seams: &[MatingSeam]) -> f64 {
        let mut worst: f64 = 0.0;
        for s in seams {
            let [a, b] = &s.sides;
            for k in 0..a.vertices.len() - 1 {
                let len = |side: &flatcut_mesh::mating::SeamSide| {
                    let (u, v) = (side.vertices[k] as usize, side.vertices[k + 1] as usize);
                    x[side.piece][u].distance(x[side.piece][v])
                };
                let l3 = pieces[a.piece].positions[a.vertices[k] as usize]
                    .distance(pieces[a.piece].positions[a.vertices[k + 1] as usize]);
                worst = worst.max((len(a) - len(b)).abs() / l3);
            }
        }
        worst
    }

    /// Every face's principal stretches of `mesh` mapped by `x`, as (largest, least).
    fn extremes(mesh: &TriMesh, x: &[DVec2]) -> (f64, f64) {
        let rest = rest_frames(mesh).unwrap();
        rest.iter().fold((0.0_f64, f64::INFINITY), |(hi, lo), r| {
            let (s1, s2) = singular_values(r.jacobian(x));
            (hi.max(s1), lo.min(s2))
        })
    }

    #[test]
    fn pieces_flattened_alone_are_sewn_within_the_limits_from_their_own_maps() {
        let (pieces, starts, seams, params) = halves();
        assert_eq!(seams.len(), 1);
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        let x0: Vec<&[DVec2]> = starts.iter().map(Vec::as_slice).collect();
        // Flattened alone, the two sides of the seam differ: there is something to solve.
        assert!(seam_mismatch(&pieces, &x0, &seams) > 1e-5);
        let flats = flatten_assembly_from(&refs, &seams, &x0, &params).unwrap();
        let x: Vec<&[DVec2]> = flats.iter().map(|f| f.uv.as_slice()).collect();
        assert!(seam_mismatch(&pieces, &x, &seams) < SEAM_REPORT_REL);
        for (p, f) in pieces.iter().zip(&flats) {
            assert!(f.info.warnings.is_empty(), "{:?}", f.info.warnings);
            let (hi, lo) = extremes(p, &f.uv);
            assert!(hi <= 1.05 && lo >= 0.95, "stretches {lo}..{hi}");
        }
        // The inner solves stop at the caller's tolerance: 26 Newton steps for the seams and the
        // limits (35 with each held to 1e-4 of it, every outer iteration running to its cap).
        assert!(
            flats[0].info.iterations <= 30,
            "{}",
            flats[0].info.iterations
        );
        // The same input gives the same bits.
        let again = flatten_assembly_from(&refs, &seams, &x0, &params).unwrap();
        assert!(flats.iter().zip(&again).all(|(a, b)| a.uv == b.uv));
    }

    #[test]
    fn a_start_that_is_turned_over_is_flattened_from_scratch() {
        let (pieces, mut starts, seams, params) = halves();
        for q in &mut starts[1] {
            q.x = -q.x;
        }
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        let x0: Vec<&[DVec2]> = starts.iter().map(Vec::as_slice).collect();
        let warm = flatten_assembly_from(&refs, &seams, &x0, &params).unwrap();
        let cold = flatten_assembly(&refs, &seams, &params).unwrap();
        assert!(warm.iter().zip(&cold).all(|(a, b)| a.uv == b.uv));
    }

    #[test]
    fn each_stage_starts_from_a_moderate_weight_whatever_the_last_left() {
        // The feasibility stage from the halves' own maps (their seam apart), once after a
        // stage that left the weight at its cap and once from the stage weight: the same steps
        // and the same map, the weight the stage before raised not carried into it.
        let (pieces, starts, seams, params) = halves();
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        let mut offset = Vec::new();
        let (mut rest, mut x0) = (Vec::new(), Vec::new());
        for (m, s) in refs.iter().zip(&starts) {
            offset.push(x0.len());
            let o = x0.len();
            rest.extend(rest_frames(m).unwrap().into_iter().map(|mut t| {
                t.v = t.v.map(|v| v + o);
                t
            }));
            x0.extend_from_slice(s);
        }
        let seam_refs: Vec<&MatingSeam> = seams.iter().collect();
        let pairs = edge_pairs(&refs, &seam_refs, &offset);
        let l = Limits::of(&params).unwrap().unwrap();
        let e = WithLimits {
            inner: SymDirichlet,
            s_max: l.aim(1.0).hi,
            s_min: l.aim(1.0).lo,
            k: PENALTY_STIFFNESS[PENALTY_STIFFNESS.len() - 1],
        };
        let run = |weight: f64| {
            let mut solve = GroupSolve {
                joint: Joint::new(&rest, &pairs, x0.len()).unwrap(),
                params: &params,
                abs: 0.0,
                iterations: 0,
                budget: Budget::none("test"),
            };
            solve.joint.weight = weight;
            let x = solve.run(&e, x0.clone()).unwrap();
            (x, solve.iterations)
        };
        let (capped, moderate) = (run(crate::assembly::MAX_WEIGHT), run(STAGE_WEIGHT));
        assert!(capped.1 > 0);
        assert_eq!(capped.1, moderate.1, "Newton steps");
        assert!(capped.0 == moderate.0, "maps differ");
    }
}
