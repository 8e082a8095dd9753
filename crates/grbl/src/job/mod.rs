//! A G-code job prepared for streaming: lines stripped the way GRBL's pre-parser strips them,
//! modal state tracked before every line (for resume), path length per line (for progress) and a
//! motion-time estimate from GRBL's own motion model (for ETA).
//!
//! The interpreter is written here rather than taken from the `gcode` crate because streaming
//! needs exactly GRBL's view of a line (its stripping rules, the 79-character limit, its modal
//! groups and arc segmentation), not a general G-code AST.
//!
//! One idea per module: `modal` (the interpreter's state), `parse` (stripping, words, the
//! interpreter), `arc` (GRBL's arcs), `time` (the estimate), `resume` (preambles), `limits`
//! (the controller's settings the sender uses), `feeds` (the feeds those settings clamp), `sync`
//! (the lines GRBL answers only once the motion before them has finished).

mod arc;
mod feeds;
mod limits;
mod modal;
mod parse;
mod resume;
mod sync;
mod time;

pub use feeds::FeedClamp;
pub use limits::MachineLimits;
pub use modal::{ModalState, MotionMode, Spindle, Units};
pub use parse::strip_line;

use parse::Interpreter;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// GRBL's line buffer holds 80 bytes including the terminator (`grbl/protocol.h:31-32`).
pub const MAX_LINE_CHARS: usize = 79;
/// Millimetres per inch (G20).
const MM_PER_INCH: f64 = 25.4;
/// Below this length a motion is treated as zero-length (GRBL drops moves of zero steps; at the
/// default 250 steps/mm one step is 0.004 mm, so this is well under a step).
const ZERO_LENGTH_MM: f64 = 1e-9;

/// Errors found while preparing a job.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum JobError {
    /// A stripped line is longer than GRBL's 79-character line buffer (would get `error:11`).
    #[error(
        "line {line}: {len} significant characters after stripping, GRBL accepts at most 79: {text}"
    )]
    LineTooLong {
        /// 1-based line number in the file.
        line: usize,
        /// Stripped length.
        len: usize,
        /// Stripped text.
        text: String,
    },
    /// A tool change (`M6`), which GRBL rejects with `error:20`.
    #[error(
        "line {line}: tool change M6 is not supported by GRBL (error:20); split the job per tool: {text}"
    )]
    ToolChange {
        /// 1-based line number in the file.
        line: usize,
        /// Stripped text.
        text: String,
    },
    /// A word whose value does not parse as a number (would get `error:2`).
    #[error("line {line}: bad number for word '{letter}': {text}")]
    BadNumber {
        /// 1-based line number in the file.
        line: usize,
        /// The word letter.
        letter: char,
        /// Stripped text.
        text: String,
    },
    /// A character GRBL would not see as written: its serial interrupt takes `?`, `!` and `~`
    /// out of the stream as realtime commands (a feed hold in the middle of a line!) and drops
    /// bytes over 0x7F, so the line it parsed would not be the line in the file.
    #[error(
        "line {line}: character {ch:?} outside a comment, which GRBL would not receive as written: {text}"
    )]
    BadCharacter {
        /// 1-based line number in the file.
        line: usize,
        /// The character.
        ch: char,
        /// Stripped text.
        text: String,
    },
    /// The file holds no line to send.
    #[error("the job has no G-code lines")]
    Empty,
}

/// What kind of line this is, for the streamer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LineKind {
    /// G-code that GRBL buffers (character counting applies).
    Gcode,
    /// A `$` system command (send-response: many need IDLE and some write EEPROM).
    System,
    /// Writes EEPROM (`$x=`, `$N..=`, `G10 L2/L20`, `G28.1`, `G30.1`): send-response only, since
    /// the EEPROM write disables the RX interrupt (`interface.md:64-71`).
    EepromWrite,
}

/// One streamable line of a job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobLine {
    /// 1-based line number in the source file.
    pub source_line: usize,
    /// The text to send (stripped, upper-case, no terminator).
    pub text: String,
    /// How to send it.
    pub kind: LineKind,
    /// Motion word given on this line or in effect through modality when it has axis words.
    pub moves: bool,
    /// Path length of this line's motion, mm.
    pub length: f64,
    /// Estimated execution time, seconds (motion with acceleration, plus dwells).
    pub time: f64,
    /// Tool on (spindle/laser on, or pen below Z=0) during this line's motion.
    pub tool_on: bool,
    /// Modal state before the line.
    pub before: ModalState,
    /// For an arc: its chord points as GRBL splits it, start and end included (G92-free work
    /// coordinates, mm); empty for anything else.
    #[serde(default)]
    pub arc: Vec<[f64; 3]>,
}

/// A job ready to stream.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// Streamable lines (blank, comment-only and `%` lines are dropped).
    pub lines: Vec<JobLine>,
    /// FNV-1a 64-bit hash of the source text, identifying the job for resume.
    pub hash: u64,
    /// Total path length, mm.
    pub total_length: f64,
    /// Total estimated time, s.
    pub total_time: f64,
    /// Bounding box of all motion endpoints and arc samples (G92-free work coordinates), mm;
    /// `None` if the job never moves.
    pub extent: Option<([f64; 3], [f64; 3])>,
    /// Whether the job uses G92 offsets (resume then has to re-establish them).
    pub uses_g92: bool,
    /// Highest Z reached (the pen-up / safe height used by resume), mm; `None` if Z never moves.
    pub safe_z: Option<f64>,
    /// State after the last line.
    pub end_state: ModalState,
    /// A comment declares that the job needs laser mode (`$32=1`), as flatcut's laser header
    /// does.
    #[serde(default)]
    pub needs_laser_mode: bool,
}

/// Where a job starts on the controller: the active work coordinate system (54..=59), the G92
/// offset in effect (mm) and the work position (mm, in the G92 frame, as `WPos` reports it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JobStart {
    /// G54..G59 as 54..=59 (0 is read as 54).
    pub wcs: u8,
    /// G92 offset, mm.
    pub g92: [f64; 3],
    /// Work position, mm.
    pub position: [f64; 3],
}

/// FNV-1a, 64 bit: a stable, dependency-free content hash (not cryptographic; it guards
/// against resuming the wrong file, not against an adversary).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

impl Job {
    /// Parses and prepares a job with the default machine limits (call [`Job::retime`] once the
    /// machine's `$$` is known).
    pub fn parse(text: &str) -> Result<Job, JobError> {
        Job::parse_with(text, &MachineLimits::DEFAULT)
    }

    /// Parses and prepares a job, estimating times with `limits`.
    pub fn parse_with(text: &str, limits: &MachineLimits) -> Result<Job, JobError> {
        let mut interp = Interpreter::new(limits.motion.arc_tolerance);
        for (i, raw) in text.lines().enumerate() {
            interp.line(i + 1, raw)?;
        }
        interp.finish(text, limits)
    }

    /// The job as it runs on a controller standing in `start`: the program begins in the
    /// controller's work coordinate system, with its G92 offset, at its position, so axes the
    /// job never sets stay where the controller has them (an XY-only job run with Z at 3 is at
    /// Z 3 throughout, not at 0) and a first relative move starts from there. Timed with
    /// `limits`; the hash (the job's identity for resume) is the file's.
    pub fn rebased(&self, start: &JobStart, limits: &MachineLimits) -> Job {
        let st = ModalState {
            wcs: start.wcs.clamp(54, 59),
            position: start.position,
            g92: start.g92,
            ..ModalState::default()
        };
        let mut interp = Interpreter::starting_at(limits.motion.arc_tolerance, st);
        for l in &self.lines {
            // The lines are already stripped and were accepted once: they parse again.
            if interp.line(l.source_line, &l.text).is_err() {
                return self.clone();
            }
        }
        match interp.finish_lines(self.hash, self.needs_laser_mode, limits) {
            Some(job) => job,
            None => self.clone(),
        }
    }

    /// Number of streamable lines.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// True if there is no line (never for a parsed job).
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// The modal state before line `index` (the end state past the last line).
    pub fn state_before(&self, index: usize) -> &ModalState {
        match self.lines.get(index) {
            Some(l) => &l.before,
            None => &self.end_state,
        }
    }

    /// The work position (G92-free, mm) where line `index` ends.
    pub fn end_of(&self, index: usize) -> [f64; 3] {
        let st = self.state_before(index + 1);
        add(st.position, st.g92)
    }

    /// What the job moves, in order: `(text, start, end)` (G92-free work coordinates, mm) of
    /// every line whose motion has length. The reference that a machine's executed trace is
    /// checked against.
    pub fn motions(&self) -> Vec<(String, [f64; 3], [f64; 3])> {
        (0..self.len())
            .filter(|&i| self.lines[i].moves && self.lines[i].length > ZERO_LENGTH_MM)
            .map(|i| (self.lines[i].text.clone(), self.start_of(i), self.end_of(i)))
            .collect()
    }

    /// The first line to send from line `source_line` of the file on (1-based; a blank or
    /// comment line names the next line that is sent): where an operator's "resume from line N"
    /// continues. `None` when nothing is sent from there on.
    pub fn first_line_from(&self, source_line: usize) -> Option<usize> {
        self.lines.iter().position(|l| l.source_line >= source_line)
    }

    /// Whether line `index` pauses the program (`M0`): GRBL holds the feed there and keeps
    /// the line's `ok` until cycle start.
    pub fn pauses(&self, index: usize) -> bool {
        self.lines.get(index).is_some_and(|l| {
            l.kind == LineKind::Gcode
                && parse::words(&l.text).is_ok_and(|ws| ws.iter().any(|w| w.0 == 'M' && w.1 == 0.0))
        })
    }

    /// The feed (mm/min) at which the job plunges the tool (a `G1` that only lowers Z) last
    /// before line `next`, else first after it; `None` if it never does.
    pub fn plunge_feed(&self, next: usize) -> Option<f64> {
        let plunge = |i: usize| {
            let l = &self.lines[i];
            let (a, b) = (self.start_of(i), self.end_of(i));
            let after = self.state_before(i + 1);
            (l.moves
                && after.motion == MotionMode::Linear
                && !after.inverse_time
                && b[2] < a[2]
                && a[0] == b[0]
                && a[1] == b[1]
                && after.feed > 0.0)
                .then_some(after.feed)
        };
        let next = next.min(self.len());
        (0..next)
            .rev()
            .find_map(plunge)
            .or_else(|| (next..self.len()).find_map(plunge))
    }

    /// The work position (G92-free, mm) where line `index` starts.
    pub fn start_of(&self, index: usize) -> [f64; 3] {
        let st = self.state_before(index);
        add(st.position, st.g92)
    }
}

/// Formats a number for G-code: up to 4 decimals, no trailing zeros, no `-0`.
pub fn fmt_num(v: f64) -> String {
    let mut s = format!("{v:.4}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" { "0".into() } else { s }
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests;
