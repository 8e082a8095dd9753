//! The device a job is streamed to: a serial port, or — with no `--port` — the embedded GRBL
//! simulator on a pseudo-terminal, so the whole pipeline runs on any machine.
//!
//! [`stream_file`] / [`stream_text`] parse the job, start the simulator if needed, open the port,
//! run [`flatcut_grbl::send_job`] with a live progress bar, turn Ctrl-C into a feed hold followed
//! by a "resume or abort" question, and stop the simulator (writing its trace and SVG). Every
//! protocol decision (handshake, alarm-lock policy, `$C`, character counting, journaling) lives in
//! `flatcut-grbl`; this module is only terminal, files and process plumbing.

use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use flatcut_firmware_sim::{Faults, PtySim, SimConfig, SimStats, TraceSegment};
use flatcut_grbl::driver::Phase;
use flatcut_grbl::{CancelToken, Control, Job, Progress, SendError, SendOptions, SendReport};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// GRBL 1.1's default baud rate (`config.h`).
pub const DEFAULT_BAUD: u32 = 115_200;
/// Default time scale of the embedded simulator: fast enough that a demo job finishes in
/// seconds, slow enough that the progress bar, feed hold and status polling are exercised.
pub const DEFAULT_SIM_SPEED: f64 = 50.0;
/// Interval of the plain progress lines printed when stderr is not a terminal (CI logs): often
/// enough to show life, rare enough not to flood a log.
pub const PLAIN_PROGRESS_INTERVAL: Duration = Duration::from_secs(3);
/// Resolution of the progress bar (it shows the fraction of the path length executed).
const BAR_STEPS: u64 = 1000;
/// Extra travel given to the embedded simulator beyond the job's extent, mm, so a job that
/// exactly fills the bed is not refused for rounding.
const SIM_TRAVEL_MARGIN_MM: f64 = 10.0;
/// Default GRBL error code injected by `--sim-error-at N` (20: unsupported command).
const DEFAULT_INJECTED_ERROR: u8 = 20;
/// Default GRBL alarm code injected by `--sim-alarm-at N` (1: hard limit).
const DEFAULT_INJECTED_ALARM: u8 = 1;

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
            journal: None,
            sim_speed: DEFAULT_SIM_SPEED,
            sim_instant: false,
            sim_laser: false,
            sim_trace: None,
            sim_svg: None,
            quiet: false,
            sim_error_at: None,
            sim_alarm_at: None,
            sim_hangup_at: None,
            sim_reset_at: None,
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

/// What a completed stream did.
#[derive(Debug, Clone)]
pub struct StreamOutcome {
    /// The sender's report.
    pub report: SendReport,
    /// Every motion the embedded simulator executed (`None` on a real port).
    pub sim_trace: Option<Vec<TraceSegment>>,
    /// The embedded simulator's counters (`None` on a real port).
    pub sim_stats: Option<SimStats>,
    /// Simulated time of the embedded simulator, s (`None` on a real port).
    pub sim_time: Option<f64>,
    /// The journal written.
    pub journal: PathBuf,
    /// Baud rate of the link, for utilisation figures.
    pub baud: u32,
}

impl StreamOutcome {
    /// Fraction of the link's byte rate (baud/10) used while streaming, 0..=1.
    pub fn link_utilisation(&self) -> f64 {
        let secs = self.report.stream_time.as_secs_f64();
        if secs <= 0.0 || self.baud == 0 {
            return 0.0;
        }
        (self.report.stream_bytes as f64 / (f64::from(self.baud) / 10.0 * secs)).clamp(0.0, 1.0)
    }
}

/// Streams the G-code file at `job_path`; see [`stream_text`].
pub fn stream_file(job_path: &Path, args: &StreamArgs) -> anyhow::Result<StreamOutcome> {
    stream_file_with_control(job_path, args, &Control::new())
}

/// [`stream_file`] steered through `control` as well; see [`stream_text_with_control`].
pub fn stream_file_with_control(
    job_path: &Path,
    args: &StreamArgs,
    control: &Control,
) -> anyhow::Result<StreamOutcome> {
    let text = std::fs::read_to_string(job_path)
        .with_context(|| format!("cannot read the job {}", job_path.display()))?;
    stream_text_with_control(&text, &job_path.display().to_string(), args, control)
}

/// Streams the G-code `job` (called `name` in messages and in the default journal path
/// `<name>.journal`) to `--port`, or to the embedded simulator when no port is given.
pub fn stream_text(job: &str, name: &str, args: &StreamArgs) -> anyhow::Result<StreamOutcome> {
    stream_text_with_control(job, name, args, &Control::new())
}

/// [`stream_text`] steered through `control` as well as by Ctrl-C: a caller (a GUI, a test, a
/// supervising script) can hold, resume or abort the job from another thread.
pub fn stream_text_with_control(
    job: &str,
    name: &str,
    args: &StreamArgs,
    control: &Control,
) -> anyhow::Result<StreamOutcome> {
    let job = Job::parse(job).with_context(|| format!("cannot prepare the job {name}"))?;
    if job.is_empty() {
        bail!("the job {name} has no line to send");
    }
    let journal = args.journal_path(name);
    // `--resume-from LINE` names a line of the file; the sender counts streamable lines.
    let resume_from = match args.resume_from {
        Some(line) => Some(
            job.lines
                .iter()
                .position(|l| l.source_line >= line)
                .with_context(|| {
                    format!("--resume-from {line}: the job {name} has nothing to send from line {line} on")
                })?,
        ),
        None => None,
    };
    let opts = SendOptions::default()
        .with_unlock(args.unlock)
        .with_check(args.check)
        .with_resume(args.resume || resume_from.is_some())
        .with_resume_from(resume_from)
        .with_journal(&journal);

    let sim = if args.uses_sim() {
        let cfg = sim_config(&job, args)?;
        let sim = PtySim::spawn(cfg).context("cannot start the embedded simulator")?;
        if !args.quiet {
            eprintln!(
                "streaming to the embedded simulator at {} ({}; pass --port PATH for a real controller)",
                sim.path().display(),
                if args.sim_instant {
                    "instant motion".to_string()
                } else {
                    format!("{}× real time", args.sim_speed)
                }
            );
        }
        Some(sim)
    } else {
        None
    };
    let port_path = match (&args.port, &sim) {
        (Some(p), _) => p.clone(),
        (None, Some(s)) => s.path().display().to_string(),
        (None, None) => bail!("no port and no simulator"),
    };

    let opened = flatcut_grbl::open_port(&port_path, args.baud).map(|mut t| {
        let r = run_send(&mut t, &job, &opts, args, control);
        drop(t);
        r
    });
    // The port is closed now; stopping the simulator writes its trace and SVG.
    let sim_report = sim.map(PtySim::stop);
    if let Some(r) = &sim_report {
        write_sim_files(&r.trace, args)?;
    }
    let sent = opened.with_context(|| format!("cannot open the serial port {port_path}"))?;
    let report = sent.map_err(|e| explain(e, name, args, &journal))?;
    Ok(StreamOutcome {
        report,
        sim_stats: sim_report.as_ref().map(|r| r.stats.clone()),
        sim_time: sim_report.as_ref().map(|r| r.sim_time),
        sim_trace: sim_report.map(|r| r.trace),
        journal,
        baud: args.baud,
    })
}

/// Parses `N[:CODE]` (a 1-based line number and an optional GRBL code).
pub(crate) fn line_code(arg: &str, default_code: u8, flag: &str) -> anyhow::Result<(u32, u8)> {
    let (n, c) = match arg.split_once(':') {
        Some((n, c)) => (n, Some(c)),
        None => (arg, None),
    };
    let n: u32 = n
        .trim()
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .with_context(|| format!("{flag} {arg}: the line number must be a positive integer"))?;
    let c: u8 = match c {
        Some(c) => c
            .trim()
            .parse()
            .with_context(|| format!("{flag} {arg}: the code must be 0..255"))?,
        None => default_code,
    };
    Ok((n, c))
}

/// The embedded simulator's configuration: the flags, plus a bed (`$130-$132`) at least as large
/// as the job so a big nest is not refused by the travel check of a machine that does not exist.
fn sim_config(job: &Job, args: &StreamArgs) -> anyhow::Result<SimConfig> {
    let mut cfg = SimConfig::default()
        .with_baud(args.baud)
        .with_time_scale(args.sim_speed)
        .with_instant_motion(args.sim_instant)
        .with_faults(Faults {
            error_at_line: args
                .sim_error_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ERROR, "--sim-error-at"))
                .transpose()?,
            alarm_at_line: args
                .sim_alarm_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ALARM, "--sim-alarm-at"))
                .transpose()?,
            hangup_at_line: args.sim_hangup_at,
            reset_at_line: args.sim_reset_at,
            ..Faults::default()
        });
    if args.sim_laser {
        cfg = cfg.with_setting(32, 1.0);
    }
    if let Some((lo, hi)) = job.extent {
        let default_travel = flatcut_firmware_sim::Settings::default().max_travel;
        for a in 0..3 {
            let size = hi[a] - lo[a];
            if size.is_finite() && size > default_travel[a] {
                cfg = cfg.with_setting(130 + a as u16, (size + SIM_TRAVEL_MARGIN_MM).ceil());
            }
        }
    }
    cfg.validate()
        .context("the embedded simulator's options are invalid")?;
    Ok(cfg)
}

/// Writes the embedded simulator's trace (JSON lines) and SVG where asked. Written here rather
/// than by the simulator so that a failure is an error of the command, not a warning.
fn write_sim_files(trace: &[TraceSegment], args: &StreamArgs) -> anyhow::Result<()> {
    if let Some(p) = &args.sim_trace {
        let mut s = String::new();
        for seg in trace {
            s.push_str(&serde_json::to_string(seg)?);
            s.push('\n');
        }
        std::fs::write(p, s)
            .with_context(|| format!("cannot write the simulator trace {}", p.display()))?;
    }
    if let Some(p) = &args.sim_svg {
        std::fs::write(p, flatcut_firmware_sim::trace_svg(trace))
            .with_context(|| format!("cannot write the simulator SVG {}", p.display()))?;
    }
    Ok(())
}

/// A send that stopped: the sender's error, and what to do next. Its message is the whole story
/// (the sender's message names the line, the code's meaning and the last line executed), so it
/// reports no separate source; [`StreamError::send_error`] gives the typed error.
#[derive(Debug)]
pub struct StreamError {
    error: SendError,
    hint: Option<String>,
}

impl StreamError {
    /// The sender's typed error.
    pub fn send_error(&self) -> &SendError {
        &self.error
    }
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(h) = &self.hint {
            write!(f, "\n{h}")?;
        }
        Ok(())
    }
}

impl std::error::Error for StreamError {}

/// Turns a send error into a message that says what to do next.
fn explain(e: SendError, name: &str, args: &StreamArgs, journal: &Path) -> anyhow::Error {
    let resumable = matches!(
        e,
        SendError::Transport { .. }
            | SendError::LineRejected { .. }
            | SendError::Alarm { .. }
            | SendError::UnexpectedReset { .. }
            | SendError::LostAck { .. }
            | SendError::DeviceSilent { .. }
            | SendError::Aborted { .. }
            | SendError::UnexpectedState { .. }
    );
    if let SendError::ResumeUncertain { from, .. } = &e {
        let port = match &args.port {
            Some(p) => format!(" --port {p}"),
            None => String::new(),
        };
        let hint = format!(
            "For example, if line {} never started: flatcut send {name}{port} --resume-from {}",
            from.source_line, from.source_line
        );
        return anyhow::Error::new(StreamError {
            error: e,
            hint: Some(hint),
        });
    }
    let hint = resumable.then(|| {
        let port = match &args.port {
            Some(p) => format!(" --port {p}"),
            None => String::new(),
        };
        let journal_flag = match &args.journal {
            Some(p) => format!(" --journal {}", p.display()),
            None => String::new(),
        };
        let mut h = format!(
            "The journal {} records what ran; after fixing the cause, continue after the last \
             completed line with: flatcut send {name}{port}{journal_flag} --resume",
            journal.display()
        );
        if let SendError::Alarm { code: 3, .. } = &e {
            h.push_str(
                " (the reset in motion lost the position: the resume will ask for --resume-from \
                 LINE after the machine is homed or its origin set again)",
            );
        }
        if let SendError::Alarm { code, .. } = &e
            && flatcut_grbl::codes::alarm_is_critical(*code)
        {
            h.push_str(
                " (the controller will be alarm-locked: home it first, or add --unlock only if \
                 the machine position is known to be right)",
            );
        }
        h
    });
    anyhow::Error::new(StreamError { error: e, hint })
}

/// Runs `send_job` with the progress display and the Ctrl-C policy.
fn run_send(
    transport: &mut dyn flatcut_grbl::Transport,
    job: &Job,
    opts: &SendOptions,
    args: &StreamArgs,
    cancel: &Control,
) -> Result<SendReport, SendError> {
    let interactive = std::io::stderr().is_terminal() && !args.quiet;
    let bar = if interactive {
        ProgressBar::with_draw_target(Some(BAR_STEPS), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    let style = ProgressStyle::with_template(
        // Two lines, so the status fits an 80-column terminal without wrapping.
        "{prefix} [{elapsed_precise}] {wide_bar}\n{wide_msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    let prompting = Arc::new(AtomicBool::new(false));
    let interrupts = Interrupts::register();
    let prompter = interrupts.as_ref().ok().map(|i| {
        let rx = i.take_receiver();
        let answers = i.tx.clone();
        let cancel = cancel.clone();
        let bar = bar.clone();
        let prompting = prompting.clone();
        std::thread::spawn(move || prompt_loop(rx, answers, cancel, bar, interactive, prompting))
    });
    if let Err(e) = &interrupts
        && !args.quiet
    {
        eprintln!("warning: Ctrl-C will not pause the job: {e}");
    }

    // The sender estimates machine time; the embedded simulator runs it `sim_speed` times faster
    // (and instant motion has no duration worth showing).
    let eta_scale = match (args.uses_sim(), args.sim_instant) {
        (false, _) => Some(1.0),
        (true, false) => Some(1.0 / args.sim_speed),
        (true, true) => None,
    };
    let mut last_plain = Instant::now();
    let plain = !interactive && !args.quiet;
    let mut observer = |p: &Progress| {
        if prompting.load(Ordering::Relaxed) {
            return;
        }
        if interactive {
            // The bar fills with the path length executed; the line count is what GRBL took.
            bar.set_prefix(format!(
                "{:>10} line {}/{}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total
            ));
            bar.set_position((p.fraction() * BAR_STEPS as f64).round() as u64);
            bar.set_message(status_text(p, eta_scale));
        } else if plain
            && (last_plain.elapsed() >= PLAIN_PROGRESS_INTERVAL || p.phase == Phase::Done)
        {
            last_plain = Instant::now();
            eprintln!(
                "{}: line {}/{} {}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total,
                status_text(p, eta_scale)
            );
        }
    };
    let result = flatcut_grbl::send_job(transport, job, opts, &mut observer, cancel);
    bar.finish_and_clear();
    if let Ok(i) = interrupts {
        i.done();
    }
    if let Some(h) = prompter {
        let _ = h.join();
    }
    result
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Connecting => "connecting",
        Phase::Checking => "checking",
        Phase::Streaming => "streaming",
        Phase::Finishing => "finishing",
        Phase::Done => "done",
    }
}

/// "12.3% of path · ETA 1:05 · Run · X10.000 Y5.000 Z-0.500".
/// `eta_scale` converts the sender's machine-time ETA to wall-clock time (`None`: no ETA).
fn status_text(p: &Progress, eta_scale: Option<f64>) -> String {
    let mut s = format!("{:5.1}% of path", 100.0 * p.fraction());
    if let (Some(eta), Some(k)) = (p.eta, eta_scale) {
        let t = (eta.as_secs_f64() * k).round() as u64;
        s.push_str(&format!(" · ETA {}:{:02}", t / 60, t % 60));
    }
    if let Some(st) = &p.state {
        s.push_str(&format!(" · {}", st.name()));
    }
    if p.holding {
        s.push_str(" (held)");
    }
    if let Some([x, y, z]) = p.position {
        s.push_str(&format!(" · X{x:.3} Y{y:.3} Z{z:.3}"));
    }
    s
}

/// What the prompt thread hears about.
enum Ev {
    /// Ctrl-C.
    Interrupt,
    /// A line typed at the "[r]esume or [a]bort?" prompt (`None`: stdin closed).
    Answer(Option<String>),
    /// The send is over.
    Done,
}

/// The process-wide Ctrl-C handler (the `ctrlc` crate allows one per process) forwards to the
/// most recently registered stream or simulator still running; with none, Ctrl-C exits (130).
/// With ctrlc's `termination` feature SIGTERM and SIGHUP come through the same handler (it does
/// not say which signal it was): a service manager stopping `flatcut send`, or a closed
/// terminal, gets the feed hold and then the abort (stdin is not a terminal, or reading the
/// answer fails), never a controller left running with a dead sender.
static SINK: Mutex<Vec<(u64, Sender<Ev>)>> = Mutex::new(Vec::new());
/// Registration ids, so a finishing stream unregisters itself and nobody else.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
static HANDLER: OnceLock<Result<(), String>> = OnceLock::new();

fn install_handler() -> Result<(), String> {
    HANDLER
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                let sink = SINK.lock().unwrap_or_else(|p| p.into_inner());
                match sink.last() {
                    Some((_, tx)) if tx.send(Ev::Interrupt).is_ok() => {}
                    _ => {
                        // No stream to stop: the command ends here, leaving no temporary file.
                        crate::output::remove_staged();
                        std::process::exit(130)
                    }
                }
            })
            .map_err(|e| e.to_string())
        })
        .clone()
}

/// Installs the signal handler for a command that writes files, so SIGINT, SIGTERM and SIGHUP
/// remove its temporary outputs before the process ends. When the handler cannot be installed
/// (an embedding program owns the signals) the outputs are still cleaned on every other path.
pub(crate) fn install_signal_cleanup() {
    let _ = install_handler();
}

/// A registration with the Ctrl-C handler; unregisters on drop.
struct Interrupts {
    id: u64,
    tx: Sender<Ev>,
    rx: Mutex<Option<Receiver<Ev>>>,
}

impl Interrupts {
    fn register() -> anyhow::Result<Interrupts> {
        install_handler().map_err(|e| anyhow::anyhow!("cannot install the Ctrl-C handler: {e}"))?;
        let (tx, rx) = channel();
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        SINK.lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((id, tx.clone()));
        Ok(Interrupts {
            id,
            tx,
            rx: Mutex::new(Some(rx)),
        })
    }

    fn take_receiver(&self) -> Receiver<Ev> {
        match self.rx.lock().unwrap_or_else(|p| p.into_inner()).take() {
            Some(rx) => rx,
            // Only called once per registration; a second call gets a closed channel.
            None => channel().1,
        }
    }

    fn done(&self) {
        let _ = self.tx.send(Ev::Done);
    }
}

impl Drop for Interrupts {
    fn drop(&mut self) {
        SINK.lock()
            .unwrap_or_else(|p| p.into_inner())
            .retain(|(id, _)| *id != self.id);
    }
}

/// Blocks until Ctrl-C (for `flatcut sim`). Errors if no handler can be installed.
pub(crate) fn wait_for_interrupt() -> anyhow::Result<()> {
    let i = Interrupts::register()?;
    let rx = i.take_receiver();
    loop {
        match rx.recv() {
            Ok(Ev::Interrupt) | Err(_) => return Ok(()),
            Ok(_) => {}
        }
    }
}

/// Ctrl-C policy (SIGTERM and SIGHUP alike): the first one holds the feed and asks "[r]esume or
/// [a]bort?" on the terminal (abort at once when stdin is not a terminal); a second one while
/// asking aborts. Abort = feed hold, soft reset, tool off, journal flushed, and a message naming
/// the last line executed.
fn prompt_loop(
    rx: Receiver<Ev>,
    answers: Sender<Ev>,
    cancel: CancelToken,
    bar: ProgressBar,
    interactive: bool,
    prompting: Arc<AtomicBool>,
) {
    let ask = || {
        eprint!("\nfeed hold: [r]esume or [a]bort (soft reset, tool off)? ");
        let _ = std::io::stderr().flush();
        // The stdin read blocks, so it runs on its own thread and answers through the channel.
        let tx = answers.clone();
        std::thread::spawn(move || {
            let mut line = String::new();
            let answer = match std::io::stdin().lock().read_line(&mut line) {
                Ok(0) | Err(_) => None,
                Ok(_) => Some(line),
            };
            let _ = tx.send(Ev::Answer(answer));
        });
    };
    let restore = |bar: &ProgressBar| {
        prompting.store(false, Ordering::Relaxed);
        if interactive {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    };
    let mut asking = false;
    for ev in rx {
        match ev {
            Ev::Done => return,
            Ev::Interrupt if asking || cancel.is_aborted() => {
                eprintln!("\naborting: soft reset, tool off");
                cancel.abort();
                asking = false;
                restore(&bar);
            }
            Ev::Interrupt => {
                cancel.hold();
                if !std::io::stdin().is_terminal() {
                    eprintln!("\ninterrupted: feed hold, then abort (stdin is not a terminal)");
                    cancel.abort();
                    continue;
                }
                prompting.store(true, Ordering::Relaxed);
                bar.set_draw_target(ProgressDrawTarget::hidden());
                asking = true;
                ask();
            }
            Ev::Answer(a) if asking => {
                match a.as_deref().map(|s| s.trim().to_ascii_lowercase()) {
                    Some(s) if s == "r" || s == "resume" => {
                        eprintln!("resuming (cycle start)");
                        cancel.resume();
                    }
                    Some(s) if s == "a" || s == "abort" => {
                        eprintln!("aborting: soft reset, tool off");
                        cancel.abort();
                    }
                    None => {
                        eprintln!("stdin closed: aborting");
                        cancel.abort();
                    }
                    Some(_) => {
                        ask();
                        continue;
                    }
                }
                asking = false;
                restore(&bar);
            }
            Ev::Answer(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_grbl::MachineState;

    fn progress() -> Progress {
        Progress {
            phase: Phase::Streaming,
            lines_acked: 40,
            lines_done: 30,
            lines_total: 100,
            last_acked: None,
            length_done: 250.0,
            length_total: 1000.0,
            eta: Some(Duration::from_secs(125)),
            state: Some(MachineState::Run),
            position: Some([10.0, 5.25, -0.5]),
            elapsed: Duration::from_secs(3),
            bytes_written: 1234,
            holding: false,
        }
    }

    #[test]
    fn status_line_shows_path_fraction_eta_state_and_position() {
        let p = progress();
        assert_eq!(
            status_text(&p, Some(1.0)),
            " 25.0% of path · ETA 2:05 · Run · X10.000 Y5.250 Z-0.500"
        );
        // The embedded simulator at 50x: 125 s of machine time is 2.5 s, shown rounded.
        assert!(status_text(&p, Some(1.0 / 50.0)).contains("ETA 0:03"));
        // Instant motion: no ETA at all.
        assert!(!status_text(&p, None).contains("ETA"));
        let held = Progress {
            holding: true,
            state: Some(MachineState::Hold { complete: true }),
            ..p
        };
        assert!(status_text(&held, Some(1.0)).contains("Hold:0 (held)"));
    }

    #[test]
    fn fault_line_and_code_parsing() {
        assert_eq!(line_code("12", 20, "--x").unwrap(), (12, 20));
        assert_eq!(line_code("12:33", 20, "--x").unwrap(), (12, 33));
        for bad in ["0", "-3", "x", "12:300", "12:"] {
            let e = line_code(bad, 20, "--sim-error-at").unwrap_err();
            assert!(
                e.to_string().contains(&format!("--sim-error-at {bad}")),
                "{e}"
            );
        }
    }

    #[test]
    fn journal_path_and_sim_bed() {
        let a = StreamArgs::default();
        assert_eq!(
            a.journal_path("out/job-1.gcode"),
            PathBuf::from("out/job-1.gcode.journal")
        );
        assert_eq!(
            a.clone().with_journal("j").journal_path("x.gcode"),
            PathBuf::from("j")
        );
        assert!(a.uses_sim() && !a.clone().with_port("/dev/ttyUSB0").uses_sim());
        // A 600 x 150 mm job: the simulated bed grows in X only, to 610 mm.
        let job = Job::parse("G0 X0 Y0\nG1 X600 Y150 F1000\n").unwrap();
        let cfg = sim_config(&job, &a).unwrap();
        assert_eq!(cfg.settings, vec![(130, 610.0)]);
        assert_eq!(cfg.time_scale, DEFAULT_SIM_SPEED);
        let bad = StreamArgs {
            sim_speed: 0.0,
            ..StreamArgs::default()
        };
        assert!(sim_config(&job, &bad).is_err());
    }
}
