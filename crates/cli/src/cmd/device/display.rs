//! The progress display of a send: a bar and a status line on a terminal, plain lines every few
//! seconds in a log, nothing with `--quiet`; and the observer that feeds it.

use std::io::{IsTerminal, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use flatcut_grbl::driver::Phase;
use flatcut_grbl::{Control, Job, Progress, SendError, SendOptions, SendReport};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::StreamArgs;
use super::signals::{Ev, Interrupts, prompt_loop};

/// Interval of the plain progress lines printed when stderr is not a terminal (CI logs): often
/// enough to show life, rare enough not to flood a log.
pub const PLAIN_PROGRESS_INTERVAL: Duration = Duration::from_secs(3);
/// Resolution of the progress bar (it shows the fraction of the path length executed).
const BAR_STEPS: u64 = 1000;

/// Runs `send_job` with the progress display and the Ctrl-C policy.
pub(super) fn run_send(
    transport: &mut dyn flatcut_grbl::Transport,
    job: &Job,
    opts: &SendOptions,
    args: &StreamArgs,
    cancel: &Control,
) -> Result<SendReport, SendError> {
    let interactive = std::io::stderr().is_terminal() && !args.quiet;
    let bar = if interactive {
        ProgressBar::with_draw_target(Some(BAR_STEPS), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    let style = ProgressStyle::with_template(
        // Two lines, so the status fits an 80-column terminal without wrapping.
        "{prefix} [{elapsed_precise}] {wide_bar}\n{wide_msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    let prompting = Arc::new(AtomicBool::new(false));
    let interrupts = Interrupts::register(Some(cancel.clone()));
    let prompter = interrupts.as_ref().ok().map(|i| {
        let rx = i.take_receiver();
        let answers = i.tx.clone();
        let cancel = cancel.clone();
        let bar = bar.clone();
        let prompting = prompting.clone();
        std::thread::spawn(move || prompt_loop(rx, answers, cancel, bar, interactive, prompting))
    });
    if let Err(e) = &interrupts
        && !args.quiet
    {
        eprintln!("warning: Ctrl-C will not pause the job: {e}");
    }

    // The sender estimates machine time; the embedded simulator runs it `sim_speed` times faster
    // (and instant motion has no duration worth showing).
    let eta_scale = match (args.uses_sim(), args.sim_instant) {
        (false, _) => Some(1.0),
        (true, false) => Some(1.0 / args.sim_speed),
        (true, true) => None,
    };
    let mut last_plain = Instant::now();
    let plain = !interactive && !args.quiet;
    let pause_tx = interrupts.as_ref().ok().map(|i| i.tx.clone());
    let mut asked_pause: Option<usize> = None;
    let mut observer = |p: &Progress| {
        // The job paused itself and waits for the operator: ask once per pause.
        if let (Some(line), Some(tx)) = (&p.paused_at, &pause_tx)
            && asked_pause != Some(line.index)
        {
            asked_pause = Some(line.index);
            let _ = tx.send(Ev::Pause(line.to_string()));
        }
        if prompting.load(Ordering::Relaxed) {
            return;
        }
        if interactive {
            // The bar fills with the path length executed; the line count is what GRBL took.
            bar.set_prefix(format!(
                "{:>10} line {}/{}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total
            ));
            bar.set_position((p.fraction() * BAR_STEPS as f64).round() as u64);
            bar.set_message(status_text(p, eta_scale));
        } else if plain
            && (last_plain.elapsed() >= PLAIN_PROGRESS_INTERVAL || p.phase == Phase::Done)
        {
            last_plain = Instant::now();
            // A log that cannot be written is no reason to stop a machine mid-job.
            let _ = writeln!(
                std::io::stderr(),
                "{}: line {}/{} {}",
                phase_name(p.phase),
                p.lines_acked,
                p.lines_total,
                status_text(p, eta_scale)
            );
        }
    };
    let result = flatcut_grbl::send_job(transport, job, opts, &mut observer, cancel);
    bar.finish_and_clear();
    if let Ok(i) = interrupts {
        i.done();
    }
    if let Some(h) = prompter {
        let _ = h.join();
    }
    result
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Connecting => "connecting",
        Phase::Checking => "checking",
        Phase::Streaming => "streaming",
        Phase::Finishing => "finishing",
        Phase::Done => "done",
    }
}

/// "12.3% of path · ETA 1:05 · Run · X10.000 Y5.000 Z-0.500".
/// `eta_scale` converts the sender's machine-time ETA to wall-clock time (`None`: no ETA).
pub(super) fn status_text(p: &Progress, eta_scale: Option<f64>) -> String {
    let mut s = format!("{:5.1}% of path", 100.0 * p.fraction());
    if let (Some(eta), Some(k)) = (p.eta, eta_scale) {
        let t = (eta.as_secs_f64() * k).round() as u64;
        s.push_str(&format!(" · ETA {}:{:02}", t / 60, t % 60));
    }
    if let Some(st) = &p.state {
        s.push_str(&format!(" · {}", st.name()));
    }
    if p.holding {
        s.push_str(" (held)");
    }
    if let Some([x, y, z]) = p.position {
        s.push_str(&format!(" · X{x:.3} Y{y:.3} Z{z:.3}"));
    }
    s
}
