//! The controller settings the motion model needs: GRBL's `$100-$102` (steps/mm), `$110-$112`
//! (max rate), `$120-$122` (acceleration), `$11` (junction deviation), `$12` (arc tolerance) and
//! `$1` (step idle delay).

/// Motion limits of a GRBL machine. Rates in mm/min, accelerations in mm/s², lengths in mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Steps per mm per axis (`$100-$102`): GRBL plans every move between whole-step positions.
    pub steps_per_mm: [f64; 3],
    /// Max rate per axis, mm/min (`$110-$112`); also the speed of `G0`.
    pub max_rate: [f64; 3],
    /// Acceleration per axis, mm/s² (`$120-$122`).
    pub accel: [f64; 3],
    /// Junction deviation, mm (`$11`).
    pub junction_deviation: f64,
    /// Arc tolerance, mm (`$12`): the chord error `mc_arc` allows.
    pub arc_tolerance: f64,
    /// Step idle delay, s (`$1` / 1000; 0 for `$1=255`, which keeps the motors enabled): each time
    /// the machine comes to a stop, `st_go_idle` holds the steppers this long (a blocking
    /// `delay_ms`) before the controller goes on.
    pub step_idle_delay: f64,
}

impl Limits {
    /// GRBL 1.1h's `DEFAULTS_GENERIC` (`defaults.h`): 250 steps/mm, 500 mm/min, 10 mm/s²,
    /// `$11` = 0.01 mm, `$12` = 0.002 mm, `$1` = 25 ms.
    pub const GRBL_DEFAULT: Limits = Limits {
        steps_per_mm: [250.0; 3],
        max_rate: [500.0; 3],
        accel: [10.0; 3],
        junction_deviation: 0.01,
        arc_tolerance: 0.002,
        step_idle_delay: 0.025,
    };

    /// The step idle delay, s, of a `$1` setting in ms: 255 keeps the motors enabled and never
    /// waits (`st_go_idle`).
    pub fn step_idle_delay_of(setting_ms: f64) -> f64 {
        if setting_ms == 255.0 || setting_ms.is_nan() || setting_ms <= 0.0 {
            0.0
        } else {
            setting_ms / 1000.0
        }
    }
}

impl Default for Limits {
    fn default() -> Limits {
        Limits::GRBL_DEFAULT
    }
}

/// GRBL's `limit_value_by_axis_maximum`: the largest value along the unit vector `unit` that
/// keeps every axis component within `per_axis` (`value` caps it further).
pub fn axis_limited(value: f64, unit: [f64; 3], per_axis: [f64; 3]) -> f64 {
    let mut v = value;
    for a in 0..3 {
        if unit[a].abs() > 1e-12 {
            v = v.min(per_axis[a] / unit[a].abs());
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diagonal_may_go_faster_than_either_axis() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let v = axis_limited(f64::INFINITY, [s, s, 0.0], [500.0, 500.0, 100.0]);
        assert!((v - 500.0 * std::f64::consts::SQRT_2).abs() < 1e-9);
        assert_eq!(
            axis_limited(f64::INFINITY, [0.0, 0.0, 1.0], [500.0, 500.0, 100.0]),
            100.0
        );
        assert_eq!(axis_limited(300.0, [1.0, 0.0, 0.0], [500.0; 3]), 300.0);
    }
}
