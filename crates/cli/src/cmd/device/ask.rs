//! The sender's questions at the terminal: when a send needs the operator's word (a resume
//! whose machine position is unknown), the library states why and what it knows, and this asks
//! on the terminal; without a terminal nobody is asked and the send refuses.

use std::io::{BufRead, IsTerminal, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use flatcut_grbl::{Operator, Question};
use indicatif::{ProgressBar, ProgressDrawTarget};

/// The operator at this terminal, if stdin is one: shows the question with the progress bar
/// hidden and reads the answer; only `y` or `yes` confirms.
pub(super) fn terminal_operator(
    bar: &ProgressBar,
    interactive: bool,
    prompting: &Arc<AtomicBool>,
) -> Option<Operator> {
    if !std::io::stdin().is_terminal() {
        return None;
    }
    let (bar, prompting) = (bar.clone(), prompting.clone());
    Some(Operator::new(move |q: &Question| {
        prompting.store(true, Ordering::Relaxed);
        bar.set_draw_target(ProgressDrawTarget::hidden());
        let mut e = std::io::stderr();
        // A terminal that is gone cannot answer: the read below then fails, which is a "no".
        let _ = write!(e, "\n{q}\n{}", q.prompt());
        let _ = e.flush();
        let mut line = String::new();
        let read = std::io::stdin().lock().read_line(&mut line);
        prompting.store(false, Ordering::Relaxed);
        if interactive {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        matches!(read, Ok(n) if n > 0) && is_yes(&line)
    }))
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
