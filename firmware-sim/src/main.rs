//! `firmware-sim`: a GRBL 1.1h controller (Arduino Uno) on a pseudo-terminal. Prints the device path, runs until
//! Ctrl-C or SIGTERM, then writes the traces. SIGUSR1 power-cycles the controller (position and G92 lost, the
//! banner after `--boot-ms`, unheard when no client has the port open).

use clap::Parser;
use flatcut_firmware_sim::{PtySim, SimArgs, write_atomic};
use nix::sys::signal::{SigSet, Signal};
use std::process::ExitCode;

/// GRBL 1.1h simulator on a pseudo-terminal: open the printed path with any serial sender.
#[derive(Debug, Parser)]
#[command(name = "firmware-sim", version)]
struct Cli {
    #[command(flatten)]
    sim: SimArgs,
}

fn main() -> ExitCode {
    let args = Cli::parse().sim;
    let cfg = match args.config() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("firmware-sim: {e}");
            return ExitCode::from(2);
        }
    };
    // Block the stop signals before the simulator thread exists, then wait for them synchronously.
    let mut signals = SigSet::empty();
    signals.add(Signal::SIGINT);
    signals.add(Signal::SIGTERM);
    signals.add(Signal::SIGHUP);
    signals.add(Signal::SIGUSR1);
    if let Err(e) = signals.thread_block() {
        eprintln!("firmware-sim: cannot block signals: {e}");
        return ExitCode::FAILURE;
    }
    let sim = match PtySim::spawn(cfg) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("firmware-sim: cannot create the pseudo-terminal: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(link) = &args.link {
        if let Err(e) = sim.link(link) {
            eprintln!("firmware-sim: cannot link {}: {e}", link.display());
            return ExitCode::FAILURE;
        }
        println!("{} -> {}", link.display(), sim.path().display());
    } else {
        println!("{}", sim.path().display());
    }
    let sig = loop {
        match signals.wait() {
            Ok(Signal::SIGUSR1) => sim.power_cycle(),
            other => break other,
        }
    };
    let report = sim.stop();
    if let Some(path) = &args.report {
        let summary = serde_json::json!({
            "stats": &report.stats,
            "sim_time": report.sim_time,
            "segments": report.trace.len(),
        });
        if let Err(e) = write_atomic(path, format!("{summary:#}\n").as_bytes()) {
            eprintln!("firmware-sim: cannot write report {}: {e}", path.display());
        }
    }
    let s = &report.stats;
    eprintln!(
        "firmware-sim: stopped ({:?}); {} lines, {} ok, {} errors, {} alarms, {} bytes dropped on overflow, {} segments, \
         {:.1} s simulated",
        sig.ok(),
        s.lines_received,
        s.oks,
        s.errors,
        s.alarms,
        s.bytes_dropped_overflow,
        report.trace.len(),
        report.sim_time
    );
    ExitCode::SUCCESS
}
