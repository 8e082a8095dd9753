//! The blocking sender: [`send_job`] runs the handshake (banner or soft reset, `$I`, `$$`,
//! status, alarm-lock policy, travel check), an optional `$C` check pass, then streams the job
//! with character counting while polling `?` at 5 Hz, honouring feed hold / resume / abort from
//! a [`CancelToken`], journaling every acknowledged line, and stopping with a typed error that
//! names the line and the code's meaning on `error:N`, `ALARM:N`, reset or hang-up.
//!
//! Which acknowledged lines have really *executed* is tracked conservatively (an `ok` only means
//! "queued"): all acknowledged lines are done when the machine reports `Idle`; a line is done
//! once more motion lines than the planner and segment buffers can hold were acknowledged after
//! it; and after a stop, the reported position locates the line the machine was on.
//!
//! One idea per module: [`options`], [`control`] and [`progress`] are the API around a send;
//! `session` is the connection, [`console`] keeps one open between jobs, `handshake` connects, `evidence` compares the controller with the journal's stop
//! record, `resume` settles what an interrupted run left in doubt, `check` runs the checks before motion, `stream` streams, `tracker` keeps the
//! books of what ran, `along` places the machine on the path for progress, `watch` checks the reported position against the job's path, `stops` stops a run, and [`send_job`] reads as handshake → check → stream
//! → finish.

mod along;
mod check;
pub mod confirm;
pub mod console;
pub mod control;
mod error;
mod evidence;
mod frame;
mod geometry;
mod handshake;
pub mod options;
mod places;
pub mod progress;
mod resume;
mod session;
mod stops;
mod stream;
mod tracker;
mod watch;

pub use confirm::{Operator, OriginQuestion, Question};
pub use console::{Console, ControllerInfo, Jog, MachineStatus};
pub use control::{CancelToken, Control};
pub use error::{LineError, LineRef, OffPath, SendError};
pub use options::{PausePolicy, SendOptions};
pub use progress::{Phase, Progress, SendReport};

use crate::job::{Job, JobStart, MachineLimits};
use crate::job_edit::JobChanges;
use crate::journal::{Journal, JournalState};
use check::{check_pass, check_travel};
use session::Session;
use std::time::{Duration, Instant};
use stream::Stream;
use tracker::Tracker;

#[cfg(test)]
use crate::transport::TransportError;
#[cfg(test)]
use resume::{Resolution, resolve_resume};
#[cfg(test)]
use std::path::PathBuf;

/// GRBL's stepper segment buffer (`SEGMENT_BUFFER_SIZE 6`, `grbl/stepper.h`): prepared segments
/// may belong to blocks already released from the planner, so that many extra lines may still be
/// moving after the planner has room.
const SEGMENT_BUFFER: usize = 6;
/// Planner blocks on a 328p, used until `[OPT:]` says otherwise (`grbl/planner.h:27-31`).
const DEFAULT_PLANNER_BLOCKS: usize = 15;
/// Position match tolerance, mm: reports carry 3 decimals and a step is 0.004 mm at 250 steps/mm.
const POSITION_TOL_MM: f64 = 0.01;
/// `ALARM:3`: reset while in motion; GRBL's position may be off by the steps lost stopping.
const ABORT_CYCLE_ALARM: u8 = 3;
/// Longest single read wait, so control requests and polls stay responsive.
const READ_SLICE: Duration = Duration::from_millis(20);
/// Longest gap between two fsyncs of the journal while streaming. Every batch of records is
/// written to the OS at once (it survives the sender being killed); the flush to the disk runs
/// on a background thread at most this often, because an fsync takes milliseconds to tens of
/// milliseconds and the link must not wait for it (at 115200 baud the 128-byte RX buffer
/// drains in 11 ms). Every stop syncs in the foreground.
const JOURNAL_FSYNC_INTERVAL: Duration = Duration::from_millis(250);
/// How long a controller found moving when the sender connects may take to finish the motion it
/// has queued (15 planner blocks) before the sender gives up waiting for it.
const DRAIN_ON_CONNECT_LIMIT: Duration = Duration::from_secs(600);

/// Runs a whole send: handshake, optional check pass, streaming with status polling and
/// journaling, and the final wait for the machine to finish. See the module docs.
///
/// With `opts.resume`, the journal at `opts.journal` must belong to this job; the lines it does
/// not record as executed are sent, each contiguous run preceded by a preamble restoring the
/// modal state, pen/tool height and position of the job at that point.
pub fn send_job(
    transport: &mut dyn crate::transport::Transport,
    job: &Job,
    opts: &SendOptions,
    observer: &mut dyn FnMut(&Progress),
    cancel: &CancelToken,
) -> Result<SendReport, SendError> {
    run_job(&mut Session::new(transport), job, opts, observer, cancel)
}

/// [`send_job`] on a session, which may know the controller already (a [`Console`] that is
/// connected): the job's own handshake runs all the same.
fn run_job<T: crate::transport::Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    opts: &SendOptions,
    observer: &mut dyn FnMut(&Progress),
    cancel: &CancelToken,
) -> Result<SendReport, SendError> {
    let t0 = Instant::now();
    // Journal first: refuse a wrong job before touching the machine.
    let (mut journal, prior, edited) = open_journal(job, opts)?;
    let mut progress = Progress::start(job);
    observer(&progress);

    let link = handshake::connect(sess, opts)?;
    let limits = MachineLimits::from_settings(&sess.settings);
    if job.needs_laser_mode && !limits.laser_mode && !opts.force_laser {
        return Err(SendError::LaserModeOff);
    }
    // The job as it runs here: from where the controller stands (or, on a resume, where the
    // interrupted run started), timed with the controller's settings.
    let start = match prior.as_ref().and_then(|p| p.start) {
        Some(s) => s,
        None => {
            let s = JobStart {
                wcs: link.frame.wcs,
                g92: link.frame.g92,
                position: sess.work_position().unwrap_or_default(),
            };
            if let Some(j) = journal.as_mut() {
                j.start(&s);
                let o = link.frame.origin_of(s.wcs);
                j.origin([o[0] + s.g92[0], o[1] + s.g92[1], o[2] + s.g92[2]]);
            }
            s
        }
    };
    let job = &job.rebased(&start, &limits);
    let mut notices: Vec<String> = link.frame_notice.iter().cloned().collect();
    notices.extend(edited.map(|c| {
        format!(
            "resumed an edited job. {}",
            c.to_string().replace('\n', " ")
        )
    }));
    // GRBL clamps a feed over an axis's max rate without a word: say so before anything runs.
    notices.extend(job.feed_clamps(&limits).iter().map(ToString::to_string));
    let plan = resume::settle(sess, job, opts, prior, &link, &mut journal)?;
    notices.extend(plan.notice.iter().cloned());
    progress.notices.clone_from(&notices);
    observer(&progress);
    if opts.check_travel {
        check_travel(
            job,
            &limits,
            &sess.settings,
            link.frame.origin_of(start.wcs),
        )?;
    }
    if opts.check {
        progress.phase = Phase::Checking;
        observer(&progress);
        check_pass(sess, job, opts)?;
    }

    let mut tracker = Tracker::new(job, sess, plan.prior_done.as_deref());
    let queued = stream::queue(sess, job, &tracker, plan.resume_at);
    // A resumed run's estimate is what it sends, from where the machine stands.
    let estimated_time = if tracker.previously_done > 0 || queued.lines < job.len() {
        let here = JobStart {
            wcs: link.frame.wcs,
            g92: link.frame.g92,
            position: sess.work_position().unwrap_or_default(),
        };
        remaining_time(&queued.texts, &here, &limits).unwrap_or_else(|| {
            let left = (0..job.len()).filter(|&i| !tracker.done[i]);
            left.map(|i| job.lines[i].time).sum()
        })
    } else {
        job.total_time
    };
    let streamed = Stream::new(
        sess,
        (job, job),
        opts,
        &mut tracker,
        &mut journal,
        &queued.preamble,
    )
    .run(&mut progress, observer, cancel)?;
    let final_position = stream::finish(sess, job, opts, queued.lines, &mut journal)?;

    progress.complete(job);
    observer(&progress);
    Ok(SendReport {
        version: sess.version.clone(),
        rx_size: sess.s.rx_size(),
        planner_blocks: sess.blocks,
        settings: sess.settings.clone(),
        lines_sent: queued.lines,
        preamble_lines: queued.preamble.len(),
        previously_done: tracker.previously_done,
        stream_bytes: streamed.bytes,
        stream_time: streamed.time,
        total_time: t0.elapsed(),
        max_in_flight_bytes: sess.s.max_in_flight_bytes(),
        final_position,
        estimated_time,
        checked: opts.check,
        notices,
    })
}

/// The estimated time of `texts` (what a resumed run sends: preambles and the lines left) on a
/// controller standing at `here` with `limits`; `None` if they do not parse as one program.
fn remaining_time(texts: &[String], here: &JobStart, limits: &MachineLimits) -> Option<f64> {
    let mut program = texts.join("\n");
    program.push('\n');
    let job = Job::parse_with(&program, limits).ok()?;
    Some(job.rebased(here, limits).total_time)
}

/// The journal of a send, what it said before this run, and what changed in the job since
/// it was written (an edited job).
type Opened = (
    Option<Journal>,
    Option<JournalState>,
    Option<Box<JobChanges>>,
);

/// Opens the journal the options ask for: a new one, or the interrupted run's together with
/// what it says. The interrupted run's journal must belong to this job, or to this file before
/// an edit that the options or the operator accept (see [`JobChanges`]).
fn open_journal(job: &Job, opts: &SendOptions) -> Result<Opened, SendError> {
    let p = match (&opts.journal, opts.resume) {
        (Some(p), true) => p,
        (Some(p), false) => return Ok((Some(Journal::create(p, job)?), None, None)),
        (None, true) => return Err(SendError::NoJournal),
        (None, false) => return Ok((None, None, None)),
    };
    let st = Journal::read(p)?;
    let changes = (st.hash != job.hash || st.lines != job.len())
        .then(|| JobChanges::between(&st, job))
        .flatten();
    let Some(changes) = changes else {
        // The same job, or a journal that does not record its lines (refused as another job).
        let (j, st) = Journal::resume(p, job)?;
        return Ok((Some(j), Some(st), None));
    };
    let changes = Box::new(changes);
    if changes.needs_resume_line() && opts.resume_from.is_none() {
        return Err(SendError::JobChangedWhereItRan { changes });
    }
    let asked = || {
        opts.operator
            .as_ref()
            .is_some_and(|o| o.confirms(&Question::ChangedJob(changes.clone())))
    };
    if !opts.accept_changed_job && !asked() {
        return Err(SendError::JobChanged { changes });
    }
    let (j, st) = Journal::resume_edited(p, job, &st, changes.as_ref())?;
    Ok((Some(j), Some(st), Some(changes)))
}

#[cfg(test)]
#[path = "../driver_tests.rs"]
mod tests;
