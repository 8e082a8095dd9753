//! Which device: [`Target`] (a serial port at a baud rate, or the embedded simulator), the check
//! that it is there before any work starts, and [`list`], the devices an operator can choose
//! from.

use crate::embedded::SimSetup;
use crate::error::DeviceError;

/// Where jobs go.
// A target is made once per session and moved rarely: boxing the simulator's set-up would change
// the variant's public shape for nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// A serial port: a GRBL controller, or a pseudo-terminal such as `flatcut sim`'s.
    Port {
        /// Device path (`/dev/ttyUSB0`, `COM3`, `/dev/pts/4`).
        path: String,
        /// Baud rate of the link.
        baud: u32,
    },
    /// The embedded GRBL simulator, started on its own pseudo-terminal when the device opens and
    /// stopped when it closes.
    Simulator(SimSetup),
}

impl Target {
    /// Checks, without touching a controller, that the device can be opened: a port that
    /// exists, a simulator set-up that is valid. Opening a serial port resets many boards (an
    /// Arduino's DTR), so the port is looked for, not opened.
    pub fn check(&self) -> Result<(), DeviceError> {
        match self {
            Target::Port { path, .. } => {
                let listed = || {
                    serialport::available_ports()
                        .map(|ps| ps.iter().any(|p| p.port_name == *path))
                        .unwrap_or(false)
                };
                if std::path::Path::new(path).exists() || listed() {
                    Ok(())
                } else {
                    Err(DeviceError::PortMissing { path: path.clone() })
                }
            }
            Target::Simulator(s) => s.config().map(|_| ()),
        }
    }

    /// How messages name the device: the port and its baud rate, or the simulator and what
    /// machine it is.
    pub fn describe(&self) -> String {
        match self {
            Target::Port { path, baud } => format!("{path} at {baud} baud"),
            Target::Simulator(s) if s.machine.is_some() => {
                "the embedded simulator (set up from the machine profile)".into()
            }
            Target::Simulator(s) if s.settings.is_empty() => {
                "the embedded simulator (GRBL defaults)".into()
            }
            Target::Simulator(_) => {
                "the embedded simulator (GRBL defaults and the settings given)".into()
            }
        }
    }

    /// The baud rate of the link.
    pub fn baud(&self) -> u32 {
        match self {
            Target::Port { baud, .. } => *baud,
            Target::Simulator(s) => s.baud,
        }
    }

    /// Wall-clock seconds per second of machine time, to turn a job's estimated time into a
    /// wall-clock ETA: 1 on a real machine, `1/speed` on the simulator; `None` when its motion
    /// is instant.
    pub fn wall_per_machine_second(&self) -> Option<f64> {
        match self {
            Target::Port { .. } => Some(1.0),
            Target::Simulator(s) => s.wall_per_machine_second(),
        }
    }
}

/// One device an operator can choose.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceInfo {
    /// What to open: a port at GRBL's 115200 baud, or the simulator with GRBL's defaults.
    pub target: Target,
    /// A line for a list: the port's USB description, or what the simulator is.
    pub description: String,
}

/// The devices on this computer: every serial port the system lists (pseudo-terminals such as
/// `flatcut sim`'s are not listed; open them by path), then the embedded simulator, which is
/// always there.
pub fn list() -> Vec<DeviceInfo> {
    let mut out: Vec<DeviceInfo> = flatcut_grbl::list_ports()
        .unwrap_or_default()
        .into_iter()
        .map(|p| DeviceInfo {
            target: Target::Port {
                path: p.name,
                baud: SimSetup::default().baud,
            },
            description: p.description,
        })
        .collect();
    out.push(DeviceInfo {
        target: Target::Simulator(SimSetup::default()),
        description: "the embedded GRBL 1.1h simulator".into(),
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_port_is_found_before_anything_opens_it() {
        let missing = Target::Port {
            path: "/dev/ttyNOPE".into(),
            baud: 115_200,
        };
        let e = missing.check().unwrap_err();
        assert!(matches!(e, DeviceError::PortMissing { .. }), "{e}");
        assert_eq!(e.to_string(), "the serial port /dev/ttyNOPE does not exist");
        assert_eq!(missing.describe(), "/dev/ttyNOPE at 115200 baud");
        let sim = Target::Simulator(SimSetup::default());
        assert!(sim.check().is_ok());
        assert_eq!(sim.describe(), "the embedded simulator (GRBL defaults)");
        assert!(list().iter().any(|d| d.target == sim));
    }
}
