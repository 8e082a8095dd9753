//! Settling a resume: which lines an interrupted run left in doubt, and where the machine stands
//! on the job's path.

use super::SendOptions;
use super::confirm::{OriginQuestion, Question};
use super::error::SendError;
use super::error::line_ref;
use super::evidence;
use super::geometry::dist;
use super::handshake::Link;
use super::places::{places_on_path, position_tolerance};
use super::session::Session;
use super::stops::{OFF_PATH_NOTE, RESET_NOTE, refused_with_tool_off};
use super::tracker::AMBIGUOUS_STOP_NOTE;
use crate::job::Job;
use crate::journal::{Journal, JournalState};
use crate::transport::Transport;

/// What a resume sends.
#[derive(Debug, Clone, Default)]
pub(super) struct ResumePlan {
    /// Per job line: done before this run (`None`: not a resume).
    pub prior_done: Option<Vec<bool>>,
    /// The first line to send, the work position to put the machine at for it, and whether
    /// the machine must travel there (it may already stand there).
    pub resume_at: Option<(usize, [f64; 3], bool)>,
    /// How the machine position was re-established, and why.
    pub notice: Option<String>,
}

/// Longest wait for a homing cycle's `ok`: at GRBL's default seek rate (500 mm/min) searching
/// 1.5× a 1 m travel on each axis takes about 3 minutes.
const HOMING_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(300);

/// Settles what the interrupted run left in doubt, from the journal `prior` and the machine:
/// its reported position is trusted only if the controller did not restart and is not in
/// alarm (a reset in motion, ALARM:3, loses steps). Journals the resolution.
pub(super) fn settle<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    opts: &SendOptions,
    prior: Option<JournalState>,
    link: &Link,
    journal: &mut Option<Journal>,
) -> Result<ResumePlan, SendError> {
    let Some(mut st) = prior else {
        return Ok(ResumePlan::default());
    };
    // A banner after the handshake is a restart too.
    let restarted = link.restarted || sess.restarts() > link.restarts_before;
    let tol = position_tolerance(&sess.settings);
    let homes = sess.settings.get(&22).is_some_and(|v| *v != 0.0);
    let disagrees = evidence::disagreement(st.stop.as_ref(), link.found.as_ref(), homes, tol);
    let trusted = !restarted && !link.unlocked && !sess.alarm_lock && disagrees.is_none();
    // Work position without the controller's G92 offset: the frame of the job's geometry.
    let g92 = link.frame.g92;
    let here = if trusted {
        sess.work_position()
            .map(|p| [p[0] + g92[0], p[1] + g92[1], p[2] + g92[2]])
    } else {
        None
    };
    let rx = sess.s.rx_size();
    let lost = restarted || disagrees.is_some();
    if let Some(r) = resolve_resume(job, &st, opts.resume_from, here, rx, tol, lost)? {
        if let Some(j) = journal.as_mut() {
            j.resolved(r.from, r.cut);
            if let Some((k, p)) = r.partial {
                j.partial(k, p);
            }
            j.sync()?;
        }
        for i in r.from..r.cut {
            st.done[i] = true;
        }
        for d in st.done.iter_mut().skip(r.cut) {
            *d = false;
        }
        st.partial = r.partial;
    }
    let why = position_lost(&st, link, restarted, disagrees);
    let notice = match reestablish_position(sess, job, &st, link, opts, why) {
        Ok(n) => n,
        // Nothing moved; the tool is switched off all the same, as on every stop.
        Err(e @ (SendError::PositionUnknown { .. } | SendError::OriginNotConfirmed { .. })) => {
            return Err(refused_with_tool_off(sess, journal, e));
        }
        Err(e) => return Err(e),
    };
    if let Some((k, _)) = st.partial
        && job.lines[k].before.incremental
    {
        return Err(SendError::ResumeUncertain {
            from: line_ref(job, k),
            to: line_ref(job, k),
            reason: format!(
                "the job stopped part-way through line {}, a relative (G91) move, which cannot be completed from the middle",
                job.lines[k].source_line
            ),
        });
    }
    // Where the first line to send starts (or where the stopped line was left): a machine
    // found standing there needs no travel, so nothing moves twice.
    let mut resume_at = None;
    if let Some(i0) = st.done.iter().position(|d| !d) {
        let at = match st.partial {
            Some((k, p)) if k == i0 => p,
            _ => job.start_of(i0),
        };
        let there = here.is_some_and(|h| dist(h, at) <= tol);
        if i0 > 0 || st.partial.is_some() || there {
            resume_at = Some((i0, at, !there));
        }
    }
    Ok(ResumePlan {
        prior_done: Some(st.done),
        resume_at,
        notice,
    })
}

/// Why the machine position cannot be trusted since the journal was written, if it cannot:
/// the controller restarted (a banner it was not asked for, at any moment since the port was
/// opened: power-up or the DTR reset of opening the port), does not agree with the journal's
/// stop record (`disagrees`: a power cycle or reset while nothing was connected), was
/// unlocked with `$X` without homing, or reset or alarmed during the interrupted run.
fn position_lost(
    st: &JournalState,
    link: &Link,
    restarted: bool,
    disagrees: Option<String>,
) -> Option<String> {
    if restarted {
        return Some("the controller restarted when the port was opened (or lost power)".into());
    }
    if disagrees.is_some() {
        return disagrees;
    }
    if link.unlocked {
        return Some("the controller was in alarm and was unlocked with $X, not homed".into());
    }
    st.notes
        .iter()
        .find(|n| n.starts_with("ALARM:") || n.starts_with(RESET_NOTE))
        .map(|n| format!("the interrupted run stopped on \"{n}\""))
}

/// A resume on a controller whose position is lost first re-establishes it: homing (`$H`)
/// where the machine homes (`$22=1`), else the operator's confirmation that the work origin is
/// where it was. Returns what was done and why, for the report.
fn reestablish_position<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    st: &JournalState,
    link: &Link,
    opts: &SendOptions,
    why: Option<String>,
) -> Result<Option<String>, SendError> {
    let started = st.done.iter().any(|d| *d) || st.partial.is_some() || opts.resume_from.is_some();
    let Some(why) = why.filter(|_| started) else {
        return Ok(None);
    };
    if sess.settings.get(&22).is_some_and(|v| *v != 0.0) {
        sess.command_ok("$H", HOMING_TIMEOUT)?;
        sess.alarm_lock = false;
        let _ = sess.query_status(opts.command_timeout);
        return Ok(Some(format!(
            "homed the machine ($H) before resuming: {why}"
        )));
    }
    if opts.origin_confirmed {
        return Ok(Some(format!(
            "resuming on the operator's word that the work origin is where it was: {why}"
        )));
    }
    let Some(operator) = &opts.operator else {
        return Err(SendError::PositionUnknown { why });
    };
    let wcs = st.start.map_or(link.frame.wcs, |s| s.wcs);
    let (o, g92) = (link.frame.origin_of(wcs), link.frame.g92);
    let q = Question::Origin(OriginQuestion {
        why: why.clone(),
        wcs,
        journal_origin: st.origin,
        controller_origin: [o[0] + g92[0], o[1] + g92[1], o[2] + g92[2]],
        resume_at: st.done.iter().position(|d| !d).map(|i| {
            let at = match st.partial {
                Some((k, p)) if k == i => p,
                _ => job.start_of(i),
            };
            let g = job.lines[i].before.g92;
            (
                job.lines[i].source_line,
                [at[0] - g[0], at[1] - g[1], at[2] - g[2]],
            )
        }),
    });
    if operator.confirms(&q) {
        Ok(Some(format!(
            "resuming on the operator's word, asked at the start, that the work origin is where it was: {why}"
        )))
    } else {
        Err(SendError::OriginNotConfirmed { why })
    }
}

/// How a resume settles the lines an interrupted run left in doubt.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Resolution {
    /// First line settled.
    pub from: usize,
    /// Lines `from..cut` executed; none from `cut` on.
    pub cut: usize,
    /// Line `cut` was stopped part-way, at this work position.
    pub partial: Option<(usize, [f64; 3])>,
}

/// Settles a resume (see [`Resolution`]): the operator's `--resume-from`; or the machine's
/// position `here` (only when it is trustworthy) matched against the job's own geometry over the
/// window of lines that may have run after the journal lost track (acknowledged but not
/// confirmed, and written but unanswered: those the journal records as written, `W`, or for a
/// journal without that record what fitted in the `rx`-byte RX buffer behind them). `None`: the journal
/// already says exactly what ran.
pub(super) fn resolve_resume(
    job: &Job,
    st: &JournalState,
    resume_from: Option<usize>,
    here: Option<[f64; 3]>,
    rx: usize,
    tol: f64,
    restarted: bool,
) -> Result<Option<Resolution>, SendError> {
    let n = job.len();
    if let Some(k) = resume_from {
        if k >= n {
            return Err(SendError::ResumeFromOutOfRange { index: k, lines: n });
        }
        return Ok(Some(Resolution {
            from: 0,
            cut: k,
            partial: None,
        }));
    }
    let doubt = |a: usize, b: usize, reason: String| SendError::ResumeUncertain {
        from: line_ref(job, a),
        to: line_ref(job, b.min(n - 1)),
        reason,
    };
    if let Some((a, b)) = st.uncertain {
        let why = st
            .notes
            .iter()
            .rev()
            .find(|n| n.starts_with(OFF_PATH_NOTE) || n.starts_with(AMBIGUOUS_STOP_NOTE));
        let reason = match why {
            Some(n) if n.starts_with(AMBIGUOUS_STOP_NOTE) => format!(
                "the interrupted run {n}; a resume from the first of these lines would cut again what may have been cut"
            ),
            Some(n) => format!(
                "the interrupted run stopped because {n}: a line damaged on the link ran elsewhere, and which of these lines ran as written is not known"
            ),
            None => "the controller was reset while moving (ALARM:3), so the position it reported is not where the tool is".into(),
        };
        return Err(doubt(a, b, reason));
    }
    if let Some((k, _)) = st.partial
        && let Some(a) = unrecorded_before_stop(st, k)
    {
        return Err(doubt(
            a,
            k,
            format!(
                "the journal records the stop part-way through line {} but not whether the lines before it from line {} ran (a stop that did not count the answers still on the wire): they may have",
                job.lines[k].source_line, job.lines[a].source_line
            ),
        ));
    }
    // Lines written by a run that died unsettled (`W`) are in doubt as acknowledged ones are:
    // the controller runs what it received, and no line after them was written.
    let sent = st.in_doubt();
    let first = match (st.unconfirmed.first(), sent.first()) {
        (Some(&a), Some(&b)) => a.min(b),
        (Some(&a), None) | (None, Some(&a)) => a,
        (None, None) => return Ok(None),
    };
    let upper = match (st.unconfirmed.last(), st.sent) {
        (Some(&last_acked), None) => window_end(job, last_acked, rx),
        (last_acked, Some(w)) => last_acked.map_or(w, |&l| l.max(w)),
        (None, None) => return Ok(None),
    };
    let Some(p) = here else {
        let why = if restarted {
            "the controller restarted when the port was opened (or lost power), so its planner and position are gone"
        } else {
            "the controller is in alarm or gave no position, so its position is not trustworthy"
        };
        return Err(doubt(
            first,
            upper,
            format!("the link dropped with lines queued, and {why}"),
        ));
    };
    if let Some(i) =
        (first..=upper).find(|&i| job.lines[i].moves && job.lines[i].before.incremental)
    {
        return Err(doubt(
            first,
            upper,
            format!(
                "line {} is a relative (G91) move, so a position cannot tell which of these lines ran",
                job.lines[i].source_line
            ),
        ));
    }
    let groups = places_on_path(job, p, first..=upper, tol, |_| false);
    let fmt = |p: [f64; 3]| format!("X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2]);
    match groups.as_slice() {
        [(cut, partial)] => Ok(Some(Resolution {
            from: first,
            cut: *cut,
            partial: partial.map(|q| (*cut, q)),
        })),
        [] => Err(doubt(
            first,
            upper,
            format!(
                "the machine stands at {} (work), which is on none of these lines",
                fmt(p)
            ),
        )),
        _ => Err(doubt(
            first,
            upper,
            format!(
                "the path passes the machine's position {} (work) {} times among these lines",
                fmt(p),
                groups.len()
            ),
        )),
    }
}

/// The first line before the stop part-way through line `k` that the journal neither records
/// as run nor explains: not rejected, not an acknowledgement waiting to be settled, not a line an
/// unexpected reset made the run send again. A stop inside line `k` means every line sent before
/// it ran, which a journal written by a stop that lost the answers still on the wire did not
/// record; resuming from the first open line would cut those lines again.
fn unrecorded_before_stop(st: &JournalState, k: usize) -> Option<usize> {
    if st.notes.iter().any(|n| n.starts_with(RESET_NOTE)) {
        return None;
    }
    (0..k.min(st.lines))
        .find(|&i| !st.done[i] && st.rejected[i].is_none() && !st.unconfirmed.contains(&i))
}

/// The last line that may have reached the controller after `last_acked`: lines sent after the
/// last acknowledged one are at most what the `rx`-byte RX buffer held.
fn window_end(job: &Job, last_acked: usize, rx: usize) -> usize {
    let mut upper = last_acked;
    let mut bytes = 0;
    while upper + 1 < job.len() {
        bytes += job.lines[upper + 1].text.len() + 1;
        if bytes > rx {
            break;
        }
        upper += 1;
    }
    upper
}
