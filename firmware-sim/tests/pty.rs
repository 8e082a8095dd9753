//! Round trips through a real pseudo-terminal opened with the `serialport` crate, as a sender would.

use flatcut_firmware_sim::{PtySim, SimConfig};
use std::io::Write;
use std::time::{Duration, Instant};

/// Reads until `pat` appears in the accumulated text or the timeout passes.
fn read_until(
    port: &mut dyn serialport::SerialPort,
    acc: &mut String,
    pat: &str,
    timeout: Duration,
) -> bool {
    let t0 = Instant::now();
    let mut buf = [0u8; 256];
    while t0.elapsed() < timeout {
        if acc.contains(pat) {
            return true;
        }
        match port.read(&mut buf) {
            Ok(n) => acc.push_str(&String::from_utf8_lossy(&buf[..n])),
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("read: {e}"),
        }
    }
    acc.contains(pat)
}

#[test]
fn serialport_round_trip() {
    let sim = PtySim::spawn(SimConfig {
        time_scale: 20.0,
        ..SimConfig::default()
    })
    .unwrap();
    let mut port = serialport::new(sim.path().to_string_lossy(), 115_200)
        .timeout(Duration::from_millis(20))
        .open()
        .unwrap();
    let mut acc = String::new();
    assert!(
        read_until(
            port.as_mut(),
            &mut acc,
            "Grbl 1.1h ['$' for help]\r\n",
            Duration::from_secs(3)
        ),
        "{acc:?}"
    );
    acc.clear();
    port.write_all(b"$I\n").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, "ok\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    assert!(acc.contains("[OPT:V,15,128]"), "{acc:?}");
    acc.clear();
    port.write_all(b"G1 X5 Y5 F3000\n").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, "ok\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    acc.clear();
    port.write_all(b"?").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, ">\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    assert!(
        acc.starts_with("<Run|MPos:") || acc.starts_with("<Idle|MPos:"),
        "{acc:?}"
    );
    // Wait for the move to finish (about 1.6 s simulated at 20x).
    let t0 = Instant::now();
    while sim.trace().is_empty() && t0.elapsed() < Duration::from_secs(3) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(sim.lines_received(), 2);
    drop(port);
    let report = sim.stop();
    assert_eq!(report.trace.len(), 1);
    assert_eq!(report.trace[0].to, [5.0, 5.0, 0.0]);
    assert_eq!(report.stats.oks, 2);
}
