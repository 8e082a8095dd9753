//! The per-line time estimate: the job's moves, dwells and planner syncs handed to GRBL's motion
//! model ([`flatcut_motion`]).

use super::arc::arc_points;
use super::modal::{MotionMode, Units};
use super::parse::words;
use super::{Job, LineKind, MM_PER_INCH, MachineLimits};
use flatcut_motion::{Estimator, Feed};

impl Job {
    /// Recomputes the per-line time estimate for the given machine limits: a look-ahead planner
    /// model like GRBL's (junction deviation, trapezoidal profiles, arcs split into chords by the
    /// arc tolerance, syncs on dwells/spindle changes/program pauses), plus `G4` dwell times.
    pub fn retime(&mut self, limits: &MachineLimits) {
        let mut est = Estimator::new(&limits.motion);
        for (i, line) in self.lines.iter().enumerate() {
            let before = &line.before;
            let after = self
                .lines
                .get(i + 1)
                .map(|l| &l.before)
                .unwrap_or(&self.end_state);
            let ws = words(&line.text).unwrap_or_default();
            let has_g = |n: i64| {
                ws.iter()
                    .any(|w| w.0 == 'G' && (w.1 * 10.0).round() as i64 == n)
            };
            let has_m = |n: i64| ws.iter().any(|w| w.0 == 'M' && w.1.round() as i64 == n);
            if line.kind != LineKind::Gcode || has_m(0) || has_m(1) || has_m(2) || has_m(30) {
                est.sync();
            }
            if has_g(40) {
                let p = ws.iter().find(|w| w.0 == 'P').map_or(0.0, |p| p.1.max(0.0));
                est.dwell(i, p);
            }
            let spindle_change = before.spindle != after.spindle
                || (before.speed != after.speed && !limits.laser_mode);
            if spindle_change && !limits.laser_mode {
                est.sync();
            }
            if !line.moves {
                continue;
            }
            let arc = match after.motion {
                MotionMode::ArcCw | MotionMode::ArcCcw => {
                    let mut st = before.clone();
                    st.plane = after.plane;
                    st.motion = after.motion;
                    let scale = if after.units == Units::Inch {
                        MM_PER_INCH
                    } else {
                        1.0
                    };
                    let mut ijk = [None; 3];
                    let mut r = None;
                    for w in &ws {
                        match w.0 {
                            'I' => ijk[0] = Some(w.1 * scale),
                            'J' => ijk[1] = Some(w.1 * scale),
                            'K' => ijk[2] = Some(w.1 * scale),
                            'R' => r = Some(w.1 * scale),
                            _ => {}
                        }
                    }
                    Some(arc_points(
                        &st,
                        before.position,
                        after.position,
                        ijk,
                        r,
                        limits.motion.arc_tolerance,
                    ))
                }
                _ => None,
            };
            let split = arc.as_ref().map_or(0, |a| a.segments);
            let feed = if after.motion == MotionMode::Rapid {
                Feed::Rapid
            } else if after.inverse_time && split > 0 {
                // `mc_arc` multiplies an inverse-time feed by its segment count and runs the
                // chords as mm/min (GRBL 1.1h's own arithmetic, whatever the arc's length).
                Feed::PerMinute(after.feed * split as f64)
            } else if after.inverse_time {
                Feed::InverseTime {
                    f: after.feed,
                    line_length: line.length,
                }
            } else {
                Feed::PerMinute(after.feed)
            };
            let pts = arc.map_or_else(|| vec![before.position, after.position], |a| a.points);
            est.polyline(i, &pts, feed);
        }
        let times = est.per_tag(self.lines.len());
        for (l, t) in self.lines.iter_mut().zip(times) {
            l.time = t;
        }
        self.total_time = self.lines.iter().map(|l| l.time).sum();
    }
}
