//! The send journal: an append-only text file recording, as it happens, every line GRBL
//! acknowledged and every point at which the driver knew the acknowledged lines had executed.
//! `--resume` reads it back and sends exactly the lines that are not known to be done.
//!
//! Format (one record per line, `#` lines are comments):
//! ```text
//! flatcut-journal 1 <job hash, 16 hex digits> <line count>
//! T <index> <line> <text> the text of job line <index> (file line <line>), as sent; one per line
//!                         after the header, so that a resume of an edited file can show and
//!                         map what changed
//! R <run number>          a send run starts (acks and confirmations below belong to it)
//! F <wcs> <gx> <gy> <gz> <x> <y> <z>
//!                         where the job started: in G<wcs>, with G92 offset (gx, gy, gz), at
//!                         work position (x, y, z) (mm); the first one counts
//! O <x> <y> <z>           machine coordinates of the job's work origin (work zero) when it
//!                         started; the first one counts
//! A <index>               line <index> (0-based job line) was answered `ok` (at a stop, also a
//!                         line whose answer was still on the wire when the machine was found
//!                         standing past it: GRBL answers a line before running it)
//! W <index>               job lines of this run up to <index> may have been written to the port:
//!                         recorded (and handed to the OS) before their bytes are written. If the
//!                         run ends without a record settling its stop (`P`, `Q`, `S`, `D`), or a
//!                         later run's `K`, the lines it wrote that are not known executed are in
//!                         doubt ([`JournalState::sent`]): the sender died, but a controller keeps
//!                         running its RX buffer and planner. Journals without `W` read as before
//! E <index> <code>        line <index> was answered `error:<code>` (it did not run)
//! X <index>               every line acknowledged in this run with index <= <index> has executed
//! U <index>               lines of this run with index >= <index> are not known executed after
//!                         all (the machine was found somewhere else: a line was corrupted)
//! P <index> <x> <y> <z>   the run stopped part-way through line <index>, at this work position
//!                         (mm, G92-free); acknowledged lines of this run from <index> on did not run
//! Q <from> <to>           lines <from>..=<to> may or may not have run: the controller lost its
//!                         position (reset in motion); resuming needs an explicit choice
//! S <mx> <my> <mz> <wcs> <gx> <gy> <gz> <tlo> <modal words>
//!                         the run stopped with the controller at machine position (mx, my, mz)
//!                         in G<wcs>, G92 offset (gx, gy, gz), tool length offset <tlo> (mm) and
//!                         this parser state (`$G`'s G and M words); it counts until the next
//!                         `A` (a later run moved the machine)
//! K <from> <to>           resolved when resuming: lines <from>..<to> (exclusive) have executed,
//!                         none from <to> on has; earlier unconfirmed acknowledgements are settled
//! N <text>                a note (why the run stopped)
//! D                       the job completed
//! ```
//! An `ok` means GRBL queued the line, not that it moved: a reset or hang-up discards the
//! planner. So a line counts as done only if it was acknowledged *and* covered by a later
//! `X` of the same run (the driver writes `X` when the machine reports `Idle` with nothing in
//! flight, and when GRBL's planner capacity proves older lines finished). Acknowledgements a run
//! could not confirm (a hang-up) stay [`JournalState::unconfirmed`] until a resume settles them
//! with `K` from where the machine is found.

mod replay;

use crate::job::{Job, JobStart};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

const MAGIC: &str = "flatcut-journal";
const VERSION: u32 = 1;

/// Journal failures.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum JournalError {
    /// Reading or writing the file failed.
    #[error("journal {path}: {source}")]
    Io {
        /// Journal path.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not a journal or is damaged.
    #[error("journal {path}, line {line}: {what}")]
    Malformed {
        /// Journal path.
        path: PathBuf,
        /// 1-based line in the journal.
        line: usize,
        /// What is wrong.
        what: String,
    },
    /// The journal belongs to another job file.
    #[error(
        "journal {path} was written for a different job (hash {journal_hash:016x}, {journal_lines} lines; this file has hash {job_hash:016x}, {job_lines} lines): refusing to resume"
    )]
    DifferentJob {
        /// Journal path.
        path: PathBuf,
        /// Hash recorded in the journal.
        journal_hash: u64,
        /// Line count recorded in the journal.
        journal_lines: usize,
        /// Hash of the job given.
        job_hash: u64,
        /// Line count of the job given.
        job_lines: usize,
    },
}

/// How the lines of the job a journal was written for map onto the same file after an edit
/// (see `job_edit`).
pub trait LineMap {
    /// Where the journal's line `old` is in the edited job; `None` for a line the edit changed.
    fn map(&self, old: usize) -> Option<usize>;
    /// What changed, for the journal's note.
    fn summary(&self) -> String;
}

/// What a journal says about a job.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalState {
    /// Job hash recorded in the header.
    pub hash: u64,
    /// Job line count recorded in the header.
    pub lines: usize,
    /// Per job line: known executed.
    pub done: Vec<bool>,
    /// Per job line: rejected with this error code in the latest run that sent it.
    pub rejected: Vec<Option<u8>>,
    /// Number of runs recorded.
    pub runs: u32,
    /// Whether a run completed the job.
    pub finished: bool,
    /// Highest line index acknowledged in any run.
    pub last_acked: Option<usize>,
    /// Notes, in order.
    pub notes: Vec<String>,
    /// Acknowledged lines no run could confirm as executed or not (a hang-up), in order.
    pub unconfirmed: Vec<usize>,
    /// The line a run stopped part-way through, and the work position (mm, G92-free) it stopped at.
    pub partial: Option<(usize, [f64; 3])>,
    /// Lines that may or may not have run because the controller lost its position.
    pub uncertain: Option<(usize, usize)>,
    /// Where the job started (its frame on the controller), if recorded.
    pub start: Option<JobStart>,
    /// Machine coordinates of the work origin when the job started, if recorded.
    pub origin: Option<[f64; 3]>,
    /// Per job line: (file line, text sent), if recorded (empty otherwise).
    pub texts: Vec<(usize, String)>,
    /// What the controller said when the last run stopped, unless a later run moved it since.
    pub stop: Option<StopRecord>,
    /// The highest line a run wrote to the port (`W`) with no record settling what became of the
    /// lines it wrote: those not known executed may have run (see [`JournalState::in_doubt`]).
    pub sent: Option<usize>,
}

/// What the controller said when a run stopped and the machine stood still (the `S` record):
/// where it stood, in which frame, with which parser state. A resume compares it with what the
/// controller says then.
#[derive(Debug, Clone, PartialEq)]
pub struct StopRecord {
    /// Machine position, mm.
    pub machine: [f64; 3],
    /// Active coordinate system, 54..=59.
    pub wcs: u8,
    /// G92 offset, mm.
    pub g92: [f64; 3],
    /// Tool length offset (G43.1), mm.
    pub tlo: f64,
    /// The G and M words of the parser state (`$G`), e.g. `G0 G54 G17 G21 G90 G94 M5 M9`.
    pub modal: String,
}

impl StopRecord {
    /// The record's text (without the leading `S `).
    fn to_record(&self) -> String {
        let (m, g) = (self.machine, self.g92);
        format!(
            "{} {} {} {} {} {} {} {} {}",
            m[0], m[1], m[2], self.wcs, g[0], g[1], g[2], self.tlo, self.modal
        )
    }
}

impl JournalState {
    /// Indices of lines still to run, in order.
    pub fn remaining(&self) -> Vec<usize> {
        (0..self.lines).filter(|&i| !self.done[i]).collect()
    }

    /// Number of lines known executed.
    pub fn done_count(&self) -> usize {
        self.done.iter().filter(|d| **d).count()
    }

    /// Lines written to the port by a run that ended unsettled and not known executed (nor
    /// rejected): the controller may have run them after the sender died.
    pub fn in_doubt(&self) -> Vec<usize> {
        let Some(w) = self.sent else {
            return Vec::new();
        };
        (0..=w.min(self.lines.saturating_sub(1)))
            .filter(|&i| !self.done[i] && self.rejected[i].is_none())
            .collect()
    }

    /// Highest index `k` such that every line `0..=k` is done (the "last completed line").
    pub fn completed_prefix(&self) -> Option<usize> {
        let n = self.done.iter().take_while(|d| **d).count();
        n.checked_sub(1)
    }
}

/// An open journal, appending records for one run.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    file: File,
    buf: String,
    /// Records written to the OS since the last fsync.
    dirty: bool,
    /// Background fsync worker (see [`Journal::sync_in_background`]).
    syncer: Option<Syncer>,
}

/// A thread that fsyncs a clone of the journal's descriptor when asked, so that the streaming
/// loop never waits for the disk (an fsync can take 10–100 ms on a busy disk, while GRBL's RX
/// buffer drains in 11 ms at 115200 baud).
#[derive(Debug)]
struct Syncer {
    tx: Option<std::sync::mpsc::Sender<()>>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Syncer {
    fn drop(&mut self) {
        drop(self.tx.take());
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// The journal's first records: the header and every line's text.
fn header(job: &Job) -> String {
    let mut h = format!("{MAGIC} {VERSION} {:016x} {}\n", job.hash, job.len());
    for (i, l) in job.lines.iter().enumerate() {
        h.push_str(&format!("T {i} {} {}\n", l.source_line, l.text));
    }
    h
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> JournalError + '_ {
    move |source| JournalError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl Journal {
    /// Creates (truncating) a journal for `job` and starts run 1.
    pub fn create(path: impl AsRef<Path>, job: &Job) -> Result<Journal, JournalError> {
        let path = path.as_ref();
        let file = File::create(path).map_err(io_err(path))?;
        let mut j = Journal {
            path: path.to_path_buf(),
            file,
            buf: String::new(),
            dirty: false,
            syncer: None,
        };
        j.buf.push_str(&header(job));
        j.buf.push_str("R 1\n");
        j.sync()?;
        Ok(j)
    }

    /// Resumes an edited `job` with the journal at `path`, written for the job before the edit
    /// (`st`, with `changes` between the two): rewrites the journal for the edited job, its
    /// lines' records mapped onto the new lines (records of lines inside the changed stretch
    /// are dropped: those lines are new), with a note of the change, then resumes it as
    /// [`Journal::resume`] does. The rewrite replaces the file at once (write, then rename).
    pub fn resume_edited(
        path: impl AsRef<Path>,
        job: &Job,
        st: &JournalState,
        changes: &dyn LineMap,
    ) -> Result<(Journal, JournalState), JournalError> {
        let path = path.as_ref();
        let m = |i: usize| changes.map(i);
        let mut t = header(job);
        t.push_str("R 1\n");
        if let Some(s) = &st.start {
            let (g, p) = (s.g92, s.position);
            t.push_str(&format!(
                "F {} {} {} {} {} {} {}\n",
                s.wcs, g[0], g[1], g[2], p[0], p[1], p[2]
            ));
        }
        if let Some(o) = st.origin {
            t.push_str(&format!("O {} {} {}\n", o[0], o[1], o[2]));
        }
        for n in &st.notes {
            t.push_str(&format!("N {n}\n"));
        }
        let mut done = vec![false; job.len()];
        for i in (0..st.done.len()).filter(|&i| st.done[i]) {
            if let Some(k) = m(i).filter(|&k| k < done.len()) {
                done[k] = true;
            }
        }
        for (i, _) in done.iter().enumerate().filter(|(_, d)| **d) {
            t.push_str(&format!("A {i}\n"));
        }
        if let Some(last) = done.iter().rposition(|d| *d) {
            t.push_str(&format!("X {last}\n"));
        }
        // What a run left in doubt stays in doubt, in a run of its own.
        t.push_str("R 2\n");
        for k in st.unconfirmed.iter().filter_map(|&i| m(i)) {
            t.push_str(&format!("A {k}\n"));
        }
        if let Some((k, p)) = st.partial
            && let Some(k) = m(k)
        {
            t.push_str(&format!("P {k} {} {} {}\n", p[0], p[1], p[2]));
        }
        if let Some((a, b)) = st.uncertain
            && let (Some(a), Some(b)) = (m(a), m(b.min(st.lines - 1)))
        {
            t.push_str(&format!("Q {a} {b}\n"));
        }
        if let Some(w) = st.in_doubt().into_iter().filter_map(m).max() {
            t.push_str(&format!("W {w}\n"));
        }
        if let Some(r) = &st.stop {
            t.push_str(&format!("S {}\n", r.to_record()));
        }
        let summary = changes.summary().replace('\n', " / ");
        t.push_str(&format!(
            "N job edited after this journal was written: {summary}\n"
        ));
        let tmp = path.with_extension("journal-edit.tmp");
        let write = || -> std::io::Result<()> {
            let mut f = File::create(&tmp)?;
            f.write_all(t.as_bytes())?;
            f.sync_all()?;
            std::fs::rename(&tmp, path)
        };
        if let Err(e) = write() {
            let _ = std::fs::remove_file(&tmp);
            return Err(io_err(path)(e));
        }
        Journal::resume(path, job)
    }

    /// Opens an existing journal to resume `job`: checks that it was written for the same job,
    /// returns its state, and starts a new run in it.
    pub fn resume(
        path: impl AsRef<Path>,
        job: &Job,
    ) -> Result<(Journal, JournalState), JournalError> {
        let path = path.as_ref();
        let state = Journal::read(path)?;
        if state.hash != job.hash || state.lines != job.len() {
            return Err(JournalError::DifferentJob {
                path: path.to_path_buf(),
                journal_hash: state.hash,
                journal_lines: state.lines,
                job_hash: job.hash,
                job_lines: job.len(),
            });
        }
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(io_err(path))?;
        let mut j = Journal {
            path: path.to_path_buf(),
            file,
            buf: String::new(),
            dirty: false,
            syncer: None,
        };
        j.buf.push_str(&format!("R {}\n", state.runs + 1));
        j.sync()?;
        Ok((j, state))
    }

    /// Reads a journal. A torn last line (crash mid-write) is ignored.
    pub fn read(path: impl AsRef<Path>) -> Result<JournalState, JournalError> {
        replay::read(path.as_ref())
    }

    /// Path of the journal file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records that line `index` was acknowledged (buffered until [`Journal::sync`]).
    pub fn ack(&mut self, index: usize) {
        self.buf.push_str(&format!("A {index}\n"));
    }

    /// Records that job lines up to `index` may be written to the port, and hands the record to
    /// the OS at once (with what is buffered before it): called before the bytes are written.
    pub fn sending(&mut self, index: usize) -> Result<(), JournalError> {
        self.buf.push_str(&format!("W {index}\n"));
        self.flush()
    }

    /// Records that line `index` was rejected with `error:code`.
    pub fn reject(&mut self, index: usize, code: u8) {
        self.buf.push_str(&format!("E {index} {code}\n"));
    }

    /// Records that every line acknowledged in this run with index <= `index` has executed.
    pub fn executed_through(&mut self, index: usize) {
        self.buf.push_str(&format!("X {index}\n"));
    }

    /// Records that lines of this run with index >= `index` are not known executed after all.
    pub fn unconfirm_from(&mut self, index: usize) {
        self.buf.push_str(&format!("U {index}\n"));
    }

    /// Records that the run stopped part-way through line `index`, at work position `pos` (mm,
    /// G92-free).
    pub fn partial(&mut self, index: usize, pos: [f64; 3]) {
        self.buf
            .push_str(&format!("P {index} {} {} {}\n", pos[0], pos[1], pos[2]));
    }

    /// Records that lines `from..=to` may or may not have run (the controller lost its position).
    pub fn uncertain(&mut self, from: usize, to: usize) {
        self.buf.push_str(&format!("Q {from} {to}\n"));
    }

    /// Records what the controller said when the run stopped (see [`StopRecord`]).
    pub fn stopped_at(&mut self, r: &StopRecord) {
        self.buf.push_str(&format!("S {}\n", r.to_record()));
    }

    /// Records the resolution of a resume: lines `from..to` executed, none from `to` on.
    pub fn resolved(&mut self, from: usize, to: usize) {
        self.buf.push_str(&format!("K {from} {to}\n"));
    }

    /// Records where the job starts on the controller (its frame).
    pub fn start(&mut self, s: &JobStart) {
        let (g, p) = (s.g92, s.position);
        self.buf.push_str(&format!(
            "F {} {} {} {} {} {} {}\n",
            s.wcs, g[0], g[1], g[2], p[0], p[1], p[2]
        ));
    }

    /// Records the machine coordinates of the job's work origin when it started.
    pub fn origin(&mut self, m: [f64; 3]) {
        self.buf
            .push_str(&format!("O {} {} {}\n", m[0], m[1], m[2]));
    }

    /// Records a note (single line).
    pub fn note(&mut self, text: &str) {
        let t = text.replace(['\n', '\r'], " ");
        self.buf.push_str(&format!("N {t}\n"));
    }

    /// Records that the job completed.
    pub fn finish(&mut self) {
        self.buf.push_str("D\n");
    }

    /// Writes buffered records to the OS without waiting for the disk: they survive the sender
    /// being killed, not a power cut (see [`Journal::sync`]).
    pub fn flush(&mut self) -> Result<(), JournalError> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let path = self.path.clone();
        self.file
            .write_all(self.buf.as_bytes())
            .map_err(io_err(&path))?;
        self.buf.clear();
        self.dirty = true;
        Ok(())
    }

    /// Writes buffered records to the OS and asks a background thread to fsync them; returns at
    /// once. [`Journal::sync`] (at every stop) still waits for the disk.
    pub fn sync_in_background(&mut self) -> Result<(), JournalError> {
        self.flush()?;
        if self.syncer.is_none() {
            let file = self.file.try_clone().map_err(io_err(&self.path))?;
            let (tx, rx) = std::sync::mpsc::channel::<()>();
            let handle = std::thread::Builder::new()
                .name("journal-fsync".into())
                .spawn(move || {
                    while rx.recv().is_ok() {
                        // Requests that piled up during one fsync are served by the next.
                        while rx.try_recv().is_ok() {}
                        // An error here resurfaces in the foreground `sync` at the stop.
                        let _ = file.sync_data();
                    }
                })
                .map_err(io_err(&self.path))?;
            self.syncer = Some(Syncer {
                tx: Some(tx),
                handle: Some(handle),
            });
        }
        if let Some(tx) = self.syncer.as_ref().and_then(|s| s.tx.as_ref()) {
            let _ = tx.send(());
        }
        Ok(())
    }

    /// Writes buffered records and fsyncs them (called once per batch of acknowledgements).
    pub fn sync(&mut self) -> Result<(), JournalError> {
        if self.buf.is_empty() && !self.dirty {
            return Ok(());
        }
        self.flush()?;
        let path = self.path.clone();
        self.file.sync_data().map_err(io_err(&path))?;
        self.dirty = false;
        Ok(())
    }
}

impl Drop for Journal {
    fn drop(&mut self) {
        let _ = self.sync();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("flatcut-grbl-journal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn only_confirmed_acks_of_the_same_run_count_as_done() {
        let job = Job::parse("G1X1F100\nG1X2\nG1X3\nG1X4\nG1X5\n").unwrap();
        let p = tmp("runs.journal");
        {
            let mut j = Journal::create(&p, &job).unwrap();
            j.ack(0);
            j.reject(1, 20);
            j.ack(2);
            j.executed_through(2);
            j.ack(3); // acked but never confirmed: may have been lost in the planner
            j.note("hang-up");
            j.sync().unwrap();
        }
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.done, vec![true, false, true, false, false]);
        assert_eq!(st.rejected[1], Some(20));
        assert_eq!(st.remaining(), vec![1, 3, 4]);
        assert_eq!(st.completed_prefix(), Some(0));
        assert_eq!(st.last_acked, Some(3));
        {
            let (mut j, st0) = Journal::resume(&p, &job).unwrap();
            assert_eq!(st0, st);
            j.ack(1);
            // An X in run 2 must not confirm run 1's unconfirmed ack of line 3.
            j.executed_through(3);
            j.ack(3);
            j.ack(4);
            j.executed_through(4);
            // ... and a U in run 2 only withdraws run 2's confirmations.
            j.unconfirm_from(2);
            j.sync().unwrap();
        }
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.remaining(), vec![3, 4]);
        assert_eq!(st.done, vec![true, true, true, false, false]);
        assert_eq!(st.runs, 2);
    }

    #[test]
    fn unconfirmed_acks_survive_runs_until_a_resume_settles_them() {
        let job = Job::parse("G1X1F100\nG1X2\nG1X3\nG1X4\nG1X5\nG1X6\n").unwrap();
        let p = tmp("settle.journal");
        {
            let mut j = Journal::create(&p, &job).unwrap();
            j.ack(0);
            j.executed_through(0);
            j.ack(1);
            j.ack(2);
            j.note("hang-up");
            j.sync().unwrap();
        }
        // A resume that fails before settling anything keeps the doubt for the next one.
        drop(Journal::resume(&p, &job).unwrap());
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.unconfirmed, vec![1, 2]);
        assert_eq!(st.done, vec![true, false, false, false, false, false]);
        {
            let (mut j, _) = Journal::resume(&p, &job).unwrap();
            // The machine was found part-way through line 3.
            j.resolved(1, 3);
            j.partial(3, [3.5, 0.0, 0.0]);
            j.ack(3);
            j.ack(4);
            j.sync().unwrap();
        }
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.done, vec![true, true, true, false, false, false]);
        assert_eq!(st.partial, Some((3, [3.5, 0.0, 0.0])));
        assert_eq!(st.unconfirmed, vec![3, 4]);
        {
            let (mut j, _) = Journal::resume(&p, &job).unwrap();
            // A reset in motion: lines 3..=5 in doubt.
            j.uncertain(3, 5);
            j.sync().unwrap();
        }
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.uncertain, Some((3, 5)));
        {
            let (mut j, _) = Journal::resume(&p, &job).unwrap();
            // The operator resumes from line 4: 0..4 done, the rest not.
            j.resolved(0, 4);
            j.sync().unwrap();
        }
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.done, vec![true, true, true, true, false, false]);
        assert_eq!((st.uncertain, st.partial), (None, None));
        assert!(st.unconfirmed.is_empty());
        let mut text = std::fs::read_to_string(&p).unwrap();
        text.push_str("P 2 1.0 nan 0\n");
        std::fs::write(&p, text).unwrap();
        assert!(matches!(
            Journal::read(&p),
            Err(JournalError::Malformed { .. })
        ));
    }

    #[test]
    fn lines_written_by_a_run_that_died_unsettled_are_in_doubt_until_resolved() {
        let job = Job::parse("G1X1F100\nG1X2\nG1X3\nG1X4\nG1X5\nG1X6\n").unwrap();
        let p = tmp("written.journal");
        {
            // Everything answered was confirmed; lines 2..=4 were written, then the sender died.
            let mut j = Journal::create(&p, &job).unwrap();
            j.sending(1).unwrap();
            j.ack(0);
            j.ack(1);
            j.executed_through(1);
            j.sending(4).unwrap();
            std::mem::forget(j);
        }
        let st = Journal::read(&p).unwrap();
        assert!(st.unconfirmed.is_empty());
        assert_eq!((st.sent, st.in_doubt()), (Some(4), vec![2, 3, 4]));
        // A resume that settles nothing keeps the doubt.
        drop(Journal::resume(&p, &job).unwrap());
        assert_eq!(Journal::read(&p).unwrap().in_doubt(), vec![2, 3, 4]);
        {
            let (mut j, _) = Journal::resume(&p, &job).unwrap();
            j.resolved(2, 4);
            j.sending(5).unwrap();
            j.ack(4);
            j.ack(5);
            j.executed_through(5);
            j.finish();
            j.sync().unwrap();
        }
        let st = Journal::read(&p).unwrap();
        assert_eq!((st.sent, st.in_doubt()), (None, vec![]));
        assert_eq!(st.remaining(), Vec::<usize>::new());
        // A stop that settled what it wrote (`P`) leaves nothing in doubt; a journal without
        // `W` (an older one) reads as before.
        let mut j = Journal::create(&p, &job).unwrap();
        j.sending(3).unwrap();
        j.ack(0);
        j.executed_through(0);
        j.partial(1, [1.5, 0.0, 0.0]);
        j.sync().unwrap();
        drop(j);
        assert_eq!(Journal::read(&p).unwrap().sent, None);
        let old: String = std::fs::read_to_string(&p)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("W "))
            .map(|l| format!("{l}\n"))
            .collect();
        std::fs::write(&p, old).unwrap();
        let st = Journal::read(&p).unwrap();
        assert_eq!((st.sent, st.partial), (None, Some((1, [1.5, 0.0, 0.0]))));
    }

    #[test]
    fn a_stop_record_counts_until_a_later_run_moves_the_machine() {
        let job = Job::parse("G1X1F100\nG1X2\nG1X3\n").unwrap();
        let p = tmp("stop.journal");
        let rec = StopRecord {
            machine: [11.244, 10.416, 3.0],
            wcs: 55,
            g92: [1.0, 0.0, -0.5],
            tlo: 0.25,
            modal: "G0 G55 G17 G21 G90 G94 M5 M9".into(),
        };
        {
            let mut j = Journal::create(&p, &job).unwrap();
            j.ack(0);
            j.executed_through(0);
            j.stopped_at(&rec);
            j.sync().unwrap();
        }
        assert_eq!(Journal::read(&p).unwrap().stop.as_ref(), Some(&rec));
        // A resume refused before anything moved keeps it for the next attempt.
        drop(Journal::resume(&p, &job).unwrap());
        assert_eq!(Journal::read(&p).unwrap().stop.as_ref(), Some(&rec));
        {
            let (mut j, _) = Journal::resume(&p, &job).unwrap();
            j.ack(1);
            j.sync().unwrap();
        }
        assert_eq!(Journal::read(&p).unwrap().stop, None);
        let mut text = std::fs::read_to_string(&p).unwrap();
        text.push_str("S 1 2 3 53 0 0 0 0 G0\n");
        std::fs::write(&p, text).unwrap();
        assert!(matches!(
            Journal::read(&p),
            Err(JournalError::Malformed { .. })
        ));
    }

    #[test]
    fn refuses_a_different_job_and_tolerates_a_torn_tail() {
        let job = Job::parse("G1X1F100\nG1X2\n").unwrap();
        let other = Job::parse("G1X1F100\nG1X3\n").unwrap();
        let p = tmp("other.journal");
        drop(Journal::create(&p, &job).unwrap());
        let err = Journal::resume(&p, &other).unwrap_err();
        assert!(matches!(err, JournalError::DifferentJob { .. }), "{err}");
        assert!(err.to_string().contains("refusing to resume"));
        let mut text = std::fs::read_to_string(&p).unwrap();
        text.push_str("A 0\nX 0\nA 1\nX");
        std::fs::write(&p, text).unwrap();
        let st = Journal::read(&p).unwrap();
        assert_eq!(st.done, vec![true, false]);
        std::fs::write(&p, "hello\n").unwrap();
        assert!(matches!(
            Journal::read(&p),
            Err(JournalError::Malformed { line: 1, .. })
        ));
    }
}
