//! The simulator's command line, as a `clap::Args` struct: the `firmware-sim` binary parses it,
//! and any other program that starts a simulator (the `flatcut sim` command) flattens the same
//! struct into its own command line, so the two can never drift apart.

use crate::{ConfigError, Faults, RxOverflow, SimConfig};
use std::path::PathBuf;

/// Default GRBL error code of `--error-at N` (20: unsupported or invalid g-code command).
pub const DEFAULT_INJECTED_ERROR: u8 = 20;
/// Default GRBL alarm code of `--alarm-at N` (1: hard limit).
pub const DEFAULT_INJECTED_ALARM: u8 = 1;

/// How to run the simulated controller.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct SimArgs {
    /// Make a symlink at PATH pointing to the device.
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Baud rate used to pace bytes (bytes/s = baud/10).
    #[arg(long, default_value_t = crate::DEFAULT_BAUD)]
    pub baud: u32,
    /// Time scale of motion (10 = ten times faster than real time).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Motion completes instantly (the planner never fills).
    #[arg(long)]
    pub instant: bool,
    /// Write every executed motion as JSON lines to this file at exit.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Write an SVG of what was drawn or cut at exit.
    #[arg(long, value_name = "FILE")]
    pub trace_svg: Option<PathBuf>,
    /// Write the counters and simulated time as JSON to this file at exit.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
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
    /// Lose one digit of the N-th received line (the first after its decimal point), so that it
    /// still parses and moves elsewhere.
    #[arg(long, value_name = "N")]
    pub drop_digit_at: Option<u32>,
    /// Seed of the fault-injection generator.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Opening the port does not reset the controller (a board with DTR auto-reset disabled):
    /// it keeps its position and keeps running through a hang-up and a reconnect.
    #[arg(long)]
    pub no_dtr_reset: bool,
    /// After a hardware reset (the reset of opening the port, a power cycle: SIGUSR1 to the
    /// `firmware-sim` binary), the banner comes N ms later and input meanwhile is lost, as in
    /// a bootloader.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub boot_ms: u64,
}

impl Default for SimArgs {
    fn default() -> SimArgs {
        SimArgs {
            link: None,
            baud: crate::DEFAULT_BAUD,
            speed: 1.0,
            instant: false,
            trace: None,
            trace_svg: None,
            report: None,
            laser: false,
            set: Vec::new(),
            block: false,
            drop_rate: 0.0,
            corrupt_rate: 0.0,
            delay_ms: 0,
            error_at: None,
            alarm_at: None,
            reset_at: None,
            hangup_at: None,
            drop_digit_at: None,
            seed: 0,
            no_dtr_reset: false,
            boot_ms: 0,
        }
    }
}

/// A command line the simulator cannot run with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ArgsError {
    /// A flag's value does not parse.
    #[error("{flag} {value}: {what}")]
    Value {
        /// The flag, `--set` say.
        flag: &'static str,
        /// What was given.
        value: String,
        /// What is wrong.
        what: &'static str,
    },
    /// The configuration the flags describe is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
}

/// Parses `N[:CODE]`: a 1-based line number and an optional GRBL code (`default_code` when
/// absent), for the fault flag `flag`.
pub fn line_code(arg: &str, default_code: u8, flag: &'static str) -> Result<(u32, u8), ArgsError> {
    let bad = |what| ArgsError::Value {
        flag,
        value: arg.to_string(),
        what,
    };
    let (n, c) = match arg.split_once(':') {
        Some((n, c)) => (n, Some(c)),
        None => (arg, None),
    };
    let n: u32 = n
        .trim()
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| bad("the line number must be a positive integer"))?;
    let c = match c {
        Some(c) => c
            .trim()
            .parse()
            .map_err(|_| bad("the code must be 0..255"))?,
        None => default_code,
    };
    Ok((n, c))
}

impl SimArgs {
    /// The `$n=value` settings the flags ask for (`--laser`, then every `--set` in order).
    pub fn settings(&self) -> Result<Vec<(u16, f64)>, ArgsError> {
        let mut settings = Vec::new();
        if self.laser {
            settings.push((32, 1.0));
        }
        for s in &self.set {
            let bad = |what| ArgsError::Value {
                flag: "--set",
                value: s.clone(),
                what,
            };
            let (n, v) = s.split_once('=').ok_or_else(|| bad("expected N=VALUE"))?;
            let n: u16 = n
                .trim_start_matches('$')
                .parse()
                .map_err(|_| bad("bad setting number"))?;
            let v: f64 = v.parse().map_err(|_| bad("bad value"))?;
            settings.push((n, v));
        }
        Ok(settings)
    }

    /// The faults the flags inject.
    pub fn faults(&self) -> Result<Faults, ArgsError> {
        for (flag, r) in [
            ("--drop-rate", self.drop_rate),
            ("--corrupt-rate", self.corrupt_rate),
        ] {
            if !(0.0..=1.0).contains(&r) {
                return Err(ArgsError::Value {
                    flag,
                    value: r.to_string(),
                    what: "must be a probability in [0, 1]",
                });
            }
        }
        Ok(Faults {
            drop_rate: self.drop_rate,
            corrupt_rate: self.corrupt_rate,
            response_delay_ms: self.delay_ms,
            error_at_line: self
                .error_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ERROR, "--error-at"))
                .transpose()?,
            alarm_at_line: self
                .alarm_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ALARM, "--alarm-at"))
                .transpose()?,
            reset_at_line: self.reset_at,
            hangup_at_line: self.hangup_at,
            drop_digit_at_line: self.drop_digit_at,
        })
    }

    /// The simulator configuration the flags describe, validated.
    pub fn config(&self) -> Result<SimConfig, ArgsError> {
        let cfg = SimConfig {
            baud: self.baud,
            time_scale: self.speed,
            instant_motion: self.instant,
            rx_overflow: if self.block {
                RxOverflow::Block
            } else {
                RxOverflow::Drop
            },
            settings: self.settings()?,
            faults: self.faults()?,
            trace_jsonl: self.trace.clone(),
            trace_svg: self.trace_svg.clone(),
            seed: self.seed,
            dtr_reset: !self.no_dtr_reset,
            boot_ms: self.boot_ms,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Cli {
        #[command(flatten)]
        sim: SimArgs,
    }

    #[test]
    fn flags_make_the_configuration_and_bad_values_name_the_flag() {
        let cli = Cli::parse_from([
            "x",
            "--laser",
            "--set",
            "130=400",
            "--error-at",
            "3:33",
            "--alarm-at",
            "9",
            "--no-dtr-reset",
        ]);
        let cfg = cli.sim.config().unwrap();
        assert_eq!(cfg.settings, vec![(32, 1.0), (130, 400.0)]);
        assert_eq!(cfg.faults.error_at_line, Some((3, 33)));
        assert_eq!(cfg.faults.alarm_at_line, Some((9, DEFAULT_INJECTED_ALARM)));
        assert!(!cfg.dtr_reset);
        assert_eq!(Cli::parse_from(["x"]).sim, SimArgs::default());
        for (flags, want) in [
            (vec!["--set", "130"], "--set 130: expected N=VALUE"),
            (vec!["--error-at", "0"], "--error-at 0: the line number"),
            (vec!["--alarm-at", "2:300"], "--alarm-at 2:300: the code"),
            (
                vec!["--drop-rate", "2"],
                "--drop-rate 2: must be a probability",
            ),
            (vec!["--speed", "0"], "time_scale must be positive"),
        ] {
            let cli = Cli::parse_from(std::iter::once("x").chain(flags));
            let e = cli.sim.config().unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
    }
}
