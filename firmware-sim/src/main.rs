//! `firmware-sim`: a GRBL 1.1h controller (Arduino Uno) on a pseudo-terminal. Prints the device path, runs until
//! Ctrl-C or SIGTERM, then writes the traces.

use clap::Parser;
use flatcut_firmware_sim::{Faults, PtySim, RxOverflow, SimConfig};
use nix::sys::signal::{SigSet, Signal};
use std::path::PathBuf;
use std::process::ExitCode;

/// GRBL 1.1h simulator on a pseudo-terminal: open the printed path with any serial sender.
#[derive(Debug, Parser)]
#[command(name = "firmware-sim", version)]
struct Args {
    /// Make a symlink at PATH pointing to the device.
    #[arg(long, value_name = "PATH")]
    link: Option<PathBuf>,
    /// Baud rate used to pace bytes (bytes/s = baud/10).
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Time scale of motion (10 = ten times faster than real time).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Motion completes instantly (the planner never fills).
    #[arg(long)]
    instant: bool,
    /// Write every executed motion as JSON lines to this file at exit.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Write an SVG of what was drawn or cut at exit.
    #[arg(long, value_name = "FILE")]
    trace_svg: Option<PathBuf>,
    /// Write the counters and simulated time as JSON to this file at exit.
    #[arg(long, value_name = "FILE")]
    report: Option<PathBuf>,
    /// Laser mode ($32=1).
    #[arg(long)]
    laser: bool,
    /// Extra `$n=value` settings at start, e.g. `--set 130=400` (repeatable).
    #[arg(long = "set", value_name = "N=VALUE")]
    set: Vec<String>,
    /// Hold bytes in the pseudo-terminal when the 128-byte RX buffer is full instead of dropping them.
    #[arg(long)]
    block: bool,
    /// Probability that a received byte is dropped.
    #[arg(long, default_value_t = 0.0)]
    drop_rate: f64,
    /// Probability that a received byte is corrupted.
    #[arg(long, default_value_t = 0.0)]
    corrupt_rate: f64,
    /// Extra latency before each response, ms.
    #[arg(long, default_value_t = 0)]
    delay_ms: u64,
    /// Answer error:code (default 20) to the N-th line.
    #[arg(long, value_name = "N[:CODE]")]
    error_at: Option<String>,
    /// Raise ALARM:code (default 1) when the N-th line executes.
    #[arg(long, value_name = "N[:CODE]")]
    alarm_at: Option<String>,
    /// Soft reset when the N-th line arrives.
    #[arg(long, value_name = "N")]
    reset_at: Option<u32>,
    /// Close the device when the N-th line arrives.
    #[arg(long, value_name = "N")]
    hangup_at: Option<u32>,
    /// Seed of the fault-injection generator.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Opening the port does not reset the controller (a board with DTR auto-reset disabled): it keeps its
    /// position and keeps running through a hang-up and a reconnect.
    #[arg(long)]
    no_dtr_reset: bool,
}

fn line_code(arg: &str, default_code: u8, what: &str) -> Result<(u32, u8), String> {
    let (n, c) = match arg.split_once(':') {
        Some((n, c)) => (n, Some(c)),
        None => (arg, None),
    };
    let n: u32 = n
        .parse()
        .map_err(|_| format!("--{what} {arg}: line number must be a positive integer"))?;
    let c: u8 = match c {
        Some(c) => c
            .parse()
            .map_err(|_| format!("--{what} {arg}: code must be 0..255"))?,
        None => default_code,
    };
    Ok((n, c))
}

fn config(args: &Args) -> Result<SimConfig, String> {
    let mut settings = Vec::new();
    if args.laser {
        settings.push((32, 1.0));
    }
    for s in &args.set {
        let (n, v) = s
            .split_once('=')
            .ok_or_else(|| format!("--set {s}: expected N=VALUE"))?;
        let n: u16 = n
            .trim_start_matches('$')
            .parse()
            .map_err(|_| format!("--set {s}: bad setting number"))?;
        let v: f64 = v.parse().map_err(|_| format!("--set {s}: bad value"))?;
        settings.push((n, v));
    }
    for (name, r) in [
        ("drop-rate", args.drop_rate),
        ("corrupt-rate", args.corrupt_rate),
    ] {
        if !(0.0..=1.0).contains(&r) {
            return Err(format!("--{name} {r}: must be a probability in [0, 1]"));
        }
    }
    let cfg = SimConfig {
        baud: args.baud,
        time_scale: args.speed,
        instant_motion: args.instant,
        rx_overflow: if args.block {
            RxOverflow::Block
        } else {
            RxOverflow::Drop
        },
        settings,
        faults: Faults {
            drop_rate: args.drop_rate,
            corrupt_rate: args.corrupt_rate,
            response_delay_ms: args.delay_ms,
            error_at_line: args
                .error_at
                .as_deref()
                .map(|a| line_code(a, 20, "error-at"))
                .transpose()?,
            alarm_at_line: args
                .alarm_at
                .as_deref()
                .map(|a| line_code(a, 1, "alarm-at"))
                .transpose()?,
            reset_at_line: args.reset_at,
            hangup_at_line: args.hangup_at,
        },
        trace_jsonl: args.trace.clone(),
        trace_svg: args.trace_svg.clone(),
        seed: args.seed,
    };
    cfg.validate().map_err(|e| e.to_string())?;
    Ok(cfg)
}

fn main() -> ExitCode {
    let args = Args::parse();
    let cfg = match config(&args) {
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
    if let Err(e) = signals.thread_block() {
        eprintln!("firmware-sim: cannot block signals: {e}");
        return ExitCode::FAILURE;
    }
    let sim = match PtySim::spawn_with_dtr_reset(cfg, !args.no_dtr_reset) {
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
    let sig = signals.wait();
    let report = sim.stop();
    if let Some(path) = &args.report {
        let summary = serde_json::json!({
            "stats": &report.stats,
            "sim_time": report.sim_time,
            "segments": report.trace.len(),
        });
        if let Err(e) = std::fs::write(path, format!("{summary:#}\n")) {
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
