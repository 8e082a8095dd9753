//! How a running send looks at the terminal: a bar and a status line on a terminal, plain lines
//! every few seconds in a log, the sender's notices as warnings, nothing with `--quiet`. It is
//! drawn on the thread that watches the device's events; a terminal that stops reading (Ctrl-S,
//! a stalled pipe, a slow remote session) blocks only that thread, never the device, whose
//! subscription keeps the newest progress in place of the ones missed and every notice.

use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use flatcut_device::grbl::Progress;
use flatcut_device::grbl::driver::Phase;
use indicatif::ProgressBar;

use super::status::{phase_name, status_text};

/// Resolution of the progress bar (it shows the fraction of the path length executed).
pub(super) const BAR_STEPS: u64 = 1000;

/// How a send is shown, and where.
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
    /// The operator is being asked something: the bar keeps still.
    pub prompting: Arc<AtomicBool>,
    /// Where plain lines and notices go (stderr).
    pub out: Box<dyn Write + Send>,
    /// When the last plain line was written.
    pub last_plain: Instant,
    /// Notices shown so far.
    pub notices_shown: usize,
}

impl View {
    /// Shows one snapshot: its new notices first, then the bar on a terminal or a plain line
    /// now and then in a log (always the last one).
    pub(super) fn show(&mut self, p: &Progress) {
        for n in p.notices.iter().skip(self.notices_shown) {
            if self.notices {
                let out = &mut self.out;
                let mut write = || {
                    // A log that cannot be written is no reason to stop anything.
                    let _ = writeln!(out, "warning: {n}");
                    let _ = out.flush();
                };
                if self.interactive {
                    self.bar.suspend(write);
                } else {
                    write();
                }
            }
        }
        self.notices_shown = self.notices_shown.max(p.notices.len());
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
            && (self.last_plain.elapsed() >= self.plain_interval || p.phase == Phase::Done)
        {
            self.last_plain = Instant::now();
            let _ = writeln!(
                self.out,
                "{}: line {}/{} {}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total,
                status_text(p, self.eta_scale)
            );
            let _ = self.out.flush();
        }
    }

    /// Clears the bar.
    pub(super) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
