//! The progress display of a send: a bar and a status line on a terminal, plain lines every few
//! seconds in a log, nothing with `--quiet`; and the observer that feeds it (the printing
//! itself runs on its own thread, `printer`).

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use flatcut_grbl::driver::Phase;
use flatcut_grbl::{Control, Job, Progress, SendError, SendOptions, SendReport};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::StreamArgs;
use super::printer::{BAR_STEPS, Printer, View};
use super::signals::{Ev, Interrupts, prompt_loop};

/// Interval of the plain progress lines printed when stderr is not a terminal (CI logs): often
/// enough to show life, rare enough not to flood a log.
pub const PLAIN_PROGRESS_INTERVAL: Duration = Duration::from_secs(3);

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
    let pause_tx = interrupts.as_ref().ok().map(|i| i.tx.clone());
    let mut asked_pause: Option<usize> = None;
    // The terminal is written on the printer's thread only: a terminal that stops reading
    // (Ctrl-S) must not stop the stream.
    let mut printer = Printer::spawn(
        View {
            bar: bar.clone(),
            interactive,
            plain: !interactive && !args.quiet,
            plain_interval: PLAIN_PROGRESS_INTERVAL,
            notices: !args.quiet,
            eta_scale,
            prompting: prompting.clone(),
        },
        Box::new(std::io::stderr()),
    );
    let mut observer = |p: &Progress| {
        // The job paused itself and waits for the operator: ask once per pause.
        if let (Some(line), Some(tx)) = (&p.paused_at, &pause_tx)
            && asked_pause != Some(line.index)
        {
            asked_pause = Some(line.index);
            let _ = tx.send(Ev::Pause(line.to_string()));
        }
        printer.show(p);
    };
    // Asked when the sender needs the operator's word (the flag that gives it was absent).
    let opts = &opts.clone().with_operator(super::ask::terminal_operator(
        &bar,
        interactive,
        &prompting,
        cancel,
    ));
    let result = flatcut_grbl::send_job(transport, job, opts, &mut observer, cancel);
    printer.finish();
    if let Ok(i) = interrupts {
        i.done();
    }
    if let Some(h) = prompter {
        let _ = h.join();
    }
    result
}

pub(super) fn phase_name(p: Phase) -> &'static str {
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
