//! Run-time estimate of a written job with GRBL's motion model ([`flatcut_motion`], the same
//! model the sender uses): the writer records every move and dwell it emits as a [`Motion`], and
//! [`estimate`] times them on a machine whose limits come from the profile ([`limits`]).

use flatcut_motion::{Estimator, Feed, Limits};

use crate::profile::Profile;

/// One timed element of a job.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// A straight move at `feed_mm_min` (`None`: a rapid, at the axes' max rate).
    Move {
        /// Start point (x, y, z in mm).
        from: [f64; 3],
        /// End point (x, y, z in mm).
        to: [f64; 3],
        /// Feed (mm/min); `None` for a rapid.
        feed_mm_min: Option<f64>,
    },
    /// A `G4` dwell, s.
    Dwell(f64),
}

/// The machine a profile describes, as the motion model sees it: its travel speed is the max
/// rate of every axis (GRBL's `G0` speed is `$110-$112`), its acceleration that of every axis;
/// steps/mm, `$12` and the step idle delay `$1` stay at GRBL's defaults (the profile does not say
/// them).
pub fn limits(profile: &Profile) -> Limits {
    Limits {
        steps_per_mm: Limits::GRBL_DEFAULT.steps_per_mm,
        max_rate: [profile.travel_mm_min; 3],
        accel: [profile.accel_mm_s2; 3],
        junction_deviation: profile.junction_deviation_mm,
        arc_tolerance: Limits::GRBL_DEFAULT.arc_tolerance,
        step_idle_delay: Limits::GRBL_DEFAULT.step_idle_delay,
    }
}

/// Seconds to run `motions` on a machine with `limits`.
pub fn estimate(motions: &[Motion], limits: &Limits) -> f64 {
    let mut e = Estimator::new(limits);
    for (k, m) in motions.iter().enumerate() {
        match *m {
            Motion::Move {
                from,
                to,
                feed_mm_min,
            } => {
                let feed = feed_mm_min.map_or(Feed::Rapid, Feed::PerMinute);
                e.segment(k, from, to, feed);
            }
            Motion::Dwell(s) => e.dwell(k, s),
        }
    }
    e.total()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mv(from: [f64; 3], to: [f64; 3], feed: f64) -> Motion {
        Motion::Move {
            from,
            to,
            feed_mm_min: Some(feed),
        }
    }

    #[test]
    fn long_straight_move_is_distance_over_feed_plus_ramps() {
        // 100 mm at 60 mm/s with a = 100: ramps take 0.6 s each and cover 18 mm each.
        let l = Limits {
            max_rate: [6000.0; 3],
            accel: [100.0; 3],
            step_idle_delay: 0.0,
            ..Limits::GRBL_DEFAULT
        };
        let t = estimate(&[mv([0.0; 3], [100.0, 0.0, 0.0], 3600.0)], &l);
        let expect = 0.6 + 0.6 + (100.0 - 36.0) / 60.0;
        assert!((t - expect).abs() < 1e-9, "{t} vs {expect}");
    }

    #[test]
    fn short_move_is_triangular_corners_slow_down_rapids_run_at_the_max_rate() {
        let l = Limits {
            max_rate: [6000.0; 3],
            accel: [100.0; 3],
            step_idle_delay: 0.0,
            ..Limits::GRBL_DEFAULT
        };
        // Triangle: t = 2 sqrt(L/a).
        let tri = estimate(&[mv([0.0; 3], [1.0, 0.0, 0.0], 6000.0)], &l);
        assert!((tri - 2.0 * 0.01f64.sqrt()).abs() < 1e-9);
        let straight = [
            mv([0.0; 3], [50.0, 0.0, 0.0], 3000.0),
            mv([50.0, 0.0, 0.0], [100.0, 0.0, 0.0], 3000.0),
        ];
        let corner = [
            mv([0.0; 3], [50.0, 0.0, 0.0], 3000.0),
            mv([50.0, 0.0, 0.0], [50.0, 50.0, 0.0], 3000.0),
        ];
        // Straight: 2.5 s. Corner: each leg ramps to 50 mm/s and down to the junction speed,
        // √(a·√2·jd·sin½θ/(1−sin½θ)) = 1.85 mm/s with the acceleration along the junction.
        let (c, s) = (estimate(&corner, &l), estimate(&straight, &l));
        assert!(
            (s - 2.5).abs() < 1e-9 && (c - 2.963).abs() < 0.001,
            "{c} {s}"
        );
        assert_eq!(estimate(&[Motion::Dwell(1.5)], &l), 1.5);
        // A rapid along X runs at the profile's travel speed.
        let rapid = Motion::Move {
            from: [0.0; 3],
            to: [600.0, 0.0, 0.0],
            feed_mm_min: None,
        };
        let t = estimate(&[rapid], &l);
        assert!((t - (600.0 / 100.0 + 1.0)).abs() < 1e-9, "{t}");
    }
}
