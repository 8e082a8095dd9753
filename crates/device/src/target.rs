//! Which device: [`Target`] (a GRBL controller on a serial port at a baud rate, the embedded
//! GRBL simulator, an HP-GL plotter on a serial port, the embedded HP-GL plotter), the check
//! that it is there before any work starts, and [`list`], the devices an operator can choose
//! from.

use crate::embedded::SimSetup;
use crate::error::DeviceError;
use crate::plotter::{PlotterLink, PlotterSimSetup};

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
    /// An HP-GL plotter or vinyl cutter on a serial port, with its link's flow control.
    Plotter {
        /// Device path.
        path: String,
        /// Flow control, buffer queries, baud rate.
        link: PlotterLink,
    },
    /// The embedded HP-GL plotter simulator, started on its own pseudo-terminal when the device
    /// opens and stopped when it closes.
    PlotterSim(PlotterSimSetup),
}

impl Target {
    /// Checks, without touching a controller, that the device can be opened: a port that
    /// exists, a simulator set-up that is valid. Opening a serial port resets many boards (an
    /// Arduino's DTR), so the port is looked for, not opened.
    pub fn check(&self) -> Result<(), DeviceError> {
        match self {
            Target::Port { path, .. } | Target::Plotter { path, .. } => {
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
            Target::PlotterSim(s) if s.link.baud > 0 && s.speed.is_finite() && s.speed > 0.0 => {
                Ok(())
            }
            Target::PlotterSim(_) => Err(DeviceError::Simulator(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the HP-GL plotter simulator needs a baud rate and a time scale > 0",
            ))),
        }
    }

    /// Whether it speaks HP-GL (a plotter or vinyl cutter, or the embedded one).
    pub fn is_plotter(&self) -> bool {
        matches!(self, Target::Plotter { .. } | Target::PlotterSim(_))
    }

    /// The serial port's path (`None` for an embedded simulator).
    pub fn path(&self) -> Option<&str> {
        match self {
            Target::Port { path, .. } | Target::Plotter { path, .. } => Some(path),
            Target::Simulator(_) | Target::PlotterSim(_) => None,
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
            Target::Plotter { path, link } => {
                format!("the HP-GL plotter on {path} at {} baud", link.baud)
            }
            Target::PlotterSim(_) => "the embedded HP-GL plotter simulator".into(),
        }
    }

    /// The baud rate of the link.
    pub fn baud(&self) -> u32 {
        match self {
            Target::Port { baud, .. } => *baud,
            Target::Simulator(s) => s.baud,
            Target::Plotter { link, .. } => link.baud,
            Target::PlotterSim(s) => s.link.baud,
        }
    }

    /// Wall-clock seconds per second of machine time, to turn a job's estimated time into a
    /// wall-clock ETA: 1 on a real machine, `1/speed` on the simulator; `None` when its motion
    /// is instant.
    pub fn wall_per_machine_second(&self) -> Option<f64> {
        match self {
            Target::Port { .. } | Target::Plotter { .. } => Some(1.0),
            Target::Simulator(s) => s.wall_per_machine_second(),
            Target::PlotterSim(s) => Some(1.0 / s.speed),
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
