//! The 15-block look-ahead planner and the motion executor, on virtual time.
//!
//! Planning follows GRBL's `planner.c`: targets are rounded to whole steps, junction speeds come from the
//! junction-deviation model (`$11`), per-axis acceleration and rate limits (`$110..$122`) are projected on the
//! move direction, and a reverse then a forward pass bound every entry speed so that the machine can always stop at
//! the end of the buffer. Execution integrates a trapezoidal speed profile in small time steps instead of generating
//! step pulses: at each instant the speed is raised by the acceleration, capped by the nominal speed and by the
//! speed from which the block exit speed is still reachable.

use crate::settings::{N_AXIS, Settings};
use std::collections::VecDeque;

/// Planner depth of an Uno build (`BLOCK_BUFFER_SIZE` 16 minus one, `planner.h`).
pub const PLANNER_BLOCKS: usize = 15;
/// `MINIMUM_JUNCTION_SPEED` (mm/s): zero, a reversal comes to a full stop.
const MINIMUM_JUNCTION_SPEED: f64 = 0.0;
/// `MINIMUM_FEED_RATE` of GRBL, mm/min.
const MINIMUM_FEED_RATE: f64 = 1.0;
/// Cosine beyond which a junction counts as straight or as a reversal (`planner.c`: 0.999999).
const JUNCTION_COS_LIMIT: f64 = 0.999_999;
/// Length below which a block counts as finished, mm (well under one step of 0.004 mm).
const LENGTH_EPS_MM: f64 = 1e-9;
/// Relative speed tolerance deciding which profile phase applies (guards against round-off ping-pong).
const SPEED_REL_EPS: f64 = 1e-9;
/// Floor of the acceleration, mm/s²: `$120=0` is accepted by GRBL but would divide by zero here.
const MIN_ACCEL_MM_S2: f64 = 1e-3;

/// One planned straight move.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanBlock {
    /// Start, machine mm (step-rounded).
    pub start: [f64; N_AXIS],
    /// Target, machine mm (step-rounded).
    pub target: [f64; N_AXIS],
    /// Length, mm.
    pub len: f64,
    /// Unit direction.
    pub unit: [f64; N_AXIS],
    /// Acceleration along the move, mm/s².
    pub accel: f64,
    /// Rapid rate along the move, mm/s.
    pub rapid_rate: f64,
    /// Programmed rate, mm/s (ignored for rapids).
    pub feed_rate: f64,
    /// Rapid move (rapid override applies).
    pub rapid: bool,
    /// Not subject to the feed override (jog).
    pub no_feed_override: bool,
    /// Junction limit, (mm/s)².
    pub max_junction_sq: f64,
    /// Planned entry speed, (mm/s)².
    pub entry_sq: f64,
    /// Trace record this block belongs to.
    pub record: usize,
    /// Execution started.
    pub started: bool,
}

impl PlanBlock {
    /// Nominal speed with the overrides (percent), mm/s.
    pub fn nominal(&self, feed_ovr: f64, rapid_ovr: f64) -> f64 {
        let v = if self.rapid {
            self.rapid_rate * rapid_ovr / 100.0
        } else if self.no_feed_override {
            self.feed_rate
        } else {
            self.feed_rate * feed_ovr / 100.0
        };
        v.max(MINIMUM_FEED_RATE / 60.0).min(self.rapid_rate)
    }
}

/// What happened during one executor step.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct StepEvents {
    /// Records whose block began, with the time into the step, s.
    pub started: Vec<(usize, f64)>,
    /// Records one of whose blocks ended, with the time into the step, s.
    pub finished: Vec<(usize, f64)>,
}

/// Planner buffer plus executor state.
#[derive(Debug, Clone)]
pub struct Planner {
    /// Queued blocks; the front one is executing.
    pub blocks: VecDeque<PlanBlock>,
    /// Planner position in steps.
    pub position_steps: [i64; N_AXIS],
    prev_unit: [f64; N_AXIS],
    /// Distance done along the front block, mm.
    pub s: f64,
    /// Current speed, mm/s.
    pub v: f64,
    /// Executed (continuous) machine position, mm.
    pub pos: [f64; N_AXIS],
}

/// Largest value of `limits[i] / |unit[i]|` over the axes the direction uses (`limit_value_by_axis_maximum`).
fn limit_by_axis(limits: &[f64; N_AXIS], unit: &[f64; N_AXIS]) -> f64 {
    let mut v = f64::INFINITY;
    for i in 0..N_AXIS {
        if unit[i] != 0.0 {
            v = v.min(limits[i] / unit[i].abs());
        }
    }
    v
}

impl Planner {
    /// An empty planner at machine position `pos`.
    pub fn new(pos: [f64; N_AXIS], settings: &Settings) -> Self {
        let mut p = Planner {
            blocks: VecDeque::new(),
            position_steps: [0; N_AXIS],
            prev_unit: [0.0; N_AXIS],
            s: 0.0,
            v: 0.0,
            pos,
        };
        p.sync_position(settings);
        p
    }

    /// Sets the planner position from the executed position (after a reset or a flush).
    pub fn sync_position(&mut self, settings: &Settings) {
        for i in 0..N_AXIS {
            self.position_steps[i] = (self.pos[i] * settings.steps_per_mm[i]).round() as i64;
        }
    }

    /// Planner position in mm.
    pub fn position_mm(&self, settings: &Settings) -> [f64; N_AXIS] {
        let mut p = [0.0; N_AXIS];
        for i in 0..N_AXIS {
            p[i] = self.position_steps[i] as f64 / settings.steps_per_mm[i];
        }
        p
    }

    /// True when no more blocks fit.
    pub fn is_full(&self) -> bool {
        self.blocks.len() >= PLANNER_BLOCKS
    }

    /// Removes all blocks and stops (reset, jog cancel after stop).
    pub fn clear(&mut self, settings: &Settings) {
        self.blocks.clear();
        self.s = 0.0;
        self.v = 0.0;
        self.sync_position(settings);
    }

    /// Queues a move to `target` (mm). Returns false for a zero-step move, which GRBL drops.
    pub fn push(
        &mut self,
        target: [f64; N_AXIS],
        rapid: bool,
        feed_mm_min: f64,
        inverse_time: bool,
        no_feed_override: bool,
        record: usize,
        settings: &Settings,
        feed_ovr: f64,
        rapid_ovr: f64,
    ) -> bool {
        let mut steps = [0i64; N_AXIS];
        let mut delta = [0.0; N_AXIS];
        let mut any = false;
        for i in 0..N_AXIS {
            steps[i] = (target[i] * settings.steps_per_mm[i]).round() as i64;
            let d = steps[i] - self.position_steps[i];
            any |= d != 0;
            delta[i] = d as f64 / settings.steps_per_mm[i];
        }
        if !any {
            return false;
        }
        let len = (delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]).sqrt();
        let mut unit = [0.0; N_AXIS];
        for i in 0..N_AXIS {
            unit[i] = delta[i] / len;
        }
        let accel = limit_by_axis(&settings.acceleration, &unit).max(MIN_ACCEL_MM_S2);
        let max_rate_s = settings.max_rate.map(|r| r / 60.0);
        let rapid_rate = limit_by_axis(&max_rate_s, &unit);
        let feed_rate = if inverse_time {
            len * feed_mm_min / 60.0
        } else {
            feed_mm_min / 60.0
        };
        // Junction speed from the deviation model.
        let max_junction_sq = if self.blocks.is_empty() {
            0.0
        } else {
            let cos = -(0..N_AXIS)
                .map(|i| self.prev_unit[i] * unit[i])
                .sum::<f64>();
            if cos > JUNCTION_COS_LIMIT {
                MINIMUM_JUNCTION_SPEED * MINIMUM_JUNCTION_SPEED
            } else if cos < -JUNCTION_COS_LIMIT {
                f64::INFINITY
            } else {
                let mut ju = [0.0; N_AXIS];
                for i in 0..N_AXIS {
                    ju[i] = unit[i] - self.prev_unit[i];
                }
                let n = (ju[0] * ju[0] + ju[1] * ju[1] + ju[2] * ju[2]).sqrt();
                for v in &mut ju {
                    *v /= n;
                }
                let ja = limit_by_axis(&settings.acceleration, &ju).max(MIN_ACCEL_MM_S2);
                let sin_half = (0.5 * (1.0 - cos)).sqrt();
                (ja * settings.junction_deviation * sin_half / (1.0 - sin_half))
                    .max(MINIMUM_JUNCTION_SPEED * MINIMUM_JUNCTION_SPEED)
            }
        };
        let start = self.position_mm(settings);
        let mut tgt = [0.0; N_AXIS];
        for i in 0..N_AXIS {
            tgt[i] = steps[i] as f64 / settings.steps_per_mm[i];
        }
        self.blocks.push_back(PlanBlock {
            start,
            target: tgt,
            len,
            unit,
            accel,
            rapid_rate,
            feed_rate,
            rapid,
            no_feed_override,
            max_junction_sq,
            entry_sq: 0.0,
            record,
            started: false,
        });
        self.position_steps = steps;
        self.prev_unit = unit;
        self.recalculate(feed_ovr, rapid_ovr);
        true
    }

    /// Reverse and forward passes over the buffer (`planner_recalculate`), with the front block fixed at its
    /// current speed.
    pub fn recalculate(&mut self, feed_ovr: f64, rapid_ovr: f64) {
        let n = self.blocks.len();
        if n < 2 {
            return;
        }
        let nominal: Vec<f64> = self
            .blocks
            .iter()
            .map(|b| b.nominal(feed_ovr, rapid_ovr))
            .collect();
        // Reverse pass: every block can stop by the end of the buffer.
        let mut next_entry_sq = 0.0;
        for i in (1..n).rev() {
            let max_entry = self.blocks[i]
                .max_junction_sq
                .min(nominal[i] * nominal[i])
                .min(nominal[i - 1] * nominal[i - 1]);
            let b = &mut self.blocks[i];
            b.entry_sq = max_entry.min(next_entry_sq + 2.0 * b.accel * b.len);
            next_entry_sq = b.entry_sq;
        }
        // Forward pass: entries reachable by acceleration from the executing block's speed.
        let front = &self.blocks[0];
        let mut reach_sq = self.v * self.v + 2.0 * front.accel * (front.len - self.s).max(0.0);
        for i in 1..n {
            let b = &mut self.blocks[i];
            b.entry_sq = b.entry_sq.min(reach_sq);
            reach_sq = b.entry_sq + 2.0 * b.accel * b.len;
        }
    }

    /// Advances the executor by `h` seconds. `hold` decelerates to a stop.
    ///
    /// The speed profile is integrated piecewise exactly: constant acceleration up to the nominal speed or to the
    /// deceleration curve `v² = v_exit² + 2·a·remaining`, cruise, then constant deceleration along that curve.
    pub fn step(&mut self, mut h: f64, hold: bool, feed_ovr: f64, rapid_ovr: f64) -> StepEvents {
        let mut ev = StepEvents::default();
        let h0 = h;
        let mut guard = 0;
        while h > 0.0 && guard < 64 {
            guard += 1;
            let Some(front) = self.blocks.front_mut() else {
                self.v = 0.0;
                break;
            };
            if !front.started {
                front.started = true;
                ev.started.push((front.record, h0 - h));
            }
            let (len, a, start, unit, target, record) = (
                front.len,
                front.accel,
                front.start,
                front.unit,
                front.target,
                front.record,
            );
            let vn = front.nominal(feed_ovr, rapid_ovr);
            let rem = (len - self.s).max(0.0);
            let ve = if hold {
                0.0
            } else {
                self.blocks.get(1).map_or(0.0, |b| b.entry_sq.sqrt())
            };
            let v = self.v;
            let v_dec = (ve * ve + 2.0 * a * rem).sqrt();
            // Time to reach the end of the block when braking at `a` from now (∞ if it stops before).
            let disc = v * v - 2.0 * a * rem;
            let t_hit = if rem <= LENGTH_EPS_MM {
                0.0
            } else if disc >= 0.0 {
                (v - disc.sqrt()) / a
            } else {
                f64::INFINITY
            };
            let braking = hold || v >= v_dec * (1.0 - SPEED_REL_EPS);
            let (dt, ds, v_new, finished) = if braking {
                if t_hit <= h {
                    (t_hit, rem, (v - a * t_hit).max(0.0), true)
                } else {
                    let t_stop = v / a;
                    if hold && t_stop <= h {
                        (t_stop, 0.5 * v * t_stop, 0.0, false)
                    } else {
                        (h, v * h - 0.5 * a * h * h, v - a * h, false)
                    }
                }
            } else if v > vn * (1.0 + SPEED_REL_EPS) {
                // Above nominal (override lowered): slow down to nominal.
                let t1 = ((v - vn) / a).min(h);
                (t1, v * t1 - 0.5 * a * t1 * t1, v - a * t1, false)
            } else if v < vn * (1.0 - SPEED_REL_EPS) {
                // Accelerate up to nominal or to where the deceleration curve is met.
                let s_meet = ((ve * ve + 2.0 * a * rem - v * v) / (4.0 * a)).max(0.0);
                let v_top = vn.min((v * v + 2.0 * a * s_meet).sqrt());
                let t1 = ((v_top - v) / a).max(0.0);
                if t1 <= h {
                    (t1, (v_top * v_top - v * v) / (2.0 * a), v_top, false)
                } else {
                    (h, v * h + 0.5 * a * h * h, v + a * h, false)
                }
            } else {
                // Cruise until the deceleration point.
                let s_cruise = (rem - (vn * vn - ve * ve).max(0.0) / (2.0 * a)).max(0.0);
                let t_c = if vn > 0.0 {
                    s_cruise / vn
                } else {
                    f64::INFINITY
                };
                if t_c <= h {
                    (t_c, s_cruise, vn, false)
                } else {
                    (h, vn * h, vn, false)
                }
            };
            h -= dt;
            if finished || self.s + ds >= len - LENGTH_EPS_MM {
                self.v = v_new.min(ve).max(0.0);
                self.s = 0.0;
                self.pos = target;
                self.blocks.pop_front();
                ev.finished.push((record, h0 - h));
                continue;
            }
            self.s += ds;
            self.v = v_new.max(0.0);
            for i in 0..N_AXIS {
                self.pos[i] = start[i] + unit[i] * self.s;
            }
            if hold && self.v <= 0.0 {
                break;
            }
        }
        ev
    }

    /// Runs every queued block to completion at once (instant motion).
    pub fn complete_all(&mut self) -> StepEvents {
        let mut ev = StepEvents::default();
        while let Some(b) = self.blocks.pop_front() {
            if !b.started {
                ev.started.push((b.record, 0.0));
            }
            ev.finished.push((b.record, 0.0));
            self.pos = b.target;
        }
        self.s = 0.0;
        self.v = 0.0;
        ev
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn junction_speed_of_a_right_angle() {
        let s = Settings::default();
        let mut p = Planner::new([0.0; 3], &s);
        assert!(p.push(
            [10.0, 0.0, 0.0],
            false,
            300.0,
            false,
            false,
            0,
            &s,
            100.0,
            100.0
        ));
        assert!(p.push(
            [10.0, 10.0, 0.0],
            false,
            300.0,
            false,
            false,
            1,
            &s,
            100.0,
            100.0
        ));
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let want = (10.0 / h) * 0.01 * h / (1.0 - h);
        assert!((p.blocks[1].max_junction_sq - want).abs() < 1e-12);
        assert!((p.blocks[1].entry_sq - want).abs() < 1e-12);
        // Zero-step moves are dropped.
        assert!(!p.push(
            [10.001, 10.0, 0.0],
            false,
            300.0,
            false,
            false,
            2,
            &s,
            100.0,
            100.0
        ));
    }

    #[test]
    fn hold_stops_within_the_braking_distance() {
        let s = Settings::default();
        let mut p = Planner::new([0.0; 3], &s);
        p.push(
            [100.0, 0.0, 0.0],
            false,
            300.0,
            false,
            false,
            0,
            &s,
            100.0,
            100.0,
        );
        p.step(5.0, false, 100.0, 100.0);
        let x0 = p.pos[0];
        assert!((p.v - 5.0).abs() < 1e-12);
        p.step(10.0, true, 100.0, 100.0);
        assert_eq!(p.v, 0.0);
        // v²/2a = 1.25 mm.
        assert!((p.pos[0] - x0 - 1.25).abs() < 1e-9, "{}", p.pos[0] - x0);
    }
}
