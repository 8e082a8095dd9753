//! Streaming: the job's lines queued (each run of lines to send behind a resume preamble), then
//! the loop that writes them with character counting, polls `?`, honours the operator's
//! controls, keeps the books and the journal, and notices every way a run can go wrong; and the
//! finish, which checks that the machine ended where the job ends.

use super::along::ahead_of_confirmed;
use super::check::job_uses_unknown_moves;
use super::error::line_ref;
use super::error::{LineError, SendError};
use super::geometry::{add, dist};
use super::progress::{Phase, Progress, eta};
use super::session::{Session, stop_noted, transport};
use super::stops::{
    abort, on_alarm, on_reset, stop_at_pause, stop_off_path, stop_unexpected, with_tool_off,
};
use super::tracker::Tracker;
use super::watch::{off_path, state_on_path};
use super::{
    CancelToken, JOURNAL_FSYNC_INTERVAL, POSITION_TOL_MM, PausePolicy, READ_SLICE, SendOptions,
};
use crate::job::{Job, LineKind};
use crate::journal::Journal;
use crate::response::MachineState;
use crate::streamer::{Event, SendMode, Tag};
use crate::transport::Transport;
use std::time::{Duration, Instant};

/// What [`queue`] put in the streamer.
pub(super) struct Queued {
    /// Job lines to send in this run.
    pub lines: usize,
    /// Resume preamble lines, in order (indexed by `Tag::Preamble`).
    pub preamble: Vec<String>,
    /// Every text queued, preamble and job lines, in the order they go out.
    pub texts: Vec<String>,
}

/// Queues every line not yet done: each contiguous run that does not start at the top of the
/// file gets a preamble putting the machine into the state the job had there; the first run of
/// a resume may start at `resume_at` = (line, work position, travel needed) instead.
pub(super) fn queue<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    tracker: &Tracker,
    mut resume_at: Option<(usize, [f64; 3], bool)>,
) -> Queued {
    let n = job.len();
    let mut q = Queued {
        lines: 0,
        preamble: Vec::new(),
        texts: Vec::new(),
    };
    let mut i = 0;
    while i < n {
        if tracker.done[i] {
            i += 1;
            continue;
        }
        let mut text = if i > 0 || resume_at.is_some() {
            let pre = match resume_at.take() {
                Some((k, at, travel)) if k == i => job.resume_preamble_from(i, at, travel),
                _ => job.resume_preamble(i),
            };
            for p in pre {
                let tag = Tag::Preamble(q.preamble.len() as u32);
                sess.s.push(tag, p.clone(), SendMode::CharCount);
                q.texts.push(p.clone());
                q.preamble.push(p);
            }
            job.resume_line(i)
        } else {
            job.lines[i].text.clone()
        };
        while i < n && !tracker.done[i] {
            let mode = match job.lines[i].kind {
                LineKind::Gcode => SendMode::CharCount,
                LineKind::System | LineKind::EepromWrite => SendMode::SendResponse,
            };
            q.texts.push(text.clone());
            sess.s.push(Tag::Job(i), std::mem::take(&mut text), mode);
            q.lines += 1;
            i += 1;
            if i < n {
                text = job.lines[i].text.clone();
            }
        }
    }
    q
}

/// What the streaming loop measured.
#[derive(Debug, Clone, Copy)]
pub(super) struct Streamed {
    /// Bytes written while streaming.
    pub bytes: u64,
    /// First job byte to the last answer.
    pub time: Duration,
}

/// The streaming loop's state. See [`Stream::run`].
pub(super) struct Stream<'s, 'a, T: Transport + ?Sized> {
    sess: &'s mut Session<'a, T>,
    job: &'s Job,
    /// The job timed with the controller's settings (for progress and ETA).
    job_t: &'s Job,
    opts: &'s SendOptions,
    tracker: &'s mut Tracker,
    journal: &'s mut Option<Journal>,
    preamble: &'s [String],
    start: Instant,
    bytes_before: u64,
    last_poll: Instant,
    last_progress: Instant,
    last_response: Instant,
    idle_since_response: u32,
    holding: bool,
    failure: Option<SendError>,
    stream_end: Option<Duration>,
    end_status_seq: u64,
    hold_since: Option<Instant>,
    last_fsync: Instant,
    /// The `G4` that proves the planner empty was answered.
    synced: bool,
    /// The job line whose `M0` holds the machine, and whether it was resumed already.
    paused: Option<(usize, bool)>,
    /// The position tolerance (mm) when the reported position is checked against the job's
    /// path; `None` when it is not (not asked, or a job moving where this model cannot follow).
    watch_tol: Option<f64>,
    /// The path length shown so far, mm: progress never goes back.
    shown_length: f64,
    /// The highest job line journaled as written (`W`).
    written: Option<usize>,
}

/// Tag of the `G4 P0.01` the sender appends to find out that the planner is empty: GRBL answers
/// a dwell only after every queued motion has finished (`mc_dwell` syncs the buffer first).
const SYNC_TAG: Tag = Tag::Setup(u32::MAX - 1);

impl<'s, 'a, T: Transport + ?Sized> Stream<'s, 'a, T> {
    /// A loop over the lines queued in `sess` (with `preamble` the texts of `Tag::Preamble`s).
    pub(super) fn new(
        sess: &'s mut Session<'a, T>,
        (job, job_t): (&'s Job, &'s Job),
        opts: &'s SendOptions,
        tracker: &'s mut Tracker,
        journal: &'s mut Option<Journal>,
        preamble: &'s [String],
    ) -> Self {
        let now = Instant::now();
        // Tolerance: the operator's, plus a step on the coarsest axis and the report's rounding
        // (the machine steps along a staircase around the programmed line).
        let watch_tol = opts
            .position_tolerance
            .filter(|_| !job_uses_unknown_moves(job))
            .map(|t| t + 2.0 * tracker.pos_tol);
        Stream {
            bytes_before: sess.s.bytes_written(),
            sess,
            job,
            job_t,
            opts,
            tracker,
            journal,
            preamble,
            start: now,
            last_poll: now - opts.status_interval,
            last_progress: now,
            last_response: now,
            idle_since_response: 0,
            holding: false,
            failure: None,
            stream_end: None,
            end_status_seq: 0,
            hold_since: None,
            last_fsync: now,
            synced: false,
            paused: None,
            watch_tol,
            shown_length: 0.0,
            written: None,
        }
    }

    /// Streams until every line is answered and the machine has drained its planner, or until
    /// the run stops (the error says why and names the last line executed).
    pub(super) fn run(
        &mut self,
        progress: &mut Progress,
        observer: &mut dyn FnMut(&Progress),
        cancel: &CancelToken,
    ) -> Result<Streamed, SendError> {
        progress.phase = Phase::Streaming;
        loop {
            self.control(cancel)?;
            self.write_ahead()?;
            let evs = match self.sess.pump(READ_SLICE) {
                Ok(e) => e,
                Err(e) => return self.link_failed(e),
            };
            if let Some(Tag::Job(i)) = self.sess.s.last_sent() {
                self.tracker.sent(i);
            }
            let acked = self.handle(evs, progress)?;
            // Refill GRBL's RX buffer at once: the answers just read made room, and the link
            // idles until the next line is written.
            self.write_ahead()?;
            if let Err(e) = self.sess.write() {
                return self.link_failed(e);
            }
            if acked {
                self.journal_batch()?;
            }
            self.check_health(progress)?;
            if self.paused.is_some_and(|p| p.1) {
                progress.paused_at = None;
            }
            if self.drained(progress) {
                break;
            }
            progress.holding = self.holding;
            self.report(progress, observer);
        }
        if let Some(mut err) = self.failure.take() {
            if let SendError::LineRejected { last_done, .. } = &mut err {
                *last_done = self.tracker.last_done(self.job);
            }
            if let Some(j) = self.journal.as_mut() {
                j.sync()?;
            }
            return Err(with_tool_off(self.sess, self.journal, err));
        }
        Ok(Streamed {
            bytes: self.sess.s.bytes_written() - self.bytes_before,
            time: self.stream_end.unwrap_or_default(),
        })
    }

    /// The operator's requests (feed hold, resume, abort) and the periodic status poll.
    fn control(&mut self, cancel: &CancelToken) -> Result<(), SendError> {
        let c = cancel.take();
        if c.abort {
            // At a program pause the machine stands where the pause is: everything before it ran.
            let at_pause = self.paused.filter(|p| !p.1).map(|p| p.0);
            return Err(abort(
                self.sess,
                self.job_t,
                at_pause,
                self.tracker,
                self.journal,
            )?);
        }
        if c.hold && !self.holding {
            self.sess.s.realtime(b'!');
            self.holding = true;
        }
        if c.resume && self.holding {
            self.sess.s.realtime(b'~');
            self.holding = false;
        } else if c.resume && self.paused.is_some_and(|p| !p.1) {
            self.resume_pause();
        }
        if self.last_poll.elapsed() >= self.opts.status_interval {
            self.sess.s.realtime(b'?');
            self.last_poll = Instant::now();
        }
        Ok(())
    }

    /// Journals the highest job line the next write hands to the port before it is written
    /// (`W`): a sender that dies after the write leaves those lines in doubt, not forgotten,
    /// since the controller runs what it received. One record per write that goes further.
    fn write_ahead(&mut self) -> Result<(), SendError> {
        let Some(i) = self.sess.s.next_job_line() else {
            return Ok(());
        };
        if self.written.is_some_and(|w| w >= i) {
            return Ok(());
        }
        if let Some(j) = self.journal.as_mut() {
            j.sending(i)?;
        }
        self.written = Some(i);
        Ok(())
    }

    /// The port failed: journal it and stop.
    fn link_failed<R>(&mut self, e: crate::transport::TransportError) -> Result<R, SendError> {
        let why = format!("transport failure: {e}");
        let last = self.tracker.last_done(self.job);
        stop_noted(self.journal, &why, transport(e, last))
    }

    /// Handles one batch of what the controller said; true if a job line was acknowledged. An
    /// alarm or a reset ends the run here.
    fn handle(&mut self, evs: Vec<Event>, progress: &mut Progress) -> Result<bool, SendError> {
        let mut acked_any = false;
        let mut batch = evs.into_iter();
        while let Some(e) = batch.next() {
            match e {
                Event::Ack(SYNC_TAG) | Event::Rejected(SYNC_TAG, _) => self.synced = true,
                Event::Ack(tag) => {
                    self.answered();
                    if let Tag::Job(i) = tag {
                        if let Some(j) = self.journal.as_mut() {
                            j.ack(i);
                        }
                        self.tracker.ack(self.job_t, i, self.journal);
                        progress.last_acked = Some(line_ref(self.job, i));
                        acked_any = true;
                    }
                }
                Event::Rejected(tag, code) => self.rejected(tag, code),
                Event::Alarm(code) => {
                    let rest: Vec<Event> = batch.collect();
                    let (job, opts) = (self.job_t, self.opts);
                    let err =
                        on_alarm(self.sess, job, code, rest, opts, self.tracker, self.journal);
                    return Err(err?);
                }
                Event::Reset { lost, .. } => {
                    let rest: Vec<Event> = batch.collect();
                    let err = on_reset(
                        self.sess,
                        self.job_t,
                        lost,
                        rest,
                        self.tracker,
                        self.journal,
                    );
                    return Err(err?);
                }
                Event::Status(st) => {
                    if st.state == MachineState::Idle {
                        if self.sess.s.in_flight() == 0 {
                            // Idle with GRBL's RX buffer empty: it already ran its auto cycle
                            // start, so the planner is empty and every acknowledged line ran.
                            // (Idle while lines wait in the RX buffer may still hold queued,
                            // unstarted blocks: GRBL starts the cycle only when the planner is
                            // full or the RX buffer is empty.)
                            self.tracker.confirm_all(self.job_t, self.journal);
                        } else {
                            self.idle_since_response += 1;
                        }
                    }
                    progress.state = Some(st.state);
                    progress.position = self.sess.work_position();
                    self.watch(st.state)?;
                }
                _ => {}
            }
        }
        Ok(acked_any)
    }

    /// Checks a status report's position against the stretch of the job's path the machine can
    /// be on, and stops the run when it is off it (see `watch`). Not after a rejected line: the
    /// lines GRBL runs behind it start from where the rejected one did not go.
    fn watch(&mut self, state: MachineState) -> Result<(), SendError> {
        let Some(tol) = self.watch_tol else {
            return Ok(());
        };
        if self.failure.is_some() || !state_on_path(state) {
            return Ok(());
        }
        let Some(p) = self.sess.work_position() else {
            return Ok(());
        };
        let preamble_first = !self.preamble.is_empty();
        match off_path(self.job, self.tracker, p, tol, preamble_first) {
            None => Ok(()),
            Some(off) => {
                let err = stop_off_path(self.sess, self.job, self.tracker, self.journal, off, tol);
                Err(err?)
            }
        }
    }

    /// The job line whose `M0` holds the machine: the oldest line in flight (GRBL keeps an
    /// `M0`'s `ok` until cycle start).
    fn pausing_line(&self) -> Option<usize> {
        match self.sess.s.in_flight_tags().first() {
            Some(Tag::Job(i)) if self.job.pauses(*i) => Some(*i),
            _ => None,
        }
    }

    /// The job line whose `M0` the controller has reached, if it has: the `M0` is the oldest
    /// line in flight, the machine stands in a completed hold, and it stands where
    /// the lines before the pause end. GRBL runs every queued motion before it pauses
    /// (`protocol_buffer_synchronize` in `gc_execute_line`), so then every line before the
    /// pause has run; a hold anywhere else is someone else's (a hold button, the door).
    fn pause_reached(&self) -> Option<usize> {
        let st = self.sess.status.as_ref()?;
        // Not Idle: GRBL may report Idle with blocks queued before it parses the `M0` (it
        // starts the cycle only then), standing where the path may pass again.
        if st.state != (MachineState::Hold { complete: true }) {
            return None;
        }
        let line = self.pausing_line()?;
        let here = self.sess.work_position()?;
        (dist(here, self.job.start_of(line)) <= self.tracker.pos_tol).then_some(line)
    }

    /// The job paused itself (`M0`) and the controller has reached the pause: every line
    /// before it ran. Resume, abort or wait, as the options say.
    fn program_pause(&mut self, line: usize, progress: &mut Progress) -> Result<(), SendError> {
        if self.paused.is_some_and(|p| p.0 == line) {
            return Ok(());
        }
        self.paused = Some((line, false));
        if let Some(j) = self.journal.as_mut() {
            let n = self.job.lines[line].source_line;
            j.note(&format!("paused by the job at line {n} (M0)"));
        }
        match self.opts.on_pause {
            PausePolicy::Resume => self.resume_pause(),
            PausePolicy::Wait => progress.paused_at = Some(line_ref(self.job, line)),
            PausePolicy::Abort => {
                stop_at_pause(self.sess, self.job_t, line, self.tracker, self.journal)?;
                let err = SendError::PausedByJob {
                    line: line_ref(self.job, line),
                    last_done: self.tracker.last_done(self.job),
                };
                return Err(with_tool_off(self.sess, self.journal, err));
            }
        }
        Ok(())
    }

    /// Cycle start after the job's own pause.
    fn resume_pause(&mut self) {
        self.sess.s.realtime(b'~');
        if let Some(p) = self.paused.as_mut() {
            p.1 = true;
        }
    }

    fn answered(&mut self) {
        self.last_response = Instant::now();
        self.idle_since_response = 0;
    }

    /// `error:N`: a job line stops the feed (lines already in GRBL's buffer still run); so does
    /// a rejected preamble line.
    fn rejected(&mut self, tag: Tag, code: u8) {
        let failure = match tag {
            Tag::Job(i) => {
                self.tracker.reject(i);
                if let Some(j) = self.journal.as_mut() {
                    j.reject(i, code);
                    let line = self.job.lines[i].source_line;
                    j.note(&format!("line {line} rejected: error:{code}"));
                }
                self.answered();
                SendError::LineRejected {
                    error: LineError {
                        line: line_ref(self.job, i),
                        code,
                    },
                    last_done: None,
                }
            }
            Tag::Preamble(k) => SendError::PreambleRejected {
                text: self.preamble[k as usize].clone(),
                code,
            },
            Tag::Setup(_) => return,
        };
        self.sess.s.set_feeding(false);
        self.sess.s.clear_queue();
        if self.failure.is_none() {
            self.failure = Some(failure);
        }
    }

    /// Writes the batch's journal records to the OS, with an fsync on the background thread
    /// at most every [`JOURNAL_FSYNC_INTERVAL`].
    fn journal_batch(&mut self) -> Result<(), SendError> {
        if let Some(j) = self.journal.as_mut() {
            if self.last_fsync.elapsed() >= JOURNAL_FSYNC_INTERVAL {
                j.sync_in_background()?;
                self.last_fsync = Instant::now();
            } else {
                j.flush()?;
            }
        }
        Ok(())
    }

    /// Stops when bytes were lost on the link, the machine sits in a hold or check mode this
    /// sender did not ask for, or the controller went silent.
    fn check_health(&mut self, progress: &mut Progress) -> Result<(), SendError> {
        let in_flight = self.sess.s.in_flight();
        if in_flight > 0
            && self.idle_since_response >= 2
            && self.last_response.elapsed() >= self.opts.idle_ack_timeout
        {
            return stop_noted(
                self.journal,
                &format!("{in_flight} line(s) unanswered while idle: link lost bytes"),
                SendError::LostAck {
                    in_flight,
                    last_done: self.tracker.last_done(self.job),
                },
            );
        }
        let state = self.sess.status.as_ref().map(|s| s.state);
        let held = matches!(
            state,
            Some(MachineState::Hold { .. }) | Some(MachineState::Door(_))
        );
        if !self.holding
            && let Some(line) = self.pause_reached()
        {
            return self.program_pause(line, progress);
        }
        if held && !self.holding {
            let since = *self.hold_since.get_or_insert_with(Instant::now);
            if self.opts.hold_timeout.is_some_and(|t| since.elapsed() >= t) {
                return Err(stop_unexpected(
                    self.sess,
                    self.job_t,
                    self.tracker,
                    self.journal,
                )?);
            }
        } else {
            self.hold_since = None;
        }
        if state == Some(MachineState::Check) {
            // Lines acknowledged in check mode do not move: never count them as done.
            return Err(stop_unexpected(
                self.sess,
                self.job_t,
                self.tracker,
                self.journal,
            )?);
        }
        if self.sess.last_rx.elapsed() >= self.opts.silence_timeout && !held {
            return stop_noted(
                self.journal,
                "controller silent",
                SendError::DeviceSilent {
                    waited: self.sess.last_rx.elapsed(),
                    last_done: self.tracker.last_done(self.job),
                },
            );
        }
        Ok(())
    }

    /// Whether the stream is complete (or stopped on an error) and the machine has drained its
    /// planner: an Idle report requested after the last answer.
    fn drained(&mut self, progress: &mut Progress) -> bool {
        if self.sess.s.queued() > 0 || self.sess.s.in_flight() > 0 {
            return false;
        }
        if self.stream_end.is_none() {
            self.stream_end = Some(self.start.elapsed());
            progress.phase = Phase::Finishing;
            // A status report alone may say Idle before GRBL's auto cycle start has begun the
            // last queued moves: finish only after a dwell's answer proves the planner empty.
            self.sess.s.set_feeding(true);
            self.sess
                .s
                .push(SYNC_TAG, "G4P0.01", SendMode::SendResponse);
            return false;
        }
        if !self.synced {
            return false;
        }
        if self.end_status_seq == 0 {
            self.end_status_seq = self.sess.status_seq.max(1);
            self.sess.s.realtime(b'?');
            self.last_poll = Instant::now();
        }
        let idle = self
            .sess
            .status
            .as_ref()
            .is_some_and(|s| s.state == MachineState::Idle);
        if idle && self.sess.status_seq > self.end_status_seq {
            self.tracker.confirm_all(self.job_t, self.journal);
            return true;
        }
        false
    }

    /// Calls the observer at most every `progress_interval`. Counters are kept incrementally:
    /// this loop runs once per answer batch and must stay O(1) in the job size to keep the link
    /// busy.
    fn report(&mut self, progress: &mut Progress, observer: &mut dyn FnMut(&Progress)) {
        if self.last_progress.elapsed() < self.opts.progress_interval {
            return;
        }
        progress.lines_acked = self.tracker.acked_count;
        progress.lines_done = self.tracker.done_count;
        // Where the machine stands on the lines not confirmed yet counts too: a status report
        // places it on the path from the first line on.
        let ahead = match self.sess.work_position() {
            Some(p) if self.failure.is_none() => {
                let tol = 4.0 * self.tracker.pos_tol;
                let pre = !self.preamble.is_empty();
                ahead_of_confirmed(self.job_t, self.tracker, p, tol, pre).unwrap_or_default()
            }
            _ => Default::default(),
        };
        let length = (self.tracker.length_done + ahead.length).min(self.job.total_length);
        self.shown_length = self.shown_length.max(length);
        progress.length_done = self.shown_length;
        progress.elapsed = self.start.elapsed();
        progress.bytes_written = self.sess.s.bytes_written() - self.bytes_before;
        progress.eta = Some(eta(self.tracker, self.start.elapsed(), ahead.time));
        observer(progress);
        self.last_progress = Instant::now();
    }
}

/// After a complete stream: checks that a run which moved the machine ended where the job ends
/// (a line corrupted on the link moves elsewhere), marks the journal complete, and returns the
/// final work position.
pub(super) fn finish<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    opts: &SendOptions,
    lines_sent: usize,
    journal: &mut Option<Journal>,
) -> Result<Option<[f64; 3]>, SendError> {
    let final_position = sess.work_position();
    if opts.verify_end_position
        && lines_sent > 0
        && !job_uses_unknown_moves(job)
        && let Some(p) = final_position
    {
        let e = add(job.end_state.position, [0.0; 3]);
        if dist(p, e) > POSITION_TOL_MM * 10.0 {
            let err = SendError::PositionMismatch {
                expected: e,
                actual: p,
            };
            let why = format!("end position {p:?} differs from the job's end {e:?}");
            let err = match stop_noted::<()>(journal, &why, err) {
                Err(e) => e,
                Ok(()) => unreachable!("stop_noted always stops"),
            };
            return Err(with_tool_off(sess, journal, err));
        }
    }
    if let Some(j) = journal.as_mut() {
        j.finish();
        j.sync()?;
    }
    Ok(final_position)
}
