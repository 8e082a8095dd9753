//! The blocking sender: [`send_job`] runs the handshake (banner or soft reset, `$I`, `$$`,
//! status, alarm-lock policy, travel check), an optional `$C` check pass, then streams the job
//! with character counting while polling `?` at 5 Hz, honouring feed hold / resume / abort from
//! a [`CancelToken`], journaling every acknowledged line, and stopping with a typed error that
//! names the line and the code's meaning on `error:N`, `ALARM:N`, reset or hang-up.
//!
//! Which acknowledged lines have really *executed* is tracked conservatively (an `ok` only means
//! "queued"): all acknowledged lines are done when the machine reports `Idle`; a line is done
//! once more motion lines than the planner and segment buffers can hold were acknowledged after
//! it; and after a stop, the reported position locates the line the machine was on.

use crate::codes::{alarm_is_critical, alarm_meaning, describe_alarm, error_meaning};
use crate::job::{Job, LineKind, MachineLimits};
use crate::journal::{Journal, JournalError, JournalState};
use crate::response::{MachineState, StatusReport};
use crate::streamer::{Event, SendMode, Streamer, Tag};
use crate::transport::{Transport, TransportError};
use std::collections::{BTreeMap, VecDeque};
use std::fmt;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use thiserror::Error;

/// GRBL's stepper segment buffer (`SEGMENT_BUFFER_SIZE 6`, `grbl/stepper.h`): prepared segments
/// may belong to blocks already released from the planner, so that many extra lines may still be
/// moving after the planner has room.
const SEGMENT_BUFFER: usize = 6;
/// Planner blocks on a 328p, used until `[OPT:]` says otherwise (`grbl/planner.h:27-31`).
const DEFAULT_PLANNER_BLOCKS: usize = 15;
/// Position match tolerance, mm: reports carry 3 decimals and a step is 0.004 mm at 250 steps/mm.
const POSITION_TOL_MM: f64 = 0.01;
/// `ALARM:3`: reset while in motion; GRBL's position may be off by the steps lost stopping.
const ABORT_CYCLE_ALARM: u8 = 3;
/// Longest single read wait, so control requests and polls stay responsive.
const READ_SLICE: Duration = Duration::from_millis(20);
/// Longest gap between two fsyncs of the journal while streaming. Every batch of records is
/// written to the OS at once (it survives the sender being killed); the flush to the disk runs
/// on a background thread at most this often, because an fsync takes milliseconds to tens of
/// milliseconds and the link must not wait for it (at 115200 baud the 128-byte RX buffer
/// drains in 11 ms). Every stop syncs in the foreground.
const JOURNAL_FSYNC_INTERVAL: Duration = Duration::from_millis(250);
/// How long a controller found moving when the sender connects may take to finish the motion it
/// has queued (15 planner blocks) before the sender gives up waiting for it.
const DRAIN_ON_CONNECT_LIMIT: Duration = Duration::from_secs(600);

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

impl fmt::Display for LineRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {} (`{}`)", self.source_line, self.text)
    }
}

fn opt_line(l: &Option<LineRef>) -> String {
    match l {
        Some(l) => l.to_string(),
        None => "none".into(),
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
        "the controller is in alarm lock ({reason}); home it, or pass --unlock to send $X if the machine position is known to be right"
    )]
    AlarmLocked {
        /// What GRBL said.
        reason: String,
    },
    /// The job does not fit the machine travel (`$130-$132`).
    #[error("the job's {axis} extent {lo:.3}..{hi:.3} mm ({size:.3} mm in machine coordinates {mlo:.3}..{mhi:.3}) exceeds the machine travel of {travel:.3} mm ($13{n})", n = axis_index(*axis))]
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
    /// `resume` was asked without a journal path.
    #[error("resume needs a journal path")]
    NoJournal,
    /// Resuming would have to guess which lines ran: the operator must choose.
    #[error(
        "cannot tell where to resume: {reason}. Lines {} to {} may or may not have run; look at the work and resume explicitly from the first line to cut (--resume-from LINE, a line number of the file)",
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
    #[error("--resume-from: the job has {lines} lines to send; index {index} is not one of them")]
    ResumeFromOutOfRange {
        /// Index asked.
        index: usize,
        /// Lines in the job.
        lines: usize,
    },
}

fn axis_index(c: char) -> usize {
    match c {
        'X' => 0,
        'Y' => 1,
        _ => 2,
    }
}

/// Options for [`send_job`].
#[derive(Debug, Clone, PartialEq)]
pub struct SendOptions {
    /// How long to wait for the banner after opening (and again after a soft reset).
    pub banner_timeout: Duration,
    /// Send a soft reset at once instead of waiting for a power-up banner first.
    pub reset_on_connect: bool,
    /// Timeout for each handshake command.
    pub command_timeout: Duration,
    /// Status poll interval (`?`); GRBL's author recommends at most 5 Hz.
    pub status_interval: Duration,
    /// Send `$X` if the controller is alarm-locked.
    pub unlock: bool,
    /// Run the whole job in check mode (`$C`) before cutting.
    pub check: bool,
    /// Refuse a job that does not fit `$130-$132`.
    pub check_travel: bool,
    /// Journal file (required for resume).
    pub journal: Option<PathBuf>,
    /// Resume from the journal instead of starting over.
    pub resume: bool,
    /// After this long idle with lines unanswered, report lost bytes.
    pub idle_ack_timeout: Duration,
    /// After this long without any byte from the controller, give up.
    pub silence_timeout: Duration,
    /// Compare the final position with the job's end point.
    pub verify_end_position: bool,
    /// Minimum interval between observer calls while streaming.
    pub progress_interval: Duration,
    /// Give up when the machine sits in a feed hold or door state that this sender did not
    /// request for this long (`None`: wait for the operator indefinitely, as after `M0`).
    pub hold_timeout: Option<Duration>,
    /// With `resume`: the operator's choice of the first job line (0-based index) to run; every
    /// line before it counts as done. Needed when the journal and the machine cannot tell.
    pub resume_from: Option<usize>,
}

impl SendOptions {
    /// Default banner wait: a real Uno's bootloader takes 1.4–2 s after DTR.
    pub const DEFAULT_BANNER_TIMEOUT: Duration = Duration::from_millis(2500);
    /// Default handshake command timeout.
    pub const DEFAULT_COMMAND_TIMEOUT: Duration = Duration::from_secs(5);
    /// Default status interval: 5 Hz.
    pub const DEFAULT_STATUS_INTERVAL: Duration = Duration::from_millis(200);
    /// Default idle-with-unanswered-lines timeout.
    pub const DEFAULT_IDLE_ACK_TIMEOUT: Duration = Duration::from_secs(2);
    /// Default silence timeout.
    pub const DEFAULT_SILENCE_TIMEOUT: Duration = Duration::from_secs(10);
    /// Default observer interval: 20 updates a second is smooth for a progress bar.
    pub const DEFAULT_PROGRESS_INTERVAL: Duration = Duration::from_millis(50);

    /// Sets [`SendOptions::resume_from`] (and `resume`).
    pub fn with_resume_from(mut self, index: Option<usize>) -> Self {
        self.resume_from = index;
        if index.is_some() {
            self.resume = true;
        }
        self
    }

    /// Sets [`SendOptions::hold_timeout`].
    pub fn with_hold_timeout(mut self, d: Option<Duration>) -> Self {
        self.hold_timeout = d;
        self
    }

    /// Sets [`SendOptions::progress_interval`].
    pub fn with_progress_interval(mut self, d: Duration) -> Self {
        self.progress_interval = d;
        self
    }

    /// Sets [`SendOptions::banner_timeout`].
    pub fn with_banner_timeout(mut self, d: Duration) -> Self {
        self.banner_timeout = d;
        self
    }
    /// Sets [`SendOptions::reset_on_connect`].
    pub fn with_reset_on_connect(mut self, on: bool) -> Self {
        self.reset_on_connect = on;
        self
    }
    /// Sets [`SendOptions::command_timeout`].
    pub fn with_command_timeout(mut self, d: Duration) -> Self {
        self.command_timeout = d;
        self
    }
    /// Sets [`SendOptions::status_interval`].
    pub fn with_status_interval(mut self, d: Duration) -> Self {
        self.status_interval = d;
        self
    }
    /// Sets [`SendOptions::unlock`].
    pub fn with_unlock(mut self, on: bool) -> Self {
        self.unlock = on;
        self
    }
    /// Sets [`SendOptions::check`].
    pub fn with_check(mut self, on: bool) -> Self {
        self.check = on;
        self
    }
    /// Sets [`SendOptions::check_travel`].
    pub fn with_check_travel(mut self, on: bool) -> Self {
        self.check_travel = on;
        self
    }
    /// Sets [`SendOptions::journal`].
    pub fn with_journal(mut self, path: impl Into<PathBuf>) -> Self {
        self.journal = Some(path.into());
        self
    }
    /// Sets [`SendOptions::resume`].
    pub fn with_resume(mut self, on: bool) -> Self {
        self.resume = on;
        self
    }
    /// Sets [`SendOptions::idle_ack_timeout`].
    pub fn with_idle_ack_timeout(mut self, d: Duration) -> Self {
        self.idle_ack_timeout = d;
        self
    }
    /// Sets [`SendOptions::silence_timeout`].
    pub fn with_silence_timeout(mut self, d: Duration) -> Self {
        self.silence_timeout = d;
        self
    }
    /// Sets [`SendOptions::verify_end_position`].
    pub fn with_verify_end_position(mut self, on: bool) -> Self {
        self.verify_end_position = on;
        self
    }
}

impl Default for SendOptions {
    fn default() -> SendOptions {
        SendOptions {
            banner_timeout: SendOptions::DEFAULT_BANNER_TIMEOUT,
            reset_on_connect: false,
            command_timeout: SendOptions::DEFAULT_COMMAND_TIMEOUT,
            status_interval: SendOptions::DEFAULT_STATUS_INTERVAL,
            unlock: false,
            check: false,
            check_travel: true,
            journal: None,
            resume: false,
            idle_ack_timeout: SendOptions::DEFAULT_IDLE_ACK_TIMEOUT,
            silence_timeout: SendOptions::DEFAULT_SILENCE_TIMEOUT,
            verify_end_position: true,
            progress_interval: SendOptions::DEFAULT_PROGRESS_INTERVAL,
            hold_timeout: None,
            resume_from: None,
        }
    }
}

#[derive(Debug, Default)]
struct ControlState {
    hold: bool,
    resume: bool,
    abort: bool,
}

/// A handle to steer a running [`send_job`] from another thread (the CLI's Ctrl-C handler):
/// feed hold, resume (cycle start) and abort (feed hold, then soft reset; tool off).
#[derive(Debug, Clone, Default)]
pub struct CancelToken {
    inner: Arc<Mutex<ControlState>>,
}

/// The same handle under the name the CLI uses.
pub type Control = CancelToken;

impl CancelToken {
    /// A new, untriggered token.
    pub fn new() -> CancelToken {
        CancelToken::default()
    }

    fn with<R>(&self, f: impl FnOnce(&mut ControlState) -> R) -> R {
        let mut g = match self.inner.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        f(&mut g)
    }

    /// Requests a feed hold (`!`).
    pub fn hold(&self) {
        self.with(|s| s.hold = true);
    }

    /// Requests a resume (`~`) after a hold.
    pub fn resume(&self) {
        self.with(|s| s.resume = true);
    }

    /// Requests an abort: feed hold, then soft reset, which turns the tool off.
    pub fn abort(&self) {
        self.with(|s| s.abort = true);
    }

    /// Whether an abort was requested.
    pub fn is_aborted(&self) -> bool {
        self.with(|s| s.abort)
    }

    fn take(&self) -> ControlState {
        self.with(std::mem::take)
    }
}

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
}

impl Progress {
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
    /// Estimated job time with the machine's settings, s.
    pub estimated_time: f64,
    /// Whether a `$C` pass ran first.
    pub checked: bool,
}

struct Session<'a, T: Transport + ?Sized> {
    t: &'a mut T,
    s: Streamer,
    last_rx: Instant,
    status: Option<StatusReport>,
    status_seq: u64,
    wco: [f64; 3],
    report_inches: bool,
    version: String,
    blocks: usize,
    settings: BTreeMap<u16, f64>,
    messages: Vec<String>,
    alarm_lock: bool,
    setup_seq: u32,
    /// Banners seen so far.
    resets: u64,
}

impl<'a, T: Transport + ?Sized> Session<'a, T> {
    fn write(&mut self) -> Result<(), TransportError> {
        while let Some(bytes) = self.s.poll_transmit() {
            self.t.write_all(&bytes)?;
        }
        Ok(())
    }

    fn pump(&mut self, wait: Duration) -> Result<Vec<Event>, TransportError> {
        self.write()?;
        let mut buf = [0u8; 1024];
        let n = self.t.read(&mut buf, wait)?;
        if n == 0 {
            return Ok(Vec::new());
        }
        self.last_rx = Instant::now();
        let events = self.s.receive(&buf[..n]);
        for e in &events {
            match e {
                Event::Status(st) => {
                    if let Some(w) = st.wco {
                        self.wco = w;
                    }
                    self.alarm_lock = st.state == MachineState::Alarm;
                    self.status = Some(st.clone());
                    self.status_seq += 1;
                }
                Event::Options { blocks, .. } => self.blocks = *blocks as usize,
                Event::Setting(n, v) => {
                    self.settings.insert(*n, *v);
                    if *n == 13 {
                        self.report_inches = *v != 0.0;
                    }
                }
                Event::Message(m) => {
                    if m.contains("unlock") {
                        self.alarm_lock = true;
                    }
                    self.messages.push(m.clone());
                }
                Event::Alarm(_) => self.alarm_lock = true,
                Event::Reset { version, .. } => {
                    self.resets += 1;
                    self.version = version.clone();
                    self.wco = [0.0; 3];
                }
                _ => {}
            }
        }
        Ok(events)
    }

    fn wait_banner(&mut self, timeout: Duration) -> Result<bool, TransportError> {
        let seen = self.resets;
        self.wait_banner_after(seen, timeout)
    }

    /// Waits until more than `seen` banners have arrived (one may already have come in while
    /// waiting for something else), then lets the push messages that follow it arrive.
    fn wait_banner_after(&mut self, seen: u64, timeout: Duration) -> Result<bool, TransportError> {
        let until = Instant::now() + timeout;
        while self.resets <= seen {
            if Instant::now() >= until {
                return Ok(false);
            }
            self.pump(READ_SLICE)?;
        }
        let settle = Instant::now() + Duration::from_millis(30);
        while Instant::now() < settle {
            self.pump(Duration::from_millis(10))?;
        }
        Ok(true)
    }

    /// Sends one command with send-response and waits for its answer.
    fn command(&mut self, text: &str, timeout: Duration) -> Result<Result<(), u8>, SendError> {
        self.setup_seq += 1;
        let tag = Tag::Setup(self.setup_seq);
        self.s.push(tag, text, SendMode::SendResponse);
        let until = Instant::now() + timeout;
        while Instant::now() < until {
            let evs = self.pump(READ_SLICE).map_err(|e| transport(e, None))?;
            for e in evs {
                match e {
                    Event::Ack(t) if t == tag => return Ok(Ok(())),
                    Event::Rejected(t, code) if t == tag => return Ok(Err(code)),
                    Event::Reset { lost, .. } if lost.contains(&tag) => {
                        // Re-send after an unexpected reset during the handshake.
                        self.s.push(tag, text, SendMode::SendResponse);
                    }
                    _ => {}
                }
            }
        }
        Err(SendError::SetupTimeout {
            command: text.into(),
            waited: timeout,
        })
    }

    fn command_ok(&mut self, text: &str, timeout: Duration) -> Result<(), SendError> {
        match self.command(text, timeout)? {
            Ok(()) => Ok(()),
            Err(code) => Err(SendError::SetupRejected {
                command: text.into(),
                code,
            }),
        }
    }

    /// Requests a status report and waits for it.
    fn query_status(&mut self, timeout: Duration) -> Result<Option<StatusReport>, TransportError> {
        let seq = self.status_seq;
        self.s.realtime(b'?');
        let until = Instant::now() + timeout;
        let mut resend = Instant::now() + Duration::from_millis(250);
        while Instant::now() < until {
            self.pump(READ_SLICE)?;
            if self.status_seq != seq {
                return Ok(self.status.clone());
            }
            if Instant::now() > resend {
                // A `?` right before or after a reset may go unanswered.
                self.s.realtime(b'?');
                resend = Instant::now() + Duration::from_millis(250);
            }
        }
        Ok(None)
    }

    fn work_position(&self) -> Option<[f64; 3]> {
        let p = self.status.as_ref()?.work_position(self.wco)?;
        let k = if self.report_inches { 25.4 } else { 1.0 };
        Some([p[0] * k, p[1] * k, p[2] * k])
    }
}

/// Stops a run: records why in the journal, makes the journal durable, and returns `err`.
fn stop_noted<T>(journal: &mut Option<Journal>, why: &str, err: SendError) -> Result<T, SendError> {
    if let Some(j) = journal.as_mut() {
        j.note(why);
        j.sync()?;
    }
    Err(err)
}

fn transport(source: TransportError, last_done: Option<LineRef>) -> SendError {
    SendError::Transport { source, last_done }
}

fn line_ref(job: &Job, i: usize) -> LineRef {
    LineRef {
        index: i,
        source_line: job.lines[i].source_line,
        text: job.lines[i].text.clone(),
    }
}

/// Bookkeeping of which job lines are acknowledged / known executed in this run.
struct Tracker {
    done: Vec<bool>,
    acked: Vec<bool>,
    /// Acked in this run, not yet known executed, in ack order.
    unconfirmed: VecDeque<usize>,
    /// Motion lines acked after each unconfirmed one, counted implicitly by position.
    motion_after: VecDeque<usize>,
    capacity: usize,
    length_done: f64,
    time_done: f64,
    /// Lines done before this run (not sent in it).
    prior_done: Vec<bool>,
    /// Position match tolerance, mm.
    pos_tol: f64,
    /// Highest job index handed to the port in this run.
    last_sent: Option<usize>,
    /// Lines acknowledged (including earlier runs).
    acked_count: usize,
    /// Lines known executed (including earlier runs).
    done_count: usize,
    /// Estimated time of the whole job, s.
    time_total: f64,
    /// Estimated time of the lines executed in this run, s.
    time_done_run: f64,
}

impl Tracker {
    fn confirm(&mut self, job: &Job, upto_count: usize, journal: &mut Option<Journal>) {
        let mut last = None;
        for _ in 0..upto_count.min(self.unconfirmed.len()) {
            let Some(i) = self.unconfirmed.pop_front() else {
                break;
            };
            self.motion_after.pop_front();
            if !self.done[i] {
                self.done[i] = true;
                self.done_count += 1;
                self.length_done += job.lines[i].length;
                self.time_done += job.lines[i].time;
                self.time_done_run += job.lines[i].time;
            }
            last = Some(last.map_or(i, |l: usize| l.max(i)));
        }
        if let (Some(k), Some(j)) = (last, journal.as_mut()) {
            j.executed_through(k);
        }
    }

    fn ack(&mut self, job: &Job, i: usize, journal: &mut Option<Journal>) {
        if !self.acked[i] {
            self.acked_count += 1;
        }
        self.acked[i] = true;
        let is_motion = job.lines[i].moves && job.lines[i].length > 0.0;
        if is_motion {
            for m in self.motion_after.iter_mut() {
                *m += 1;
            }
        }
        self.unconfirmed.push_back(i);
        self.motion_after.push_back(0);
        // Lines with more motion lines acknowledged after them than GRBL can hold are done.
        let n = self
            .motion_after
            .iter()
            .take_while(|&&m| m >= self.capacity)
            .count();
        if n > 0 {
            self.confirm(job, n, journal);
        }
    }

    /// Confirms every unconfirmed line with index below `bound`.
    fn confirm_below(&mut self, job: &Job, bound: usize, journal: &mut Option<Journal>) {
        let c = self.unconfirmed.iter().take_while(|&&i| i < bound).count();
        self.confirm(job, c, journal);
    }

    /// Confirms by the reported position `pos`: the first line sent in this run (up to index
    /// `upto`, acknowledged or not) whose path contains `pos` is where the machine stopped;
    /// every acknowledged line before it is done, and it too if `pos` is its end point. A stop
    /// inside a line is journaled (`P`) so that a resume completes that line from there.
    fn confirm_by_position(
        &mut self,
        job: &Job,
        pos: [f64; 3],
        upto: usize,
        journal: &mut Option<Journal>,
    ) {
        let Some(&first) = self.unconfirmed.front() else {
            return;
        };
        let upto = upto.min(job.len().saturating_sub(1)).max(first);
        let prior = &self.prior_done;
        let places = places_on_path(job, pos, first..=upto, self.pos_tol, |i| prior[i]);
        // Ambiguous (the path passes here twice): the earliest place confirms least.
        let Some(&(cut, partial)) = places.first() else {
            return;
        };
        self.confirm_below(job, cut, journal);
        if cut < job.len()
            && let Some(j) = journal.as_mut()
        {
            // The lines from `cut` on did not run (the stop flushed GRBL's planner): the resume
            // continues line `cut` from where the machine stands.
            j.partial(cut, partial.unwrap_or(pos));
        }
    }

    fn last_done(&self, job: &Job) -> Option<LineRef> {
        let n = self.done.iter().take_while(|d| **d).count();
        n.checked_sub(1).map(|i| line_ref(job, i))
    }
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn seg_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let t = if l2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t])
}

/// Runs a whole send: handshake, optional check pass, streaming with status polling and
/// journaling, and the final wait for the machine to finish. See the module docs.
///
/// With `opts.resume`, the journal at `opts.journal` must belong to this job; the lines it does
/// not record as executed are sent, each contiguous run preceded by a preamble restoring the
/// modal state, pen/tool height and position of the job at that point.
pub fn send_job(
    transport_: &mut dyn Transport,
    job: &Job,
    opts: &SendOptions,
    observer: &mut dyn FnMut(&Progress),
    cancel: &CancelToken,
) -> Result<SendReport, SendError> {
    let t0 = Instant::now();
    // Journal first: refuse a wrong job before touching the machine.
    let (mut journal, prior): (Option<Journal>, Option<JournalState>) =
        match (&opts.journal, opts.resume) {
            (Some(p), true) => {
                let (j, st) = Journal::resume(p, job)?;
                (Some(j), Some(st))
            }
            (Some(p), false) => (Some(Journal::create(p, job)?), None),
            (None, true) => return Err(SendError::NoJournal),
            (None, false) => (None, None),
        };
    let mut sess = Session {
        t: transport_,
        s: Streamer::default(),
        last_rx: Instant::now(),
        status: None,
        status_seq: 0,
        wco: [0.0; 3],
        report_inches: false,
        version: String::new(),
        blocks: DEFAULT_PLANNER_BLOCKS,
        settings: BTreeMap::new(),
        messages: Vec::new(),
        alarm_lock: false,
        setup_seq: 0,
        resets: 0,
    };
    let mut progress = Progress {
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
    };
    observer(&progress);

    // --- Handshake: banner (or soft reset), $I, $$, status, alarm policy, travel.
    // A banner that comes by itself means the controller just restarted (power-up, or the DTR
    // pulse of opening the port): its planner and position are gone.
    let restarted = !opts.reset_on_connect
        && sess
            .wait_banner(opts.banner_timeout)
            .map_err(|e| transport(e, None))?;
    let mut got = restarted;
    if !got {
        if !opts.reset_on_connect {
            // A controller that kept running while the host was away may still be draining its
            // planner: a reset now would stop it mid-move (ALARM:3, position lost).
            wait_until_still(&mut sess, opts).map_err(|e| transport(e, None))?;
        }
        sess.s.realtime(0x18);
        got = sess
            .wait_banner(opts.banner_timeout)
            .map_err(|e| transport(e, None))?;
    }
    if !got {
        return Err(SendError::NoBanner(opts.banner_timeout));
    }
    sess.command_ok("$I", opts.command_timeout)?;
    sess.command_ok("$$", opts.command_timeout)?;
    sess.query_status(opts.command_timeout)
        .map_err(|e| transport(e, None))?;
    if sess.alarm_lock {
        let reason = sess
            .messages
            .iter()
            .rev()
            .find(|m| m.contains("unlock") || m.contains("Reset"))
            .cloned()
            .unwrap_or_else(|| "state Alarm".into());
        if !opts.unlock {
            return Err(SendError::AlarmLocked { reason });
        }
        sess.command_ok("$X", opts.command_timeout)?;
        sess.alarm_lock = false;
        sess.query_status(opts.command_timeout)
            .map_err(|e| transport(e, None))?;
    }
    // --- Settle what the interrupted run left in doubt, from the journal and the machine.
    // Trust the reported position only if the controller did not restart and is not in alarm
    // (a reset in motion, ALARM:3, loses steps).
    let trusted = !restarted && !sess.alarm_lock;
    let mut prior = prior;
    let mut resume_at: Option<(usize, [f64; 3], bool)> = None;
    if let Some(st) = prior.as_mut() {
        let here = if trusted { sess.work_position() } else { None };
        let tol = position_tolerance(&sess.settings);
        let rx = sess.s.rx_size();
        if let Some(r) = resolve_resume(job, st, opts.resume_from, here, rx, tol, restarted)? {
            if let Some(j) = journal.as_mut() {
                j.resolved(r.from, r.cut);
                if let Some((k, p)) = r.partial {
                    j.partial(k, p);
                }
                j.sync()?;
            }
            for i in r.from..r.cut {
                st.done[i] = true;
            }
            for d in st.done.iter_mut().skip(r.cut) {
                *d = false;
            }
            st.partial = r.partial;
        }
        if let Some((k, _)) = st.partial
            && job.lines[k].before.incremental
        {
            return Err(SendError::ResumeUncertain {
                from: line_ref(job, k),
                to: line_ref(job, k),
                reason: format!(
                    "the job stopped part-way through line {}, a relative (G91) move, which cannot be completed from the middle",
                    job.lines[k].source_line
                ),
            });
        }
        // Where the first line to send starts (or where the stopped line was left): a machine
        // found standing there needs no travel, so nothing moves twice.
        if let Some(i0) = st.done.iter().position(|d| !d) {
            let at = match st.partial {
                Some((k, p)) if k == i0 => p,
                _ => job.start_of(i0),
            };
            let there = here.is_some_and(|h| dist(h, at) <= tol);
            if i0 > 0 || st.partial.is_some() || there {
                resume_at = Some((i0, at, !there));
            }
        }
    }
    let limits = MachineLimits::from_settings(&sess.settings);
    if opts.check_travel {
        check_travel(job, &limits, &sess.settings, sess.wco)?;
    }
    let timed;
    let job_t: &Job = if limits != MachineLimits::DEFAULT {
        let mut j = job.clone();
        j.retime(&limits);
        timed = j;
        &timed
    } else {
        job
    };

    // --- Check pass.
    if opts.check {
        progress.phase = Phase::Checking;
        observer(&progress);
        check_pass(&mut sess, job, opts)?;
    }

    // --- Plan what to send.
    let n = job.len();
    let mut tracker = Tracker {
        done: vec![false; n],
        acked: vec![false; n],
        unconfirmed: VecDeque::new(),
        motion_after: VecDeque::new(),
        capacity: sess.blocks + SEGMENT_BUFFER,
        length_done: 0.0,
        time_done: 0.0,
        prior_done: prior
            .as_ref()
            .map(|p| p.done.clone())
            .unwrap_or_else(|| vec![false; n]),
        pos_tol: position_tolerance(&sess.settings),
        last_sent: None,
        acked_count: 0,
        done_count: 0,
        time_total: job_t.total_time,
        time_done_run: 0.0,
    };
    let mut previously_done = 0;
    if let Some(st) = &prior {
        for i in 0..n {
            if st.done[i] {
                tracker.done[i] = true;
                tracker.acked[i] = true;
                tracker.length_done += job.lines[i].length;
                tracker.time_done += job_t.lines[i].time;
                tracker.acked_count += 1;
                tracker.done_count += 1;
                previously_done += 1;
            }
        }
    }
    let mut preamble_texts: Vec<String> = Vec::new();
    let mut lines_sent = 0;
    let mut i = 0;
    while i < n {
        if tracker.done[i] {
            i += 1;
            continue;
        }
        // A run that does not start at the top of the file needs the machine put back into
        // the state the job had there.
        let first = if i > 0 || resume_at.is_some() {
            let pre = match resume_at.take() {
                Some((k, at, travel)) if k == i => job.resume_preamble_from(i, at, travel),
                _ => job.resume_preamble(i),
            };
            for p in pre {
                sess.s.push(
                    Tag::Preamble(preamble_texts.len() as u32),
                    p.clone(),
                    SendMode::CharCount,
                );
                preamble_texts.push(p);
            }
            job.resume_line(i)
        } else {
            job.lines[i].text.clone()
        };
        let mut text = first;
        while i < n && !tracker.done[i] {
            let mode = match job.lines[i].kind {
                LineKind::Gcode => SendMode::CharCount,
                LineKind::System | LineKind::EepromWrite => SendMode::SendResponse,
            };
            sess.s.push(Tag::Job(i), std::mem::take(&mut text), mode);
            lines_sent += 1;
            i += 1;
            if i < n {
                text = job.lines[i].text.clone();
            }
        }
    }

    // --- Stream.
    progress.phase = Phase::Streaming;
    let stream_start = Instant::now();
    let bytes_before = sess.s.bytes_written();
    let mut last_poll = Instant::now() - opts.status_interval;
    let mut last_progress = Instant::now();
    let mut last_response = Instant::now();
    let mut idle_since_response = 0u32;
    let mut holding = false;
    let mut failure: Option<SendError> = None;
    let mut stream_end = None;
    let mut end_status_seq = 0;
    let mut hold_since: Option<Instant> = None;
    let mut last_fsync = Instant::now();
    loop {
        // Control requests.
        let c = cancel.take();
        if c.abort {
            let err = abort(&mut sess, job, &mut tracker, &mut journal)?;
            return Err(err);
        }
        if c.hold && !holding {
            sess.s.realtime(b'!');
            holding = true;
        }
        if c.resume && holding {
            sess.s.realtime(b'~');
            holding = false;
        }
        if last_poll.elapsed() >= opts.status_interval {
            sess.s.realtime(b'?');
            last_poll = Instant::now();
        }
        let evs = match sess.pump(READ_SLICE) {
            Ok(e) => e,
            Err(e) => {
                let why = format!("transport failure: {e}");
                return stop_noted(&mut journal, &why, transport(e, tracker.last_done(job)));
            }
        };
        if let Some(Tag::Job(i)) = sess.s.last_sent() {
            tracker.last_sent = Some(tracker.last_sent.map_or(i, |l| l.max(i)));
        }
        let mut acked_any = false;
        let mut batch = evs.into_iter();
        while let Some(e) = batch.next() {
            match e {
                Event::Ack(Tag::Job(i)) => {
                    if let Some(j) = journal.as_mut() {
                        j.ack(i);
                    }
                    tracker.ack(job_t, i, &mut journal);
                    progress.last_acked = Some(line_ref(job, i));
                    acked_any = true;
                    last_response = Instant::now();
                    idle_since_response = 0;
                }
                Event::Ack(_) => {
                    last_response = Instant::now();
                    idle_since_response = 0;
                }
                Event::Rejected(Tag::Job(i), code) => {
                    if let Some(j) = journal.as_mut() {
                        j.reject(i, code);
                        j.note(&format!(
                            "line {} rejected: error:{code}",
                            job.lines[i].source_line
                        ));
                    }
                    last_response = Instant::now();
                    idle_since_response = 0;
                    if failure.is_none() {
                        sess.s.set_feeding(false);
                        sess.s.clear_queue();
                        failure = Some(SendError::LineRejected {
                            error: LineError {
                                line: line_ref(job, i),
                                code,
                            },
                            last_done: None,
                        });
                    }
                }
                Event::Rejected(Tag::Preamble(k), code) => {
                    sess.s.set_feeding(false);
                    sess.s.clear_queue();
                    if failure.is_none() {
                        failure = Some(SendError::PreambleRejected {
                            text: preamble_texts[k as usize].clone(),
                            code,
                        });
                    }
                }
                Event::Rejected(_, _) => {}
                Event::Alarm(code) => {
                    let rest: Vec<Event> = batch.collect();
                    let err = on_alarm(
                        &mut sess,
                        job_t,
                        code,
                        rest,
                        opts,
                        &mut tracker,
                        &mut journal,
                    )?;
                    return Err(err);
                }
                Event::Reset { lost, .. } => {
                    let rest: Vec<Event> = batch.collect();
                    let err = on_reset(&mut sess, job_t, lost, rest, &mut tracker, &mut journal)?;
                    return Err(err);
                }
                Event::Status(st) => {
                    if st.state == MachineState::Idle {
                        if sess.s.in_flight() == 0 {
                            // Idle with GRBL's RX buffer empty: it already ran its auto cycle
                            // start, so the planner is empty and every acknowledged line ran.
                            // (Idle while lines wait in the RX buffer may still hold queued,
                            // unstarted blocks: GRBL starts the cycle only when the planner is
                            // full or the RX buffer is empty.)
                            let k = tracker.unconfirmed.len();
                            tracker.confirm(job_t, k, &mut journal);
                        } else {
                            idle_since_response += 1;
                        }
                    }
                    progress.state = Some(st.state);
                    progress.position = sess.work_position();
                }
                _ => {}
            }
        }
        // Refill GRBL's RX buffer at once: the answers just read made room, and the link idles
        // until the next line is written.
        if let Err(e) = sess.write() {
            let why = format!("transport failure: {e}");
            return stop_noted(&mut journal, &why, transport(e, tracker.last_done(job)));
        }
        if acked_any && let Some(j) = journal.as_mut() {
            if last_fsync.elapsed() >= JOURNAL_FSYNC_INTERVAL {
                j.sync_in_background()?;
                last_fsync = Instant::now();
            } else {
                j.flush()?;
            }
        }
        // Lost bytes: the controller sits idle while lines are unanswered.
        if sess.s.in_flight() > 0
            && idle_since_response >= 2
            && last_response.elapsed() >= opts.idle_ack_timeout
        {
            let n_in = sess.s.in_flight();
            return stop_noted(
                &mut journal,
                &format!("{n_in} line(s) unanswered while idle: link lost bytes"),
                SendError::LostAck {
                    in_flight: n_in,
                    last_done: tracker.last_done(job),
                },
            );
        }
        let state_now = sess.status.as_ref().map(|s| s.state);
        let foreign_hold = matches!(
            state_now,
            Some(MachineState::Hold { .. }) | Some(MachineState::Door(_))
        ) && !holding;
        if foreign_hold {
            let since = *hold_since.get_or_insert_with(Instant::now);
            if opts.hold_timeout.is_some_and(|t| since.elapsed() >= t) {
                return Err(stop_unexpected(
                    &mut sess,
                    job_t,
                    &mut tracker,
                    &mut journal,
                )?);
            }
        } else {
            hold_since = None;
        }
        if state_now == Some(MachineState::Check) {
            // Lines acknowledged in check mode do not move: never count them as done.
            return Err(stop_unexpected(
                &mut sess,
                job_t,
                &mut tracker,
                &mut journal,
            )?);
        }
        let waiting_on_user = matches!(
            sess.status.as_ref().map(|s| s.state),
            Some(MachineState::Hold { .. }) | Some(MachineState::Door(_))
        );
        if sess.last_rx.elapsed() >= opts.silence_timeout && !waiting_on_user {
            return stop_noted(
                &mut journal,
                "controller silent",
                SendError::DeviceSilent {
                    waited: sess.last_rx.elapsed(),
                    last_done: tracker.last_done(job),
                },
            );
        }
        // Stream complete or stopped on an error: wait for the planner to drain.
        if sess.s.queued() == 0 && sess.s.in_flight() == 0 {
            if stream_end.is_none() {
                stream_end = Some(stream_start.elapsed());
                end_status_seq = sess.status_seq;
                progress.phase = Phase::Finishing;
                sess.s.realtime(b'?');
                last_poll = Instant::now();
            }
            // An Idle report requested after the last answer: the planner has drained.
            let idle = sess
                .status
                .as_ref()
                .is_some_and(|s| s.state == MachineState::Idle);
            if idle && sess.status_seq > end_status_seq {
                let k = tracker.unconfirmed.len();
                tracker.confirm(job_t, k, &mut journal);
                break;
            }
        }
        progress.holding = holding;
        if last_progress.elapsed() >= opts.progress_interval {
            // Counters are kept incrementally: this loop runs once per answer batch and must
            // stay O(1) in the job size to keep the link busy.
            progress.lines_acked = tracker.acked_count;
            progress.lines_done = tracker.done_count;
            progress.length_done = tracker.length_done;
            progress.elapsed = stream_start.elapsed();
            progress.bytes_written = sess.s.bytes_written() - bytes_before;
            progress.eta = Some(eta(&tracker, stream_start.elapsed()));
            observer(&progress);
            last_progress = Instant::now();
        }
    }
    if let Some(mut err) = failure {
        if let SendError::LineRejected { last_done, .. } = &mut err {
            *last_done = tracker.last_done(job);
        }
        if let Some(j) = journal.as_mut() {
            j.sync()?;
        }
        return Err(err);
    }
    let final_position = sess.work_position();
    // Only a run that moved the machine can be checked against the job's end point.
    if opts.verify_end_position
        && lines_sent > 0
        && !job_uses_unknown_moves(job)
        && let Some(p) = final_position
    {
        let e = add(job.end_state.position, [0.0; 3]);
        if dist(p, e) > POSITION_TOL_MM * 10.0 {
            return stop_noted(
                &mut journal,
                &format!("end position {p:?} differs from the job's end {e:?}"),
                SendError::PositionMismatch {
                    expected: e,
                    actual: p,
                },
            );
        }
    }
    if let Some(j) = journal.as_mut() {
        j.finish();
        j.sync()?;
    }
    progress.phase = Phase::Done;
    progress.lines_done = n;
    progress.lines_acked = n;
    progress.length_done = job.total_length;
    progress.eta = Some(Duration::ZERO);
    observer(&progress);
    Ok(SendReport {
        version: sess.version.clone(),
        rx_size: sess.s.rx_size(),
        planner_blocks: sess.blocks,
        settings: sess.settings.clone(),
        lines_sent,
        preamble_lines: preamble_texts.len(),
        previously_done,
        stream_bytes: sess.s.bytes_written() - bytes_before,
        stream_time: stream_end.unwrap_or_default(),
        total_time: t0.elapsed(),
        max_in_flight_bytes: sess.s.max_in_flight_bytes(),
        final_position,
        estimated_time: job_t.total_time,
        checked: opts.check,
    })
}

/// Waits while the controller reports motion (`Run`, `Jog`, `Home`, a hold still braking): the
/// planner it kept running while no host was connected must finish before anything resets it.
fn wait_until_still<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    opts: &SendOptions,
) -> Result<(), TransportError> {
    let until = Instant::now() + DRAIN_ON_CONNECT_LIMIT;
    while Instant::now() < until {
        match sess.query_status(Duration::from_millis(500))? {
            Some(st)
                if matches!(
                    st.state,
                    MachineState::Run
                        | MachineState::Jog
                        | MachineState::Home
                        | MachineState::Hold { complete: false }
                ) =>
            {
                let next = Instant::now() + opts.status_interval;
                while Instant::now() < next {
                    sess.pump(READ_SLICE)?;
                }
            }
            _ => return Ok(()),
        }
    }
    Ok(())
}

/// How a resume settles the lines an interrupted run left in doubt.
#[derive(Debug, Clone, PartialEq)]
struct Resolution {
    /// First line settled.
    from: usize,
    /// Lines `from..cut` executed; none from `cut` on.
    cut: usize,
    /// Line `cut` was stopped part-way, at this work position.
    partial: Option<(usize, [f64; 3])>,
}

/// Where on line `i`'s path the work position `p` lies: `Some(true)` at its end, `Some(false)`
/// strictly inside it (not at its start), `None` off it. Arcs are tested against their chords,
/// which is where GRBL moves.
fn locate_on_line(job: &Job, i: usize, p: [f64; 3], tol: f64) -> Option<bool> {
    let l = &job.lines[i];
    if !l.moves || l.length <= 0.0 {
        return None;
    }
    let (a, b) = (job.start_of(i), job.end_of(i));
    if dist(p, b) <= tol {
        return Some(true);
    }
    if dist(p, a) <= tol {
        return None;
    }
    let on = if l.arc.len() >= 2 {
        l.arc.windows(2).any(|w| seg_dist(p, w[0], w[1]) <= tol)
    } else {
        seg_dist(p, a, b) <= tol
    };
    on.then_some(false)
}

/// The places in the job, among lines `range` (skipping those `skip` says), where the machine
/// standing at work position `p` may be: `(cut, partial)` = every line before `cut` has run, and
/// `partial` = line `cut` was stopped part-way at `p`. Candidates that touch (consecutive lines
/// meeting at a vertex `p` lies within tolerance of, or endpoints separated only by lines that
/// do not move) are one place in the job: for a stop inside a line the later line wins (finishing
/// it from `p` leaves out at most the tolerance of the earlier one, and repeats nothing); for an
/// endpoint the earlier one (the non-moving lines are sent again, which only re-applies modal
/// state). More than one group means the path passes `p` more than once.
fn places_on_path(
    job: &Job,
    p: [f64; 3],
    range: std::ops::RangeInclusive<usize>,
    tol: f64,
    skip: impl Fn(usize) -> bool,
) -> Vec<(usize, Option<[f64; 3]>)> {
    let first = *range.start();
    let mut cuts: Vec<(usize, Option<[f64; 3]>)> = Vec::new();
    let mut matched: Vec<usize> = Vec::new();
    if dist(p, job.start_of(first)) <= tol {
        cuts.push((first, None));
    }
    for i in range {
        if skip(i) {
            continue;
        }
        match locate_on_line(job, i, p, tol) {
            Some(true) => cuts.push((i + 1, None)),
            Some(false) => cuts.push((i, Some(p))),
            None => continue,
        }
        matched.push(i);
    }
    let mut groups: Vec<Vec<(usize, Option<[f64; 3]>)>> = Vec::new();
    for c in cuts {
        let touches = groups.last().and_then(|g| g.last()).is_some_and(|last| {
            (last.0..c.0).all(|l| {
                let line = &job.lines[l];
                !line.moves || line.length <= 0.0 || matched.contains(&l)
            })
        });
        match groups.last_mut() {
            Some(g) if touches => g.push(c),
            _ => groups.push(vec![c]),
        }
    }
    groups
        .into_iter()
        .filter_map(|g| {
            if g.iter().any(|c| c.1.is_some()) {
                g.last().copied()
            } else {
                g.first().copied()
            }
        })
        .collect()
}

/// Settles a resume (see [`Resolution`]): the operator's `--resume-from`; or the machine's
/// position `here` (only when it is trustworthy) matched against the job's own geometry over the
/// window of lines that may have run after the journal lost track (acknowledged but not
/// confirmed, plus what fitted in the `rx`-byte RX buffer behind them). `None`: the journal
/// already says exactly what ran.
fn resolve_resume(
    job: &Job,
    st: &JournalState,
    resume_from: Option<usize>,
    here: Option<[f64; 3]>,
    rx: usize,
    tol: f64,
    restarted: bool,
) -> Result<Option<Resolution>, SendError> {
    let n = job.len();
    if let Some(k) = resume_from {
        if k >= n {
            return Err(SendError::ResumeFromOutOfRange { index: k, lines: n });
        }
        return Ok(Some(Resolution {
            from: 0,
            cut: k,
            partial: None,
        }));
    }
    let doubt = |a: usize, b: usize, reason: String| SendError::ResumeUncertain {
        from: line_ref(job, a),
        to: line_ref(job, b.min(n - 1)),
        reason,
    };
    if let Some((a, b)) = st.uncertain {
        return Err(doubt(
            a,
            b,
            "the controller was reset while moving (ALARM:3), so the position it reported is not where the tool is".into(),
        ));
    }
    let (Some(&first), Some(&last_acked)) = (st.unconfirmed.first(), st.unconfirmed.last()) else {
        return Ok(None);
    };
    // Lines sent after the last acknowledged one: at most what the RX buffer held.
    let mut upper = last_acked;
    let mut bytes = 0;
    while upper + 1 < n {
        bytes += job.lines[upper + 1].text.len() + 1;
        if bytes > rx {
            break;
        }
        upper += 1;
    }
    let Some(p) = here else {
        let why = if restarted {
            "the controller restarted when the port was opened (or lost power), so its planner and position are gone"
        } else {
            "the controller is in alarm or gave no position, so its position is not trustworthy"
        };
        return Err(doubt(
            first,
            upper,
            format!("the link dropped with lines queued, and {why}"),
        ));
    };
    if let Some(i) =
        (first..=upper).find(|&i| job.lines[i].moves && job.lines[i].before.incremental)
    {
        return Err(doubt(
            first,
            upper,
            format!(
                "line {} is a relative (G91) move, so a position cannot tell which of these lines ran",
                job.lines[i].source_line
            ),
        ));
    }
    let groups = places_on_path(job, p, first..=upper, tol, |_| false);
    let fmt = |p: [f64; 3]| format!("X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2]);
    match groups.as_slice() {
        [(cut, partial)] => Ok(Some(Resolution {
            from: first,
            cut: *cut,
            partial: partial.map(|q| (*cut, q)),
        })),
        [] => Err(doubt(
            first,
            upper,
            format!(
                "the machine stands at {} (work), which is on none of these lines",
                fmt(p)
            ),
        )),
        _ => Err(doubt(
            first,
            upper,
            format!(
                "the path passes the machine's position {} (work) {} times among these lines",
                fmt(p),
                groups.len()
            ),
        )),
    }
}

/// Half a step on the coarsest axis plus the 3-decimal rounding of status reports: how far a
/// reported position may sit from a programmed point that was reached.
fn position_tolerance(settings: &BTreeMap<u16, f64>) -> f64 {
    let min_steps = (100..=102)
        .filter_map(|n| settings.get(&n).copied())
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold(f64::INFINITY, f64::min);
    let half_step = if min_steps.is_finite() {
        0.5 / min_steps
    } else {
        0.5 / 250.0
    };
    half_step + 0.0011
}

/// G28/G30/G53 and `$` motion (homing, jog) go to places this model does not track.
fn job_uses_unknown_moves(job: &Job) -> bool {
    job.lines.iter().any(|l| {
        l.kind != LineKind::Gcode
            || l.text.contains("G28")
            || l.text.contains("G30")
            || l.text.contains("G53")
    })
}

/// ETA: the remaining estimated motion time, scaled by how the machine kept up with the
/// estimate so far (clamped so one stall cannot make the figure absurd).
fn eta(tr: &Tracker, elapsed: Duration) -> Duration {
    let remaining = (tr.time_total - tr.time_done).max(0.0);
    let ratio = if tr.time_done_run > 2.0 {
        (elapsed.as_secs_f64() / tr.time_done_run).clamp(0.5, 2.0)
    } else {
        1.0
    };
    Duration::from_secs_f64(remaining * ratio)
}

/// Stops because the machine is in a state this sender did not ask for.
fn stop_unexpected<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    // Where the machine stands tells which acknowledged lines it got through.
    if let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent) {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    let state = sess
        .status
        .as_ref()
        .map(|s| s.state.name())
        .unwrap_or_default();
    if let Some(j) = journal.as_mut() {
        j.note(&format!("stopped: unexpected state {state}"));
        j.sync()?;
    }
    Ok(SendError::UnexpectedState {
        state,
        last_done: tracker.last_done(job),
    })
}

/// Stops on `ALARM:N`: collects the answers to lines still in GRBL's buffer, resets a critical
/// alarm (GRBL answers nothing else until then), and locates the machine on the path.
fn on_alarm<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    code: u8,
    rest: Vec<Event>,
    opts: &SendOptions,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    if let Some(j) = journal.as_mut() {
        j.note(&format!(
            "ALARM:{code} {}",
            alarm_meaning(code).unwrap_or("")
        ));
    }
    // The `ok` of the line that raised it and `error:9`s for lines behind it may follow (some
    // may already be in the batch that carried the alarm).
    let settle = Instant::now() + Duration::from_millis(300);
    let mut first = Some(rest);
    while Instant::now() < settle {
        let evs = match first.take() {
            Some(r) => r,
            None => match sess.pump(READ_SLICE) {
                Ok(e) => e,
                Err(e) => return Err(transport(e, tracker.last_done(job))),
            },
        };
        for e in evs {
            match e {
                Event::Ack(Tag::Job(i)) => {
                    if let Some(j) = journal.as_mut() {
                        j.ack(i);
                    }
                    tracker.ack(job, i, journal);
                }
                Event::Rejected(Tag::Job(i), c) => {
                    if let Some(j) = journal.as_mut() {
                        j.reject(i, c);
                    }
                }
                _ => {}
            }
        }
    }
    if let Some(Tag::Job(i)) = sess.s.last_sent() {
        tracker.last_sent = Some(tracker.last_sent.map_or(i, |l| l.max(i)));
    }
    if alarm_is_critical(code) {
        // GRBL blocks everything until reset; position is reported after it.
        sess.s.forget_in_flight();
        sess.s.realtime(0x18);
        let _ = sess.wait_banner(opts.banner_timeout);
    }
    if code == ABORT_CYCLE_ALARM {
        // A reset in motion: steps were lost, so the reported position says nothing about which
        // queued lines ran. Name the range in doubt instead of guessing.
        if let (Some(&a), Some(b)) = (tracker.unconfirmed.front(), tracker.last_sent)
            && let Some(j) = journal.as_mut()
        {
            j.uncertain(a, b.max(a));
        }
    } else if let Ok(Some(_)) = sess.query_status(Duration::from_millis(500))
        && let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent)
    {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    if let Some(j) = journal.as_mut() {
        j.sync()?;
    }
    Ok(SendError::Alarm {
        code,
        last_done: tracker.last_done(job),
    })
}

/// Whether line `i` does the same thing right after a soft reset (GRBL's parser back at G0 G54
/// G17 G21 G90 G94 M5 M9, no G92) as it would in the job: then a line that GRBL took in after
/// resetting really ran as the job meant it.
fn same_after_reset(job: &Job, i: usize) -> bool {
    let st = &job.lines[i].before;
    let d = crate::job::ModalState::default();
    let explicit_motion = job.lines[i].text.contains("G0")
        || job.lines[i].text.contains("G1")
        || st.motion == d.motion;
    st.units == d.units
        && st.incremental == d.incremental
        && st.plane == d.plane
        && st.wcs == d.wcs
        && st.inverse_time == d.inverse_time
        && st.spindle == d.spindle
        && st.mist == d.mist
        && st.flood == d.flood
        && st.g92 == d.g92
        && explicit_motion
}

/// Stops on an unexpected banner. GRBL cleared its RX buffer at the reset, but bytes still on
/// the wire landed in the fresh buffer and ran: their answers arrive after the banner and belong
/// to the newest lines that were in flight.
fn on_reset<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    lost: Vec<Tag>,
    rest: Vec<Event>,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    if let Some(Tag::Job(i)) = lost.iter().rev().find(|t| matches!(t, Tag::Job(_))) {
        tracker.last_sent = Some(tracker.last_sent.map_or(*i, |l| l.max(*i)));
    }
    // A `$G` sentinel written after the banner is parsed after every byte already on the
    // wire, so every `ok`/`error` before its `[GC:..]` answers a line that ran after the reset.
    // It bypasses the streamer, whose FIFO no longer holds those lines.
    let mut late: Vec<crate::response::Response> = rest
        .into_iter()
        .filter_map(|e| match e {
            Event::Unmatched(r) => Some(r),
            _ => None,
        })
        .collect();
    if let Err(e) = sess.t.write_all(b"$G\n") {
        return Err(transport(e, tracker.last_done(job)));
    }
    let until = Instant::now() + Duration::from_secs(2);
    let mut sentinel_ok = false;
    'wait: while Instant::now() < until {
        let evs = match sess.pump(READ_SLICE) {
            Ok(e) => e,
            Err(e) => return Err(transport(e, tracker.last_done(job))),
        };
        for e in evs {
            match e {
                Event::Unmatched(r) if !sentinel_ok => late.push(r),
                Event::Feedback(f) if f.starts_with("GC:") => sentinel_ok = true,
                Event::Unmatched(_) if sentinel_ok => break 'wait,
                _ => {}
            }
        }
    }
    let m = late.len().min(lost.len());
    let mut ran_after_reset = 0;
    for (k, (tag, r)) in lost[lost.len() - m..]
        .iter()
        .zip(&late[late.len() - m..])
        .enumerate()
    {
        if let (Tag::Job(i), crate::response::Response::Ok) = (tag, r) {
            ran_after_reset += 1;
            // The first of them may be the tail of a line the reset cut in half (GRBL then ran
            // only a fragment): never count it, so it is re-sent whole.
            if k > 0 && same_after_reset(job, *i) {
                if let Some(j) = journal.as_mut() {
                    j.ack(*i);
                }
                tracker.ack(job, *i, journal);
            }
        }
    }
    if let Some(j) = journal.as_mut() {
        j.note(&format!(
            "unexpected reset; {} line(s) in flight, {ran_after_reset} of them ran after the reset",
            lost.len()
        ));
    }
    // Wait for the motion those lines queued, then locate the machine.
    let until = Instant::now() + Duration::from_secs(30);
    while Instant::now() < until {
        match sess.query_status(Duration::from_millis(500)) {
            Ok(Some(st)) if st.state != MachineState::Run => break,
            Ok(_) => {}
            Err(e) => return Err(transport(e, tracker.last_done(job))),
        }
    }
    if let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent) {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    if let Some(j) = journal.as_mut() {
        j.sync()?;
    }
    Ok(SendError::UnexpectedReset {
        lost: lost.len() - ran_after_reset,
        last_done: tracker.last_done(job),
    })
}

fn check_travel(
    job: &Job,
    limits: &MachineLimits,
    settings: &BTreeMap<u16, f64>,
    wco: [f64; 3],
) -> Result<(), SendError> {
    let Some((lo, hi)) = job.extent else {
        return Ok(());
    };
    let soft_limits = settings.get(&20).copied().unwrap_or(0.0) != 0.0;
    for a in 0..3 {
        let travel = limits.max_travel[a];
        let size = hi[a] - lo[a];
        let (mlo, mhi) = (lo[a] + wco[a], hi[a] + wco[a]);
        // Absolute check only where GRBL itself enforces it (homing + soft limits: machine
        // space is [-travel, 0]); otherwise the job must at least fit the travel.
        let out = size > travel + POSITION_TOL_MM
            || (limits.homing
                && soft_limits
                && (mlo < -travel - POSITION_TOL_MM || mhi > POSITION_TOL_MM));
        if out {
            return Err(SendError::OutOfTravel {
                axis: ['X', 'Y', 'Z'][a],
                lo: lo[a],
                hi: hi[a],
                size,
                mlo,
                mhi,
                travel,
            });
        }
    }
    Ok(())
}

fn check_pass<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    opts: &SendOptions,
) -> Result<(), SendError> {
    sess.command_ok("$C", opts.command_timeout)?;
    for (i, l) in job.lines.iter().enumerate() {
        if l.kind == LineKind::Gcode {
            sess.s
                .push(Tag::Job(i), l.text.clone(), SendMode::CharCount);
        }
    }
    let mut errors = Vec::new();
    let mut last = Instant::now();
    while sess.s.queued() > 0 || sess.s.in_flight() > 0 {
        let evs = sess.pump(READ_SLICE).map_err(|e| transport(e, None))?;
        if !evs.is_empty() {
            last = Instant::now();
        }
        for e in evs {
            match e {
                Event::Rejected(Tag::Job(i), code) => errors.push(LineError {
                    line: line_ref(job, i),
                    code,
                }),
                Event::Reset { .. } => {
                    return Err(SendError::UnexpectedReset {
                        lost: 0,
                        last_done: None,
                    });
                }
                Event::Alarm(code) => {
                    return Err(SendError::Alarm {
                        code,
                        last_done: None,
                    });
                }
                _ => {}
            }
        }
        if last.elapsed() > opts.silence_timeout {
            return Err(SendError::DeviceSilent {
                waited: last.elapsed(),
                last_done: None,
            });
        }
    }
    // Leaving check mode soft-resets GRBL: wait for the banner.
    let seen = sess.resets;
    sess.command_ok("$C", opts.command_timeout)?;
    if !sess
        .wait_banner_after(seen, opts.banner_timeout)
        .map_err(|e| transport(e, None))?
    {
        return Err(SendError::NoBanner(opts.banner_timeout));
    }
    if !errors.is_empty() {
        return Err(SendError::CheckFailed { errors });
    }
    Ok(())
}

fn abort<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    // Feed hold first so the reset does not lose position (reset in motion = ALARM:3).
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    sess.s.realtime(b'!');
    let until = Instant::now() + Duration::from_secs(10);
    while Instant::now() < until {
        match sess.query_status(Duration::from_millis(500)) {
            Ok(Some(st))
                if matches!(
                    st.state,
                    MachineState::Hold { complete: true }
                        | MachineState::Idle
                        | MachineState::Alarm
                ) =>
            {
                break;
            }
            Ok(_) => {}
            Err(e) => return Err(transport(e, tracker.last_done(job))),
        }
    }
    if let Some(Tag::Job(i)) = sess.s.last_sent() {
        tracker.last_sent = Some(tracker.last_sent.map_or(i, |l| l.max(i)));
    }
    if let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent) {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    sess.s.forget_in_flight();
    sess.s.realtime(0x18);
    let _ = sess.wait_banner(Duration::from_secs(3));
    // After the reset GRBL's spindle/laser is off (M5); say so explicitly if it accepts lines.
    sess.s.set_feeding(true);
    sess.s
        .push(Tag::Setup(u32::MAX), "M5", SendMode::SendResponse);
    let until = Instant::now() + Duration::from_millis(500);
    while Instant::now() < until && sess.s.in_flight() + sess.s.queued() > 0 {
        if sess.pump(READ_SLICE).is_err() {
            break;
        }
    }
    if let Some(j) = journal.as_mut() {
        j.note("aborted by the user (feed hold, soft reset, M5)");
        j.sync()?;
    }
    Ok(SendError::Aborted {
        last_done: tracker.last_done(job),
    })
}

#[cfg(test)]
#[path = "driver_tests.rs"]
mod tests;
