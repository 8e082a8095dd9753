//! Splitting seams: a piece cut right through into pieces that are sewn back together, for where
//! no dart can bring it within its limits. A dart takes a wedge out; where the flat piece is too
//! short rather than too long (a saddle's rim, the flare of a collar) a wedge only makes it worse,
//! and the pattern maker splits the piece instead (OptCuts' setting: cuts that end on the outline
//! at both ends).
//!
//! Method, greedy as a pattern maker adds seams, worst place first:
//! 1. **Candidates.** In the piece's current flat map, straight chords of the flat outline through
//!    the face of largest limit excess, through the piece's middle and through the middle of its
//!    excess (the faces beyond the limits weighted by their area and excess: where the excess is
//!    spread, round a ring's inner side or over an elephant's head, the worst face is one of
//!    many, and a chord through it or the middle passes beside most of them), in [`DIRECTIONS`]
//!    directions each. A chord is carried onto the surface (its points found in the flat
//!    triangles and lifted to 3D, then traced along the surface as a style line,
//!    [`flatcut_mesh::lines`]), so the cut is a smooth line the sewer can follow. And the cuts
//!    from the outline through the cone next to that face (the vertex whose 3D angle sum is
//!    farthest from a full turn) and on to the outline ([`crate::cone`]): no chord beside a cone
//!    frees it, however small the parts get.
//! 2. **Choice.** A chord that splits the piece into two disks, neither smaller than
//!    [`MIN_AREA_SHARE`] of it, is scored by the larger of the two halves' limit excess, each
//!    half flattened on its own (isometric, without limits). The lowest score wins, the cheaper
//!    seam on a tie (below). A chord with a side under [`MIN_SURFACE_SHARE`] of the whole
//!    surface is taken only when no other chord brings the piece's excess down (flattened on its
//!    own as the halves are): a toe's tip or an eyelet's rim may need a small part of its own,
//!    but a part cut small where a larger one would do is a sliver no one wants to sew.
//! 3. **All pieces together.** The pieces are flattened together, the two sides of every seam
//!    kept at equal lengths edge by edge and the limits held ([`flatcut_flatten::assembly`]); while
//!    a piece is still beyond the limits and fewer than `max_pieces` exist, the worst is split
//!    again.
//!
//! A surface that is not a disk (closed, of any genus, or with several boundary loops) cannot be
//! flattened at all: [`split_surface`] first opens it into disks ([`crate::open`]: its handles
//! cut along short loops, its holes joined, a sphere slit) and goes on from those. New parts are
//! judged flattened on their own with the limits held (the two sides of a cut side by side);
//! all parts are flattened together only when they look done (step 3 is then the proof, or it
//! sends the loop on).
//!
//! Among the chords, one whose two halves both come within the limits, or that ties on the
//! excess within [`SCORE_TIE`], is chosen by its seam cost ([`crate::seam_cost`]: length weighted
//! by visibility, and turning) before its excess. The chords are judged side by side (rayon,
//! results taken in the order of the candidates, so the choice does not depend on the threads),
//! each half by [`CANDIDATE_ITERS`] Newton steps at most: enough to rank them.
//!
//! Parts are sewn back where a cut is no longer needed ([`crate::resew`]): a side of a cut that
//! holds the end of the sphere's opening slit has that slit sewn shut (a slit ending inside a
//! part is a V no seam allowance fits in), and once every part is within the limits,
//! neighbours whose union still lies within them are merged, the pairs sharing the longest
//! seams first (the fewest pieces for the limits: a ball within ±10 % comes as the two halves
//! of a tennis ball); where those rounds leave at most [`crate::fewest::FEWEST_EXACT`] parts,
//! the groupings of them are searched for the fewest parts, then the shortest seams
//! ([`crate::fewest`]), as the longest seams first can pair parts so that none merges after.
//! A union the split's capped solve leaves just beyond the limits
//! ([`MERGE_NEAR_MISS`]) is solved again with the flattener's full steps before it is refused.
//! The merged pieces are kept only when their joint solve holds the limits.
//!
//! A part within the limits can still overlap itself flat (a long limb or a ring laid out past
//! a full turn): its outline crossing itself ([`crate::crossing`]) makes it a piece to cut like
//! one beyond the limits, by chords through the face at the crossing and by its necks (the
//! shortest ways across it from points round its outline); candidates whose halves overlap
//! themselves rank last. A split that cannot undo an overlap within its pieces or time is an
//! error ([`DartError::SplitOverlap`]), never a result.
//!
//! The loop stops early on its time limit (returning the best split so far, `timed_out`; once
//! every part is within the limits, the merging of neighbours stops there too, the parts then
//! all valid but perhaps more than needed) and
//! on the flattening hooks' cancel flag (an error; the candidates not yet judged are skipped);
//! it reports its progress through them. The time limit bounds the whole split, from the
//! opening on: every solve runs within the time left (`until_limit`), the candidates stop
//! being judged, and a joint solve the limit stops with a seam's sides still apart is not the
//! result: the last split whose joint solve held them is (or, where none did, these parts,
//! `seams_apart`). The split ends within its limit and the Newton step, or the candidate, under
//! way when it ran out, and the checks after (a 9,216-face ring with a limit of 0.5 s CPU: 0.52
//! s, where the joint solve used to run on for 13 s).
//!
//! The seams between the final pieces are found by their coincident vertices
//! ([`flatcut_mesh::mating::coincident_seams`]): a cut's vertices are copied to both of its sides
//! with the same coordinates, and a cut ends at an outline vertex, so it adds no vertex to one
//! side of an earlier seam that the other side lacks.
//!
//! Why chords of the flat map rather than OptCuts' joint optimisation of cuts and map: a few
//! candidates, each judged by the flattener itself, give seams a pattern maker would draw (smooth,
//! across the strain) at the cost of a handful of solves per cut, and the limit solve of the
//! assembled pieces is the proof that the limits hold.

use flatcut_flatten::assembly::SEAM_REPORT_REL;
use flatcut_flatten::flatten_assembly_from;
use flatcut_flatten::nonlinear::kernel::rest_frames;
use flatcut_flatten::{FlattenParams, Method};
use flatcut_geom::{DVec2, DVec3, polygon};
use flatcut_mesh::lines::{LineSpec, embed_lines};
use flatcut_mesh::mating::{MatingSeam, coincident_seams};
use flatcut_mesh::regions::split_along_lines;
use flatcut_mesh::{Topology, TriMesh, check_disk};

use rayon::prelude::*;
use std::collections::BTreeMap;
use std::time::Duration;

use crate::clock::CpuClock;
use crate::cone;
use crate::crossing::outline_crossing;
use crate::fewest::{Parts, Verdict, fewest};
use crate::limits::{Band, Limits, face_excess};
use crate::resew::{close_slits, merge};
use crate::seam_cost::{SeamCost, Visibility};
use crate::{DartError, KeepOut};

/// How far inside the limits (log strain, 0.001 % of stretch) the assembled parts are held: the
/// flattener's limits land on their bound, and a map written to a file (to a micrometre) and
/// checked independently must still be within it.
const HELD_INSIDE: f64 = 1e-5;
/// Newton steps of each solve of a flattening that holds the limits (the parts alone, and all
/// of them together): the limits are brought in by a dozen solves of rising stiffness, and in
/// the joint solve each of them runs the seams' augmented Lagrangian again. At the flattener's
/// 200 steps a joint solve of the 7,680-face torus's parts took 3,200–3,700 Newton steps (70–96 s
/// under load, several times per split); at 30 it takes 170–900, and the limits still hold (the
/// check after every joint solve is what decides).
pub const HELD_SOLVE_ITERS: usize = 30;
/// Relative energy decrease below which those solves stop: the split needs a map within the
/// limits with its seams equal, not the last digits of its energy.
pub const HELD_REL_TOLERANCE: f64 = 1e-6;
/// Directions of the chords tried through each centre, evenly over a half turn.
pub const DIRECTIONS: usize = 8;
/// Points of a chord lifted to the surface between its ends (the trace joins them along it).
const CHORD_SAMPLES: usize = 16;
/// Neither side of a cut may be smaller than this share of the piece's area: a sliver cut off
/// the rim relieves nothing and is a piece no one wants to sew.
pub const MIN_AREA_SHARE: f64 = 0.05;
/// Nor smaller than this share of the whole surface being split, while a cut that keeps to it
/// brings the piece's excess down: measured against the piece alone, the least side shrinks
/// with every split, and a piece cut from pieces cut from pieces ends as slivers. As a hard
/// floor it stopped the split where small features need small parts (the genus-3 elephant
/// ended 17–23 % beyond ±10 % at 64 parts, the genus-12 boot with a part it could not cut), so
/// it is a preference.
pub const MIN_SURFACE_SHARE: f64 = 0.003;
/// Excesses (log strain) this close count as a tie, broken by the seam cost.
pub const SCORE_TIE: f64 = 2e-3;
/// Newton steps a candidate's half is flattened with to rank the candidates.
pub const CANDIDATE_ITERS: usize = 12;

/// What to split for.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitOptions {
    /// The limits every face must meet.
    pub band: Band,
    /// Most pieces the piece may become.
    pub max_pieces: usize,
    /// Vertices of the piece no cut may pass (no_cut regions, marks), as for darts; `None`: none.
    pub keep_out: Option<KeepOut>,
    /// Where seams should hide (its flags index the piece's vertices).
    pub visibility: Visibility,
    /// CPU time of the process ([`crate::clock`]) after which the best split so far is
    /// returned (`timed_out`).
    pub time_limit: Option<std::time::Duration>,
    /// The seam allowance the parts will be cut with (mm): no merged part gets a neck too
    /// narrow to take it on both sides ([`merged_neck`]).
    pub seam_allowance_mm: f64,
}

impl SplitOptions {
    /// Default [`SplitOptions::max_pieces`].
    pub const DEFAULT_MAX_PIECES: usize = 32;
}

/// A piece split into pieces.
#[derive(Clone, Debug)]
pub struct Split {
    /// The pieces, each flattened (`flat` set), the first containing the original's first face.
    pub pieces: Vec<TriMesh>,
    /// The seams between them (sides index `pieces`), named `"<a>/<b>"` after the pieces' numbers
    /// (1-based).
    pub seams: Vec<MatingSeam>,
    /// The 3D path of every cut, in the order made.
    pub cuts: Vec<Vec<DVec3>>,
    /// Largest limit excess over every piece's faces (log strain; negative within the limits).
    pub excess: f64,
    /// True when every piece's faces are within the limits (`excess` ≤ 0).
    pub feasible: bool,
    /// Where the largest excess is (3D).
    pub worst_3d: DVec3,
    /// The time limit ended the search before the limits were met or the pieces ran out, or
    /// (every piece within the limits) before neighbours that could be sewn back were merged.
    pub timed_out: bool,
    /// The time limit stopped the joint solve of these parts with a seam's two sides still
    /// apart, and no earlier joint solve had held them equal (`timed_out` is set too): the
    /// best cut found, its seams to be solved again (the report says how far apart they are).
    pub seams_apart: bool,
    /// The inside vertices of the surface split (3D, the largest defect first) whose angle
    /// defect their corners cannot absorb within the limits ([`cone::beyond_reach`]): no part
    /// within the limits holds one inside, so only a split with a seam through every one of them
    /// can meet the limits. A smooth surface has none; a raw scan's spikes are these.
    pub beyond_reach: Vec<DVec3>,
}

impl Split {
    /// Total 3D length of the cuts (mm): the seams to sew.
    pub fn total_cut_mm(&self) -> f64 {
        self.cuts.iter().map(|c| polyline_length(c)).sum()
    }
}

/// Splits `mesh` (flattened as `x0`) until every piece is within the limits of `opts` or it has
/// `opts.max_pieces` pieces; `params` flattens the pieces (their method is taken as isometric,
/// the one that holds seams and limits together). A result that is not `feasible` says how far
/// beyond the limits the best split reached.
pub fn split(
    mesh: &TriMesh,
    x0: &[DVec2],
    params: &FlattenParams,
    opts: &SplitOptions,
) -> Result<Split, DartError> {
    let cpu = CpuClock::start();
    let mut first = mesh.clone();
    first.flat = Some(x0.to_vec());
    let mut s = split_on(mesh, vec![first], Vec::new(), true, params, opts, cpu)?;
    s.beyond_reach = beyond_reach(mesh, opts.band)?;
    Ok(s)
}

/// The inside vertices of `mesh` whose angle defect their corners cannot absorb within `band`
/// ([`cone::beyond_reach`]), the largest defect first (the lower index on a tie).
fn beyond_reach(mesh: &TriMesh, band: Band) -> Result<Vec<DVec3>, DartError> {
    let topo = Topology::build(mesh)?;
    let defects = cone::angle_defects(mesh, &topo);
    let beyond = cone::beyond_reach(mesh, &defects, band);
    let mut at: Vec<usize> = (0..mesh.positions.len()).filter(|&v| beyond[v]).collect();
    at.sort_by(|&a, &b| {
        defects[b]
            .abs()
            .total_cmp(&defects[a].abs())
            .then(a.cmp(&b))
    });
    Ok(at.into_iter().map(|v| mesh.positions[v]).collect())
}

/// Splits a surface that is not a disk (closed, of any genus, or with several boundary loops):
/// it is first opened into disks ([`crate::open::open_surface`]), each flattened on its own, and
/// then split as [`split`] does (the seams of the opening held equal from the first joint solve
/// on). The opening cuts are the first of the result's `cuts`.
pub fn split_surface(
    mesh: &TriMesh,
    params: &FlattenParams,
    opts: &SplitOptions,
) -> Result<Split, DartError> {
    let cpu = CpuClock::start();
    let mut vis = opts.visibility.clone();
    if let Some(k) = &opts.keep_out {
        vis.blocked = k.blocked.clone();
    }
    let opened = crate::open::open_surface(mesh, &vis)?;
    // Each opened part flattened on its own, without limits: where the loop cuts next is all
    // this map is for (the joint solve with the limits held is the last step).
    let free = isometric(params)
        .with_max_stretch_pct(None)
        .with_max_compress_pct(None);
    let mut pieces = opened.pieces;
    for p in &mut pieces {
        let free = until_limit(&free, opts.time_limit, &cpu);
        let f = flatcut_flatten::flatten(p, &free).map_err(DartError::Flatten)?;
        p.flat = Some(f.uv);
    }
    let mut s = split_on(mesh, pieces, opened.cuts, false, params, opts, cpu)?;
    s.beyond_reach = beyond_reach(mesh, opts.band)?;
    Ok(s)
}

/// `p` with every solve stopped where the split's time limit `limit` (CPU time, from `cpu`'s
/// start) runs out: the stage its solves run within (the split's own, or one made for it)
/// stopping at that CPU time ([`flatcut_flatten::Budget::until_cpu`]), so that a joint solve of
/// a large scan started just before the limit stops there with its best map rather than
/// running on. The limit and the solves' deadlines are one clock: a solve on one core spends
/// the CPU time left in as much wall time or more (a busy machine), one that keeps both cores
/// busy in half of it.
fn until_limit(p: &FlattenParams, limit: Option<Duration>, cpu: &CpuClock) -> FlattenParams {
    let Some(limit) = limit else {
        return p.clone();
    };
    let left = limit.saturating_sub(cpu.elapsed());
    let stage = match &p.within {
        Some(b) => b.clone(),
        None => flatcut_flatten::Budget::stage(
            "split",
            p.split_iters,
            None,
            p.hooks.clone(),
            std::time::Instant::now(),
        ),
    };
    p.clone()
        .with_within(Some(stage.until_cpu(cpu.at(limit), left)))
}

/// The flattening parameters that hold the limits of `opts` (a little inside them).
fn held_params(params: &FlattenParams, opts: &SplitOptions) -> FlattenParams {
    // Inside by the margin, or by half a side narrower than it (a 0 % limit stays 0 %).
    let inside = Band {
        ln_s: (opts.band.ln_s - HELD_INSIDE).max(0.5 * opts.band.ln_s),
        ln_c: (opts.band.ln_c + HELD_INSIDE).min(0.5 * opts.band.ln_c),
    };
    let mut p = isometric(params)
        .with_max_stretch_pct(stretch_pct(inside))
        .with_max_compress_pct(compress_pct(inside));
    p.max_iters = p.max_iters.min(HELD_SOLVE_ITERS);
    p.rel_tolerance = p.rel_tolerance.max(HELD_REL_TOLERANCE);
    p
}

/// The greedy loop of the module documentation from `pieces` (each flattened; `together` when
/// flattened together with their seams and limits), the cuts made so far being `cuts`; `mesh`
/// is the piece the keep-out of `opts` is indexed by.
fn split_on(
    mesh: &TriMesh,
    mut pieces: Vec<TriMesh>,
    mut cuts: Vec<Vec<DVec3>>,
    mut together: bool,
    params: &FlattenParams,
    opts: &SplitOptions,
    cpu: CpuClock,
) -> Result<Split, DartError> {
    let held_unbounded = held_params(params, opts);
    // The limit-holding solves, stopped where the time limit runs out.
    let held = || until_limit(&held_unbounded, opts.time_limit, &cpu);
    let guard = Guard::new(mesh, opts.keep_out.as_ref(), &opts.visibility);
    let started = std::time::Instant::now();
    let mut timed_out = false;
    let out_of_time = || opts.time_limit.is_some_and(|t| cpu.elapsed() >= t);
    // The split whose joint solve last held its seams equal, with the least excess: what is
    // returned when the time limit stops a later joint solve with its seams apart.
    let mut valid: Option<Valid> = None;
    // Whether the last joint solve left its seams apart (stopped by its cap or the time).
    let mut apart = false;
    // Whether neighbours were tried for merging, whether any cut was sewn back, and whether the
    // time limit left neighbours unmerged.
    let (mut merged, mut resewn, mut merge_cut_short) = (false, false, false);
    // New parts are judged flattened on their own with the limits held; the parts are flattened
    // together (seams equal) only when that says they are done, and split further if the seams
    // then push one beyond the limits.
    loop {
        if params.hooks.cancelled() {
            return Err(cancelled());
        }
        let (w, excess, face) = worst(&pieces, opts.band)?;
        let crossing = first_crossing(&pieces)?;
        if together && !apart && valid.as_ref().is_none_or(|v| excess <= v.excess) {
            valid = Some(Valid {
                pieces: pieces.clone(),
                cuts: cuts.clone(),
                resewn,
                excess,
            });
        }
        params.hooks.report(&flatcut_flatten::FlattenProgress {
            stage: "split",
            iteration: pieces.len(),
            max_iterations: opts.max_pieces,
            energy: excess,
            elapsed: started.elapsed(),
        });
        timed_out |= out_of_time();
        let full = pieces.len() >= opts.max_pieces.max(1) || timed_out;
        let done = excess <= 0.0 && crossing.is_none();
        if (done || full) && !together {
            apart = !flatten_together(&mut pieces, &held())?;
            if apart && out_of_time() {
                return stopped_apart(pieces, cuts, resewn, valid, opts.band);
            }
            together = true;
            continue;
        }
        // The piece to cut: the worst beyond the limits, else one that overlaps itself flat
        // (cut through the face at the crossing).
        let target = if excess > 0.0 {
            Some((w, face))
        } else {
            crossing.map(|(k, v)| (k, face_at(&pieces[k], v)))
        };
        let next = match target {
            Some((k, t)) if !full => best_cut(
                &pieces[k],
                t,
                excess <= 0.0,
                opts.band,
                &until_limit(params, opts.time_limit, &cpu),
                &guard,
                &out_of_time,
            )?
            .map(|cut| (k, cut)),
            _ => None,
        };
        if params.hooks.cancelled() {
            return Err(cancelled());
        }
        let Some((k, halves)) = next else {
            // The candidates stop being judged when the time runs out.
            timed_out |= out_of_time();
            if !together {
                apart = !flatten_together(&mut pieces, &held())?;
                if apart && out_of_time() {
                    return stopped_apart(pieces, cuts, resewn, valid, opts.band);
                }
                together = true;
                continue;
            }
            // Never a piece that overlaps itself: no pattern can be cut from it.
            if let Some((k, v)) = crossing {
                return Err(DartError::SplitOverlap {
                    parts: pieces.len(),
                    at: pieces[k].positions[v as usize],
                    excess,
                });
            }
            // The fewest pieces: neighbours whose union lies within the limits are sewn back.
            if excess <= 0.0 && !merged {
                merged = true;
                let (mw, short) = if out_of_time() {
                    (None, true)
                } else {
                    merge_within(
                        &pieces,
                        &held(),
                        opts.band,
                        opts.seam_allowance_mm,
                        params,
                        &out_of_time,
                    )?
                };
                merge_cut_short = short;
                if let Some(fewer) = mw {
                    pieces = fewer;
                    resewn = true;
                    continue;
                }
            }
            if apart && timed_out {
                return stopped_apart(pieces, cuts, resewn, valid, opts.band);
            }
            let mut s = finish(pieces, cuts, resewn, opts.band)?;
            s.timed_out = (timed_out && excess > 0.0) || merge_cut_short;
            return Ok(s);
        };
        resewn |= halves.closed_slit;
        let cut = halves.path;
        let mut parts = halves.sides;
        // The two sides side by side: each is its own solve, so the maps are those of one after
        // the other, and an error is the first side's before the second's.
        let solved: Vec<Result<(), DartError>> = parts
            .par_iter_mut()
            .map(|p| {
                let f = flatcut_flatten::flatten(p, &held()).map_err(DartError::Flatten)?;
                p.flat = Some(f.uv);
                Ok(())
            })
            .collect();
        solved.into_iter().collect::<Result<Vec<()>, DartError>>()?;
        let [a, b] = parts;
        pieces[k] = a;
        pieces.push(b);
        cuts.push(cut);
        together = false;
    }
}

/// A split whose parts were flattened together with their seams equal, and its excess.
struct Valid {
    pieces: Vec<TriMesh>,
    cuts: Vec<Vec<DVec3>>,
    resewn: bool,
    excess: f64,
}

/// The split of `pieces` (flattened), made by `cuts` (replaced by the seams that remain where a
/// cut was sewn back, `resewn`), judged against `band`; not `timed_out`.
fn finish(
    pieces: Vec<TriMesh>,
    mut cuts: Vec<Vec<DVec3>>,
    resewn: bool,
    band: Band,
) -> Result<Split, DartError> {
    let (w, excess, face) = worst(&pieces, band)?;
    if let Some((k, v)) = first_crossing(&pieces)? {
        return Err(DartError::SplitOverlap {
            parts: pieces.len(),
            at: pieces[k].positions[v as usize],
            excess,
        });
    }
    let seams = seams_of(&pieces);
    if resewn {
        // The seams that remain are the cuts.
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        cuts = seams.iter().map(|s| s.points_3d(0, &refs)).collect();
    }
    Ok(Split {
        worst_3d: centroid(&pieces[w], face),
        pieces,
        seams,
        cuts,
        excess,
        feasible: excess <= 0.0,
        timed_out: false,
        seams_apart: false,
        beyond_reach: Vec::new(),
    })
}

/// The result of a split whose joint solve the time limit stopped with the seams of `pieces`
/// apart: the split before it whose seams were equal (`valid`), else these pieces as they are
/// (`seams_apart`; the report's seam check says how far apart); `timed_out` either way.
fn stopped_apart(
    pieces: Vec<TriMesh>,
    cuts: Vec<Vec<DVec3>>,
    resewn: bool,
    valid: Option<Valid>,
    band: Band,
) -> Result<Split, DartError> {
    let mut s = match valid {
        Some(v) => finish(v.pieces, v.cuts, v.resewn, band)?,
        None => {
            let mut s = finish(pieces, cuts, resewn, band)?;
            s.seams_apart = true;
            s
        }
    };
    s.timed_out = true;
    Ok(s)
}

/// The pieces with neighbours sewn back together wherever their union, flattened alone with the
/// limits held (`held`), lies within `band` and does not overlap itself ([`merge`]): in rounds,
/// the pairs that share the longest seams first, each part in one merge a round; then, for up
/// to [`crate::fewest::FEWEST_EXACT`] pieces, the search for the grouping with the fewest parts and the
/// shortest seams ([`crate::fewest`]), from the judgements of the rounds. The result is
/// flattened together and kept only when every piece is then within the limits without
/// overlap (else the rounds' grouping, if it differs, is tried the same way); `None` when no
/// pair merges or the joint solve undoes them. Once `out_of_time`, no union is judged further
/// and the best grouping so far is the result (the flag returned).
fn merge_within(
    pieces: &[TriMesh],
    held: &FlattenParams,
    band: Band,
    allowance_mm: f64,
    params: &FlattenParams,
    out_of_time: &(dyn Fn() -> bool + Sync),
) -> Result<(Option<Vec<TriMesh>>, bool), DartError> {
    let alone = held
        .clone()
        .with_hooks(flatcut_flatten::FlattenHooks::default());
    // Each solve's own cap raised; the stages' caps are the split's.
    let mut again = alone.clone();
    again.max_iters = params.max_iters.max(alone.max_iters);
    let solves = Solves {
        alone: &alone,
        again: &again,
    };
    // Out of time or cancelled: no union is judged further.
    let stop = || params.hooks.cancelled() || out_of_time();
    let judge = |a: &TriMesh, b: &TriMesh| merged_within(a, b, solves, band, allowance_mm);
    let shared = shared_seams(pieces);
    // Every union judged, by the pieces it is made of (ascending): the same union met again,
    // in a later round or in the search, is judged once.
    let mut judged: BTreeMap<Vec<usize>, Verdict<TriMesh>> = BTreeMap::new();
    // The rounds' grouping: each part, the pieces it is made of.
    let mut groups: Vec<Vec<usize>> = (0..pieces.len()).map(|k| vec![k]).collect();
    let mut cur = pieces.to_vec();
    let mut cut_short = false;
    loop {
        if params.hooks.cancelled() {
            return Err(cancelled());
        }
        if out_of_time() {
            cut_short = true;
            break;
        }
        let mut pairs: Vec<((usize, usize), f64)> = shared_seams(&cur).into_iter().collect();
        pairs.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let union = |i: usize, j: usize| {
            let mut u = [groups[i].as_slice(), groups[j].as_slice()].concat();
            u.sort_unstable();
            u
        };
        // The pairs not judged before, judged side by side; taken in the pairs' order.
        let fresh: Vec<(usize, usize)> = pairs
            .iter()
            .map(|&(ij, _)| ij)
            .filter(|&(i, j)| !judged.contains_key(&union(i, j)))
            .collect();
        // `None`: not judged (out of time).
        let new: Vec<Option<Verdict<TriMesh>>> = fresh
            .par_iter()
            .map(|&(i, j)| (!stop()).then(|| judge(&cur[i], &cur[j])))
            .collect();
        if params.hooks.cancelled() {
            return Err(cancelled());
        }
        for ((i, j), m) in fresh.into_iter().zip(new) {
            match m {
                Some(m) => {
                    judged.insert(union(i, j), m);
                }
                None => cut_short = true,
            }
        }
        let mut used = vec![false; cur.len()];
        let mut gone = vec![false; cur.len()];
        let mut next = cur.clone();
        let mut next_groups = groups.clone();
        for &((i, j), _) in &pairs {
            let Some(Verdict::Within(m)) = judged.get(&union(i, j)) else {
                continue;
            };
            if used[i] || used[j] {
                continue;
            }
            (used[i], used[j], gone[j]) = (true, true, true);
            next[i] = m.clone();
            next_groups[i] = union(i, j);
        }
        if !gone.iter().any(|&g| g) {
            break;
        }
        cur = kept(next, &gone);
        groups = kept(next_groups, &gone);
    }
    // The grouping with the fewest parts, from what the rounds judged.
    let mut tries = Vec::new();
    if !cut_short {
        let parts = Parts {
            parts: pieces,
            shared: &shared,
            judged: &judged,
        };
        if let Some(f) = fewest(&parts, &judge, &stop) {
            if params.hooks.cancelled() {
                return Err(cancelled());
            }
            cut_short |= f.cut_short;
            judged.extend(f.judged);
            if f.groups != groups {
                tries.push(f.groups);
            }
        }
    }
    tries.push(groups);
    for groups in tries {
        if groups.len() == pieces.len() {
            continue;
        }
        let mut cur: Vec<TriMesh> = groups
            .iter()
            .map(|g| match g.as_slice() {
                [k] => Some(pieces[*k].clone()),
                _ => match judged.get(g) {
                    Some(Verdict::Within(m)) => Some(m.clone()),
                    _ => None,
                },
            })
            .collect::<Option<_>>()
            .ok_or_else(|| DartError::Internal("a merged part was not judged".into()))?;
        if !matches!(flatten_together(&mut cur, held), Ok(true)) {
            continue;
        }
        let (_, e, _) = worst(&cur, band)?;
        if e <= 0.0 && first_crossing(&cur)?.is_none() {
            return Ok((Some(cur), cut_short));
        }
    }
    Ok((None, cut_short))
}

/// The seam length (mm, along the 3D seam) shared by each pair of neighbouring pieces
/// `(i, j)`, `i < j`.
fn shared_seams(pieces: &[TriMesh]) -> BTreeMap<(usize, usize), f64> {
    let refs: Vec<&TriMesh> = pieces.iter().collect();
    let mut shared: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    for s in seams_of(pieces) {
        let (i, j) = (s.sides[0].piece, s.sides[1].piece);
        if i != j {
            *shared.entry((i.min(j), i.max(j))).or_default() +=
                polyline_length(&s.points_3d(0, &refs));
        }
    }
    shared
}

/// How far beyond the limits (log strain) a merged part flattened alone may come out and still
/// be solved again with the flattener's full steps (`Solves::again`). The solves that hold the
/// limits stop at [`HELD_SOLVE_ITERS`] steps, and a union that lies within the limits can come
/// out a hair beyond them there: the quarters of the ±10 % ball at 0.02 % beyond on one
/// diagonal and within on the other, so that it came in three parts instead of the two halves
/// of a tennis ball. A union far beyond them is not worth the longer solve.
pub const MERGE_NEAR_MISS: f64 = 5e-3;

/// The flattenings a merged part is judged by: `alone` (the limits held, the split's capped
/// steps), and `again` from that map (the flattener's full steps) where it came out within
/// [`MERGE_NEAR_MISS`] beyond the limits.
#[derive(Clone, Copy)]
struct Solves<'a> {
    alone: &'a FlattenParams,
    again: &'a FlattenParams,
}

/// `a` and `b` sewn into one part, flattened alone with `solves` (the limits held): within
/// when it lies within `band`, has no neck too narrow for `allowance_mm` and does not overlap
/// itself flat; beyond when its map is beyond the limits or overlaps itself; unfit when the
/// union is not one disk, its neck is too narrow or a solve fails.
fn merged_within(
    a: &TriMesh,
    b: &TriMesh,
    solves: Solves,
    band: Band,
    allowance_mm: f64,
) -> Verdict<TriMesh> {
    let Some(mut m) = merge(a, b) else {
        return Verdict::Unfit;
    };
    let judged = (|| {
        m.flat = Some(flatcut_flatten::flatten(&m, solves.alone).ok()?.uv);
        let (_, mut e, _) = worst(std::slice::from_ref(&m), band).ok()?;
        if e > 0.0 && e <= MERGE_NEAR_MISS {
            let start = m.flat.as_deref()?;
            let f = flatten_assembly_from(&[&m], &[], &[start], solves.again).ok()?;
            m.flat = f.into_iter().next().map(|f| f.uv);
            e = worst(std::slice::from_ref(&m), band).ok()?.1;
        }
        let x = m.flat.as_deref()?;
        let beyond = e > 0.0 || outline_crossing(&m, x).ok()?.is_some();
        let wide = narrowest_neck(&m, x)? >= merged_neck(m.area(), allowance_mm);
        Some((beyond, wide))
    })();
    match judged {
        Some((true, _)) => Verdict::Beyond,
        Some((false, true)) => Verdict::Within(m),
        _ => Verdict::Unfit,
    }
}

/// The items of `v` whose `gone` flag is not set, in order.
fn kept<T>(v: Vec<T>, gone: &[bool]) -> Vec<T> {
    v.into_iter()
        .zip(gone)
        .filter_map(|(p, &g)| (!g).then_some(p))
        .collect()
}

/// The narrowest neck a merged part may have, as a share of the square root of its area: two
/// parts that meet at a corner or along a short seam make a piece of two lobes on a thin waist
/// (or a long peel), within the limits but no piece to sew.
pub const MERGED_NECK: f64 = 0.15;

/// The narrowest neck a merged part of `area` (mm²) cut with a seam allowance of
/// `allowance_mm` may have: [`MERGED_NECK`] of the square root of its area, and never less than
/// twice the allowance (the allowances of the neck's two sides would meet across it, and the
/// cut line would run across the piece).
pub fn merged_neck(area: f64, allowance_mm: f64) -> f64 {
    (MERGED_NECK * area.sqrt()).max(2.0 * allowance_mm)
}

/// The narrowest neck of the flat outline of `mesh` (map `x`): the least distance between two
/// outline vertices at least three times as far apart round the outline, and a tenth of it
/// (the sides of a corner are not a neck). `None` for a mesh with no outline.
fn narrowest_neck(mesh: &TriMesh, x: &[DVec2]) -> Option<f64> {
    let topo = Topology::build(mesh).ok()?;
    let rim = topo.boundary_loops.iter().max_by_key(|l| l.len())?;
    let p: Vec<DVec2> = rim.iter().map(|&v| x[v as usize]).collect();
    let n = p.len();
    let mut along = vec![0.0; n + 1];
    for i in 0..n {
        along[i + 1] = along[i] + p[i].distance(p[(i + 1) % n]);
    }
    let round = along[n];
    let mut neck = f64::INFINITY;
    for i in 0..n {
        for j in i + 1..n {
            let a = (along[j] - along[i]).min(round - (along[j] - along[i]));
            let d = p[i].distance(p[j]);
            if a >= 3.0 * d && a >= 0.1 * round {
                neck = neck.min(d);
            }
        }
    }
    Some(neck)
}

/// The error of a split stopped by the flattening hooks' cancel flag.
fn cancelled() -> DartError {
    DartError::Flatten(flatcut_flatten::FlattenError::Cancelled {
        method: Method::Isometric,
    })
}

/// The first piece whose flat outline crosses itself, and the boundary vertex nearest the
/// crossing ([`crate::crossing`]).
fn first_crossing(pieces: &[TriMesh]) -> Result<Option<(usize, u32)>, DartError> {
    for (k, p) in pieces.iter().enumerate() {
        let x = p
            .flat
            .as_deref()
            .ok_or_else(|| DartError::Internal("a split piece has no map".into()))?;
        if let Some(v) = outline_crossing(p, x)? {
            return Ok(Some((k, v)));
        }
    }
    Ok(None)
}

/// A face of `mesh` at vertex `v` (the first, 0 when none).
fn face_at(mesh: &TriMesh, v: u32) -> usize {
    mesh.triangles
        .iter()
        .position(|t| t.contains(&v))
        .unwrap_or(0)
}

/// `params` with the isometric method (no material's grain): the one that holds seams and limits
/// together.
fn isometric(params: &FlattenParams) -> FlattenParams {
    let mut p = params.clone().with_anisotropy(None);
    p.method = Method::Isometric;
    p
}

/// The band's stretch limit in percent, `None` when open.
fn stretch_pct(b: Band) -> Option<f64> {
    b.ln_s.is_finite().then(|| (b.ln_s.exp() - 1.0) * 100.0)
}

/// The band's compression limit in percent, `None` when open.
fn compress_pct(b: Band) -> Option<f64> {
    b.ln_c.is_finite().then(|| (1.0 - b.ln_c.exp()) * 100.0)
}

/// The piece, its largest face excess and that face.
fn worst(pieces: &[TriMesh], band: Band) -> Result<(usize, f64, usize), DartError> {
    let mut best = (0, f64::NEG_INFINITY, 0);
    for (k, p) in pieces.iter().enumerate() {
        let x = p
            .flat
            .as_deref()
            .ok_or_else(|| DartError::Internal("a split piece has no map".into()))?;
        let rest =
            rest_frames(p).map_err(|t| DartError::Internal(format!("degenerate face {t}")))?;
        for (t, e) in face_excess(&rest, x, &Limits::Band(band))
            .into_iter()
            .enumerate()
        {
            if e > best.1 {
                best = (k, e, t);
            }
        }
    }
    Ok(best)
}

/// The seams between the pieces, named by the pieces' 1-based numbers.
fn seams_of(pieces: &[TriMesh]) -> Vec<MatingSeam> {
    let refs: Vec<&TriMesh> = pieces.iter().collect();
    let names: Vec<String> = (1..=pieces.len()).map(|k| k.to_string()).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    coincident_seams(&refs, &names)
}

/// Flattens the pieces together: seams at equal lengths, the limits of `params` held. False
/// when the solve stopped (at its cap or its time) with a seam's two sides still apart, by more
/// than the flattener reports ([`SEAM_REPORT_REL`] of an edge's length).
fn flatten_together(pieces: &mut [TriMesh], params: &FlattenParams) -> Result<bool, DartError> {
    let seams = seams_of(pieces);
    let flats = {
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        let starts: Vec<&[DVec2]> = pieces.iter().filter_map(|p| p.flat.as_deref()).collect();
        flatten_assembly_from(&refs, &seams, &starts, params)
            .map_err(|e| DartError::Solver(e.to_string()))?
    };
    let stopped = flats
        .iter()
        .any(|f| f.info.stages.iter().any(|s| s.stopped));
    for (p, f) in pieces.iter_mut().zip(flats) {
        p.flat = Some(f.uv);
    }
    Ok(!stopped || seams_apart(pieces, &seams) <= SEAM_REPORT_REL)
}

/// The largest difference between the flat lengths of a seam's two sides, edge by edge, as a
/// share of the edge's 3D length.
fn seams_apart(pieces: &[TriMesh], seams: &[MatingSeam]) -> f64 {
    let mut apart: f64 = 0.0;
    for s in seams {
        let [a, b] = &s.sides;
        let (Some(xa), Some(xb)) = (
            pieces[a.piece].flat.as_deref(),
            pieces[b.piece].flat.as_deref(),
        ) else {
            return f64::INFINITY;
        };
        let pa = &pieces[a.piece].positions;
        for (va, vb) in a.vertices.windows(2).zip(b.vertices.windows(2)) {
            let (a0, a1, b0, b1) = (
                va[0] as usize,
                va[1] as usize,
                vb[0] as usize,
                vb[1] as usize,
            );
            let flat = (xa[a0].distance(xa[a1]) - xb[b0].distance(xb[b1])).abs();
            apart = apart.max(flat / pa[a0].distance(pa[a1]));
        }
    }
    apart
}

/// The best cut of `piece` (see the module documentation): its two sides (each with its own
/// map, flattened alone) and the cut's 3D path. `None` when no chord splits the piece.
/// With `necks`, the shortest ways across the piece from points round its outline are judged
/// too ([`necks`]). Once `out_of_time`, no further candidate is judged (the best of those
/// judged is taken).
fn best_cut(
    piece: &TriMesh,
    worst_face: usize,
    necks: bool,
    band: Band,
    params: &FlattenParams,
    guard: &Guard,
    out_of_time: &(dyn Fn() -> bool + Sync),
) -> Result<Option<Halves>, DartError> {
    let x = piece
        .flat
        .as_deref()
        .ok_or_else(|| DartError::Internal("a split piece has no map".into()))?;
    let topo = Topology::build(piece)?;
    let Some(rim) = topo.boundary_loops.iter().max_by_key(|l| l.len()) else {
        return Ok(None);
    };
    let outline: Vec<DVec2> = rim.iter().map(|&v| x[v as usize]).collect();
    let rim3: Vec<DVec3> = rim.iter().map(|&v| piece.positions[v as usize]).collect();
    let mut free = isometric(params)
        .with_max_stretch_pct(None)
        .with_max_compress_pct(None)
        .with_hooks(flatcut_flatten::FlattenHooks::default());
    free.max_iters = free.max_iters.min(CANDIDATE_ITERS);
    free.time_limit = None;
    let least = MIN_AREA_SHARE * piece.area();
    let preferred = least.max(MIN_SURFACE_SHARE * guard.area);
    let tri = piece.triangles[worst_face];
    let mut centres = vec![tri.iter().map(|&v| x[v as usize]).sum::<DVec2>() / 3.0];
    centres.extend(polygon::area_centroid(&outline).filter(|&c| polygon::contains(&outline, c)));
    let mut bare = piece.clone();
    bare.flat = None;
    let mut lines = chords(&centres);
    if necks {
        lines.extend(self::necks(piece, rim).into_iter().map(Line::Path));
    } else {
        // Through the cone next to the worst face, which no chord beside it frees.
        let defects = cone::angle_defects(piece, &topo);
        if let Some(v) = cone::worst_cone(piece, &defects, worst_face) {
            lines.extend(
                cone::cuts_through(piece, &defects, rim, v)
                    .into_iter()
                    .map(Line::Path),
            );
        }
        // Through the middle of the excess too: where it is spread, the worst face is one of
        // many. Judged with the others, in one batch: judged apart, the second batch's eight
        // chords waited for the slowest of the first.
        if let Some(c) = excess_centre(piece, x, band)?.filter(|&c| polygon::contains(&outline, c))
        {
            lines.extend(chords(&[c]));
        }
    }
    // Judged side by side; taken in the candidates' order.
    let judge = |lines: &[Line]| -> Vec<Candidate> {
        lines
            .par_iter()
            .map(|line| {
                if params.hooks.cancelled() || out_of_time() {
                    return None;
                }
                let points = match line {
                    Line::Chord(c, d) => chord_on_surface(piece, x, &outline, &rim3, *c, *d)?,
                    Line::Path(p) => p.clone(),
                };
                let Halves {
                    mut sides,
                    path,
                    closed_slit,
                } = cut_in_two(&bare, points, least)?;
                let small = sides.iter().any(|s| s.area() < preferred);
                if guard.blocks(&path) {
                    return None;
                }
                let sa = alone_excess(&mut sides[0], &free, band)?;
                let sb = alone_excess(&mut sides[1], &free, band)?;
                let score = sa.max(sb);
                let crossed = sides
                    .iter()
                    .filter(|s| {
                        s.flat
                            .as_deref()
                            .is_none_or(|x| !matches!(outline_crossing(s, x), Ok(None)))
                    })
                    .count();
                score.is_finite().then(|| Candidate {
                    small,
                    crossed,
                    score,
                    cost: guard.cost(&path).total(),
                    halves: Halves {
                        sides,
                        path,
                        closed_slit,
                    },
                })
            })
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect()
    };
    let judged = judge(&lines);
    // The piece's own excess, flattened as the halves are: what a cut must bring down.
    let own = std::cell::OnceCell::new();
    let helps = |b: &Candidate| {
        let own = *own.get_or_init(|| {
            let mut whole = bare.clone();
            alone_excess(&mut whole, &free, band).unwrap_or(f64::INFINITY)
        });
        b.crossed == 0 && b.score < own - SCORE_TIE
    };
    let (small, sized): (Vec<Candidate>, Vec<Candidate>) =
        judged.into_iter().partition(|c| c.small);
    let best = sized
        .into_iter()
        .reduce(|b, c| if c.beats(&b) { c } else { b });
    let Some(small) = small
        .into_iter()
        .reduce(|b, c| if c.beats(&b) { c } else { b })
    else {
        return Ok(best.map(|c| c.halves));
    };
    // A side under the surface share only where no other cut brings the excess down.
    Ok(match best {
        Some(b) if helps(&b) || !small.beats(&b) => Some(b.halves),
        _ => Some(small.halves),
    })
}

/// The middle of the excess of `piece` (flat map `x`): the mean of its faces' flat centroids
/// weighted by their 3D area and their excess over `band`, over the faces beyond it; `None`
/// when none is.
fn excess_centre(piece: &TriMesh, x: &[DVec2], band: Band) -> Result<Option<DVec2>, DartError> {
    let rest =
        rest_frames(piece).map_err(|t| DartError::Internal(format!("degenerate face {t}")))?;
    let (mut weight, mut sum) = (0.0, DVec2::ZERO);
    for (t, e) in face_excess(&rest, x, &Limits::Band(band))
        .into_iter()
        .enumerate()
    {
        if e > 0.0 {
            let w = e * piece.triangle_area(t);
            weight += w;
            sum += piece.triangles[t]
                .iter()
                .map(|&v| x[v as usize])
                .sum::<DVec2>()
                / 3.0
                * w;
        }
    }
    Ok((weight > 0.0).then(|| sum / weight))
}

/// The chords through each of `centres`, in [`DIRECTIONS`] directions evenly over a half turn.
fn chords(centres: &[DVec2]) -> Vec<Line> {
    centres
        .iter()
        .flat_map(|&c| {
            (0..DIRECTIONS).map(move |k| {
                Line::Chord(
                    c,
                    DVec2::from_angle(std::f64::consts::PI * k as f64 / DIRECTIONS as f64),
                )
            })
        })
        .collect()
}

/// A line a piece may be cut along: a chord of its flat outline (through a centre, along a
/// direction), or a path on its surface (3D points).
enum Line {
    Chord(DVec2, DVec2),
    Path(Vec<DVec3>),
}

/// Rim vertices a neck is sought from, evenly round the outline.
const NECK_STARTS: usize = 16;

/// Necks of the piece: from each of [`NECK_STARTS`] vertices evenly round its outline `rim`, the
/// shortest edge path across the piece to the nearest rim vertex at least twice as far round the
/// outline as across. Cutting a piece that overlaps itself flat (a long limb, a ring past a full
/// turn) across such a neck parts its overlapping ends, where a chord of its tangled flat map
/// need not.
fn necks(piece: &TriMesh, rim: &[u32]) -> Vec<Vec<DVec3>> {
    let n = rim.len();
    if n < 4 {
        return Vec::new();
    }
    let p = &piece.positions;
    let mut along = vec![0.0; n];
    for i in 1..n {
        along[i] = along[i - 1] + p[rim[i - 1] as usize].distance(p[rim[i] as usize]);
    }
    let round = along[n - 1] + p[rim[n - 1] as usize].distance(p[rim[0] as usize]);
    let cost = vec![1.0; p.len()];
    (0..NECK_STARTS.min(n))
        .into_par_iter()
        .filter_map(|k| {
            let i = k * n / NECK_STARTS.min(n);
            let d = flatcut_mesh::geodesic::distances_from(piece, rim[i]);
            let (j, _) = (0..n)
                .filter(|&j| {
                    let a = (along[i] - along[j]).abs();
                    a.min(round - a) >= 2.0 * d[rim[j] as usize]
                })
                .map(|j| (j, d[rim[j] as usize]))
                .filter(|(_, dj)| dj.is_finite() && *dj > 0.0)
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
            let path = flatcut_mesh::cut_graph::shortest_path(piece, &cost, rim[i], rim[j])?;
            Some(path.iter().map(|&v| p[v as usize]).collect())
        })
        .collect()
}

/// A chord judged: whether a side is under the surface share ([`MIN_SURFACE_SHARE`]), how many
/// of its two halves overlap themselves flattened alone, the larger excess of the two, its seam
/// cost, and the piece cut along it.
struct Candidate {
    small: bool,
    crossed: usize,
    score: f64,
    cost: f64,
    halves: Halves,
}

impl Candidate {
    /// Fewer halves that overlap themselves first, then lower excess; where both are within the
    /// limits, or tie within [`SCORE_TIE`], the cheaper seam.
    fn beats(&self, other: &Candidate) -> bool {
        if self.crossed != other.crossed {
            return self.crossed < other.crossed;
        }
        let both_within = self.score <= 0.0 && other.score <= 0.0;
        if both_within || (self.score - other.score).abs() <= SCORE_TIE {
            self.cost < other.cost
        } else {
            self.score < other.score
        }
    }
}

/// The keep-out of the piece being split, in 3D: the parts are new meshes, so a cut is checked
/// against the original piece's vertices, a path point taking the flag of its nearest one.
struct Guard {
    mesh: TriMesh,
    /// The nearest-point hierarchy of `mesh`, built once for every cut costed.
    bvh: flatcut_mesh::nearest::Bvh,
    /// The area of the whole surface being split (mm²).
    area: f64,
    blocked: Vec<bool>,
    /// The seams' visibility factor at every vertex.
    factors: Vec<f64>,
}

impl Guard {
    fn new(mesh: &TriMesh, keep_out: Option<&KeepOut>, visibility: &Visibility) -> Self {
        Self {
            mesh: mesh.clone(),
            bvh: flatcut_mesh::nearest::Bvh::new(&mesh.positions, &mesh.triangles),
            area: mesh.area(),
            blocked: keep_out.map_or_else(Vec::new, |k| k.blocked.clone()),
            factors: visibility.vertex_factors(mesh),
        }
    }

    /// What a cut along `path` costs as a seam.
    fn cost(&self, path: &[DVec3]) -> SeamCost {
        SeamCost::of_points_in(&self.mesh, &self.bvh, &self.factors, path)
    }

    /// True when some point of the cut lies at a blocked vertex's place.
    fn blocks(&self, path: &[DVec3]) -> bool {
        if !self.blocked.iter().any(|&b| b) {
            return false;
        }
        path.iter().any(|&p| {
            let v = flatcut_mesh::seams::nearest_vertex(&self.mesh.positions, p) as usize;
            self.blocked.get(v).copied().unwrap_or(false)
        })
    }
}

/// The largest face excess of `side` flattened on its own with `free` (its map is kept);
/// `None` when it cannot be flattened.
fn alone_excess(side: &mut TriMesh, free: &FlattenParams, band: Band) -> Option<f64> {
    let f = flatcut_flatten::flatten(side, free).ok()?;
    let rest = rest_frames(side).ok()?;
    let e = face_excess(&rest, &f.uv, &Limits::Band(band))
        .into_iter()
        .fold(f64::NEG_INFINITY, f64::max);
    side.flat = Some(f.uv);
    Some(e)
}

/// The chord of the flat outline through `c` along `d`, as points on the surface: its two ends on
/// the 3D outline and the points between found in the flat triangles. `None` when the chord does
/// not cross the outline on both sides.
fn chord_on_surface(
    piece: &TriMesh,
    x: &[DVec2],
    outline: &[DVec2],
    rim3: &[DVec3],
    c: DVec2,
    d: DVec2,
) -> Option<Vec<DVec3>> {
    let ha = polygon::ray_hit(outline, c, d)?;
    let hb = polygon::ray_hit(outline, c, -d)?;
    // A cut ends at an outline vertex, never inside an outline edge: a new vertex there would be
    // on this part's side of a seam only, and its neighbour's side would no longer match it
    // vertex for vertex.
    let n = rim3.len();
    let on_rim = |h: polygon::RayHit| rim3[(h.edge + usize::from(h.u > 0.5)) % n];
    let (a3, b3) = (on_rim(ha), on_rim(hb));
    let (a2, b2) = (c + d * ha.t, c - d * hb.t);
    let mut points = vec![a3];
    points.extend(
        (1..CHORD_SAMPLES)
            .filter_map(|j| lift(piece, x, a2.lerp(b2, j as f64 / CHORD_SAMPLES as f64))),
    );
    points.push(b3);
    Some(points)
}

/// The piece cut along the surface line through `points` into exactly two disks, neither under
/// `least` (mm²), and the cut's 3D path.
fn cut_in_two(bare: &TriMesh, points: Vec<DVec3>, least: f64) -> Option<Halves> {
    let spec = LineSpec {
        points,
        notches: Vec::new(),
    };
    let e = embed_lines(bare, std::slice::from_ref(&spec)).ok()?;
    let s = split_along_lines(&e.mesh, &e.lines).ok()?;
    let [a, b] = <[_; 2]>::try_from(s.regions).ok()?;
    for r in [&a, &b] {
        check_disk(&r.mesh).ok()?;
        if r.mesh.area() < least {
            return None;
        }
    }
    let path = e.lines[0]
        .iter()
        .map(|&v| e.mesh.positions[v as usize])
        .collect();
    // A slit the cut leaves ending inside a side is sewn shut there.
    let [(a, ca), (b, cb)] = [a.mesh, b.mesh].map(|m| match close_slits(&m) {
        Some(c) => (c, true),
        None => (m, false),
    });
    Some(Halves {
        sides: [a, b],
        path,
        closed_slit: ca || cb,
    })
}

/// A piece cut in two: its sides, the cut's 3D path, and whether a slit was sewn shut in a side
/// ([`close_slits`]).
struct Halves {
    sides: [TriMesh; 2],
    path: Vec<DVec3>,
    closed_slit: bool,
}

/// The surface point whose flat image is `p`, found in the flat triangle containing it.
fn lift(mesh: &TriMesh, x: &[DVec2], p: DVec2) -> Option<DVec3> {
    mesh.triangles.iter().find_map(|t| {
        let [a, b, c] = t.map(|v| x[v as usize]);
        let den = (b - a).perp_dot(c - a);
        if den.abs() < f64::MIN_POSITIVE {
            return None;
        }
        let wb = (p - a).perp_dot(c - a) / den;
        let wc = (b - a).perp_dot(p - a) / den;
        let wa = 1.0 - wb - wc;
        let inside = [wa, wb, wc].iter().all(|&w| w >= -1e-12);
        inside.then(|| {
            let [pa, pb, pc] = t.map(|v| mesh.positions[v as usize]);
            pa * wa + pb * wb + pc * wc
        })
    })
}

fn polyline_length(p: &[DVec3]) -> f64 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}

fn centroid(mesh: &TriMesh, t: usize) -> DVec3 {
    mesh.corners(t).iter().sum::<DVec3>() / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_flatten::Method;

    /// Environment variable that makes [`limit_clock_child`] measure.
    const LIMIT_CHILD_ENV: &str = "FLATCUT_SPLIT_LIMIT_CHILD";

    /// The measuring half of [`the_solves_stop_on_the_clock_of_the_limit`], run alone in a
    /// child process (the tests beside it spend CPU time while it sleeps); does nothing without
    /// the variable set.
    #[test]
    fn limit_clock_child() {
        if std::env::var_os(LIMIT_CHILD_ENV).is_none() {
            return;
        }
        let params = FlattenParams::new(Method::Isometric);
        let limit = Some(Duration::from_millis(200));
        let cpu = CpuClock::start();
        let budget = |p: &FlattenParams| p.within.clone().expect("a stage with the limit");
        // A process that waits (a busy machine gives it no core) spends none of its CPU
        // limit: after twice the limit of wall time, its solves still have time.
        let held = until_limit(&params, limit, &cpu);
        std::thread::sleep(Duration::from_millis(400));
        assert!(!budget(&held).expired(), "stopped by the wall clock");
        // Nor does the same stage made later, inside an enclosing stage.
        let inside = params
            .clone()
            .with_within(Some(flatcut_flatten::Budget::none("outer")));
        assert!(!budget(&until_limit(&inside, limit, &cpu)).expired());
        // Once the limit's CPU time is spent, they stop.
        crate::clock::alone::busy_until(|| cpu.elapsed() >= Duration::from_millis(250));
        assert!(budget(&held).expired(), "not stopped at the CPU limit");
        assert!(budget(&until_limit(&inside, limit, &cpu)).expired());
        println!("SPLIT-LIMIT-CLOCK-CHECKED");
    }

    /// The split's limit counts the process's CPU time, and its solves stop on that clock
    /// too, not on the wall clock: measured in a child process running [`limit_clock_child`].
    #[test]
    #[cfg(unix)]
    fn the_solves_stop_on_the_clock_of_the_limit() {
        crate::clock::alone::run_alone(
            "split::tests::limit_clock_child",
            LIMIT_CHILD_ENV,
            "SPLIT-LIMIT-CLOCK-CHECKED",
        );
    }

    /// Four flat strips 10 mm × 40 mm side by side (a 40 mm square cut along x = 10, 20, 30),
    /// each mapped flat as it lies: every neighbour pair merges within any limits.
    fn strips() -> Vec<TriMesh> {
        (0..4)
            .map(|k| {
                let mut p = Vec::new();
                for j in 0..=4 {
                    for i in 0..=1 {
                        p.push(DVec3::new(10.0 * (k + i) as f64, 10.0 * j as f64, 0.0));
                    }
                }
                let t = (0..4u32)
                    .flat_map(|j| {
                        let (a, b, c, d) = (2 * j, 2 * j + 1, 2 * j + 3, 2 * j + 2);
                        [[a, b, c], [a, c, d]]
                    })
                    .collect();
                let mut m = TriMesh::new(p, t);
                m.flat = Some(m.positions.iter().map(|q| DVec2::new(q.x, q.y)).collect());
                m
            })
            .collect()
    }

    fn limits() -> (FlattenParams, Band) {
        let band = Band::from_pct(Some(10.0), Some(10.0));
        let opts = SplitOptions {
            band,
            max_pieces: 8,
            keep_out: None,
            visibility: Visibility::default(),
            time_limit: None,
            seam_allowance_mm: 0.0,
        };
        let params = FlattenParams::new(Method::Isometric);
        (held_params(&params, &opts), band)
    }

    #[test]
    fn neighbours_within_the_limits_are_merged_into_one_part() {
        let (held, band) = limits();
        let (merged, cut_short) =
            merge_within(&strips(), &held, band, 0.0, &held, &|| false).unwrap();
        assert!(!cut_short);
        let merged = merged.expect("the strips merge");
        assert_eq!(merged.len(), 1);
        assert!((merged[0].area() - 1600.0).abs() < 1e-9);
    }

    #[test]
    fn merging_stops_when_the_time_is_out_and_says_so() {
        let (held, band) = limits();
        let (merged, cut_short) =
            merge_within(&strips(), &held, band, 0.0, &held, &|| true).unwrap();
        assert!(cut_short);
        assert!(merged.is_none());
    }
}
