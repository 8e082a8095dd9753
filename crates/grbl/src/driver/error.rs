//! Why a send stopped: [`SendError`], with the line references its messages name.

use crate::codes::{alarm_is_critical, describe_alarm, error_meaning};
use crate::job_edit::JobChanges;
use crate::journal::JournalError;
use crate::transport::TransportError;
use std::fmt;
use std::time::Duration;
use thiserror::Error;

/// A reference to one job line, for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct LineRef {
    /// 0-based index among the job's streamable lines.
    pub index: usize,
    /// 1-based line number in the file.
    pub source_line: usize,
    /// The text sent.
    pub text: String,
}

/// Job line `i`, for messages.
pub(super) fn line_ref(job: &crate::job::Job, i: usize) -> LineRef {
    LineRef {
        index: i,
        source_line: job.lines[i].source_line,
        text: job.lines[i].text.clone(),
    }
}

impl fmt::Display for LineRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {} (`{}`)", self.source_line, self.text)
    }
}

fn fmt_pos(p: [f64; 3]) -> String {
    format!("X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2])
}

fn opt_line(l: &Option<LineRef>) -> String {
    match l {
        Some(l) => l.to_string(),
        None => "none".into(),
    }
}

/// Where the machine was found off the job's path during a run (see [`SendError::OffPath`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OffPath {
    /// First line of the stretch the machine could have been on.
    pub from: LineRef,
    /// Last line of that stretch.
    pub to: LineRef,
    /// Nearest point of that stretch, work coordinates (mm).
    pub expected: [f64; 3],
    /// Reported work position, mm.
    pub reported: [f64; 3],
    /// Tolerance, mm.
    pub tolerance: f64,
    /// Last line known executed.
    pub last_done: Option<LineRef>,
}

impl fmt::Display for OffPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the machine left the job's path while running lines {} to {}: it reported work position {} where the nearest point of those lines is {} ({:.3} mm away, more than the tolerance of {:.3} mm); a line was probably damaged on the link and ran elsewhere. Stopped: feed hold, soft reset, tool off. Last line known executed: {}",
            self.from.source_line,
            self.to.source_line,
            fmt_pos(self.reported),
            fmt_pos(self.expected),
            super::geometry::dist(self.reported, self.expected),
            self.tolerance,
            opt_line(&self.last_done)
        )
    }
}

/// A rejected line found by the check pass or while streaming.
#[derive(Debug, Clone, PartialEq)]
pub struct LineError {
    /// The line.
    pub line: LineRef,
    /// GRBL error code.
    pub code: u8,
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: error:{} ({})",
            self.line,
            self.code,
            error_meaning(self.code).unwrap_or("not a GRBL 1.1h error code")
        )
    }
}

/// Why sending stopped.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SendError {
    /// The port failed.
    #[error("{source}; last line known executed: {}", opt_line(last_done))]
    Transport {
        /// The transport error (hang-up, stall, ...).
        source: TransportError,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// The journal could not be written or read.
    #[error(transparent)]
    Journal(#[from] JournalError),
    /// No banner after opening and after a soft reset.
    #[error(
        "no GRBL banner within {0:?}, even after a soft reset (0x18): wrong port or baud rate?"
    )]
    NoBanner(Duration),
    /// A handshake command was rejected.
    #[error("the controller rejected `{command}`: error:{code} ({})", error_meaning(*code).unwrap_or("unknown code"))]
    SetupRejected {
        /// The command.
        command: String,
        /// Error code.
        code: u8,
    },
    /// A handshake command got no answer.
    #[error("no answer to `{command}` within {waited:?}")]
    SetupTimeout {
        /// The command.
        command: String,
        /// How long we waited.
        waited: Duration,
    },
    /// The controller is alarm-locked and unlocking was not allowed.
    #[error(
        "the controller is in alarm lock ({reason}) and unlocking it was not allowed: it must be homed, or unlocked with $X only if the machine position is known to be right"
    )]
    AlarmLocked {
        /// What GRBL said.
        reason: String,
    },
    /// The job does not fit the machine travel (`$130-$132`).
    #[error("{}", travel_message(*axis, *lo, *hi, *size, *mlo, *mhi, *travel))]
    OutOfTravel {
        /// Axis letter.
        axis: char,
        /// Work-coordinate extent.
        lo: f64,
        /// Work-coordinate extent.
        hi: f64,
        /// Size.
        size: f64,
        /// Machine-coordinate extent.
        mlo: f64,
        /// Machine-coordinate extent.
        mhi: f64,
        /// `$13n`.
        travel: f64,
    },
    /// The `$C` check pass found errors; nothing moved.
    #[error("check mode found {} rejected line(s); nothing was cut. First: {}", errors.len(), errors.first().map(|e| e.to_string()).unwrap_or_default())]
    CheckFailed {
        /// Every rejected line.
        errors: Vec<LineError>,
    },
    /// A line was rejected while streaming; no further lines were sent.
    #[error(
        "{error}; stopped sending (lines already in GRBL's buffer ran); last line known executed: {}",
        opt_line(last_done)
    )]
    LineRejected {
        /// The rejected line and code.
        error: LineError,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// A resume preamble line was rejected.
    #[error("resume preamble line `{text}` rejected: error:{code} ({})", error_meaning(*code).unwrap_or("unknown code"))]
    PreambleRejected {
        /// The preamble line.
        text: String,
        /// Error code.
        code: u8,
    },
    /// An alarm stopped the job.
    #[error("{}; the job stopped. Last line known executed: {}{}", describe_alarm(*code), opt_line(last_done), if alarm_is_critical(*code) { ". A soft reset was sent; home or unlock before resuming" } else { "" })]
    Alarm {
        /// Alarm code.
        code: u8,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// The controller reset by itself (banner mid-job); queued motion was lost.
    #[error(
        "the controller reset unexpectedly (banner received mid-job); {lost} unanswered line(s) were discarded. Last line known executed: {}",
        opt_line(last_done)
    )]
    UnexpectedReset {
        /// Lines in flight that were discarded.
        lost: usize,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// The controller went idle while lines were unanswered: bytes were lost on the link.
    #[error(
        "the controller is idle but {in_flight} line(s) sent were never answered: bytes were lost on the link. Last line known executed: {}",
        opt_line(last_done)
    )]
    LostAck {
        /// Unanswered lines.
        in_flight: usize,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// Nothing at all came back for too long.
    #[error(
        "the controller has been silent for {waited:?}. Last line known executed: {}",
        opt_line(last_done)
    )]
    DeviceSilent {
        /// How long.
        waited: Duration,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// The user aborted (soft reset sent, spindle/laser off).
    #[error(
        "aborted: soft reset sent, tool off. Last line known executed: {}",
        opt_line(last_done)
    )]
    Aborted {
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// After the job the machine is not where the job ends (a corrupted line moved elsewhere).
    #[error(
        "the job finished at work position {actual:?} but should end at {expected:?}: a line was corrupted on the link"
    )]
    PositionMismatch {
        /// Expected work position, mm.
        expected: [f64; 3],
        /// Reported work position, mm.
        actual: [f64; 3],
    },
    /// During the run the machine was found off the job's path: a line damaged on the link
    /// (GRBL's link has no checksum) that still parsed ran somewhere else.
    #[error("{0}")]
    OffPath(Box<OffPath>),
    /// The machine stayed in a state this sender did not ask for (a hold nobody released, check
    /// mode): lines it acknowledges there are not being cut.
    #[error(
        "the controller is in state {state}, which this sender did not request; stopped. Last line known executed: {}",
        opt_line(last_done)
    )]
    UnexpectedState {
        /// GRBL's state name.
        state: String,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// The job declares that it needs laser mode, and the controller has `$32=0`.
    #[error(
        "the job is a laser job (its header says it needs $32=1) but the controller has $32=0: in spindle mode the laser stays on during rapids and stops at every power change. It needs $32=1 on the controller, or an explicit override"
    )]
    LaserModeOff,
    /// The job paused itself (`M0`) with nobody to resume it: the run was aborted.
    #[error(
        "the job paused itself at {line} and the pause policy (abort, the default without a terminal) aborted the run: soft reset sent, tool off. Last line known executed: {}",
        opt_line(last_done)
    )]
    PausedByJob {
        /// The pausing line.
        line: LineRef,
        /// Last line known executed.
        last_done: Option<LineRef>,
    },
    /// The controller restarted or lost its position since the journal was written, it does
    /// not home, and nobody confirmed the work origin.
    #[error(
        "cannot resume: {why}, so the machine position is not known; the machine does not home, and nobody confirmed that its work origin is where it was when the job stopped"
    )]
    PositionUnknown {
        /// Why the position is lost.
        why: String,
    },
    /// The controller restarted or lost its position, it does not home, and the operator,
    /// asked, did not confirm that the work origin is where it was. Nothing moved.
    #[error(
        "cannot resume: {why}, and the operator did not confirm that the work origin is where it was; nothing moved, tool off"
    )]
    OriginNotConfirmed {
        /// Why the position is lost.
        why: String,
    },
    /// The job file was edited after its journal was written, and nobody accepted resuming it.
    #[error("{changes}\nRefusing to resume the changed job without confirmation; nothing was sent")]
    JobChanged {
        /// What changed.
        changes: Box<JobChanges>,
    },
    /// The job file was edited where the journal's job had already run (or had lines in
    /// doubt): only the operator can say which line to continue from.
    #[error("{changes}\nRefusing to guess where to continue the changed job; nothing was sent")]
    JobChangedWhereItRan {
        /// What changed.
        changes: Box<JobChanges>,
    },
    /// A stop whose tool-off sequence could not be confirmed.
    #[error(
        "{cause}. WARNING: the tool-off sequence (M5 M9) could not be confirmed with $G: check that the spindle, laser and air are off"
    )]
    ToolOffUnconfirmed {
        /// Why the run stopped.
        cause: Box<SendError>,
    },
    /// The controller's work frame could not be read before the soft reset at connection,
    /// which clears G92 and returns to G54: the job might run away from the operator's origin.
    #[error(
        "cannot read the controller's work offsets before the soft reset at connection ({why}); GRBL's reset clears a G92 offset and returns to G54, so the job could run away from the origin you set, and discarding the offsets was not allowed"
    )]
    OffsetsUnknown {
        /// What went wrong.
        why: String,
    },
    /// `resume` was asked without a journal path.
    #[error("resume needs a journal path")]
    NoJournal,
    /// Resuming would have to guess which lines ran: the operator must choose.
    #[error(
        "cannot tell where to resume: {reason}. Lines {} to {} may or may not have run; look at the work and resume explicitly from the first line to cut",
        from.source_line, to.source_line
    )]
    ResumeUncertain {
        /// First line in doubt.
        from: LineRef,
        /// Last line in doubt.
        to: LineRef,
        /// Why the journal and the machine cannot settle it.
        reason: String,
    },
    /// `resume_from` names no line of the job.
    #[error("cannot resume from line index {index}: the job has {lines} lines to send")]
    ResumeFromOutOfRange {
        /// Index asked.
        index: usize,
        /// Lines in the job.
        lines: usize,
    },
}

/// Why a job does not fit, in the coordinates where it fails: its length against the travel,
/// or, with homing and soft limits (GRBL then allows machine coordinates −travel..0 only), its
/// machine-coordinate range against that space.
fn travel_message(
    axis: char,
    lo: f64,
    hi: f64,
    size: f64,
    mlo: f64,
    mhi: f64,
    travel: f64,
) -> String {
    let n = axis_index(axis);
    if size > travel {
        format!(
            "the job's {axis} extent {lo:.3}..{hi:.3} mm is {size:.3} mm long, more than the machine travel of {travel:.3} mm ($13{n})"
        )
    } else {
        format!(
            "the job's {axis} extent {lo:.3}..{hi:.3} mm (work) lies at {mlo:.3}..{mhi:.3} mm in machine coordinates, outside {:.3}..0.000 mm, the machine space soft limits allow ($20=1 with homing, $13{n}={travel:.3}): set the work origin (G10 L20 or G92) so that the job lies inside it",
            -travel
        )
    }
}

fn axis_index(c: char) -> usize {
    match c {
        'X' => 0,
        'Y' => 1,
        _ => 2,
    }
}
