//! [`StreamArgs`]: where and how to stream a job, as flags of `flatcut send` and `flatcut run`,
//! and what they mean to the device library: the [`Target`] and the sender's options.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use flatcut_device::sim::{
    DEFAULT_INJECTED_ALARM, DEFAULT_INJECTED_ERROR, Faults, SimArgs, line_code,
};
use flatcut_device::{SimMachine, SimSetup, Target};

/// GRBL 1.1's default baud rate (`config.h`).
pub const DEFAULT_BAUD: u32 = 115_200;
/// Default `--boot-wait`: [`flatcut_device::grbl::SendOptions::DEFAULT_BANNER_TIMEOUT`].
pub const DEFAULT_BOOT_WAIT_MS: u64 =
    flatcut_device::grbl::SendOptions::DEFAULT_BANNER_TIMEOUT.as_millis() as u64;
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
    #[arg(long, value_name = "MM", default_value_t = flatcut_device::grbl::SendOptions::DEFAULT_POSITION_TOLERANCE, value_parser = crate::values::positive_mm)]
    pub position_tolerance: f64,
    /// Stream a laser job (its header says it needs `$32=1`) to a controller with `$32=0`
    /// (`flatcut send --force`; `flatcut run --force` sets it too).
    #[arg(skip)]
    pub force_laser: bool,
    /// How long a controller may take to start after the port opens (the reset of opening it,
    /// then its bootloader) before it must have said something, ms. A banner that comes later
    /// still counts as a restart.
    #[arg(long, value_name = "MS", default_value_t = DEFAULT_BOOT_WAIT_MS)]
    pub boot_wait: u64,
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
    /// The machine the embedded simulator is (from a machine profile: its rates,
    /// accelerations and work area); `None`: GRBL's defaults.
    #[arg(skip)]
    pub sim_machine: Option<SimMachine>,
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
            position_tolerance: flatcut_device::grbl::SendOptions::DEFAULT_POSITION_TOLERANCE,
            on_pause: None,
            force_laser: false,
            boot_wait: DEFAULT_BOOT_WAIT_MS,
            journal: None,
            sim_speed: DEFAULT_SIM_SPEED,
            sim_instant: false,
            sim_laser: false,
            sim_set: Vec::new(),
            sim_machine: None,
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
    /// Adds a `--sim-set N=VALUE`.
    pub fn with_sim_set(mut self, setting: impl Into<String>) -> Self {
        self.sim_set.push(setting.into());
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

    /// The device the flags name: `--port` at `--baud`, or the embedded simulator as the
    /// `--sim-*` flags set it up. Errors name the flag.
    pub fn target(&self) -> anyhow::Result<Target> {
        Ok(match &self.port {
            Some(p) => Target::Port {
                path: p.clone(),
                baud: self.baud,
            },
            None => Target::Simulator(self.sim_setup()?),
        })
    }

    /// The embedded simulator the `--sim-*` flags describe.
    pub fn sim_setup(&self) -> anyhow::Result<SimSetup> {
        let flags = SimArgs {
            set: self.sim_set.clone(),
            ..SimArgs::default()
        };
        let settings = flags
            .settings()
            .map_err(|e| anyhow::anyhow!("{}", e.to_string().replacen("--set", "--sim-set", 1)))?;
        let faults = Faults {
            error_at_line: self
                .sim_error_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ERROR, "--sim-error-at"))
                .transpose()?,
            alarm_at_line: self
                .sim_alarm_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ALARM, "--sim-alarm-at"))
                .transpose()?,
            hangup_at_line: self.sim_hangup_at,
            reset_at_line: self.sim_reset_at,
            drop_digit_at_line: self.sim_drop_digit_at,
            ..Faults::default()
        };
        Ok(SimSetup {
            machine: self.sim_machine,
            settings,
            laser: self.sim_laser,
            speed: self.sim_speed,
            instant: self.sim_instant,
            baud: self.baud,
            faults,
        })
    }

    /// How messages name the device: the port and its baud rate, or the simulator.
    pub fn describe(&self) -> String {
        match &self.port {
            Some(p) => format!("{p} at {} baud", self.baud),
            None if self.sim_machine.is_some() => {
                "the embedded simulator (set up from the machine profile)".into()
            }
            None if self.sim_set.is_empty() => "the embedded simulator (GRBL defaults)".into(),
            None => "the embedded simulator (GRBL defaults and --sim-set)".into(),
        }
    }

    /// The sender's options for a job whose journal is `journal`; `resume_from` is the
    /// `--resume-from` line as an index among the job's lines.
    pub fn send_options(
        &self,
        journal: &Path,
        resume_from: Option<usize>,
    ) -> flatcut_device::grbl::SendOptions {
        flatcut_device::grbl::SendOptions::default()
            .with_unlock(self.unlock)
            .with_check(self.check)
            .with_resume(self.resume || resume_from.is_some())
            .with_resume_from(resume_from)
            .with_journal(journal)
            .with_origin_confirmed(self.origin_confirmed)
            .with_accept_changed_job(self.accept_changed_job)
            .with_discard_offsets(self.discard_offsets)
            .with_position_tolerance(Some(self.position_tolerance))
            .with_on_pause(self.pause_policy())
            .with_force_laser(self.force_laser)
            .with_banner_timeout(std::time::Duration::from_millis(self.boot_wait))
    }

    /// The job line `--resume-from` names (a line number of the file), as an index among the
    /// lines the sender streams.
    pub fn resume_index(
        &self,
        job: &flatcut_device::grbl::Job,
        name: &str,
    ) -> anyhow::Result<Option<usize>> {
        self.resume_from
            .map(|line| {
                job.first_line_from(line).with_context(|| {
                        format!(
                            "--resume-from {line}: the job {name} has nothing to send from line {line} on"
                        )
                    })
            })
            .transpose()
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
    pub fn pause_policy(&self) -> flatcut_device::grbl::PausePolicy {
        use flatcut_device::grbl::PausePolicy;
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
