//! Feeds the controller will not run: GRBL limits every move so that no axis exceeds its
//! maximum rate (`$110..$112`, `limit_value_by_axis_maximum` in `grbl/planner.c`) and says
//! nothing, so a job asking F3000 on a machine set to 500 mm/min runs six times slower than
//! planned. [`Job::feed_clamps`] finds those moves before streaming.

use super::{Job, MachineLimits, MotionMode};

/// Relative margin before a feed counts as over a rate (the numbers are printed to a few
/// decimals; a feed equal to the rate is not clamped).
const REL_TOL: f64 = 1e-9;
/// `$110`..`$112` name the X, Y and Z maximum rates.
const AXES: [(char, u16); 3] = [('X', 110), ('Y', 111), ('Z', 112)];

/// One axis whose maximum rate clamps some of the job's feed moves.
#[derive(Debug, Clone, PartialEq)]
pub struct FeedClamp {
    /// The axis: 0 = X, 1 = Y, 2 = Z.
    pub axis: usize,
    /// The controller's maximum rate for the axis, mm/min.
    pub max_rate: f64,
    /// The largest feed the job asks on a move the axis clamps, mm/min.
    pub feed: f64,
    /// The speed GRBL runs that move at, mm/min.
    pub runs_at: f64,
    /// 1-based source line of that move.
    pub line: usize,
    /// How many moves the axis clamps.
    pub moves: usize,
}

impl std::fmt::Display for FeedClamp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (name, setting) = AXES[self.axis];
        write!(
            f,
            "the job asks F{} (line {}) but the controller's {name} max rate (${setting}) is {} mm/min: \
             {} move(s) will run slower than the job says, that one at {} mm/min",
            fmt_rate(self.feed),
            self.line,
            fmt_rate(self.max_rate),
            self.moves,
            fmt_rate(self.runs_at),
        )
    }
}

/// A rate as G-code writes it: no trailing zeros.
fn fmt_rate(v: f64) -> String {
    let s = format!("{v:.1}");
    s.strip_suffix(".0").map(str::to_string).unwrap_or(s)
}

impl Job {
    /// The axes whose maximum rate in `limits` clamps feed moves of this job (per axis, the
    /// largest feed clamped), X before Y before Z; empty when the controller runs every feed
    /// as written. A move's speed on an axis is its feed times the axis component of its
    /// direction; arcs are checked chord by chord, as GRBL plans them. Rapids run at the
    /// maximum rates by definition, and inverse-time feeds are left out (their speed depends
    /// on each move's length, not on one F).
    pub fn feed_clamps(&self, limits: &MachineLimits) -> Vec<FeedClamp> {
        let rates = limits.motion.max_rate;
        let mut found: [Option<FeedClamp>; 3] = [None, None, None];
        for (i, line) in self.lines.iter().enumerate() {
            let after = self.state_before(i + 1);
            if !line.moves || after.motion == MotionMode::Rapid || after.inverse_time {
                continue;
            }
            let feed = after.feed;
            let pts = if line.arc.len() >= 2 {
                line.arc.clone()
            } else {
                vec![self.start_of(i), self.end_of(i)]
            };
            // Per axis, whether some chord of this line is clamped on it, and the slowest
            // speed GRBL allows any clamped chord.
            let mut hit = [false; 3];
            let mut runs_at = feed;
            for w in pts.windows(2) {
                let d: [f64; 3] = std::array::from_fn(|a| w[1][a] - w[0][a]);
                let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
                if len <= super::ZERO_LENGTH_MM {
                    continue;
                }
                for a in 0..3 {
                    let u = d[a].abs() / len;
                    if feed * u > rates[a] * (1.0 + REL_TOL) {
                        hit[a] = true;
                        runs_at = runs_at.min(rates[a] / u);
                    }
                }
            }
            for a in (0..3).filter(|&a| hit[a]) {
                let c = found[a].get_or_insert(FeedClamp {
                    axis: a,
                    max_rate: rates[a],
                    feed,
                    runs_at,
                    line: line.source_line,
                    moves: 0,
                });
                c.moves += 1;
                if feed > c.feed {
                    (c.feed, c.runs_at, c.line) = (feed, runs_at, line.source_line);
                }
            }
        }
        found.into_iter().flatten().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn limits(x: f64, y: f64, z: f64) -> MachineLimits {
        let s = BTreeMap::from([(110, x), (111, y), (112, z)]);
        MachineLimits::from_settings(&s)
    }

    #[test]
    fn a_feed_along_an_axis_over_its_rate_runs_at_the_rate() {
        let job = Job::parse("G21 G90\nG1 X10 F3000\nG1 X20 F400\nG0 Y50\n").unwrap();
        let c = job.feed_clamps(&limits(500.0, 5000.0, 5000.0));
        assert_eq!(
            c,
            vec![FeedClamp {
                axis: 0,
                max_rate: 500.0,
                feed: 3000.0,
                runs_at: 500.0,
                line: 2,
                moves: 1,
            }]
        );
        assert_eq!(
            c[0].to_string(),
            "the job asks F3000 (line 2) but the controller's X max rate ($110) is 500 mm/min: \
             1 move(s) will run slower than the job says, that one at 500 mm/min"
        );
    }

    #[test]
    fn a_diagonal_feed_is_clamped_by_its_axis_component() {
        // 3-4-5 triangle: at F1000 X moves at 600 and Y at 800 mm/min.
        let job = Job::parse("G21 G90\nG1 X30 Y40 F1000\n").unwrap();
        assert!(job.feed_clamps(&limits(600.0, 800.0, 500.0)).is_empty());
        let c = job.feed_clamps(&limits(300.0, 800.0, 500.0));
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].axis, 0);
        // GRBL's nominal speed: 300 / (30/50) = 500 mm/min.
        assert!((c[0].runs_at - 500.0).abs() < 1e-9, "{:?}", c[0]);
    }

    #[test]
    fn rapids_and_plunges_are_checked_on_their_own_axes() {
        let job = Job::parse("G21 G90\nG0 X100\nG1 Z-2 F300\nG1 X0 F300\n").unwrap();
        let c = job.feed_clamps(&limits(500.0, 500.0, 200.0));
        assert_eq!(c.len(), 1);
        assert_eq!((c[0].axis, c[0].line, c[0].runs_at), (2, 3, 200.0));
    }

    #[test]
    fn an_arc_is_checked_chord_by_chord() {
        // A half circle from (10,0) to (-10,0) round the origin: its chords point along Y at
        // the start, so a low Y rate clamps it though the chord end to end is along X.
        let job = Job::parse("G21 G90\nG0 X10 Y0\nG3 X-10 Y0 I-10 J0 F1000\n").unwrap();
        let c = job.feed_clamps(&limits(5000.0, 500.0, 500.0));
        assert_eq!(c.len(), 1);
        assert_eq!((c[0].axis, c[0].line), (1, 3));
    }
}
