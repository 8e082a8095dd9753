//! The embedded GRBL simulator as a device: [`SimSetup`] says what machine it is (GRBL's
//! defaults, or the machine a profile describes: [`SimMachine`]) and how it runs (time scale,
//! laser mode, injected faults), and becomes firmware-sim's configuration. The simulated bed is
//! the machine's: a job larger than its travel is refused as a real machine's would be.

use crate::error::DeviceError;
use flatcut_firmware_sim::{Faults, SimConfig};
use flatcut_motion::Limits;

/// GRBL's `MAX_STEP_RATE_HZ` (`config.h`): `$100 × $110 / 60` may not exceed it.
const MAX_STEP_RATE_HZ: f64 = 30_000.0;
/// GRBL 1.1's default baud rate (`config.h`).
const GRBL_BAUD: u32 = 115_200;

/// A machine for the simulator to be: its motion limits and its work area, as a machine profile
/// states them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimMachine {
    /// Steps/mm, rates, accelerations, junction deviation and arc tolerance.
    pub limits: Limits,
    /// Work area (X, Y), mm: the travel `$130`, `$131`.
    pub work_area: [f64; 2],
}

impl SimMachine {
    /// The `$N=VALUE` settings of a GRBL controller that is this machine: `$110-$112` = its
    /// rates, `$120-$122` = its accelerations, `$11` = its junction deviation, `$1` = its step idle
    /// delay, `$130/$131` = its work area; steps/mm lowered where GRBL's 30 kHz step rate would
    /// refuse the rate at them.
    pub fn settings(&self) -> Vec<(u16, f64)> {
        let m = &self.limits;
        let mut out = Vec::new();
        for a in 0..3 {
            let steps = m.steps_per_mm[a].min((MAX_STEP_RATE_HZ * 60.0 / m.max_rate[a]).floor());
            let n = a as u16;
            out.push((100 + n, steps));
            out.push((110 + n, m.max_rate[a]));
            out.push((120 + n, m.accel[a]));
        }
        out.push((11, m.junction_deviation));
        out.push((1, (m.step_idle_delay * 1000.0).round().clamp(0.0, 254.0)));
        out.push((130, self.work_area[0]));
        out.push((131, self.work_area[1]));
        out
    }
}

/// How the embedded simulator runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SimSetup {
    /// The machine it is; `None`: GRBL 1.1h's defaults (200 mm of travel on each axis).
    pub machine: Option<SimMachine>,
    /// Further `$N=VALUE` settings at start, applied after the machine's (so they win).
    pub settings: Vec<(u16, f64)>,
    /// Laser mode (`$32=1`).
    pub laser: bool,
    /// Time scale: 1 is real time, 50 runs motion fifty times faster.
    pub speed: f64,
    /// Motion completes at once.
    pub instant: bool,
    /// Baud rate the link is paced at.
    pub baud: u32,
    /// Faults to inject (tests, demonstrations).
    pub faults: Faults,
}

impl Default for SimSetup {
    fn default() -> SimSetup {
        SimSetup {
            machine: None,
            settings: Vec::new(),
            laser: false,
            speed: 1.0,
            instant: false,
            baud: GRBL_BAUD,
            faults: Faults::default(),
        }
    }
}

impl SimSetup {
    /// Sets [`SimSetup::machine`].
    pub fn with_machine(mut self, m: SimMachine) -> Self {
        self.machine = Some(m);
        self
    }
    /// Sets [`SimSetup::speed`].
    pub fn with_speed(mut self, speed: f64) -> Self {
        self.speed = speed;
        self
    }
    /// Sets [`SimSetup::instant`].
    pub fn with_instant(mut self, on: bool) -> Self {
        self.instant = on;
        self
    }
    /// Sets [`SimSetup::laser`].
    pub fn with_laser(mut self, on: bool) -> Self {
        self.laser = on;
        self
    }
    /// Adds a `$n=value` setting.
    pub fn with_setting(mut self, n: u16, value: f64) -> Self {
        self.settings.push((n, value));
        self
    }

    /// Every start setting, in the order applied: laser mode, the machine's, then the others.
    pub fn all_settings(&self) -> Vec<(u16, f64)> {
        let mut s = Vec::new();
        if self.laser {
            s.push((32, 1.0));
        }
        if let Some(m) = &self.machine {
            s.extend(m.settings());
        }
        s.extend(self.settings.iter().copied());
        s
    }

    /// firmware-sim's configuration for this set-up, validated.
    pub fn config(&self) -> Result<SimConfig, DeviceError> {
        let mut cfg = SimConfig::default()
            .with_baud(self.baud)
            .with_time_scale(self.speed)
            .with_instant_motion(self.instant)
            .with_faults(self.faults.clone());
        cfg.settings = self.all_settings();
        cfg.validate().map_err(DeviceError::SimConfig)?;
        Ok(cfg)
    }

    /// Wall-clock seconds per second of machine time (`None`: motion is instant).
    pub fn wall_per_machine_second(&self) -> Option<f64> {
        (!self.instant).then(|| 1.0 / self.speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_simulator_is_the_machine_it_is_told_and_no_larger() {
        let knife = SimMachine {
            limits: Limits {
                max_rate: [5000.0; 3],
                accel: [400.0; 3],
                ..Limits::GRBL_DEFAULT
            },
            work_area: [600.0, 400.0],
        };
        let s = SimSetup::default()
            .with_machine(knife)
            .with_laser(true)
            .with_setting(130, 610.0);
        let cfg = s.config().unwrap();
        // 250 steps/mm × 5000 mm/min = 20.8 kHz: within GRBL's 30 kHz, so kept.
        for want in [
            (32, 1.0),
            (100, 250.0),
            (110, 5000.0),
            (121, 400.0),
            (11, 0.01),
            (1, 25.0),
            (130, 600.0),
            (131, 400.0),
        ] {
            assert!(cfg.settings.contains(&want), "{want:?}: {:?}", cfg.settings);
        }
        // Laser first, the explicit setting last (it wins), and nothing else: no bed grown for
        // a job.
        assert_eq!(cfg.settings.first(), Some(&(32, 1.0)));
        assert_eq!(cfg.settings.last(), Some(&(130, 610.0)));
        assert_eq!(cfg.settings.len(), 1 + 9 + 2 + 2 + 1);
        // A rate GRBL's step rate cannot reach at 250 steps/mm lowers the steps/mm.
        let fast = SimMachine {
            limits: Limits {
                max_rate: [12_000.0; 3],
                ..Limits::GRBL_DEFAULT
            },
            work_area: [100.0, 100.0],
        };
        assert_eq!(fast.settings()[0], (100, 150.0));
        assert!(SimSetup::default().with_speed(0.0).config().is_err());
        assert_eq!(
            SimSetup::default()
                .with_speed(50.0)
                .wall_per_machine_second(),
            Some(0.02)
        );
    }
}
