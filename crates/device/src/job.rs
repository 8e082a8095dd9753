//! A job for a device: what to stream and how ([`JobRequest`]), the handle that steers it and
//! waits for its end ([`JobHandle`]), and what a completed job did ([`JobOutcome`]).

use crate::error::DeviceError;
use flatcut_grbl::{CancelToken, Job, JobError, SendError, SendOptions, SendReport};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

/// A job to stream, from memory.
#[derive(Debug, Clone)]
pub struct JobRequest {
    /// What messages call the job (its file name, say).
    pub name: String,
    /// The job.
    pub job: Job,
    /// How to send it: journal, resume, timeouts, policies.
    pub options: SendOptions,
    /// Steers it (hold, resume, stop); the device's own hold, resume and stop use it too.
    pub control: CancelToken,
    /// Put the operator's questions to the device's subscribers ([`crate::DeviceEvent::Question`])
    /// and wait for [`crate::Device::answer`]; without it nobody is asked and the job refuses
    /// where it would have to ask (as the sender does with nobody there).
    pub ask: bool,
}

impl JobRequest {
    /// A job called `name`, sent with default options.
    pub fn new(name: impl Into<String>, job: Job) -> JobRequest {
        JobRequest {
            name: name.into(),
            job,
            options: SendOptions::default(),
            control: CancelToken::new(),
            ask: false,
        }
    }

    /// Parses the G-code `text` (held in memory: nothing is written to disk) into a job called
    /// `name`.
    pub fn parse(name: impl Into<String>, text: &str) -> Result<JobRequest, JobError> {
        Ok(JobRequest::new(name, Job::parse(text)?))
    }

    /// Sets [`JobRequest::options`].
    pub fn with_options(mut self, o: SendOptions) -> Self {
        self.options = o;
        self
    }

    /// Sets [`JobRequest::control`].
    pub fn with_control(mut self, c: CancelToken) -> Self {
        self.control = c;
        self
    }

    /// Resumes the job from line `line` of its file (1-based; a blank or comment line means the
    /// next line sent), whatever its journal says ran: the operator's answer when a resume
    /// cannot tell which lines ran (`flatcut send --resume-from`). The sender settles the
    /// journal from there, and asks or checks as for any resume (the work origin when the
    /// position is lost, an edited job). Keep the other options set first:
    /// [`JobRequest::with_options`] replaces them.
    pub fn resume_from_line(mut self, line: usize) -> Result<JobRequest, DeviceError> {
        let index = self
            .job
            .first_line_from(line)
            .ok_or_else(|| DeviceError::NothingFrom {
                job: self.name.clone(),
                line,
            })?;
        self.options = self.options.with_resume_from(Some(index));
        Ok(self)
    }

    /// Sets [`JobRequest::ask`].
    pub fn with_questions(mut self, on: bool) -> Self {
        self.ask = on;
        self
    }
}

/// What a completed job did.
#[derive(Debug, Clone, PartialEq)]
pub struct JobOutcome {
    /// The job's name.
    pub name: String,
    /// The sender's report.
    pub report: SendReport,
}

/// A running job: steer it, and wait for its end.
#[derive(Debug)]
pub struct JobHandle {
    pub(crate) control: CancelToken,
    pub(crate) done: Receiver<Result<JobOutcome, SendError>>,
}

impl JobHandle {
    /// The job's controls (hold, resume, stop), to hand to another thread.
    pub fn control(&self) -> &CancelToken {
        &self.control
    }

    /// Waits for the job's end.
    pub fn wait(self) -> Result<JobOutcome, SendError> {
        self.done.recv().unwrap_or_else(|_| Err(gone()))
    }

    /// The job's end if it came within `timeout`; the handle back otherwise.
    pub fn wait_timeout(self, timeout: Duration) -> Result<Result<JobOutcome, SendError>, Self> {
        match self.done.recv_timeout(timeout) {
            Ok(r) => Ok(r),
            Err(RecvTimeoutError::Timeout) => Err(self),
            Err(RecvTimeoutError::Disconnected) => Ok(Err(gone())),
        }
    }
}

/// The device's worker ended without an answer (it cannot, short of a panic).
fn gone() -> SendError {
    SendError::Transport {
        source: flatcut_grbl::TransportError::HangUp("the device's worker stopped".into()),
        last_done: None,
    }
}
