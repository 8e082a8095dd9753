//! `flatcut sim`: the simulated GRBL 1.1h controller on a pseudo-terminal, in the foreground
//! until Ctrl-C, for any sender (including `flatcut send --port`). Its flags are the
//! `firmware-sim` binary's own ([`flatcut_device::sim::SimArgs`]).

use std::process::ExitCode;

use anyhow::Context;
use flatcut_device::sim::{PtySim, SimArgs};

use super::device::wait_for_interrupt;

/// Arguments of `flatcut sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub sim: SimArgs,
}

/// Runs `flatcut sim` until Ctrl-C.
pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let a = a.sim;
    let cfg = a.config()?;
    let sim = PtySim::spawn(cfg).context("cannot create the pseudo-terminal")?;
    match &a.link {
        Some(link) => {
            sim.link(link)
                .with_context(|| format!("cannot link {}", link.display()))?;
            crate::outln!("{} -> {}", link.display(), sim.path().display());
        }
        None => crate::outln!("{}", sim.path().display()),
    }
    eprintln!(
        "simulated GRBL 1.1h at {} baud; connect with `flatcut send JOB --port {}`; Ctrl-C stops",
        a.baud,
        a.link.as_deref().unwrap_or(sim.path()).display()
    );
    wait_for_interrupt();
    let report = sim.stop();
    if let Some(path) = &a.report {
        let summary = serde_json::json!({
            "stats": &report.stats,
            "sim_time": report.sim_time,
            "segments": report.trace.len(),
        });
        super::common::write(path, format!("{summary:#}\n").as_bytes())?;
    }
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
    Ok(ExitCode::SUCCESS)
}
