//! [`DeviceError`]: why a device could not be opened or could not do what it was asked.

use flatcut_firmware_sim::ConfigError;
use flatcut_grbl::{SendError, TransportError};
use thiserror::Error;

/// Why a device could not be opened or could not do what it was asked. A job's own failure is
/// a [`SendError`] (from [`crate::JobHandle::wait`]).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum DeviceError {
    /// The serial port is not there (unplugged, a typo, a simulator that is not running).
    #[error("the serial port {path} does not exist")]
    PortMissing {
        /// The path given.
        path: String,
    },
    /// The serial port is there but could not be opened.
    #[error("cannot open the serial port {path}")]
    Open {
        /// The path given.
        path: String,
        /// Why.
        source: TransportError,
    },
    /// The embedded simulator's set-up is invalid (a setting GRBL refuses, a time scale of 0).
    #[error("the embedded simulator's options are invalid")]
    SimConfig(#[source] ConfigError),
    /// The embedded simulator could not start (no pseudo-terminal).
    #[error("cannot start the embedded simulator")]
    Simulator(#[source] std::io::Error),
    /// A job is running: the device takes one job at a time, and nothing else meanwhile but
    /// hold, resume, stop and the operator's answers.
    #[error("a job is running on {device}: it takes one job at a time")]
    Busy {
        /// The device.
        device: String,
    },
    /// Hold, resume or stop with no job running.
    #[error("no job is running on {device}")]
    NoJob {
        /// The device.
        device: String,
    },
    /// An answer to a question that is not (or no longer) asked.
    #[error("question {0} is not open (answered, withdrawn, or never asked)")]
    NoQuestion(u64),
    /// The controller refused or failed what it was asked (a command outside a job).
    #[error(transparent)]
    Controller(#[from] SendError),
    /// "Resume from line N" names a line of the file after which nothing is sent.
    #[error("the job {job} has nothing to send from line {line} on")]
    NothingFrom {
        /// The job's name.
        job: String,
        /// The 1-based line of the file given.
        line: usize,
    },
    /// A GRBL command or a G-code job asked of an HP-GL plotter.
    #[error("{device} is an HP-GL plotter: it takes no {what} (GRBL controllers only)")]
    NotGrbl {
        /// The device.
        device: String,
        /// What was asked.
        what: &'static str,
    },
    /// An HP-GL job asked of a GRBL device.
    #[error("{device} is a GRBL device: it takes G-code, not HP-GL")]
    NotPlotter {
        /// The device.
        device: String,
    },
    /// The device was closed (its link failed or it was shut).
    #[error("the device {device} is closed")]
    Closed {
        /// The device.
        device: String,
    },
}
