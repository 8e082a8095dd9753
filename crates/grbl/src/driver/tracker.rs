//! Which job lines are acknowledged and which are known executed in this run (an `ok` only means
//! "queued").

use super::SEGMENT_BUFFER;
use super::error::{LineRef, line_ref};
use super::places::{places_on_path, position_tolerance};
use super::session::Session;
use crate::job::Job;
use crate::journal::Journal;
use crate::transport::Transport;
use std::collections::VecDeque;

/// Bookkeeping of which job lines are acknowledged / known executed in this run.
pub(super) struct Tracker {
    pub(super) done: Vec<bool>,
    pub(super) acked: Vec<bool>,
    /// Acked in this run, not yet known executed, in ack order.
    pub(super) unconfirmed: VecDeque<usize>,
    /// Motion lines acked after each unconfirmed one, counted implicitly by position.
    pub(super) motion_after: VecDeque<usize>,
    pub(super) capacity: usize,
    pub(super) length_done: f64,
    pub(super) time_done: f64,
    /// Lines done before this run (not sent in it).
    pub(super) prior_done: Vec<bool>,
    /// Position match tolerance, mm.
    pub(super) pos_tol: f64,
    /// Highest job index handed to the port in this run.
    pub(super) last_sent: Option<usize>,
    /// Lines acknowledged (including earlier runs).
    pub(super) acked_count: usize,
    /// Lines known executed (including earlier runs).
    pub(super) done_count: usize,
    /// Estimated time of the whole job, s.
    pub(super) time_total: f64,
    /// Estimated time of the lines executed in this run, s.
    pub(super) time_done_run: f64,
    /// Lines done before this run (resume).
    pub(super) previously_done: usize,
    /// Every line before this index is done (see [`Tracker::first_open`]).
    open_from: usize,
    /// Shortest motion certain to take a step on some axis, mm: GRBL drops a move of zero
    /// steps without using a planner block, so shorter lines must not count towards the
    /// planner's capacity.
    min_motion: f64,
    /// The controller is in laser mode (`$32=1`): which lines sync (see
    /// [`Job::answer_waits_for_motion`]).
    laser: bool,
    /// Per job line: answered `error:N` in this run (it did not run).
    rejected: Vec<bool>,
    /// Per job line: to be sent again whatever the machine's position says (it ran from where an
    /// unexpected reset left the tool, not from its programmed start).
    resend: Vec<bool>,
}

impl Tracker {
    /// Books for a run of `job` (timed with the controller's settings) on the controller
    /// `sess` talks to; `prior_done` marks the lines a resumed run found done.
    pub(super) fn new<T: Transport + ?Sized>(
        job: &Job,
        sess: &Session<'_, T>,
        prior_done: Option<&[bool]>,
    ) -> Tracker {
        let n = job.len();
        let mut t = Tracker {
            done: vec![false; n],
            acked: vec![false; n],
            unconfirmed: VecDeque::new(),
            motion_after: VecDeque::new(),
            capacity: sess.blocks + SEGMENT_BUFFER,
            length_done: 0.0,
            time_done: 0.0,
            prior_done: prior_done.map_or_else(|| vec![false; n], <[bool]>::to_vec),
            pos_tol: position_tolerance(&sess.settings),
            last_sent: None,
            acked_count: 0,
            done_count: 0,
            time_total: job.total_time,
            time_done_run: 0.0,
            previously_done: 0,
            open_from: 0,
            min_motion: min_motion(&sess.settings),
            laser: sess.settings.get(&32).is_some_and(|v| *v != 0.0),
            rejected: vec![false; n],
            resend: vec![false; n],
        };
        for i in (0..n).filter(|&i| t.prior_done[i]) {
            t.done[i] = true;
            t.acked[i] = true;
            t.length_done += job.lines[i].length;
            t.time_done += job.lines[i].time;
            t.acked_count += 1;
            t.done_count += 1;
            t.previously_done += 1;
        }
        t
    }

    /// Line `i` was handed to the port.
    pub(super) fn sent(&mut self, i: usize) {
        self.last_sent = Some(self.last_sent.map_or(i, |l| l.max(i)));
    }

    /// Every acknowledged line has executed (the machine drained its planner).
    pub(super) fn confirm_all(&mut self, job: &Job, journal: &mut Option<Journal>) {
        let k = self.unconfirmed.len();
        self.confirm(job, k, journal);
    }

    pub(super) fn confirm(&mut self, job: &Job, upto_count: usize, journal: &mut Option<Journal>) {
        let mut last = None;
        for _ in 0..upto_count.min(self.unconfirmed.len()) {
            let Some(i) = self.unconfirmed.pop_front() else {
                break;
            };
            self.motion_after.pop_front();
            if !self.done[i] {
                self.done[i] = true;
                self.done_count += 1;
                self.length_done += job.lines[i].length;
                self.time_done += job.lines[i].time;
                self.time_done_run += job.lines[i].time;
            }
            last = Some(last.map_or(i, |l: usize| l.max(i)));
        }
        if let (Some(k), Some(j)) = (last, journal.as_mut()) {
            j.executed_through(k);
        }
    }

    pub(super) fn ack(&mut self, job: &Job, i: usize, journal: &mut Option<Journal>) {
        if !self.acked[i] {
            self.acked_count += 1;
        }
        self.acked[i] = true;
        let is_motion = job.lines[i].moves && job.lines[i].length >= self.min_motion;
        if is_motion {
            for m in self.motion_after.iter_mut() {
                *m += 1;
            }
        }
        self.unconfirmed.push_back(i);
        self.motion_after.push_back(0);
        if job.answer_waits_for_motion(i, self.laser) {
            // GRBL answered it only after every motion before it had finished, and it ran.
            self.confirm_all(job, journal);
            return;
        }
        // Lines with more motion lines acknowledged after them than GRBL can hold are done.
        let n = self
            .motion_after
            .iter()
            .take_while(|&&m| m >= self.capacity)
            .count();
        if n > 0 {
            self.confirm(job, n, journal);
        }
    }

    /// Confirms every unconfirmed line with index below `bound`.
    pub(super) fn confirm_below(&mut self, job: &Job, bound: usize, journal: &mut Option<Journal>) {
        let c = self.unconfirmed.iter().take_while(|&&i| i < bound).count();
        self.confirm(job, c, journal);
    }

    /// Line `i` was answered `error:N`: it did not run.
    pub(super) fn reject(&mut self, i: usize) {
        self.rejected[i] = true;
    }

    /// Line `i` ran from where an unexpected reset left the tool: it is sent again whatever the
    /// machine's position says.
    pub(super) fn keep_for_resend(&mut self, i: usize) {
        self.resend[i] = true;
    }

    /// Confirms by the reported position `pos` of a machine standing still: the first line sent
    /// in this run and not known executed (up to index `upto`, answered or not) whose path
    /// contains `pos` is where the machine stopped. Every line sent before it ran — GRBL runs
    /// lines in order, and the machine got past them — whether or not its `ok` was read (a stop
    /// may come while answers are still on the wire); it too if `pos` is its end point. A stop
    /// inside a line is journaled (`P`) so that a resume completes that line from there.
    pub(super) fn confirm_by_position(
        &mut self,
        job: &Job,
        pos: [f64; 3],
        upto: usize,
        journal: &mut Option<Journal>,
    ) {
        let upto = upto.min(job.len().saturating_sub(1));
        let open = |t: &Tracker, i: usize| !t.done[i] && !t.rejected[i] && !t.resend[i];
        let first_open = (self.first_open()..=upto).find(|&i| open(self, i));
        let first = match (first_open, self.unconfirmed.front()) {
            (Some(a), Some(&b)) => a.min(b),
            (Some(a), None) => a,
            (None, Some(&b)) => b,
            (None, None) => return,
        };
        let upto = upto.max(first);
        // GRBL parses no line after a dwell, a pause or a spindle or coolant change before that
        // line has finished and been answered, and its answer precedes the status report that
        // gave `pos` on the wire: the machine cannot stand on a line after an unanswered one.
        // (A pen that waits at the start of a closed stroke stands where the stroke ends too.)
        let upto = (first..=upto)
            .find(|&i| {
                !self.acked[i] && !self.rejected[i] && job.answer_waits_for_motion(i, self.laser)
            })
            .unwrap_or(upto);
        let (prior, rejected) = (&self.prior_done, &self.rejected);
        let places = places_on_path(job, pos, first..=upto, self.pos_tol, |i| {
            prior[i] || rejected[i]
        });
        // Ambiguous (the path passes here twice): the earliest place confirms least, and the
        // lines from there to the last place may have run: a resume must not pass over them
        // without the operator's `--resume-from`.
        let (Some(&(cut, partial)), Some(&(last, _))) = (places.first(), places.last()) else {
            return;
        };
        self.ran_unanswered(first..cut, journal);
        self.confirm_below(job, cut, journal);
        if last > cut
            && let Some(j) = journal.as_mut()
        {
            j.note(&format!(
                "{AMBIGUOUS_STOP_NOTE}: the machine stood at X{:.3} Y{:.3} Z{:.3} (work), which the path passes {} times",
                pos[0],
                pos[1],
                pos[2],
                places.len()
            ));
            j.uncertain(cut, last.min(job.len() - 1));
            return;
        }
        if cut < job.len()
            && let Some(j) = journal.as_mut()
        {
            // The lines from `cut` on did not run (the stop flushed GRBL's planner): the resume
            // continues line `cut` from where the machine stands.
            j.partial(cut, partial.unwrap_or(pos));
        }
    }

    /// The lines of `range` sent in this run whose answer was not read (still on the wire when
    /// the run stopped) but which ran, the machine standing past them: acknowledged (GRBL
    /// answered each before running it) and, with the acknowledged ones, confirmed by the caller.
    fn ran_unanswered(&mut self, range: std::ops::Range<usize>, journal: &mut Option<Journal>) {
        let unanswered: Vec<usize> = range
            .filter(|&i| !self.acked[i] && !self.rejected[i] && !self.resend[i])
            .collect();
        if unanswered.is_empty() {
            return;
        }
        // Answers in order: the earlier of these come first in the confirmation queue.
        let mut rest: Vec<usize> = self.unconfirmed.drain(..).collect();
        self.motion_after.clear();
        rest.extend(&unanswered);
        rest.sort_unstable();
        for i in rest {
            if unanswered.contains(&i) {
                self.acked[i] = true;
                self.acked_count += 1;
                if let Some(j) = journal.as_mut() {
                    j.ack(i);
                }
            }
            self.unconfirmed.push_back(i);
            self.motion_after.push_back(0);
        }
    }

    /// The first line not known executed (the job's length when all are).
    pub(super) fn first_open(&mut self) -> usize {
        while self.done.get(self.open_from).is_some_and(|d| *d) {
            self.open_from += 1;
        }
        self.open_from
    }

    pub(super) fn last_done(&self, job: &Job) -> Option<LineRef> {
        // The last line executed, exactly: after a rejected line, the lines GRBL already held
        // behind it ran too (the rejected one did not; its error names it).
        let i = self.done.iter().rposition(|d| *d)?;
        Some(line_ref(job, i))
    }
}

/// How the journal's note of a stop at a place the job's path passes more than once begins (a
/// resume names it as the reason the lines are in doubt).
pub(super) const AMBIGUOUS_STOP_NOTE: &str = "stopped where the job's path passes twice";

/// A line at least this long moves some axis by at least one step (its longest component is at
/// least its length / √3), so GRBL plans it; `$100-$102` (default 250 steps/mm).
fn min_motion(settings: &std::collections::BTreeMap<u16, f64>) -> f64 {
    let coarsest_step = (100..=102)
        .map(|n| settings.get(&n).copied().unwrap_or(250.0))
        .filter(|v| *v > 0.0 && v.is_finite())
        .map(|v| 1.0 / v)
        .fold(0.0, f64::max);
    3f64.sqrt() * coarsest_step
}
