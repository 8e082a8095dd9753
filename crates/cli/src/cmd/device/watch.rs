//! A job on a device, watched from the terminal: the device's events drawn as a progress bar
//! and status line (plain lines every few seconds in a log, nothing with `--quiet`), the job's
//! own pauses and the sender's questions asked at the terminal, and Ctrl-C (SIGTERM, SIGHUP)
//! turned into feed hold, resume or abort. A terminal that stops reading blocks only this
//! thread: the device never waits for a watcher (see `view`).

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use flatcut_device::grbl::SendError;
use flatcut_device::{Device, DeviceError, DeviceEvent, JobOutcome, JobRequest};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::args::StreamArgs;
use super::ask;
use super::signals::{Ev, Interrupts, prompt_loop};
use super::view::{BAR_STEPS, View};

/// Interval of the plain progress lines printed when stderr is not a terminal (CI logs): often
/// enough to show life, rare enough not to flood a log.
pub const PLAIN_PROGRESS_INTERVAL: Duration = Duration::from_secs(3);

/// Runs `req` on `device` with the progress display, the terminal's questions and the Ctrl-C
/// policy; the job's result once it ended (a device that refuses the job is the outer error).
pub(super) fn run_job(
    device: &Device,
    req: JobRequest,
    args: &StreamArgs,
) -> Result<Result<JobOutcome, SendError>, DeviceError> {
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
    let control = req.control.clone();
    let interrupts = Interrupts::register(Some(control.clone()));
    let prompter = {
        let rx = interrupts.take_receiver();
        let answers = interrupts.tx.clone();
        let control = control.clone();
        let bar = bar.clone();
        let prompting = prompting.clone();
        std::thread::spawn(move || prompt_loop(rx, answers, control, bar, interactive, prompting))
    };
    let mut view = View {
        bar: bar.clone(),
        interactive,
        plain: !interactive && !args.quiet,
        plain_interval: PLAIN_PROGRESS_INTERVAL,
        notices: !args.quiet,
        eta_scale: device.target().wall_per_machine_second(),
        prompting: prompting.clone(),
        out: Box::new(std::io::stderr()),
        last_plain: Instant::now(),
        notices_shown: 0,
    };
    let events = device.subscribe();
    // Questions are put to the operator only where one can answer: at a terminal.
    let started = device.start(req.with_questions(std::io::stdin().is_terminal()));
    if started.is_ok() {
        while let Some(e) = events.recv() {
            match e {
                DeviceEvent::Progress(p) => view.show(&p),
                // The job paused itself and waits for the operator: asked once per pause.
                DeviceEvent::Paused(line) => {
                    let _ = interrupts.tx.send(Ev::Pause(line.to_string()));
                }
                DeviceEvent::Question(a) => {
                    let yes =
                        ask::at_terminal(&a.question, &bar, interactive, &prompting, &control);
                    // A question the job gave up on (the send was aborted) needs no answer.
                    let _ = device.answer(a.id, yes);
                }
                DeviceEvent::JobFinished { .. } | DeviceEvent::Closed(_) => break,
                _ => {}
            }
        }
    }
    view.finish();
    interrupts.done();
    let _ = prompter.join();
    Ok(started?.wait())
}
