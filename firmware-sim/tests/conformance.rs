//! Conformance of the simulated controller against GRBL 1.1h facts (grbl-protocol.md and the firmware sources).

use flatcut_firmware_sim::{BANNER, Grbl, SimConfig, State};

/// A core with the banner already consumed.
fn grbl(config: SimConfig) -> Grbl {
    let mut g = Grbl::new(&config);
    let out = String::from_utf8(g.take_output()).unwrap();
    assert!(out.starts_with(BANNER), "banner first, got {out:?}");
    g
}

/// Sends a line and runs until the machine is quiet; returns the text answered.
fn send(g: &mut Grbl, line: &str) -> String {
    g.receive_all(line.as_bytes());
    g.receive(b'\n');
    g.run_until_idle(600.0);
    String::from_utf8(g.take_output()).unwrap()
}

fn lines(s: &str) -> Vec<&str> {
    s.split("\r\n").filter(|l| !l.is_empty()).collect()
}

#[test]
fn banner_and_build_info() {
    let mut g = grbl(SimConfig::default());
    assert_eq!(
        lines(&send(&mut g, "$I")),
        ["[VER:1.1h.20190830:]", "[OPT:V,15,128]", "ok"]
    );
    assert_eq!(lines(&send(&mut g, "")), ["ok"]);
    g.receive(0x18);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), BANNER);
}

#[test]
fn status_report_idle() {
    let mut g = grbl(SimConfig::default());
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert_eq!(
        s,
        "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n"
    );
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert_eq!(s, "<Idle|MPos:0.000,0.000,0.000|FS:0,0|Ov:100,100,100>\r\n");
}

#[test]
fn simple_move_runs_and_ends_idle() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G1 X10 F600\n");
    g.tick(0.01);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "ok\r\n");
    assert_eq!(g.state(), State::Cycle);
    g.run_until_idle(100.0);
    assert_eq!(g.state(), State::Idle);
    assert_eq!(g.machine_position(), [10.0, 0.0, 0.0]);
    let tr = g.trace();
    assert_eq!(tr.len(), 1);
    // 10 mm at 10 mm/s with 10 mm/s² : accelerate 1 s (5 mm), decelerate 1 s (5 mm): 2 s, no cruise.
    let dt = tr[0].t_end - tr[0].t_start;
    assert!((dt - 2.0).abs() < 0.01, "duration {dt}");
}
