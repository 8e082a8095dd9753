//! The search for the darts: how many, where they start, how far they reach.
//!
//! 1. **Demand.** The piece is flattened as if it could be darted everywhere
//!    ([`crate::relaxed`]); the 2D length its outline has beyond the stretch limit is the total
//!    opening W the darts must give at their mouths, and where along the outline it lies says
//!    where the darts go. Where the stretch beyond the limit ends inside the piece is how far
//!    each dart must reach (its *rule length*).
//! 2. **Count.** A dart may open no faster than the material lets its point turn: around the
//!    apex the 3D surface spans 2π, the flat piece 2π − θ, and a fan of faces whose stretches stay
//!    in `[C, S]` spans at least 2π·C/S, so θ ≤ θ_max = 2π(1 − C/S). A dart of length L then opens
//!    at most w(L) = 2L·sin(θ_max/2)·κ at its mouth (κ = [`CURVED_LEGS`] allows for legs that bow
//!    outwards). The first count tried is k₀ = ⌈W / w(L̄)⌉, L̄ the mean rule length.
//! 3. **Placement.** k darts start at the middles of k stretches of the outline carrying equal
//!    demand; each is the geodesic leaving the outline at right angles ([`crate::trace`]), first
//!    [`FIRST_REACH`] of its rule length long, cut along the mesh edges next to it.
//! 4. **Proof.** The cut piece is flattened with the limits as hard constraints
//!    ([`crate::limits::hold`]). Where the limits are still exceeded next to dart points, those
//!    darts grow by [`GROWTH`] of their length (the map carried over as the next start) until
//!    the limits hold, or no dart point is near the excess, or the darts can grow no further.
//! 5. **Fewest.** When k₀ darts fail, k₀ + 1, … are tried; when they succeed, k₀ − 1, … are tried
//!    while they succeed. The answer is the fewest darts that held the limits, each no longer
//!    than the growth needed (so the total length is the smallest the growth steps resolve), and
//!    every attempt is kept in [`Darted::attempts`]. The attempt the search will most likely
//!    ask for next (one fewer after a success, one more after a failure) is computed alongside
//!    the one it asks for, on the other core; the search and its answer are unchanged.
//!
//! Dart legs are kept at equal 2D lengths edge by edge in the final map ([`crate::solve`]).

use flatcut_flatten::nonlinear::kernel::rest_frames;
use flatcut_flatten::{Budget, FlattenParams, Method, flatten};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{Topology, TriMesh, check_disk};

use crate::cut::{CutMesh, Legs, all_pairs};
use crate::embed::{Embedded, embed, transfer};
use crate::fit::{CLOSE_WEIGHTS, DartFit, closing, jammed, shut_points};
use crate::keepout::KeepOut;
use crate::limits::{self, Effort, Held, Limits};
use crate::relaxed::{Yield, face_opening, rim_demand};
use crate::sewn::{Closing, EdgePairs};
use crate::solve::{self, LEG_MATCH_MM};
use crate::trace::{Adjacency, Geodesic, inward_direction, trace};
use crate::{Attempt, Dart, DartError, DartOptions, Darted};

/// Allowance for dart legs that bow outwards and darts that grow past their rule length: a
/// curved dart opens more at its mouth than a straight wedge of the same point angle. Calibrated
/// on the bench's spherical caps, hemisphere and toe at ±3 % (20k faces), where the darts that
/// held opened 0.61–0.64 mm per mm of rule length: with 1.75 the first count tried is the
/// fewest that held on each of them.
pub const CURVED_LEGS: f64 = 1.75;
/// Counts above the largest tried that the search goes on to when every count that held closes
/// a dart past its mouth.
const OVERLAP_MORE_DARTS: usize = 3;
/// Fraction of the rule length a dart first reaches.
pub const FIRST_REACH: f64 = 1.0;
/// Fraction of its length a dart grows by when the limits are exceeded next to its point.
pub const GROWTH: f64 = 0.15;
/// Most growth steps of one attempt.
const MAX_GROWTH_STEPS: usize = 12;
/// An attempt stops when the excess fell by less than this fraction over [`STALL_STEPS`]
/// growth steps: its darts are long enough, too few of them.
const STALL_FRACTION: f64 = 0.1;
const STALL_STEPS: usize = 2;
/// An attempt stops when its excesses head for a limit above this (log strain, 0.2 %).
const PREDICTED_OUT: f64 = 2e-3;
/// The rule length ends where the yielded stretch first falls below this fraction of its
/// largest value along the dart's geodesic.
const REACH_FRACTION: f64 = 0.05;
/// Newton iterations of the relaxed (yielding) flattening, and its stopping rule (the demand
/// needs a few digits).
const RELAXED_ITERS: usize = 80;
const RELAXED_TOLERANCE: f64 = 1e-6;
/// A face counts as part of the excess next to a dart point when its excess is at least this
/// fraction of the largest.
const HOT_FRACTION: f64 = 0.5;
/// A dart point is next to the excess when the excess is within this fraction of the mean
/// distance between neighbouring dart starts.
const NEAR_FRACTION: f64 = 0.5;
/// How far (in edge lengths) a dart's geodesic must run clear of the outline at its mouth.
const MOUTH_CLEARANCE: f64 = 4.0;
/// Total opening below this fraction of the outline's length is no demand at all.
const NO_DEMAND_REL: f64 = 1e-4;

/// The piece and what is known about it, shared by the attempts.
struct Piece<'a> {
    mesh: &'a TriMesh,
    adj: Adjacency,
    opts: &'a DartOptions,
    keep_out: KeepOut,
    /// The outline (outer boundary loop), interior on the left.
    rim: Vec<u32>,
    /// Demand per rim vertex (half of each adjacent rim edge's), mm.
    demand: Vec<f64>,
    /// Yielded stretch per face of the relaxed map.
    opening: Vec<f64>,
    /// The uncut piece's map nearest the limits: every attempt starts from it.
    start: Vec<DVec2>,
}

/// The attempts of the search for the count, one ahead: an attempt is computed together with the
/// one the search will most likely ask for next (`next`), on the other core, since an attempt
/// is a sequence of solves on one mesh that keeps one core busy. The search asks for the same
/// attempts in the same order as without it and each attempt is the same bits, so the answer
/// is too; an attempt computed ahead and never asked for is dropped.
struct Lookahead<'p, 'a> {
    piece: &'p Piece<'a>,
    /// Attempts computed ahead: the count, the outcome, the fork of the budget it was computed
    /// on, and what the budget had used at the fork.
    ready: Vec<(usize, Result<Outcome, DartError>, Budget, usize)>,
}

impl<'p, 'a> Lookahead<'p, 'a> {
    fn new(piece: &'p Piece<'a>) -> Self {
        Self {
            piece,
            ready: Vec::new(),
        }
    }

    /// The attempt with `k` darts; `next` (when not 0, not `k` and not yet computed) is
    /// computed alongside it.
    fn attempt(&mut self, k: usize, next: usize) -> Result<Outcome, DartError> {
        let budget = &self.piece.opts.budget;
        if let Some(i) = self.ready.iter().position(|(j, ..)| *j == k) {
            let (_, outcome, fork, at) = self.ready.swap_remove(i);
            // Taken only where the iterations spent since would have cut none of its solves
            // short: it is then the attempt computed now, bit for bit.
            if budget.join(&fork, at) {
                return outcome;
            }
            return self.piece.attempt(k, budget);
        }
        let ahead = next != 0 && next != k && self.ready.iter().all(|(j, ..)| *j != next);
        if !ahead {
            return self.piece.attempt(k, budget);
        }
        let piece = self.piece;
        let (at, fork) = (budget.used(), budget.fork());
        let (this, that) = rayon::join(|| piece.attempt(k, budget), || piece.attempt(next, &fork));
        self.ready.push((next, that, fork, at));
        this
    }
}

/// One dart while it is being placed: its start on the rim, direction and reach.
#[derive(Clone, Debug)]
struct Plan {
    rim_index: usize,
    dir: DVec3,
    reach: f64,
    max_reach: f64,
}

/// What one attempt reached: the cut, its darts and the map nearest the limits.
struct Outcome {
    emb: Embedded,
    cut: CutMesh,
    darts: Vec<(Vec<u32>, Legs)>,
    held: Held,
}

impl Outcome {
    fn total_length(&self) -> f64 {
        self.darts
            .iter()
            .map(|(p, _)| path_length(&self.emb.mesh, p))
            .sum()
    }

    fn legs(&self) -> Vec<Legs> {
        self.darts.iter().map(|(_, l)| l.clone()).collect()
    }

    /// The outcome with each dart ending where `shut` says ([`shut_points`]; a dart shut up to
    /// its mouth is dropped), from its map `x`: the piece cut again, the map carried over with
    /// the copies the shorter cut joins merged at their mean, and brought within the limits
    /// again. `None` when the merged map folds or cannot be brought within the limits.
    fn shortened(
        &self,
        shut: &[Option<usize>],
        x: &[DVec2],
        limits: &Limits,
        budget: &Budget,
    ) -> Result<Option<Outcome>, DartError> {
        let paths: Vec<Vec<u32>> = self
            .darts
            .iter()
            .zip(shut)
            .filter_map(|((path, _), s)| {
                let end = s.map_or(path.len(), |i| i + 1);
                (end >= 2).then(|| path[..end].to_vec())
            })
            .collect();
        let cut = CutMesh::new(&self.emb.mesh, &paths)?;
        let merged = cut.merge_from(&self.cut, x);
        if !flip_free(&cut.mesh, &merged) {
            debug("shortened: folds");
            return Ok(None);
        }
        let held = limits::reach(&cut.mesh, &merged, limits, Effort::Warm, budget)?;
        if !held.feasible {
            debug(&format!(
                "shortened: infeasible {:.3}%",
                held.excess * 100.0
            ));
            return Ok(None);
        }
        let topo = Topology::build(&self.emb.mesh)?;
        let legs = legs_of(&topo, &self.emb.mesh, &cut, &paths)?;
        Ok(Some(Outcome {
            emb: self.emb.clone(),
            cut,
            darts: paths.into_iter().zip(legs).collect(),
            held,
        }))
    }
}

/// Finds the fewest darts that bring `mesh` (a disk) within the limits, starting from its
/// flattening `x0` (flip-free).
pub fn place(mesh: &TriMesh, x0: &[DVec2], opts: &DartOptions) -> Result<Darted, DartError> {
    let topo = check_disk(mesh)?;
    let limits = &opts.limits;
    let budget = &opts.budget;
    // Demand, reach and count are estimated on the principal stretches ([`Limits::estimate_band`]).
    let band = limits.estimate_band();
    let uncut = CutMesh::new(mesh, &[])?;
    let held = limits::reach(mesh, x0, limits, Effort::Full, budget)?;
    let mut attempts = vec![Attempt {
        darts: 0,
        total_length_mm: 0.0,
        excess: held.excess,
        feasible: held.feasible,
    }];
    if held.feasible {
        let settled = limits::settle(
            mesh,
            &held.x,
            limits,
            &Default::default(),
            Closing::default(),
            budget,
        )?;
        // No dart to draw shut: every fit is this map.
        return Ok(finish(
            mesh,
            &uncut,
            &[],
            settled,
            attempts,
            opts.drill_offset_mm,
            opts.fit,
        ));
    }
    let adj = Adjacency::new(mesh, &topo);
    let rim = topo
        .boundary_loops
        .iter()
        .max_by(|a, b| loop_length(mesh, a).total_cmp(&loop_length(mesh, b)))
        .cloned()
        .unwrap_or_default();
    // 1. Demand, from the relaxed map.
    let rest = rest_of(mesh)?;
    let relaxed = solve::Solves::new(&rest, mesh.positions.len(), budget)
        .newton(Yield::new(band), x0, RELAXED_ITERS, None, RELAXED_TOLERANCE)
        .map_err(DartError::Solver)?;
    let edge_demand = rim_demand(&mesh.positions, &relaxed.x, &rim, band.s_max());
    let total: f64 = edge_demand.iter().sum();
    let n = rim.len();
    let demand: Vec<f64> = (0..n)
        .map(|i| 0.5 * (edge_demand[i] + edge_demand[(i + n - 1) % n]))
        .collect();
    let keep_out = opts.keep_out.clone().unwrap_or_else(|| KeepOut::none(mesh));
    let piece = Piece {
        mesh,
        adj,
        opts,
        keep_out,
        opening: face_opening(&rest, &relaxed.x, band.s_max()),
        rim,
        demand,
        start: held.x.clone(),
    };
    let worst_at = centroid(mesh, held.worst_face);
    if total <= NO_DEMAND_REL * loop_length(mesh, &piece.rim) {
        return Err(DartError::Infeasible {
            darts: 0,
            excess: held.excess,
            at: worst_at,
            reason: "no dart can help: where the limits are exceeded the flat piece is too short, not too long (the surface curves like a saddle there); split the piece (--split auto)".into(),
        });
    }
    // 2. Count.
    let mean_reach = piece.mean_rule_reach();
    let count_band = limits.count_band();
    let theta = (std::f64::consts::TAU * (1.0 - count_band.s_min() / count_band.s_max()))
        .min(std::f64::consts::PI);
    let capacity = 2.0 * mean_reach * (0.5 * theta).sin() * CURVED_LEGS;
    let k_cap = opts.max_darts.min(piece.most_darts());
    if k_cap == 0 {
        return Err(DartError::Infeasible {
            darts: 0,
            excess: held.excess,
            at: worst_at,
            reason: "no dart fits on the outline (--max-darts, --dart-min-spacing or no_cut regions leave no room)".into(),
        });
    }
    let k0 = ((total / capacity.max(f64::MIN_POSITIVE)).ceil() as usize).clamp(1, k_cap);
    debug(&format!(
        "demand {total:.1} mm, mean reach {mean_reach:.1} mm, capacity {capacity:.1} mm/dart, k0 {k0}, cap {k_cap}"
    ));
    // 3–5. Attempts: down from k0 while they hold, else up until one does.
    let mut outcomes: Vec<Outcome> = Vec::new();
    let mut unplaced: Vec<String> = Vec::new();
    let mut ahead = Lookahead::new(&piece);
    let mut try_k =
        |k: usize, next: usize, attempts: &mut Vec<Attempt>| -> Result<bool, DartError> {
            match ahead.attempt(k, next) {
                Ok(o) => {
                    attempts.push(Attempt {
                        darts: k,
                        total_length_mm: o.total_length(),
                        excess: o.held.excess,
                        feasible: o.held.feasible,
                    });
                    let ok = o.held.feasible;
                    outcomes.push(o);
                    Ok(ok)
                }
                Err(DartError::Placement(reason)) => {
                    debug(&format!("k = {k}: {reason}"));
                    unplaced.push(format!("{k} darts: {reason}"));
                    Ok(false)
                }
                Err(e) => Err(e),
            }
        };
    // The search ends, too, once the stage's iterations or time are spent.
    let mut k = k0;
    if try_k(k, k - 1, &mut attempts)? {
        while k > 1 && !budget.spent() && try_k(k - 1, k - 2, &mut attempts)? {
            k -= 1;
        }
    } else if attempts.len() == 1 {
        // k0 darts could not even be placed: fewer might.
        while k > 1 && !budget.spent() {
            k -= 1;
            if try_k(k, k - 1, &mut attempts)? {
                break;
            }
        }
    } else {
        while k < k_cap && !budget.spent() {
            k += 1;
            if try_k(k, (k + 1).min(k_cap), &mut attempts)? {
                break;
            }
        }
    }
    // The shortest total length that held, the fewer darts on a tie, whose final map keeps every
    // dart's legs equal and whose flat outline does not overlap itself: a dart the limits hardly
    // need can close past its mouth in the final map (the outline on its two sides crossing),
    // and where the limits press hard on a dart's flanks along different threads its legs may
    // not be kept equal; no pattern can be cut or sewn from either.
    let mut held_ok: Vec<usize> = (0..outcomes.len())
        .filter(|&i| outcomes[i].held.feasible)
        .collect();
    held_ok.sort_by(|&a, &b| {
        let (a, b) = (&outcomes[a], &outcomes[b]);
        a.total_length()
            .total_cmp(&b.total_length())
            .then(a.darts.len().cmp(&b.darts.len()))
    });
    let mut unsettled: Option<DartError> = None;
    let mut chosen: Option<(usize, Settled)> = None;
    for i in held_ok {
        match settle_simple(&outcomes[i], limits, opts.fit, budget)? {
            Ok(settled) => {
                chosen = Some((i, settled));
                break;
            }
            Err(e) => {
                unsettled.get_or_insert(e);
            }
        }
    }
    // Every count that held closes a dart past its mouth or parts its legs: more darts, each
    // needed less, may not.
    if chosen.is_none() && unsettled.is_some() {
        let tried = attempts.iter().map(|a| a.darts).max().unwrap_or(0);
        for k in (tried + 1..=k_cap).take(OVERLAP_MORE_DARTS) {
            if budget.spent() {
                break;
            }
            let o = match piece.attempt(k, budget) {
                Ok(o) => o,
                Err(DartError::Placement(_)) => break,
                Err(e) => return Err(e),
            };
            attempts.push(Attempt {
                darts: k,
                total_length_mm: o.total_length(),
                excess: o.held.excess,
                feasible: o.held.feasible,
            });
            if !o.held.feasible {
                continue;
            }
            outcomes.push(o);
            let i = outcomes.len() - 1;
            if let Ok(settled) = settle_simple(&outcomes[i], limits, opts.fit, budget)? {
                chosen = Some((i, settled));
                break;
            }
        }
    }
    if let Some((i, settled)) = chosen {
        let o = settled.shortened.as_ref().unwrap_or(&outcomes[i]);
        return Ok(finish(
            &o.emb.mesh,
            &o.cut,
            &o.darts,
            settled.held,
            attempts,
            opts.drill_offset_mm,
            settled.fit,
        ));
    }
    if let Some(e) = unsettled {
        return Err(e);
    }
    let closest = outcomes
        .iter()
        .min_by(|a, b| a.held.excess.total_cmp(&b.held.excess));
    Err(match closest {
        Some(o) if o.held.excess < held.excess => DartError::Infeasible {
            darts: o.darts.len(),
            excess: o.held.excess,
            at: centroid(&o.cut.mesh, o.held.worst_face),
            reason: format!("no set of up to {k_cap} darts brought every face within the limits"),
        },
        _ => DartError::Infeasible {
            darts: 0,
            excess: held.excess,
            at: worst_at,
            reason: if outcomes.is_empty() {
                format!(
                    "no darts could be placed ({})",
                    unplaced.last().map_or("", String::as_str)
                )
            } else {
                format!("no set of up to {k_cap} darts brought every face within the limits")
            },
        },
    })
}

/// Where the flat outline of `mesh` in the map `x` crosses itself (the 3D position of the
/// boundary vertex nearest the first crossing), or `None` when every boundary loop is simple.
fn outline_overlap(mesh: &TriMesh, x: &[DVec2]) -> Result<Option<DVec3>, DartError> {
    Ok(crate::crossing::outline_crossing(mesh, x)?.map(|v| mesh.positions[v as usize]))
}

/// The final map of an outcome that held the limits, fitted as `fit` says, with the fit it has
/// and, where the tight fit shortened darts, the outcome it shortened them in. A tight map whose
/// legs would cross or part is not kept, at any of [`CLOSE_WEIGHTS`]: the outcome's
/// least-strained map is settled instead.
fn settle_simple(
    o: &Outcome,
    limits: &Limits,
    fit: DartFit,
    budget: &Budget,
) -> Result<Result<Settled, DartError>, DartError> {
    if fit == DartFit::Tight {
        // Darts one weight shortens stay short for the next: they held the limits.
        let mut shortened = None;
        for weight in CLOSE_WEIGHTS {
            match settle_tight(o, &mut shortened, limits, weight, budget)? {
                Ok(held) => {
                    return Ok(Ok(Settled {
                        held,
                        fit: DartFit::Tight,
                        shortened,
                    }));
                }
                Err(e) => debug(&format!("drawn tight at {weight}: {e}")),
            }
        }
        debug("settled least-strained");
    }
    let pairs = all_pairs(&o.legs());
    let held = limits::settle(
        &o.cut.mesh,
        &o.held.x,
        limits,
        &pairs,
        Closing::default(),
        budget,
    )?;
    Ok(checked(o, &pairs, held)?.map(|held| Settled {
        held,
        fit: DartFit::LeastStrain,
        shortened: None,
    }))
}

/// A final map of an outcome and what it took.
struct Settled {
    held: Held,
    fit: DartFit,
    /// The outcome with its darts shortened where the tight map drew them shut.
    shortened: Option<Outcome>,
}

/// Most times the tight fit shortens the darts of one outcome.
const MAX_SHORTENINGS: usize = 12;

/// The tight map of outcome `o` at the pulls' `weight`, from its darts as `shortened` has them
/// (`None`: as placed). Where the map draws a dart shut before its point ([`shut_points`]), the
/// dart ends there: the piece is cut again with the shorter darts (kept in `shortened`), the map
/// carried over with the shut copies merged, brought within the limits and drawn tight again.
fn settle_tight(
    o: &Outcome,
    shortened: &mut Option<Outcome>,
    limits: &Limits,
    weight: f64,
    budget: &Budget,
) -> Result<Result<Held, DartError>, DartError> {
    let mut rounds = 0;
    // Per dart, its pull's weight: a dart drawn shut where it cannot end is let go.
    let mut weights = vec![weight; shortened.as_ref().unwrap_or(o).darts.len()];
    loop {
        let cur = shortened.as_ref().unwrap_or(o);
        let legs = cur.legs();
        let pairs = all_pairs(&legs);
        let held = limits::settle(
            &cur.cut.mesh,
            &cur.held.x,
            limits,
            &pairs,
            closing(&legs, &cur.held.x, &weights),
            budget,
        )?;
        let shut = shut_points(&legs, &held.x);
        if rounds < MAX_SHORTENINGS
            && shut.iter().any(Option::is_some)
            && let Some(next) = cur.shortened(&shut, &held.x, limits, budget)?
        {
            debug(&format!(
                "tight: darts shortened from {:.1} to {:.1} mm",
                cur.total_length(),
                next.total_length()
            ));
            // A dart shut up to its mouth is gone, and its weight with it.
            weights = weights
                .iter()
                .zip(&shut)
                .filter(|(_, s)| **s != Some(0))
                .map(|(w, _)| *w)
                .collect();
            *shortened = Some(next);
            rounds += 1;
            continue;
        }
        // A dart drawn shut that could not end there (ending it broke the limits): its guards
        // stop every step of the solver, so it is let go and the others drawn tight.
        let stuck = jammed(&legs, &held.x);
        if rounds < MAX_SHORTENINGS && stuck.iter().zip(&weights).any(|(&j, &w)| j && w > 0.0) {
            for (w, j) in weights.iter_mut().zip(&stuck) {
                if *j {
                    *w = 0.0;
                }
            }
            debug(&format!(
                "tight: {} darts let go",
                stuck.iter().filter(|&&j| j).count()
            ));
            rounds += 1;
            continue;
        }
        return checked(cur, &pairs, held);
    }
}

/// A final map `settled` of outcome `o`, [`DartError::LegsApart`] when a dart's legs are not
/// kept equal, or [`DartError::Overlap`] when its flat outline crosses itself.
fn checked(
    o: &Outcome,
    pairs: &EdgePairs,
    settled: Held,
) -> Result<Result<Held, DartError>, DartError> {
    if let Some((k, apart)) = pairs.worst_legs(&settled.x)
        && apart > LEG_MATCH_MM
    {
        debug(&format!(
            "{} darts: a dart's legs differ by {apart:.3} mm",
            o.darts.len()
        ));
        let at = o.darts[k]
            .0
            .first()
            .map_or(DVec3::ZERO, |&v| o.emb.mesh.positions[v as usize]);
        return Ok(Err(DartError::LegsApart {
            darts: o.darts.len(),
            apart_mm: apart,
            at,
        }));
    }
    Ok(match outline_overlap(&o.cut.mesh, &settled.x)? {
        Some(at) => {
            debug(&format!(
                "{} darts: the flat outline overlaps itself",
                o.darts.len()
            ));
            Err(DartError::Overlap {
                darts: o.darts.len(),
                at,
            })
        }
        None => Ok(settled),
    })
}

fn debug(msg: &str) {
    tracing::debug!("{msg}");
}

fn loop_length(mesh: &TriMesh, lp: &[u32]) -> f64 {
    (0..lp.len())
        .map(|i| {
            mesh.positions[lp[i] as usize].distance(mesh.positions[lp[(i + 1) % lp.len()] as usize])
        })
        .sum()
}

fn centroid(mesh: &TriMesh, t: usize) -> DVec3 {
    let c = mesh.corners(t.min(mesh.triangles.len().saturating_sub(1)));
    (c[0] + c[1] + c[2]) / 3.0
}

impl Piece<'_> {
    /// The geodesic from rim vertex `i`, at right angles to the outline, `length` long at most.
    fn geodesic(&self, i: usize, length: f64) -> (DVec3, Geodesic) {
        let dir = inward_direction(self.mesh, &self.adj, &self.rim, i);
        (dir, trace(self.mesh, &self.adj, self.rim[i], dir, length))
    }

    /// How far the yielded stretch reaches along the geodesic from rim vertex `i`.
    fn rule_reach(&self, i: usize) -> f64 {
        let diag = self.mesh.bbox().diagonal();
        let (_, g) = self.geodesic(i, diag);
        let peak = g
            .faces
            .iter()
            .map(|&t| self.opening[t as usize])
            .fold(0.0, f64::max);
        // From the mouth inwards, up to where the yielded stretch first dies out.
        let mut reach = 0.0;
        let mut acc = 0.0;
        for (j, &t) in g.faces.iter().enumerate() {
            if j + 1 < g.points.len() {
                acc += g.points[j].distance(g.points[j + 1]);
            }
            if self.opening[t as usize] > REACH_FRACTION * peak {
                reach = acc;
            } else if reach > 0.0 {
                break;
            }
        }
        reach.min(0.95 * g.length)
    }

    /// True when a dart can leave the outline at rim vertex `i`: the geodesic at right angles
    /// runs [`MOUTH_CLEARANCE`] edge lengths into the piece without meeting the outline (at a rim
    /// vertex with a narrow fan it would run along the outline instead).
    fn good_mouth(&self, i: usize) -> bool {
        let need = MOUTH_CLEARANCE * self.edge_scale();
        let (_, g) = self.geodesic(i, need);
        !g.hit_boundary && g.length >= need * (1.0 - 1e-9)
    }

    /// Mean rule reach over the rim, weighted by demand.
    fn mean_rule_reach(&self) -> f64 {
        let (mut s, mut w) = (0.0, 0.0);
        for (i, &d) in self.demand.iter().enumerate() {
            if d > 0.0 && self.good_mouth(i) {
                s += d * self.rule_reach(i);
                w += d;
            }
        }
        if w > 0.0 { s / w } else { 0.0 }
    }

    /// Most darts the outline holds at the minimum spacing.
    fn most_darts(&self) -> usize {
        let len = loop_length(self.mesh, &self.rim);
        let free = self
            .rim
            .iter()
            .filter(|&&v| !self.keep_out.is_blocked(v))
            .count();
        let by_spacing = if self.opts.min_spacing_mm > 0.0 {
            (len / self.opts.min_spacing_mm).floor() as usize
        } else {
            usize::MAX
        };
        by_spacing.min(free / 3)
    }

    /// Rim indices of the starts of k darts: the middles of k stretches of equal demand, the
    /// first at the peak of demand, each moved to the nearest rim vertex a dart may use.
    fn starts(&self, k: usize) -> Result<Vec<usize>, DartError> {
        let n = self.rim.len();
        let total: f64 = self.demand.iter().sum();
        let peak = (0..n)
            .max_by(|&a, &b| self.demand[a].total_cmp(&self.demand[b]))
            .unwrap_or(0);
        // Cumulative demand from the peak.
        let mut cum = Vec::with_capacity(n);
        let mut acc = 0.0;
        for j in 0..n {
            cum.push(acc);
            acc += self.demand[(peak + j) % n];
        }
        let mut out: Vec<usize> = Vec::with_capacity(k);
        for d in 0..k {
            let target = total * d as f64 / k as f64;
            let j = cum.partition_point(|&c| c < target).min(n - 1);
            let mut i = (peak + j) % n;
            // Nearest usable rim vertex.
            let usable = |i: usize| {
                let v = self.rim[i];
                !self.keep_out.is_blocked(v) && self.good_mouth(i)
            };
            let mut found = false;
            for off in 0..n {
                for cand in [(i + off) % n, (i + n - off % n) % n] {
                    if usable(cand) {
                        i = cand;
                        found = true;
                        break;
                    }
                }
                if found {
                    break;
                }
            }
            if !found {
                return Err(DartError::Placement(
                    "no rim vertex is free of no_cut regions and marks".into(),
                ));
            }
            out.push(i);
        }
        // Spacing along the rim.
        let min = self.opts.min_spacing_mm;
        for a in 0..out.len() {
            for b in 0..a {
                let d = self.mesh.positions[self.rim[out[a]] as usize]
                    .distance(self.mesh.positions[self.rim[out[b]] as usize]);
                if d < min.max(f64::MIN_POSITIVE) {
                    return Err(DartError::Placement(format!(
                        "{k} darts do not fit on the outline {min:.1} mm apart"
                    )));
                }
            }
        }
        Ok(out)
    }

    /// The darts embedded in the piece at their reaches: each traced on the piece as embedded
    /// so far, stopped short of the outline, of keep-out faces and of the other darts (by the
    /// spacing), and made part of the mesh. Returns the embedding and each dart's path; a dart
    /// that cannot leave the outline is an error.
    fn embed_all(&self, plans: &mut [Plan]) -> Result<(Embedded, Vec<Vec<u32>>), DartError> {
        let mut e = Embedded::new(self.mesh);
        let mut paths: Vec<Vec<u32>> = Vec::with_capacity(plans.len());
        let mut polylines: Vec<Vec<DVec3>> = Vec::with_capacity(plans.len());
        for (i, plan) in plans.iter_mut().enumerate() {
            let start = self.rim[plan.rim_index];
            let topo = Topology::build(&e.mesh)?;
            let adj = Adjacency::new(&e.mesh, &topo);
            let mut g = trace(&e.mesh, &adj, start, plan.dir, plan.reach);
            // Stop short of keep-out faces and of the other darts.
            let gap = (0.5 * self.opts.min_spacing_mm).max(self.edge_scale());
            let mut keep = g.points.len();
            for (j, p) in g.points.iter().enumerate().skip(1) {
                let near_other = polylines
                    .iter()
                    .any(|pl| pl.iter().any(|q| q.distance(*p) < gap));
                let blocked = g.faces.get(j.saturating_sub(1)).is_some_and(|&t| {
                    let base = e.parent[t as usize] as usize;
                    self.mesh.triangles[base]
                        .iter()
                        .any(|&v| self.keep_out.is_blocked(v))
                });
                if near_other || blocked {
                    keep = j;
                    plan.max_reach = plan.max_reach.min(plan.reach);
                    break;
                }
            }
            if keep < g.points.len() {
                g.points.truncate(keep);
                g.faces.truncate(keep.saturating_sub(1).max(1));
                g.hit_boundary = false;
                // The trace now ends at a crossing: keep it as the point.
                g.points.push(*g.points.last().unwrap_or(&DVec3::ZERO));
            }
            if g.hit_boundary {
                plan.max_reach = plan.max_reach.min(0.9 * g.length);
            }
            let (next, path) = embed(&e, start, &g).ok_or_else(|| {
                DartError::Placement(format!("dart {i} cannot leave the outline"))
            })?;
            // Only the mouth may touch the outline.
            if path[1..].iter().any(|&v| {
                (v as usize) < self.adj.on_boundary.len() && self.adj.on_boundary[v as usize]
            }) {
                return Err(DartError::Placement(format!(
                    "dart {i} runs along the outline"
                )));
            }
            polylines.push(
                path.iter()
                    .map(|&v| next.mesh.positions[v as usize])
                    .collect(),
            );
            paths.push(path);
            e = next;
        }
        Ok((e, paths))
    }

    /// One attempt with k darts (steps 3–4 of the module doc).
    /// The attempt with `k` darts, its solves drawing on `budget`.
    fn attempt(&self, k: usize, budget: &Budget) -> Result<Outcome, DartError> {
        let starts = self.starts(k)?;
        let mut plans: Vec<Plan> = starts
            .iter()
            .map(|&i| Plan {
                rim_index: i,
                dir: inward_direction(self.mesh, &self.adj, &self.rim, i),
                reach: (FIRST_REACH * self.rule_reach(i)).max(2.0 * self.edge_scale()),
                max_reach: self.mesh.bbox().diagonal(),
            })
            .collect();
        let (mut emb, mut paths) = self.embed_all(&mut plans)?;
        let mut cut = CutMesh::new(&emb.mesh, &paths)?;
        // The uncut piece's map nearest the limits, the darts closed: the solve opens them.
        let identity: Vec<u32> = (0..self.mesh.triangles.len() as u32).collect();
        let mut x = transfer(self.mesh, &identity, &self.start, &cut.mesh, &emb.parent);
        let mut steps = 0;
        let mut history: Vec<f64> = Vec::new();
        loop {
            let topo = Topology::build(&emb.mesh)?;
            let legs = legs_of(&topo, &emb.mesh, &cut, &paths)?;
            let effort = if steps > 0 {
                Effort::Warm
            } else {
                Effort::Full
            };
            let t0 = std::time::Instant::now();
            let held = limits::reach(&cut.mesh, &x, &self.opts.limits, effort, budget)?;
            debug(&format!(
                "reach: {} iterations, {:.2} s",
                held.iterations,
                t0.elapsed().as_secs_f64()
            ));
            let total: f64 = paths.iter().map(|p| path_length(&emb.mesh, p)).sum();
            debug(&format!(
                "k = {k}, step {steps}: total {total:.1} mm, excess {:.3} %, feasible {}",
                held.excess * 100.0,
                held.feasible
            ));
            history.push(held.excess);
            let stalled = history.len() > STALL_STEPS
                && history[history.len() - 1 - STALL_STEPS] - held.excess
                    < STALL_FRACTION * history[history.len() - 1 - STALL_STEPS].abs()
                || converges_above_zero(&history);
            if held.feasible || steps >= MAX_GROWTH_STEPS || stalled {
                return Ok(Outcome {
                    darts: paths.into_iter().zip(legs).collect(),
                    emb,
                    cut,
                    held,
                });
            }
            // Grow the darts whose points are next to the excess.
            let exc = limits::face_excess(&rest_of(&cut.mesh)?, &held.x, &self.opts.limits);
            let emax = held.excess;
            let hot: Vec<DVec3> = exc
                .iter()
                .enumerate()
                .filter(|&(_, &e)| e > 0.0 && e >= HOT_FRACTION * emax)
                .map(|(t, _)| centroid(&cut.mesh, t))
                .collect();
            let near = NEAR_FRACTION * self.mean_start_gap(plans.len());
            let mut grown = false;
            let is_hot: Vec<bool> = paths
                .iter()
                .map(|path| {
                    let apex = emb.mesh.positions[*path.last().unwrap_or(&0) as usize];
                    hot.iter().any(|h| h.distance(apex) <= near)
                })
                .collect();
            for (plan, &hot_here) in plans.iter_mut().zip(&is_hot) {
                if !hot_here {
                    continue;
                }
                let new_reach = (plan.reach * (1.0 + GROWTH)).max(plan.reach + self.edge_scale());
                if new_reach <= plan.max_reach {
                    plan.reach = new_reach;
                    grown = true;
                }
            }
            if !grown {
                return Ok(Outcome {
                    darts: paths.into_iter().zip(legs).collect(),
                    emb,
                    cut,
                    held,
                });
            }
            let (next_emb, next_paths) = self.embed_all(&mut plans)?;
            let next_cut = CutMesh::new(&next_emb.mesh, &next_paths)?;
            let carried = transfer(
                &cut.mesh,
                &emb.parent,
                &held.x,
                &next_cut.mesh,
                &next_emb.parent,
            );
            x = if flip_free(&next_cut.mesh, &carried) {
                carried
            } else {
                debug("the carried map folds: starting afresh");
                let params = FlattenParams::new(Method::Isometric)
                    .with_max_iters(budget.allow(FlattenParams::DEFAULT_MAX_ITERS))
                    .with_time_limit(budget.time_left());
                let f = flatten(&next_cut.mesh, &params).map_err(DartError::Flatten)?;
                budget.spend(f.info.iterations);
                f.uv
            };
            emb = next_emb;
            paths = next_paths;
            cut = next_cut;
            steps += 1;
        }
    }

    /// A length of the order of the mesh's edges (mm).
    fn edge_scale(&self) -> f64 {
        let n = self.rim.len().max(1);
        loop_length(self.mesh, &self.rim) / n as f64
    }

    /// Mean 3D distance between neighbouring dart starts.
    fn mean_start_gap(&self, k: usize) -> f64 {
        loop_length(self.mesh, &self.rim) / k.max(2) as f64
    }
}

fn legs_of(
    topo: &Topology,
    mesh: &TriMesh,
    cut: &CutMesh,
    paths: &[Vec<u32>],
) -> Result<Vec<Legs>, DartError> {
    paths
        .iter()
        .map(|p| {
            Legs::of(topo, mesh, cut, p)
                .ok_or_else(|| DartError::Internal("a dart runs along the outline".into()))
        })
        .collect()
}

/// True when the last three excesses of the growth fall geometrically towards a limit above
/// [`PREDICTED_OUT`]: the darts would need to grow without end.
fn converges_above_zero(h: &[f64]) -> bool {
    let n = h.len();
    if n < 3 {
        return false;
    }
    let (d1, d2) = (h[n - 3] - h[n - 2], h[n - 2] - h[n - 1]);
    if !(d1 > 0.0 && d2 > 0.0 && d2 < d1) {
        return false;
    }
    let r = d2 / d1;
    h[n - 1] - d2 * r / (1.0 - r) > PREDICTED_OUT
}

fn flip_free(mesh: &TriMesh, x: &[DVec2]) -> bool {
    mesh.triangles.iter().all(|t| {
        let [a, b, c] = t.map(|v| x[v as usize]);
        (b - a).perp_dot(c - a) > 0.0
    })
}

fn rest_of(mesh: &TriMesh) -> Result<Vec<flatcut_flatten::nonlinear::kernel::RestTri>, DartError> {
    rest_frames(mesh).map_err(|t| DartError::Internal(format!("triangle {t} is degenerate")))
}

fn path_length(mesh: &TriMesh, path: &[u32]) -> f64 {
    path.windows(2)
        .map(|w| mesh.positions[w[0] as usize].distance(mesh.positions[w[1] as usize]))
        .sum()
}

/// The result of a solve as darts with their measures.
fn finish(
    mesh: &TriMesh,
    cut: &CutMesh,
    darts: &[(Vec<u32>, Legs)],
    held: Held,
    attempts: Vec<Attempt>,
    drill_mm: f64,
    fit: DartFit,
) -> Darted {
    let mut out = cut.mesh.clone();
    out.flat = Some(held.x.clone());
    let worst_3d = centroid(&cut.mesh, held.worst_face);
    let darts = darts
        .iter()
        .map(|(path, legs)| Dart::measure(mesh, path, legs, &held.x, drill_mm))
        .collect();
    Darted {
        mesh: out,
        origin: cut.origin.clone(),
        darts,
        excess: held.excess,
        feasible: held.feasible,
        worst_3d,
        attempts,
        fit,
    }
}
