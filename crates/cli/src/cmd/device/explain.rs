//! What a stopped send tells the operator: the sender's error, and what to do next.

use flatcut_device::grbl::SendError;
use std::path::Path;

use super::args::StreamArgs;

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
    let port = match &args.port {
        Some(p) => format!(" --port {p}"),
        None => String::new(),
    };
    if let SendError::ResumeUncertain { from, .. } = &e {
        let hint = format!(
            "Resume explicitly from the first line to cut with --resume-from LINE (a line number of the file). For example, if line {} never started: flatcut send {name}{port} --resume-from {}",
            from.source_line, from.source_line
        );
        return anyhow::Error::new(StreamError {
            error: e,
            hint: Some(hint),
        });
    }
    let flag_hint = match &e {
        SendError::AlarmLocked { .. } => Some(
            "Home the machine, or add --unlock to send $X if the machine position is known to be right."
                .to_string(),
        ),
        SendError::LaserModeOff => Some(
            "Set $32=1 on the controller (or, with `flatcut run`, add --force to stream anyway)."
                .to_string(),
        ),
        SendError::PausedByJob { .. } => Some(
            "Choose what a program pause does with --on-pause resume|abort|wait, or run on a terminal to be asked."
                .to_string(),
        ),
        SendError::PositionUnknown { .. } | SendError::OriginNotConfirmed { .. } => Some(
            "Home the machine, or set its work origin back where it was, then resume with --origin-confirmed (on a terminal, the resume asks)."
                .to_string(),
        ),
        SendError::OffPath(off) => Some(format!(
            "A line was probably damaged on the link (GRBL's link has no checksum): check the cable, its shielding and the baud rate. Look at the work, then continue with --resume-from LINE, for example the first line of the range: flatcut send {name}{port} --resume-from {}",
            off.from.source_line
        )),
        SendError::JobChanged { .. } => Some(format!(
            "If the change is meant (a bad line fixed), resume with --accept-changed-job (on a terminal, the resume asks): flatcut send {name}{port} --resume --accept-changed-job"
        )),
        SendError::JobChangedWhereItRan { .. } => Some(format!(
            "Look at the work, then continue from the first line to cut of the edited file: flatcut send {name}{port} --resume-from LINE --accept-changed-job"
        )),
        SendError::ResumeFromOutOfRange { .. } => {
            Some("--resume-from takes a line number of the file that has a line to send.".to_string())
        }
        SendError::OutOfTravel { .. } if args.uses_sim() => Some(if args.sim_machine.is_some() {
            "The embedded simulator is the machine the profile describes: the job must fit its work area."
                .to_string()
        } else {
            "The embedded simulator is GRBL's default machine (200 mm of travel on each axis): give it the machine's profile with --profile, or its travel with --sim-set 130=X --sim-set 131=Y."
                .to_string()
        }),
        SendError::OffsetsUnknown { .. } => Some(
            "Let the controller come to Idle and try again, or add --discard-offsets to run in G54 without G92."
                .to_string(),
        ),
        _ => None,
    };
    if flag_hint.is_some() {
        return anyhow::Error::new(StreamError {
            error: e,
            hint: flag_hint,
        });
    }
    let hint = resumable.then(|| {
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
            && flatcut_device::grbl::codes::alarm_is_critical(*code)
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
