//! A GRBL 1.1h controller (Arduino Uno build) simulated behind a pseudo-terminal, for tests and for users with no
//! plotter attached.
//!
//! The simulator is the independent check on the sender and the G-code writer: it shares no code with them.
//! It has two layers:
//! * [`Grbl`], a sans-IO core on virtual time: feed it received bytes with [`Grbl::receive`], advance the clock
//!   with [`Grbl::tick`], and collect the bytes it answers with [`Grbl::take_output`]. Deterministic, for unit tests.
//! * [`PtySim`], a thread that puts the core behind a pseudo-terminal, paces bytes at the baud rate in both
//!   directions and runs the clock in (optionally scaled) real time, so that `serialport` opens [`PtySim::path`] like
//!   a USB serial adapter.
//!
//! What is modelled from the firmware (GRBL 1.1h, build 20190830): the 128-byte RX ring that silently drops overflow,
//! realtime bytes taken out before the ring, the line pre-parser (79 significant characters), the g-code parser with
//! its modal groups and error numbers, `$` system commands and settings, check mode, alarm lock, soft limits, a
//! 15-block planner with junction deviation and trapezoidal acceleration, feed hold / resume / soft reset, overrides,
//! laser mode, jogging and a simulated homing cycle. A motion trace (JSON lines) and an SVG of what was drawn come
//! out as evidence.
//!
//! In-process, on virtual time:
//! ```
//! use flatcut_firmware_sim::{Grbl, SimConfig};
//! let mut g = Grbl::new(&SimConfig::default());
//! assert!(g.take_output().starts_with(b"\r\nGrbl 1.1h"));
//! g.receive_all(b"G1 X10 F600\n");
//! g.run_until_idle(60.0);
//! assert_eq!(g.take_output(), b"ok\r\n");
//! assert_eq!(g.machine_position(), [10.0, 0.0, 0.0]);
//! assert_eq!(g.trace()[0].to, [10.0, 0.0, 0.0]);
//! ```
//!
//! On a pseudo-terminal, for a sender under test:
//! ```no_run
//! use flatcut_firmware_sim::{PtySim, SimConfig};
//! let sim = PtySim::spawn(SimConfig { time_scale: 10.0, ..SimConfig::default() })?;
//! let port = serialport::new(sim.path().to_string_lossy(), 115_200).open();
//! // ... stream a job through `port` ...
//! let report = sim.stop();
//! println!("{} segments, {} bytes lost to overflow", report.trace.len(), report.stats.bytes_dropped_overflow);
//! # Ok::<(), std::io::Error>(())
//! ```

mod args;
mod files;
mod gcode;
pub mod hpgl;
mod machine;
mod planner;
mod pty;
mod rng;
mod settings;
mod status;
mod svg;

pub use args::{ArgsError, DEFAULT_INJECTED_ALARM, DEFAULT_INJECTED_ERROR, SimArgs, line_code};
pub use files::write_atomic;
pub use gcode::{Flow, GcState, Motion, Persist, Spindle, read_float};
pub use machine::{BANNER, Grbl, Machine, SimEvent, State};
pub use planner::PLANNER_BLOCKS;
pub use pty::PtySim;
pub use settings::{N_AXIS, Settings, fmt_float};
pub use status::{Status, alarm};
pub use svg::trace_svg;

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Size of GRBL's serial receive buffer on an Uno (`RX_BUFFER_SIZE`, `serial.h`).
pub const RX_BUFFER_SIZE: usize = 128;

/// What happens to received bytes when the 128-byte RX buffer is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum RxOverflow {
    /// Dropped silently, as the real device does (`serial.c`).
    #[default]
    Drop,
    /// Left unread in the pseudo-terminal until there is room (as if the link had hardware flow control).
    Block,
}

/// Injected faults; all off by default.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Faults {
    /// Probability that a received byte is dropped.
    pub drop_rate: f64,
    /// Probability that a received byte is corrupted (one bit flipped).
    pub corrupt_rate: f64,
    /// Extra latency before each response, ms.
    pub response_delay_ms: u64,
    /// Answer `error:N` to the n-th received line (1-based, counting every line).
    pub error_at_line: Option<(u32, u8)>,
    /// Raise `ALARM:N` when the n-th line executes.
    pub alarm_at_line: Option<(u32, u8)>,
    /// Spontaneous soft reset (banner again) when the n-th line arrives.
    pub reset_at_line: Option<u32>,
    /// Close the device (port hang-up) right after the n-th line arrives (that line and the bytes already in
    /// the RX ring still run).
    pub hangup_at_line: Option<u32>,
    /// Lose one digit of the n-th line on the link: the first digit after its first decimal point (else its
    /// last digit), so `X156.169` arrives as `X156.69`, a line that still parses and runs elsewhere.
    #[serde(default)]
    pub drop_digit_at_line: Option<u32>,
}

/// Simulator configuration. `Default` is GRBL 1.1h on an Uno at 115200 baud with real-time motion.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Byte pacing: bytes/s = baud/10 in both directions.
    pub baud: u32,
    /// 1.0 = real time; 10.0 = motion runs 10× faster.
    pub time_scale: f64,
    /// Motion completes instantly (the planner never fills).
    pub instant_motion: bool,
    /// RX overflow behaviour.
    pub rx_overflow: RxOverflow,
    /// `$n=value` overrides at start (e.g. `(32, 1.0)` laser mode, `(130, 400.0)` travel).
    pub settings: Vec<(u16, f64)>,
    /// Fault injection.
    pub faults: Faults,
    /// Every executed motion segment as a JSON line, written at stop (also kept in memory).
    pub trace_jsonl: Option<PathBuf>,
    /// SVG of what was drawn/cut (tool-on moves), written at stop.
    pub trace_svg: Option<PathBuf>,
    /// Seed of the fault-injection random generator.
    pub seed: u64,
    /// Opening the port resets the controller, as the DTR pulse does on an Uno (a hang-up
    /// power-cycles it). `false`: a board with auto-reset disabled and its own supply, which
    /// keeps running its planner and its position through a hang-up and a reconnect.
    pub dtr_reset: bool,
    /// After a hardware reset (power-up, the reset of opening the port, a power cycle) the
    /// banner comes this many milliseconds later (wall-clock time, as a bootloader's), and what
    /// arrives meanwhile is lost. 0: at once.
    pub boot_ms: u64,
}

/// Default baud rate of GRBL 1.1 (`config.h`).
pub const DEFAULT_BAUD: u32 = 115_200;

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            baud: DEFAULT_BAUD,
            time_scale: 1.0,
            instant_motion: false,
            rx_overflow: RxOverflow::Drop,
            settings: Vec::new(),
            faults: Faults::default(),
            trace_jsonl: None,
            trace_svg: None,
            seed: 0,
            dtr_reset: true,
            boot_ms: 0,
        }
    }
}

/// A configuration the simulator cannot run with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// Zero baud rate.
    #[error("sim config: baud rate must be positive (got {0})")]
    Baud(u32),
    /// Non-positive or non-finite time scale.
    #[error("sim config: time_scale must be positive and finite (got {0})")]
    TimeScale(f64),
    /// A probability outside [0, 1].
    #[error("sim config: faults.{name} must be a probability in [0, 1] (got {value})")]
    Probability {
        /// Field name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
    /// A `$n=value` start setting that GRBL would refuse.
    #[error("sim config: setting ${n}={value} refused with error:{code}")]
    Setting {
        /// Setting number.
        n: u16,
        /// Value given.
        value: f64,
        /// GRBL's error code for it.
        code: u8,
    },
}

impl SimConfig {
    /// Checks the configuration: positive baud and time scale, probabilities in [0, 1], and start settings that
    /// GRBL accepts (soft limits may be enabled without homing: homing is switched on for them).
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.baud == 0 {
            return Err(ConfigError::Baud(self.baud));
        }
        if !(self.time_scale > 0.0 && self.time_scale.is_finite()) {
            return Err(ConfigError::TimeScale(self.time_scale));
        }
        for (name, value) in [
            ("drop_rate", self.faults.drop_rate),
            ("corrupt_rate", self.faults.corrupt_rate),
        ] {
            if !(0.0..=1.0).contains(&value) {
                return Err(ConfigError::Probability { name, value });
            }
        }
        let mut s = Settings::default();
        for &(n, value) in &self.settings {
            if n == 20 && value != 0.0 {
                s.homing = true;
            }
            s.store(u32::from(n), value)
                .map_err(|e| ConfigError::Setting {
                    n,
                    value,
                    code: e.code(),
                })?;
        }
        Ok(())
    }

    /// Sets the baud rate.
    pub fn with_baud(mut self, baud: u32) -> Self {
        self.baud = baud;
        self
    }
    /// Sets the time scale (`--speed`).
    pub fn with_time_scale(mut self, scale: f64) -> Self {
        self.time_scale = scale;
        self
    }
    /// Makes motion instant.
    pub fn with_instant_motion(mut self, instant: bool) -> Self {
        self.instant_motion = instant;
        self
    }
    /// Adds a `$n=value` setting applied at start.
    pub fn with_setting(mut self, n: u16, value: f64) -> Self {
        self.settings.push((n, value));
        self
    }
    /// Sets the faults.
    pub fn with_faults(mut self, faults: Faults) -> Self {
        self.faults = faults;
        self
    }
    /// Sets whether opening the port resets the controller ([`SimConfig::dtr_reset`]).
    pub fn with_dtr_reset(mut self, on: bool) -> Self {
        self.dtr_reset = on;
        self
    }
    /// Sets the bootloader's delay after a hardware reset ([`SimConfig::boot_ms`]).
    pub fn with_boot_ms(mut self, ms: u64) -> Self {
        self.boot_ms = ms;
        self
    }
}

/// One executed motion: a g-code motion command (an arc is one segment with its centre).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceSegment {
    /// Received line (1-based) that produced it.
    pub line: u32,
    /// That line as executed (stripped, upper-case).
    pub text: String,
    /// `G0`, `G1`, `G2`, `G3`, `G28`, `G30`, `G38.2`, `JOG`, `HOME`.
    pub motion: String,
    /// Start, machine mm.
    pub from: [f64; 3],
    /// End, machine mm.
    pub to: [f64; 3],
    /// Arc centre, machine mm.
    pub arc_center: Option<[f64; 3]>,
    /// Programmed feed, mm/min (0 for rapids).
    pub feed: f64,
    /// Spindle/laser on with S > 0 (laser mode: never during G0), or pen down (work Z < 0) when `$32=0`.
    pub tool_on: bool,
    /// S value in effect (laser mode: 0 during G0).
    pub power: f64,
    /// Simulated start time, s (with `instant_motion`, start and end coincide).
    pub t_start: f64,
    /// Simulated end time, s.
    pub t_end: f64,
}

/// Counters of a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SimStats {
    /// Bytes read from the link (realtime bytes included).
    pub bytes_received: u64,
    /// Bytes lost because the RX buffer was full.
    pub bytes_dropped_overflow: u64,
    /// Bytes dropped by fault injection.
    pub bytes_dropped_fault: u64,
    /// Bytes lost while an EEPROM write held the RX interrupt off (`$x=`, G10, G28.1, `$N`, `$RST`).
    pub bytes_dropped_eeprom: u64,
    /// Bytes lost while the controller was off or in its bootloader after a reset (`boot_ms`).
    #[serde(default)]
    pub bytes_dropped_boot: u64,
    /// Bytes corrupted by fault injection.
    pub bytes_corrupted: u64,
    /// Highest RX buffer fill seen, bytes.
    pub max_rx_fill: usize,
    /// Highest planner fill seen, blocks.
    pub max_planner_fill: usize,
    /// Times motion stopped because the planner ran dry while running.
    pub planner_starvations: u64,
    /// Lines received (every line terminator counts).
    pub lines_received: u32,
    /// `ok` responses sent.
    pub oks: u64,
    /// `error:N` responses sent.
    pub errors: u64,
    /// `ALARM:N` sent.
    pub alarms: u64,
    /// Soft resets (realtime 0x18, `$C` off, faults).
    pub resets: u64,
    /// Bytes written to the link.
    pub bytes_sent: u64,
}

/// What [`PtySim::stop`] returns.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SimReport {
    /// Every executed motion.
    pub trace: Vec<TraceSegment>,
    /// Counters.
    pub stats: SimStats,
    /// Simulated time at stop, s.
    pub sim_time: f64,
}
