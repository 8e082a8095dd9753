//! Exact resume over a real pseudo-terminal, on a controller that keeps its position across
//! reconnects (firmware-sim with DTR auto-reset off): a hang-up while moving, a feed hold followed
//! by a soft reset, a reset in motion (ALARM:3), a stop while answers are still on the wire, and a
//! pause then a stop where the path passes twice, and a sender that dies mid-stream while the
//! controller runs on (killed for real, and the journals such a death leaves, built from a real
//! run so that the outcome does not depend on timing). In each case the simulator's trace over all
//! runs, with a line that was stopped part-way joined to its completion, is the job's motion
//! exactly once, in order.

use flatcut_firmware_sim::{Faults, PtySim, SimConfig, TraceSegment};
use flatcut_grbl::{CancelToken, Job, Journal, SendError, SendOptions};
use flatcut_testkit::jobs;
use flatcut_testkit::pty::send_with;
use flatcut_testkit::trace::{assert_job_exactly_once, close};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A pen-plotter job of `n` strokes, each at its own place, at F1200 so that motion is still
/// queued when the link drops.
fn strokes(n: usize) -> String {
    jobs::zigzag(n, 0.2, 4.0, 1200.0)
}

fn opts(journal: &Path) -> SendOptions {
    SendOptions::default()
        .with_banner_timeout(Duration::from_millis(300))
        .with_silence_timeout(Duration::from_secs(5))
        .with_journal(journal)
}

fn send(
    path: &Path,
    job: &Job,
    o: &SendOptions,
    cancel: &CancelToken,
    abort_after: Option<usize>,
) -> Result<flatcut_grbl::SendReport, SendError> {
    let c = cancel.clone();
    send_with(path, job, o, cancel, &mut |p| {
        if abort_after.is_some_and(|n| p.lines_acked >= n) {
            c.abort();
        }
    })
}

struct Bench {
    _dir: tempfile::TempDir,
    journal: PathBuf,
    job: Job,
}

fn bench(n: usize) -> Bench {
    let dir = tempfile::tempdir().unwrap();
    Bench {
        journal: dir.path().join("job.journal"),
        job: Job::parse(&strokes(n)).unwrap(),
        _dir: dir,
    }
}

/// A board that keeps running and keeps its position through reconnects.
fn keeping_sim(faults: Faults) -> PtySim {
    PtySim::spawn_with_dtr_reset(
        SimConfig::default()
            .with_time_scale(8.0)
            .with_faults(faults),
        false,
    )
    .expect("spawn firmware-sim")
}

#[test]
fn hangup_while_moving_then_reconnect_resumes_exactly() {
    let b = bench(120);
    let sim = keeping_sim(Faults {
        hangup_at_line: Some(70),
        ..Faults::default()
    });
    let e = send(
        sim.path(),
        &b.job,
        &opts(&b.journal),
        &CancelToken::new(),
        None,
    )
    .unwrap_err();
    assert!(matches!(e, SendError::Transport { .. }), "{e}");
    let st = Journal::read(&b.journal).unwrap();
    assert!(
        !st.unconfirmed.is_empty(),
        "the hang-up left acknowledged lines unconfirmed"
    );
    // The device re-enumerates on a new path; the controller kept running meanwhile.
    let t0 = Instant::now();
    while sim.replugs() == 0 && t0.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let rep = send(
        &sim.current_path(),
        &b.job,
        &opts(&b.journal).with_resume(true),
        &CancelToken::new(),
        None,
    )
    .unwrap_or_else(|e| panic!("resume failed: {e}"));
    assert!(
        rep.previously_done > st.done_count(),
        "the position settled the doubt"
    );
    let report = sim.stop();
    assert_job_exactly_once(&b.job, &report.trace);
    assert!(Journal::read(&b.journal).unwrap().finished);
}

#[test]
fn feed_hold_and_reset_resume_completes_the_line_in_progress() {
    let b = bench(80);
    let sim = keeping_sim(Faults::default());
    let cancel = CancelToken::new();
    let e = send(sim.path(), &b.job, &opts(&b.journal), &cancel, Some(30)).unwrap_err();
    assert!(matches!(e, SendError::Aborted { .. }), "{e}");
    let st = Journal::read(&b.journal).unwrap();
    assert!(st.unconfirmed.is_empty(), "hold + reset leaves no doubt");
    assert!(
        st.partial.is_some(),
        "the hold stopped inside a line (braking spans several)"
    );
    let rep = send(
        sim.path(),
        &b.job,
        &opts(&b.journal).with_resume(true),
        &CancelToken::new(),
        None,
    )
    .unwrap_or_else(|e| panic!("resume failed: {e}"));
    assert_eq!(rep.previously_done, st.done_count());
    let report = sim.stop();
    assert_eq!(
        report.stats.alarms, 0,
        "a reset after the hold came to rest is no alarm"
    );
    assert_job_exactly_once(&b.job, &report.trace);
}

#[test]
fn reset_in_motion_requires_an_explicit_resume_point() {
    let b = bench(80);
    let sim = keeping_sim(Faults {
        reset_at_line: Some(50),
        ..Faults::default()
    });
    let e = send(
        sim.path(),
        &b.job,
        &opts(&b.journal),
        &CancelToken::new(),
        None,
    )
    .unwrap_err();
    assert!(matches!(e, SendError::Alarm { code: 3, .. }), "{e}");
    let run1 = sim.trace();
    let st = Journal::read(&b.journal).unwrap();
    let (a, z) = st.uncertain.expect("the journal names the lines in doubt");
    // The line the reset cut short is in the range named.
    let cut = run1.last().unwrap();
    let k = (0..b.job.len())
        .find(|&i| b.job.lines[i].text == cut.text)
        .unwrap();
    assert!(
        !close(cut.to, b.job.end_of(k)),
        "the reset stopped line {k} part-way"
    );
    assert!((a..=z).contains(&k), "{k} not in {a}..={z}");

    // Resuming without a choice refuses and says which lines are in doubt.
    let o = opts(&b.journal).with_resume(true).with_unlock(true);
    let e = send(sim.path(), &b.job, &o, &CancelToken::new(), None).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, SendError::ResumeUncertain { .. }), "{msg}");
    assert!(
        msg.contains("ALARM:3") && msg.contains("resume explicitly from the first line"),
        "{msg}"
    );
    assert!(
        msg.contains(&format!(
            "Lines {} to {}",
            b.job.lines[a].source_line, b.job.lines[z].source_line
        )),
        "{msg}"
    );
    assert_eq!(sim.trace().len(), run1.len(), "nothing moved");

    // The operator saw line k cut short, and that the machine stands where it did: resume
    // from it (the reset in motion lost the position, so the origin needs the operator's word).
    let rep = send(
        sim.path(),
        &b.job,
        &o.clone()
            .with_resume_from(Some(k))
            .with_origin_confirmed(true),
        &CancelToken::new(),
        None,
    )
    .unwrap_or_else(|e| panic!("resume from {k} failed: {e}"));
    assert_eq!(rep.previously_done, k);
    let all = sim.stop().trace;
    // Run 1 up to the interrupted fragment, then run 2 from line k (after its travel there).
    let mut joinedtrace: Vec<TraceSegment> = run1[..run1.len() - 1].to_vec();
    let run2 = &all[run1.len()..];
    let from_k = run2
        .iter()
        .position(|s| s.text == b.job.lines[k].text)
        .expect("line k ran again");
    joinedtrace.extend_from_slice(&run2[from_k..]);
    assert_job_exactly_once(&b.job, &joinedtrace);
}

/// How many times each job motion drawn with the tool on (pen down) ran over the trace, a line
/// stopped part-way and completed later counted once; the lines cut twice, and the drawing lines
/// never cut.
fn cut_counts(job: &Job, trace: &[TraceSegment]) -> (Vec<(String, usize)>, Vec<String>) {
    let joined = flatcut_testkit::trace::joined(trace);
    let mut twice = Vec::new();
    let mut uncut = Vec::new();
    for (text, from, to) in job.motions() {
        if close(from, to) || !text.starts_with("G1 X") && !text.starts_with("G1X") {
            continue;
        }
        let n = joined
            .iter()
            .filter(|s| s.tool_on && s.text == text && close(s.to, to))
            .count();
        match n {
            0 => uncut.push(text),
            1 => {}
            _ => twice.push((text, n)),
        }
    }
    (twice, uncut)
}

/// A fast machine that brakes gently (3000 mm/min, 20 mm/s²) at 16× real time: short chords at
/// F2400 run many a line while the sender does not read, and stopping takes several of them.
fn braking_sim() -> PtySim {
    let mut cfg = SimConfig::default().with_time_scale(16.0);
    for axis in 0..2 {
        cfg = cfg
            .with_setting(110 + axis, 3000.0)
            .with_setting(120 + axis, 20.0);
    }
    PtySim::spawn_with_dtr_reset(cfg, false).expect("spawn firmware-sim")
}

/// A stop while running, with answers on their way: every line the controller ran before it
/// stood still is journaled as executed (its `ok` read or not), so the resume continues where the
/// machine stands. Over both runs, firmware-sim's trace cuts every drawing line exactly once.
#[test]
fn stop_with_answers_in_flight_resumes_without_cutting_twice() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("job.journal");
    let job = Job::parse(&jobs::pattern_job(3)).unwrap();
    let sim = braking_sim();
    // The sender stops reading for a while (a loaded host), the controller runs on and answers
    // into the link; then the operator stops the job, before those answers are read.
    let cancel = CancelToken::new();
    let c = cancel.clone();
    let e = send_with(sim.path(), &job, &opts(&journal), &cancel, &mut |p| {
        if p.lines_acked >= 90 && !c.is_aborted() {
            std::thread::sleep(Duration::from_millis(400));
            c.abort();
        }
    })
    .unwrap_err();
    assert!(matches!(e, SendError::Aborted { .. }), "{e}");
    let st = Journal::read(&journal).unwrap();
    let (k, _) = st
        .partial
        .expect("the stop is journaled where the machine stands");
    let open: Vec<usize> = (0..k).filter(|&i| !st.done[i]).collect();
    let rep = send(
        sim.path(),
        &job,
        &opts(&journal).with_resume(true),
        &CancelToken::new(),
        None,
    )
    .unwrap_or_else(|e| panic!("resume failed: {e}"));
    let trace = sim.stop().trace;
    let (twice, uncut) = cut_counts(&job, &trace);
    assert!(twice.is_empty(), "cut twice: {twice:?}");
    assert!(uncut.is_empty(), "never cut: {uncut:?}");
    assert_job_exactly_once(&job, &trace);
    assert!(
        open.is_empty(),
        "lines before the stop at {k} not journaled as run: {open:?}"
    );
    assert_eq!(rep.previously_done, k);
}

/// A pen plotter's three strokes, the pen a servo (`M3 S1000` down, `M3 S0` up, a dwell while it
/// moves), the third starting on the first, as letters do: where the machine waits for the pen
/// over the third stroke's start, the job's path passes twice.
const CROSSING: &str = "G21 G90 G17\nM3 S0\nG4 P0.15\nG0 X10 Y10\nM3 S1000\nG4 P0.150\n\
G1 X10 Y20 F2000\nM3 S0.0\nG4 P0.1500\nG0 X30 Y30\nM3 S1000.00\nG4 P0.15000\nG1 X40 Y30\n\
M3 S0.000\nG4 P0.150000\nG0 X10 Y15\nM3 S1000.0\nG4 P4.0\nG1 X20 Y15\nM3 S0.00\n\
G4 P0.1500000\nG0 X0 Y0\n";

/// A closed square whose pen waits (`G4 P4`) at its first corner, which is also its last.
const CLOSED_SQUARE: &str = "G21 G90 G17\nM3 S0\nG4 P0.15\nG0 X10 Y10\nM3 S1000\nG4 P4.0\n\
G1 X20 Y10 F2000\nG1 X20 Y20\nG1 X10 Y20\nG1 X10 Y10\nM3 S0.0\nG4 P0.15\nG0 X0 Y0\n";

/// The operator stops while the pen waits at the start of a closed square, every line of the
/// square already sent: the machine stands where the square also ends, but GRBL parses nothing
/// after the unanswered dwell, so the journal records the stop at the dwell (`P`), not a place
/// in doubt, and the resume cuts the square once.
#[test]
fn a_stop_during_a_dwell_at_a_closed_strokes_start_is_not_in_doubt() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("job.journal");
    let job = Job::parse(CLOSED_SQUARE).unwrap();
    let sim = plotter_sim();
    let pen_down = line_index(&job, "M3S1000");
    let st = stop_after_pen_down(&sim, &job, &journal, pen_down, false);
    let (k, at) = st
        .partial
        .expect("the stop is journaled where the machine stands");
    assert!(close(at, [10.0, 10.0, 0.0]), "{at:?}");
    assert!(
        k <= pen_down + 1,
        "stopped at line {k}, the dwell is {}",
        pen_down + 1
    );
    resume_cutting_each_stroke_once(sim, &job, &journal, k);
}

/// The operator pauses while the machine waits for the pen at the third stroke's start (a point
/// the first stroke passed), then stops. The controller answered the pen's `M3` only once the
/// motion before it had finished, so the journal knows where the machine stands: the stop is
/// recorded there (`P`), and the resume continues without a question; over both runs,
/// firmware-sim's trace cuts each stroke once.
#[test]
fn pause_then_stop_where_the_path_passes_twice_is_journaled_and_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("job.journal");
    let job = Job::parse(CROSSING).unwrap();
    let sim = plotter_sim();
    let pen_down = line_index(&job, "M3S1000.0");
    let st = stop_after_pen_down(&sim, &job, &journal, pen_down, true);
    let (k, at) = st
        .partial
        .expect("the stop is journaled where the machine stands");
    assert!(close(at, [10.0, 15.0, 0.0]), "{at:?}");
    assert!((0..k).all(|i| st.done[i]), "{:?}", st.done);
    resume_cutting_each_stroke_once(sim, &job, &journal, k);
}

/// firmware-sim with a plotter's rates (as the lampshade's profile), at 4× real time.
fn plotter_sim() -> PtySim {
    let mut cfg = SimConfig::default().with_time_scale(4.0);
    for axis in 0..2 {
        cfg = cfg
            .with_setting(110 + axis, 6000.0)
            .with_setting(120 + axis, 500.0);
    }
    PtySim::spawn_with_dtr_reset(cfg, false).expect("spawn firmware-sim")
}

/// The index of the job line whose text is `text`.
fn line_index(job: &Job, text: &str) -> usize {
    job.lines.iter().position(|l| l.text == text).unwrap()
}

/// Streams `job` and, 300 ms after the pen-down line `pen_down` was answered, stops it (after a
/// feed hold when `hold`); the stop must leave no place in doubt. Returns the journal.
fn stop_after_pen_down(
    sim: &PtySim,
    job: &Job,
    journal: &Path,
    pen_down: usize,
    hold: bool,
) -> flatcut_grbl::JournalState {
    let cancel = CancelToken::new();
    let c = cancel.clone();
    let mut seen: Option<Instant> = None;
    let e = send_with(sim.path(), job, &opts(journal), &cancel, &mut |p| {
        if seen.is_none() && p.lines_acked > pen_down {
            if hold {
                c.hold();
            }
            seen = Some(Instant::now());
        }
        if seen.is_some_and(|t| t.elapsed() > Duration::from_millis(300)) {
            c.abort();
        }
    })
    .unwrap_err();
    assert!(matches!(e, SendError::Aborted { .. }), "{e}");
    let st = Journal::read(journal).unwrap();
    assert_eq!(st.uncertain, None, "{:?}", st.notes);
    st
}

/// Resumes `job` from its journal, which says `k` lines ran; over both runs firmware-sim's trace
/// cuts every stroke once and runs the job's motions exactly once.
fn resume_cutting_each_stroke_once(sim: PtySim, job: &Job, journal: &Path, k: usize) {
    let rep = send(
        sim.path(),
        job,
        &opts(journal).with_resume(true),
        &CancelToken::new(),
        None,
    )
    .unwrap_or_else(|e| panic!("resume failed: {e}"));
    assert_eq!(rep.previously_done, k);
    let trace = sim.stop().trace;
    let (twice, uncut) = cut_counts(job, &trace);
    assert!(twice.is_empty(), "cut twice: {twice:?}");
    assert!(uncut.is_empty(), "never cut: {uncut:?}");
    assert_job_exactly_once(job, &trace);
}

/// A board that keeps running after the host dies, accelerating briskly (200 mm/s²) at 16×
/// real time: a stroke of the zigzag takes about 15 ms, so the job runs in seconds.
fn crash_sim() -> PtySim {
    let mut cfg = SimConfig::default().with_time_scale(32.0);
    for axis in 0..2 {
        cfg = cfg.with_setting(120 + axis, 200.0);
    }
    PtySim::spawn_with_dtr_reset(cfg, false).expect("spawn firmware-sim")
}

/// How many times each job motion ran over the trace (each has its own text here): the lines run
/// more than once, and those never run.
fn run_counts(job: &Job, trace: &[TraceSegment]) -> (Vec<(String, usize)>, Vec<String>) {
    let (mut twice, mut never) = (Vec::new(), Vec::new());
    for (text, _, to) in job.motions() {
        let n = trace
            .iter()
            .filter(|s| s.text == text && close(s.to, to))
            .count();
        match n {
            0 => never.push(text),
            1 => {}
            _ => twice.push((text, n)),
        }
    }
    (twice, never)
}

/// Environment of the sender process [`crash_sender`] runs as: the simulator's device path,
/// the job file and the journal.
const CRASH_ENV: [&str; 3] = [
    "FLATCUT_CRASH_PORT",
    "FLATCUT_CRASH_JOB",
    "FLATCUT_CRASH_JOURNAL",
];

/// The sender that [`a_sender_killed_mid_stream_never_resumes_from_a_place_it_does_not_know`]
/// kills: this test binary run again with [`CRASH_ENV`] set. It streams the job and never
/// returns on its own before the job is done.
#[test]
#[ignore = "the sender process of the crash test, run by it"]
fn crash_sender() {
    let [port, job, journal] = CRASH_ENV.map(|k| std::env::var(k).expect(k));
    let job = Job::parse(&std::fs::read_to_string(job).unwrap()).unwrap();
    let _ = send(
        Path::new(&port),
        &job,
        &opts(Path::new(&journal)),
        &CancelToken::new(),
        None,
    );
}

/// The host dies mid-stream (SIGKILL, as a crash or a power cut would) while a real GRBL keeps
/// running what its RX buffer and planner hold: firmware-sim on a pseudo-terminal, the sender
/// a separate process killed after `kill_after` lines reached the controller, with journal
/// records still in its buffer. The simulator finishes on its own; then `--resume` either
/// completes the job with every motion run exactly once, or refuses naming the lines in doubt,
/// and a resume from the line the operator names (the first one the workpiece shows undone)
/// completes it. Returns the number of drawing motions cut twice and never cut.
fn crash_and_resume(kill_after: u32) -> (usize, usize) {
    let text = jobs::zigzag(160, 0.1, 1.0, 1200.0);
    let dir = tempfile::tempdir().unwrap();
    let b = Bench {
        journal: dir.path().join("job.journal"),
        job: Job::parse(&text).unwrap(),
        _dir: dir,
    };
    let job_path = b.journal.with_extension("gcode");
    std::fs::write(&job_path, text).unwrap();
    let sim = crash_sim();
    let mut child = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "crash_sender", "--ignored", "--nocapture"])
        .env(CRASH_ENV[0], sim.path())
        .env(CRASH_ENV[1], &job_path)
        .env(CRASH_ENV[2], &b.journal)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start the sender");
    let t0 = Instant::now();
    while sim.lines_received() < kill_after {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the sender never got going"
        );
        std::thread::sleep(Duration::from_micros(200));
    }
    child.kill().expect("SIGKILL the sender");
    child.wait().unwrap();
    // The controller runs on: wait until it has run everything it was given.
    let mut seen = (sim.trace().len(), Instant::now());
    while seen.1.elapsed() < Duration::from_millis(400) {
        std::thread::sleep(Duration::from_millis(50));
        let n = sim.trace().len();
        if n != seen.0 {
            seen = (n, Instant::now());
        }
    }
    let ran_before = sim.trace();
    let resumed = send(
        sim.path(),
        &b.job,
        &opts(&b.journal).with_resume(true),
        &CancelToken::new(),
        None,
    );
    let trace = match resumed {
        Ok(_) => sim.stop().trace,
        Err(SendError::ResumeUncertain { from, to, reason }) => {
            assert!(from.index <= to.index, "{reason}");
            // The operator looks at the work and names the first stroke not drawn.
            let done = flatcut_testkit::trace::joined(&ran_before).len();
            let named = b
                .job
                .lines
                .iter()
                .enumerate()
                .filter(|(_, l)| l.moves)
                .nth(done)
                .map(|(i, _)| i)
                .expect("a line still to run");
            assert!(
                (from.index..=to.index + 1).contains(&named),
                "the lines in doubt {}..={} do not hold the line the machine stands at ({named}): {reason}",
                from.index,
                to.index
            );
            send(
                sim.path(),
                &b.job,
                &opts(&b.journal)
                    .with_resume(true)
                    .with_resume_from(Some(named)),
                &CancelToken::new(),
                None,
            )
            .unwrap_or_else(|e| panic!("resume from line {named} failed: {e}"));
            sim.stop().trace
        }
        Err(e) => panic!("the resume after a crash failed otherwise: {e}"),
    };
    let (twice, uncut) = run_counts(&b.job, &trace);
    eprintln!("killed after {kill_after} lines: cut twice {twice:?}, never cut {uncut:?}");
    if twice.is_empty() && uncut.is_empty() {
        assert_job_exactly_once(&b.job, &trace);
    }
    (twice.len(), uncut.len())
}

#[test]
fn a_sender_killed_mid_stream_never_resumes_from_a_place_it_does_not_know() {
    // Lines the controller received (a dozen are the handshake's) when the sender dies: once
    // with the planner and RX buffer full mid-job, once near the end. Where the journal ends is
    // up to the scheduler here; the journals a death can leave are each taken in turn, without
    // timing, by `a_killed_senders_unflushed_answers_are_settled_from_the_position_not_resent`.
    let found: Vec<(u32, (usize, usize))> = [61, 140]
        .into_iter()
        .map(|k| (k, crash_and_resume(k)))
        .collect();
    assert!(
        found.iter().all(|(_, (twice, uncut))| twice + uncut == 0),
        "(lines received when killed, (motions cut twice, never cut)): {found:?}"
    );
}

/// The journal a sender killed mid-stream leaves, built from `full`, the journal of a run that
/// streamed the first lines of `job` to completion: `job`'s header (the run's own job was that
/// prefix), then the run's records up to its first `X` confirming line `from` or later, then of
/// the rest only the `W` marks, which reach the OS before their lines' bytes do; the answers and
/// confirmations behind that `X` were still in the dead process's buffer. With
/// `answers_lost_too`, the answers before the `X` that it does not cover are dropped as well
/// (they were in the buffer too), so the journal confirms every answer it holds. Returns the
/// line the kept `X` confirms.
fn journal_of_a_killed_sender(
    full: &str,
    job: &Job,
    journal: &Path,
    from: usize,
    answers_lost_too: bool,
) -> usize {
    drop(Journal::create(journal, job).unwrap());
    let head: Vec<String> = std::fs::read_to_string(journal)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("R "))
        .map(String::from)
        .collect();
    let body: Vec<&str> = full
        .lines()
        .filter(|l| !l.starts_with("flatcut-journal") && !l.starts_with("T "))
        .collect();
    let index = |rec: &str, kind: &str| -> Option<usize> {
        rec.strip_prefix(kind).map(|i| i.trim().parse().unwrap())
    };
    let (at, x) = body
        .iter()
        .enumerate()
        .find_map(|(n, r)| index(r, "X ").filter(|&x| x >= from).map(|x| (n, x)))
        .expect("the run confirmed lines as it went");
    let kept = body.iter().enumerate().filter(|&(n, r)| {
        if n > at {
            r.starts_with("W ")
        } else {
            !answers_lost_too || index(r, "A ").is_none_or(|i| i <= x)
        }
    });
    let text: String = head
        .iter()
        .map(String::as_str)
        .chain(kept.map(|(_, r)| *r))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(journal, text).unwrap();
    x
}

/// firmware-sim runs the first `m` lines of a zigzag (the lines a sender wrote before it was
/// killed) to the end; the journal the sender left ([`journal_of_a_killed_sender`]) confirms
/// lines only up to `x`, well before `m`. The resume must not send lines `x + 1..m` again: it
/// settles them from the machine's position, or refuses naming a range that holds them (then the
/// operator resumes from line `m`). Over both runs the simulator's trace must run every motion
/// exactly once. Returns how the resume went.
fn resume_after_a_killed_sender(answers_lost_too: bool) -> String {
    let text = jobs::zigzag(120, 0.1, 1.0, 1200.0);
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("job.journal");
    let job = Job::parse(&text).unwrap();
    let m = 100;
    let written: String = text.lines().take(m).map(|l| format!("{l}\n")).collect();
    let prefix = Job::parse(&written).unwrap();
    assert_eq!(prefix.len(), m);
    let sim = crash_sim();
    let run = dir.path().join("run.journal");
    send(sim.path(), &prefix, &opts(&run), &CancelToken::new(), None)
        .unwrap_or_else(|e| panic!("streaming the lines written failed: {e}"));
    let ran_before = sim.trace();
    let full = std::fs::read_to_string(&run).unwrap();
    let x = journal_of_a_killed_sender(&full, &job, &journal, 30, answers_lost_too);
    assert!(
        x + 20 < m,
        "the kept confirmation {x} is not well before line {m}"
    );
    let resumed = send(
        sim.path(),
        &job,
        &opts(&journal).with_resume(true),
        &CancelToken::new(),
        None,
    );
    let (how, trace) = match resumed {
        Ok(rep) => {
            let how = format!("resumed from line {}", rep.previously_done);
            (how, sim.stop().trace)
        }
        Err(SendError::ResumeUncertain { from, to, reason }) => {
            assert!(
                from.index <= x + 1 && to.index + 1 >= m,
                "confirmed through line {x}, ran through line {}: the lines in doubt {}..={} do not hold them all: {reason}",
                m - 1,
                from.index,
                to.index,
            );
            assert_eq!(sim.trace().len(), ran_before.len(), "nothing moved");
            send(
                sim.path(),
                &job,
                &opts(&journal).with_resume(true).with_resume_from(Some(m)),
                &CancelToken::new(),
                None,
            )
            .unwrap_or_else(|e| panic!("resume from line {m} failed: {e}"));
            let how = format!("refused naming lines {}..={}", from.index, to.index);
            (how, sim.stop().trace)
        }
        Err(e) => panic!("the resume failed otherwise: {e}"),
    };
    let (twice, never) = run_counts(&job, &trace);
    let span = |v: Vec<String>| match (v.first(), v.last()) {
        (Some(a), Some(b)) => format!("{} motions, {a} to {b}", v.len()),
        _ => "none".to_string(),
    };
    assert!(
        twice.is_empty() && never.is_empty(),
        "confirmed through line {x}, ran through line {}, {how}: run twice {}, never run {}",
        m - 1,
        span(twice.into_iter().map(|(t, _)| t).collect()),
        span(never),
    );
    assert_job_exactly_once(&job, &trace);
    format!("confirmed through line {x}: {how}")
}

/// The host dies with answers read but their records unflushed while the controller runs on
/// through what it was written, in both shapes of journal that leaves: every answer journaled is
/// confirmed (a resume that trusted it would send the lines run since again), or some are not
/// (one that looked only one RX buffer past them would not find the machine). Deterministic: the
/// simulator runs the lines written to their end, no process is killed, nothing is timed.
#[test]
fn a_killed_senders_unflushed_answers_are_settled_from_the_position_not_resent() {
    for answers_lost_too in [true, false] {
        let how = resume_after_a_killed_sender(answers_lost_too);
        eprintln!("answers before the confirmation lost too: {answers_lost_too}: {how}");
    }
}
