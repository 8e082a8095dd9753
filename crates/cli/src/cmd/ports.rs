//! `flatcut ports`: lists the serial ports a GRBL controller may be on.

use std::process::ExitCode;

use anyhow::Context;
use serialport::SerialPortType;

/// Arguments of `flatcut ports`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// One port, as listed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port {
    /// Device path.
    pub name: String,
    /// `usb`, `pci`, `bluetooth` or `unknown`.
    pub kind: &'static str,
    /// USB vendor and product id as `vvvv:pppp`.
    pub vid_pid: Option<String>,
    /// USB serial number.
    pub serial: Option<String>,
    /// USB manufacturer.
    pub manufacturer: Option<String>,
    /// USB product.
    pub product: Option<String>,
}

/// The system's serial ports, sorted by name (pseudo-terminals are not serial ports to the
/// operating system and are never listed).
pub fn list() -> anyhow::Result<Vec<Port>> {
    let mut ports: Vec<Port> = serialport::available_ports()
        .context("cannot enumerate serial ports")?
        .into_iter()
        .map(|p| match p.port_type {
            SerialPortType::UsbPort(u) => Port {
                name: p.port_name,
                kind: "usb",
                vid_pid: Some(format!("{:04x}:{:04x}", u.vid, u.pid)),
                serial: u.serial_number,
                manufacturer: u.manufacturer,
                product: u.product,
            },
            other => Port {
                name: p.port_name,
                kind: match other {
                    SerialPortType::PciPort => "pci",
                    SerialPortType::BluetoothPort => "bluetooth",
                    _ => "unknown",
                },
                vid_pid: None,
                serial: None,
                manufacturer: None,
                product: None,
            },
        })
        .collect();
    ports.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(ports)
}

/// Runs `flatcut ports`.
pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let ports = list()?;
    if a.json {
        let v: Vec<serde_json::Value> = ports
            .iter()
            .map(|p| {
                serde_json::json!({
                    "name": p.name,
                    "type": p.kind,
                    "vid_pid": p.vid_pid,
                    "serial": p.serial,
                    "manufacturer": p.manufacturer,
                    "product": p.product,
                })
            })
            .collect();
        crate::outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(ExitCode::SUCCESS);
    }
    if ports.is_empty() {
        crate::outln!("no serial ports found");
    }
    for p in &ports {
        let mut line = format!("{:<24} {}", p.name, p.kind);
        if let Some(v) = &p.vid_pid {
            line.push_str(&format!(" {v}"));
        }
        for s in [&p.manufacturer, &p.product].into_iter().flatten() {
            line.push_str(&format!(" {s}"));
        }
        if let Some(s) = &p.serial {
            line.push_str(&format!(" serial {s}"));
        }
        crate::outln!("{line}");
    }
    eprintln!(
        "note: pseudo-terminals (such as `flatcut sim`) are not listed; pass their path with --port"
    );
    Ok(ExitCode::SUCCESS)
}
