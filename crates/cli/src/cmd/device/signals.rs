//! Signals during a send: the process-wide Ctrl-C (SIGTERM, SIGHUP) handler, and the prompt
//! thread that turns them into feed hold, resume or abort.

use std::io::{BufRead, IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex, OnceLock};

use flatcut_grbl::CancelToken;
use indicatif::{ProgressBar, ProgressDrawTarget};

/// What the prompt thread hears about.
pub(super) enum Ev {
    /// Ctrl-C.
    Interrupt,
    /// A line typed at the "[r]esume or [a]bort?" prompt (`None`: stdin closed).
    Answer(Option<String>),
    /// The send is over.
    Done,
}

/// The process-wide Ctrl-C handler (the `ctrlc` crate allows one per process) forwards to the
/// most recently registered stream or simulator still running; with none, Ctrl-C exits (130).
/// With ctrlc's `termination` feature SIGTERM and SIGHUP come through the same handler (it does
/// not say which signal it was): a service manager stopping `flatcut send`, or a closed
/// terminal, gets the feed hold and then the abort (stdin is not a terminal, or reading the
/// answer fails), never a controller left running with a dead sender.
static SINK: Mutex<Vec<(u64, Sender<Ev>)>> = Mutex::new(Vec::new());
/// Registration ids, so a finishing stream unregisters itself and nobody else.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
static HANDLER: OnceLock<Result<(), String>> = OnceLock::new();

fn install_handler() -> Result<(), String> {
    HANDLER
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                let sink = SINK.lock().unwrap_or_else(|p| p.into_inner());
                match sink.last() {
                    Some((_, tx)) if tx.send(Ev::Interrupt).is_ok() => {}
                    _ => std::process::exit(130),
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
    pub(super) fn register() -> anyhow::Result<Interrupts> {
        install_handler().map_err(|e| anyhow::anyhow!("cannot install the Ctrl-C handler: {e}"))?;
        let (tx, rx) = channel();
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        SINK.lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((id, tx.clone()));
        Ok(Interrupts {
            id,
            tx,
            rx: Mutex::new(Some(rx)),
        })
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
            .retain(|(id, _)| *id != self.id);
    }
}

/// Blocks until Ctrl-C (for `flatcut sim`). Errors if no handler can be installed.
pub(crate) fn wait_for_interrupt() -> anyhow::Result<()> {
    let i = Interrupts::register()?;
    let rx = i.take_receiver();
    loop {
        match rx.recv() {
            Ok(Ev::Interrupt) | Err(_) => return Ok(()),
            Ok(_) => {}
        }
    }
}

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
    let ask = || {
        eprint!("\nfeed hold: [r]esume or [a]bort (soft reset, tool off)? ");
        let _ = std::io::stderr().flush();
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
            Ev::Interrupt if asking || cancel.is_aborted() => {
                eprintln!("\naborting: soft reset, tool off");
                cancel.abort();
                asking = false;
                restore(&bar);
            }
            Ev::Interrupt => {
                cancel.hold();
                if !std::io::stdin().is_terminal() {
                    eprintln!("\ninterrupted: feed hold, then abort (stdin is not a terminal)");
                    cancel.abort();
                    continue;
                }
                prompting.store(true, Ordering::Relaxed);
                bar.set_draw_target(ProgressDrawTarget::hidden());
                asking = true;
                ask();
            }
            Ev::Answer(a) if asking => {
                match a.as_deref().map(|s| s.trim().to_ascii_lowercase()) {
                    Some(s) if s == "r" || s == "resume" => {
                        eprintln!("resuming (cycle start)");
                        cancel.resume();
                    }
                    Some(s) if s == "a" || s == "abort" => {
                        eprintln!("aborting: soft reset, tool off");
                        cancel.abort();
                    }
                    None => {
                        eprintln!("stdin closed: aborting");
                        cancel.abort();
                    }
                    Some(_) => {
                        ask();
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
