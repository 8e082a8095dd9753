//! [`CancelToken`]: feed hold, resume and abort requested from another thread while a send runs.

use std::sync::{Arc, Mutex};

#[derive(Debug, Default)]
pub(super) struct ControlState {
    pub(super) hold: bool,
    pub(super) resume: bool,
    pub(super) abort: bool,
}

/// A handle to steer a running [`super::send_job`] from another thread (the CLI's Ctrl-C handler):
/// feed hold, resume (cycle start) and abort (feed hold, then soft reset; tool off).
#[derive(Debug, Clone, Default)]
pub struct CancelToken {
    inner: Arc<Mutex<ControlState>>,
}

/// The same handle under the name the CLI uses.
pub type Control = CancelToken;

impl CancelToken {
    /// A new, untriggered token.
    pub fn new() -> CancelToken {
        CancelToken::default()
    }

    fn with<R>(&self, f: impl FnOnce(&mut ControlState) -> R) -> R {
        let mut g = match self.inner.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        f(&mut g)
    }

    /// Requests a feed hold (`!`).
    pub fn hold(&self) {
        self.with(|s| s.hold = true);
    }

    /// Requests a resume (`~`) after a hold.
    pub fn resume(&self) {
        self.with(|s| s.resume = true);
    }

    /// Requests an abort: feed hold, then soft reset, which turns the tool off.
    pub fn abort(&self) {
        self.with(|s| s.abort = true);
    }

    /// Whether an abort was requested.
    pub fn is_aborted(&self) -> bool {
        self.with(|s| s.abort)
    }

    pub(super) fn take(&self) -> ControlState {
        self.with(std::mem::take)
    }
}
