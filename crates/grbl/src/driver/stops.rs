//! How a run stops: on an alarm, an unexpected reset, a state nobody asked for, or the
//! operator's abort. Each locates the machine on the path, journals why, and returns the error.

use super::error::SendError;
use super::error::line_ref;
use super::evidence;
use super::session::{Session, transport};
use super::tracker::Tracker;
use super::watch::Deviation;
use super::{ABORT_CYCLE_ALARM, READ_SLICE, SendOptions};
use crate::codes::{alarm_is_critical, alarm_meaning};
use crate::job::Job;
use crate::journal::Journal;
use crate::response::MachineState;
use crate::response::Response;
use crate::streamer::{Event, Tag};
use crate::transport::{Transport, TransportError};
use std::time::{Duration, Instant};

/// Stops because the machine is in a state this sender did not ask for.
pub(super) fn stop_unexpected<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    // Where the machine stands tells which acknowledged lines it got through.
    if let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent) {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    let state = sess
        .status
        .as_ref()
        .map(|s| s.state.name())
        .unwrap_or_default();
    if let Some(j) = journal.as_mut() {
        j.note(&format!("stopped: unexpected state {state}"));
        j.sync()?;
    }
    Ok(SendError::UnexpectedState {
        state,
        last_done: tracker.last_done(job),
    })
}

/// Stops on `ALARM:N`: collects the answers to lines still in GRBL's buffer, resets a critical
/// alarm (GRBL answers nothing else until then), and locates the machine on the path.
pub(super) fn on_alarm<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    code: u8,
    rest: Vec<Event>,
    opts: &SendOptions,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    if let Some(j) = journal.as_mut() {
        j.note(&format!(
            "ALARM:{code} {}",
            alarm_meaning(code).unwrap_or("")
        ));
    }
    // The `ok` of the line that raised it and `error:9`s for lines behind it may follow (some
    // may already be in the batch that carried the alarm).
    let settle = Instant::now() + Duration::from_millis(300);
    let mut first = Some(rest);
    while Instant::now() < settle {
        let evs = match first.take() {
            Some(r) => r,
            None => match sess.pump(READ_SLICE) {
                Ok(e) => e,
                Err(e) => return Err(transport(e, tracker.last_done(job))),
            },
        };
        for e in evs {
            book_answer(e, job, tracker, journal);
        }
    }
    if let Some(Tag::Job(i)) = sess.s.last_sent() {
        tracker.last_sent = Some(tracker.last_sent.map_or(i, |l| l.max(i)));
    }
    if alarm_is_critical(code) {
        // GRBL blocks everything until reset; position is reported after it.
        sess.s.forget_in_flight();
        sess.soft_reset();
        let _ = sess.wait_banner(opts.banner_timeout);
    }
    if code == ABORT_CYCLE_ALARM {
        // A reset in motion: steps were lost, so the reported position says nothing about which
        // queued lines ran. Name the range in doubt instead of guessing.
        if let (Some(&a), Some(b)) = (tracker.unconfirmed.front(), tracker.last_sent)
            && let Some(j) = journal.as_mut()
        {
            j.uncertain(a, b.max(a));
        }
    } else if let Ok(Some(_)) = sess.query_status(Duration::from_millis(500))
        && let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent)
    {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    if let Some(j) = journal.as_mut() {
        j.sync()?;
    }
    Ok(SendError::Alarm {
        code,
        last_done: tracker.last_done(job),
    })
}

/// Books an answer to a job line that came in while a run stops (the controller answers what it
/// parses until its buffers are flushed): an `ok` is journaled and counted as for a running job,
/// an `error:N` journaled as a line that did not run. Anything else is left alone.
fn book_answer(e: Event, job: &Job, tracker: &mut Tracker, journal: &mut Option<Journal>) {
    match e {
        Event::Ack(Tag::Job(i)) => {
            if let Some(j) = journal.as_mut() {
                j.ack(i);
            }
            tracker.ack(job, i, journal);
        }
        Event::Rejected(Tag::Job(i), c) => {
            if let Some(j) = journal.as_mut() {
                j.reject(i, c);
            }
            tracker.reject(i);
        }
        _ => {}
    }
}

/// Whether line `i` does the same thing right after a soft reset (GRBL's parser back at G0 G54
/// G17 G21 G90 G94 M5 M9, no G92) as it would in the job: then a line that GRBL took in after
/// resetting really ran as the job meant it.
pub(super) fn same_after_reset(job: &Job, i: usize) -> bool {
    let st = &job.lines[i].before;
    let d = crate::job::ModalState::default();
    let explicit_motion = job.lines[i].text.contains("G0")
        || job.lines[i].text.contains("G1")
        || st.motion == d.motion;
    st.units == d.units
        && st.incremental == d.incremental
        && st.plane == d.plane
        && st.wcs == d.wcs
        && st.inverse_time == d.inverse_time
        && st.spindle == d.spindle
        && st.mist == d.mist
        && st.flood == d.flood
        && st.g92 == d.g92
        && explicit_motion
}

/// How many of the lines answered after an unexpected reset may not have cut their programmed
/// segment (see [`on_reset`]).
const RESET_DOUBT_LINES: usize = 2;

/// How the journal's note of an unexpected reset begins (a resume names it as the reason the
/// position is lost, and knows from it that lines it lost are sent again).
pub(super) const RESET_NOTE: &str = "unexpected reset";

/// Stops on an unexpected banner. GRBL cleared its RX buffer at the reset, but bytes still on
/// the wire landed in the fresh buffer and ran: their answers arrive after the banner and belong
/// to the newest lines that were in flight.
pub(super) fn on_reset<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    lost: Vec<Tag>,
    rest: Vec<Event>,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    if let Some(Tag::Job(i)) = lost.iter().rev().find(|t| matches!(t, Tag::Job(_))) {
        tracker.last_sent = Some(tracker.last_sent.map_or(*i, |l| l.max(*i)));
    }
    let late = match answers_after_reset(sess, rest) {
        Ok(l) => l,
        Err(e) => return Err(transport(e, tracker.last_done(job))),
    };
    let m = late.len().min(lost.len());
    let mut ran_after_reset = 0;
    let mut resent = Vec::new();
    for (k, (tag, r)) in lost[lost.len() - m..]
        .iter()
        .zip(&late[late.len() - m..])
        .enumerate()
    {
        if let (Tag::Job(i), Response::Ok) = (tag, r) {
            ran_after_reset += 1;
            // No answer tells whether the first of them ran whole or as the tail of a line the
            // reset cut in half; either way it did not cut the job's segment (a whole one ran
            // from where the reset left the tool, not from the end of the line before it, which
            // the reset discarded). The second then started wherever the first stopped, which
            // is its programmed start only if the first ran whole. The status reports come only
            // after all of them ran, so neither can be confirmed: both are re-sent. The price is
            // that the second is cut twice when the first ran whole; counting it instead would
            // skip its cut when the first was a fragment.
            if k < RESET_DOUBT_LINES {
                resent.push(*i);
            }
            if k >= RESET_DOUBT_LINES && same_after_reset(job, *i) {
                if let Some(j) = journal.as_mut() {
                    j.ack(*i);
                }
                tracker.ack(job, *i, journal);
            }
        }
    }
    // The lost lines not counted above did not run as the job meant (the reset discarded them,
    // or they ran from the wrong place or in the wrong state): whatever the position says, they
    // are sent again.
    for t in &lost {
        if let Tag::Job(i) = t
            && !tracker.acked[*i]
        {
            tracker.keep_for_resend(*i);
        }
    }
    if let Some(j) = journal.as_mut() {
        j.note(&format!(
            "{RESET_NOTE}; {} line(s) in flight, {ran_after_reset} of them ran after the reset; lines {resent:?} ran from where the reset left the tool and are re-sent",
            lost.len()
        ));
    }
    // Wait for the motion those lines queued, then locate the machine.
    let until = Instant::now() + Duration::from_secs(30);
    while Instant::now() < until {
        match sess.query_status(Duration::from_millis(500)) {
            Ok(Some(st)) if st.state != MachineState::Run => break,
            Ok(_) => {}
            Err(e) => return Err(transport(e, tracker.last_done(job))),
        }
    }
    if let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent) {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    if let Some(j) = journal.as_mut() {
        j.sync()?;
    }
    Ok(SendError::UnexpectedReset {
        lost: lost.len() - ran_after_reset,
        last_done: tracker.last_done(job),
    })
}

/// Stops the machine without losing its position: feed hold, wait until it stands, locate it
/// on the path, then a soft reset (no `ALARM:3` after a completed hold) that empties GRBL's
/// buffers and switches spindle and coolant off.
pub(super) fn stop_with_reset<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<(), SendError> {
    hold_still(sess, job, tracker, journal)?;
    if let (Some(p), Some(upto)) = (sess.work_position(), tracker.last_sent) {
        tracker.confirm_by_position(job, p, upto, journal);
    }
    reset_held(sess, journal)
}

/// Stops at a program pause (`M0`, line `line`) the controller has reached: every line
/// before it ran (GRBL finished their motion before pausing) and so did the pause, which the
/// journal records; then the soft reset, which keeps the position of a machine standing
/// still. A resume continues after the pause, from where the machine stands.
pub(super) fn stop_at_pause<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    line: usize,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<(), SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    tracker.confirm_below(job, line, journal);
    if let Some(j) = journal.as_mut() {
        j.ack(line);
    }
    tracker.ack(job, line, journal);
    tracker.confirm_below(job, line + 1, journal);
    if let Some(Tag::Job(i)) = sess.s.last_sent() {
        tracker.last_sent = Some(tracker.last_sent.map_or(i, |l| l.max(i)));
    }
    reset_held(sess, journal)
}

/// Feed hold (so that a reset does not lose the position: a reset in motion is `ALARM:3`),
/// then waits until the machine stands, booking the answers that come in meanwhile.
fn hold_still<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<(), SendError> {
    sess.s.set_feeding(false);
    sess.s.clear_queue();
    sess.s.realtime(b'!');
    let until = Instant::now() + Duration::from_secs(10);
    while Instant::now() < until {
        // Answers still on the wire (the run may stop before it read them) count: lines they
        // answer may have run before the machine stood still.
        let mut book = |e: Event| book_answer(e, job, tracker, journal);
        match sess.query_status_seeing(Duration::from_millis(500), &mut book) {
            Ok(Some(st))
                if matches!(
                    st.state,
                    MachineState::Hold { complete: true }
                        | MachineState::Idle
                        | MachineState::Alarm
                ) =>
            {
                break;
            }
            Ok(_) => {}
            Err(e) => return Err(transport(e, tracker.last_done(job))),
        }
    }
    if let Some(Tag::Job(i)) = sess.s.last_sent() {
        tracker.last_sent = Some(tracker.last_sent.map_or(i, |l| l.max(i)));
    }
    Ok(())
}

/// The soft reset after a completed hold: empties GRBL's buffers, spindle and coolant off.
fn reset_held<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    journal: &mut Option<Journal>,
) -> Result<(), SendError> {
    sess.s.forget_in_flight();
    sess.soft_reset();
    let _ = sess.wait_banner(Duration::from_secs(3));
    if let Some(j) = journal.as_mut() {
        j.note("stopped: feed hold, soft reset");
        j.sync()?;
    }
    Ok(())
}

/// Stops because the machine was found off the job's path (a line damaged on the link ran
/// elsewhere): feed hold, soft reset, tool off. Its position says nothing about which lines of
/// the stretch ran as written, so the journal marks them in doubt and a resume asks for the
/// line to continue from.
pub(super) fn stop_off_path<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
    off: Deviation,
    tolerance: f64,
) -> Result<SendError, SendError> {
    hold_still(sess, job, tracker, journal)?;
    let to = tracker.last_sent.unwrap_or(off.to).max(off.to);
    if let Some(j) = journal.as_mut() {
        j.note(&format!(
            "{OFF_PATH_NOTE} while running lines {} to {}: reported {:?}, expected {:?}",
            job.lines[off.from].source_line,
            job.lines[off.to].source_line,
            off.reported,
            off.expected
        ));
        j.uncertain(off.from, to);
    }
    reset_held(sess, journal)?;
    let err = SendError::OffPath(Box::new(super::error::OffPath {
        from: line_ref(job, off.from),
        to: line_ref(job, off.to),
        expected: off.expected,
        reported: off.reported,
        tolerance,
        last_done: tracker.last_done(job),
    }));
    Ok(with_tool_off(sess, journal, err))
}

/// How the journal's note of an off-path stop begins (a resume names it as the reason the
/// lines are in doubt).
pub(super) const OFF_PATH_NOTE: &str = "the machine left the job's path";

/// The operator's abort: feed hold, soft reset, tool off (confirmed by `$G`). `at_pause`: the
/// machine stands at this line's program pause (`M0`), which it reached.
pub(super) fn abort<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    at_pause: Option<usize>,
    tracker: &mut Tracker,
    journal: &mut Option<Journal>,
) -> Result<SendError, SendError> {
    match at_pause {
        Some(line) => stop_at_pause(sess, job, line, tracker, journal)?,
        None => stop_with_reset(sess, job, tracker, journal)?,
    }
    if let Some(j) = journal.as_mut() {
        j.note("aborted by the user (feed hold, soft reset, tool off)");
    }
    let err = SendError::Aborted {
        last_done: tracker.last_done(job),
    };
    Ok(with_tool_off(sess, journal, err))
}

/// The `ok`/`error` answers that arrived after an unexpected banner (some may already be in
/// `rest`, the batch that carried it). A `$G` sentinel written after the banner is parsed after
/// every byte already on the wire, so every answer before its `[GC:..]` answers a line that ran
/// after the reset. It bypasses the streamer, whose FIFO no longer holds those lines.
fn answers_after_reset<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    rest: Vec<Event>,
) -> Result<Vec<Response>, TransportError> {
    let mut late: Vec<Response> = rest
        .into_iter()
        .filter_map(|e| match e {
            Event::Unmatched(r) => Some(r),
            _ => None,
        })
        .collect();
    sess.t.write_all(b"$G\n")?;
    let until = Instant::now() + Duration::from_secs(2);
    let mut sentinel_ok = false;
    while Instant::now() < until {
        for e in sess.pump(READ_SLICE)? {
            match e {
                Event::Unmatched(r) if !sentinel_ok => late.push(r),
                Event::Feedback(f) if f.starts_with("GC:") => sentinel_ok = true,
                Event::Unmatched(_) if sentinel_ok => return Ok(late),
                _ => {}
            }
        }
    }
    Ok(late)
}

/// GRBL's parser-state words that mean the tool is off: spindle/laser (`M5`) and coolant or air
/// assist (`M9`).
const TOOL_OFF_WORDS: [&str; 2] = ["M5", "M9"];

/// Turns the tool off after a stop and confirms it with `$G`: `M5` and `M9`, and `S0` in laser
/// mode (so a later `M3` cannot relight the laser at the old power); a controller in alarm
/// refuses G-code, but its reset already switched everything off, which `$G` shows. True when
/// the parser state reads `M5 M9` (and `S0` in laser mode) afterwards.
pub(super) fn tool_off<T: Transport + ?Sized>(sess: &mut Session<'_, T>) -> bool {
    let laser = sess.settings.get(&32).is_some_and(|v| *v != 0.0);
    let wait = Duration::from_secs(3);
    sess.s.set_feeding(true);
    if !sess.alarm_lock {
        let words: &[&str] = if laser {
            &["M5", "S0", "M9"]
        } else {
            &["M5", "M9"]
        };
        for w in words {
            if !matches!(sess.command(w, wait), Ok(Ok(()))) {
                return false;
            }
        }
    }
    sess.last_gc = None;
    if !matches!(sess.command("$G", wait), Ok(Ok(()))) {
        return false;
    }
    let Some(gc) = sess.last_gc.clone() else {
        return false;
    };
    let has = |w: &str| {
        gc.split_whitespace()
            .any(|x| x.trim_start_matches("GC:") == w)
    };
    TOOL_OFF_WORDS.iter().all(|w| has(w)) && (!laser || has("S0"))
}

/// `err` after a stop of a run: the tool switched off (see [`tool_off`]) and, the machine
/// standing still, what the controller says journaled as the run's stop record (see
/// `evidence`); or — when the tool-off sequence could not be confirmed — `err` with that
/// warning.
pub(super) fn with_tool_off<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    journal: &mut Option<Journal>,
    err: SendError,
) -> SendError {
    let err = refused_with_tool_off(sess, journal, err);
    if let Some(j) = journal.as_mut()
        && let Some(r) = evidence::read(sess, STOP_RECORD_WAIT)
    {
        j.stopped_at(&r);
        let _ = j.sync();
    }
    err
}

/// Longest wait for each answer the stop record needs (a status, `$#`, `$G`).
const STOP_RECORD_WAIT: Duration = Duration::from_secs(3);

/// `err` with the tool switched off, as [`with_tool_off`] but without a stop record: for a
/// resume refused before anything moved, whose controller is not where the journal's stop
/// record says (that record must still count for the next attempt).
pub(super) fn refused_with_tool_off<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    journal: &mut Option<Journal>,
    err: SendError,
) -> SendError {
    let ok = tool_off(sess);
    if let Some(j) = journal.as_mut() {
        j.note(if ok {
            "tool off (M5 M9), confirmed by $G"
        } else {
            "tool off NOT confirmed by $G"
        });
        let _ = j.sync();
    }
    if ok {
        err
    } else {
        SendError::ToolOffUnconfirmed {
            cause: Box::new(err),
        }
    }
}
