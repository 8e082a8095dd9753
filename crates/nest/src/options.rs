//! Search options: spacing, seed, budget (iterations and/or time), workers and threads, the
//! cancel hook.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// Search options.
#[derive(Clone, Debug)]
pub struct NestOptions {
    /// Minimum gap between pieces and from the stock edge (kerf, knife clearance), mm.
    pub spacing: f64,
    /// Seed of the search's random streams.
    pub seed: u64,
    /// Search budget in separation iterations (one iteration = every worker moves each
    /// overlapping piece once). With no time limit the layout depends on the seed only.
    pub max_iters: usize,
    /// Wall-clock budget (`None` = iterations only, fully deterministic). The search stops at
    /// whichever budget runs out first.
    pub time_limit: Option<Duration>,
    /// Search workers: independent seeded streams that each try moves from the same layout; the
    /// best one is kept every iteration. The result depends on this number, not on `threads`.
    pub workers: usize,
    /// Threads running the workers (0 = one per available core).
    pub threads: usize,
    /// Container-wide position samples per placement search.
    pub samples: usize,
    /// Angles sampled for freely rotating pieces (the refinement then turns them continuously).
    pub free_rotation_steps: usize,
    /// Set to `true` from another thread to stop the search; the best layout so far is returned.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl NestOptions {
    /// 2 mm between pieces: a typical knife/laser clearance.
    pub const DEFAULT_SPACING: f64 = 2.0;
    /// Seed 0 unless asked otherwise.
    pub const DEFAULT_SEED: u64 = 0;
    /// Enough for a pattern's worth of pieces to settle well on a sheet or a roll in seconds.
    pub const DEFAULT_MAX_ITERS: usize = 1000;
    /// Two workers: one per core of a small machine (and of CI).
    pub const DEFAULT_WORKERS: usize = 2;
    /// 50 samples over the container per search, then refinement (Gardeyn & Vanden Berghe).
    pub const DEFAULT_SAMPLES: usize = 50;
    /// 16 sampled angles for free rotation (22.5° apart), refined continuously.
    pub const DEFAULT_FREE_ROTATION_STEPS: usize = 16;
    /// Every option at its default, no time limit, no cancel hook.
    pub const DEFAULT: Self = Self {
        spacing: Self::DEFAULT_SPACING,
        seed: Self::DEFAULT_SEED,
        max_iters: Self::DEFAULT_MAX_ITERS,
        time_limit: None,
        workers: Self::DEFAULT_WORKERS,
        threads: 0,
        samples: Self::DEFAULT_SAMPLES,
        free_rotation_steps: Self::DEFAULT_FREE_ROTATION_STEPS,
        cancel: None,
    };
    /// These options with `v` mm between pieces.
    pub fn with_spacing(mut self, v: f64) -> Self {
        self.spacing = v;
        self
    }
    /// These options with seed `v`.
    pub fn with_seed(mut self, v: u64) -> Self {
        self.seed = v;
        self
    }
    /// These options with a budget of `v` separation iterations.
    pub fn with_max_iters(mut self, v: usize) -> Self {
        self.max_iters = v;
        self
    }
    /// These options with the wall-clock budget `v` (`None`: iterations only).
    pub fn with_time_limit(mut self, v: Option<Duration>) -> Self {
        self.time_limit = v;
        self
    }
    /// These options with `v` position samples per placement search.
    pub fn with_samples(mut self, v: usize) -> Self {
        self.samples = v;
        self
    }
    /// These options with `v` search workers.
    pub fn with_workers(mut self, v: usize) -> Self {
        self.workers = v;
        self
    }
    /// These options with `v` threads (0: one per available core).
    pub fn with_threads(mut self, v: usize) -> Self {
        self.threads = v;
        self
    }
    /// These options stopped when `flag` is set.
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }
}

impl Default for NestOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}
