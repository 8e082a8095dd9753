//! [`MachineLimits`]: what the sender needs of a controller's `$$` settings.

use flatcut_motion::Limits;
use std::collections::BTreeMap;

/// What the sender needs to know of a controller's settings: the motion model's limits
/// (`$100-$102`, `$110-$112`, `$120-$122`, `$11`, `$12`, `$1`) for the estimate, and `$32`, `$130-$132`,
/// `$22` for the checks before a job runs.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineLimits {
    /// Steps/mm, max rates, accelerations, junction deviation, arc tolerance and step idle
    /// delay.
    pub motion: Limits,
    /// Laser mode (`$32`): spindle changes do not stop the planner.
    pub laser_mode: bool,
    /// Max travel per axis, mm (`$130-$132`).
    pub max_travel: [f64; 3],
    /// Homing enabled (`$22`): machine coordinates are meaningful for an absolute envelope check.
    pub homing: bool,
}

impl MachineLimits {
    /// GRBL 1.1h defaults (`defaults.h`, DEFAULTS_GENERIC): [`Limits::GRBL_DEFAULT`], laser mode
    /// off, 200 mm travel, homing off.
    pub const DEFAULT: MachineLimits = MachineLimits {
        motion: Limits::GRBL_DEFAULT,
        laser_mode: false,
        max_travel: [200.0; 3],
        homing: false,
    };

    /// Limits from a `$$` dump; settings that are missing keep their default.
    pub fn from_settings(settings: &BTreeMap<u16, f64>) -> MachineLimits {
        let mut l = MachineLimits::DEFAULT;
        let get = |n: u16, d: f64| {
            settings
                .get(&n)
                .copied()
                .filter(|v| v.is_finite())
                .unwrap_or(d)
        };
        let m = &mut l.motion;
        for a in 0..3 {
            m.steps_per_mm[a] = get(100 + a as u16, m.steps_per_mm[a]);
            m.max_rate[a] = get(110 + a as u16, m.max_rate[a]);
            m.accel[a] = get(120 + a as u16, m.accel[a]);
            l.max_travel[a] = get(130 + a as u16, l.max_travel[a]);
        }
        m.junction_deviation = get(11, m.junction_deviation);
        m.arc_tolerance = get(12, m.arc_tolerance);
        m.step_idle_delay = Limits::step_idle_delay_of(get(1, m.step_idle_delay * 1000.0));
        l.laser_mode = get(32, 0.0) != 0.0;
        l.homing = get(22, 0.0) != 0.0;
        l
    }
}

impl Default for MachineLimits {
    fn default() -> MachineLimits {
        MachineLimits::DEFAULT
    }
}
