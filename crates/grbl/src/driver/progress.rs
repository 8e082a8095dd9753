//! What the observer sees while a send runs ([`Progress`]) and what a completed send did
//! ([`SendReport`]).

use super::error::LineRef;
use super::tracker::Tracker;
use crate::response::MachineState;
use std::collections::BTreeMap;
use std::time::Duration;

/// What the sender is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Handshake.
    Connecting,
    /// `$C` check pass.
    Checking,
    /// Streaming the job.
    Streaming,
    /// All lines answered; waiting for the machine to finish.
    Finishing,
    /// Done.
    Done,
}

/// A progress snapshot for the observer.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// Phase.
    pub phase: Phase,
    /// Job lines acknowledged (including lines done in earlier runs when resuming).
    pub lines_acked: usize,
    /// Job lines known executed.
    pub lines_done: usize,
    /// Job lines in total.
    pub lines_total: usize,
    /// Last acknowledged line.
    pub last_acked: Option<LineRef>,
    /// Path length of executed lines, mm.
    pub length_done: f64,
    /// Total path length, mm.
    pub length_total: f64,
    /// Estimated remaining time.
    pub eta: Option<Duration>,
    /// Last reported machine state.
    pub state: Option<MachineState>,
    /// Last reported work position, mm.
    pub position: Option<[f64; 3]>,
    /// Time since streaming started.
    pub elapsed: Duration,
    /// Bytes written to the port.
    pub bytes_written: u64,
    /// Whether a feed hold is in effect.
    pub holding: bool,
    /// The job paused itself (`M0`) at this line and waits for the operator (resume or abort
    /// through the [`super::CancelToken`]).
    pub paused_at: Option<LineRef>,
    /// What the sender noticed so far that the operator should know before the machine runs
    /// (feeds over the controller's max rates, a work frame kept across the reset, a resume's
    /// homing), in order; the same texts end in [`SendReport::notices`].
    pub notices: Vec<String>,
}

impl Progress {
    /// The snapshot before anything happened.
    pub(super) fn start(job: &crate::job::Job) -> Progress {
        Progress {
            phase: Phase::Connecting,
            lines_acked: 0,
            lines_done: 0,
            lines_total: job.len(),
            last_acked: None,
            length_done: 0.0,
            length_total: job.total_length,
            eta: None,
            state: None,
            position: None,
            elapsed: Duration::ZERO,
            bytes_written: 0,
            holding: false,
            paused_at: None,
            notices: Vec::new(),
        }
    }

    /// The job is done.
    pub(super) fn complete(&mut self, job: &crate::job::Job) {
        self.phase = Phase::Done;
        self.lines_done = job.len();
        self.lines_acked = job.len();
        self.length_done = job.total_length;
        self.eta = Some(Duration::ZERO);
    }

    /// Fraction of the path length done, 0..=1 (line fraction for a job without motion).
    pub fn fraction(&self) -> f64 {
        if self.length_total > 0.0 {
            (self.length_done / self.length_total).clamp(0.0, 1.0)
        } else if self.lines_total > 0 {
            self.lines_done as f64 / self.lines_total as f64
        } else {
            1.0
        }
    }
}

/// What a completed send did.
#[derive(Debug, Clone, PartialEq)]
pub struct SendReport {
    /// GRBL version from the banner.
    pub version: String,
    /// RX buffer size used for character counting.
    pub rx_size: usize,
    /// Planner blocks reported by `[OPT:]`.
    pub planner_blocks: usize,
    /// Settings from `$$`.
    pub settings: BTreeMap<u16, f64>,
    /// Job lines sent in this run.
    pub lines_sent: usize,
    /// Resume preamble lines sent.
    pub preamble_lines: usize,
    /// Job lines already done before this run (resume).
    pub previously_done: usize,
    /// Bytes written during streaming.
    pub stream_bytes: u64,
    /// Streaming duration (first job byte to last `ok`).
    pub stream_time: Duration,
    /// Total duration including handshake and finishing.
    pub total_time: Duration,
    /// Largest number of bytes in flight.
    pub max_in_flight_bytes: usize,
    /// Final work position, mm.
    pub final_position: Option<[f64; 3]>,
    /// Estimated time of what this run sent with the machine's settings, s: the whole job, or
    /// on a resume what remained (preambles included, from where the machine stood).
    pub estimated_time: f64,
    /// Whether a `$C` pass ran first.
    pub checked: bool,
    /// What the sender did on its own and why (homing before a resume, say).
    pub notices: Vec<String>,
}

/// ETA: the remaining estimated motion time (less `ahead` s of lines the machine has passed but
/// nobody confirmed yet), scaled by how the machine kept up with the estimate so far (clamped
/// so one stall cannot make the figure absurd).
pub(super) fn eta(tr: &Tracker, elapsed: Duration, ahead: f64) -> Duration {
    let remaining = (tr.time_total - tr.time_done - ahead).max(0.0);
    let run = tr.time_done_run + ahead;
    let ratio = if run > 2.0 {
        (elapsed.as_secs_f64() / run).clamp(0.5, 2.0)
    } else {
        1.0
    };
    Duration::from_secs_f64(remaining * ratio)
}
