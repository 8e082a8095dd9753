//! [`StreamArgs`]: where and how to stream a job, as flags of `flatcut send` and `flatcut run`.

use std::path::PathBuf;

/// GRBL 1.1's default baud rate (`config.h`).
pub const DEFAULT_BAUD: u32 = 115_200;
/// Default time scale of the embedded simulator: fast enough that a demo job finishes in
/// seconds, slow enough that the progress bar, feed hold and status polling are exercised.
pub const DEFAULT_SIM_SPEED: f64 = 50.0;

/// Where and how to stream a job; flattened into `flatcut send` and `flatcut run`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct StreamArgs {
    /// Serial port of the GRBL controller (see `flatcut ports`); without it the job is streamed
    /// to the embedded simulator.
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Baud rate of the serial link.
    #[arg(long, default_value_t = DEFAULT_BAUD)]
    pub baud: u32,
    /// If the controller is alarm-locked, send `$X` to unlock it (only when the machine position
    /// is known to be right); without it a locked controller stops the send.
    #[arg(long)]
    pub unlock: bool,
    /// Run the whole job in GRBL check mode (`$C`) before cutting; nothing moves if a line is
    /// rejected.
    #[arg(long)]
    pub check: bool,
    /// Continue an interrupted job after the last completed line, with the modal state restored
    /// (needs the journal of the interrupted run).
    #[arg(long)]
    pub resume: bool,
    /// With --resume: run from this line of the file on, counting every line before it as done.
    /// Needed when the journal and the controller cannot tell which queued lines ran (a reset
    /// in motion, a controller that restarted after a hang-up); the refusal names the lines in
    /// doubt.
    #[arg(long, value_name = "LINE")]
    pub resume_from: Option<usize>,
    /// With --resume: the operator confirms that the work origin is where it was when the job
    /// stopped; needed on a controller that restarted or lost its position and does not home
    /// (one that homes, `$22=1`, is homed with `$H` instead).
    #[arg(long)]
    pub origin_confirmed: bool,
    /// With --resume: resume a job file edited after its journal was written (a bad line fixed);
    /// the change is shown first. Without it the resume asks on a terminal, and refuses without
    /// one. Lines already executed never run again unless --resume-from says so.
    #[arg(long)]
    pub accept_changed_job: bool,
    /// When the job pauses itself (M0): abort, resume, or wait for the operator. Default: ask
    /// on a terminal, abort without one.
    #[arg(long, value_enum, value_name = "POLICY")]
    pub on_pause: Option<OnPause>,
    /// Run in G54 without G92: do not put back the work frame (G55..G59, a G92 offset, a tool
    /// length offset) that the soft reset at connection clears, and do not stop when it cannot
    /// be read.
    #[arg(long)]
    pub discard_offsets: bool,
    /// Stop the job when a status report places the machine farther than this from the stretch
    /// of the job's path it can be on (a line damaged on the link runs elsewhere), mm.
    #[arg(long, value_name = "MM", default_value_t = flatcut_grbl::SendOptions::DEFAULT_POSITION_TOLERANCE, value_parser = crate::values::positive_mm)]
    pub position_tolerance: f64,
    /// Stream a laser job (its header says it needs `$32=1`) to a controller with `$32=0`.
    #[arg(skip)]
    pub force_laser: bool,
    /// Journal of acknowledged and executed lines (default: `<job>.journal`).
    #[arg(long, value_name = "PATH")]
    pub journal: Option<PathBuf>,
    /// Time scale of the embedded simulator (1 = real time).
    #[arg(long, value_name = "F", default_value_t = DEFAULT_SIM_SPEED)]
    pub sim_speed: f64,
    /// The embedded simulator completes motion instantly.
    #[arg(long)]
    pub sim_instant: bool,
    /// Laser mode in the embedded simulator (`$32=1`).
    #[arg(long)]
    pub sim_laser: bool,
    /// A `$N=VALUE` setting of the embedded simulator at start, e.g. `--sim-set 110=5000`
    /// (repeatable; `flatcut run` sets the machine profile's rates, accelerations and travel).
    #[arg(long = "sim-set", value_name = "N=VALUE")]
    pub sim_set: Vec<String>,
    /// Write every motion the embedded simulator executed as JSON lines.
    #[arg(long, value_name = "PATH")]
    pub sim_trace: Option<PathBuf>,
    /// Write an SVG of what the embedded simulator drew or cut.
    #[arg(long, value_name = "PATH")]
    pub sim_svg: Option<PathBuf>,
    /// No progress bar or status lines (for scripts and CI).
    #[arg(long, short)]
    pub quiet: bool,
    /// Embedded simulator answers `error:CODE` to its N-th received line (fault injection).
    #[arg(long, hide = true, value_name = "N[:CODE]")]
    pub sim_error_at: Option<String>,
    /// Embedded simulator raises `ALARM:CODE` when its N-th line executes (fault injection).
    #[arg(long, hide = true, value_name = "N[:CODE]")]
    pub sim_alarm_at: Option<String>,
    /// Embedded simulator loses a digit of its N-th line (fault injection).
    #[arg(long, hide = true, value_name = "N")]
    pub sim_drop_digit_at: Option<u32>,
    /// Embedded simulator hangs up when its N-th line arrives (fault injection).
    #[arg(long, hide = true, value_name = "N")]
    pub sim_hangup_at: Option<u32>,
    /// Embedded simulator resets by itself when its N-th line arrives (fault injection).
    #[arg(long, hide = true, value_name = "N")]
    pub sim_reset_at: Option<u32>,
}

impl Default for StreamArgs {
    fn default() -> StreamArgs {
        StreamArgs {
            port: None,
            baud: DEFAULT_BAUD,
            unlock: false,
            check: false,
            resume: false,
            resume_from: None,
            origin_confirmed: false,
            accept_changed_job: false,
            discard_offsets: false,
            position_tolerance: flatcut_grbl::SendOptions::DEFAULT_POSITION_TOLERANCE,
            on_pause: None,
            force_laser: false,
            journal: None,
            sim_speed: DEFAULT_SIM_SPEED,
            sim_instant: false,
            sim_laser: false,
            sim_set: Vec::new(),
            sim_trace: None,
            sim_svg: None,
            quiet: false,
            sim_error_at: None,
            sim_alarm_at: None,
            sim_hangup_at: None,
            sim_reset_at: None,
            sim_drop_digit_at: None,
        }
    }
}

impl StreamArgs {
    /// Sets [`StreamArgs::port`].
    pub fn with_port(mut self, port: impl Into<String>) -> Self {
        self.port = Some(port.into());
        self
    }
    /// Sets [`StreamArgs::journal`].
    pub fn with_journal(mut self, path: impl Into<PathBuf>) -> Self {
        self.journal = Some(path.into());
        self
    }
    /// Sets [`StreamArgs::check`].
    pub fn with_check(mut self, on: bool) -> Self {
        self.check = on;
        self
    }
    /// Sets [`StreamArgs::resume`].
    pub fn with_resume(mut self, on: bool) -> Self {
        self.resume = on;
        self
    }
    /// Sets [`StreamArgs::resume_from`] (a 1-based line number of the file; implies resume).
    pub fn with_resume_from(mut self, line: Option<usize>) -> Self {
        self.resume_from = line;
        if line.is_some() {
            self.resume = true;
        }
        self
    }
    /// Sets [`StreamArgs::origin_confirmed`].
    pub fn with_origin_confirmed(mut self, on: bool) -> Self {
        self.origin_confirmed = on;
        self
    }
    /// Sets [`StreamArgs::accept_changed_job`].
    pub fn with_accept_changed_job(mut self, on: bool) -> Self {
        self.accept_changed_job = on;
        self
    }
    /// Sets [`StreamArgs::unlock`].
    pub fn with_unlock(mut self, on: bool) -> Self {
        self.unlock = on;
        self
    }
    /// Sets [`StreamArgs::sim_instant`].
    pub fn with_sim_instant(mut self, on: bool) -> Self {
        self.sim_instant = on;
        self
    }
    /// Sets [`StreamArgs::sim_speed`].
    pub fn with_sim_speed(mut self, speed: f64) -> Self {
        self.sim_speed = speed;
        self
    }
    /// Sets [`StreamArgs::sim_svg`].
    pub fn with_sim_svg(mut self, path: impl Into<PathBuf>) -> Self {
        self.sim_svg = Some(path.into());
        self
    }
    /// Sets [`StreamArgs::sim_trace`].
    pub fn with_sim_trace(mut self, path: impl Into<PathBuf>) -> Self {
        self.sim_trace = Some(path.into());
        self
    }
    /// Sets [`StreamArgs::quiet`].
    pub fn with_quiet(mut self, on: bool) -> Self {
        self.quiet = on;
        self
    }

    /// The journal path for a job called `name`: `--journal`, else `<name>.journal`.
    pub fn journal_path(&self, name: &str) -> PathBuf {
        match &self.journal {
            Some(p) => p.clone(),
            None => PathBuf::from(format!("{name}.journal")),
        }
    }

    /// Whether the job goes to the embedded simulator.
    pub fn uses_sim(&self) -> bool {
        self.port.is_none()
    }
}

/// `--on-pause`: what to do when the job pauses itself (M0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OnPause {
    /// Abort: feed hold, soft reset, tool off.
    Abort,
    /// Resume at once (cycle start).
    Resume,
    /// Wait for the operator (Ctrl-C then resume or abort, or a prompt on a terminal).
    Wait,
}

impl StreamArgs {
    /// The pause policy: `--on-pause`, else wait and ask on a terminal, abort without one.
    pub fn pause_policy(&self) -> flatcut_grbl::PausePolicy {
        use flatcut_grbl::PausePolicy;
        use std::io::IsTerminal;
        match self.on_pause {
            Some(OnPause::Abort) => PausePolicy::Abort,
            Some(OnPause::Resume) => PausePolicy::Resume,
            Some(OnPause::Wait) => PausePolicy::Wait,
            None if std::io::stdin().is_terminal() && std::io::stderr().is_terminal() => {
                PausePolicy::Wait
            }
            None => PausePolicy::Abort,
        }
    }
}
