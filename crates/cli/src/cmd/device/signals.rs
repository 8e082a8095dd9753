//! Signals: the process-wide Ctrl-C (SIGTERM, SIGHUP) handler, which the binary installs once
//! at start ([`install_handler`]), and the prompt thread that turns a signal during a send into
//! feed hold, resume or abort.

use std::io::{BufRead, IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex, OnceLock};

use flatcut_device::grbl::CancelToken;
use indicatif::{ProgressBar, ProgressDrawTarget};

/// What the prompt thread hears about.
pub(super) enum Ev {
    /// Ctrl-C.
    Interrupt,
    /// A line typed at the "[r]esume or [a]bort?" prompt (`None`: stdin closed).
    Answer(Option<String>),
    /// The job paused itself (`M0`) at this line; the operator decides.
    Pause(String),
    /// The send is over.
    Done,
}

/// The process-wide Ctrl-C handler (the `ctrlc` crate allows one per process) forwards to the
/// most recently registered stream or simulator still running; with none, Ctrl-C exits (130).
/// With ctrlc's `termination` feature SIGTERM and SIGHUP come through the same handler (it does
/// not say which signal it was): a service manager stopping `flatcut send`, or a closed
/// terminal, gets the feed hold and then the abort (stdin is not a terminal, or reading the
/// answer fails), never a controller left running with a dead sender.
static SINK: Mutex<Vec<(u64, Sender<Ev>, Option<CancelToken>)>> = Mutex::new(Vec::new());
/// Registration ids, so a finishing stream unregisters itself and nobody else.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
static HANDLER: OnceLock<Result<(), String>> = OnceLock::new();

/// Installs the process's handler of SIGINT, SIGTERM and SIGHUP (once; later calls say how the
/// first went). Without a send or a simulator registered, a signal stops a running flattening
/// or split at its cancel flag ([`crate::stop`]; a second one ends the process), or else
/// removes the command's temporary outputs and ends the process (130). An embedding program that owns its signals
/// does not call it.
pub fn install_handler() -> Result<(), String> {
    HANDLER
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                let sink = SINK.lock().unwrap_or_else(|p| p.into_inner());
                match sink.last() {
                    Some((_, tx, _)) if tx.send(Ev::Interrupt).is_ok() => {}
                    // A send whose prompt thread is gone still stops safely: the streaming
                    // thread aborts (feed hold, soft reset, tool off) and returns.
                    Some((_, _, Some(cancel))) => cancel.abort(),
                    // A flattening or split stops at its cancel flag and writes nothing.
                    _ if crate::stop::interrupt() => {}
                    _ => {
                        // No stream to stop: the command ends here, leaving no temporary file.
                        crate::output::remove_staged();
                        std::process::exit(130)
                    }
                }
            })
            .map_err(|e| e.to_string())
        })
        .clone()
}

/// A registration with the Ctrl-C handler; unregisters on drop.
pub(super) struct Interrupts {
    id: u64,
    pub(super) tx: Sender<Ev>,
    rx: Mutex<Option<Receiver<Ev>>>,
}

impl Interrupts {
    /// Registers a receiver of Ctrl-C (SIGTERM, SIGHUP) with the handler [`install_handler`]
    /// put in place; `cancel` is aborted directly when nothing listens any more.
    pub(super) fn register(cancel: Option<CancelToken>) -> Interrupts {
        let (tx, rx) = channel();
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        SINK.lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((id, tx.clone(), cancel));
        Interrupts {
            id,
            tx,
            rx: Mutex::new(Some(rx)),
        }
    }

    pub(super) fn take_receiver(&self) -> Receiver<Ev> {
        match self.rx.lock().unwrap_or_else(|p| p.into_inner()).take() {
            Some(rx) => rx,
            // Only called once per registration; a second call gets a closed channel.
            None => channel().1,
        }
    }

    pub(super) fn done(&self) {
        let _ = self.tx.send(Ev::Done);
    }
}

impl Drop for Interrupts {
    fn drop(&mut self) {
        SINK.lock()
            .unwrap_or_else(|p| p.into_inner())
            .retain(|(id, _, _)| *id != self.id);
    }
}

/// Blocks until Ctrl-C (for `flatcut sim`); the binary's handler must be in place
/// ([`install_handler`]).
pub fn wait_for_interrupt() {
    let i = Interrupts::register(None);
    let rx = i.take_receiver();
    loop {
        match rx.recv() {
            Ok(Ev::Interrupt) | Err(_) => return,
            Ok(_) => {}
        }
    }
}

/// The question after a feed hold.
const HOLD_QUESTION: &str = "\nfeed hold: [r]esume or [a]bort (soft reset, tool off)? ";

/// Ctrl-C policy (SIGTERM and SIGHUP alike): the first one holds the feed and asks "[r]esume or
/// [a]bort?" on the terminal (abort at once when stdin is not a terminal); a second one while
/// asking aborts. Abort = feed hold, soft reset, tool off, journal flushed, and a message naming
/// the last line executed.
pub(super) fn prompt_loop(
    rx: Receiver<Ev>,
    answers: Sender<Ev>,
    cancel: CancelToken,
    bar: ProgressBar,
    interactive: bool,
    prompting: Arc<AtomicBool>,
) {
    // Writes to a terminal that may be gone (SIGHUP): a failed write must not end this thread,
    // which is what turns the next answer or signal into an abort.
    let say = |text: &str| {
        let mut e = std::io::stderr();
        let _ = e.write_all(text.as_bytes());
        let _ = e.flush();
    };
    let ask = |question: &str| {
        say(question);
        // The stdin read blocks, so it runs on its own thread and answers through the channel.
        let tx = answers.clone();
        std::thread::spawn(move || {
            let mut line = String::new();
            let answer = match std::io::stdin().lock().read_line(&mut line) {
                Ok(0) | Err(_) => None,
                Ok(_) => Some(line),
            };
            let _ = tx.send(Ev::Answer(answer));
        });
    };
    let restore = |bar: &ProgressBar| {
        prompting.store(false, Ordering::Relaxed);
        if interactive {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    };
    let mut asking = false;
    for ev in rx {
        match ev {
            Ev::Done => return,
            // Ctrl-C while the sender waits for the operator's word (the origin question):
            // the answer is no, and the send ends with nothing moved.
            Ev::Interrupt if !asking && prompting.load(Ordering::Relaxed) => {
                say("\ninterrupted: not confirmed; aborting\n");
                cancel.abort();
            }
            Ev::Interrupt if asking || cancel.is_aborted() => {
                say("\naborting: soft reset, tool off\n");
                cancel.abort();
                asking = false;
                restore(&bar);
            }
            Ev::Interrupt => {
                cancel.hold();
                if !std::io::stdin().is_terminal() {
                    say("\ninterrupted: feed hold, then abort (stdin is not a terminal)\n");
                    cancel.abort();
                    continue;
                }
                prompting.store(true, Ordering::Relaxed);
                bar.set_draw_target(ProgressDrawTarget::hidden());
                asking = true;
                ask(HOLD_QUESTION);
            }
            Ev::Pause(line) if !asking => {
                prompting.store(true, Ordering::Relaxed);
                bar.set_draw_target(ProgressDrawTarget::hidden());
                asking = true;
                ask(&format!(
                    "\npaused by the job at {line}: [r]esume or [a]bort (soft reset, tool off)? "
                ));
            }
            Ev::Pause(_) => {}
            Ev::Answer(a) if asking => {
                match a.as_deref().map(|s| s.trim().to_ascii_lowercase()) {
                    Some(s) if s == "r" || s == "resume" => {
                        say("resuming (cycle start)\n");
                        cancel.resume();
                    }
                    Some(s) if s == "a" || s == "abort" => {
                        say("aborting: soft reset, tool off\n");
                        cancel.abort();
                    }
                    None => {
                        say("stdin closed: aborting\n");
                        cancel.abort();
                    }
                    Some(_) => {
                        ask("[r]esume or [a]bort? ");
                        continue;
                    }
                }
                asking = false;
                restore(&bar);
            }
            Ev::Answer(_) => {}
        }
    }
}
