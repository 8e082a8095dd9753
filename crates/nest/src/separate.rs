//! Separation: removing the overlaps of a layout by moving overlapping pieces to places of least
//! weighted overlap, with guided-local-search weights, until no overlap is left or the search
//! stops improving (Gardeyn & Vanden Berghe 2025, Algs. 5, 9, 10).
//!
//! Several workers start every iteration from the same layout, each moving the overlapping
//! pieces in its own seeded random order; the layout of least weighted loss is kept. Workers run
//! on a rayon pool, one per thread; the result depends on the number of workers, never on the
//! number of threads.

use crate::budget::Budget;
use crate::evaluate::SeparationEval;
use crate::problem::Problem;
use crate::search::{SampleConfig, search};
use crate::state::{Snap, State};
use rand::rngs::Xoshiro256PlusPlus;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// Limits of one separation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SepConfig {
    /// Iterations without improvement before a strike.
    pub patience: usize,
    /// Strikes (rounds without substantial improvement) before giving up.
    pub strikes: usize,
    pub sample: SampleConfig,
}

/// An improvement counts as substantial below this fraction of the previous best loss.
const SUBSTANTIAL: f32 = 0.98;

struct Worker {
    st: State,
    rng: Xoshiro256PlusPlus,
}

impl Worker {
    /// Moves every overlapping piece once, in random order (Alg. 5).
    fn move_items(&mut self, prob: &Problem, cfg: &SampleConfig) {
        let mut cands: Vec<usize> = self
            .st
            .placed()
            .filter(|&i| self.st.tracker.loss(i) > 0.0)
            .collect();
        cands.shuffle(&mut self.rng);
        for i in cands {
            if self.st.tracker.loss(i) <= 0.0 {
                continue;
            }
            let (Some(dt), Some(shape)) = (self.st.dt(i), self.st.shape(i)) else {
                continue;
            };
            let current = Some((dt, shape.bbox()));
            let bin = self.st.bin.clone();
            let found = {
                let mut ev = SeparationEval::new(&self.st, prob, i);
                search(prob, &bin, i, current, &mut ev, *cfg, &mut self.rng)
            };
            if let Some((dt, _)) = found {
                self.st.put(prob, i, dt);
            }
        }
    }
}

/// Separates layouts of one container.
pub(crate) struct Separator<'p> {
    prob: &'p Problem,
    pub st: State,
    workers: Vec<Worker>,
    pool: Option<&'p rayon::ThreadPool>,
    pub rng: Xoshiro256PlusPlus,
}

impl<'p> Separator<'p> {
    pub(crate) fn new(
        prob: &'p Problem,
        st: State,
        n_workers: usize,
        pool: Option<&'p rayon::ThreadPool>,
        mut rng: Xoshiro256PlusPlus,
    ) -> Self {
        let workers = (0..n_workers.max(1))
            .map(|_| Worker {
                st: st.clone(),
                rng: Xoshiro256PlusPlus::seed_from_u64(rng.next_u64()),
            })
            .collect();
        Self {
            prob,
            st,
            workers,
            pool,
            rng,
        }
    }

    /// After the master state changed container or was rebuilt: workers follow.
    pub(crate) fn resync_workers(&mut self) {
        for w in &mut self.workers {
            w.st = self.st.clone();
        }
    }

    /// One iteration: every worker moves the overlapping pieces from the master layout; the
    /// least weighted loss wins (Alg. 10).
    fn move_items_multi(&mut self, cfg: &SampleConfig) {
        let master = self.st.save();
        let prob = self.prob;
        let tracker = &self.st.tracker;
        let run = |w: &mut Worker| {
            w.st.restore(&master);
            w.st.tracker.clone_from(tracker);
            w.move_items(prob, cfg);
        };
        match self.pool {
            Some(pool) if self.workers.len() > 1 => {
                pool.install(|| self.workers.par_iter_mut().for_each(run));
            }
            _ => self.workers.iter_mut().for_each(run),
        }
        let best = self
            .workers
            .iter()
            .enumerate()
            .min_by(|a, b| {
                a.1.st
                    .tracker
                    .total_weighted_loss()
                    .total_cmp(&b.1.st.tracker.total_weighted_loss())
                    .then(a.0.cmp(&b.0))
            })
            .map(|(i, _)| i)
            .expect("at least one worker");
        self.st.copy_from(&self.workers[best].st);
    }

    /// Separates the master layout (Alg. 9). Returns the best layout found (overlap-free if
    /// `total_loss == 0`); the master is left at it.
    pub(crate) fn separate(&mut self, cfg: &SepConfig, budget: &mut Budget) -> Snap {
        let mut best = self.st.save();
        let mut min_loss = best.total_loss;
        let mut strikes = 0;
        while strikes < cfg.strikes && min_loss > 0.0 && !budget.phase_over() {
            let strike_start = self.st.tracker.total_loss();
            let mut idle = 0;
            while idle < cfg.patience && !budget.phase_over() {
                self.move_items_multi(&cfg.sample);
                budget.tick();
                let loss = self.st.tracker.total_loss();
                if loss == 0.0 {
                    best = self.st.save();
                    min_loss = 0.0;
                    break;
                } else if loss < min_loss {
                    if loss < min_loss * SUBSTANTIAL {
                        idle = 0;
                    }
                    best = self.st.save();
                    min_loss = loss;
                } else {
                    idle += 1;
                }
                self.st.tracker.update_weights();
            }
            if min_loss == 0.0 {
                break;
            }
            if strike_start * SUBSTANTIAL <= min_loss {
                strikes += 1;
            } else {
                strikes = 0;
            }
            self.st.restore(&best);
        }
        self.st.restore(&best);
        best
    }

    /// Restores the master to `snap`; with `keep_weights` false the weights start over.
    pub(crate) fn rollback(&mut self, snap: &Snap, keep_weights: bool) {
        self.st.restore(snap);
        if !keep_weights {
            self.st.rebuild_tracker(self.prob);
        }
    }

    pub(crate) fn random_f32(&mut self) -> f32 {
        rand::RngExt::random::<f32>(&mut self.rng)
    }
}
