//! The device a job is streamed to: a serial port, or — with no `--port` — the embedded GRBL
//! simulator on a pseudo-terminal, so the whole pipeline runs on any machine.
//!
//! [`stream_file`] / [`stream_text`] parse the job, start the simulator if needed, open the port,
//! run [`flatcut_grbl::send_job`] with a live progress bar, turn Ctrl-C into a feed hold followed
//! by a "resume or abort" question, and stop the simulator (writing its trace and SVG). Every
//! protocol decision (handshake, alarm-lock policy, `$C`, character counting, journaling) lives in
//! `flatcut-grbl`; this module is only terminal, files and process plumbing.

//!
//! One concern per module: `args` (the flags), `ask` (the sender's questions at the terminal), `embedded` (the simulator as the device),
//! `display` (the progress display), `printer` (the thread that writes it), `signals` (Ctrl-C, SIGTERM, SIGHUP and the prompt),
//! `explain` (what a stopped send tells the operator); this module streams.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flatcut_firmware_sim::{PtySim, SimStats, TraceSegment};
use flatcut_grbl::{Control, Job, SendOptions, SendReport};

mod args;
mod ask;
mod display;
mod embedded;
mod explain;
mod printer;
pub mod select;
mod signals;

pub use args::{DEFAULT_BAUD, DEFAULT_SIM_SPEED, OnPause, StreamArgs};
pub use display::PLAIN_PROGRESS_INTERVAL;
pub use explain::StreamError;
pub(crate) use signals::{install_signal_cleanup, wait_for_interrupt};

use display::run_send;
use embedded::{sim_config, write_sim_files};
use explain::explain;

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
    /// Which device ran the job (the port and its baud rate, or the simulator).
    pub device: String,
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
        .with_journal(&journal)
        .with_origin_confirmed(args.origin_confirmed)
        .with_accept_changed_job(args.accept_changed_job)
        .with_discard_offsets(args.discard_offsets)
        .with_position_tolerance(Some(args.position_tolerance))
        .with_on_pause(args.pause_policy())
        .with_force_laser(args.force_laser);

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
        device: select::describe(args),
    })
}

#[cfg(test)]
mod tests;
