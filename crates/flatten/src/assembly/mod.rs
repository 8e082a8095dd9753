//! Pieces that are sewn together, flattened together: the pieces joined by mating seams
//! ([`flatcut_mesh::mating`]) are one problem whose unknowns are every piece's flat vertices, and
//! every pair of corresponding seam edges must come out equally long. Since a seam's sides have
//! their vertices in correspondence (vertex k of one side is sewn to vertex k of the other), equal
//! edges make the two sides equally long and put every notch (a seam vertex) at the same arc
//! length from the seam's start on both. Duncan's f1, where every boundary edge keeps its 3D
//! length, is the one-piece relative of this: here only the two sides must agree, and each may
//! stretch as the material allows.
//!
//! Method (isometric, δ2): each piece's own δ2 optimum is the flip-free start; then an augmented
//! Lagrangian on the edge pairs ([`joint`]): Newton solves of δ2 plus the pair terms,
//! multipliers λ ← λ + w c, weight ×10 (up to `MAX_WEIGHT`) while the mismatch does not shrink
//! fast enough, until every pair agrees to [`SEAM_REL_TOLERANCE`]. Material limits are then brought in as for one piece
//! ([`crate::limits`]), every solve keeping the seam terms. Other methods flatten each piece on
//! its own (a seam then matches only as far as the method keeps boundary lengths: exactly for
//! `developable` and `boundary-isometric`).

pub mod joint;

use crate::internal::InternalError;
use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::{MatingError, MatingSeam};

use crate::limits::{self, EnergySolve, Limits};
use crate::nonlinear::kernel::{IsoEnergy, RestTri, SymDirichlet, rest_frames};
use crate::nonlinear::{ABS_DECREMENT_PER_AREA, mean_density};
use crate::{Budget, FlattenError, FlattenInfo, FlattenParams, Flattening, Method, StageCount};
use joint::{EdgePair, Joint};
use std::time::Instant;

/// Target relative length difference of two sewn edges (|ℓa − ℓb| / L): far below any
/// tolerance of cutting (1e-9 of a 2 mm edge is 2 pm).
pub const SEAM_REL_TOLERANCE: f64 = 1e-9;
/// Relative mismatch above which a seam is reported as not matched.
pub const SEAM_REPORT_REL: f64 = 1e-6;
/// Outer augmented-Lagrangian iterations per solve.
const MAX_OUTER: usize = 16;
/// Initial penalty weight (relative to the δ2 density).
pub(crate) const INITIAL_WEIGHT: f64 = 10.0;
/// Weight growth when the mismatch shrank by less than [`REQUIRED_SHRINK`].
const WEIGHT_GROWTH: f64 = 10.0;
/// Largest penalty weight: the multipliers bring feasible seams equal at a bounded weight, and
/// beyond it the pair terms only make the Newton systems stiffer (a weight left to grow reached
/// 10¹⁶ on a 75k-face split, every solve after it crawling).
pub(crate) const MAX_WEIGHT: f64 = 1e8;
/// Largest weight a solve of a new energy (a stage: the next penalty stiffness, margin or
/// barrier) starts from. The multipliers carry the seams' forces from the stage before; the
/// weight that stage raised to [`MAX_WEIGHT`] only made the new stage's Newton steps crawl:
/// traced on the torus's joint solve, every barrier stage's inner solves ran to their cap at
/// 1e8, converging linearly, and started again from at most 1e5 the solve took 833 Newton
/// steps instead of 1,084 (bunny00's first joint solve 444 instead of 609).
pub(crate) const STAGE_WEIGHT: f64 = 1e5;
/// Factor by which one outer iteration must shrink the mismatch to count as progress.
const REQUIRED_SHRINK: f64 = 0.25;
/// Newton steps of an inner solve while the mismatch is above [`INEXACT_ABOVE`].
const INEXACT_INNER_ITERS: usize = 30;
/// Mismatch above which the inner solves stop early (an inexact augmented Lagrangian).
const INEXACT_ABOVE: f64 = 1e-4;

/// Why pieces could not be flattened together.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AssemblyError {
    /// One piece could not be flattened.
    #[error("piece {piece}: {source}")]
    Piece {
        /// The piece (0-based, in the order given).
        piece: usize,
        /// Why it failed.
        source: FlattenError,
    },
    /// The mating seams are inconsistent.
    #[error(transparent)]
    Seam(#[from] MatingError),
    /// Pins were given; pieces flattened together take none.
    #[error("pieces flattened together cannot be pinned (pins place one piece)")]
    Pins,
}

/// Flattens the pieces, those joined by seams together (see the module documentation). One
/// flattening per mesh, in order.
pub fn flatten_assembly(
    meshes: &[&TriMesh],
    seams: &[MatingSeam],
    params: &FlattenParams,
) -> Result<Vec<Flattening>, AssemblyError> {
    for s in seams {
        s.check(meshes)?;
    }
    let mut out: Vec<Option<Flattening>> = vec![None; meshes.len()];
    for group in groups(meshes.len(), seams) {
        let joined: Vec<&MatingSeam> = seams
            .iter()
            .filter(|s| group.contains(&s.sides[0].piece))
            .collect();
        if joined.is_empty() || params.method != Method::Isometric {
            for &p in &group {
                let f = crate::flatten(meshes[p], params)
                    .map_err(|source| AssemblyError::Piece { piece: p, source })?;
                out[p] = Some(f);
            }
            continue;
        }
        if !params.pins.is_empty() {
            return Err(AssemblyError::Pins);
        }
        let flats = flatten_group(meshes, &group, &joined, params)?;
        for (p, f) in group.iter().zip(flats) {
            out[*p] = Some(f);
        }
    }
    Ok(out
        .into_iter()
        .map(|f| f.expect("every piece is in a group"))
        .collect())
}

/// The pieces joined (directly or through others) by seams, each group sorted; pieces without
/// seams are groups of one.
fn groups(n: usize, seams: &[MatingSeam]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for s in seams {
        let (a, b) = (
            find(&mut parent, s.sides[0].piece),
            find(&mut parent, s.sides[1].piece),
        );
        if a != b {
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut index_of_root = vec![usize::MAX; n];
    for p in 0..n {
        let r = find(&mut parent, p);
        if index_of_root[r] == usize::MAX {
            index_of_root[r] = out.len();
            out.push(Vec::new());
        }
        out[index_of_root[r]].push(p);
    }
    out
}

/// The Newton solves of the joined pieces, each run to seam convergence, within the budget of
/// the stage they belong to (the seams, then the limits).
pub(crate) struct GroupSolve<'a> {
    pub(crate) joint: Joint<'a>,
    pub(crate) params: &'a FlattenParams,
    pub(crate) abs: f64,
    pub(crate) iterations: usize,
    pub(crate) budget: Budget,
}

impl GroupSolve<'_> {
    /// Minimises `energy` with the seam terms from `x` until the seams agree (or stall, or the
    /// stage's budget is spent), the weight starting from at most [`STAGE_WEIGHT`].
    pub(crate) fn run<E: IsoEnergy>(
        &mut self,
        energy: &E,
        mut x: Vec<DVec2>,
    ) -> Result<Vec<DVec2>, String> {
        self.joint.weight = self.joint.weight.min(STAGE_WEIGHT);
        let mut viol = self.joint.max_mismatch(&x);
        for outer in 0..MAX_OUTER {
            if outer > 0 && viol <= SEAM_REL_TOLERANCE || self.budget.spent() {
                break;
            }
            let iters = if viol > INEXACT_ABOVE {
                INEXACT_INNER_ITERS.min(self.params.max_iters)
            } else {
                self.params.max_iters
            };
            let (y, it) = self.joint.minimise(
                energy,
                &x,
                iters,
                self.params.rel_tolerance,
                self.abs,
                &self.budget,
            )?;
            self.iterations += it;
            x = y;
            self.joint.update_multipliers(&x);
            let v = self.joint.max_mismatch(&x);
            if v > REQUIRED_SHRINK * viol {
                self.joint.weight = (self.joint.weight * WEIGHT_GROWTH).min(MAX_WEIGHT);
            }
            viol = v;
        }
        Ok(x)
    }
}

impl EnergySolve for GroupSolve<'_> {
    fn solve<E: IsoEnergy + Copy>(
        &mut self,
        energy: E,
        x: &[DVec2],
    ) -> Result<(Vec<DVec2>, usize), FlattenError> {
        let before = self.iterations;
        let y = self
            .run(&energy, x.to_vec())
            .map_err(|reason| FlattenError::NoConvergence {
                method: Method::Isometric,
                reason,
            })?;
        Ok((y, self.iterations - before))
    }

    fn stopped(&self) -> bool {
        self.budget.spent()
    }
}

/// Flattens the pieces of one group together.
fn flatten_group(
    meshes: &[&TriMesh],
    group: &[usize],
    seams: &[&MatingSeam],
    params: &FlattenParams,
) -> Result<Vec<Flattening>, AssemblyError> {
    // Each piece's own δ2 optimum (no limits yet) is the start.
    let free = FlattenParams {
        max_stretch_pct: None,
        max_compress_pct: None,
        ..params.clone()
    };
    let started = Instant::now();
    let mut offset = vec![usize::MAX; meshes.len()];
    let mut x: Vec<DVec2> = Vec::new();
    let mut rest: Vec<RestTri> = Vec::new();
    let mut own: Vec<FlattenInfo> = Vec::new();
    for &p in group {
        let f = crate::flatten(meshes[p], &free)
            .map_err(|source| AssemblyError::Piece { piece: p, source })?;
        own.push(f.info);
        let r = rest_frames(meshes[p]).map_err(|t| AssemblyError::Piece {
            piece: p,
            source: FlattenError::Internal(InternalError::DegenerateTriangle { triangle: t }),
        })?;
        offset[p] = x.len();
        rest.extend(r.into_iter().map(|mut t| {
            t.v = t.v.map(|v| v + offset[p]);
            t
        }));
        x.extend(f.uv);
    }
    let pairs = edge_pairs(meshes, seams, &offset);
    let joint = Joint::new(&rest, &pairs, x.len()).map_err(|reason| AssemblyError::Piece {
        piece: group[0],
        source: FlattenError::Solver {
            stage: "assembly",
            reason,
        },
    })?;
    let area: f64 = rest.iter().map(|r| r.area).sum();
    let mut solve = GroupSolve {
        joint,
        params,
        abs: ABS_DECREMENT_PER_AREA * area,
        iterations: 0,
        budget: params.budget("seams", started),
    };
    solve.joint.weight = INITIAL_WEIGHT;
    let fail = |reason: String| AssemblyError::Piece {
        piece: group[0],
        source: FlattenError::NoConvergence {
            method: Method::Isometric,
            reason,
        },
    };
    let mut x = solve.run(&SymDirichlet, x).map_err(fail)?;
    let mut group_stages = vec![solve.budget.count()];
    let mut timed_out = solve.budget.expired();
    let limits = Limits::of(params).map_err(|source| AssemblyError::Piece {
        piece: group[0],
        source,
    })?;
    if let Some(l) = limits {
        solve.budget = solve
            .budget
            .next_capped("limits", params.stage_iters, params.time_limit);
        let r =
            limits::enforce(&mut solve, &rest, x, l).map_err(|source| AssemblyError::Piece {
                piece: group[0],
                source,
            })?;
        x = r.x;
        group_stages.push(solve.budget.count());
        timed_out |= solve.budget.expired();
    }
    if params.hooks.cancelled() {
        return Err(AssemblyError::Piece {
            piece: group[0],
            source: FlattenError::Cancelled {
                method: Method::Isometric,
            },
        });
    }
    let mismatch = solve.joint.max_mismatch(&x);
    let mut out = Vec::with_capacity(group.len());
    for (&p, own) in group.iter().zip(own) {
        let n = meshes[p].positions.len();
        let uv = x[offset[p]..offset[p] + n].to_vec();
        let frames = rest_frames(meshes[p]).unwrap_or_default();
        let mut warnings = own.warnings;
        warnings.extend(group_warnings(meshes[p], &uv, limits, mismatch, timed_out));
        let stages: Vec<StageCount> = own.stages.into_iter().chain(group_stages.clone()).collect();
        out.push(Flattening {
            info: FlattenInfo {
                iterations: stages.iter().map(|s| s.iterations).sum(),
                final_energy: mean_density(&frames, &uv, &SymDirichlet),
                warnings,
                stages,
                timings: own.timings,
            },
            uv,
        });
    }
    Ok(out)
}

/// The warnings a piece of a group flattened together carries: the faces beyond `limits`, the
/// group's seams agreeing only to `mismatch` (relative) when above [`SEAM_REPORT_REL`], and a
/// joint solve stopped at its time limit.
pub(crate) fn group_warnings(
    mesh: &TriMesh,
    uv: &[DVec2],
    limits: Option<Limits>,
    mismatch: f64,
    timed_out: bool,
) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some(l) = limits {
        warnings.extend(limits::violations(mesh, uv, l));
    }
    if mismatch > SEAM_REPORT_REL {
        warnings.push(format!(
            "mating seams of this piece's group agree only to {mismatch:.2e} of an edge's length"
        ));
    }
    if timed_out {
        warnings.push(
            "the joint solve of this piece's group stopped at the time limit: the map is flip-free but not fully converged".into(),
        );
    }
    warnings
}

/// The corresponding edges of every seam, in the joint numbering.
pub(crate) fn edge_pairs(
    meshes: &[&TriMesh],
    seams: &[&MatingSeam],
    offset: &[usize],
) -> Vec<EdgePair> {
    let mut out = Vec::new();
    for s in seams {
        let [a, b] = &s.sides;
        let (ma, mb) = (meshes[a.piece], meshes[b.piece]);
        for k in 0..a.vertices.len() - 1 {
            let (a0, a1) = (a.vertices[k] as usize, a.vertices[k + 1] as usize);
            let (b0, b1) = (b.vertices[k] as usize, b.vertices[k + 1] as usize);
            let la = ma.positions[a0].distance(ma.positions[a1]);
            let lb = mb.positions[b0].distance(mb.positions[b1]);
            out.push(EdgePair {
                a: [offset[a.piece] + a0, offset[a.piece] + a1],
                b: [offset[b.piece] + b0, offset[b.piece] + b1],
                l: 0.5 * (la + lb),
            });
        }
    }
    out
}
