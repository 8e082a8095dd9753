//! What a running project tells its caller: named stages starting and finishing, progress inside
//! a stage, and warnings. The caller renders them (progress bars, log lines) or ignores them.

use std::time::Duration;

/// The stages of a project run, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Flattening the pieces.
    Flatten,
    /// Measuring their distortion.
    Report,
    /// Building the pattern pieces.
    Pattern,
    /// Nesting them on sheets.
    Nest,
    /// Planning one job per sheet.
    Gcode,
    /// Streaming to the device: run by the caller that owns the device, after the others.
    Send,
}

impl Stage {
    /// Every stage, in run order.
    pub const ALL: [Stage; 6] = [
        Stage::Flatten,
        Stage::Report,
        Stage::Pattern,
        Stage::Nest,
        Stage::Gcode,
        Stage::Send,
    ];

    /// 1-based position among [`Stage::ALL`].
    pub fn number(self) -> usize {
        Stage::ALL.iter().position(|&s| s == self).unwrap_or(0) + 1
    }

    /// The stage's name as progress lines print it.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Flatten => "flatten",
            Stage::Report => "distortion report",
            Stage::Pattern => "pattern pieces",
            Stage::Nest => "nesting",
            Stage::Gcode => "G-code",
            Stage::Send => "send",
        }
    }
}

/// One thing that happened during a run.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// A stage begins; `detail` says on what (e.g. the design file and method).
    Started {
        /// The stage.
        stage: Stage,
        /// What the stage works on.
        detail: &'a str,
    },
    /// Work inside a stage: `done` of `total` units, on `what` (a piece name, a phase).
    Progress {
        /// The stage.
        stage: Stage,
        /// Units done.
        done: usize,
        /// Units in all.
        total: usize,
        /// What is being worked on.
        what: &'a str,
    },
    /// Something the user should know that does not stop the run.
    Warning {
        /// The stage.
        stage: Stage,
        /// The warning.
        message: &'a str,
    },
    /// A stage ended after `elapsed`.
    Finished {
        /// The stage.
        stage: Stage,
        /// Its wall time.
        elapsed: Duration,
    },
}

/// Receives a run's events.
pub trait Observer {
    /// Called for every event, in the order they happen.
    fn event(&mut self, e: &Event<'_>);
}

impl<F: FnMut(&Event<'_>)> Observer for F {
    fn event(&mut self, e: &Event<'_>) {
        self(e)
    }
}

/// An observer that ignores everything.
pub struct Silent;

impl Observer for Silent {
    fn event(&mut self, _: &Event<'_>) {}
}
