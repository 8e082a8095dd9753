//! The `firmware-sim` binary: prints the device path, serves a sender, and writes its traces on SIGTERM.

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[test]
fn binary_serves_a_client_and_writes_traces_on_sigterm() {
    let dir = std::env::temp_dir().join(format!("fw-sim-bin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (jsonl, svg, link) = (dir.join("t.jsonl"), dir.join("t.svg"), dir.join("ttyGRBL"));
    let report = dir.join("report.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_firmware-sim"))
        .args([
            "--link",
            link.to_str().unwrap(),
            "--speed",
            "50",
            "--laser",
            "--error-at",
            "3:33",
        ])
        .args([
            "--trace",
            jsonl.to_str().unwrap(),
            "--trace-svg",
            svg.to_str().unwrap(),
        ])
        .args(["--report", report.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(
        first.starts_with(link.to_str().unwrap()) && first.contains("/dev/pts/"),
        "{first}"
    );
    let mut port = serialport::new(link.to_string_lossy(), 115_200)
        .timeout(Duration::from_millis(20))
        .open()
        .unwrap();
    // Opening the port resets the board like an Uno's DTR pulse: bytes sent before its banner are lost, so a
    // client waits for the banner before it writes.
    let mut acc = String::new();
    let t0 = Instant::now();
    let mut buf = [0u8; 256];
    while !acc.contains("for help]\r\n") && t0.elapsed() < Duration::from_secs(5) {
        if let Ok(n) = port.read(&mut buf) {
            acc.push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    }
    assert!(acc.contains("for help]\r\n"), "{acc:?}");
    port.write_all(b"M3 S800\nG1 X2 Y2 F3000\nG1 X0\nG1 X0 Y0\n")
        .unwrap();
    acc.clear();
    let t0 = Instant::now();
    while acc.matches("ok\r\n").count() + acc.matches("error:").count() < 4
        && t0.elapsed() < Duration::from_secs(5)
    {
        if let Ok(n) = port.read(&mut buf) {
            acc.push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    }
    assert!(acc.ends_with("ok\r\nok\r\nerror:33\r\nok\r\n"), "{acc:?}");
    std::thread::sleep(Duration::from_millis(300));
    drop(port);
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGTERM,
    )
    .unwrap();
    let status = child.wait().unwrap();
    assert!(status.success());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(err.contains("4 lines"), "{err}");
    let trace = std::fs::read_to_string(&jsonl).unwrap();
    assert_eq!(trace.lines().count(), 2, "{trace}");
    assert!(trace.contains(r#""tool_on":true"#) && trace.contains(r#""power":800.0"#));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<polyline"));
    assert!(!link.exists());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(summary["stats"]["oks"], 3);
    assert_eq!(summary["stats"]["errors"], 1);
    assert_eq!(summary["segments"], 2);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn binary_rejects_bad_arguments() {
    let out = Command::new(env!("CARGO_BIN_EXE_firmware-sim"))
        .args(["--drop-rate", "2"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--drop-rate"));
    let out = Command::new(env!("CARGO_BIN_EXE_firmware-sim"))
        .args(["--alarm-at", "x:1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}
