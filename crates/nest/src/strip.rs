//! Strip packing (a roll): construct, then explore and compress (Gardeyn & Vanden Berghe 2025,
//! Algs. 11–13). Exploration shrinks the strip by a fixed step whenever the layout is separated
//! and, when separation fails, restarts from a pooled infeasible layout disrupted by swapping
//! two large pieces; compression shrinks the best layout by ever smaller random cuts.

use crate::bin::Bin;
use crate::budget::Budget;
use crate::construct::try_fill;
use crate::error::NestError;
use crate::orient::wrap;
use crate::problem::Problem;
use crate::progress::{NestPhase, NestProgress};
use crate::search::SampleConfig;
use crate::separate::{SepConfig, Separator};
use crate::state::{Snap, State};
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::geo_traits::CollidesWith;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Exploration shrinks the strip by 0.1 % after each separated layout (Gardeyn & Vanden Berghe)…
const EXPLORE_SHRINK: f64 = 0.001;
/// …and, while shrinks separate at once (within this many iterations), by doubling steps up to
/// 0.8 %: far from the final density the first minutes would otherwise go to trivial steps.
const EASY_ITERS: u64 = 3;
const EXPLORE_SHRINK_MAX: f64 = 0.008;
/// Compression's shrink step decays from 0.05 % to 0.001 % over the phase.
const COMPRESS_SHRINK: (f64, f64) = (0.0005, 0.00001);
/// Share of the budget spent exploring; the rest compresses.
pub(crate) const EXPLORE_SHARE: f64 = 0.8;
/// Pool selection: |N(0, σ)| over the pool sorted by loss, so better layouts are picked more.
const POOL_STDDEV: f32 = 0.25;
/// Disruption swaps pieces among the largest making up this share of the hull area.
const LARGE_SHARE: f32 = 0.75;
/// The construction grows a too-short strip by this factor.
const GROW: f64 = 1.2;

pub(crate) fn explore_config(samples: usize) -> SepConfig {
    SepConfig {
        patience: 200,
        strikes: 3,
        sample: SampleConfig {
            container: samples,
            focused: samples / 2,
            descents: 3,
        },
    }
}

fn compress_config(samples: usize) -> SepConfig {
    SepConfig {
        patience: 100,
        strikes: 5,
        ..explore_config(samples)
    }
}

/// What a strip run found.
pub(crate) struct StripOutcome {
    pub best: Snap,
    pub baseline: Snap,
}

/// The strip's length in a snapshot.
fn width_of(s: &Snap) -> f64 {
    s.bin().rect.map_or(0.0, |r| r.0)
}

/// Changes the strip's length: pieces right of `split` move by the change (Alg. 12's shrink).
fn set_width(
    sep: &mut Separator,
    prob: &Problem,
    height: f64,
    w: f64,
    split: f32,
) -> Result<(), NestError> {
    let old = sep.st.bin.rect.map_or(w, |r| r.0);
    let delta = (w - old) as f32;
    let moved: Vec<(usize, DTransformation)> = sep
        .st
        .placed()
        .filter_map(|i| {
            let s = sep.st.shape(i)?;
            (s.centroid().0 > split).then(|| {
                let dt = sep.st.dt(i).expect("placed");
                let (x, y) = dt.translation();
                (i, DTransformation::new(dt.rotation(), (x + delta, y)))
            })
        })
        .collect();
    let bin = Bin::rect(&prob.importer, "roll".into(), w, height)?;
    sep.st.swap_bin(bin);
    for (i, dt) in moved {
        sep.st.put(prob, i, dt);
    }
    sep.st.rebuild_tracker(prob);
    sep.resync_workers();
    Ok(())
}

/// Builds the first layout on a strip long enough for everything.
fn construct(
    prob: &Problem,
    height: f64,
    budget: &Budget,
    rng: &mut Xoshiro256PlusPlus,
) -> Result<State, NestError> {
    let n = prob.instances.len();
    let diam_sum: f64 = (0..n)
        .map(|i| prob.kind_of(i).jitem.shape_cd().diameter() as f64)
        .sum();
    let max_diam = (0..n)
        .map(|i| prob.kind_of(i).jitem.shape_cd().diameter() as f64)
        .fold(0.0, f64::max);
    let mut w = (prob.total_area() / height).max(max_diam) + prob.spacing;
    let mut st = State::new(Bin::rect(&prob.importer, "roll".into(), w, height)?, n);
    for i in prob.construction_order() {
        let mut tries = 0;
        loop {
            // past a strip long enough for every piece side by side, stop sampling
            let quick = budget.out_of_time() || w > 2.0 * diam_sum + max_diam;
            if try_fill(prob, &mut st, i, quick, rng) {
                break;
            }
            tries += 1;
            if tries > 200 {
                return Err(NestError::Engine(format!(
                    "could not place `{}` on a strip {w:.0} mm long",
                    prob.names[prob.kind_of(i).item]
                )));
            }
            w *= GROW;
            st.swap_bin(Bin::rect(&prob.importer, "roll".into(), w, height)?);
        }
    }
    // fit the strip to the pieces (with a hair of slack against false positives)
    let fit = st.x_extent() as f64 * 1.00001 + 0.5 * prob.spacing;
    st.swap_bin(Bin::rect(&prob.importer, "roll".into(), fit, height)?);
    st.rebuild_tracker(prob);
    Ok(st)
}

/// Swaps two large pieces and carries along the pieces lying mostly on them (Alg. 12's
/// disruption).
fn disrupt(sep: &mut Separator, prob: &Problem) {
    let placed: Vec<usize> = sep.st.placed().collect();
    if placed.len() < 2 {
        return;
    }
    let hull = |i: usize| {
        prob.kind_of(i)
            .jitem
            .shape_cd()
            .surrogate()
            .convex_hull_area
    };
    let mut by_size = placed.clone();
    by_size.sort_by(|&a, &b| hull(b).total_cmp(&hull(a)).then(a.cmp(&b)));
    let total: f32 = by_size.iter().map(|&i| hull(i)).sum();
    let mut acc = 0.0;
    let mut cutoff = 0.0;
    for &i in &by_size {
        acc += hull(i);
        if acc > total * LARGE_SHARE {
            cutoff = hull(i);
            break;
        }
    }
    let large: Vec<usize> = placed
        .iter()
        .copied()
        .filter(|&i| hull(i) >= cutoff)
        .collect();
    let i1 = large[sep.rng.random_range(0..large.len())];
    let s1 = prob.kind_of(i1).jitem.shape_cd();
    let distinct: Vec<usize> = large
        .iter()
        .copied()
        .filter(|&j| {
            let s = prob.kind_of(j).jitem.shape_cd();
            (s.area() - s1.area()).abs() > 0.01 * s1.area()
                && (s.diameter() - s1.diameter()).abs() > 0.01 * s1.diameter()
        })
        .collect();
    let i2 = if distinct.is_empty() {
        let others: Vec<usize> = placed.iter().copied().filter(|&j| j != i1).collect();
        others[sep.rng.random_range(0..others.len())]
    } else {
        distinct[sep.rng.random_range(0..distinct.len())]
    };
    let (d1, d2) = (
        sep.st.dt(i1).expect("placed"),
        sep.st.dt(i2).expect("placed"),
    );
    let bin = sep.st.bin.clone();
    let allowed = |i: usize, dt: DTransformation| {
        let k = prob.kind_of(i);
        let a = crate::search::project_turn(k, &bin, dt.rotation(), dt.translation());
        DTransformation::new(wrap(a), dt.translation())
    };
    let n1 = allowed(i1, d2);
    let n2 = allowed(i2, d1);
    sep.st.put(prob, i1, n1);
    sep.st.put(prob, i2, n2);
    // pieces whose pole of inaccessibility now lies under a swapped piece follow it to the space
    // it left
    for (moved, other, old, new) in [(i1, i2, d1, n1), (i2, i1, d2, n2)] {
        let shape = sep.st.shape(moved).expect("placed").clone();
        let carry: Vec<usize> = sep
            .st
            .placed()
            .filter(|&j| j != moved && j != other)
            .filter(|&j| {
                let s = sep.st.shape(j).expect("placed");
                s.bbox().x_min < shape.bbox().x_max
                    && s.bbox().x_max > shape.bbox().x_min
                    && shape.collides_with(&s.poi().center)
            })
            .collect();
        let conv = new.compose().inverse().transform(&old.compose());
        for j in carry {
            let dt = sep.st.dt(j).expect("placed");
            let t = dt.compose().transform(&conv).decompose();
            let t = allowed(j, DTransformation::new(t.rotation(), t.translation()));
            sep.st.put(prob, j, t);
        }
    }
}

/// Half-normal sample |N(0, σ)| by Box–Muller (deterministic for the seed).
fn half_normal(sep: &mut Separator, sigma: f32) -> f32 {
    let u1 = sep.random_f32().max(f32::MIN_POSITIVE);
    let u2 = sep.random_f32();
    (sigma * (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()).abs()
}

/// Nests all instances on a strip of `height`; returns the best overlap-free layout.
pub(crate) fn nest_strip(
    prob: &Problem,
    height: f64,
    workers: usize,
    pool: Option<&rayon::ThreadPool>,
    seed: u64,
    budget: &mut Budget,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<StripOutcome, NestError> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5EED_F1A7_C0DE_0001);
    let area = prob.total_area();
    let mut report = |phase: NestPhase, budget: &Budget, w: f64| {
        progress(&NestProgress {
            phase,
            iteration: budget.iters as usize,
            elapsed: budget.elapsed(),
            budget_used: budget.used(),
            length: w,
            sheets: 1,
            utilization: if w > 0.0 {
                100.0 * area / (w * height)
            } else {
                0.0
            },
        })
    };
    let st = construct(prob, height, budget, &mut rng)?;
    let baseline = st.save();
    report(NestPhase::Construct, budget, width_of(&baseline));
    let sep_rng = Xoshiro256PlusPlus::seed_from_u64(rand::Rng::next_u64(&mut rng));
    let mut sep = Separator::new(prob, st, workers, pool, sep_rng);
    let mut best = baseline.clone();

    // exploration
    budget.begin_phase(EXPLORE_SHARE);
    let ecfg = explore_config(prob.samples);
    let mut cur = width_of(&best);
    let mut pool_: Vec<(Snap, f32)> = Vec::new();
    let mut step = EXPLORE_SHRINK;
    while !budget.phase_over() {
        let before = budget.iters;
        let local = sep.separate(&ecfg, budget);
        if local.total_loss == 0.0 {
            if cur < width_of(&best) {
                best = local;
            }
            step = if budget.iters - before <= EASY_ITERS {
                (2.0 * step).min(EXPLORE_SHRINK_MAX)
            } else {
                EXPLORE_SHRINK
            };
            let next = cur * (1.0 - step);
            set_width(&mut sep, prob, height, next, (0.5 * cur) as f32)?;
            cur = next;
            pool_.clear();
        } else {
            step = EXPLORE_SHRINK;
            if budget.phase_over() {
                break;
            }
            let at = pool_.partition_point(|(_, l)| *l <= local.total_loss);
            pool_.insert(at, (local.clone(), local.total_loss));
            let pick =
                ((half_normal(&mut sep, POOL_STDDEV).min(0.999)) * pool_.len() as f32) as usize;
            let chosen = pool_[pick.min(pool_.len() - 1)].0.clone();
            sep.rollback(&chosen, false);
            disrupt(&mut sep, prob);
            sep.resync_workers();
        }
        report(NestPhase::Explore, budget, width_of(&best));
    }

    // compression
    budget.begin_phase(1.0);
    let ccfg = compress_config(prob.samples);
    while !budget.over() {
        let step =
            COMPRESS_SHRINK.0 + (COMPRESS_SHRINK.1 - COMPRESS_SHRINK.0) * budget.phase_used();
        let bw = width_of(&best);
        sep.rollback(&best, false);
        sep.resync_workers();
        let split = sep.random_f32() * bw as f32;
        set_width(&mut sep, prob, height, bw * (1.0 - step), split)?;
        let local = sep.separate(&ccfg, budget);
        if local.total_loss == 0.0 {
            best = local;
        }
        report(NestPhase::Compress, budget, width_of(&best));
    }
    Ok(StripOutcome { best, baseline })
}
