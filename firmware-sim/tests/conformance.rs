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
    // F600 is capped by $110 = 500 mm/min: 8.333 mm/s, reached after 0.833 s (3.47 mm) at 10 mm/s².
    let v = 500.0 / 60.0;
    let want = 2.0 * v / 10.0 + (10.0 - v * v / 10.0) / v;
    let dt = tr[0].t_end - tr[0].t_start;
    assert!((dt - want).abs() < 1e-3, "duration {dt} vs {want}");
}

fn err(g: &mut Grbl, line: &str) -> String {
    let out = send(g, line);
    let l = lines(&out);
    l.last().copied().unwrap_or("").to_string()
}

#[test]
fn error_codes_match_grbl() {
    let mut g = grbl(SimConfig::default());
    let cases: &[(&str, &str)] = &[
        ("%", "error:1"),
        ("G1 X1.2.3 F100", "error:1"),
        ("G1 X- F100", "error:2"),
        ("$Q", "error:2"),
        ("$I5", "error:3"),
        ("G4 P-1", "error:4"),
        ("$H", "error:5"),
        ("$0=2", "error:6"),
        ("$20=1", "error:10"),
        ("$100=4000", "error:12"),
        ("M6", "error:20"),
        ("T1 M6", "error:20"),
        ("G5 X1", "error:20"),
        ("G1 X1 F100 Q1", "error:20"),
        ("G17 G18", "error:21"),
        ("G90 G91", "error:21"),
        ("M3 M5", "error:21"),
        ("G1 X10", "error:22"),
        ("G1.5 X1 F100", "error:23"),
        ("G0 G1 X1", "error:24"),
        ("G0 G28 X1", "error:24"),
        ("X1 X2", "error:25"),
        ("G10 L2 P1", "error:26"),
        ("G2 F100", "error:26"),
        ("N99999999 G0 X0", "error:27"),
        ("G4", "error:28"),
        ("G10 L2 P8 X1", "error:29"),
        ("G53 G2 X1 I1 F100", "error:30"),
        ("G80 X1", "error:31"),
        ("G2 Z5 I1 F100", "error:32"),
        ("G2 X10 I3 F100", "error:33"),
        ("G2 X10 R2 F100", "error:34"),
        ("G2 X10 F100", "error:35"),
        ("G0 X1 R5", "error:36"),
        ("G43.1 X1", "error:37"),
        ("T300", "error:38"),
    ];
    for (line, want) in cases {
        assert_eq!(err(&mut g, line), *want, "line {line:?}");
        assert_eq!(g.state(), State::Idle, "after {line:?}");
    }
    // Nothing moved: every line above was rejected whole.
    assert!(g.trace().is_empty());
    assert_eq!(g.machine_position(), [0.0, 0.0, 0.0]);
}

#[test]
fn line_length_limit_is_79_significant_characters() {
    let mut g = grbl(SimConfig::default());
    let pad = |n: usize| format!("G4P0{}", "0".repeat(n - 4));
    assert_eq!(err(&mut g, &pad(79)), "ok");
    assert_eq!(err(&mut g, &pad(80)), "error:11");
    // Spaces and comments do not count.
    let spaced = format!(
        "G4 P0 {} (a long comment that is stripped) ; and more",
        "0".repeat(75)
    );
    assert_eq!(err(&mut g, &spaced), "ok");
}

#[test]
fn pre_parser_strips_comments_spaces_and_case() {
    let mut g = grbl(SimConfig::default());
    assert_eq!(err(&mut g, "g1 x1 (comment) f600 ; tail"), "ok");
    assert_eq!(err(&mut g, "/G0 X0"), "ok");
    let tr = g.trace();
    assert_eq!(tr[0].text, "G1X1F600");
    assert_eq!(tr[1].text, "G0X0");
    // CR LF is two line ends: two `ok`s.
    g.receive_all(b"G4 P0\r\n");
    g.run_until_idle(1.0);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "ok\r\nok\r\n");
    assert_eq!(g.lines_received(), 4);
}

#[test]
fn settings_listing_and_store() {
    let mut g = grbl(SimConfig::default());
    let out = send(&mut g, "$$");
    let l = lines(&out);
    assert_eq!(l.len(), 35);
    assert_eq!(l[0], "$0=10");
    assert!(l.contains(&"$11=0.010"));
    assert!(l.contains(&"$30=1000"));
    assert!(l.contains(&"$110=500.000"));
    assert!(l.contains(&"$132=200.000"));
    assert_eq!(l[34], "ok");
    assert_eq!(err(&mut g, "$110=1000"), "ok");
    assert!(send(&mut g, "$$").contains("$110=1000.000\r\n"));
    assert_eq!(err(&mut g, "$999=1"), "error:3");
    assert_eq!(err(&mut g, "$103=1"), "error:3");
    assert_eq!(err(&mut g, "$11=-1"), "error:4");
}

#[test]
fn parser_state_and_offsets() {
    let mut g = grbl(SimConfig::default());
    assert_eq!(
        lines(&send(&mut g, "$G")),
        ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"]
    );
    send(&mut g, "G1 G91 X1 F250 M3 S300 M8 T2");
    assert_eq!(
        lines(&send(&mut g, "$G"))[0],
        "[GC:G1 G54 G17 G21 G91 G94 M3 M8 T2 F250 S300]"
    );
    assert_eq!(err(&mut g, "G10 L2 P1 X5 Y-3"), "ok");
    let l = lines(&send(&mut g, "$#"))
        .iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>();
    assert_eq!(l[0], "[G54:5.000,-3.000,0.000]");
    assert_eq!(l[6], "[G28:0.000,0.000,0.000]");
    assert_eq!(l[9], "[TLO:0.000]");
    assert_eq!(l.last().unwrap(), "ok");
    assert_eq!(lines(&send(&mut g, "$N")), ["$N0=", "$N1=", "ok"]);
    assert_eq!(
        lines(&send(&mut g, "$")),
        [
            "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]",
            "ok"
        ]
    );
}

#[test]
fn work_coordinates_and_wpos() {
    let mut g = grbl(
        SimConfig::default()
            .with_setting(10, 0.0)
            .with_instant_motion(true),
    );
    send(&mut g, "G0 X10 Y5");
    send(&mut g, "G92 X0 Y0");
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.starts_with("<Idle|WPos:0.000,0.000,0.000|"), "{s}");
    assert!(s.contains("WCO:10.000,5.000,0.000"), "{s}");
    send(&mut g, "G0 X1");
    assert_eq!(g.machine_position(), [11.0, 5.0, 0.0]);
    send(&mut g, "G20 G0 X1");
    assert!((g.machine_position()[0] - 35.4).abs() < 0.0041);
    send(&mut g, "G21 G53 G0 X0 Y0");
    assert_eq!(g.machine_position(), [0.0, 0.0, 0.0]);
}

#[test]
fn buffer_field_with_status_mask_3() {
    let mut g = grbl(SimConfig::default().with_setting(10, 3.0));
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(
        s.starts_with("<Idle|MPos:0.000,0.000,0.000|Bf:15,128|FS:0,0"),
        "{s}"
    );
}

#[test]
fn alarm_lock_with_homing_enabled() {
    let mut g = Grbl::new(&SimConfig::default().with_setting(22, 1.0));
    let out = String::from_utf8(g.take_output()).unwrap();
    assert_eq!(out, format!("{BANNER}[MSG:'$H'|'$X' to unlock]\r\n"));
    assert_eq!(g.state(), State::Alarm);
    assert_eq!(err(&mut g, "G0 X1"), "error:9");
    assert!(
        send(&mut g, "$$").ends_with("ok\r\n"),
        "settings are readable in alarm"
    );
    assert_eq!(
        lines(&send(&mut g, "$X")),
        ["[MSG:Caution: Unlocked]", "ok"]
    );
    assert_eq!(g.state(), State::Idle);
    // Homing: ends at -pull-off on every axis.
    assert_eq!(err(&mut g, "$H"), "ok");
    assert_eq!(g.state(), State::Idle);
    assert_eq!(g.machine_position(), [-1.0, -1.0, -1.0]);
}

#[test]
fn soft_limit_raises_alarm_2_and_locks_until_reset() {
    let mut g = Grbl::new(
        &SimConfig::default()
            .with_setting(22, 1.0)
            .with_setting(20, 1.0),
    );
    g.take_output();
    send(&mut g, "$X");
    assert_eq!(err(&mut g, "G0 X-10"), "ok");
    let out = send(&mut g, "G0 X10");
    assert_eq!(lines(&out), ["ALARM:2", "[MSG:Reset to continue]"]);
    assert_eq!(g.state(), State::Alarm);
    // Critical: no status report, no line processed until the reset.
    g.receive(b'?');
    assert!(send(&mut g, "G0 X-1").is_empty());
    g.receive(0x18);
    let out = String::from_utf8(g.take_output()).unwrap();
    assert_eq!(out, format!("ok\r\n{BANNER}[MSG:'$H'|'$X' to unlock]\r\n"));
    // Position kept at the last valid target.
    assert_eq!(g.machine_position(), [-10.0, 0.0, 0.0]);
    assert_eq!(err(&mut g, "G0 X-1"), "error:9");
}

#[test]
fn check_mode_parses_without_moving() {
    let mut g = grbl(SimConfig::default());
    assert_eq!(lines(&send(&mut g, "$C")), ["[MSG:Enabled]", "ok"]);
    assert_eq!(err(&mut g, "G1 X10 F100"), "ok");
    // The parser position follows the lines even though nothing moves.
    assert_eq!(err(&mut g, "G2 X10 R2"), "error:33");
    assert_eq!(err(&mut g, "G2 X0 R2"), "error:34");
    g.receive(b'?');
    assert!(
        String::from_utf8(g.take_output())
            .unwrap()
            .starts_with("<Check|MPos:0.000,0.000,0.000")
    );
    let out = send(&mut g, "$C");
    assert_eq!(out, format!("[MSG:Disabled]\r\nok\r\n{BANNER}"));
    assert_eq!(g.state(), State::Idle);
    assert!(g.trace().is_empty());
    // The reset restored the default modes.
    assert_eq!(
        lines(&send(&mut g, "$G"))[0],
        "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"
    );
}

#[test]
fn reset_during_motion_gives_alarm_3() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G1 X30 F500\n");
    g.tick(1.0);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "ok\r\n");
    g.receive(0x18);
    let out = String::from_utf8(g.take_output()).unwrap();
    assert_eq!(
        out,
        format!("ALARM:3\r\n{BANNER}[MSG:'$H'|'$X' to unlock]\r\n")
    );
    let x = g.machine_position()[0];
    assert!(x > 0.0 && x < 30.0, "{x}");
    assert_eq!(err(&mut g, "G1 X1"), "error:9");
    assert_eq!(
        lines(&send(&mut g, "$X")),
        ["[MSG:Caution: Unlocked]", "ok"]
    );
    // The trace holds the part that ran.
    assert_eq!(g.trace().len(), 1);
    assert_eq!(g.trace()[0].to[0], x);
}

#[test]
fn feed_hold_and_resume() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G1 X50 F300\n");
    g.tick(2.0);
    g.receive(b'!');
    g.take_output();
    g.tick(0.05);
    g.receive(b'?');
    assert!(
        String::from_utf8(g.take_output())
            .unwrap()
            .starts_with("<Hold:1|")
    );
    g.tick(2.0);
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.starts_with("<Hold:0|"), "{s}");
    assert!(s.contains("FS:0,0"), "{s}");
    let x = g.machine_position()[0];
    g.tick(5.0);
    assert_eq!(g.machine_position()[0], x, "no motion in hold");
    g.receive(b'~');
    g.run_until_idle(60.0);
    assert_eq!(g.state(), State::Idle);
    assert_eq!(g.machine_position()[0], 50.0);
}

#[test]
fn m0_holds_its_ok_until_cycle_start() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G1 X2 F600\nM0\nG1 X0\n");
    g.run_until_idle(30.0);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "ok\r\n");
    g.receive(b'?');
    assert!(
        String::from_utf8(g.take_output())
            .unwrap()
            .starts_with("<Hold:0|MPos:2.000")
    );
    g.receive(b'~');
    g.run_until_idle(30.0);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "ok\r\nok\r\n");
    assert_eq!(g.machine_position()[0], 0.0);
}

#[test]
fn program_end_resets_modes() {
    let mut g = grbl(SimConfig::default().with_instant_motion(true));
    send(&mut g, "G91 G1 X1 F100 M3 S100");
    g.receive(0x91);
    g.receive(0x96);
    assert_eq!(lines(&send(&mut g, "M2")), ["[MSG:Pgm End]", "ok"]);
    g.receive(b'?');
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.contains("|Ov:100,100,100"), "overrides restored: {s}");
    assert_eq!(
        lines(&send(&mut g, "$G"))[0],
        "[GC:G1 G54 G17 G21 G90 G94 M5 M9 T0 F100 S100]"
    );
}

#[test]
fn jog_and_jog_cancel() {
    let mut g = grbl(SimConfig::default());
    assert_eq!(err(&mut g, "$J=X10"), "error:22");
    assert_eq!(err(&mut g, "$J=G1 X10 F100"), "error:16");
    g.receive_all(b"$J=G91 X20 F500\n");
    g.tick(1.0);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "ok\r\n");
    assert_eq!(g.state(), State::Jog);
    g.receive_all(b"G0 X0\n");
    g.tick(0.01);
    assert_eq!(String::from_utf8(g.take_output()).unwrap(), "error:9\r\n");
    g.receive(0x85);
    g.run_until_idle(10.0);
    assert_eq!(g.state(), State::Idle);
    let x = g.machine_position()[0];
    assert!(x > 0.0 && x < 20.0, "{x}");
    // Jogging keeps the parser modes (G90 still).
    assert_eq!(
        lines(&send(&mut g, "$G"))[0],
        "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"
    );
}

#[test]
fn dollar_commands_need_idle() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G1 X30 F500\n");
    g.run_until_idle(60.0);
    assert_eq!(err(&mut g, "$$"), "ok");
    g.receive_all(b"G1 X0 F500\n$$\n$C\n$10=2\n");
    g.tick(0.2);
    assert_eq!(
        String::from_utf8(g.take_output()).unwrap(),
        "ok\r\nerror:8\r\nerror:8\r\nerror:8\r\n"
    );
}

#[test]
fn safety_door_stops_and_resumes_after_spin_up() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"M3 S500\nG1 X40 F300\n");
    g.tick(3.0);
    g.take_output();
    g.receive(0x84);
    assert_eq!(
        String::from_utf8(g.take_output()).unwrap(),
        "[MSG:Check Door]\r\n"
    );
    g.receive(b'?');
    assert!(
        String::from_utf8(g.take_output())
            .unwrap()
            .starts_with("<Door:2|")
    );
    g.tick(1.0);
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.starts_with("<Door:0|") && s.contains("FS:0,0"), "{s}");
    let x = g.machine_position()[0];
    g.receive(b'~');
    g.tick(2.0);
    g.receive(b'?');
    assert!(
        String::from_utf8(g.take_output())
            .unwrap()
            .starts_with("<Door:3|")
    );
    assert_eq!(
        g.machine_position()[0],
        x,
        "no motion while the spindle spins up"
    );
    g.tick(2.5);
    assert_eq!(g.state(), State::Cycle);
    g.run_until_idle(60.0);
    assert_eq!(g.machine_position()[0], 40.0);
}

#[test]
fn startup_lines_sleep_and_restore() {
    let mut g = grbl(SimConfig::default());
    assert_eq!(err(&mut g, "$N0=G20G91"), "ok");
    assert_eq!(lines(&send(&mut g, "$N")), ["$N0=G20G91", "$N1=", "ok"]);
    g.receive(0x18);
    let out = String::from_utf8(g.take_output()).unwrap();
    assert_eq!(out, format!("{BANNER}>G20G91:ok\r\n"));
    assert_eq!(
        lines(&send(&mut g, "$G"))[0],
        "[GC:G0 G54 G17 G20 G91 G94 M5 M9 T0 F0 S0]"
    );
    // GRBL checks the feed before it notices that G1 has no axis words.
    assert_eq!(err(&mut g, "$N0=G1"), "error:22");
    assert_eq!(err(&mut g, "$N0=G21"), "ok");
    assert_eq!(err(&mut g, "$N1=G1 X1"), "error:22");
    assert_eq!(err(&mut g, "$110=600"), "ok");
    // Restoring resets the controller: banner again, and the startup lines (kept by `$RST=$`) run.
    assert_eq!(
        lines(&send(&mut g, "$RST=$")),
        ["[MSG:Restoring defaults]", "ok", BANNER.trim(), ">G21:ok"]
    );
    assert!(send(&mut g, "$$").contains("$110=500.000\r\n"));
    assert_eq!(lines(&send(&mut g, "$SLP")), ["ok", "[MSG:Sleeping]"]);
    assert_eq!(g.state(), State::Sleep);
    assert!(send(&mut g, "G0 X1").is_empty(), "asleep until reset");
    g.receive(0x18);
    assert!(
        String::from_utf8(g.take_output())
            .unwrap()
            .ends_with("[MSG:'$H'|'$X' to unlock]\r\n")
    );
}

#[test]
fn home_positions_offsets_and_tool_length() {
    let mut g = grbl(SimConfig::default().with_instant_motion(true));
    send(&mut g, "G0 X5 Y6 Z-1");
    assert_eq!(err(&mut g, "G28.1"), "ok");
    send(&mut g, "G0 X0 Y0 Z0");
    assert_eq!(err(&mut g, "G28 X2"), "ok");
    let tr = g.trace();
    let n = tr.len();
    assert_eq!(
        (tr[n - 2].motion.as_str(), tr[n - 2].to),
        ("G28", [2.0, 0.0, 0.0])
    );
    assert_eq!(
        (tr[n - 1].motion.as_str(), tr[n - 1].to),
        ("G28", [5.0, 6.0, -1.0])
    );
    // G10 L20: make the current point X=1 in G55.
    assert_eq!(err(&mut g, "G10 L20 P2 X1"), "ok");
    assert!(send(&mut g, "$#").contains("[G55:4.000,0.000,0.000]"));
    send(&mut g, "G55 G0 X0");
    assert_eq!(g.machine_position()[0], 4.0);
    // Dynamic tool length offset shifts Z.
    assert_eq!(err(&mut g, "G43.1 Z2"), "ok");
    send(&mut g, "G0 Z0");
    assert_eq!(g.machine_position()[2], 2.0);
    assert!(send(&mut g, "$#").contains("[TLO:2.000]"));
    send(&mut g, "G49");
    // G18 arc in the ZX plane.
    send(&mut g, "G54 G0 X0 Y0 Z0");
    assert_eq!(err(&mut g, "G18 G2 X10 Z0 I5 K0 F500"), "ok");
    assert_eq!(g.trace().last().unwrap().arc_center, Some([5.0, 0.0, 0.0]));
}

#[test]
fn inverse_time_feed_and_probe_without_contact() {
    let mut g = grbl(SimConfig::default());
    // G93 F6: the move takes 1/6 min = 10 s.
    assert_eq!(err(&mut g, "G93 G1 X40 F6"), "ok");
    let seg = g.trace().last().unwrap().clone();
    assert!((seg.t_end - seg.t_start - 10.0).abs() < 0.7, "{seg:?}");
    assert_eq!(
        err(&mut g, "G1 X0"),
        "error:22",
        "G93 needs F on every move"
    );
    let mut g = grbl(SimConfig::default().with_instant_motion(true));
    let out = send(&mut g, "G38.2 Z-5 F100");
    assert_eq!(
        lines(&out),
        [
            "ok",
            "ALARM:5",
            "",
            "Grbl 1.1h ['$' for help]",
            "[MSG:'$H'|'$X' to unlock]"
        ]
        .iter()
        .filter(|l| !l.is_empty())
        .copied()
        .collect::<Vec<_>>()
    );
    send(&mut g, "$X");
    assert_eq!(
        lines(&send(&mut g, "G38.3 Z-6 F100")),
        ["[PRB:0.000,0.000,-6.000:0]", "ok"]
    );
}

#[test]
fn invalid_configurations_are_refused_with_a_reason() {
    use flatcut_firmware_sim::{ConfigError, Faults, PtySim};
    assert_eq!(SimConfig::default().validate(), Ok(()));
    assert_eq!(
        SimConfig::default().with_baud(0).validate(),
        Err(ConfigError::Baud(0))
    );
    assert!(matches!(
        SimConfig::default().with_time_scale(f64::NAN).validate(),
        Err(ConfigError::TimeScale(_))
    ));
    let bad = SimConfig::default().with_faults(Faults {
        drop_rate: 1.5,
        ..Faults::default()
    });
    assert!(matches!(
        bad.validate(),
        Err(ConfigError::Probability {
            name: "drop_rate",
            ..
        })
    ));
    let e = SimConfig::default()
        .with_setting(0, 1.0)
        .validate()
        .unwrap_err();
    assert_eq!(
        e,
        ConfigError::Setting {
            n: 0,
            value: 1.0,
            code: 6
        }
    );
    assert_eq!(
        e.to_string(),
        "sim config: setting $0=1 refused with error:6"
    );
    // Soft limits in the start settings switch homing on, so they are accepted.
    assert_eq!(
        SimConfig::default().with_setting(20, 1.0).validate(),
        Ok(())
    );
    let err = PtySim::spawn(SimConfig::default().with_setting(999, 1.0)).unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
    assert!(err.to_string().contains("$999=1"), "{err}");
}

#[test]
fn status_spindle_speed_and_inch_reports() {
    let mut g = grbl(SimConfig::default().with_instant_motion(true));
    send(&mut g, "M3 S800");
    g.receive(0x9a); // spindle +10 %
    g.receive(0x9a);
    g.receive(0x9a); // 130 % of 800 = 1040, clamped to $30 = 1000
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.contains("|FS:0,1000|"), "{s}");
    g.receive(0x99);
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.contains("|FS:0,800"), "{s}");
    assert_eq!(err(&mut g, "$13=1"), "ok");
    send(&mut g, "G0 X25.4 Y-12.7");
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.starts_with("<Idle|MPos:1.0000,-0.5000,0.0000|"), "{s}");
}

/// GRBL 1.1h (`gcode.c`, `gc_init`): program end (M2/M30) returns to G54 but keeps the G92
/// offset and the tool length offset; a soft reset clears G92 and the tool length offset and
/// returns to G54; the stored G54..G59 offsets survive both.
#[test]
fn g92_survives_program_end_but_not_a_soft_reset() {
    let mut g = grbl(SimConfig::default().with_instant_motion(true));
    send(&mut g, "G10 L2 P2 X50 Y20");
    send(&mut g, "G55 G0 X10 Y0");
    send(&mut g, "G92 X0 Y0");
    send(&mut g, "G43.1 Z2");
    let ngc = |g: &mut Grbl| send(g, "$#");
    let before = ngc(&mut g);
    assert!(before.contains("[G92:10.000,0.000,0.000]"), "{before}");
    assert!(before.contains("[TLO:2.000]"), "{before}");
    assert!(lines(&send(&mut g, "$G"))[0].contains(" G55 "));
    send(&mut g, "M2");
    let after_end = ngc(&mut g);
    assert!(
        after_end.contains("[G92:10.000,0.000,0.000]"),
        "{after_end}"
    );
    assert!(after_end.contains("[TLO:2.000]"), "{after_end}");
    assert!(lines(&send(&mut g, "$G"))[0].contains(" G54 "));
    g.receive(0x18);
    g.run_until_idle(1.0);
    g.take_output();
    let after_reset = ngc(&mut g);
    assert!(
        after_reset.contains("[G92:0.000,0.000,0.000]"),
        "{after_reset}"
    );
    assert!(after_reset.contains("[TLO:0.000]"), "{after_reset}");
    assert!(
        after_reset.contains("[G55:50.000,20.000,0.000]"),
        "{after_reset}"
    );
    assert!(lines(&send(&mut g, "$G"))[0].contains(" G54 "));
}
