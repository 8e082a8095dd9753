//! What a stopped send tells the operator: the sender's error, and what to do next.

use flatcut_grbl::SendError;
use std::path::Path;

use super::StreamArgs;

/// A send that stopped: the sender's error, and what to do next. Its message is the whole story
/// (the sender's message names the line, the code's meaning and the last line executed), so it
/// reports no separate source; [`StreamError::send_error`] gives the typed error.
#[derive(Debug)]
pub struct StreamError {
    error: SendError,
    hint: Option<String>,
}

impl StreamError {
    /// The sender's typed error.
    pub fn send_error(&self) -> &SendError {
        &self.error
    }
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(h) = &self.hint {
            write!(f, "\n{h}")?;
        }
        Ok(())
    }
}

impl std::error::Error for StreamError {}

/// Turns a send error into a message that says what to do next.
pub(super) fn explain(
    e: SendError,
    name: &str,
    args: &StreamArgs,
    journal: &Path,
) -> anyhow::Error {
    let resumable = matches!(
        e,
        SendError::Transport { .. }
            | SendError::LineRejected { .. }
            | SendError::Alarm { .. }
            | SendError::UnexpectedReset { .. }
            | SendError::LostAck { .. }
            | SendError::DeviceSilent { .. }
            | SendError::Aborted { .. }
            | SendError::UnexpectedState { .. }
    );
    if let SendError::ResumeUncertain { from, .. } = &e {
        let port = match &args.port {
            Some(p) => format!(" --port {p}"),
            None => String::new(),
        };
        let hint = format!(
            "For example, if line {} never started: flatcut send {name}{port} --resume-from {}",
            from.source_line, from.source_line
        );
        return anyhow::Error::new(StreamError {
            error: e,
            hint: Some(hint),
        });
    }
    let hint = resumable.then(|| {
        let port = match &args.port {
            Some(p) => format!(" --port {p}"),
            None => String::new(),
        };
        let journal_flag = match &args.journal {
            Some(p) => format!(" --journal {}", p.display()),
            None => String::new(),
        };
        let mut h = format!(
            "The journal {} records what ran; after fixing the cause, continue after the last \
             completed line with: flatcut send {name}{port}{journal_flag} --resume",
            journal.display()
        );
        if let SendError::Alarm { code: 3, .. } = &e {
            h.push_str(
                " (the reset in motion lost the position: the resume will ask for --resume-from \
                 LINE after the machine is homed or its origin set again)",
            );
        }
        if let SendError::Alarm { code, .. } = &e
            && flatcut_grbl::codes::alarm_is_critical(*code)
        {
            h.push_str(
                " (the controller will be alarm-locked: home it first, or add --unlock only if \
                 the machine position is known to be right)",
            );
        }
        h
    });
    anyhow::Error::new(StreamError { error: e, hint })
}
