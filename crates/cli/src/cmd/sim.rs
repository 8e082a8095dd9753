//! `flatcut sim`: the simulated GRBL 1.1h controller on a pseudo-terminal, in the foreground
//! until Ctrl-C, for any sender (including `flatcut send --port`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use flatcut_firmware_sim::{Faults, PtySim, RxOverflow, SimConfig};

use super::device::{DEFAULT_BAUD, line_code, wait_for_interrupt};

/// Arguments of `flatcut sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Make a symlink at PATH pointing to the device.
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Baud rate used to pace bytes (bytes/s = baud/10).
    #[arg(long, default_value_t = DEFAULT_BAUD)]
    pub baud: u32,
    /// Time scale of motion (10 = ten times faster than real time).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Motion completes instantly.
    #[arg(long)]
    pub instant: bool,
    /// Write every executed motion as JSON lines to this file at exit.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Write an SVG of what was drawn or cut at exit.
    #[arg(long, value_name = "FILE")]
    pub trace_svg: Option<PathBuf>,
    /// Laser mode (`$32=1`).
    #[arg(long)]
    pub laser: bool,
    /// Extra `$n=value` settings at start, e.g. `--set 130=400` (repeatable).
    #[arg(long = "set", value_name = "N=VALUE")]
    pub set: Vec<String>,
    /// Hold bytes in the pseudo-terminal when the 128-byte RX buffer is full instead of dropping
    /// them as the real controller does.
    #[arg(long)]
    pub block: bool,
    /// Probability that a received byte is dropped.
    #[arg(long, default_value_t = 0.0)]
    pub drop_rate: f64,
    /// Probability that a received byte is corrupted.
    #[arg(long, default_value_t = 0.0)]
    pub corrupt_rate: f64,
    /// Extra latency before each response, ms.
    #[arg(long, default_value_t = 0)]
    pub delay_ms: u64,
    /// Answer `error:CODE` (default 20) to the N-th received line.
    #[arg(long, value_name = "N[:CODE]")]
    pub error_at: Option<String>,
    /// Raise `ALARM:CODE` (default 1) when the N-th line executes.
    #[arg(long, value_name = "N[:CODE]")]
    pub alarm_at: Option<String>,
    /// Reset by itself when the N-th line arrives.
    #[arg(long, value_name = "N")]
    pub reset_at: Option<u32>,
    /// Hang up (close the device) when the N-th line arrives.
    #[arg(long, value_name = "N")]
    pub hangup_at: Option<u32>,
    /// Seed of the fault-injection generator.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// The simulator configuration the arguments describe.
pub fn config(a: &Args) -> anyhow::Result<SimConfig> {
    let mut settings = Vec::new();
    if a.laser {
        settings.push((32, 1.0));
    }
    for s in &a.set {
        let Some((n, v)) = s.split_once('=') else {
            bail!("--set {s}: expected N=VALUE");
        };
        let n: u16 = n
            .trim_start_matches('$')
            .parse()
            .with_context(|| format!("--set {s}: bad setting number"))?;
        let v: f64 = v.parse().with_context(|| format!("--set {s}: bad value"))?;
        settings.push((n, v));
    }
    let cfg = SimConfig {
        baud: a.baud,
        time_scale: a.speed,
        instant_motion: a.instant,
        rx_overflow: if a.block {
            RxOverflow::Block
        } else {
            RxOverflow::Drop
        },
        settings,
        faults: Faults {
            drop_rate: a.drop_rate,
            corrupt_rate: a.corrupt_rate,
            response_delay_ms: a.delay_ms,
            error_at_line: a
                .error_at
                .as_deref()
                .map(|s| line_code(s, 20, "--error-at"))
                .transpose()?,
            alarm_at_line: a
                .alarm_at
                .as_deref()
                .map(|s| line_code(s, 1, "--alarm-at"))
                .transpose()?,
            reset_at_line: a.reset_at,
            hangup_at_line: a.hangup_at,
        },
        trace_jsonl: a.trace.clone(),
        trace_svg: a.trace_svg.clone(),
        seed: a.seed,
    };
    cfg.validate()?;
    Ok(cfg)
}

/// Runs `flatcut sim` until Ctrl-C.
pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let cfg = config(&a)?;
    let sim = PtySim::spawn(cfg).context("cannot create the pseudo-terminal")?;
    match &a.link {
        Some(link) => {
            sim.link(link)
                .with_context(|| format!("cannot link {}", link.display()))?;
            println!("{} -> {}", link.display(), sim.path().display());
        }
        None => println!("{}", sim.path().display()),
    }
    eprintln!(
        "simulated GRBL 1.1h at {} baud; connect with `flatcut send JOB --port {}`; Ctrl-C stops",
        a.baud,
        a.link.as_deref().unwrap_or(sim.path()).display()
    );
    let waited = wait_for_interrupt();
    let report = sim.stop();
    let s = &report.stats;
    eprintln!(
        "simulator stopped: {} lines, {} ok, {} errors, {} alarms, {} bytes lost to RX overflow, {} segments, {:.1} s simulated",
        s.lines_received,
        s.oks,
        s.errors,
        s.alarms,
        s.bytes_dropped_overflow,
        report.trace.len(),
        report.sim_time
    );
    waited?;
    Ok(ExitCode::SUCCESS)
}
