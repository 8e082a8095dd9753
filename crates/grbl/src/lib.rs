//! flatcut-grbl: streams G-code to GRBL 1.1 controllers without dropping or repeating a line.
//!
//! Layers, from the inside out:
//! * [`response`] and [`codes`]: what GRBL says and what its codes mean;
//! * [`job`]: a G-code file prepared for streaming (stripped lines, modal state, lengths, ETA);
//! * [`streamer`]: the sans-IO protocol core (character-counting flow control, realtime bytes,
//!   line ↔ response matching) that never touches a port;
//! * [`transport`]: a byte pipe with timeouts, implemented for serial ports;
//! * [`journal`]: an append-only record of acknowledged lines, for `--resume`;
//! * [`driver`]: the blocking [`send_job`] that runs handshake, check mode, streaming, status
//!   polling, feed hold/abort and journaling over a transport.
//!
//! **Architecture invariant:** never more bytes in flight than the device's RX buffer holds.
#![warn(missing_docs)]

pub mod codes;
pub mod driver;
#[cfg(test)]
mod fake;
pub mod hpgl;
pub mod job;
pub mod job_edit;
pub mod journal;
pub mod response;
pub mod streamer;
pub mod transport;

pub use driver::{
    CancelToken, Console, Control, ControllerInfo, Jog, MachineStatus, Operator, OriginQuestion,
    PausePolicy, Progress, Question, SendError, SendOptions, SendReport, send_job,
};
pub use job::{FeedClamp, Job, JobError, JobLine, JobStart, MachineLimits, ModalState};
pub use job_edit::JobChanges;
pub use journal::{Journal, JournalError, JournalState, LineMap, StopRecord};
pub use response::{MachineState, Response, StatusReport, parse_response};
pub use streamer::{Event, Streamer, Tag};
pub use transport::{SerialTransport, Transport, TransportError, list_ports, open_port};
