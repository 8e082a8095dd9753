//! The sender's questions at the terminal: when a send needs the operator's word (a resume
//! whose machine position is unknown, a job file edited since its journal), the device library
//! states why and what it knows, and this asks on the terminal. Without a terminal nobody is
//! asked (the job is started without questions) and the send refuses.

use std::io::{BufRead, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

use flatcut_device::grbl::{CancelToken, Question};
use indicatif::{ProgressBar, ProgressDrawTarget};

/// How often a question waiting for its answer looks whether the send was aborted.
const ABORT_POLL: Duration = Duration::from_millis(50);

/// Asks `q` at this terminal: shows the question with the progress bar hidden and reads the
/// answer; only `y` or `yes` confirms. Ctrl-C while it waits aborts the send (the prompt loop
/// sees `prompting` set), and the question returns its safe "no" at once rather than waiting
/// for a line that may never come.
pub(super) fn at_terminal(
    q: &Question,
    bar: &ProgressBar,
    interactive: bool,
    prompting: &Arc<AtomicBool>,
    cancel: &CancelToken,
) -> bool {
    prompting.store(true, Ordering::Relaxed);
    bar.set_draw_target(ProgressDrawTarget::hidden());
    let mut e = std::io::stderr();
    // A terminal that is gone cannot answer: the read then fails, which is a "no".
    let _ = write!(e, "\n{q}\n{}", q.prompt());
    let _ = e.flush();
    // The stdin read blocks, so it runs on its own thread; an abort does not wait for it.
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let read = std::io::stdin().lock().read_line(&mut line);
        let _ = tx.send(matches!(read, Ok(n) if n > 0).then_some(line));
    });
    let answer = loop {
        if cancel.is_aborted() {
            break None;
        }
        match rx.recv_timeout(ABORT_POLL) {
            Ok(line) => break line,
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break None,
        }
    };
    prompting.store(false, Ordering::Relaxed);
    if interactive {
        bar.set_draw_target(ProgressDrawTarget::stderr());
    }
    answer.is_some_and(|l| is_yes(&l))
}

/// Whether an answer is a yes: `y` or `yes`, in any case; anything else is the safe no.
pub(super) fn is_yes(answer: &str) -> bool {
    matches!(answer.trim().to_ascii_lowercase().as_str(), "y" | "yes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_y_or_yes_confirms() {
        for a in ["y\n", "Y", " yes \n", "YES"] {
            assert!(is_yes(a), "{a:?}");
        }
        for a in ["", "\n", "n", "no", "yess", "ja", "y y"] {
            assert!(!is_yes(a), "{a:?}");
        }
    }
}
