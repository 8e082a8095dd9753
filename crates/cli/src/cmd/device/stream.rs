//! Streaming a job from the command line: the job parsed from memory, the device the flags name
//! opened through the device library (the embedded simulator without `--port`), the job watched
//! at the terminal, the simulator's evidence written, and a stop explained with the flag to use
//! next. Every protocol decision (handshake, alarm-lock policy, `$C`, character counting,
//! journaling, resume) lives in `flatcut-grbl`, the session in `flatcut-device`.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flatcut_device::grbl::{Control, Job, SendReport};
use flatcut_device::sim::{SimStats, TraceSegment};
use flatcut_device::{Device, JobRequest, Target};

use super::args::StreamArgs;
use super::evidence::write_sim_files;
use super::explain::explain;
use super::watch;

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
    let opts = args.send_options(&journal, args.resume_index(&job, name)?);
    let target = args.target()?;
    let device = match &target {
        Target::Port { path, .. } => Device::open(target.clone())
            .with_context(|| format!("cannot open the serial port {path}"))?,
        Target::Simulator(s) => {
            let device = Device::open(target.clone())?;
            if !args.quiet {
                eprintln!(
                    "streaming to the embedded simulator at {} ({}; pass --port PATH for a real controller)",
                    device.link(),
                    if s.instant {
                        "instant motion".to_string()
                    } else {
                        format!("{}× real time", s.speed)
                    }
                );
            }
            device
        }
        t => bail!(
            "{} is an HP-GL plotter: G-code goes to a GRBL controller",
            t.describe()
        ),
    };
    let req = JobRequest::new(name, job)
        .with_options(opts)
        .with_control(control.clone());
    let ran = watch::run_job(&device, req, args);
    // Closing closes the port, then stops the simulator, which gives its trace.
    let sim = device.close().sim;
    if let Some(r) = &sim {
        write_sim_files(&r.trace, args)?;
    }
    let outcome = ran?.map_err(|e| explain(e, name, args, &journal))?;
    Ok(StreamOutcome {
        report: outcome.report,
        sim_stats: sim.as_ref().map(|r| r.stats.clone()),
        sim_time: sim.as_ref().map(|r| r.sim_time),
        sim_trace: sim.map(|r| r.trace),
        journal,
        baud: args.baud,
        device: args.describe(),
    })
}
