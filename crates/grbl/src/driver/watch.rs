//! Watching the reported position during a run: GRBL's link has no checksum, so a line damaged
//! on the way that still parses (a dropped digit turns `X156.169` into `X156.69`) is cut where
//! nobody meant. Every status report places the machine somewhere on the job's path between the
//! first line not known executed and the last line handed to the port (the planner's lookahead
//! and the RX buffer hold everything in between; an arc runs before its `ok`); a machine found
//! farther than the tolerance from every segment of that stretch is off the job's path.

use super::geometry::{dist, nearest_on_segment};
use super::tracker::Tracker;
use crate::job::Job;
use crate::response::MachineState;

/// The machine found off the job's path.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Deviation {
    /// First line of the stretch the machine may have been on (0-based job index).
    pub from: usize,
    /// Last line of that stretch.
    pub to: usize,
    /// The nearest point of that stretch, work coordinates (mm, as `WPos` reports).
    pub expected: [f64; 3],
    /// The reported work position, mm.
    pub reported: [f64; 3],
}

/// Whether a report in `state` places the machine on its programmed path: running, held (a
/// feed hold decelerates along the path) or idle. Homing, jogging, alarm and a safety door
/// (which may park) move elsewhere or say nothing.
pub(super) fn state_on_path(state: MachineState) -> bool {
    matches!(
        state,
        MachineState::Idle | MachineState::Run | MachineState::Hold { .. }
    )
}

/// The stretch of `job` the machine can be on now (see the module docs): lines `lo..=hi`, and the
/// G92 offset that turns a reported work position into the job's G92-free frame; `None` when a
/// report cannot be placed on it: nothing sent yet, every line done, a resume preamble still
/// travelling to the first line of a run (`preamble_first`: the run at line 0 has one), lines
/// done earlier inside it, or a change of work frame (G92, G54..G59) inside it (GRBL reports in
/// the parser's frame, which runs ahead of the motion).
pub(super) fn stretch(
    job: &Job,
    tracker: &mut Tracker,
    preamble_first: bool,
) -> Option<(usize, usize, [f64; 3])> {
    let lo = tracker.first_open();
    let hi = tracker.last_sent?;
    if lo >= job.len() {
        return None;
    }
    // A run of lines after lines done earlier (or a resume of line 0) starts with a preamble
    // that travels from wherever the machine stood.
    let after_preamble = if lo == 0 {
        preamble_first
    } else {
        tracker.prior_done[lo - 1]
    };
    let hi = hi.max(lo).min(job.len() - 1);
    if after_preamble || (lo..=hi).any(|i| tracker.prior_done[i]) {
        return None;
    }
    let (first, after) = (&job.lines[lo].before, job.state_before(hi + 1));
    if first.g92 != after.g92 || first.wcs != after.wcs {
        return None;
    }
    Some((lo, hi, first.g92))
}

/// The straight pieces line `i` moves along (an arc's chords, where GRBL moves); empty for a
/// line that does not move.
pub(super) fn line_chords(job: &Job, i: usize) -> Vec<[f64; 3]> {
    let l = &job.lines[i];
    if !l.moves || l.length <= 0.0 {
        Vec::new()
    } else if l.arc.len() >= 2 {
        l.arc.clone()
    } else {
        vec![job.start_of(i), job.end_of(i)]
    }
}

/// Checks the reported work position `wpos` against the [`stretch`] of `job` the machine can be
/// on now; `None` when it lies within `tol` mm of it, or when this report cannot be checked.
pub(super) fn off_path(
    job: &Job,
    tracker: &mut Tracker,
    wpos: [f64; 3],
    tol: f64,
    preamble_first: bool,
) -> Option<Deviation> {
    let (lo, hi, g) = stretch(job, tracker, preamble_first)?;
    // The job's geometry is G92-free; the report is in the G92 frame.
    let p = [wpos[0] + g[0], wpos[1] + g[1], wpos[2] + g[2]];
    let mut best = (dist(p, job.start_of(lo)), job.start_of(lo));
    for i in lo..=hi {
        for w in line_chords(job, i).windows(2) {
            let q = nearest_on_segment(p, w[0], w[1]);
            let d = dist(p, q);
            if d < best.0 {
                best = (d, q);
            }
        }
    }
    (best.0 > tol).then(|| Deviation {
        from: lo,
        to: hi,
        expected: [best.1[0] - g[0], best.1[1] - g[1], best.1[2] - g[2]],
        reported: wpos,
    })
}
