//! The sender against firmware-sim over a real pseudo-terminal: complete streaming, every
//! fault-injection mode, resume from the journal.

use flatcut_firmware_sim::{Faults, SimConfig, TraceSegment};
use flatcut_grbl::driver::Phase;
use flatcut_grbl::{CancelToken, Job, Journal, SendError, SendOptions, open_port, send_job};
use flatcut_testkit::jobs;
use flatcut_testkit::pty::{send as run, spawn};
use flatcut_testkit::trace::{
    assert_exactly_once, assert_exactly_once_except, assert_trace_is_job, close,
};
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Duration;

/// A pen-plotter job of `n` zig-zag strokes with unique line texts, X on the step grid.
fn zigzag(n: usize) -> String {
    jobs::zigzag(n, 0.012, 5.0, 3000.0)
}

fn opts() -> SendOptions {
    SendOptions::default()
        .with_banner_timeout(Duration::from_millis(500))
        .with_idle_ack_timeout(Duration::from_millis(1500))
        .with_silence_timeout(Duration::from_secs(5))
        .with_hold_timeout(Some(Duration::from_secs(2)))
}

#[test]
fn ten_thousand_lines_stream_completely_in_order() {
    let job = Job::parse(&zigzag(10_000)).unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_baud(230_400)
            .with_instant_motion(true),
    );
    let mut phases = Vec::new();
    let mut port = open_port(sim.path().to_str().unwrap(), 230_400).unwrap();
    let rep = send_job(
        &mut port,
        &job,
        &opts(),
        &mut |p| {
            if phases.last() != Some(&p.phase) {
                phases.push(p.phase);
            }
        },
        &CancelToken::new(),
    )
    .unwrap();
    drop(port);
    let report = sim.stop();
    assert_trace_is_job(&job, &report.trace);
    assert_eq!(report.stats.bytes_dropped_overflow, 0);
    assert!(report.stats.max_rx_fill <= 128);
    assert_eq!(report.stats.errors, 0);
    assert_eq!(rep.lines_sent, job.len());
    assert_eq!(phases.first(), Some(&Phase::Connecting));
    assert_eq!(phases.last(), Some(&Phase::Done));
}

/// Asserts that one of the report's notices satisfies `f`.
fn assert_notice(rep: &flatcut_grbl::SendReport, f: impl Fn(&str) -> bool) {
    assert!(rep.notices.iter().any(|n| f(n)), "{:?}", rep.notices);
}

fn fault_case(
    name: &str,
    n: usize,
    faults: Faults,
    check: impl FnOnce(&Result<flatcut_grbl::SendReport, SendError>),
) {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join(format!("{name}.journal"));
    let job = Job::parse(&zigzag(n)).unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_faults(faults),
    );
    let first = run(&sim, &job, &opts().with_journal(&jp));
    check(&first);
    let r1 = sim.stop();
    match first {
        Ok(_) => assert_trace_is_job(&job, &r1.trace),
        Err(e) => {
            // A clear message, and a journal that lets --resume finish the job.
            assert!(!e.to_string().is_empty());
            let st = Journal::read(&jp).unwrap();
            if std::env::var("SIM_DEBUG").is_ok() {
                eprintln!("{name}: {e}");
                let txt = std::fs::read_to_string(&jp).unwrap();
                let lines: Vec<&str> = txt.lines().collect();
                eprintln!(
                    "journal tail: {:?}",
                    &lines[lines.len().saturating_sub(40)..]
                );
                let t: Vec<(u32, &str)> =
                    r1.trace.iter().map(|s| (s.line, s.text.as_str())).collect();
                eprintln!("trace tail: {:?}", &t[t.len().saturating_sub(8)..]);
            }
            assert!(!st.finished, "{name}: journal says finished after {e}");
            let sim2 = spawn(SimConfig::default().with_instant_motion(true));
            // A fresh controller restarted (power-up banner): the operator confirms the origin.
            let o2 = opts()
                .with_journal(&jp)
                .with_resume(true)
                .with_origin_confirmed(true);
            let resumed = run(&sim2, &job, &o2);
            // A fresh controller (power-up banner, position zero) cannot say which queued lines
            // ran: the sender refuses to guess and names the lines in doubt; resuming from the
            // first of them is the operator's safe choice.
            let (rep, from) = match resumed {
                Err(SendError::ResumeUncertain { from, to, reason }) => {
                    // Only lines the first run could not locate are in doubt: those of a
                    // hang-up, and of any stop whose status query went unanswered (a loaded
                    // host, a damaged reply).
                    assert!(!st.unconfirmed.is_empty(), "{name}: {reason}");
                    assert_eq!(Some(from.index), st.unconfirmed.first().copied());
                    assert!(to.index >= from.index);
                    let o = o2.clone().with_resume_from(Some(from.index));
                    let rep = run(&sim2, &job, &o).unwrap_or_else(|e2| {
                        panic!("{name}: resume from {} failed: {e2}", from.index)
                    });
                    (rep, Some(from.index))
                }
                r => (
                    r.unwrap_or_else(|e2| panic!("{name}: resume after `{e}` failed: {e2}")),
                    None,
                ),
            };
            match from {
                Some(k) => assert_eq!(rep.previously_done, k),
                None => assert_eq!(rep.previously_done, st.done_count()),
            }
            let r2 = sim2.stop();
            if name == "hangup" || from.is_some() {
                // The hang-up (or a stop whose status query went unanswered) loses the `ok`s in
                // flight: lines the journal could not confirm may run again, but none is
                // skipped (beyond one per damaged byte, which no sender can see) and none
                // journaled as done re-runs.
                let damaged = (r1.stats.bytes_dropped_fault + r1.stats.bytes_corrupted) as usize;
                let ran1: BTreeSet<&str> = r1.trace.iter().map(|s| s.text.as_str()).collect();
                let ran2: BTreeSet<&str> = r2.trace.iter().map(|s| s.text.as_str()).collect();
                let mut skipped = Vec::new();
                for (i, l) in job.lines.iter().enumerate() {
                    if l.moves && l.length > 1e-6 {
                        if !ran1.contains(l.text.as_str()) && !ran2.contains(l.text.as_str()) {
                            skipped.push(i);
                        }
                        // (A resume preamble writes the pen moves of the job itself.)
                        let in_preamble =
                            (1..job.len()).any(|k| job.resume_preamble(k).contains(&l.text));
                        if st.done[i] && !in_preamble {
                            assert!(
                                !ran2.contains(l.text.as_str()),
                                "line {i} journaled done but re-ran"
                            );
                        }
                    }
                }
                assert!(
                    skipped.len() <= damaged,
                    "{name}: lines {skipped:?} skipped"
                );
            } else if name == "reset" {
                // The reset discards the line it interrupts and GRBL's RX buffer; the bytes still
                // on the wire then run: perhaps the tail of a line, then whole lines. Whether the
                // first line answered after the reset ran whole (from where the reset left the
                // tool, not from its programmed start) or as a fragment depends on where the
                // reset cut the byte stream, which no answer reveals, and whether the second
                // started at its programmed start depends on that; the status reports come only
                // after both ran. So the safety claim is about segments, not line texts: every
                // segment of the job is cut (a line that ran from the wrong start did not cut
                // its segment), and at most one of them, the second line after the reset when
                // the first ran whole, is cut twice.
                let ran: Vec<&TraceSegment> = r1.trace.iter().chain(&r2.trace).collect();
                let mut twice = Vec::new();
                for (text, from, to) in job.motions() {
                    let cuts = ran
                        .iter()
                        .filter(|s| s.text == text && close(s.from, from) && close(s.to, to))
                        .count();
                    assert!(cuts > 0, "`{text}` from {from:?} to {to:?} never cut");
                    if cuts > 1 && !text.starts_with("G0Z") {
                        twice.push(text);
                    }
                }
                assert!(twice.len() <= 1, "cut twice: {twice:?}");
            } else if name == "alarm" {
                // The line that raised the alarm was interrupted by it: it runs again.
                let hit: BTreeSet<String> = r1
                    .trace
                    .last()
                    .map(|s| s.text.clone())
                    .into_iter()
                    .collect();
                assert_exactly_once_except(&job, &[&r1.trace, &r2.trace], &hit);
            } else if name == "drop" || name == "corrupt" {
                // GRBL's link has no checksum: a damaged byte that still parses runs as
                // something else and cannot be seen by any sender. Each damaged byte may spoil
                // one line; beyond those, nothing is skipped or repeated.
                let damaged = (r1.stats.bytes_dropped_fault + r1.stats.bytes_corrupted) as usize;
                let want = job.motions();
                let bad: Vec<&String> = want
                    .iter()
                    .filter(|(t, _, to)| {
                        let hits: Vec<&TraceSegment> = r1
                            .trace
                            .iter()
                            .chain(&r2.trace)
                            .filter(|s| &s.text == t)
                            .collect();
                        hits.len() != 1 || !close(hits[0].to, *to)
                    })
                    .map(|(t, _, _)| t)
                    .collect();
                assert!(
                    bad.len() <= 2 * damaged + 1,
                    "{name}: {} bad lines for {damaged} damaged bytes after `{e}`: {:?}",
                    bad.len(),
                    &bad[..bad.len().min(12)]
                );
            } else {
                assert_exactly_once(&job, &[&r1.trace, &r2.trace]);
            }
            assert!(Journal::read(&jp).unwrap().finished);
        }
    }
}

#[test]
fn fault_error_at_line() {
    fault_case(
        "error",
        300,
        Faults {
            error_at_line: Some((120, 33)),
            ..Faults::default()
        },
        |r| {
            let e = r.as_ref().unwrap_err();
            assert!(matches!(e, SendError::LineRejected { .. }), "{e}");
            assert!(
                e.to_string()
                    .contains("error:33 (motion command target is invalid)"),
                "{e}"
            );
        },
    );
}

#[test]
fn fault_alarm_at_line() {
    fault_case(
        "alarm",
        300,
        Faults {
            alarm_at_line: Some((150, 1)),
            ..Faults::default()
        },
        |r| {
            let e = r.as_ref().unwrap_err();
            assert!(matches!(e, SendError::Alarm { code: 1, .. }), "{e}");
        },
    );
}

#[test]
fn fault_reset_at_line() {
    fault_case(
        "reset",
        300,
        Faults {
            reset_at_line: Some(150),
            ..Faults::default()
        },
        |r| {
            let e = r.as_ref().unwrap_err();
            assert!(matches!(e, SendError::UnexpectedReset { .. }), "{e}");
        },
    );
}

#[test]
fn fault_hangup_at_line() {
    fault_case(
        "hangup",
        300,
        Faults {
            hangup_at_line: Some(150),
            ..Faults::default()
        },
        |r| {
            let e = r.as_ref().unwrap_err();
            assert!(matches!(e, SendError::Transport { .. }), "{e}");
            assert!(
                e.to_string().contains("last line known executed: line"),
                "{e}"
            );
        },
    );
}

#[test]
fn fault_response_delay() {
    fault_case(
        "delay",
        100,
        Faults {
            response_delay_ms: 5,
            ..Faults::default()
        },
        |r| {
            assert!(r.is_ok(), "{:?}", r.as_ref().err().map(|e| e.to_string()));
        },
    );
}

#[test]
fn fault_dropped_bytes() {
    fault_case(
        "drop",
        300,
        Faults {
            drop_rate: 0.002,
            ..Faults::default()
        },
        |_| {},
    );
}

#[test]
fn fault_corrupted_bytes() {
    fault_case(
        "corrupt",
        300,
        Faults {
            corrupt_rate: 0.002,
            ..Faults::default()
        },
        |_| {},
    );
}

#[test]
fn check_mode_pass_then_cut_with_real_motion() {
    let job = Job::parse(&zigzag(40)).unwrap();
    let sim = spawn(SimConfig::default().with_time_scale(50.0));
    let rep = run(&sim, &job, &opts().with_check(true)).unwrap();
    assert!(rep.checked);
    let r = sim.stop();
    assert_trace_is_job(&job, &r.trace);
}

#[test]
fn travel_and_alarm_policy_against_the_simulator() {
    let job = Job::parse("G0X0Y0\nG1X150Y10F1000\n").unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_setting(130, 100.0),
    );
    let e = run(&sim, &job, &opts()).unwrap_err();
    assert!(matches!(e, SendError::OutOfTravel { axis: 'X', .. }), "{e}");
    assert!(sim.stop().trace.is_empty());
    // Homing enabled: GRBL starts alarm-locked.
    let job = Job::parse("G0X1\n").unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_setting(22, 1.0),
    );
    let e = run(&sim, &job, &opts()).unwrap_err();
    assert!(matches!(e, SendError::AlarmLocked { .. }), "{e}");
    run(&sim, &job, &opts().with_unlock(true)).unwrap();
    assert_eq!(sim.stop().trace.len(), 1);
}

#[test]
fn refuses_to_resume_another_job() {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join("j");
    let job = Job::parse(&zigzag(10)).unwrap();
    let sim = spawn(SimConfig::default().with_instant_motion(true));
    run(&sim, &job, &opts().with_journal(&jp)).unwrap();
    let other = Job::parse(&zigzag(11)).unwrap();
    // The journal keeps the lines' texts: the refusal shows the change (here, lines appended).
    let e = run(&sim, &other, &opts().with_journal(&jp).with_resume(true)).unwrap_err();
    assert!(matches!(e, SendError::JobChanged { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("Refusing to resume the changed job without confirmation"),
        "{e}"
    );
    // A journal that does not keep them (written before it did) is another job.
    let text = std::fs::read_to_string(&jp).unwrap();
    let old: String = text
        .lines()
        .filter(|l| !l.starts_with("T "))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&jp, old).unwrap();
    let e = run(&sim, &other, &opts().with_journal(&jp).with_resume(true)).unwrap_err();
    assert!(e.to_string().contains("different job"), "{e}");
}

/// A job's estimate with controller `settings`, and the time the simulated controller with those
/// settings takes to run it on virtual time (lines fed as GRBL's RX buffer frees, so the planner
/// stays full as behind a character-counting sender).
fn estimate_and_simulated(text: &str, settings: &[(u16, f64)]) -> (f64, f64) {
    use flatcut_firmware_sim::Grbl;
    let limits = flatcut_grbl::MachineLimits::from_settings(&settings.iter().copied().collect());
    let job = Job::parse_with(text, &limits).unwrap();
    let mut g = Grbl::new(&SimConfig {
        settings: settings.to_vec(),
        ..SimConfig::default()
    });
    for l in &job.lines {
        while g.rx_free() < l.text.len() + 1 {
            g.tick(0.001);
        }
        g.receive_all(format!("{}\n", l.text).as_bytes());
    }
    g.run_until_idle(3600.0);
    (job.total_time, g.clock())
}

/// The time estimate against the simulated planner: short diagonal zig-zags, whose junction
/// speed depends on the acceleration along the junction vector, and long straight strokes.
#[test]
fn estimate_matches_the_simulated_machine() {
    for (name, dx, dy, feed, n, within) in [
        ("0.5 mm 90° zig-zag at F1500", 0.5, 0.5, 1500.0, 400, 0.002),
        ("5 mm strokes at F3000", 0.012, 5.0, 3000.0, 200, 0.002),
    ] {
        let mut text = String::from("G21 G90\n");
        for i in 1..=n {
            text.push_str(&format!(
                "G1 X{:.3} Y{:.3} F{feed}\n",
                i as f64 * dx,
                (i % 2) as f64 * dy
            ));
        }
        let (est, sim) = estimate_and_simulated(&text, &[]);
        assert!(
            (est - sim).abs() <= within * sim,
            "{name}: estimate {est:.2} s, simulated {sim:.2} s"
        );
        eprintln!("{name}: estimate {est:.3} s, simulated {sim:.3} s");
    }
}

/// The lampshade's plotter job (its profile's rates and accelerations) with GRBL's default step
/// idle delay `$1 = 25`: 237 pen lifts and drops each stop the machine, and each stop holds it
/// 25 ms (about 3 % of the job). The estimate counts them as the simulated controller spends
/// them: with `$1 = 255` (no delay) both drop by the same amount.
#[test]
fn estimate_counts_the_step_idle_delay_on_the_lampshade() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../patterns/golden/lampshade/job-1.gcode"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let plotter = |idle_ms: f64| {
        let mut s = vec![(1, idle_ms), (11, 0.01), (130, 1200.0), (131, 914.0)];
        for a in 0..3 {
            s.push((110 + a, 6000.0));
            s.push((120 + a, 500.0));
        }
        s
    };
    let (est, sim) = estimate_and_simulated(&text, &plotter(25.0));
    let (est_off, sim_off) = estimate_and_simulated(&text, &plotter(255.0));
    eprintln!(
        "lampshade, $1=25: estimate {est:.2} s, simulated {sim:.2} s ({:+.2} %); $1=255: \
         estimate {est_off:.2} s, simulated {sim_off:.2} s",
        100.0 * (est - sim) / sim
    );
    assert!((est - sim).abs() <= 0.005 * sim, "{est} vs {sim}");
    // The stops' share: 25 ms at each of the job's stops, the same in both.
    let (d_est, d_sim) = (est - est_off, sim - sim_off);
    assert!(d_sim > 0.02 * sim, "{d_sim}");
    assert!((d_est - d_sim).abs() <= 0.02 * d_sim, "{d_est} vs {d_sim}");
}

/// Issue 14, item 5: with homing and soft limits GRBL allows machine coordinates −travel..0
/// only; the refusal says so in machine coordinates.
#[test]
fn travel_refusal_explains_machine_coordinates() {
    let job = Job::parse("G0X0Y0\nG1X95Y10F1000\n").unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_setting(22, 1.0)
            .with_setting(20, 1.0)
            .with_setting(130, 800.0),
    );
    let e = run(&sim, &job, &opts().with_unlock(true)).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, SendError::OutOfTravel { axis: 'X', .. }),
        "{msg}"
    );
    assert!(
        msg.contains("0.000..95.000 mm in machine coordinates")
            && msg.contains("outside -800.000..0.000 mm"),
        "{msg}"
    );
    assert!(sim.stop().trace.is_empty());
}

/// Issue 14, item 3: a job that pauses itself (M0) is aborted by default when nobody can
/// answer (tool off, the line named), and runs through with `PausePolicy::Resume`.
#[test]
fn program_pause_aborts_without_an_operator_and_resumes_when_asked() {
    let text = "G21 G90\nG1 X1 F3000\nM0\nG1 X2\nG1 X3\n";
    let job = Job::parse(text).unwrap();
    let sim = spawn(SimConfig::default().with_instant_motion(true));
    let e = run(&sim, &job, &opts()).unwrap_err();
    assert!(
        matches!(&e, SendError::PausedByJob { line, .. } if line.source_line == 3),
        "{e}"
    );
    assert!(e.to_string().contains("tool off"), "{e}");
    // The pausing line is named once, with its text.
    let msg = e.to_string();
    assert!(
        msg.contains("paused itself at line 3 (`M0`) and") && !msg.contains("(M0)"),
        "{msg}"
    );
    let o = opts().with_on_pause(flatcut_grbl::PausePolicy::Resume);
    run(&sim, &job, &o).expect("resumed after the pause");
    let trace = sim.stop().trace;
    assert_eq!(trace.iter().filter(|s| s.text == "G1X3").count(), 1);
    assert!(!trace.iter().any(|s| s.text == "G1X2" && s.line < 5));
}

/// Progress by path length from the first line: a job this short lies wholly in GRBL's buffers,
/// so no line is known executed until it ends, yet the progress follows the machine along its
/// path (from the same status report as the position), and never goes back.
#[test]
fn progress_follows_the_machine_from_the_first_line() {
    let job = Job::parse("G21 G90\nG1 X10 F600\nG1 X20\nG1 Y10\nG1 X0 Y0\n").unwrap();
    let sim = spawn(SimConfig::default().with_time_scale(5.0));
    let o = opts()
        .with_status_interval(Duration::from_millis(40))
        .with_progress_interval(Duration::from_millis(40));
    let mut seen = Vec::new();
    flatcut_testkit::pty::send_with(sim.path(), &job, &o, &CancelToken::new(), &mut |p| {
        if matches!(p.phase, Phase::Streaming | Phase::Finishing) {
            seen.push((p.lines_done, p.length_done, p.position));
        }
    })
    .unwrap();
    sim.stop();
    assert!(seen.windows(2).all(|w| w[1].1 >= w[0].1), "{seen:?}");
    let on_first_move: Vec<_> = seen
        .iter()
        .filter_map(|&(done, len, pos)| {
            let [x, y, _] = pos?;
            (done == 0 && y == 0.0 && x > 1.0 && x < 9.0).then_some((len, x))
        })
        .collect();
    assert!(!on_first_move.is_empty(), "{seen:?}");
    for (len, x) in on_first_move {
        assert!((len - x).abs() < 0.02, "{len} mm shown at X{x}");
    }
    assert!(
        seen.iter()
            .any(|&(done, len, _)| done == 0 && len > 20.0 && len < 30.0),
        "{seen:?}"
    );
}

/// Issue 14, item 5: a laser job (M3 keeps the laser on while stopped) stopped by a rejected
/// line ends with M5 S0 M9, confirmed by `$G`.
#[test]
fn error_stop_turns_the_laser_off_and_confirms_it() {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join("laser.journal");
    let mut text = String::from("G21 G90\nM8\nG1 F600\nM3 S500\n");
    for i in 1..=40 {
        text.push_str(&format!("G1 X{} Y{}\n", i, i % 2));
    }
    let job = Job::parse(&text).unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_setting(32, 1.0)
            .with_faults(Faults {
                error_at_line: Some((30, 33)),
                ..Faults::default()
            }),
    );
    let e = run(&sim, &job, &opts().with_journal(&jp)).unwrap_err();
    assert!(matches!(e, SendError::LineRejected { .. }), "{e}");
    let notes = Journal::read(&jp).unwrap().notes;
    assert!(
        notes
            .iter()
            .any(|n| n == "tool off (M5 M9), confirmed by $G"),
        "{notes:?}"
    );
    sim.stop();
}

/// Issue 14, item 5: a job whose header says it needs laser mode is refused on a controller
/// with `$32=0` before anything moves, unless forced.
#[test]
fn laser_job_is_refused_when_laser_mode_is_off() {
    let job =
        Job::parse("(profile laser - laser: needs $32=1)\nG21 G90\nM4 S0\nG1 X5 F600 S300\nM5\n")
            .unwrap();
    let sim = spawn(SimConfig::default().with_instant_motion(true));
    let e = run(&sim, &job, &opts()).unwrap_err();
    assert!(matches!(e, SendError::LaserModeOff), "{e}");
    run(&sim, &job, &opts().with_force_laser(true)).unwrap();
    assert_eq!(sim.stop().trace.len(), 1);
}

/// Issue 14, item 2: a resume on a controller that restarted (the DTR reset of opening the
/// port) re-establishes the position first: homing where the machine homes, else only on the
/// operator's word; never the remaining lines at once.
#[test]
fn resume_after_a_controller_restart_homes_or_needs_the_operators_word() {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join("j.journal");
    let job = Job::parse(&zigzag(120)).unwrap();
    let faults = Faults {
        error_at_line: Some((60, 33)),
        ..Faults::default()
    };
    let first = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_faults(faults),
    );
    run(&first, &job, &opts().with_journal(&jp)).unwrap_err();
    first.stop();
    let resume = opts().with_journal(&jp).with_resume(true);
    // A fresh controller that does not home: refused, with the reason.
    let plain = spawn(SimConfig::default().with_instant_motion(true));
    let e = run(&plain, &job, &resume).unwrap_err();
    assert!(
        matches!(&e, SendError::PositionUnknown { why } if why.contains("restarted")),
        "{e}"
    );
    assert!(plain.stop().trace.is_empty(), "nothing moved");
    // A fresh controller that homes ($22=1, alarm-locked at power-up): homed, then resumed.
    let homing = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_setting(22, 1.0)
            .with_setting(23, 3.0),
    );
    let rep = run(&homing, &job, &resume).expect("homed and resumed");
    assert_notice(&rep, |n| n.starts_with("homed the machine ($H)"));
    let trace = homing.stop().trace;
    assert_eq!(trace.first().map(|s| s.motion.as_str()), Some("HOME"));
    assert!(Journal::read(&jp).unwrap().finished);
}

/// The journal at `jp` records a tool-off sequence confirmed by `$G`.
fn assert_tool_off_journaled(jp: &std::path::Path) {
    let notes = Journal::read(jp).unwrap().notes;
    assert!(
        notes
            .iter()
            .any(|n| n == "tool off (M5 M9), confirmed by $G"),
        "{notes:?}"
    );
}

/// The questions an [`answering`] operator was asked, with their prompts.
type Asked = std::sync::Arc<std::sync::Mutex<Vec<String>>>;

/// An operator that answers every question with `yes`, noting it in `asked`.
fn answering(asked: &Asked, yes: bool) -> flatcut_grbl::Operator {
    let asked = asked.clone();
    flatcut_grbl::Operator::new(move |q| {
        asked.lock().unwrap().push(format!("{q}\n{}", q.prompt()));
        yes
    })
}

/// Runs `job` journaled at `jp` on a controller that rejects its 60th line (`error:33`):
/// the stop, and what the machine ran.
fn stopped_by_a_bad_line(job: &Job, jp: &std::path::Path) -> (SendError, Vec<TraceSegment>) {
    let first = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_faults(Faults {
                error_at_line: Some((60, 33)),
                ..Faults::default()
            }),
    );
    let e = run(&first, job, &opts().with_journal(jp)).unwrap_err();
    (e, first.stop().trace)
}

/// Issue 14, item 2: without `--origin-confirmed`, a resume on a restarted controller that does
/// not home asks the operator (what the journal says the work origin was, why the position is
/// unknown); "no" refuses with nothing moved and the tool off, "yes" resumes.
#[test]
fn resume_after_a_restart_asks_the_operator_and_moves_only_on_yes() {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join("j.journal");
    let job = Job::parse(&zigzag(120)).unwrap();
    stopped_by_a_bad_line(&job, &jp);
    assert_eq!(Journal::read(&jp).unwrap().origin, Some([0.0; 3]));
    let asked: Asked = Arc::default();
    let operator = |yes: bool| answering(&asked, yes);
    let resume = opts().with_journal(&jp).with_resume(true);
    let no = spawn(SimConfig::default().with_instant_motion(true));
    let e = run(
        &no,
        &job,
        &resume.clone().with_operator(Some(operator(false))),
    )
    .unwrap_err();
    assert!(
        matches!(&e, SendError::OriginNotConfirmed { why } if why.contains("restarted")),
        "{e}"
    );
    assert!(e.to_string().contains("nothing moved, tool off"), "{e}");
    assert!(no.stop().trace.is_empty(), "nothing moved");
    let q = asked.lock().unwrap().pop().expect("the operator was asked");
    assert!(
        q.contains("not known: the controller restarted")
            && q.contains(
                "its work origin (G54 zero) was at machine X0.000 Y0.000 Z0.000 (journal)"
            )
            && q.contains("The job continues with line ")
            && q.ends_with("Is the work origin where it was? [y/N] "),
        "{q}"
    );
    assert_tool_off_journaled(&jp);
    let yes = spawn(SimConfig::default().with_instant_motion(true));
    let remaining = Journal::read(&jp).unwrap().remaining();
    let rep = run(&yes, &job, &resume.with_operator(Some(operator(true)))).expect("resumed");
    // The estimate is what the resumed run sent, not the whole job's: the lines left, and the
    // preambles' travel to where each stretch of them starts (the line the controller refused
    // is one stretch, the lines after those that ran behind it another).
    let left: f64 = remaining.iter().map(|&i| job.lines[i].time).sum();
    assert!(
        rep.estimated_time >= left
            && rep.estimated_time <= 1.1 * left
            && rep.estimated_time < 0.8 * job.total_time,
        "estimated {} s, the lines left {left} s, the whole job {} s",
        rep.estimated_time,
        job.total_time
    );
    assert_notice(&rep, |n| {
        n.starts_with("resuming on the operator's word, asked")
    });
    assert!(!yes.stop().trace.is_empty());
    assert!(Journal::read(&jp).unwrap().finished);
    assert_eq!(asked.lock().unwrap().len(), 1);
}

/// Issue 14, item 5: the soft reset at connection clears G92 and returns to G54 (GRBL 1.1h's
/// `gc_init`); the sender reads `$#` and `$G` first and puts the operator's frame back, says
/// so, and leaves it cleared only when told to.
#[test]
fn soft_reset_at_connection_keeps_the_operators_g92_origin_and_coordinate_system() {
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_dtr_reset(false),
    );
    // The operator's set-up: G55 at X20, then the work origin moved 5 mm further with G92.
    let setup = Job::parse("G10 L2 P2 X20 Y0 Z0\nG55\nG0 X5 Y0\nG92 X0 Y0\n").unwrap();
    run(&sim, &setup, &opts()).unwrap();
    let job = Job::parse("G21 G90\nG1 X10 Y0 F3000\nG1 X10 Y4\n").unwrap();
    let rep = run(&sim, &job, &opts()).unwrap();
    assert_notice(&rep, |n| {
        n.starts_with(
            "kept the controller's work frame across the soft reset at connection (G55, G92 offset X5 Y0 Z0",
        )
    });
    // Work X10 is machine X 20 (G55) + 5 (G92) + 10.
    let trace = sim.trace();
    let cut = trace.iter().find(|s| s.text == "G1X10Y0F3000").unwrap();
    assert!(close(cut.to, [35.0, 0.0, 0.0]), "{cut:?}");
    // Told to discard it: the job runs in G54 without G92, and the report says so.
    let rep = run(&sim, &job, &opts().with_discard_offsets(true)).unwrap();
    assert_notice(&rep, |n| n.contains("it was left so as asked"));
    let trace = sim.stop().trace;
    let last = trace.iter().rfind(|s| s.text == "G1X10Y0F3000").unwrap();
    assert!(close(last.to, [10.0, 0.0, 0.0]), "{last:?}");
}

/// Issue 14, item 5: a job that never sets Z runs where the controller has Z (here 3 mm), and
/// finishes there: not "a line was corrupted on the link".
#[test]
fn axes_the_job_never_sets_start_where_the_controller_has_them() {
    let dir = tempfile::tempdir().unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_dtr_reset(false),
    );
    run(&sim, &Job::parse("G0 Z3\n").unwrap(), &opts()).unwrap();
    let job = Job::parse(
        &zigzag(30)
            .replace("G0 Z2\n", "")
            .replace("G1 Z-0.5 F300\n", "")
            .replace("G0 Z1.5\n", ""),
    )
    .unwrap();
    assert!(job.safe_z.is_none(), "the job never moves Z");
    let jp = dir.path().join("xy.journal");
    let rep = run(&sim, &job, &opts().with_journal(&jp)).unwrap();
    let end = rep.final_position.unwrap();
    assert!((end[2] - 3.0).abs() < 1e-3, "{end:?}");
    assert!(Journal::read(&jp).unwrap().finished);
    let trace = sim.stop().trace;
    assert!(
        trace
            .iter()
            .filter(|s| s.text.starts_with("G1X"))
            .all(|s| (s.to[2] - 3.0).abs() < 1e-3)
    );
}

/// Issue 14, item 12: a job whose feeds exceed the controller's max rates (read from `$$` at
/// the handshake) is warned about before streaming; GRBL itself slows the moves without a word.
#[test]
fn feeds_over_the_controllers_max_rates_are_warned_before_streaming() {
    let job = Job::parse("G21 G90\nG1 X10 F3000\nG1 Y10 F400\n").unwrap();
    // X at 500 mm/min, the GRBL default; Y fast enough for its F400.
    let sim = spawn(
        SimConfig::default()
            .with_time_scale(20.0)
            .with_setting(110, 500.0)
            .with_setting(111, 1000.0),
    );
    // The notice reaches the observer before the first line streams.
    let mut seen_before_streaming = Vec::new();
    let rep =
        flatcut_testkit::pty::send_with(sim.path(), &job, &opts(), &CancelToken::new(), &mut |p| {
            if p.phase != Phase::Streaming && p.lines_acked == 0 {
                seen_before_streaming.clone_from(&p.notices);
            }
        })
        .unwrap();
    let want = "the job asks F3000 (line 2) but the controller's X max rate ($110) is 500 mm/min: \
                1 move(s) will run slower than the job says, that one at 500 mm/min";
    assert_eq!(seen_before_streaming, vec![want.to_string()]);
    assert_notice(&rep, |n| n == want);
    assert_eq!(rep.notices.len(), 1, "{:?}", rep.notices);
    // The machine did run the 10 mm at 500 mm/min, not 3000 (1.2 s, not 0.2 s), and the
    // estimate knew it.
    let trace = sim.stop().trace;
    let x = trace.iter().find(|s| s.text == "G1X10F3000").unwrap();
    let took = x.t_end - x.t_start;
    assert!(took >= 1.2 - 1e-6, "{took} s");
    assert!(rep.estimated_time >= 1.2 + 1.5, "{}", rep.estimated_time);
}

/// Issue 14, item 4: a line damaged on the link that still parses (`--drop-digit-at`, one digit
/// lost: `X40.8` ran as `X40.`) is caught while it runs, by the reported position leaving the
/// job's path; the run stops (feed hold, soft reset, tool off) naming the lines, the expected
/// and the reported position, and a resume asks where to continue. The same job undamaged
/// runs to the end without a false alarm.
#[test]
fn a_line_damaged_on_the_link_stops_the_run_naming_the_lines() {
    let dir = tempfile::tempdir().unwrap();
    let job = Job::parse(&jobs::long_strokes(12)).unwrap();
    let k = 6;
    let cfg = SimConfig::default().with_time_scale(6.0);
    // Undamaged: complete, and tells which received line is job line k.
    let clean = spawn(cfg.clone());
    run(&clean, &job, &opts()).expect("an undamaged run passes the position checks");
    let trace = clean.stop().trace;
    assert_trace_is_job(&job, &trace);
    let n = trace
        .iter()
        .find(|s| s.text == job.lines[k].text)
        .map(|s| s.line)
        .unwrap();
    let jp = dir.path().join("damaged.journal");
    let sim = spawn(cfg.with_faults(Faults {
        drop_digit_at_line: Some(n),
        ..Faults::default()
    }));
    let e = match run(&sim, &job, &opts().with_journal(&jp)) {
        Err(e) => e,
        Ok(_) => {
            let t: Vec<(u32, String, [f64; 3])> = sim
                .stop()
                .trace
                .iter()
                .map(|s| (s.line, s.text.clone(), s.to))
                .collect();
            panic!("not caught; line {n}; trace {t:?}");
        }
    };
    let SendError::OffPath(off) = &e else {
        panic!("{e}");
    };
    let (from, to, expected, reported) = (&off.from, &off.to, off.expected, off.reported);
    assert!(from.index <= k && k <= to.index, "{e}");
    let dev = ((expected[0] - reported[0]).powi(2) + (expected[1] - reported[1]).powi(2)).sqrt();
    assert!(dev > off.tolerance && dev <= 0.81, "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains(&format!("lines {} to {}", from.source_line, to.source_line))
            && msg.contains("tool off"),
        "{msg}"
    );
    let report = sim.stop();
    // Job line 6 is `G1X10.8Y40`: it ran as `G1X10.Y40`.
    assert_eq!(job.lines[k].text, "G1X10.8Y40");
    assert!(
        report.trace.iter().any(|s| s.text == "G1X10.Y40"),
        "the damaged line ran"
    );
    // The machine stopped where it was found: the strokes after the damaged one did not all run.
    assert!(report.trace.len() < 12, "{}", report.trace.len());
    assert_tool_off_journaled(&jp);
    // Which lines ran as written is not known: a resume names them and asks.
    let sim2 = spawn(SimConfig::default().with_instant_motion(true));
    let o = opts()
        .with_journal(&jp)
        .with_resume(true)
        .with_origin_confirmed(true);
    let e2 = run(&sim2, &job, &o).unwrap_err();
    assert!(
        matches!(&e2, SendError::ResumeUncertain { from: f, reason, .. }
            if f.index == from.index && reason.contains("left the job's path")),
        "{e2}"
    );
    sim2.stop();
}

/// Issue 14, item 5: a job stopped by a bad line continues after the file is fixed: the resume
/// shows what changed and the last line executed, refuses until the change is accepted (the
/// operator's "yes", or the option), then sends the fixed line and what had not run, never a
/// line that had. The stop names the last line executed exactly: the last the machine ran.
#[test]
fn an_edited_job_resumes_after_its_fix_only_when_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join("j.journal");
    let text = zigzag(120);
    let job = Job::parse(&text).unwrap();
    let (e, r1) = stopped_by_a_bad_line(&job, &jp);
    let SendError::LineRejected { error, last_done } = &e else {
        panic!("{e}");
    };
    // Exactly the last line the machine ran (lines GRBL held behind the rejected one ran too).
    let last = last_done.as_ref().expect("lines ran");
    assert_eq!(
        r1.last().map(|s| s.text.as_str()),
        Some(last.text.as_str()),
        "{e}"
    );
    assert!(last.index > error.line.index, "{e}");
    assert!(
        e.to_string()
            .contains(&format!("last line known executed: {last}")),
        "{e}"
    );
    // The fix: the rejected line written another way (the same move).
    let bad = error.line.source_line;
    let fixed: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == bad {
                format!("{}\n", l.replacen(" Y", "0 Y", 1))
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let job2 = Job::parse(&fixed).unwrap();
    assert_ne!(job2.lines[error.line.index].text, error.line.text);
    let asked: Asked = Arc::default();
    let operator = |yes: bool| answering(&asked, yes);
    let resume = opts()
        .with_journal(&jp)
        .with_resume(true)
        .with_origin_confirmed(true);
    // Refused, nothing sent: without an operator, and when the operator says no.
    let sim = spawn(SimConfig::default().with_instant_motion(true));
    for o in [None, Some(operator(false))] {
        let e = run(&sim, &job2, &resume.clone().with_operator(o)).unwrap_err();
        assert!(matches!(e, SendError::JobChanged { .. }), "{e}");
        let msg = e.to_string();
        for want in [
            format!("Changed: line {bad} of the journal's job became line {bad} of this file:"),
            format!("  - {bad}: {}", error.line.text),
            format!("  + {bad}: {}", job2.lines[error.line.index].text),
            format!(
                "Last line executed: line {} ({})",
                last.source_line, last.text
            ),
            format!("The resume continues at line {bad} "),
        ] {
            assert!(msg.contains(&want), "{want:?} not in {msg}");
        }
    }
    let q = asked.lock().unwrap().pop().expect("the operator was asked");
    assert!(q.ends_with("Resume the changed job? [y/N] "), "{q}");
    assert_eq!(sim.stop().stats.lines_received, 0, "nothing was sent");
    // Accepted by the operator: the fixed line and the lines that had not run are sent.
    let sim = spawn(SimConfig::default().with_instant_motion(true));
    let st = Journal::read(&jp).unwrap();
    let rep = run(
        &sim,
        &job2,
        &resume.clone().with_operator(Some(operator(true))),
    )
    .unwrap();
    assert_eq!(rep.previously_done, st.done_count());
    assert_notice(&rep, |n| n.starts_with("resumed an edited job."));
    let r2 = sim.stop().trace;
    assert!(
        r2.iter()
            .any(|s| s.text == job2.lines[error.line.index].text)
    );
    assert_exactly_once(&job2, &[&r1, &r2]);
    assert!(Journal::read(&jp).unwrap().finished);
}

/// Issue 14, item 5: an edit of a line that already ran cannot be resumed by guessing: the
/// resume asks for the line to continue from, and runs from it when told.
#[test]
fn an_edit_where_the_job_already_ran_needs_the_line_to_continue_from() {
    let dir = tempfile::tempdir().unwrap();
    let jp = dir.path().join("j.journal");
    let text = zigzag(80);
    let job = Job::parse(&text).unwrap();
    stopped_by_a_bad_line(&job, &jp);
    // Line 10 of the file (long done) is changed.
    let edited: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == 10 {
                format!("{l} S0\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let job2 = Job::parse(&edited).unwrap();
    let resume = opts()
        .with_journal(&jp)
        .with_resume(true)
        .with_origin_confirmed(true)
        .with_accept_changed_job(true);
    let sim = spawn(SimConfig::default().with_instant_motion(true));
    let e = run(&sim, &job2, &resume).unwrap_err();
    assert!(matches!(e, SendError::JobChangedWhereItRan { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("executed line(s) were changed (from line 10)"),
        "{e}"
    );
    let from = job2.lines.iter().position(|l| l.source_line == 70).unwrap();
    let rep = run(&sim, &job2, &resume.with_resume_from(Some(from))).unwrap();
    assert_eq!(rep.previously_done, from);
    let r2 = sim.stop().trace;
    assert!(r2.iter().any(|s| s.text == job2.lines[from].text));
    assert!(!r2.iter().any(|s| s.text == job2.lines[from - 1].text));
    assert!(Journal::read(&jp).unwrap().finished);
}

/// Issue 14, item 4: arcs run as GRBL's chords, which the sender's model reproduces, so status
/// reports taken mid-arc never stop a correct run: full circles and half circles, both ways,
/// with motion in time.
#[test]
fn arcs_pass_the_position_checks_without_a_false_alarm() {
    let mut text = String::from("G21 G90\nG0 X10 Y0\nG1 F2400\n");
    for k in 0..4 {
        let r = 10.0 + 4.0 * f64::from(k);
        text.push_str(&format!(
            "G1 X{r} Y0\nG2 X-{r} Y0 I-{r} J0\nG2 X{r} Y0 I{r} J0\n"
        ));
        text.push_str(&format!("G3 X{r} Y0 I-{r} J0\n"));
    }
    let job = Job::parse(&text).unwrap();
    let sim = spawn(
        SimConfig::default()
            .with_time_scale(8.0)
            .with_setting(110, 3000.0)
            .with_setting(111, 3000.0),
    );
    let mut reports = 0;
    let rep =
        flatcut_testkit::pty::send_with(sim.path(), &job, &opts(), &CancelToken::new(), &mut |p| {
            if p.state == Some(flatcut_grbl::MachineState::Run) {
                reports += 1;
            }
        })
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rep.lines_sent, job.len());
    // Every move ran: the rapid, three of the four G1s (the first is already there) and 12 arcs.
    assert_eq!(sim.stop().trace.len(), 16);
    assert!(reports > 10, "status reports while moving: {reports}");
}
