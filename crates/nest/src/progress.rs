//! Progress events: which phase the search is in, how far through its budget, and the best
//! layout so far.

use std::time::Duration;

/// The phases of a nesting run, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NestPhase {
    /// The first feasible layout (left-bottom fill).
    Construct,
    /// Overlap minimisation while the strip shrinks in steps.
    Explore,
    /// Smaller shrink steps from the best layout.
    Compress,
    /// Sheets and hides: emptying the last sheet or hide into the others, placing what is left.
    Reduce,
    /// The final layout.
    Done,
}

impl NestPhase {
    /// The phase's name in progress lines and JSON.
    pub fn name(self) -> &'static str {
        match self {
            NestPhase::Construct => "construct",
            NestPhase::Explore => "explore",
            NestPhase::Compress => "compress",
            NestPhase::Reduce => "reduce",
            NestPhase::Done => "done",
        }
    }
}

/// Reported while searching (on the calling thread).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NestProgress {
    /// The phase the search is in.
    pub phase: NestPhase,
    /// Separation iterations so far.
    pub iteration: usize,
    /// Wall-clock time since the search started.
    pub elapsed: Duration,
    /// Fraction of the budget used (iterations or time, whichever is further), 0..=1.
    pub budget_used: f64,
    /// Best feasible layout so far: used roll length, or the extent on the last sheet (mm).
    pub length: f64,
    /// Sheets or hides the best layout uses.
    pub sheets: usize,
    /// The best layout's utilization, percent.
    pub utilization: f64,
}
