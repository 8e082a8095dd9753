//! HP-GL plotters and vinyl cutters as devices: the link's flow control ([`PlotterLink`]), the
//! embedded HP-GL plotter simulator ([`PlotterSimSetup`]), a job of HP-GL bytes
//! ([`PlotRequest`], [`PlotHandle`], [`PlotOutcome`]), its progress ([`PlotProgress`]) and what
//! the embedded plotter drew ([`PlotterReport`]).
//!
//! HP-GL has no acknowledgements: a plot's progress is the bytes the link accepted (and, with the
//! buffer query, the device's free buffer), never what the device has drawn. A pause stops the
//! feed at an instruction boundary and lifts the pen; a resume puts it back; a stop sends
//! `ESC.K` (the device drops its buffer) and `PU;`.

use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

use flatcut_firmware_sim::hpgl::{PenSegment, PlotterConfig, PlotterStats};
use flatcut_grbl::TransportError;
use flatcut_grbl::hpgl::{HpglControl, HpglError, HpglFlow, HpglReport, HpglStreamOptions};

/// How an HP-GL device's serial link works: its flow control, whether it answers the buffer
/// queries (`ESC.B`, `ESC.L`), its baud rate (a profile's `[hpgl]` section says all three).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotterLink {
    /// XON/XOFF or RTS/CTS.
    pub flow: HpglFlow,
    /// Ask the device for its free buffer (`ESC.B`) and never send more.
    pub buffer_query: bool,
    /// Baud rate of the link.
    pub baud: u32,
}

impl PlotterLink {
    /// The streamer's options for this link.
    pub fn stream_options(&self) -> HpglStreamOptions {
        HpglStreamOptions::new(self.flow, self.buffer_query, self.baud)
    }
}

/// The embedded HP-GL plotter simulator: firmware-sim's plotter (a 512-byte buffer that loses
/// bytes when overrun, XON/XOFF, the buffer queries when the link has them) on its own
/// pseudo-terminal, recording its pen strokes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotterSimSetup {
    /// The link it is on (its flow control and queries are the profile's).
    pub link: PlotterLink,
    /// Time scale of its pen motion: 1 is real time.
    pub speed: f64,
}

impl PlotterSimSetup {
    /// The plotter the simulator models: the link's buffer queries, a 512-byte buffer (smaller
    /// than any job worth streaming).
    pub fn config(&self) -> PlotterConfig {
        PlotterConfig {
            buffer_query: self.link.buffer_query,
            ..PlotterConfig::default()
        }
    }
}

/// An HP-GL job to stream, from memory.
#[derive(Debug, Clone)]
pub struct PlotRequest {
    /// What messages call the job (its file name, say).
    pub name: String,
    /// The HP-GL bytes.
    pub bytes: Vec<u8>,
    /// Pauses, resumes and stops it; the device's own hold, resume and stop use it too.
    pub control: HpglControl,
}

impl PlotRequest {
    /// The job `bytes` called `name`.
    pub fn new(name: impl Into<String>, bytes: impl Into<Vec<u8>>) -> PlotRequest {
        PlotRequest {
            name: name.into(),
            bytes: bytes.into(),
            control: HpglControl::new(),
        }
    }
}

/// What a completed plot did.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotOutcome {
    /// The job's name.
    pub name: String,
    /// The streamer's report (bytes, XON/XOFF, queries, pauses, time).
    pub report: HpglReport,
}

/// Where a plot stands: the bytes the link accepted, never what the device drew.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotProgress {
    /// Bytes of the job written to the link.
    pub bytes_sent: usize,
    /// Bytes in the job.
    pub bytes_total: usize,
    /// The device holds the feed (XOFF).
    pub held: bool,
    /// Paused by the operator (the feed stopped at an instruction boundary, the pen lifted).
    pub paused: bool,
    /// Whether the job's pen is down after the last instruction sent.
    pub pen_down: bool,
    /// The free bytes the device reported last (`ESC.B`), when it is asked.
    pub device_free: Option<usize>,
    /// Wall time since the job started.
    pub elapsed: Duration,
    /// Wall time still to send the rest at the rate so far (pauses not counted); `None` before
    /// the first bytes or while paused.
    pub eta: Option<Duration>,
}

impl PlotProgress {
    /// The share of the job's bytes sent, 0 to 1.
    pub fn fraction(&self) -> f64 {
        if self.bytes_total == 0 {
            1.0
        } else {
            self.bytes_sent as f64 / self.bytes_total as f64
        }
    }
}

/// What the embedded HP-GL plotter did: its pen-down strokes (mm), counters, its pen now.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlotterReport {
    /// Pen-down segments in the order drawn (mm).
    pub strokes: Vec<PenSegment>,
    /// Bytes received, lost, buffer high-water, XON/XOFF, queries, aborts, instructions.
    pub stats: PlotterStats,
    /// Whether the pen is down now.
    pub pen_down: bool,
    /// Whether it has executed everything it received.
    pub idle: bool,
}

/// A running plot: steer it, and wait for its end.
#[derive(Debug)]
pub struct PlotHandle {
    pub(crate) control: HpglControl,
    pub(crate) done: Receiver<Result<PlotOutcome, HpglError>>,
}

impl PlotHandle {
    /// The job's controls (pause, resume, abort), to hand to another thread.
    pub fn control(&self) -> &HpglControl {
        &self.control
    }

    /// Waits for the job's end.
    pub fn wait(self) -> Result<PlotOutcome, HpglError> {
        self.done.recv().unwrap_or_else(|_| Err(gone()))
    }

    /// The job's end if it came within `timeout`; the handle back otherwise.
    pub fn wait_timeout(self, timeout: Duration) -> Result<Result<PlotOutcome, HpglError>, Self> {
        match self.done.recv_timeout(timeout) {
            Ok(r) => Ok(r),
            Err(RecvTimeoutError::Timeout) => Err(self),
            Err(RecvTimeoutError::Disconnected) => Ok(Err(gone())),
        }
    }
}

/// The device's worker ended without an answer (it cannot, short of a panic).
fn gone() -> HpglError {
    HpglError::Transport(TransportError::HangUp("the device's worker stopped".into()))
}
