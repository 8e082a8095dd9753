//! The device a job is streamed to, from the command line: a serial port, or — with no `--port`
//! — the embedded GRBL simulator, so the whole pipeline runs on any machine. The session itself
//! (choosing and opening the device, streaming, journal, resume questions, events) is the
//! `flatcut-device` library; this module is flags, terminal and files.
//!
//! One concern per module: `args` (the flags and what they mean to the library), `select` (a
//! project's device), `stream` (a job streamed and its outcome), `watch` (a running job at the
//! terminal), `view` (how it is drawn), `status` (its one-line state), `ask` (the
//! sender's questions at the terminal), `signals` (Ctrl-C, SIGTERM, SIGHUP and the prompt),
//! `explain` (what a stopped send tells the operator), `evidence` (the simulator's files).
//! This module only names them.

mod args;
mod ask;
mod evidence;
mod explain;
pub mod select;
mod signals;
mod status;
mod stream;
mod view;
mod watch;

pub use args::{DEFAULT_BAUD, DEFAULT_SIM_SPEED, OnPause, StreamArgs};
pub use explain::StreamError;
pub use signals::{install_handler, wait_for_interrupt};
pub use stream::{
    StreamOutcome, stream_file, stream_file_with_control, stream_text, stream_text_with_control,
};
pub use watch::PLAIN_PROGRESS_INTERVAL;

#[cfg(test)]
mod tests;
