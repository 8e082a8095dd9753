//! Where on a job's path a position lies: the lines whose path passes within a tolerance of it,
//! grouped into the places in the job it may be (the path may pass the same point twice), and
//! the tolerance a reported position deserves.

use super::geometry::{dist, seg_dist};
use crate::job::Job;
use std::collections::BTreeMap;

/// Where on line `i`'s path the work position `p` lies: `Some(true)` at its end, `Some(false)`
/// strictly inside it (not at its start), `None` off it. Arcs are tested against their chords,
/// which is where GRBL moves.
fn locate_on_line(job: &Job, i: usize, p: [f64; 3], tol: f64) -> Option<bool> {
    let l = &job.lines[i];
    if !l.moves || l.length <= 0.0 {
        return None;
    }
    let (a, b) = (job.start_of(i), job.end_of(i));
    if dist(p, b) <= tol {
        return Some(true);
    }
    if dist(p, a) <= tol {
        return None;
    }
    let on = if l.arc.len() >= 2 {
        l.arc.windows(2).any(|w| seg_dist(p, w[0], w[1]) <= tol)
    } else {
        seg_dist(p, a, b) <= tol
    };
    on.then_some(false)
}

/// The places in the job, among lines `range` (skipping those `skip` says), where the machine
/// standing at work position `p` may be: `(cut, partial)` = every line before `cut` has run, and
/// `partial` = line `cut` was stopped part-way at `p`. Candidates that touch (consecutive lines
/// meeting at a vertex `p` lies within tolerance of, or endpoints separated only by lines that
/// do not move) are one place in the job: for a stop inside a line the later line wins (finishing
/// it from `p` leaves out at most the tolerance of the earlier one, and repeats nothing); for an
/// endpoint the earlier one (the non-moving lines are sent again, which only re-applies modal
/// state). More than one group means the path passes `p` more than once.
pub(super) fn places_on_path(
    job: &Job,
    p: [f64; 3],
    range: std::ops::RangeInclusive<usize>,
    tol: f64,
    skip: impl Fn(usize) -> bool,
) -> Vec<(usize, Option<[f64; 3]>)> {
    let first = *range.start();
    let mut cuts: Vec<(usize, Option<[f64; 3]>)> = Vec::new();
    let mut matched: Vec<usize> = Vec::new();
    if dist(p, job.start_of(first)) <= tol {
        cuts.push((first, None));
    }
    for i in range {
        if skip(i) {
            continue;
        }
        match locate_on_line(job, i, p, tol) {
            Some(true) => cuts.push((i + 1, None)),
            Some(false) => cuts.push((i, Some(p))),
            None => continue,
        }
        matched.push(i);
    }
    let mut groups: Vec<Vec<(usize, Option<[f64; 3]>)>> = Vec::new();
    for c in cuts {
        let touches = groups.last().and_then(|g| g.last()).is_some_and(|last| {
            (last.0..c.0).all(|l| {
                let line = &job.lines[l];
                !line.moves || line.length <= 0.0 || matched.contains(&l)
            })
        });
        match groups.last_mut() {
            Some(g) if touches => g.push(c),
            _ => groups.push(vec![c]),
        }
    }
    groups
        .into_iter()
        .filter_map(|g| {
            if g.iter().any(|c| c.1.is_some()) {
                g.last().copied()
            } else {
                g.first().copied()
            }
        })
        .collect()
}

/// Half a step on the coarsest axis plus the 3-decimal rounding of status reports: how far a
/// reported position may sit from a programmed point that was reached.
pub(super) fn position_tolerance(settings: &BTreeMap<u16, f64>) -> f64 {
    let min_steps = (100..=102)
        .filter_map(|n| settings.get(&n).copied())
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold(f64::INFINITY, f64::min);
    let half_step = if min_steps.is_finite() {
        0.5 / min_steps
    } else {
        0.5 / 250.0
    };
    half_step + 0.0011
}
