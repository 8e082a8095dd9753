//! Motion: trapezoid timing against closed forms, junction deviation, arcs within `$12` of the circle, the trace
//! of a known program against its geometry, laser-mode semantics and overrides.

use flatcut_firmware_sim::{Grbl, SimConfig, State, TraceSegment, trace_svg};

fn grbl(config: SimConfig) -> Grbl {
    let mut g = Grbl::new(&config);
    g.take_output();
    g
}

/// Streams a program with simple send-response and runs it to the end; returns all output.
fn run_program(g: &mut Grbl, program: &str) -> String {
    let mut out = String::new();
    for line in program.lines() {
        g.receive_all(line.as_bytes());
        g.receive(b'\n');
        let mut guard = 0;
        loop {
            g.tick(0.01);
            let o = String::from_utf8(g.take_output()).unwrap();
            let done = o.contains("ok\r\n") || o.contains("error:");
            out.push_str(&o);
            if done {
                break;
            }
            guard += 1;
            assert!(
                guard < 100_000,
                "no answer to {line:?}; output so far {out:?}"
            );
        }
    }
    g.run_until_idle(1000.0);
    out.push_str(&String::from_utf8(g.take_output()).unwrap());
    out
}

fn duration(tr: &[TraceSegment]) -> f64 {
    tr.last().unwrap().t_end - tr.first().unwrap().t_start
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

/// One step of the default 250 steps/mm.
const STEP: f64 = 0.004;

#[test]
fn trapezoid_time_matches_closed_form() {
    // 100 mm at 5 mm/s with 10 mm/s²: 0.5 s up, 0.5 s down, 97.5 mm cruise: 20.5 s.
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "G1 X100 F300");
    let t = duration(g.trace());
    assert!((t - 20.5).abs() < 0.01, "{t}");
    // Rapid is capped by $110 = 500 mm/min on X: 8.333 mm/s.
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "G0 X100");
    let v: f64 = 500.0 / 60.0;
    let want = 100.0 / v + v / 10.0;
    assert!((duration(g.trace()) - want).abs() < 0.01);
    // A diagonal rapid is limited per axis: both axes at 8.333 mm/s, so 11.785 mm/s along the move.
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "G0 X100 Y100");
    let (len, v, a) = (100.0 * 2f64.sqrt(), v * 2f64.sqrt(), 10.0 * 2f64.sqrt());
    let want = len / v + v / a;
    assert!(
        (duration(g.trace()) - want).abs() < 0.01,
        "{} vs {want}",
        duration(g.trace())
    );
}

#[test]
fn look_ahead_straight_junction_does_not_stop_and_reversal_does() {
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "G1 X5 F300\nG1 X10");
    assert!(
        (duration(g.trace()) - 2.5).abs() < 0.01,
        "{}",
        duration(g.trace())
    );
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "G1 X10 F300\nG1 X0");
    assert!((duration(g.trace()) - 5.0).abs() < 0.01);
}

#[test]
fn right_angle_junction_speed_follows_junction_deviation() {
    // v_j² = a_j δ sin(θ/2) / (1 − sin(θ/2)), a_j = 10/cos 45°, δ = 0.01 mm, θ/2 = 45°.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let vj2 = (10.0 / s) * 0.01 * s / (1.0 - s);
    let leg = 0.5 + (5.0 - vj2.sqrt()) / 10.0 + (10.0 - 1.25 - (25.0 - vj2) / 20.0) / 5.0;
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "G1 X10 F300\nG1 Y10");
    let t = duration(g.trace());
    assert!((t - 2.0 * leg).abs() < 0.01, "{t} vs {}", 2.0 * leg);
    assert!(t < 4.95, "the corner is not a full stop");
}

#[test]
fn arcs_stay_within_arc_tolerance() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G0 X-20 Y-20\nG2 X-20 Y-20 I10 J0 F400\n");
    let mut max_dev: f64 = 0.0;
    let mut on_arc = false;
    for _ in 0..200_000 {
        g.tick(0.002);
        let p = g.machine_position();
        if g.trace().len() == 1 && g.state() == State::Cycle {
            on_arc = true;
            let r = ((p[0] + 10.0).powi(2) + (p[1] + 20.0).powi(2)).sqrt();
            max_dev = max_dev.max((r - 10.0).abs());
        }
        if g.trace().len() == 2 {
            break;
        }
    }
    assert!(on_arc);
    assert_eq!(g.trace().len(), 2);
    // Chords lie inside the circle by at most $12 = 0.002 mm, plus step rounding.
    assert!(max_dev <= 0.002 + STEP, "{max_dev}");
    let arc = &g.trace()[1];
    assert_eq!(arc.motion, "G2");
    assert_eq!(arc.arc_center, Some([-10.0, -20.0, 0.0]));
    // A full circle of radius 10 at 400 mm/min (6.667 mm/s) with the centripetal limits of the chords.
    let t = arc.t_end - arc.t_start;
    let ideal = 2.0 * std::f64::consts::PI * 10.0 / (400.0 / 60.0);
    assert!(t > ideal && t < ideal * 1.2, "{t} vs {ideal}");
}

#[test]
fn known_program_trace_equals_its_geometry() {
    let program = "\
G21 G90 G17
M4 S600
G0 X10 Y10
G1 X40 Y10 F1200
G1 X40 Y30
G3 X20 Y30 R10
G2 X10 Y20 I0 J-10
G1 X10 Y10 S300
G0 X0 Y0
M5
G91 G0 X5
G90 G2 X5 Y0 I5 J0 F600";
    let mut g = grbl(
        SimConfig::default()
            .with_setting(32, 1.0)
            .with_setting(110, 6000.0)
            .with_setting(111, 6000.0),
    );
    let out = run_program(&mut g, program);
    assert_eq!(out.matches("ok\r\n").count(), 12, "{out}");
    let tr = g.trace();
    let expect: &[(&str, [f64; 3], [f64; 3], Option<[f64; 3]>, bool, f64)] = &[
        ("G0", [0.0, 0.0, 0.0], [10.0, 10.0, 0.0], None, false, 0.0),
        (
            "G1",
            [10.0, 10.0, 0.0],
            [40.0, 10.0, 0.0],
            None,
            true,
            600.0,
        ),
        (
            "G1",
            [40.0, 10.0, 0.0],
            [40.0, 30.0, 0.0],
            None,
            true,
            600.0,
        ),
        (
            "G3",
            [40.0, 30.0, 0.0],
            [20.0, 30.0, 0.0],
            Some([30.0, 30.0, 0.0]),
            true,
            600.0,
        ),
        (
            "G2",
            [20.0, 30.0, 0.0],
            [10.0, 20.0, 0.0],
            Some([20.0, 20.0, 0.0]),
            true,
            600.0,
        ),
        (
            "G1",
            [10.0, 20.0, 0.0],
            [10.0, 10.0, 0.0],
            None,
            true,
            300.0,
        ),
        ("G0", [10.0, 10.0, 0.0], [0.0, 0.0, 0.0], None, false, 0.0),
        ("G0", [0.0, 0.0, 0.0], [5.0, 0.0, 0.0], None, false, 0.0),
        (
            "G2",
            [5.0, 0.0, 0.0],
            [5.0, 0.0, 0.0],
            Some([10.0, 0.0, 0.0]),
            false,
            0.0,
        ),
    ];
    assert_eq!(tr.len(), expect.len(), "{tr:#?}");
    for (i, (seg, e)) in tr.iter().zip(expect).enumerate() {
        assert_eq!(seg.motion, e.0, "segment {i}");
        assert!(
            close(seg.from, e.1, 1e-9),
            "segment {i} from {:?}",
            seg.from
        );
        assert!(close(seg.to, e.2, 1e-9), "segment {i} to {:?}", seg.to);
        match (seg.arc_center, e.3) {
            (Some(c), Some(w)) => assert!(close(c, w, 1e-9), "segment {i} centre {c:?}"),
            (None, None) => {}
            other => panic!("segment {i} centre {other:?}"),
        }
        assert_eq!(seg.tool_on, e.4, "segment {i} tool");
        assert_eq!(seg.power, e.5, "segment {i} power");
        assert!(seg.t_end > seg.t_start);
        if i > 0 {
            assert!(
                seg.t_start >= tr[i - 1].t_end - 1e-9,
                "segment {i} starts before the previous ended"
            );
            assert!(
                close(seg.from, tr[i - 1].to, 1e-9),
                "segment {i} is not continuous"
            );
        }
    }
    assert_eq!(tr[3].text, "G3X20Y30R10");
    assert_eq!(tr[3].line, 6);
    assert_eq!(tr[1].feed, 1200.0);
    // The SVG draws the burned path solid and travel dashed.
    let svg = trace_svg(tr);
    assert_eq!(svg.matches(r##"stroke="#000""##).count(), 5);
    assert_eq!(svg.matches("stroke-dasharray").count(), 4);
    // JSON lines round trip.
    for seg in tr {
        let j = serde_json::to_string(seg).unwrap();
        let mut back: TraceSegment = serde_json::from_str(&j).unwrap();
        // serde_json's default float parser may differ in the last bit.
        assert!(
            (back.t_end - seg.t_end).abs() < 1e-12 && (back.t_start - seg.t_start).abs() < 1e-12
        );
        (back.t_start, back.t_end) = (seg.t_start, seg.t_end);
        assert_eq!(&back, seg);
    }
}

#[test]
fn laser_mode_s_changes_do_not_stop_but_spindle_mode_does() {
    let laser = SimConfig::default().with_setting(32, 1.0);
    let mut g = grbl(laser);
    run_program(&mut g, "M4 S500\nG1 X5 F300 S800\nG1 X10 S300");
    assert!(
        (duration(g.trace()) - 2.5).abs() < 0.01,
        "{}",
        duration(g.trace())
    );
    assert_eq!(g.trace()[0].power, 800.0);
    assert_eq!(g.trace()[1].power, 300.0);
    assert_eq!(g.stats().planner_starvations, 1);
    // Without laser mode an S change is a planner sync: the machine stops between the moves.
    let mut g = grbl(SimConfig::default());
    run_program(&mut g, "M3 S500\nG1 X5 F300 S800\nG1 X10 S300");
    let tr = g.trace();
    assert!(duration(tr) >= 2.0 * (1.0 + 0.5) - 0.01, "{}", duration(tr));
    assert_eq!(g.stats().planner_starvations, 2);
    // Laser mode: G0 never burns, and the status report keeps the S value.
    let mut g = grbl(SimConfig::default().with_setting(32, 1.0));
    run_program(&mut g, "M3 S1000\nG0 X5");
    assert!(!g.trace()[0].tool_on);
    assert_eq!(g.trace()[0].power, 0.0);
}

#[test]
fn pen_plotter_tool_state_follows_z() {
    let mut g = grbl(SimConfig::default().with_instant_motion(true));
    run_program(&mut g, "G0 X5\nG1 Z-1 F300\nG1 X10\nG0 Z2\nG0 X0");
    let on: Vec<bool> = g.trace().iter().map(|s| s.tool_on).collect();
    assert_eq!(on, [false, false, true, false, false]);
}

#[test]
fn feed_and_rapid_overrides() {
    let mut g = grbl(SimConfig::default());
    for _ in 0..12 {
        g.receive(0x91); // +10 % each, capped at 200 %
    }
    // The first report after a reset carries WCO and defers Ov to the next one, as GRBL does.
    g.receive(b'?');
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.contains("|Ov:200,100,100"), "{s}");
    run_program(&mut g, "G1 X100 F150");
    // 2.5 mm/s programmed, 5 mm/s executed.
    assert!((duration(g.trace()) - 20.5).abs() < 0.01);
    let mut g = grbl(SimConfig::default());
    g.receive(0x97); // rapid 25 %
    run_program(&mut g, "G0 X10");
    let v: f64 = 500.0 / 60.0 * 0.25;
    assert!((duration(g.trace()) - (10.0 / v + v / 10.0)).abs() < 0.01);
}

#[test]
fn dwell_waits_in_simulated_time() {
    let mut g = grbl(SimConfig::default());
    g.receive_all(b"G4 P1.5\n");
    g.tick(1.4);
    assert!(g.take_output().is_empty());
    g.tick(0.2);
    assert_eq!(g.take_output(), b"ok\r\n");
}

#[test]
fn planner_fill_blocks_parsing_and_ok() {
    let mut g = grbl(SimConfig::default().with_setting(10, 3.0));
    let mut program = String::new();
    for i in 0..20 {
        program.push_str(&format!("G1 X{} F300\n", if i % 2 == 0 { 1 } else { 0 }));
    }
    g.receive_all(&program.as_bytes()[..120]);
    g.tick(0.001);
    let oks = String::from_utf8(g.take_output())
        .unwrap()
        .matches("ok")
        .count();
    // 120 bytes hold 10 complete lines: all planned at once.
    assert_eq!(oks, 10);
    g.receive_all(&program.as_bytes()[120..]);
    g.tick(0.001);
    let oks = String::from_utf8(g.take_output())
        .unwrap()
        .matches("ok")
        .count();
    assert_eq!(oks, 5, "15 blocks fill the planner; the 16th line waits");
    assert_eq!(g.planner_len(), 15);
    g.receive(b'?');
    let s = String::from_utf8(g.take_output()).unwrap();
    assert!(s.contains("|Bf:0,"), "{s}");
    g.run_until_idle(100.0);
    assert_eq!(
        String::from_utf8(g.take_output())
            .unwrap()
            .matches("ok")
            .count(),
        5
    );
}

/// `$1`: when the steppers stop, `st_go_idle` holds them `$1` ms inside the stepper interrupt, so
/// the controller reports Run that long after the motion ended and only then Idle; `$1=255`
/// keeps them enabled and does not wait. A dwell lasts whole 50 ms steps (`delay_sec`).
#[test]
fn step_idle_delay_holds_the_cycle_after_every_stop() {
    let idle_after = |cfg: SimConfig, program: &[u8]| {
        let mut g = grbl(cfg);
        g.receive_all(program);
        let mut moved_until = None;
        while g.clock() < 60.0 {
            g.tick(0.001);
            if moved_until.is_none() && g.trace().len() == 1 {
                moved_until = Some(g.trace()[0].t_end);
            }
            if g.state() == State::Idle && g.is_quiescent() {
                break;
            }
        }
        (g.clock(), moved_until.unwrap())
    };
    let (idle, moved) = idle_after(SimConfig::default(), b"G1 X10 F600\n");
    assert!((idle - moved - 0.025).abs() < 0.0015, "{idle} {moved}");
    let (idle, moved) = idle_after(
        SimConfig::default().with_setting(1, 255.0),
        b"G1 X10 F600\n",
    );
    assert!(idle - moved < 0.0015, "{idle} {moved}");
    // The delay comes before a dwell starts; P0.01 waits one 50 ms step.
    let (idle, moved) = idle_after(SimConfig::default(), b"G1 X10 F600\nG4 P0.01\n");
    assert!((idle - moved - 0.075).abs() < 0.0015, "{idle} {moved}");
}

/// GRBL 1.1h runs an inverse-time arc's chords at F × segments mm/min (`mc_arc` multiplies the
/// feed and clears the inverse-time flag), not in 1/F minutes.
#[test]
fn inverse_time_arc_runs_at_f_times_segments() {
    let mut g = grbl(SimConfig::default().with_setting(1, 255.0));
    // Quarter circle r = 10 at $12 = 0.002: 39 chords, so F2 runs at 78 mm/min = 1.3 mm/s.
    run_program(&mut g, "G0 X10\nG93 G3 X0 Y10 I-10 J0 F2");
    let seg = g.trace().last().unwrap().clone();
    let len = 39.0 * 20.0 * (std::f64::consts::FRAC_PI_4 / 39.0).sin();
    // Cruise plus the ramps up and down (v/a); in 1/F minutes it would have taken 30 s.
    let want = len / 1.3 + 1.3 / 10.0;
    let t = seg.t_end - seg.t_start;
    assert!((t - want).abs() < 0.1, "{t} vs {want}");
}
