//! Byte transports: the [`Transport`] trait the driver talks through, and its serial-port
//! implementation (which also opens pseudo-terminals such as firmware-sim's).
//!
//! Serial pitfalls handled here (see grbl-protocol.md, Appendix A): modem-line ioctls fail with
//! ENOTTY on a pty, so DTR/RTS are never relied on (a reset is a 0x18 byte, sent by the driver);
//! `read` reports a timeout as an error, which becomes `Ok(0)`; a vanished device reads as
//! `BrokenPipe`, which becomes [`TransportError::HangUp`]; the port is never `clear()`ed after
//! opening, because flushing drops the banner a freshly reset controller just printed.

use serde::Serialize;
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};
use thiserror::Error;

/// Longest time a single write may wait for the device to take bytes before giving up: at
/// 9600 baud a full 128-byte buffer drains in 0.13 s, so 5 s means the device has stopped
/// reading.
pub const WRITE_STALL_LIMIT: Duration = Duration::from_secs(5);

/// Transport failures.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum TransportError {
    /// The device went away (unplugged, simulator stopped, pty closed).
    #[error("device hung up: {0}")]
    HangUp(String),
    /// The device stopped taking bytes.
    #[error("write stalled for {0:?}: the device is not reading")]
    WriteStalled(Duration),
    /// The port could not be opened.
    #[error("cannot open serial port {path}: {reason}")]
    Open {
        /// Device path.
        path: String,
        /// Why.
        reason: String,
    },
    /// Any other I/O error.
    #[error("serial I/O error: {0}")]
    Io(#[from] std::io::Error),
}

/// A byte pipe to a GRBL device.
pub trait Transport {
    /// Writes all bytes (blocking until the OS took them).
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError>;
    /// Reads whatever is available, waiting at most `timeout` for the first byte; `Ok(0)` means
    /// nothing arrived in time.
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError>;
}

impl<T: Transport + ?Sized> Transport for &mut T {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        (**self).write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        (**self).read(buf, timeout)
    }
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        (**self).write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        (**self).read(buf, timeout)
    }
}

fn map_io(e: std::io::Error) -> TransportError {
    match e.kind() {
        ErrorKind::BrokenPipe
        | ErrorKind::ConnectionReset
        | ErrorKind::ConnectionAborted
        | ErrorKind::UnexpectedEof
        | ErrorKind::NotConnected => TransportError::HangUp(e.to_string()),
        _ if e.raw_os_error() == Some(5) => TransportError::HangUp(e.to_string()), // EIO: pty peer gone
        _ => TransportError::Io(e),
    }
}

/// A serial port (or pty) transport.
pub struct SerialTransport {
    port: Box<dyn serialport::SerialPort>,
    timeout: Duration,
}

impl std::fmt::Debug for SerialTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialTransport")
            .field("name", &self.port.name())
            .finish()
    }
}

impl SerialTransport {
    /// Wraps an already opened port.
    pub fn new(port: Box<dyn serialport::SerialPort>) -> SerialTransport {
        let timeout = port.timeout();
        SerialTransport { port, timeout }
    }

    /// The underlying port.
    pub fn port_mut(&mut self) -> &mut dyn serialport::SerialPort {
        self.port.as_mut()
    }
}

/// Opens `path` at `baud`, 8N1, no flow control, for GRBL. The port is opened exclusively (a
/// second sender on the same machine would interleave lines); if the exclusive advisory lock is
/// refused on a pseudo-terminal (`/dev/pts/*`, where a simulator may hold it), it is retried in
/// shared mode. Modem lines are left alone: they fail on ptys and some boards are held in reset
/// by DTR.
pub fn open_port(path: &str, baud: u32) -> Result<SerialTransport, TransportError> {
    let builder = || {
        serialport::new(path, baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(50))
    };
    let port = match builder().open() {
        Ok(p) => p,
        Err(e) if e.description.contains("lock") && is_pty(path) => builder()
            .open_native_shared()
            .map_err(|e2| TransportError::Open {
                path: path.into(),
                reason: format!("{e}; shared open also failed: {e2}"),
            })?,
        Err(e) => {
            return Err(TransportError::Open {
                path: path.into(),
                reason: e.to_string(),
            });
        }
    };
    Ok(SerialTransport::new(port))
}

trait OpenShared {
    fn open_native_shared(self) -> serialport::Result<Box<dyn serialport::SerialPort>>;
}

impl OpenShared for serialport::SerialPortBuilder {
    fn open_native_shared(self) -> serialport::Result<Box<dyn serialport::SerialPort>> {
        let mut p = serialport::TTYPort::open(&self.exclusive(false))?;
        let _ = p.set_exclusive(false);
        Ok(Box::new(p))
    }
}

fn is_pty(path: &str) -> bool {
    let real = std::fs::canonicalize(path).map(|p| p.to_string_lossy().into_owned());
    real.unwrap_or_else(|_| path.to_string())
        .starts_with("/dev/pts/")
}

impl Transport for SerialTransport {
    fn write_all(&mut self, mut bytes: &[u8]) -> Result<(), TransportError> {
        let start = Instant::now();
        while !bytes.is_empty() {
            match self.port.write(bytes) {
                Ok(0) => {}
                Ok(n) => bytes = &bytes[n..],
                Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::Interrupted => {
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {}
                Err(e) => return Err(map_io(e)),
            }
            if !bytes.is_empty() && start.elapsed() > WRITE_STALL_LIMIT {
                return Err(TransportError::WriteStalled(WRITE_STALL_LIMIT));
            }
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        if timeout != self.timeout {
            self.port
                .set_timeout(timeout)
                .map_err(|e| TransportError::Io(e.into()))?;
            self.timeout = timeout;
        }
        match self.port.read(buf) {
            Ok(0) => Err(TransportError::HangUp("end of file".into())),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::Interrupted => {
                Ok(0)
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => Ok(0),
            Err(e) => Err(map_io(e)),
        }
    }
}

/// A serial port found on the system.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PortInfo {
    /// Device path.
    pub name: String,
    /// Description: USB VID:PID, manufacturer and product when known.
    pub description: String,
}

/// Lists serial ports (`serialport::available_ports`, sysfs-based without libudev). Pseudo-
/// terminals (such as firmware-sim's) are never listed: pass their path explicitly.
pub fn list_ports() -> Result<Vec<PortInfo>, TransportError> {
    let ports = serialport::available_ports().map_err(|e| TransportError::Io(e.into()))?;
    let mut out: Vec<PortInfo> = ports
        .into_iter()
        .map(|p| {
            let description = match p.port_type {
                serialport::SerialPortType::UsbPort(u) => {
                    let mut s = format!("USB {:04x}:{:04x}", u.vid, u.pid);
                    if let Some(m) = u.manufacturer {
                        s.push_str(&format!(" {m}"));
                    }
                    if let Some(pr) = u.product {
                        s.push_str(&format!(" {pr}"));
                    }
                    s
                }
                serialport::SerialPortType::PciPort => "PCI".into(),
                serialport::SerialPortType::BluetoothPort => "Bluetooth".into(),
                serialport::SerialPortType::Unknown => "unknown".into(),
            };
            PortInfo {
                name: p.port_name,
                description,
            }
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}
