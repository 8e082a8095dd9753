//! Sheets and hides (bin packing): fill the containers in order, largest pieces first; then,
//! while the budget lasts, insert what did not fit into a container by overlap minimisation, and
//! empty the last container into the earlier ones the same way. A container takes a piece only
//! when the separation ends overlap-free, so every layout returned is feasible.
//!
//! Objective, in order: place as much piece area as possible, use as few containers as
//! possible, fill the containers in order (each as full as it goes).

use crate::bin::Bin;
use crate::budget::Budget;
use crate::construct::try_fill;
use crate::evaluate::{Eval, SeparationEval};
use crate::problem::Problem;
use crate::progress::{NestPhase, NestProgress};
use crate::search::search;
use crate::separate::{SepConfig, Separator};
use crate::state::{Snap, State};
use crate::strip::explore_config;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{Rng, SeedableRng};
use std::sync::Arc;

/// The containers available, in order of use.
pub(crate) enum Supply {
    /// Identical sheets, up to a limit.
    Sheets { template: Arc<Bin>, max: usize },
    /// These hides, in order.
    Hides(Vec<Arc<Bin>>),
}

impl Supply {
    fn get(&self, k: usize) -> Option<Arc<Bin>> {
        match self {
            Supply::Sheets { template, max } => (k < *max).then(|| template.clone()),
            Supply::Hides(h) => h.get(k).cloned(),
        }
    }
}

/// The layouts found: one snapshot per container used, and the instances left out.
pub(crate) struct BinsOutcome {
    pub bins: Vec<Snap>,
    pub unplaced: Vec<usize>,
    pub baseline: Vec<Snap>,
}

/// A separation that gives up sooner: an insertion that does not settle quickly is not worth
/// the budget.
fn insert_config(samples: usize) -> SepConfig {
    SepConfig {
        patience: 50,
        strikes: 2,
        ..explore_config(samples)
    }
}

struct Packer<'p> {
    prob: &'p Problem,
    supply: Supply,
    states: Vec<State>,
    workers: usize,
    pool: Option<&'p rayon::ThreadPool>,
    rng: Xoshiro256PlusPlus,
}

impl Packer<'_> {
    fn open(&mut self) -> bool {
        match self.supply.get(self.states.len()) {
            Some(bin) => {
                self.states.push(State::new(bin, self.prob.instances.len()));
                true
            }
            None => false,
        }
    }

    /// Places `inst` in container `b` by overlap minimisation: the least-overlap place, then
    /// separation. Keeps it only if the layout ends overlap-free.
    fn insert(&mut self, b: usize, inst: usize, budget: &mut Budget) -> bool {
        let prob = self.prob;
        let st = &mut self.states[b];
        let before = st.save();
        let found = {
            let mut ev = SeparationEval::new(st, prob, inst);
            let bin = st.bin.clone();
            let cfg = explore_config(prob.samples).sample;
            search(prob, &bin, inst, None, &mut ev, cfg, &mut self.rng)
        };
        let Some((dt, e)) = found else { return false };
        st.put(prob, inst, dt);
        if matches!(e, Eval::Clear(_)) && st.feasible() {
            return true;
        }
        let mut sep = Separator::new(
            prob,
            st.clone(),
            self.workers,
            self.pool,
            Xoshiro256PlusPlus::seed_from_u64(self.rng.next_u64()),
        );
        let r = sep.separate(&insert_config(prob.samples), budget);
        if r.total_loss == 0.0 {
            st.restore(&r);
            st.rebuild_tracker(prob);
            true
        } else {
            st.restore(&before);
            st.rebuild_tracker(prob);
            false
        }
    }

    fn placed_area(&self, b: usize) -> f64 {
        self.states[b]
            .placed()
            .map(|i| self.prob.kind_of(i).area)
            .sum()
    }
}

/// Nests on sheets or hides.
pub(crate) fn nest_bins(
    prob: &Problem,
    supply: Supply,
    workers: usize,
    pool: Option<&rayon::ThreadPool>,
    seed: u64,
    budget: &mut Budget,
    progress: &mut dyn FnMut(&NestProgress),
) -> BinsOutcome {
    let mut p = Packer {
        prob,
        supply,
        states: Vec::new(),
        workers,
        pool,
        rng: Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5EED_B175_0000_0002),
    };
    let total_area = prob.total_area();
    let mut report = |p: &Packer, phase: NestPhase, budget: &Budget| {
        let used: f64 = p.states.iter().map(|s| s.bin.usable_area).sum();
        let area: f64 = (0..p.states.len()).map(|b| p.placed_area(b)).sum();
        progress(&NestProgress {
            phase,
            iteration: budget.iters as usize,
            elapsed: budget.elapsed(),
            budget_used: budget.used(),
            length: p.states.last().map_or(0.0, |s| s.x_extent() as f64),
            sheets: p.states.len(),
            utilization: if used > 0.0 { 100.0 * area / used } else { 0.0 },
        });
        let _ = total_area;
    };

    // construction: first fit over the containers, largest pieces first
    let mut unplaced = Vec::new();
    // per container: the smallest piece area it refused (a larger one will not fit either)
    let mut refused: Vec<f64> = Vec::new();
    for i in prob.construction_order() {
        let area = prob.kind_of(i).area;
        let mut done = false;
        for b in 0..p.states.len() {
            if area >= refused[b] {
                continue;
            }
            let quick = budget.out_of_time();
            if try_fill(prob, &mut p.states[b], i, quick, &mut p.rng) {
                done = true;
                break;
            }
            refused[b] = refused[b].min(area);
        }
        while !done && p.open() {
            refused.push(f64::INFINITY);
            let b = p.states.len() - 1;
            if try_fill(prob, &mut p.states[b], i, budget.out_of_time(), &mut p.rng) {
                done = true;
            } else {
                refused[b] = area;
                if matches!(p.supply, Supply::Sheets { .. }) {
                    // a piece that does not fit an empty sheet never will
                    p.states.pop();
                    refused.pop();
                    break;
                }
            }
        }
        if !done {
            unplaced.push(i);
        }
    }
    // drop containers left empty (hides a piece was tried on but none went onto)
    while p.states.last().is_some_and(|s| s.n_placed() == 0) {
        p.states.pop();
    }
    let baseline: Vec<Snap> = p.states.iter().map(State::save).collect();
    report(&p, NestPhase::Construct, budget);

    // improvement: what is left over goes in by overlap minimisation, then the last container is
    // emptied into the earlier ones
    budget.begin_phase(1.0);
    let mut stalled = 0;
    while !budget.over() && stalled < 3 {
        let mut progress_made = false;
        // 1. pieces that did not fit, into any container (opening more while there are some)
        let mut still = Vec::new();
        for &i in &unplaced {
            let mut ok = false;
            for b in 0..p.states.len() {
                if budget.over() {
                    break;
                }
                if p.insert(b, i, budget) {
                    ok = true;
                    break;
                }
            }
            if ok {
                progress_made = true;
                report(&p, NestPhase::Reduce, budget);
            } else {
                still.push(i);
            }
        }
        unplaced = still;
        // 2. the last container's pieces into the earlier ones
        if p.states.len() > 1 && unplaced.is_empty() {
            let last = p.states.len() - 1;
            let mut items: Vec<usize> = p.states[last].placed().collect();
            items.sort_by(|&a, &b| {
                prob.kind_of(b)
                    .area
                    .total_cmp(&prob.kind_of(a).area)
                    .then(a.cmp(&b))
            });
            for i in items {
                if budget.over() {
                    break;
                }
                let dt = p.states[last].dt(i).expect("placed");
                p.states[last].take(i);
                let mut moved = false;
                for b in 0..last {
                    if p.insert(b, i, budget) {
                        moved = true;
                        break;
                    }
                }
                if moved {
                    progress_made = true;
                    report(&p, NestPhase::Reduce, budget);
                } else {
                    p.states[last].put(prob, i, dt);
                }
            }
            if p.states[last].n_placed() == 0 {
                p.states.pop();
                progress_made = true;
            }
        }
        if progress_made {
            stalled = 0;
        } else {
            stalled += 1;
        }
        if unplaced.is_empty() && p.states.len() <= 1 {
            break;
        }
    }
    let bins: Vec<Snap> = p.states.iter().map(State::save).collect();
    report(&p, NestPhase::Done, budget);
    BinsOutcome {
        bins,
        unplaced,
        baseline,
    }
}
