//! `flatcut sim`: the simulated GRBL 1.1h controller on a pseudo-terminal, in the foreground
//! until Ctrl-C, for any sender (including `flatcut send --port`). Its flags are the
//! `firmware-sim` binary's own ([`flatcut_device::sim::SimArgs`]). SIGUSR1 power-cycles the
//! controller as the `firmware-sim` binary does (position and G92 lost, the banner after
//! `--boot-ms`, unheard when no client has the port open), so an operator can try what a resume
//! does after a restart the sender did not see.

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
    let port = a
        .link
        .as_deref()
        .unwrap_or(sim.path())
        .display()
        .to_string();
    power_cycles_on_sigusr1(&sim, || {
        eprintln!(
            "simulated GRBL 1.1h at {} baud; connect with `flatcut send JOB --port {port}`; `kill -USR1 {}` power-cycles it; Ctrl-C stops",
            a.baud,
            std::process::id()
        );
        wait_for_interrupt();
    })?;
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

/// Runs `until` while every SIGUSR1 the process gets power-cycles `sim` (tokio's signal handling,
/// which lives beside the Ctrl-C handler, on a thread of its own); the handler is in place before
/// `until` starts, and the thread stops listening when `until` returns.
fn power_cycles_on_sigusr1(sim: &PtySim, until: impl FnOnce()) -> anyhow::Result<()> {
    use tokio::signal::unix::{SignalKind, signal};
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .build()
        .context("cannot start the signal listener")?;
    let mut usr1 = {
        let _in_runtime = rt.enter();
        signal(SignalKind::user_defined1()).context("cannot listen for SIGUSR1")?
    };
    let (stop, mut stopped) = tokio::sync::oneshot::channel::<()>();
    std::thread::scope(|scope| {
        scope.spawn(|| {
            rt.block_on(async {
                loop {
                    tokio::select! {
                        got = usr1.recv() => {
                            if got.is_none() {
                                break;
                            }
                            sim.power_cycle();
                            eprintln!("power cycle (SIGUSR1): position and G92 lost, the banner as at power-up");
                        }
                        _ = &mut stopped => break,
                    }
                }
            });
        });
        until();
        let _ = stop.send(());
    });
    Ok(())
}
