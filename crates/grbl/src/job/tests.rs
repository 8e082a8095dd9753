//! Tests of job preparation: stripping, modal state, arcs, times, resume preambles, limits.

use super::*;
use approx::assert_relative_eq;
use flatcut_motion::{Limits, trapezoid_time};
use std::collections::BTreeMap;

#[test]
fn stripping_follows_grbl_preparser() {
    assert_eq!(strip_line("g1 x10 (move) y2.5 ; tail"), "G1X10Y2.5");
    assert_eq!(strip_line("%"), "");
    assert_eq!(strip_line("/G1 X1\t\r"), "G1X1");
    assert_eq!(strip_line("(only a comment)"), "");
}

#[test]
fn rejects_what_grbl_would_reject() {
    let long = format!("G1X{}", "1".repeat(80));
    assert!(matches!(
        Job::parse(&long),
        Err(JobError::LineTooLong { line: 1, .. })
    ));
    let ok79 = format!("G1X{}", "1".repeat(76));
    assert_eq!(ok79.len(), 79);
    assert!(Job::parse(&format!("G21\n{ok79}")).is_ok());
    assert!(matches!(
        Job::parse("G0X1\nT1 M6\n"),
        Err(JobError::ToolChange { line: 2, .. })
    ));
    assert!(matches!(
        Job::parse("G1 X1..2"),
        Err(JobError::BadNumber { letter: 'X', .. })
    ));
    assert!(matches!(Job::parse("%\n(nothing)\n"), Err(JobError::Empty)));
}

#[test]
fn modal_state_units_distance_and_feed() {
    let job =
        Job::parse("G20 G91\nG1 X1 F10\nX1 Y1\nG21 G90 M3 S500\nG0 Z5\n$32=1\nG10 L20 P1 X0\n")
            .unwrap();
    let l = &job.lines;
    assert_eq!(l[2].before.units, Units::Inch);
    assert!(l[2].before.incremental);
    assert_relative_eq!(l[2].before.feed, 254.0);
    assert_relative_eq!(l[2].before.position[0], 25.4);
    assert_relative_eq!(l[3].before.position[0], 50.8);
    assert_relative_eq!(l[3].before.position[1], 25.4);
    assert_relative_eq!(l[1].length, 25.4);
    assert_relative_eq!(l[2].length, 25.4 * 2f64.sqrt(), epsilon = 1e-12);
    assert_eq!(l[4].before.spindle, Spindle::Cw);
    assert_eq!(l[5].kind, LineKind::EepromWrite);
    assert_eq!(l[6].kind, LineKind::EepromWrite);
    assert_eq!(job.safe_z, Some(5.0));
    assert!(!l[1].tool_on && !l[4].tool_on);
}

#[test]
fn arc_length_and_extent() {
    // Quarter circle of radius 10 about the origin, CCW from (10,0) to (0,10).
    let job = Job::parse("G0X10Y0\nG3X0Y10I-10J0F600\n").unwrap();
    // `mc_arc`'s 39 chords (floor(½·π/2·10 / √(0.002·19.998))): 39 · 2r · sin(π/4 / 39).
    let chords = |n: f64, sweep: f64| n * 20.0 * (sweep / (2.0 * n)).sin();
    let exact = chords(39.0, std::f64::consts::FRAC_PI_2);
    assert!(
        (job.lines[1].length - exact).abs() < 1e-4,
        "{} vs {exact}",
        job.lines[1].length
    );
    let (lo, hi) = job.extent.unwrap();
    assert_relative_eq!(lo[0], 0.0, epsilon = 1e-9);
    assert!(hi[0] >= 10.0 - 1e-9 && hi[1] >= 10.0 - 1e-9);
    // R form: same arc.
    let r = Job::parse("G0X10Y0\nG3X0Y10R10F600\n").unwrap();
    assert_relative_eq!(r.lines[1].length, job.lines[1].length, epsilon = 1e-9);
    // Full circle when start == end.
    let full = Job::parse("G0X10Y0\nG2X10Y0I-10J0F600\n").unwrap();
    let exact = chords(157.0, std::f64::consts::TAU);
    assert!(
        (full.lines[1].length - exact).abs() < 1e-4,
        "{} vs {exact}",
        full.lines[1].length
    );
}

#[test]
fn trapezoid_times_match_kinematics() {
    // 100 mm at 10 mm/s with 10 mm/s²: 1 s up (5 mm), 9 s cruise, 1 s down = 11 s.
    assert_relative_eq!(
        trapezoid_time(100.0, 0.0, 0.0, 10.0, 10.0),
        11.0,
        epsilon = 1e-12
    );
    // 4 mm never reaches 10 mm/s: triangle to sqrt(40) and back = 2·sqrt(40)/10.
    assert_relative_eq!(
        trapezoid_time(4.0, 0.0, 0.0, 10.0, 10.0),
        2.0 * 40f64.sqrt() / 10.0,
        epsilon = 1e-12
    );
    // Feeds are capped by $110-$112; lift the cap so F600 (10 mm/s) is what runs.
    // No step idle delay ($1) here: the stops are timed on their own below.
    let fast = MachineLimits {
        motion: Limits {
            max_rate: [6000.0; 3],
            step_idle_delay: 0.0,
            ..Limits::GRBL_DEFAULT
        },
        ..MachineLimits::DEFAULT
    };
    let parse = |t: &str| Job::parse_with(t, &fast).unwrap();
    // With the default 500 mm/min cap the same move runs at 8.33 mm/s, and its stop at the end
    // holds the steppers for the default $1 = 25 ms.
    assert_relative_eq!(
        Job::parse("G1X100F600").unwrap().total_time,
        trapezoid_time(100.0, 0.0, 0.0, 500.0 / 60.0, 10.0) + 0.025,
        epsilon = 1e-9
    );
    let one = parse("G1X100F600\n");
    assert_relative_eq!(one.total_time, 11.0, epsilon = 1e-9);
    // Collinear split: no stop at the junction.
    let two = parse("G1X50F600\nG1X100\n");
    assert_relative_eq!(two.total_time, 11.0, epsilon = 1e-9);
    // A reversal forces a full stop: two independent 50 mm moves.
    let rev = parse("G1X50F600\nG1X0\n");
    assert_relative_eq!(
        rev.total_time,
        2.0 * trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0),
        epsilon = 1e-9
    );
    // A dwell adds its seconds and a spindle change syncs the planner (laser mode off).
    let dw = parse("G1X50F600\nG4P1.5\nG1X100\n");
    assert_relative_eq!(
        dw.total_time,
        1.5 + 2.0 * trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0),
        epsilon = 1e-9
    );
    // A 90° corner: junction speed from the junction-deviation rule, with the acceleration
    // along the junction vector (-1, 1)/√2, which the 10 mm/s² axis limits allow at 10·√2
    // (`plan_buffer_line`: limit_value_by_axis_maximum on junction_unit_vec).
    let corner = parse("G1X50F600\nG1Y50\n");
    let sin_half = (0.5f64).sqrt();
    let ja = 10.0 * 2.0f64.sqrt();
    let vj = (ja * 0.01 * sin_half / (1.0 - sin_half)).sqrt();
    let expect = 2.0 * trapezoid_time(50.0, 0.0, vj, 10.0, 10.0);
    assert_relative_eq!(corner.total_time, expect, epsilon = 1e-9);
    // Rapids run at $110 (500 mm/min default): 60 mm → 7.2 s cruise plus ramps, plus $1.
    let g0 = Job::parse("G0X60\n").unwrap();
    assert_relative_eq!(
        g0.total_time,
        trapezoid_time(60.0, 0.0, 0.0, 500.0 / 60.0, 10.0) + 0.025,
        epsilon = 1e-9
    );
}

/// Absolute end points of every moving line from index `from` on.
fn endpoints(job: &Job, from_text: usize) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for (k, l) in job.lines.iter().enumerate().skip(from_text) {
        if l.moves {
            let after = job
                .lines
                .get(k + 1)
                .map(|n| &n.before)
                .unwrap_or(&job.end_state);
            let p = add(after.position, after.g92);
            out.push(p.map(|v| (v * 1e6).round() / 1e6));
        }
    }
    out
}

#[test]
fn resume_preamble_restores_state_at_every_line() {
    let src = "G21 G90\nG0 Z5\nG0 X10 Y10\nM3 S800\nG1 Z-1 F300\nG91\nG1 X5 F1200\nY5\nG90 G20\nG1 X1 Y1\nG2 X1.5 Y1.5 I0.25 J0.25\nX1 Y1 I-0.25 J-0.25\nG92 X0 Y0\nG1 X0.5\nG90 G21 M5\nG0 Z5\nG0 X0 Y0\n";
    let job = Job::parse(src).unwrap();
    for k in 1..job.len() {
        let pre = job.resume_preamble(k);
        assert!(
            pre.iter()
                .all(|l| l.len() <= MAX_LINE_CHARS && strip_line(l) == *l)
        );
        let mut text = pre.join("\n");
        text.push('\n');
        text.push_str(&job.resume_line(k));
        text.push('\n');
        for l in &job.lines[k + 1..] {
            text.push_str(&l.text);
            text.push('\n');
        }
        let resumed = Job::parse(&text).unwrap();
        let skip = pre.len();
        let st_orig = &job.lines[k].before;
        let st_new = &resumed.lines[skip].before;
        assert_eq!(st_new.units, st_orig.units, "resume at {k}");
        assert_eq!(st_new.incremental, st_orig.incremental, "resume at {k}");
        assert_eq!(st_new.spindle, st_orig.spindle, "resume at {k}");
        assert_relative_eq!(st_new.feed, st_orig.feed, epsilon = 1e-9);
        assert_relative_eq!(st_new.speed, st_orig.speed, epsilon = 1e-9);
        assert_eq!(
            endpoints(&resumed, skip),
            endpoints(&job, k),
            "resume at {k}"
        );
    }
}

#[test]
fn machine_limits_from_settings() {
    let mut s = BTreeMap::new();
    s.insert(110, 3000.0);
    s.insert(121, 50.0);
    s.insert(132, 30.0);
    s.insert(32, 1.0);
    s.insert(1, 100.0);
    let l = MachineLimits::from_settings(&s);
    assert_eq!(l.motion.step_idle_delay, 0.1);
    assert_eq!(l.motion.max_rate, [3000.0, 500.0, 500.0]);
    assert_eq!(l.motion.accel, [10.0, 50.0, 10.0]);
    assert_eq!(l.max_travel, [200.0, 200.0, 30.0]);
    assert!(l.laser_mode && !l.homing);
    let mut job = Job::parse("G0X60\n").unwrap();
    job.retime(&l);
    assert_relative_eq!(
        job.total_time,
        trapezoid_time(60.0, 0.0, 0.0, 50.0, 10.0) + 0.1,
        epsilon = 1e-9
    );
    // $1 = 255 keeps the motors enabled: no wait at a stop.
    s.insert(1, 255.0);
    assert_eq!(MachineLimits::from_settings(&s).motion.step_idle_delay, 0.0);
}

#[test]
fn hash_identifies_content() {
    assert_eq!(fnv1a64(b""), 0xcbf29ce484222325);
    assert_eq!(fnv1a64(b"a"), 0xaf63dc4c8601ec8c);
    assert_ne!(
        Job::parse("G0X1").unwrap().hash,
        Job::parse("G0X2").unwrap().hash
    );
    assert_eq!(fmt_num(-0.00001), "0");
    assert_eq!(fmt_num(12.5), "12.5");
    assert_eq!(fmt_num(3.0), "3");
}

/// Issue 14, item 5: a resume plunges at the job's own plunge feed, not its cutting feed, and
/// restores the cutting feed after.
#[test]
fn resume_plunges_at_the_jobs_plunge_feed() {
    let job = Job::parse(
        "G21 G90\nG0 Z3\nG0 X10 Y10\nG1 Z-1 F300\nG1 X20 F1500\nG1 Y20\nG0 Z3\nG0 X40\nG1 Z-1 F250\nG1 X50 F1500\n",
    )
    .unwrap();
    let at = |i: usize| job.resume_preamble(i);
    let plunge = |pre: &[String]| {
        pre.iter()
            .find(|l| l.starts_with("G1Z-1"))
            .cloned()
            .unwrap_or_default()
    };
    // Resuming at `G1 Y20`: the plunge before it was at F300.
    assert_eq!(plunge(&at(5)), "G1Z-1F300");
    assert_eq!(at(5).last().map(String::as_str), Some("G1"));
    assert!(at(5).iter().any(|l| l == "F1500"), "{:?}", at(5));
    // At `G1 X50`: the latest plunge, F250.
    assert_eq!(plunge(&at(9)), "G1Z-1F250");
    assert_eq!(job.plunge_feed(1), Some(300.0));
    assert_eq!(Job::parse("G1 X1 F100\n").unwrap().plunge_feed(0), None);
}

/// flatcut's laser header declares laser mode; nothing else does.
#[test]
fn a_laser_header_declares_laser_mode() {
    let laser = Job::parse("(profile laser - laser: needs $32=1)\nG21 G90\nM4 S0\nG1 X1 F600\n");
    assert!(laser.unwrap().needs_laser_mode);
    assert!(
        !Job::parse("G21 G90\nM3 S1000\nG1 X1 F600\n")
            .unwrap()
            .needs_laser_mode
    );
    let pause = Job::parse("G1 X1 F600\nM0\nM00\nM1\nG1 X2\n").unwrap();
    assert_eq!(
        (0..5).map(|i| pause.pauses(i)).collect::<Vec<_>>(),
        [false, true, true, false, false]
    );
}
