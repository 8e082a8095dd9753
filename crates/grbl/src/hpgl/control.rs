//! Steering an HP-GL stream from another thread: [`HpglControl`] (pause, resume, abort), and
//! [`Steering`], what the streamer asks of it (an `AtomicBool` is an abort-only control).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// What the streamer asks between writes: whether to stop, whether to hold at the next
/// instruction boundary.
pub trait Steering {
    /// The stream is to end (`ESC.K`, `PU;`).
    fn aborted(&self) -> bool;
    /// The stream is to stop feeding at the next instruction boundary, pen up, until this is
    /// false again.
    fn paused(&self) -> bool;
}

impl Steering for AtomicBool {
    fn aborted(&self) -> bool {
        self.load(Ordering::SeqCst)
    }
    fn paused(&self) -> bool {
        false
    }
}

#[derive(Debug, Default)]
struct State {
    pause: AtomicBool,
    abort: AtomicBool,
}

/// A handle that pauses, resumes and aborts a running HP-GL stream; clones steer the same one.
#[derive(Debug, Clone, Default)]
pub struct HpglControl {
    state: Arc<State>,
}

impl HpglControl {
    /// A new control: not paused, not aborted.
    pub fn new() -> HpglControl {
        HpglControl::default()
    }
    /// Pause at the next instruction boundary, pen up.
    pub fn pause(&self) {
        self.state.pause.store(true, Ordering::SeqCst);
    }
    /// Go on after a pause, the pen put back as it was.
    pub fn resume(&self) {
        self.state.pause.store(false, Ordering::SeqCst);
    }
    /// End the stream: `ESC.K` (the device drops its buffer) and `PU;`.
    pub fn abort(&self) {
        self.state.abort.store(true, Ordering::SeqCst);
    }
    /// Whether a pause is asked for.
    pub fn is_paused(&self) -> bool {
        self.state.pause.load(Ordering::SeqCst)
    }
    /// Whether an abort was asked for.
    pub fn is_aborted(&self) -> bool {
        self.state.abort.load(Ordering::SeqCst)
    }
}

impl Steering for HpglControl {
    fn aborted(&self) -> bool {
        self.is_aborted()
    }
    fn paused(&self) -> bool {
        self.is_paused()
    }
}
