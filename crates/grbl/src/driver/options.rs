//! [`SendOptions`]: timeouts, policies and resume choices of one send.

use super::confirm::Operator;
use std::path::PathBuf;
use std::time::Duration;

/// Options for [`super::send_job`].
#[derive(Debug, Clone, PartialEq)]
pub struct SendOptions {
    /// The boot wait: how long a controller may take after the port opens to say something (a
    /// banner, or an answer to `?`), and how long to wait for the banner after a soft reset.
    /// A banner that comes later still counts as a restart.
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
    /// What to do when the job pauses itself (`M0`): GRBL holds the feed and waits for cycle
    /// start.
    pub on_pause: PausePolicy,
    /// The operator confirmed that the work origin is where it was when the journal was
    /// written; needed to resume on a controller that restarted or lost its position and does
    /// not home (`$22=0`).
    pub origin_confirmed: bool,
    /// Stream a job that declares it needs laser mode (`$32=1`) to a controller with `$32=0`.
    pub force_laser: bool,
    /// Do not put back the work frame (G55..G59, G92, G43.1) that the soft reset at connection
    /// clears: the job runs in G54 without G92.
    pub discard_offsets: bool,
    /// Stop when a status report places the machine farther than this (mm) from the stretch of
    /// the job's path it can be on (see `watch`); `None`: do not watch.
    pub position_tolerance: Option<f64>,
    /// Who answers what only the operator can (a terminal prompt); `None`: nobody, so the
    /// send refuses where it would have to ask.
    pub operator: Option<Operator>,
    /// With `resume`: resume a job file edited after its journal was written (the change is
    /// shown in the report); otherwise only the operator's "yes" allows it.
    pub accept_changed_job: bool,
    /// The caller saw the controller restart on this link before the job (a banner it did not
    /// ask for, as a [`super::Console`] notices): its position counts as lost, as when the
    /// banner comes during the job's own handshake.
    pub controller_restarted: bool,
}

/// What to do when the job pauses itself with `M0` (GRBL 1.1h ignores `M1`, and `M2`/`M30` end
/// the program without pausing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PausePolicy {
    /// Abort the run (feed hold, soft reset, tool off): nobody is there to decide.
    #[default]
    Abort,
    /// Resume at once (cycle start).
    Resume,
    /// Wait for the operator's resume or abort through the [`super::CancelToken`]; the progress
    /// reports the pause ([`super::Progress::paused_at`]).
    Wait,
}

impl SendOptions {
    /// Default boot wait: a real Uno's bootloader takes 1.4–2 s after DTR, slower boards and
    /// bootloaders up to about 3 s. A controller that was running answers the first `?` at
    /// once, so only a silent port waits this long.
    pub const DEFAULT_BANNER_TIMEOUT: Duration = Duration::from_millis(5000);
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

    /// Default position tolerance while running, mm: 12.5 steps at GRBL's default 250 steps/mm,
    /// far above a status report's rounding and a step's granularity, far below a damaged
    /// digit's error.
    pub const DEFAULT_POSITION_TOLERANCE: f64 = 0.05;

    /// Sets [`SendOptions::resume_from`] (and `resume`).
    pub fn with_resume_from(mut self, index: Option<usize>) -> Self {
        self.resume_from = index;
        if index.is_some() {
            self.resume = true;
        }
        self
    }

    /// Sets [`SendOptions::on_pause`].
    pub fn with_on_pause(mut self, p: PausePolicy) -> Self {
        self.on_pause = p;
        self
    }

    /// Sets [`SendOptions::origin_confirmed`].
    pub fn with_origin_confirmed(mut self, on: bool) -> Self {
        self.origin_confirmed = on;
        self
    }

    /// Sets [`SendOptions::force_laser`].
    pub fn with_force_laser(mut self, on: bool) -> Self {
        self.force_laser = on;
        self
    }

    /// Sets [`SendOptions::position_tolerance`].
    pub fn with_position_tolerance(mut self, mm: Option<f64>) -> Self {
        self.position_tolerance = mm;
        self
    }

    /// Sets [`SendOptions::operator`].
    pub fn with_operator(mut self, o: Option<Operator>) -> Self {
        self.operator = o;
        self
    }

    /// Sets [`SendOptions::accept_changed_job`].
    pub fn with_accept_changed_job(mut self, on: bool) -> Self {
        self.accept_changed_job = on;
        self
    }

    /// Sets [`SendOptions::discard_offsets`].
    pub fn with_discard_offsets(mut self, on: bool) -> Self {
        self.discard_offsets = on;
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
            on_pause: PausePolicy::Abort,
            origin_confirmed: false,
            force_laser: false,
            discard_offsets: false,
            position_tolerance: Some(SendOptions::DEFAULT_POSITION_TOLERANCE),
            operator: None,
            accept_changed_job: false,
            controller_restarted: false,
        }
    }
}
