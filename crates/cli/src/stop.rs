//! Ctrl-C during a long computation (a flattening, a `--split auto`, a project's stages): the
//! first signal sets the library's cancel flag ([`flatcut::flatten::FlattenHooks::with_cancel`]),
//! which the split's candidates, the Newton solves and the joint solve check between steps; the
//! command then ends with [`Interrupted`] (exit [`EXIT_INTERRUPTED`]) and writes nothing. A
//! second Ctrl-C ends the process at once, as it does when nothing is being computed.
//!
//! The process-wide handler (`cmd::device::install_handler`) asks [`interrupt`] first when no
//! send is streaming.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use flatcut::flatten::FlattenHooks;

/// Exit code of a command stopped by Ctrl-C (SIGINT, SIGTERM, SIGHUP): 128 + SIGINT, the
/// shell's convention, as the handler's immediate exit.
pub const EXIT_INTERRUPTED: u8 = 130;

/// The computations that Ctrl-C stops, most recent last.
static RUNNING: Mutex<Vec<(u64, Arc<AtomicBool>)>> = Mutex::new(Vec::new());
/// Registration ids, so a finishing computation unregisters itself and nobody else.
static NEXT_ID: AtomicU64 = AtomicU64::new(0);

/// A command stopped by Ctrl-C before it wrote anything.
#[derive(Debug)]
pub struct Interrupted {
    /// What was running, e.g. "the flattening of ball.obj".
    pub what: String,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "interrupted (Ctrl-C) during {}: stopped, nothing written",
            self.what
        )
    }
}

impl std::error::Error for Interrupted {}

/// A computation that Ctrl-C stops; unregisters on drop.
pub struct Stoppable {
    id: u64,
    flag: Arc<AtomicBool>,
}

impl Stoppable {
    /// Registers a new cancel flag with the Ctrl-C handler.
    pub fn register() -> Stoppable {
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        let flag = Arc::new(AtomicBool::new(false));
        running().push((id, flag.clone()));
        Stoppable { id, flag }
    }

    /// The flag itself, for computations that take a bare flag (the nesting).
    pub fn flag(&self) -> Arc<AtomicBool> {
        self.flag.clone()
    }

    /// `hooks` that stop at this flag.
    pub fn hooks(&self, hooks: FlattenHooks) -> FlattenHooks {
        hooks.with_cancel(self.flag.clone())
    }

    /// [`Interrupted`] (naming `what`) once Ctrl-C came, whatever the computation returned: a
    /// result finished after the signal is not written either.
    pub fn check(&self, what: impl FnOnce() -> String) -> Result<(), Interrupted> {
        if self.flag.load(Ordering::SeqCst) {
            Err(Interrupted { what: what() })
        } else {
            Ok(())
        }
    }
}

impl Drop for Stoppable {
    fn drop(&mut self) {
        running().retain(|(id, _)| *id != self.id);
    }
}

fn running() -> std::sync::MutexGuard<'static, Vec<(u64, Arc<AtomicBool>)>> {
    RUNNING.lock().unwrap_or_else(|p| p.into_inner())
}

/// For the signal handler: sets the most recent computation's cancel flag and says so. False
/// when nothing is running or its flag was already set (a second Ctrl-C): the handler then
/// ends the process.
pub fn interrupt() -> bool {
    let Some(flag) = running().last().map(|(_, f)| f.clone()) else {
        return false;
    };
    if flag.swap(true, Ordering::SeqCst) {
        return false;
    }
    eprintln!("\ninterrupted: stopping; nothing will be written (Ctrl-C again ends at once)");
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_interrupt_sets_the_flag_and_the_second_is_refused() {
        let s = Stoppable::register();
        assert!(s.check(|| "x".into()).is_ok());
        assert!(!s.hooks(FlattenHooks::default()).cancelled());
        assert!(interrupt());
        assert!(s.hooks(FlattenHooks::default()).cancelled());
        let e = s.check(|| "the split of ball.obj".into()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "interrupted (Ctrl-C) during the split of ball.obj: stopped, nothing written"
        );
        assert!(!interrupt());
        drop(s);
        assert!(!interrupt(), "nothing registered any more");
    }
}
