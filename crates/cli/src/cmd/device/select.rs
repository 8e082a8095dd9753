//! Which device a project's jobs go to: the project's `[device]` port at its baud rate, or the
//! embedded simulator configured as the machine the profile describes (its rates, accelerations,
//! junction deviation and bed), so a run on the simulator takes as long as the machine would.

use flatcut::gcode::Profile;
use flatcut::project::Device;

use super::{DEFAULT_BAUD, StreamArgs};

/// GRBL's `MAX_STEP_RATE_HZ` (`config.h`): `$100 × $110 / 60` may not exceed it.
const MAX_STEP_RATE_HZ: f64 = 30_000.0;

/// The stream arguments of a project's run: `cli` as given, with the device taken from the
/// project. A `--port` on the command line wins over the project's; otherwise the project's port
/// (at its baud rate, GRBL's 115200 if it names none) is the device, and without one (or with
/// `port = "simulator"`) the embedded simulator runs, set up from `profile`.
pub fn for_project(device: &Device, profile: &Profile, cli: &StreamArgs) -> StreamArgs {
    let mut a = cli.clone();
    if a.port.is_some() {
        return a;
    }
    if !device.is_simulator() {
        a.port = device.port.clone();
        a.baud = device.baud.unwrap_or(DEFAULT_BAUD);
        return a;
    }
    a.baud = device.baud.unwrap_or(a.baud);
    let mut set = profile_settings(profile);
    // Explicit --sim-set flags come last, so they win.
    set.append(&mut a.sim_set);
    a.sim_set = set;
    a
}

/// The `$N=VALUE` settings of a GRBL controller that is the machine `profile` describes:
/// `$110-$112` = its travel speed, `$120-$122` = its acceleration, `$11` = its junction
/// deviation, `$130/$131` = its work area; steps/mm lowered where GRBL's 30 kHz step rate would
/// refuse the rate at the default 250.
pub fn profile_settings(profile: &Profile) -> Vec<String> {
    let m = flatcut::gcode::time::limits(profile);
    let mut out = Vec::new();
    for a in 0..3 {
        let steps = m.steps_per_mm[a].min((MAX_STEP_RATE_HZ * 60.0 / m.max_rate[a]).floor());
        out.push(format!("{}={steps}", 100 + a));
        out.push(format!("{}={}", 110 + a, m.max_rate[a]));
        out.push(format!("{}={}", 120 + a, m.accel[a]));
    }
    out.push(format!("11={}", m.junction_deviation));
    out.push(format!("130={}", profile.work_area_mm[0]));
    out.push(format!("131={}", profile.work_area_mm[1]));
    out
}

/// How a run's summary names the device: the port and its baud rate, or the simulator.
pub fn describe(args: &StreamArgs) -> String {
    match &args.port {
        Some(p) => format!("{p} at {} baud", args.baud),
        None if args.sim_set.is_empty() => "the embedded simulator (GRBL defaults)".into(),
        None => "the embedded simulator (set up from the machine profile)".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_projects_device_is_the_device_and_the_simulator_is_the_profiles_machine() {
        let knife = Profile::resolve("knife").unwrap();
        let cli = StreamArgs::default();
        let real = Device {
            port: Some("/dev/ttyUSB7".into()),
            baud: Some(57_600),
        };
        let a = for_project(&real, &knife, &cli);
        assert_eq!(a.port.as_deref(), Some("/dev/ttyUSB7"));
        assert_eq!(a.baud, 57_600);
        assert_eq!(describe(&a), "/dev/ttyUSB7 at 57600 baud");
        // The command line's --port wins.
        let b = for_project(&real, &knife, &cli.clone().with_port("/dev/ttyACM0"));
        assert_eq!(b.port.as_deref(), Some("/dev/ttyACM0"));
        for sim in [
            Device::default(),
            Device {
                port: Some(Device::SIMULATOR.into()),
                baud: None,
            },
        ] {
            let s = for_project(&sim, &knife, &cli);
            assert!(s.uses_sim());
            for want in [
                "110=5000", "111=5000", "120=400", "121=400", "130=600", "131=400",
            ] {
                assert!(
                    s.sim_set.iter().any(|x| x == want),
                    "{want}: {:?}",
                    s.sim_set
                );
            }
            assert!(describe(&s).contains("machine profile"));
        }
    }
}
