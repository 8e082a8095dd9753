//! The search budget: iterations and/or wall time, split into phases, and the cancel hook.
//! Only the calling thread reads it; workers run one bounded pass at a time.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Budget of one nesting run.
pub(crate) struct Budget {
    start: Instant,
    time: Option<Duration>,
    max_iters: u64,
    /// Separation iterations so far.
    pub(crate) iters: u64,
    cancel: Option<Arc<AtomicBool>>,
    /// End of the current phase: (time from start, iteration count).
    phase_end: (Option<Duration>, u64),
    phase_start: (Duration, u64),
}

impl Budget {
    pub(crate) fn new(
        time: Option<Duration>,
        max_iters: usize,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Self {
        let max_iters = max_iters as u64;
        Self {
            start: Instant::now(),
            time,
            max_iters,
            iters: 0,
            cancel,
            phase_end: (time, max_iters),
            phase_start: (Duration::ZERO, 0),
        }
    }

    /// Starts a phase that ends when `until` (0..=1) of the whole budget is used.
    pub(crate) fn begin_phase(&mut self, until: f64) {
        let until = until.clamp(0.0, 1.0);
        self.phase_start = (self.start.elapsed(), self.iters);
        self.phase_end = (
            self.time.map(|t| t.mul_f64(until)),
            ((self.max_iters as f64) * until).round() as u64,
        );
    }

    pub(crate) fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// The current phase is over (its share of iterations or time is used, or cancelled).
    pub(crate) fn phase_over(&self) -> bool {
        self.iters >= self.phase_end.1
            || self.phase_end.0.is_some_and(|t| self.start.elapsed() >= t)
            || self.cancelled()
    }

    /// The time is up (or the search was cancelled); iterations aside.
    pub(crate) fn out_of_time(&self) -> bool {
        self.time.is_some_and(|t| self.start.elapsed() >= t) || self.cancelled()
    }

    /// The whole budget is used (or cancelled).
    pub(crate) fn over(&self) -> bool {
        self.iters >= self.max_iters
            || self.time.is_some_and(|t| self.start.elapsed() >= t)
            || self.cancelled()
    }

    pub(crate) fn tick(&mut self) {
        self.iters += 1;
    }

    pub(crate) fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }

    /// Fraction of the whole budget used: the further of iterations and time.
    pub(crate) fn used(&self) -> f64 {
        let by_iters = if self.max_iters == 0 {
            1.0
        } else {
            self.iters as f64 / self.max_iters as f64
        };
        let by_time = self.time.map_or(0.0, |t| {
            if t.is_zero() {
                1.0
            } else {
                self.start.elapsed().as_secs_f64() / t.as_secs_f64()
            }
        });
        by_iters.max(by_time).clamp(0.0, 1.0)
    }

    /// Fraction of the current phase used.
    pub(crate) fn phase_used(&self) -> f64 {
        let span_i = self.phase_end.1.saturating_sub(self.phase_start.1);
        let by_iters = if span_i == 0 {
            1.0
        } else {
            (self.iters - self.phase_start.1) as f64 / span_i as f64
        };
        let by_time = self.phase_end.0.map_or(0.0, |end| {
            let span = end.saturating_sub(self.phase_start.0).as_secs_f64();
            if span <= 0.0 {
                1.0
            } else {
                (self.start.elapsed().saturating_sub(self.phase_start.0)).as_secs_f64() / span
            }
        });
        by_iters.max(by_time).clamp(0.0, 1.0)
    }
}
