//! Streaming end to end through the command line's device layer: a pattern-like job goes to the
//! embedded simulator (no `--port`), every motion runs once in order, `--check` runs a `$C` pass,
//! and injected faults (an `error:N`, a hang-up) stop the job with a message naming the line and
//! leave a journal from which `--resume` completes it.

use flatcut_cli::Command;
use flatcut_cli::cmd::device::{
    StreamArgs, StreamError, StreamOutcome, stream_file, stream_file_with_control,
};
use flatcut_cli::cmd::send::parse_command_line;
use flatcut_firmware_sim::TraceSegment;
use flatcut_grbl::{Control, Job, Journal, SendError};
use flatcut_testkit::jobs::pattern_job;
use flatcut_testkit::trace::{self, close, moving, read_trace};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

struct Case {
    _dir: tempfile::TempDir,
    job_path: PathBuf,
    journal: PathBuf,
    job: Job,
    root: PathBuf,
}

fn case(pieces: usize) -> Case {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().to_path_buf();
    let text = pattern_job(pieces);
    let job_path = root.join("job.gcode");
    std::fs::write(&job_path, &text).unwrap();
    Case {
        journal: root.join("job.journal"),
        job: Job::parse(&text).unwrap(),
        job_path,
        root,
        _dir: dir,
    }
}

/// The pattern jobs of up to 6 pieces span 257 mm in X: the simulated machine's X travel.
const PATTERN_TRAVEL: &str = "130=300";

fn args(c: &Case) -> StreamArgs {
    StreamArgs::default()
        .with_sim_instant(true)
        .with_quiet(true)
        .with_journal(&c.journal)
        .with_sim_set(PATTERN_TRAVEL)
}

fn trace_of(out: &StreamOutcome) -> &[TraceSegment] {
    out.sim_trace
        .as_deref()
        .expect("the embedded simulator's trace")
}

/// Every job motion with a unique text ran exactly once over all runs (and most lines are
/// checkable).
fn assert_exactly_once(job: &Job, traces: &[&[TraceSegment]]) {
    assert_exactly_once_except(job, traces, &BTreeSet::new());
}

fn assert_exactly_once_except(job: &Job, traces: &[&[TraceSegment]], except: &BTreeSet<String>) {
    let checked = trace::assert_exactly_once_except(job, traces, except);
    assert!(
        checked > job.len() / 2,
        "only {checked} lines were checkable"
    );
}

#[test]
fn streams_to_the_embedded_simulator_every_motion_once_in_order() {
    let c = case(6);
    let svg = c.root.join("drawn.svg");
    let jsonl = c.root.join("trace.jsonl");
    let out = stream_file(
        &c.job_path,
        &args(&c).with_sim_svg(&svg).with_sim_trace(&jsonl),
    )
    .unwrap();
    assert_eq!(out.report.lines_sent, c.job.len());
    assert!(!out.report.checked);
    let want = c.job.motions();
    let got = moving(trace_of(&out));
    assert_eq!(got.len(), want.len(), "motion segment count");
    for (k, (w, g)) in want.iter().zip(&got).enumerate() {
        assert_eq!(g.text, w.0, "segment {k}");
        assert!(
            close(g.from, w.1) && close(g.to, w.2),
            "segment {k}: {g:?} vs {w:?}"
        );
    }
    // Pen down exactly on the drawing lines: 6 pieces × 48 sides.
    assert_eq!(got.iter().filter(|s| s.tool_on).count(), 6 * 48);
    let end = out.report.final_position.expect("final position");
    assert!(close(end, c.job.end_state.position), "{end:?}");
    let stats = out.sim_stats.as_ref().unwrap();
    assert_eq!(stats.errors, 0);
    assert_eq!(stats.bytes_dropped_overflow, 0);
    assert!(stats.max_rx_fill <= 128);
    // Evidence files: the SVG of what was drawn and the trace, identical to the one returned.
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.contains("<svg"), "{svg_text:.200}");
    // (serde_json's default float parsing is not always correctly rounded: compare to 1 µm.)
    let from_file = read_trace(&jsonl);
    assert_eq!(from_file.len(), trace_of(&out).len());
    for (a, b) in from_file.iter().zip(trace_of(&out)) {
        assert!(
            a.text == b.text && close(a.from, b.from) && close(a.to, b.to),
            "{a:?} vs {b:?}"
        );
    }
    let j = Journal::read(&c.journal).unwrap();
    assert!(j.finished);
    assert_eq!(j.done_count(), c.job.len());
    let summary = flatcut_cli::cmd::send::summary(&out);
    assert!(
        summary.contains(&format!("sent {} line(s)", c.job.len())),
        "{summary}"
    );
}

#[test]
fn command_line_send_with_check_pass() {
    let c = case(2);
    let svg = c.root.join("drawn.svg");
    let cli = parse_command_line([
        "flatcut",
        "send",
        c.job_path.to_str().unwrap(),
        "--sim-instant",
        "--quiet",
        "--check",
        "--journal",
        c.journal.to_str().unwrap(),
        "--sim-svg",
        svg.to_str().unwrap(),
    ])
    .unwrap();
    let code = flatcut_cli::run(cli).unwrap();
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    assert!(Journal::read(&c.journal).unwrap().finished);

    // The same through the library entry, to see the report: a check pass ran, then the cut.
    let out = stream_file(&c.job_path, &args(&c).with_check(true)).unwrap();
    assert!(out.report.checked);
    assert_eq!(moving(trace_of(&out)).len(), c.job.motions().len());
}

#[test]
fn check_pass_refuses_a_bad_job_before_anything_moves() {
    let c = case(1);
    // G2 without I/J/R: GRBL rejects it (error:26, no axis words... or missing offsets).
    let bad = format!("{}G2 X10 Y10\n", pattern_job(1));
    let bad_path = c.root.join("bad.gcode");
    std::fs::write(&bad_path, bad).unwrap();
    let e = stream_file(&bad_path, &args(&c).with_check(true)).unwrap_err();
    let msg = format!("{e:#}");
    assert!(msg.contains("check mode found 1 rejected line"), "{msg}");
    assert!(msg.contains("`G2X10Y10`"), "{msg}");
}

#[test]
fn injected_error_names_the_line_and_resume_completes() {
    let c = case(6);
    let t1 = c.root.join("run1.jsonl");
    let mut a = args(&c).with_sim_trace(&t1);
    a.sim_error_at = Some("150:33".into());
    let e = stream_file(&c.job_path, &a).unwrap_err();
    let msg = format!("{e:#}");
    assert!(
        msg.contains("error:33 (motion command target is invalid)"),
        "{msg}"
    );
    assert_eq!(msg.matches("error:33").count(), 1, "said once: {msg}");
    let typed = e.downcast_ref::<StreamError>().expect("a StreamError");
    assert!(
        matches!(typed.send_error(), SendError::LineRejected { error, .. } if error.code == 33),
        "{typed:?}"
    );
    assert!(msg.contains("--resume"), "{msg}");
    assert!(msg.contains("last line known executed"), "{msg}");
    // The message names the rejected line by file line number and text; it is a job line that
    // did not run in this first run.
    let text = msg.split('`').nth(1).expect("a quoted line");
    let line = c
        .job
        .lines
        .iter()
        .find(|l| l.text == text)
        .unwrap_or_else(|| panic!("`{text}` is not a job line: {msg}"));
    assert!(
        msg.contains(&format!("line {} (`{text}`)", line.source_line)),
        "{msg}"
    );
    let run1 = read_trace(&t1);
    assert!(
        !run1.iter().any(|s| s.text == text),
        "`{text}` ran although rejected"
    );
    let st = Journal::read(&c.journal).unwrap();
    assert!(!st.finished);
    assert!(st.done_count() > 0 && st.done_count() < c.job.len());

    let out = stream_file(
        &c.job_path,
        &args(&c).with_resume(true).with_origin_confirmed(true),
    )
    .unwrap();
    assert_eq!(out.report.previously_done, st.done_count());
    assert!(out.report.preamble_lines > 0);
    assert!(
        trace_of(&out).iter().any(|s| s.text == text),
        "`{text}` not re-sent"
    );
    assert_exactly_once(&c.job, &[&run1, trace_of(&out)]);
    assert!(Journal::read(&c.journal).unwrap().finished);
}

#[test]
fn hold_then_abort_stops_with_a_soft_reset_and_resume_completes() {
    let c = case(4);
    let t1 = c.root.join("run1.jsonl");
    // Real motion (5x real time) so the job is still running when the operator steps in.
    let mut a = args(&c).with_sim_trace(&t1).with_sim_speed(5.0);
    a.sim_instant = false;
    let control = Control::new();
    let operator = {
        let control = control.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(1200));
            control.hold();
            std::thread::sleep(std::time::Duration::from_millis(300));
            control.abort();
        })
    };
    let e = stream_file_with_control(&c.job_path, &a, &control).unwrap_err();
    operator.join().unwrap();
    let msg = format!("{e:#}");
    assert!(msg.contains("aborted: soft reset sent, tool off"), "{msg}");
    assert!(msg.contains("--resume"), "{msg}");
    let run1 = read_trace(&t1);
    assert!(!run1.is_empty(), "nothing ran before the abort");
    let st = Journal::read(&c.journal).unwrap();
    assert!(!st.finished);
    assert!(st.done_count() < c.job.len());

    let out = stream_file(
        &c.job_path,
        &args(&c).with_resume(true).with_origin_confirmed(true),
    )
    .unwrap();
    assert_eq!(out.report.previously_done, st.done_count());
    // The line the abort cut short runs again whole; every other motion runs exactly once.
    let cut_short: BTreeSet<String> = run1.last().map(|s| s.text.clone()).into_iter().collect();
    assert_exactly_once_except(&c.job, &[&run1, trace_of(&out)], &cut_short);
    assert!(Journal::read(&c.journal).unwrap().finished);
}

#[test]
fn hangup_reports_the_last_executed_line_and_resume_completes() {
    let c = case(5);
    let t1 = c.root.join("run1.jsonl");
    let mut a = args(&c).with_sim_trace(&t1);
    a.sim_hangup_at = Some(180);
    let e = stream_file(&c.job_path, &a).unwrap_err();
    let msg = format!("{e:#}");
    assert!(msg.contains("last line known executed: line "), "{msg}");
    assert!(msg.contains("--resume"), "{msg}");
    let run1 = read_trace(&t1);
    let st = Journal::read(&c.journal).unwrap();
    assert!(!st.finished);

    // The embedded simulator comes back as a fresh controller (power-up banner, position zero):
    // nothing can tell which of the queued lines ran, so a plain resume refuses to guess, names
    // the lines in doubt and says how to choose.
    let e = stream_file(
        &c.job_path,
        &args(&c).with_resume(true).with_origin_confirmed(true),
    )
    .unwrap_err();
    let msg = format!("{e:#}");
    let se = e.downcast_ref::<StreamError>().expect("a send error");
    let SendError::ResumeUncertain { from, to, .. } = se.send_error() else {
        panic!("{msg}")
    };
    assert_eq!(Some(from.index), st.unconfirmed.first().copied(), "{msg}");
    assert!(
        msg.contains(&format!(
            "Lines {} to {} may or may not have run",
            from.source_line, to.source_line
        )),
        "{msg}"
    );
    assert!(
        msg.contains(&format!("--resume-from {}", from.source_line)),
        "{msg}"
    );
    let out = stream_file(
        &c.job_path,
        &args(&c)
            .with_resume_from(Some(from.source_line))
            .with_origin_confirmed(true),
    )
    .unwrap();
    assert_eq!(out.report.previously_done, from.index);
    let run2 = trace_of(&out);
    // Resuming from the first line in doubt: lines the journal could not confirm may run again;
    // none is skipped, and none journaled as done runs again.
    let ran1: BTreeSet<&str> = run1.iter().map(|s| s.text.as_str()).collect();
    let ran2: BTreeSet<&str> = run2.iter().map(|s| s.text.as_str()).collect();
    let preamble: BTreeSet<String> = (1..c.job.len())
        .flat_map(|k| c.job.resume_preamble(k))
        .collect();
    for (i, l) in c.job.lines.iter().enumerate() {
        if !(l.moves && l.length > 1e-6) {
            continue;
        }
        assert!(
            ran1.contains(l.text.as_str()) || ran2.contains(l.text.as_str()),
            "line {i} `{}` skipped",
            l.text
        );
        let unique = c.job.lines.iter().filter(|m| m.text == l.text).count() == 1;
        if st.done[i] && unique && !preamble.contains(&l.text) {
            assert!(
                !ran2.contains(l.text.as_str()),
                "line {i} journaled done but re-ran"
            );
        }
    }
    assert!(Journal::read(&c.journal).unwrap().finished);
}

#[test]
fn alarm_mid_job_is_explained_and_resume_completes() {
    let c = case(3);
    let t1 = c.root.join("run1.jsonl");
    let mut a = args(&c).with_sim_trace(&t1);
    a.sim_alarm_at = Some("90:1".into());
    let e = stream_file(&c.job_path, &a).unwrap_err();
    let msg = format!("{e:#}");
    assert!(msg.contains("ALARM:1"), "{msg}");
    assert!(msg.contains("hard limit"), "{msg}");
    assert!(
        msg.to_lowercase().contains("last line known executed"),
        "{msg}"
    );
    assert!(
        msg.contains("--unlock"),
        "a locked controller needs it: {msg}"
    );
    assert!(msg.contains("--resume"), "{msg}");
    let run1 = read_trace(&t1);
    assert!(!Journal::read(&c.journal).unwrap().finished);
    let out = stream_file(
        &c.job_path,
        &args(&c).with_resume(true).with_origin_confirmed(true),
    )
    .unwrap();
    // The line the alarm interrupted runs again; every other motion exactly once.
    let hit: BTreeSet<String> = run1.last().map(|s| s.text.clone()).into_iter().collect();
    assert_exactly_once_except(&c.job, &[&run1, trace_of(&out)], &hit);
    assert!(Journal::read(&c.journal).unwrap().finished);
}

#[test]
fn explicit_port_streams_to_an_external_controller() {
    // A simulator started outside the command (as `flatcut sim` does) is a real port to `send`.
    let c = case(2);
    let sim = flatcut_firmware_sim::PtySim::spawn(
        flatcut_firmware_sim::SimConfig::default().with_instant_motion(true),
    )
    .unwrap();
    let port = sim.path().to_str().unwrap().to_string();
    let out = stream_file(&c.job_path, &args(&c).with_port(&port)).unwrap();
    assert!(out.sim_trace.is_none() && out.sim_stats.is_none());
    assert_eq!(out.report.lines_sent, c.job.len());
    let u = out.link_utilisation();
    assert!(u > 0.0 && u <= 1.0, "{u}");
    let report = sim.stop();
    let got = moving(&report.trace);
    assert_eq!(got.len(), c.job.motions().len());
}

/// A laser job written by flatcut's own G-code writer (arcs fitted, laser on only while cutting)
/// streamed to the embedded simulator in laser mode: everything cut lies on the drawn circle and
/// the cut length is its circumference.
#[test]
fn laser_job_from_the_gcode_writer_cuts_the_drawn_circle() {
    use flatcut::gcode::{GcodeOptions, Profile, plan};
    use flatcut::geom::DVec2;
    use flatcut::pattern::drawing::{Drawing, Layer, Stroke, StrokeKind};
    /// Fitting tolerance of the writer plus one machine step, mm.
    const ON_CIRCLE_MM: f64 = 0.06;
    let (centre, r) = (DVec2::new(60.0, 45.0), 30.0);
    let circle: Vec<DVec2> = (0..720)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 720.0;
            centre + r * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    let drawing = Drawing::from_strokes(vec![Stroke {
        layer: Layer::Cut,
        points: circle,
        closed: true,
        piece: Some(0),
        kind: StrokeKind::Boundary,
        id: "disc".into(),
    }]);
    let profile = Profile::laser();
    let gcode = plan(&drawing, &profile, &GcodeOptions::default())
        .unwrap()
        .to_gcode();
    let c = case(1);
    let path = c.root.join("disc.gcode");
    std::fs::write(&path, &gcode).unwrap();
    let mut a = args(&c);
    a.sim_laser = true;
    let out = stream_file(&path, &a).unwrap();
    let m = profile.to_machine(centre);
    let mc = [m.x, m.y];
    let cut: Vec<&TraceSegment> = trace_of(&out).iter().filter(|s| s.tool_on).collect();
    assert!(!cut.is_empty(), "nothing was cut:\n{gcode}");
    assert!(
        cut.iter().any(|s| s.arc_center.is_some()),
        "the writer fits arcs to a dense circle"
    );
    let mut length = 0.0;
    for s in &cut {
        for p in [s.from, s.to] {
            let d = ((p[0] - mc[0]).powi(2) + (p[1] - mc[1]).powi(2)).sqrt();
            assert!(
                (d - r).abs() <= ON_CIRCLE_MM,
                "{s:?} is {d} mm from the centre"
            );
        }
        length += match s.arc_center {
            Some(ac) => {
                let a0 = (s.from[1] - ac[1]).atan2(s.from[0] - ac[0]);
                let a1 = (s.to[1] - ac[1]).atan2(s.to[0] - ac[0]);
                let mut sweep = if s.motion == "G2" { a0 - a1 } else { a1 - a0 };
                if sweep <= 0.0 {
                    sweep += std::f64::consts::TAU;
                }
                sweep * ((s.from[0] - ac[0]).powi(2) + (s.from[1] - ac[1]).powi(2)).sqrt()
            }
            None => ((s.to[0] - s.from[0]).powi(2) + (s.to[1] - s.from[1]).powi(2)).sqrt(),
        };
    }
    // The laser profile cuts in several passes.
    let passes = profile.layer(Layer::Cut).passes;
    assert!(passes >= 1);
    let want = std::f64::consts::TAU * r * f64::from(passes);
    assert!(
        (length - want).abs() / want < 2e-3,
        "cut {length} mm, circle × {passes} passes {want} mm"
    );
    assert!(
        trace_of(&out)
            .iter()
            .filter(|s| s.motion == "G0")
            .all(|s| !s.tool_on)
    );
}

#[test]
fn stream_arguments_defaults_hidden_faults_and_bad_port() {
    let cli = parse_command_line(["flatcut", "send", "job.gcode"]).unwrap();
    let Command::Send(a) = cli.command else {
        panic!("not a send")
    };
    assert_eq!(a.stream, StreamArgs::default());
    assert_eq!(a.stream.sim_speed, 50.0);
    assert_eq!(a.stream.baud, 115_200);
    assert_eq!(
        a.stream.journal_path("job.gcode"),
        PathBuf::from("job.gcode.journal")
    );
    let cli = parse_command_line([
        "flatcut",
        "send",
        "job.gcode",
        "--sim-error-at",
        "12:33",
        "--sim-hangup-at",
        "40",
    ])
    .unwrap();
    let Command::Send(a) = cli.command else {
        panic!("not a send")
    };
    assert_eq!(a.stream.sim_error_at.as_deref(), Some("12:33"));
    assert_eq!(a.stream.sim_hangup_at, Some(40));
    let help = parse_command_line(["flatcut", "send", "--help"])
        .unwrap_err()
        .to_string();
    assert!(
        help.contains("--unlock") && help.contains("--resume"),
        "{help}"
    );
    assert!(
        !help.contains("--sim-error-at"),
        "fault flags are hidden: {help}"
    );

    let c = case(1);
    let e = stream_file(&c.job_path, &args(&c).with_port("/nonexistent/ttyUSB9")).unwrap_err();
    assert!(
        format!("{e:#}").contains("cannot open the serial port /nonexistent/ttyUSB9"),
        "{e:#}"
    );
    let mut a = args(&c);
    a.sim_error_at = Some("0".into());
    let e = stream_file(&c.job_path, &a).unwrap_err();
    assert!(format!("{e:#}").contains("--sim-error-at 0"), "{e:#}");
}

/// A command running the test `name` of this binary alone (its output shown), with the
/// environment variable `env` naming `dir`: the half of a test that must run in a process of
/// its own (a signal, another stdin).
pub(crate) fn child_test(name: &str, env: &str, dir: &Path) -> std::process::Command {
    let mut c = std::process::Command::new(std::env::current_exe().unwrap());
    c.args([name, "--exact", "--nocapture", "--test-threads=1"])
        .env(env, dir);
    c
}

/// Environment variable naming the working directory of [`sigterm_child_process`].
const SIGTERM_CHILD_ENV: &str = "FLATCUT_SIGTERM_CHILD_DIR";

/// The sending half of [`sigterm_aborts_safely_and_names_the_last_line`], run in a child
/// process (a signal to this test binary would reach every test running in it). Without the
/// variable set it is the parent's run and does nothing.
#[test]
fn sigterm_child_process() {
    let Some(dir) = std::env::var_os(SIGTERM_CHILD_ENV) else {
        return;
    };
    // As the binary does at start: the signal comes to the send, not to the default action.
    flatcut_cli::install_signal_handler().unwrap();
    let dir = PathBuf::from(dir);
    let job = dir.join("job.gcode");
    std::fs::write(&job, pattern_job(6)).unwrap();
    let a = StreamArgs::default()
        .with_sim_speed(2.0)
        .with_quiet(true)
        .with_journal(dir.join("job.journal"))
        .with_sim_set(PATTERN_TRAVEL);
    let e = stream_file(&job, &a).expect_err("the job was stopped by SIGTERM");
    eprintln!("CHILD-ERROR: {e:#}");
    let se = e.downcast_ref::<StreamError>().expect("a send error");
    assert!(
        matches!(se.send_error(), SendError::Aborted { .. }),
        "{e:#}"
    );
}

/// SIGTERM during `flatcut send` takes the abort path: feed hold, soft reset, tool off, journal
/// flushed, and a message naming the last line executed.
#[test]
fn sigterm_aborts_safely_and_names_the_last_line() {
    signal_aborts_with_the_tool_off("-TERM");
}

/// Issue 14, item 5: closing the terminal (SIGHUP) aborts as SIGTERM does, and the tool-off is
/// confirmed.
#[test]
fn sighup_aborts_with_the_tool_off() {
    signal_aborts_with_the_tool_off("-HUP");
}

fn signal_aborts_with_the_tool_off(signal: &str) {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let child = child_test(
        "stream::sigterm_child_process",
        SIGTERM_CHILD_ENV,
        dir.path(),
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    let journal = dir.path().join("job.journal");
    let t0 = Instant::now();
    let streaming = loop {
        let acks = std::fs::read_to_string(&journal)
            .map(|t| t.lines().filter(|l| l.starts_with("A ")).count())
            .unwrap_or(0);
        if acks >= 20 {
            break true;
        }
        if t0.elapsed() > Duration::from_secs(30) {
            break false;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let killed = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(streaming, "the child never streamed: {stderr}");
    assert!(out.status.success(), "child failed: {stderr}");
    assert!(
        stderr.contains(
            "CHILD-ERROR: aborted: soft reset sent, tool off. Last line known executed: line "
        ),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&journal).unwrap();
    assert!(text.contains("N aborted by the user"), "{text}");
    assert!(
        text.contains("N tool off (M5 M9), confirmed by $G"),
        "{text}"
    );
    let st = Journal::read(&journal).unwrap();
    assert!(!st.finished && st.done_count() > 0);
}

/// Environment variable naming the working directory of [`sim_child_process`].
const SIM_CHILD_ENV: &str = "FLATCUT_SIM_CHILD_DIR";

/// `flatcut sim` in a process of its own for [`flatcut_sim_power_cycles_on_sigusr1`] (a board
/// with auto-reset off, so only the power cycle loses its position). Without the variable set it
/// is the parent's run and does nothing.
#[test]
fn sim_child_process() {
    let Some(dir) = std::env::var_os(SIM_CHILD_ENV) else {
        return;
    };
    flatcut_cli::install_signal_handler().unwrap();
    let link = PathBuf::from(dir).join("ttyGRBL");
    let cli = parse_command_line([
        "flatcut",
        "sim",
        "--link",
        link.to_str().unwrap(),
        "--no-dtr-reset",
        "--instant",
    ])
    .unwrap();
    let code = flatcut_cli::run(cli).unwrap();
    assert_eq!(code, std::process::ExitCode::SUCCESS);
}

/// `flatcut sim` passes SIGUSR1 on as a power cycle: the position a client left it at survives
/// closing and reopening the port (no auto-reset), and is lost after the signal, as the board's
/// is when its power goes; Ctrl-C still stops it cleanly.
#[test]
fn flatcut_sim_power_cycles_on_sigusr1() {
    use flatcut_grbl::Transport;
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    use std::sync::mpsc::channel;
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let mut child = child_test("stream::sim_child_process", SIM_CHILD_ENV, dir.path())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, said) = channel();
    let stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        for l in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(l);
        }
    });
    let wait_for = |what: &str| {
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(30) {
            if let Ok(l) = said.recv_timeout(Duration::from_millis(100))
                && l.contains(what)
            {
                return;
            }
        }
        panic!("the simulator never said {what:?}");
    };
    wait_for("power-cycles it");
    let link = dir.path().join("ttyGRBL");
    let ask = |text: &str, until: &str| -> String {
        let mut port = flatcut_grbl::open_port(link.to_str().unwrap(), 115_200).unwrap();
        port.write_all(text.as_bytes()).unwrap();
        let (mut acc, mut buf, t0) = (String::new(), [0u8; 256], Instant::now());
        while !acc.contains(until) && t0.elapsed() < Duration::from_secs(5) {
            let n = port.read(&mut buf, Duration::from_millis(50)).unwrap_or(0);
            acc.push_str(&String::from_utf8_lossy(&buf[..n]));
        }
        acc
    };
    // `?` is a realtime byte: the board answers it the moment it arrives, ahead of the line
    // before it, so the move is confirmed by its `ok` and its end by polling the status.
    assert!(ask("G1 X5 F600\n", "ok").contains("ok"));
    let t0 = Instant::now();
    let mut moved = ask("?", ">\r\n");
    while !moved.contains("MPos:5.000,0.000,0.000") && t0.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(50));
        moved = ask("?", ">\r\n");
    }
    assert!(moved.contains("MPos:5.000,0.000,0.000"), "{moved:?}");
    assert!(ask("?", ">\r\n").contains("MPos:5.000,0.000,0.000"));
    let kill = |sig: &str| {
        let st = std::process::Command::new("kill")
            .args([sig, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(st.success());
    };
    kill("-USR1");
    wait_for("power cycle (SIGUSR1)");
    // The simulator's thread takes the power cycle on its next turn (milliseconds).
    let t0 = Instant::now();
    let mut after = ask("?", ">\r\n");
    while !after.contains("MPos:0.000,0.000,0.000") && t0.elapsed() < Duration::from_secs(2) {
        std::thread::sleep(Duration::from_millis(50));
        after = ask("?", ">\r\n");
    }
    assert!(after.contains("MPos:0.000,0.000,0.000"), "{after:?}");
    kill("-INT");
    wait_for("simulator stopped");
    assert!(child.wait().unwrap().success());
    reader.join().unwrap();
}

/// Writes the lampshade project into `dir` with `device` as its `[device]` section.
fn lampshade_project(dir: &Path, device: &str) -> PathBuf {
    let src = crate::pipeline::root().join("patterns/lampshade");
    let text = format!(
        "name = \"lampshade\"\ndesign = \"{}\"\nmethod = \"developable\"\nseam_mm = 10.0\n\
         [material]\nname = \"parchment\"\n[sheet]\nwidth_mm = 1189.0\nheight_mm = 841.0\n\
         spacing_mm = 5.0\n[machine]\nprofile = \"{}\"\n{device}",
        src.join("design.toml").display(),
        src.join("plotter-a0.toml").display(),
    );
    let p = dir.join("project.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Issue 14, item 1: `flatcut run` streams to the project's `[device]`, refuses a port that is
/// not there (instead of quietly using the simulator), and refuses a baud rate of 0.
#[test]
fn run_uses_the_projects_device() {
    let dir = tempfile::tempdir().unwrap();
    let sim = flatcut_firmware_sim::PtySim::spawn(
        flatcut_firmware_sim::SimConfig::default()
            .with_instant_motion(true)
            .with_setting(130, 1200.0)
            .with_setting(131, 1000.0),
    )
    .unwrap();
    let dev = format!(
        "[device]\nport = \"{}\"\nbaud = 115200\n",
        sim.path().display()
    );
    let project = lampshade_project(dir.path(), &dev);
    let out = dir.path().join("out");
    let run = |project: &Path| {
        let cli = parse_command_line([
            "flatcut",
            "run",
            project.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .unwrap();
        flatcut_cli::run(cli)
    };
    run(&project).expect("the run streams to the project's port");
    let report = sim.stop();
    let job = Job::parse(&std::fs::read_to_string(out.join("job-1.gcode")).unwrap()).unwrap();
    assert_eq!(
        moving(&report.trace).len(),
        job.motions().len(),
        "the project's controller received the job"
    );

    let nope = lampshade_project(dir.path(), "[device]\nport = \"/dev/ttyNOPE\"\n");
    let e = run(&nope).expect_err("a missing port fails the run");
    assert!(
        format!("{e:#}").contains("cannot open the serial port /dev/ttyNOPE"),
        "{e:#}"
    );
    let zero = lampshade_project(dir.path(), "[device]\nbaud = 0\n");
    let e = run(&zero).expect_err("baud = 0 is refused");
    assert!(format!("{e:#}").contains("[device] baud = 0"), "{e:#}");
}

/// Issue 38, item 7: a project whose `[device] port` does not exist fails before any work
/// starts: no output is written (it wrote 12 before), and the error names the port. With
/// `--no-send` the device is not needed and the run writes its outputs.
#[test]
fn a_missing_port_fails_the_run_before_any_output() {
    let dir = tempfile::tempdir().unwrap();
    let nope = lampshade_project(dir.path(), "[device]\nport = \"/dev/ttyNOPE\"\n");
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        let mut argv = vec![
            "flatcut",
            "run",
            nope.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ];
        argv.extend_from_slice(extra);
        flatcut_cli::run(parse_command_line(argv).unwrap())
    };
    let t0 = std::time::Instant::now();
    let e = run(&[]).expect_err("a missing port fails the run");
    let report = flatcut_cli::error_report(&e);
    assert!(
        report.contains("cannot open the serial port /dev/ttyNOPE")
            && report.contains("the serial port /dev/ttyNOPE does not exist"),
        "{report}"
    );
    assert!(!out.exists(), "outputs written before the failure");
    // Nothing was flattened or nested first.
    assert!(
        t0.elapsed() < std::time::Duration::from_secs(1),
        "{:?}",
        t0.elapsed()
    );
    run(&["--no-send"]).expect("without streaming the port is not needed");
    assert!(out.join("job-1.gcode").exists());
}

/// Issue 38, item 7: the embedded simulator is the machine it is set up as, never a bed grown
/// to fit the job: `G1 X9999` is refused before anything moves on GRBL's default machine
/// (200 mm of travel), and the message says how to describe the machine; set up as a
/// profile's machine (the knife's 600 × 400 mm), a job within its work area runs and one
/// beyond it is refused.
#[test]
fn the_embedded_simulator_does_not_grow_to_fit_a_job() {
    let dir = tempfile::tempdir().unwrap();
    let send = |name: &str, gcode: &str, extra: &[&str]| {
        let job = dir.path().join(name);
        std::fs::write(&job, gcode).unwrap();
        let trace = dir.path().join(format!("{name}.jsonl"));
        let (job_s, trace_s) = (job.display().to_string(), trace.display().to_string());
        let mut argv = vec!["flatcut", "send", &job_s, "--sim-instant", "--quiet"];
        argv.extend_from_slice(&["--sim-trace", &trace_s]);
        argv.extend_from_slice(extra);
        let r = flatcut_cli::run(parse_command_line(argv).unwrap());
        (r, read_trace(&trace))
    };
    let (r, trace) = send("far.gcode", "G21 G90\nG1 X9999 F1000\n", &[]);
    let report = flatcut_cli::error_report(&r.expect_err("G1 X9999 is beyond the machine"));
    assert!(
        report.contains("the job's X extent 0.000..9999.000 mm is 9999.000 mm long, more than the machine travel of 200.000 mm ($130)")
            && report.contains("--profile"),
        "{report}"
    );
    assert!(trace.is_empty(), "moved: {trace:?}");
    let (r, trace) = send(
        "in.gcode",
        "G21 G90\nG1 X590 Y390 F1000\n",
        &["--profile", "knife"],
    );
    r.unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(moving(&trace).len(), 1);
    let (r, trace) = send(
        "out.gcode",
        "G21 G90\nG1 X610 F1000\n",
        &["--profile", "knife"],
    );
    let report = flatcut_cli::error_report(&r.expect_err("beyond the knife's work area"));
    assert!(
        report.contains("more than the machine travel of 600.000 mm ($130)")
            && report.contains("the machine the profile describes"),
        "{report}"
    );
    assert!(trace.is_empty());
}

/// Issue 14, item 4: a correct run is never stopped by the position checks: the lampshade's
/// plotter job (2,000 lines), streamed with motion in time so that every status report lands
/// mid-path, runs to the end.
#[test]
fn the_lampshade_job_passes_the_position_checks_without_a_false_alarm() {
    let dir = tempfile::tempdir().unwrap();
    let job_path = crate::pipeline::root().join("patterns/golden/lampshade/job-1.gcode");
    // The lampshade's plotter (its profile's A0 work area).
    let a = StreamArgs::default()
        .with_sim_speed(100.0)
        .with_quiet(true)
        .with_journal(dir.path().join("job.journal"))
        .with_sim_set("130=1200")
        .with_sim_set("131=914");
    let out = stream_file(&job_path, &a).unwrap_or_else(|e| panic!("{e:#}"));
    let job = Job::parse(&std::fs::read_to_string(&job_path).unwrap()).unwrap();
    assert_eq!(out.report.lines_sent, job.len());
    assert!(out.sim_time.unwrap() > 10.0, "motion ran in time");
}

/// Issue 14, item 4: `flatcut send` over a link that loses a digit of one line stops with a
/// failing exit code, and its message names the lines, the reported and the expected position.
#[test]
fn a_damaged_line_fails_the_send_naming_the_lines() {
    let dir = tempfile::tempdir().unwrap();
    let job_path = dir.path().join("strokes.gcode");
    std::fs::write(&job_path, flatcut_testkit::jobs::long_strokes(12)).unwrap();
    let job = Job::parse(&std::fs::read_to_string(&job_path).unwrap()).unwrap();
    let journal = dir.path().join("strokes.journal");
    let journal_s = journal.display().to_string();
    let job_s = job_path.display().to_string();
    let argv = |extra: &[&str]| {
        let mut v = vec![
            "flatcut",
            "send",
            &job_s,
            "-q",
            "--sim-speed",
            "6",
            "--journal",
            &journal_s,
        ];
        v.extend_from_slice(extra);
        v.into_iter().map(String::from).collect::<Vec<_>>()
    };
    // Undamaged, with the trace telling which received line is job line 6.
    let trace = dir.path().join("clean.jsonl");
    let trace_s = trace.display().to_string();
    let cli = parse_command_line(argv(&["--sim-trace", &trace_s])).unwrap();
    flatcut_cli::run(cli).unwrap_or_else(|e| panic!("{e:#}"));
    let n = read_trace(&trace)
        .iter()
        .find(|s| s.text == job.lines[6].text)
        .map(|s| s.line)
        .unwrap()
        .to_string();
    let cli = parse_command_line(argv(&["--sim-drop-digit-at", &n])).unwrap();
    let e = flatcut_cli::run(cli).expect_err("the damaged line stops the send");
    let report = flatcut_cli::error_report(&e);
    assert_ne!(
        flatcut_cli::exit_code(Err(e)),
        std::process::ExitCode::SUCCESS
    );
    // Job line 6 is line 8 of the file.
    assert!(
        report.contains("the machine left the job's path while running lines "),
        "{report}"
    );
    let (from, to) = report
        .split("while running lines ")
        .nth(1)
        .and_then(|r| r.split_once(':'))
        .and_then(|(r, _)| r.split_once(" to "))
        .map(|(a, b)| (a.parse::<usize>().unwrap(), b.parse::<usize>().unwrap()))
        .unwrap();
    assert!(from <= 8 && 8 <= to, "{report}");
    assert!(
        report.contains("reported work position X") && report.contains("tool off"),
        "{report}"
    );
    assert!(report.contains("--resume-from"), "{report}");
}

/// Environment variable naming the working directory of [`resume_without_a_terminal_child`].
const NO_TERMINAL_CHILD_ENV: &str = "FLATCUT_NO_TERMINAL_CHILD_DIR";

/// The resuming half of [`a_resume_without_a_terminal_or_the_flag_refuses`], run in a child
/// process whose stdin is not a terminal. Without the variable set it does nothing.
#[test]
fn resume_without_a_terminal_child() {
    let Some(dir) = std::env::var_os(NO_TERMINAL_CHILD_ENV) else {
        return;
    };
    let dir = PathBuf::from(dir);
    let job = dir.join("job.gcode");
    std::fs::write(&job, pattern_job(2)).unwrap();
    let a = StreamArgs::default()
        .with_sim_instant(true)
        .with_quiet(true)
        .with_journal(dir.join("job.journal"));
    let mut failing = a.clone();
    failing.sim_error_at = Some("40".into());
    stream_file(&job, &failing).expect_err("the injected error stops the first run");
    // The embedded simulator starts afresh (a restart), and it does not home.
    let e = stream_file(&job, &a.with_resume(true)).expect_err("nobody confirmed the origin");
    eprintln!("CHILD-ERROR: {e:#}");
}

/// Issue 14, item 2: without a terminal to ask on and without `--origin-confirmed`, a resume on a
/// controller whose position is unknown refuses, as before the prompt existed.
#[test]
fn a_resume_without_a_terminal_or_the_flag_refuses() {
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let out = child_test(
        "stream::resume_without_a_terminal_child",
        NO_TERMINAL_CHILD_ENV,
        dir.path(),
    )
    .stdin(Stdio::null())
    .output()
    .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "child failed: {stderr}");
    assert!(
        stderr.contains(
            "CHILD-ERROR: cannot resume: the controller restarted when the port was opened"
        ) && stderr.contains("nobody confirmed that its work origin is where it was")
            && stderr.contains("--origin-confirmed"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("[y/N]"),
        "asked without a terminal: {stderr}"
    );
}

/// Issue 14, item 5: `flatcut send --resume --accept-changed-job` continues a job whose bad line
/// was fixed in the file after the stop, and says that it resumed an edited job.
#[test]
fn a_fixed_job_file_resumes_with_accept_changed_job() {
    let c = case(3);
    let mut a = args(&c);
    a.sim_error_at = Some("60:33".into());
    let e = stream_file(&c.job_path, &a).unwrap_err();
    let typed = e.downcast_ref::<StreamError>().expect("a StreamError");
    let SendError::LineRejected { error, .. } = typed.send_error() else {
        panic!("{e:#}");
    };
    let bad = error.line.source_line;
    let text = std::fs::read_to_string(&c.job_path).unwrap();
    let fixed: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == bad {
                format!("{l} (fixed)\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(&c.job_path, fixed).unwrap();
    let out = stream_file(
        &c.job_path,
        &args(&c)
            .with_resume(true)
            .with_origin_confirmed(true)
            .with_accept_changed_job(true),
    )
    .unwrap_or_else(|e| panic!("{e:#}"));
    assert!(out.report.previously_done > 0);
    let summary = flatcut_cli::cmd::send::summary(&out);
    assert!(
        summary.contains("note: resumed an edited job.")
            && summary.contains("The lines to send are the same; only comments"),
        "{summary}"
    );
    assert!(Journal::read(&c.journal).unwrap().finished);
}

/// Environment variable naming the working directory of [`resume_at_a_terminal_child`].
const TERMINAL_CHILD_ENV: &str = "FLATCUT_TERMINAL_CHILD_DIR";

/// The resuming half of [`the_terminal_prompt_resumes_on_yes_and_refuses_otherwise`], run in a
/// child process whose stdin is a pseudo-terminal. Without the variable set it does nothing.
#[test]
fn resume_at_a_terminal_child() {
    let Some(dir) = std::env::var_os(TERMINAL_CHILD_ENV) else {
        return;
    };
    flatcut_cli::install_signal_handler().unwrap();
    let dir = PathBuf::from(dir);
    let a = StreamArgs::default()
        .with_sim_instant(true)
        .with_quiet(true)
        .with_journal(dir.join("job.journal"))
        .with_resume(true);
    match stream_file(&dir.join("job.gcode"), &a) {
        Ok(out) => eprintln!("CHILD-OK: {}", flatcut_cli::cmd::send::summary(&out)),
        Err(e) => eprintln!("CHILD-ERROR: {e:#}"),
    }
}

/// How the operator at the terminal responds to the question.
enum Respond<'a> {
    /// Types this.
    Type(&'a str),
    /// Presses Ctrl-C (SIGINT to the process).
    Interrupt,
}

/// Runs [`resume_at_a_terminal_child`] in `dir` with a pseudo-terminal as stdin, responds to its
/// question, and returns what it printed on stderr; the child must end within 30 s.
fn resume_at_a_terminal(dir: &Path, respond: Respond<'_>) -> String {
    use std::io::{Read, Write};
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let pty = nix::pty::openpty(None, None).unwrap();
    let mut child = child_test(
        "stream::resume_at_a_terminal_child",
        TERMINAL_CHILD_ENV,
        dir,
    )
    .stdin(Stdio::from(pty.slave))
    .stdout(Stdio::null())
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    let mut stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel::<Vec<u8>>();
    let reader = std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = stderr.read(&mut buf) {
            if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    let mut said = String::new();
    let t0 = Instant::now();
    while !said.contains("[y/N]") && t0.elapsed() < Duration::from_secs(60) {
        if let Ok(b) = rx.recv_timeout(Duration::from_millis(100)) {
            said.push_str(&String::from_utf8_lossy(&b));
        }
    }
    assert!(said.contains("[y/N]"), "never asked: {said}");
    let mut master = std::fs::File::from(pty.master);
    match respond {
        Respond::Type(answer) => master.write_all(answer.as_bytes()).unwrap(),
        Respond::Interrupt => nix::sys::signal::kill(
            nix::unistd::Pid::from_raw(child.id() as i32),
            nix::sys::signal::Signal::SIGINT,
        )
        .unwrap(),
    }
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("the child hangs after the response: {said}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    reader.join().unwrap();
    said.extend(
        rx.try_iter()
            .map(|b| String::from_utf8_lossy(&b).into_owned()),
    );
    assert!(status.success(), "child failed: {said}");
    said
}

/// Issue 14, item 2: on a terminal, a resume whose machine position is unknown says why and
/// where the journal put the work origin, asks "Is the work origin where it was? [y/N]", and
/// resumes on `y`; any other answer refuses with nothing moved and the tool off.
#[test]
fn the_terminal_prompt_resumes_on_yes_and_refuses_otherwise() {
    let c = case(2);
    let mut a = args(&c);
    a.sim_error_at = Some("40".into());
    stream_file(&c.job_path, &a).expect_err("the injected error stops the first run");
    let said = resume_at_a_terminal(&c.root, Respond::Type("no\n"));
    assert!(
        said.contains("The machine position is not known: the controller restarted")
            && said.contains(
                "its work origin (G54 zero) was at machine X0.000 Y0.000 Z0.000 (journal)"
            )
            && said.contains("Is the work origin where it was? [y/N] "),
        "{said}"
    );
    assert!(
        said.contains("CHILD-ERROR: cannot resume: the controller restarted")
            && said.contains("the operator did not confirm that the work origin is where it was; nothing moved, tool off"),
        "{said}"
    );
    assert!(!Journal::read(&c.journal).unwrap().finished);
    // Ctrl-C at the question is a no, at once: nothing moved, nothing left waiting for a line.
    let said = resume_at_a_terminal(&c.root, Respond::Interrupt);
    assert!(
        said.contains("interrupted: not confirmed; aborting")
            && said.contains("CHILD-ERROR: cannot resume")
            && said.contains("nothing moved, tool off"),
        "{said}"
    );
    assert!(!Journal::read(&c.journal).unwrap().finished);
    let said = resume_at_a_terminal(&c.root, Respond::Type("y\n"));
    assert!(
        said.contains("CHILD-OK: ")
            && said.contains("note: resuming on the operator's word, asked at the start"),
        "{said}"
    );
    assert!(Journal::read(&c.journal).unwrap().finished);
}
