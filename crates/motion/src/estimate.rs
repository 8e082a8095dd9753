//! The planner model: a job is a sequence of straight blocks (arcs already split into chords),
//! each with a nominal speed and an acceleration limited per axis, and points where the planner
//! is emptied (dwells, spindle changes, program pauses). Junction speeds follow GRBL's
//! junction-deviation rule; a backward pass (able to stop at the end of every planned sequence)
//! and a forward pass (reachable from the previous exit) give each block's entry speed, and the
//! block's time is that of its trapezoidal (or triangular) profile. Every stop after motion (the
//! planner emptied, and the job's end) adds the step idle delay `$1`, and a dwell lasts whole
//! 50 ms steps, as GRBL's `delay_sec` counts it.

use crate::limits::{Limits, axis_limited};
use crate::profile::trapezoid_time;

/// Direction cosine above which two consecutive moves count as straight on (or reversed): GRBL's
/// `planner.c` uses the same 0.999999 before applying the junction-deviation formula.
const STRAIGHT_JUNCTION_COS: f64 = 0.999999;
/// GRBL's `DWELL_TIME_STEP` (`config.h`), s: `delay_sec` waits in whole steps of it.
const DWELL_TIME_STEP: f64 = 0.05;

/// How fast a move is asked to run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Feed {
    /// `G0`: as fast as the axes allow (`$110-$112` along the move).
    Rapid,
    /// `G94` feed, mm/min (0 = unset: GRBL would refuse the move; timed as a rapid).
    PerMinute(f64),
    /// `G93` inverse time: the whole line (of `line_length` mm) takes `1/f` minutes.
    InverseTime {
        /// The F word.
        f: f64,
        /// Length of the whole programmed line (all its chords), mm.
        line_length: f64,
    },
}

/// One straight piece of motion.
#[derive(Debug, Clone, Copy)]
struct Block {
    tag: usize,
    len: f64,
    unit: [f64; 3],
    /// Nominal speed, mm/s.
    v_nom: f64,
    /// Acceleration along the move, mm/s².
    accel: f64,
    /// The planner is emptied before this block.
    sync_before: bool,
}

/// Collects a job's moves and dwells, then times them with GRBL's planner model. Every move and
/// dwell carries a caller's `tag` (a line index, say) so times can be reported per line.
#[derive(Debug, Clone)]
pub struct Estimator {
    limits: Limits,
    blocks: Vec<Block>,
    /// Dwells and the step idle delays of stops, per tag.
    dwells: Vec<(usize, f64)>,
    sync_next: bool,
    /// A block was planned since the planner last emptied (the steppers are running).
    moving: bool,
}

impl Estimator {
    /// An empty job on a machine with `limits`.
    pub fn new(limits: &Limits) -> Estimator {
        Estimator {
            limits: *limits,
            blocks: Vec::new(),
            dwells: Vec::new(),
            sync_next: true,
            moving: false,
        }
    }

    /// The limits in use.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// The planner is emptied here (the next move starts from rest). When the machine was
    /// moving, its stop costs the step idle delay (`st_go_idle`), counted to the last move.
    pub fn sync(&mut self) {
        self.sync_next = true;
        if let Some(stop) = self.stop_delay() {
            self.dwells.push(stop);
        }
        self.moving = false;
    }

    /// The step idle delay of the stop after the moves planned so far: (last move's tag, s).
    fn stop_delay(&self) -> Option<(usize, f64)> {
        let delay = self.limits.step_idle_delay;
        let last = self.blocks.last().filter(|_| self.moving)?;
        (delay > 0.0 && delay.is_finite()).then_some((last.tag, delay))
    }

    /// A dwell of `seconds` (`G4`): the planner empties, then the machine waits, in whole
    /// `DWELL_TIME_STEP`s: GRBL 1.1h's `delay_sec` loops `ceil(20 × P)` times over 50 ms, in
    /// single precision (`G4 P0.01` waits 50 ms).
    pub fn dwell(&mut self, tag: usize, seconds: f64) {
        self.sync();
        if seconds > 0.0 && seconds.is_finite() {
            let steps = (20.0f32 * seconds as f32).ceil();
            self.dwells.push((tag, f64::from(steps) * DWELL_TIME_STEP));
        }
    }

    /// A straight move from `from` to `to` (mm). As `plan_buffer_line` does, both ends are
    /// rounded to whole steps and the move is planned between them: a move of no step is
    /// dropped, and a sub-step wiggle becomes a step or nothing, never a sharp corner.
    pub fn segment(&mut self, tag: usize, from: [f64; 3], to: [f64; 3], feed: Feed) {
        let spm = self.limits.steps_per_mm;
        let step = |v: f64, a: usize| {
            if spm[a] > 0.0 {
                (v * spm[a]).round() / spm[a]
            } else {
                v
            }
        };
        let d: [f64; 3] = std::array::from_fn(|a| step(to[a], a) - step(from[a], a));
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if len == 0.0 || !len.is_finite() {
            return;
        }
        let unit = [d[0] / len, d[1] / len, d[2] / len];
        let rate_cap = axis_limited(f64::INFINITY, unit, self.limits.max_rate) / 60.0;
        let v_nom = match feed {
            Feed::Rapid => rate_cap,
            Feed::InverseTime { f, line_length } if f > 0.0 => {
                (line_length * f / 60.0).min(rate_cap)
            }
            Feed::PerMinute(f) if f > 0.0 => (f / 60.0).min(rate_cap),
            _ => rate_cap,
        };
        self.blocks.push(Block {
            tag,
            len,
            unit,
            v_nom,
            accel: axis_limited(f64::INFINITY, unit, self.limits.accel),
            sync_before: self.sync_next,
        });
        self.sync_next = false;
        self.moving = true;
    }

    /// Consecutive straight moves through `points` (an arc's chords, say).
    pub fn polyline(&mut self, tag: usize, points: &[[f64; 3]], feed: Feed) {
        for w in points.windows(2) {
            self.segment(tag, w[0], w[1], feed);
        }
    }

    /// Seconds per tag for tags `0..n` (moves and dwells with other tags are left out).
    pub fn per_tag(&self, n: usize) -> Vec<f64> {
        let mut out = vec![0.0; n];
        for (b, t) in self.blocks.iter().zip(self.block_times()) {
            if let Some(slot) = out.get_mut(b.tag) {
                *slot += t;
            }
        }
        for &(tag, s) in self.dwells.iter().chain(&self.stop_delay()) {
            if let Some(slot) = out.get_mut(tag) {
                *slot += s;
            }
        }
        out
    }

    /// Seconds for the whole job (its last stop included).
    pub fn total(&self) -> f64 {
        let end = self.stop_delay();
        let waits: f64 = self.dwells.iter().chain(&end).map(|d| d.1).sum();
        self.block_times().iter().sum::<f64>() + waits
    }

    /// Per-block times of GRBL's planner (`planner.c`). The junction acceleration is the
    /// axis-limited acceleration along the junction vector (the difference of the two unit
    /// vectors), as `plan_buffer_line` computes it, not the smaller of the two blocks'
    /// accelerations: on a 90° zig-zag of diagonal moves the latter is √2 too high and made the
    /// estimate about 3 % short.
    fn block_times(&self) -> Vec<f64> {
        let blocks = &self.blocks;
        let n = blocks.len();
        let mut entry: Vec<f64> = (0..n).map(|i| self.max_entry(i)).collect();
        // Backward: entry[i] limited by decelerating to entry[i+1] over block i.
        let mut next_entry = 0.0;
        for i in (0..n).rev() {
            let b = &blocks[i];
            entry[i] = entry[i].min((next_entry * next_entry + 2.0 * b.accel * b.len).sqrt());
            next_entry = entry[i];
        }
        // Forward: entry[i+1] limited by accelerating from entry[i] over block i.
        for i in 0..n.saturating_sub(1) {
            let b = &blocks[i];
            let reach = (entry[i] * entry[i] + 2.0 * b.accel * b.len).sqrt();
            entry[i + 1] = entry[i + 1].min(reach);
        }
        (0..n)
            .map(|i| {
                let b = &blocks[i];
                let vf = if i + 1 < n { entry[i + 1] } else { 0.0 };
                trapezoid_time(b.len, entry[i], vf, b.v_nom, b.accel)
            })
            .collect()
    }

    /// The highest speed block `i` may enter at: zero after a sync, else the junction-deviation
    /// speed of the corner with the block before, capped by both nominal speeds.
    fn max_entry(&self, i: usize) -> f64 {
        let c = &self.blocks[i];
        if i == 0 || c.sync_before {
            return 0.0;
        }
        let p = &self.blocks[i - 1];
        let cos = -(p.unit[0] * c.unit[0] + p.unit[1] * c.unit[1] + p.unit[2] * c.unit[2]);
        let v_lim = p.v_nom.min(c.v_nom);
        let v = if cos > STRAIGHT_JUNCTION_COS {
            0.0
        } else if cos < -STRAIGHT_JUNCTION_COS {
            v_lim
        } else {
            let sin_half = (0.5 * (1.0 - cos)).sqrt();
            let jv = [
                c.unit[0] - p.unit[0],
                c.unit[1] - p.unit[1],
                c.unit[2] - p.unit[2],
            ];
            let jl = (jv[0] * jv[0] + jv[1] * jv[1] + jv[2] * jv[2]).sqrt();
            let a = if jl > 0.0 {
                axis_limited(
                    f64::INFINITY,
                    [jv[0] / jl, jv[1] / jl, jv[2] / jl],
                    self.limits.accel,
                )
            } else {
                p.accel.min(c.accel)
            };
            (a * self.limits.junction_deviation * sin_half / (1.0 - sin_half)).sqrt()
        };
        v.min(v_lim)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// 10 mm/s² on every axis, feeds never capped, no step idle delay.
    fn fast() -> Limits {
        Limits {
            max_rate: [6000.0; 3],
            step_idle_delay: 0.0,
            ..Limits::GRBL_DEFAULT
        }
    }

    fn time(moves: &[([f64; 3], [f64; 3])], feed: Feed) -> f64 {
        let mut e = Estimator::new(&fast());
        for (k, (a, b)) in moves.iter().enumerate() {
            e.segment(k, *a, *b, feed);
        }
        e.total()
    }

    #[test]
    fn straight_split_reversal_and_corner() {
        let f = Feed::PerMinute(600.0);
        let one = time(&[([0.0; 3], [100.0, 0.0, 0.0])], f);
        assert_relative_eq!(one, 11.0, epsilon = 1e-9);
        // Collinear split: no stop at the junction.
        let two = time(
            &[
                ([0.0; 3], [50.0, 0.0, 0.0]),
                ([50.0, 0.0, 0.0], [100.0, 0.0, 0.0]),
            ],
            f,
        );
        assert_relative_eq!(two, 11.0, epsilon = 1e-9);
        // A reversal stops: two independent 50 mm moves.
        let rev = time(
            &[([0.0; 3], [50.0, 0.0, 0.0]), ([50.0, 0.0, 0.0], [0.0; 3])],
            f,
        );
        assert_relative_eq!(
            rev,
            2.0 * trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0),
            epsilon = 1e-9
        );
        // A 90° corner: the junction acceleration is along (−1, 1)/√2, which 10 mm/s² per axis
        // allow at 10·√2 (`plan_buffer_line`: limit_value_by_axis_maximum on the junction vector).
        let corner = time(
            &[
                ([0.0; 3], [50.0, 0.0, 0.0]),
                ([50.0, 0.0, 0.0], [50.0, 50.0, 0.0]),
            ],
            f,
        );
        let sin_half = 0.5f64.sqrt();
        let vj = (10.0 * 2f64.sqrt() * 0.01 * sin_half / (1.0 - sin_half)).sqrt();
        assert_relative_eq!(
            corner,
            2.0 * trapezoid_time(50.0, 0.0, vj, 10.0, 10.0),
            epsilon = 1e-9
        );
    }

    #[test]
    fn rates_dwells_syncs_and_tags() {
        // Rapids run at $110 (500 mm/min by default): 60 mm.
        let slow = Limits {
            step_idle_delay: 0.0,
            ..Limits::GRBL_DEFAULT
        };
        let mut e = Estimator::new(&slow);
        e.segment(0, [0.0; 3], [60.0, 0.0, 0.0], Feed::Rapid);
        let g0 = trapezoid_time(60.0, 0.0, 0.0, 500.0 / 60.0, 10.0);
        assert_relative_eq!(e.total(), g0, epsilon = 1e-9);
        // A feed above the axis rate is capped by it.
        let mut capped = Estimator::new(&slow);
        capped.segment(0, [0.0; 3], [60.0, 0.0, 0.0], Feed::PerMinute(3000.0));
        assert_relative_eq!(capped.total(), g0, epsilon = 1e-9);
        // A dwell adds its time and stops the planner between two collinear moves.
        let mut d = Estimator::new(&fast());
        d.segment(0, [0.0; 3], [50.0, 0.0, 0.0], Feed::PerMinute(600.0));
        d.dwell(1, 1.5);
        d.segment(
            2,
            [50.0, 0.0, 0.0],
            [100.0, 0.0, 0.0],
            Feed::PerMinute(600.0),
        );
        let leg = trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0);
        assert_relative_eq!(d.total(), 1.5 + 2.0 * leg, epsilon = 1e-9);
        let per = d.per_tag(3);
        assert_relative_eq!(per[1], 1.5);
        assert_relative_eq!(per[0], leg, epsilon = 1e-9);
        // Inverse time: 1/F minutes for the whole line, capped by the axis rate.
        let mut it = Estimator::new(&fast());
        let feed = Feed::InverseTime {
            f: 12.0,
            line_length: 50.0,
        };
        it.segment(0, [0.0; 3], [50.0, 0.0, 0.0], feed);
        assert_relative_eq!(
            it.total(),
            trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0),
            epsilon = 1e-9
        );
        // A dwell waits whole 50 ms steps: P0.01 is 50 ms, P0.15 is 150 ms.
        let mut short = Estimator::new(&fast());
        short.dwell(0, 0.01);
        short.dwell(1, 0.15);
        assert_relative_eq!(short.total(), 0.2, epsilon = 1e-12);
        // Zero-length moves vanish.
        let mut z = Estimator::new(&fast());
        z.segment(0, [1.0; 3], [1.0; 3], Feed::Rapid);
        assert_eq!(z.total(), 0.0);
    }

    /// `$1`: every stop after motion waits the step idle delay (`st_go_idle`), counted to the
    /// move before it; a dwell or spindle sync with no motion before it does not, nor does
    /// `$1=255`.
    #[test]
    fn step_idle_delay_at_every_stop_after_motion() {
        let l = Limits {
            step_idle_delay: Limits::step_idle_delay_of(25.0),
            ..fast()
        };
        let f = Feed::PerMinute(600.0);
        let leg = trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0);
        let mut e = Estimator::new(&l);
        e.sync(); // nothing moved yet: no delay
        e.segment(0, [0.0; 3], [50.0, 0.0, 0.0], f);
        e.dwell(1, 1.0); // stop: 25 ms, then the dwell
        e.sync(); // no motion since: nothing
        e.segment(2, [50.0, 0.0, 0.0], [100.0, 0.0, 0.0], f); // the job's end: 25 ms
        assert_relative_eq!(e.total(), 2.0 * leg + 1.0 + 0.05, epsilon = 1e-9);
        let per = e.per_tag(3);
        assert_relative_eq!(per[0], leg + 0.025, epsilon = 1e-9);
        assert_relative_eq!(per[1], 1.0, epsilon = 1e-12);
        assert_relative_eq!(per[2], leg + 0.025, epsilon = 1e-9);
        assert_eq!(Limits::step_idle_delay_of(255.0), 0.0);
        assert_eq!(Limits::step_idle_delay_of(0.0), 0.0);
    }
}
