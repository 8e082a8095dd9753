//! The send's terminal output on its own thread: the streaming thread hands over progress
//! snapshots and notices through a channel and never writes itself, so a terminal that stops
//! reading (Ctrl-S, a stalled pipe, a slow remote session) cannot stall the link and starve the
//! machine mid-path. Progress ticks are dropped while the printer is behind (only the newest
//! matters); notices and the final snapshot never are.

use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Sender, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use flatcut_grbl::Progress;
use flatcut_grbl::driver::Phase;
use indicatif::ProgressBar;

use super::display::{phase_name, status_text};

/// Progress ticks allowed to wait for the printer; more are dropped (the next one carries the
/// same figures, newer).
const MAX_PENDING_TICKS: usize = 2;
/// Resolution of the progress bar (it shows the fraction of the path length executed).
pub(super) const BAR_STEPS: u64 = 1000;

/// How the printer shows a send.
pub(super) struct View {
    /// The progress bar (hidden when not on a terminal).
    pub bar: ProgressBar,
    /// The bar is drawn (stderr is a terminal and not `--quiet`).
    pub interactive: bool,
    /// Plain progress lines every `plain_interval` (a log, not `--quiet`).
    pub plain: bool,
    /// Interval of the plain lines.
    pub plain_interval: Duration,
    /// Notices are shown (not `--quiet`; the summary repeats them anyway).
    pub notices: bool,
    /// Machine time to wall-clock time for the ETA (`None`: no ETA).
    pub eta_scale: Option<f64>,
    /// The prompt thread is asking the operator: the bar keeps still.
    pub prompting: Arc<AtomicBool>,
}

enum Msg {
    Tick(Box<Progress>),
    Notice(String),
}

/// The printing thread and the streaming thread's end of its channel.
pub(super) struct Printer {
    tx: Sender<Msg>,
    pending: Arc<AtomicUsize>,
    notices_sent: usize,
    handle: JoinHandle<()>,
}

impl Printer {
    /// Starts the printing thread; plain lines and notices go to `out`, the bar to its own
    /// draw target.
    pub(super) fn spawn(view: View, out: Box<dyn Write + Send>) -> Printer {
        let (tx, rx) = channel::<Msg>();
        let pending = Arc::new(AtomicUsize::new(0));
        let counter = pending.clone();
        let handle = std::thread::spawn(move || {
            let mut out = out;
            let mut last_plain = Instant::now();
            for msg in rx {
                match msg {
                    Msg::Tick(p) => {
                        counter.fetch_sub(1, Ordering::Relaxed);
                        view.tick(&p, &mut last_plain, &mut out);
                    }
                    Msg::Notice(_) if !view.notices => {}
                    Msg::Notice(n) => {
                        let mut write = || {
                            // A log that cannot be written is no reason to stop anything.
                            let _ = writeln!(out, "warning: {n}");
                            let _ = out.flush();
                        };
                        if view.interactive {
                            view.bar.suspend(write);
                        } else {
                            write();
                        }
                    }
                }
            }
            view.bar.finish_and_clear();
        });
        Printer {
            tx,
            pending,
            notices_sent: 0,
            handle,
        }
    }

    /// Called on the streaming thread: queues the new notices and this snapshot, without
    /// waiting for anything (the snapshot is dropped when the printer is behind, unless it is
    /// the last).
    pub(super) fn show(&mut self, p: &Progress) {
        if !self.tx_notices(p) {
            return;
        }
        let last = p.phase == Phase::Done;
        if last || self.pending.load(Ordering::Relaxed) < MAX_PENDING_TICKS {
            self.pending.fetch_add(1, Ordering::Relaxed);
            let _ = self.tx.send(Msg::Tick(Box::new(p.clone())));
        }
    }

    /// Queues the notices not sent yet; false when the printer is gone.
    fn tx_notices(&mut self, p: &Progress) -> bool {
        for n in p.notices.iter().skip(self.notices_sent) {
            if self.tx.send(Msg::Notice(n.clone())).is_err() {
                return false;
            }
        }
        self.notices_sent = self.notices_sent.max(p.notices.len());
        true
    }

    /// Closes the channel and waits until everything queued is printed (the bar cleared).
    pub(super) fn finish(self) {
        drop(self.tx);
        let _ = self.handle.join();
    }
}

impl View {
    /// Shows one snapshot: the bar on a terminal, a plain line now and then in a log.
    fn tick(&self, p: &Progress, last_plain: &mut Instant, out: &mut dyn Write) {
        if self.prompting.load(Ordering::Relaxed) {
            return;
        }
        if self.interactive {
            // The bar fills with the path length executed; the line count is what GRBL took.
            self.bar.set_prefix(format!(
                "{:>10} line {}/{}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total
            ));
            self.bar
                .set_position((p.fraction() * BAR_STEPS as f64).round() as u64);
            self.bar.set_message(status_text(p, self.eta_scale));
        } else if self.plain
            && (last_plain.elapsed() >= self.plain_interval || p.phase == Phase::Done)
        {
            *last_plain = Instant::now();
            let _ = writeln!(
                out,
                "{}: line {}/{} {}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total,
                status_text(p, self.eta_scale)
            );
            let _ = out.flush();
        }
    }
}
