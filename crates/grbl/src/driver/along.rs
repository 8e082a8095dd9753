//! How far along the job's path the machine stands: the reported position placed on the lines
//! between the first line not known executed and the last line handed to the port, so progress
//! moves from the first line on instead of waiting until the planner's look-ahead confirms lines
//! (a short job sits entirely in GRBL's buffers until it ends).

use super::geometry::{dist, nearest_on_segment};
use super::tracker::Tracker;
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
/// be on (see the module docs): the first place within `tol` mm, so a path passing the same
/// point twice counts the earlier pass. `None` when it is on none of it (a resume's preamble
/// still travelling, a change of work frame inside the stretch, nothing sent yet).
pub(super) fn ahead_of_confirmed(
    job: &Job,
    tracker: &mut Tracker,
    wpos: [f64; 3],
    tol: f64,
) -> Option<Ahead> {
    let lo = tracker.first_open();
    let hi = tracker.last_sent?;
    if lo >= job.len() {
        return None;
    }
    let hi = hi.max(lo).min(job.len() - 1);
    let (first, after) = (&job.lines[lo].before, job.state_before(hi + 1));
    if first.g92 != after.g92 || first.wcs != after.wcs {
        return None;
    }
    // The job's geometry is G92-free; the report is in the G92 frame.
    let g = first.g92;
    let p = [wpos[0] + g[0], wpos[1] + g[1], wpos[2] + g[2]];
    let mut passed = Ahead::default();
    for i in lo..=hi {
        let l = &job.lines[i];
        if tracker.done[i] || !l.moves || l.length <= 0.0 {
            continue;
        }
        let chords: Vec<[f64; 3]> = if l.arc.len() >= 2 {
            l.arc.clone()
        } else {
            vec![job.start_of(i), job.end_of(i)]
        };
        let mut run = 0.0;
        for w in chords.windows(2) {
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
        passed.length += l.length;
        passed.time += l.time;
    }
    None
}
