//! How far along the job's path the machine stands: the reported position placed on the lines
//! between the first line not known executed and the last line handed to the port, so progress
//! moves from the first line on instead of waiting until the planner's look-ahead confirms lines
//! (a short job sits entirely in GRBL's buffers until it ends).

use super::geometry::{dist, nearest_on_segment};
use super::tracker::Tracker;
use super::watch::{line_chords, stretch};
use crate::job::Job;

/// Path length and estimated time of the lines not yet known executed that the machine has
/// already passed, up to where it stands.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Ahead {
    /// mm.
    pub length: f64,
    /// s, by the per-line estimate (a line's time in proportion to how far into it).
    pub time: f64,
}

/// Where the machine reported at work position `wpos` stands on the stretch of the path it can
/// be on ([`stretch`]): the first place within `tol` mm, so a path passing the same point twice
/// counts the earlier pass. `None` when it is on none of it, or the stretch cannot be placed.
pub(super) fn ahead_of_confirmed(
    job: &Job,
    tracker: &mut Tracker,
    wpos: [f64; 3],
    tol: f64,
    preamble_first: bool,
) -> Option<Ahead> {
    let (lo, hi, g) = stretch(job, tracker, preamble_first)?;
    // The job's geometry is G92-free; the report is in the G92 frame.
    let p = [wpos[0] + g[0], wpos[1] + g[1], wpos[2] + g[2]];
    let mut passed = Ahead::default();
    for i in lo..=hi {
        let l = &job.lines[i];
        let mut run = 0.0;
        for w in line_chords(job, i).windows(2) {
            let q = nearest_on_segment(p, w[0], w[1]);
            if dist(p, q) <= tol {
                let into = (run + dist(w[0], q)).min(l.length);
                return Some(Ahead {
                    length: passed.length + into,
                    time: passed.time + l.time * into / l.length,
                });
            }
            run += dist(w[0], w[1]);
        }
        if l.moves && l.length > 0.0 {
            passed.length += l.length;
            passed.time += l.time;
        }
    }
    None
}
