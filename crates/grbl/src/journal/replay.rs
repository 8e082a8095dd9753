//! Reading a send journal back: the header, then every complete record replayed in order into
//! the [`JournalState`] it describes (the format is in the parent module's doc).

use super::{JournalError, JournalState, MAGIC, StopRecord, VERSION, io_err};
use crate::job::JobStart;
use std::path::Path;

/// Reads the journal at `path`. A torn last line (crash mid-write) is ignored.
pub(super) fn read(path: &Path) -> Result<JournalState, JournalError> {
    let text = std::fs::read_to_string(path).map_err(io_err(path))?;
    let mut records = complete_lines(&text).lines().enumerate();
    let (_, header) = records
        .next()
        .ok_or_else(|| malformed(path, 1, "empty file"))?;
    let (hash, lines) = parse_header(path, header)?;
    let mut replay = Replay::new(path, hash, lines);
    for (n0, record) in records {
        replay.record(n0 + 1, record)?;
    }
    Ok(replay.finish())
}

/// The error for a bad record on (1-based) line `line` of the journal.
fn malformed(path: &Path, line: usize, what: &str) -> JournalError {
    JournalError::Malformed {
        path: path.to_path_buf(),
        line,
        what: what.to_string(),
    }
}

/// The text up to and including its last newline: a torn last line is left out.
fn complete_lines(text: &str) -> &str {
    if text.ends_with('\n') {
        text
    } else {
        text.rsplit_once('\n').map(|(a, _)| a).unwrap_or("")
    }
}

/// The job hash and line count of the header line, after checking its magic and version.
fn parse_header(path: &Path, header: &str) -> Result<(u64, usize), JournalError> {
    let h: Vec<&str> = header.split_whitespace().collect();
    if h.len() != 4 || h[0] != MAGIC {
        return Err(malformed(path, 1, "not a flatcut journal header"));
    }
    if h[1] != VERSION.to_string() {
        return Err(malformed(
            path,
            1,
            &format!("unsupported journal version {}", h[1]),
        ));
    }
    let hash = u64::from_str_radix(h[2], 16).map_err(|_| malformed(path, 1, "bad job hash"))?;
    let lines: usize = h[3]
        .parse()
        .map_err(|_| malformed(path, 1, "bad line count"))?;
    Ok((hash, lines))
}

/// The state of a job of `lines` lines before any record: nothing sent, nothing done.
fn fresh_state(hash: u64, lines: usize) -> JournalState {
    JournalState {
        hash,
        lines,
        done: vec![false; lines],
        rejected: vec![None; lines],
        runs: 0,
        finished: false,
        last_acked: None,
        notes: Vec::new(),
        unconfirmed: Vec::new(),
        partial: None,
        uncertain: None,
        start: None,
        origin: None,
        texts: Vec::new(),
        stop: None,
        sent: None,
    }
}

/// The journal's state as its records are replayed one by one, with the bookkeeping of the runs
/// that the final state does not keep.
struct Replay<'a> {
    path: &'a Path,
    st: JournalState,
    /// Acks of the current run not yet confirmed, kept sorted by arrival (= index order within a
    /// run except across resume gaps).
    pending: Vec<usize>,
    /// Acks of the current run confirmed executed (an `U` may take them back).
    confirmed: Vec<usize>,
    /// Unconfirmed acknowledgements of earlier runs, waiting for a `K`.
    carried: Vec<usize>,
    /// The current run's `W` high-water mark.
    written: Option<usize>,
    /// The highest `W` of earlier unsettled runs.
    carried_written: Option<usize>,
}

impl<'a> Replay<'a> {
    fn new(path: &'a Path, hash: u64, lines: usize) -> Self {
        Replay {
            path,
            st: fresh_state(hash, lines),
            pending: Vec::new(),
            confirmed: Vec::new(),
            carried: Vec::new(),
            written: None,
            carried_written: None,
        }
    }

    fn bad(&self, n: usize, what: &str) -> JournalError {
        malformed(self.path, n, what)
    }

    /// A job line index of record line `n`, checked against the job's length.
    fn index(&self, n: usize, s: Option<&str>) -> Result<usize, JournalError> {
        let lines = self.st.lines;
        let i: usize = s
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| self.bad(n, "missing index"))?;
        if i >= lines {
            return Err(self.bad(n, &format!("line index {i} beyond the job's {lines} lines")));
        }
        Ok(i)
    }

    /// A finite coordinate (mm).
    fn coord(&self, n: usize, s: Option<&str>) -> Result<f64, JournalError> {
        s.and_then(|s| s.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(n, "missing or bad coordinate"))
    }

    /// The next three coordinates of `words`, in order.
    fn point<'w>(
        &self,
        n: usize,
        words: &mut impl Iterator<Item = &'w str>,
    ) -> Result<[f64; 3], JournalError> {
        Ok([
            self.coord(n, words.next())?,
            self.coord(n, words.next())?,
            self.coord(n, words.next())?,
        ])
    }

    /// A coordinate system number, 54..=59.
    fn wcs(&self, n: usize, s: Option<&str>) -> Result<u8, JournalError> {
        s.and_then(|s| s.parse::<u8>().ok())
            .filter(|n| (54..=59).contains(n))
            .ok_or_else(|| self.bad(n, "bad coordinate system"))
    }

    /// Applies record line `n`.
    fn record(&mut self, n: usize, rec: &str) -> Result<(), JournalError> {
        let mut parts = rec.splitn(2, ' ');
        let kind = parts.next().unwrap_or("");
        let rest = parts.next();
        match kind {
            "" | "#" => {}
            "R" => self.run_started(),
            "A" => self.acked(n, rest)?,
            "W" => self.writing(n, rest)?,
            "E" => self.rejected(n, rest)?,
            "X" => self.executed(n, rest)?,
            "U" => self.unconfirmed(n, rest)?,
            "P" => self.stopped_part_way(n, rest)?,
            "Q" => self.position_lost(n, rest)?,
            "K" => self.settled(n, rest)?,
            "F" => self.job_start(n, rest)?,
            "O" => self.work_origin(n, rest)?,
            "T" => self.line_text(n, rest)?,
            "S" => self.stop(n, rest)?,
            "N" => self.st.notes.push(rest.unwrap_or("").to_string()),
            "D" => self.finished(),
            _ => return Err(self.bad(n, &format!("unknown record '{kind}'"))),
        }
        Ok(())
    }

    /// `R`: a run starts; the previous run's unconfirmed acks and writes carry over.
    fn run_started(&mut self) {
        self.st.runs += 1;
        self.carried.append(&mut self.pending);
        self.confirmed.clear();
        self.carried_written = self.carried_written.max(self.written.take());
    }

    /// `A <index>`.
    fn acked(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let i = self.index(n, rest)?;
        self.st.rejected[i] = None;
        self.st.last_acked = Some(self.st.last_acked.map_or(i, |l| l.max(i)));
        self.pending.push(i);
        self.st.stop = None;
        Ok(())
    }

    /// `W <index>`.
    fn writing(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let i = self.index(n, rest)?;
        self.written = self.written.max(Some(i));
        Ok(())
    }

    /// `E <index> <code>`.
    fn rejected(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let mut w = rest.unwrap_or("").split_whitespace();
        let i = self.index(n, w.next())?;
        let code = w
            .next()
            .and_then(|c| c.parse().ok())
            .ok_or_else(|| self.bad(n, "missing code"))?;
        self.st.rejected[i] = Some(code);
        Ok(())
    }

    /// `X <index>`: the run's acks up to `index` executed.
    fn executed(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let k = self.index(n, rest)?;
        let (done, confirmed) = (&mut self.st.done, &mut self.confirmed);
        self.pending.retain(|&i| {
            if i <= k {
                done[i] = true;
                confirmed.push(i);
                false
            } else {
                true
            }
        });
        Ok(())
    }

    /// `U <index>`: the run's confirmed lines from `index` on are not known executed after all.
    fn unconfirmed(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let k = self.index(n, rest)?;
        let done = &mut self.st.done;
        self.confirmed.retain(|&i| {
            if i >= k {
                done[i] = false;
                false
            } else {
                true
            }
        });
        Ok(())
    }

    /// `P <index> <x> <y> <z>`: the run stopped part-way through line `index`.
    fn stopped_part_way(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let mut w = rest.unwrap_or("").split_whitespace();
        let k = self.index(n, w.next())?;
        let p = self.point(n, &mut w)?;
        self.pending.retain(|&i| i < k);
        self.st.partial = Some((k, p));
        self.written = None;
        Ok(())
    }

    /// The `<a> <b>` range of a `Q` or `K` record: a line index and an end at most the job's
    /// length.
    fn range(&self, n: usize, rest: Option<&str>) -> Result<(usize, usize), JournalError> {
        let mut w = rest.unwrap_or("").split_whitespace();
        let a = self.index(n, w.next())?;
        let b: usize = w
            .next()
            .and_then(|s| s.parse().ok())
            .filter(|&b| b <= self.st.lines)
            .ok_or_else(|| self.bad(n, "missing or bad range end"))?;
        Ok((a, b))
    }

    /// `Q <a> <b>`: the controller lost its position; lines `a..b` may or may not have run.
    fn position_lost(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let (a, b) = self.range(n, rest)?;
        self.written = None;
        self.pending.clear();
        self.st.uncertain = Some((a, b));
        Ok(())
    }

    /// `K <a> <b>`: lines `a..b` are done and those from `b` on are not; every doubt is settled.
    fn settled(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let (a, b) = self.range(n, rest)?;
        self.written = None;
        self.carried_written = None;
        for (i, d) in self.st.done.iter_mut().enumerate() {
            if i >= b {
                *d = false;
            } else if i >= a {
                *d = true;
            }
        }
        self.carried.clear();
        self.pending.clear();
        self.st.uncertain = None;
        self.st.partial = None;
        Ok(())
    }

    /// `F <wcs> <gx> <gy> <gz> <x> <y> <z>`: where the job started; the first one counts.
    fn job_start(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let mut w = rest.unwrap_or("").split_whitespace();
        let wcs = self.wcs(n, w.next())?;
        let g92 = self.point(n, &mut w)?;
        let position = self.point(n, &mut w)?;
        self.st.start.get_or_insert(JobStart { wcs, g92, position });
        Ok(())
    }

    /// `O <x> <y> <z>`: the job's work origin; the first one counts.
    fn work_origin(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let mut w = rest.unwrap_or("").split_whitespace();
        let o = self.point(n, &mut w)?;
        self.st.origin.get_or_insert(o);
        Ok(())
    }

    /// `T <index> <line> <text>`: the text of the next job line.
    fn line_text(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let mut w = rest.unwrap_or("").splitn(3, ' ');
        let i = self.index(n, w.next())?;
        let line: usize = w
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| self.bad(n, "missing file line"))?;
        if i != self.st.texts.len() {
            return Err(self.bad(n, "line texts out of order"));
        }
        self.st
            .texts
            .push((line, w.next().unwrap_or("").to_string()));
        Ok(())
    }

    /// `S <x> <y> <z> <wcs> <gx> <gy> <gz> <tlo> <modal…>`: what the controller said when the run
    /// stopped.
    fn stop(&mut self, n: usize, rest: Option<&str>) -> Result<(), JournalError> {
        let mut w = rest.unwrap_or("").split_whitespace();
        let machine = self.point(n, &mut w)?;
        let wcs = self.wcs(n, w.next())?;
        let g92 = self.point(n, &mut w)?;
        let tlo = self.coord(n, w.next())?;
        self.written = None;
        self.st.stop = Some(StopRecord {
            machine,
            wcs,
            g92,
            tlo,
            modal: w.collect::<Vec<_>>().join(" "),
        });
        Ok(())
    }

    /// `D`: a run completed the job.
    fn finished(&mut self) {
        self.st.finished = true;
        self.written = None;
    }

    /// The state after the last record: acks no run confirmed become unconfirmed, and a partial
    /// line known done since is no longer partial.
    fn finish(mut self) -> JournalState {
        let mut carried = self.carried;
        carried.append(&mut self.pending);
        carried.retain(|&i| !self.st.done[i]);
        carried.sort_unstable();
        carried.dedup();
        self.st.unconfirmed = carried;
        self.st.sent = self.carried_written.max(self.written);
        if self.st.partial.is_some_and(|(k, _)| self.st.done[k]) {
            self.st.partial = None;
        }
        self.st
    }
}
