//! Which device a project's jobs go to: the project's `[device]` port at its baud rate, or the
//! embedded simulator set up as the machine the profile describes (its rates, accelerations,
//! junction deviation and bed), so a run on the simulator takes as long as the machine would
//! and a job that does not fit the machine is refused as the machine would refuse it.

use flatcut::gcode::Profile;
use flatcut::project::Device;
use flatcut_device::SimMachine;

use super::args::{DEFAULT_BAUD, StreamArgs};

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
    a.sim_machine = Some(machine(profile));
    a
}

/// The machine `profile` describes, for the embedded simulator to be.
pub fn machine(profile: &Profile) -> SimMachine {
    SimMachine {
        limits: flatcut::gcode::time::limits(profile),
        work_area: profile.work_area_mm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_device::Target;

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
        assert_eq!(a.describe(), "/dev/ttyUSB7 at 57600 baud");
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
            let Target::Simulator(setup) = s.target().unwrap() else {
                panic!("not the simulator")
            };
            let settings = setup.config().unwrap().settings;
            for want in [
                (110, 5000.0),
                (111, 5000.0),
                (120, 400.0),
                (121, 400.0),
                (130, 600.0),
                (131, 400.0),
            ] {
                assert!(settings.contains(&want), "{want:?}: {settings:?}");
            }
            assert!(s.describe().contains("machine profile"));
        }
    }
}
