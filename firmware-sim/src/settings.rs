//! GRBL 1.1h `$n` settings: the default table of an Uno build, validation as `settings.c` does it, and the `$$` listing.

use crate::status::Status;

/// Number of axes of the Uno build (X, Y, Z).
pub const N_AXIS: usize = 3;

/// `MAX_STEP_RATE_HZ` of `config.h`: `$100 × $110 / 60` may not exceed 30 kHz (error:12).
pub const MAX_STEP_RATE_HZ: f64 = 30_000.0;

/// The settings GRBL 1.1h keeps in EEPROM, in the units of the `$$` listing (mm, mm/min, mm/s²).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// `$0` step pulse, µs.
    pub pulse_us: u8,
    /// `$1` step idle delay, ms.
    pub idle_delay_ms: u8,
    /// `$2` step port invert mask.
    pub step_invert: u8,
    /// `$3` direction port invert mask.
    pub dir_invert: u8,
    /// `$4` step enable invert.
    pub enable_invert: bool,
    /// `$5` limit pins invert.
    pub limit_invert: bool,
    /// `$6` probe pin invert.
    pub probe_invert: bool,
    /// `$10` status report mask (bit 0: MPos instead of WPos, bit 1: `Bf:` field).
    pub status_mask: u8,
    /// `$11` junction deviation, mm.
    pub junction_deviation: f64,
    /// `$12` arc tolerance, mm.
    pub arc_tolerance: f64,
    /// `$13` report in inches.
    pub report_inches: bool,
    /// `$20` soft limits.
    pub soft_limits: bool,
    /// `$21` hard limits.
    pub hard_limits: bool,
    /// `$22` homing cycle enabled.
    pub homing: bool,
    /// `$23` homing direction invert mask.
    pub homing_dir_mask: u8,
    /// `$24` homing locate feed, mm/min.
    pub homing_feed: f64,
    /// `$25` homing search seek, mm/min.
    pub homing_seek: f64,
    /// `$26` homing switch debounce, ms.
    pub homing_debounce: u8,
    /// `$27` homing pull-off, mm.
    pub homing_pulloff: f64,
    /// `$30` maximum spindle speed (S at 100 % PWM).
    pub rpm_max: f64,
    /// `$31` minimum spindle speed.
    pub rpm_min: f64,
    /// `$32` laser mode.
    pub laser_mode: bool,
    /// `$100..$102` steps/mm.
    pub steps_per_mm: [f64; N_AXIS],
    /// `$110..$112` maximum rate, mm/min.
    pub max_rate: [f64; N_AXIS],
    /// `$120..$122` acceleration, mm/s².
    pub acceleration: [f64; N_AXIS],
    /// `$130..$132` maximum travel, mm (positive; the machine space is `[-travel, 0]`).
    pub max_travel: [f64; N_AXIS],
}

impl Default for Settings {
    /// The `DEFAULTS_GENERIC` table of GRBL 1.1h (`defaults.h`), as an Uno build ships.
    fn default() -> Self {
        Settings {
            pulse_us: 10,
            idle_delay_ms: 25,
            step_invert: 0,
            dir_invert: 0,
            enable_invert: false,
            limit_invert: false,
            probe_invert: false,
            status_mask: 1,
            junction_deviation: 0.01,
            arc_tolerance: 0.002,
            report_inches: false,
            soft_limits: false,
            hard_limits: false,
            homing: false,
            homing_dir_mask: 0,
            homing_feed: 25.0,
            homing_seek: 500.0,
            homing_debounce: 250,
            homing_pulloff: 1.0,
            rpm_max: 1000.0,
            rpm_min: 0.0,
            laser_mode: false,
            steps_per_mm: [250.0; N_AXIS],
            max_rate: [500.0; N_AXIS],
            acceleration: [10.0; N_AXIS],
            max_travel: [200.0; N_AXIS],
        }
    }
}

/// Formats a value with `decimals` places the way GRBL's `printFloat` does (round half away from zero).
pub fn fmt_float(value: f64, decimals: usize) -> String {
    let v = if value == 0.0 { 0.0 } else { value };
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

impl Settings {
    /// How long `st_go_idle` holds the steppers when they stop (`delay_ms($1)`), s: `$1=255`
    /// keeps them enabled and does not wait.
    pub fn step_idle_delay_s(&self) -> f64 {
        if self.idle_delay_ms == 255 {
            0.0
        } else {
            f64::from(self.idle_delay_ms) / 1000.0
        }
    }

    /// Stores `$parameter=value` with GRBL's checks (`settings_store_global_setting`).
    pub fn store(&mut self, parameter: u32, value: f64) -> Result<(), Status> {
        if value < 0.0 {
            return Err(Status::NegativeValue);
        }
        if parameter >= 100 {
            let mut p = parameter - 100;
            let mut group = 0;
            loop {
                if (p as usize) < N_AXIS {
                    let a = p as usize;
                    match group {
                        0 => {
                            if value * self.max_rate[a] > MAX_STEP_RATE_HZ * 60.0 {
                                return Err(Status::MaxStepRateExceeded);
                            }
                            self.steps_per_mm[a] = value;
                        }
                        1 => {
                            if value * self.steps_per_mm[a] > MAX_STEP_RATE_HZ * 60.0 {
                                return Err(Status::MaxStepRateExceeded);
                            }
                            self.max_rate[a] = value;
                        }
                        2 => self.acceleration[a] = value,
                        _ => self.max_travel[a] = value,
                    }
                    return Ok(());
                }
                group += 1;
                if p < 10 || group == 4 {
                    return Err(Status::InvalidStatement);
                }
                p -= 10;
            }
        }
        // GRBL truncates to uint8_t for the integer settings.
        let int_value = (value.trunc() as u64 & 0xff) as u8;
        match parameter {
            0 => {
                if int_value < 3 {
                    return Err(Status::SettingStepPulseMin);
                }
                self.pulse_us = int_value;
            }
            1 => self.idle_delay_ms = int_value,
            2 => self.step_invert = int_value,
            3 => self.dir_invert = int_value,
            4 => self.enable_invert = int_value != 0,
            5 => self.limit_invert = int_value != 0,
            6 => self.probe_invert = int_value != 0,
            10 => self.status_mask = int_value,
            11 => self.junction_deviation = value,
            12 => self.arc_tolerance = value,
            13 => self.report_inches = int_value != 0,
            20 => {
                if int_value != 0 && !self.homing {
                    return Err(Status::SoftLimitError);
                }
                self.soft_limits = int_value != 0;
            }
            21 => self.hard_limits = int_value != 0,
            22 => {
                self.homing = int_value != 0;
                if !self.homing {
                    // settings.c: disabling homing forces soft limits off.
                    self.soft_limits = false;
                }
            }
            23 => self.homing_dir_mask = int_value,
            24 => self.homing_feed = value,
            25 => self.homing_seek = value,
            26 => self.homing_debounce = int_value,
            27 => self.homing_pulloff = value,
            30 => self.rpm_max = value,
            31 => self.rpm_min = value,
            32 => self.laser_mode = int_value != 0,
            _ => return Err(Status::InvalidStatement),
        }
        Ok(())
    }

    /// The `$$` listing, one `$n=value\r\n` line each, formatted as `report_grbl_settings` does.
    pub fn listing(&self) -> String {
        let mut out = String::new();
        let mut int = |n: u32, v: u32| out.push_str(&format!("${n}={v}\r\n"));
        int(0, self.pulse_us.into());
        int(1, self.idle_delay_ms.into());
        int(2, self.step_invert.into());
        int(3, self.dir_invert.into());
        int(4, self.enable_invert.into());
        int(5, self.limit_invert.into());
        int(6, self.probe_invert.into());
        int(10, self.status_mask.into());
        let mut s = out;
        let flt = |s: &mut String, n: u32, v: f64, d: usize| {
            s.push_str(&format!("${n}={}\r\n", fmt_float(v, d)))
        };
        flt(&mut s, 11, self.junction_deviation, 3);
        flt(&mut s, 12, self.arc_tolerance, 3);
        s.push_str(&format!("$13={}\r\n", u8::from(self.report_inches)));
        s.push_str(&format!("$20={}\r\n", u8::from(self.soft_limits)));
        s.push_str(&format!("$21={}\r\n", u8::from(self.hard_limits)));
        s.push_str(&format!("$22={}\r\n", u8::from(self.homing)));
        s.push_str(&format!("$23={}\r\n", self.homing_dir_mask));
        flt(&mut s, 24, self.homing_feed, 3);
        flt(&mut s, 25, self.homing_seek, 3);
        s.push_str(&format!("$26={}\r\n", self.homing_debounce));
        flt(&mut s, 27, self.homing_pulloff, 3);
        flt(&mut s, 30, self.rpm_max, 0);
        flt(&mut s, 31, self.rpm_min, 0);
        s.push_str(&format!("$32={}\r\n", u8::from(self.laser_mode)));
        for (base, values) in [
            (100, self.steps_per_mm),
            (110, self.max_rate),
            (120, self.acceleration),
            (130, self.max_travel),
        ] {
            for (a, v) in values.iter().enumerate() {
                flt(&mut s, base + a as u32, *v, 3);
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn store_checks_like_settings_c() {
        let mut s = Settings::default();
        assert_eq!(s.store(0, 2.0), Err(Status::SettingStepPulseMin));
        assert_eq!(s.store(20, 1.0), Err(Status::SoftLimitError));
        assert_eq!(s.store(22, 1.0), Ok(()));
        assert_eq!(s.store(20, 1.0), Ok(()));
        // Turning homing off forces soft limits off.
        assert_eq!(s.store(22, 0.0), Ok(()));
        assert!(!s.soft_limits);
        assert_eq!(s.store(121, 50.0), Ok(()));
        assert_eq!(s.acceleration, [10.0, 50.0, 10.0]);
        assert_eq!(s.store(133, 1.0), Err(Status::InvalidStatement));
        assert_eq!(s.store(140, 1.0), Err(Status::InvalidStatement));
        assert_eq!(s.store(7, 1.0), Err(Status::InvalidStatement));
        // 250 steps/mm × 7300 mm/min = 30.4 kHz > 30 kHz.
        assert_eq!(s.store(110, 7300.0), Err(Status::MaxStepRateExceeded));
        assert_eq!(s.store(110, 7200.0), Ok(()));
        assert_eq!(s.store(11, -0.1), Err(Status::NegativeValue));
    }

    #[test]
    fn floats_print_like_grbl() {
        assert_eq!(fmt_float(0.01, 3), "0.010");
        assert_eq!(fmt_float(-0.0001, 3), "0.000");
        assert_eq!(fmt_float(-1.5, 3), "-1.500");
        assert_eq!(fmt_float(999.6, 0), "1000");
    }
}
