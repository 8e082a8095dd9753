//! The shop-floor cases of issue 39 on firmware-sim: a restart the handshake did not see must
//! never be resumed from (A: a banner later than the sender's wait; B: a power cycle while the
//! port was closed), and a program pause is acted on where the controller reached it, so the
//! resume after it cuts nothing twice (C).

use flatcut_firmware_sim::{PtySim, SimConfig, TraceSegment};
use flatcut_grbl::{CancelToken, Job, Journal, PausePolicy, SendError, SendOptions};
use flatcut_testkit::pty::send_with;
use flatcut_testkit::trace::{assert_job_exactly_once, close};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Strokes of a pen plotter at F1200, each at its own place, long enough that the job is still
/// running when it is stopped.
fn strokes(n: usize) -> String {
    flatcut_testkit::jobs::zigzag(n, 0.2, 4.0, 1200.0)
}

fn opts(journal: &Path) -> SendOptions {
    SendOptions::default()
        .with_silence_timeout(Duration::from_secs(8))
        .with_journal(journal)
}

/// Sends `job` to `path`, aborting once `abort_after` lines were acknowledged.
fn send(
    path: &Path,
    job: &Job,
    o: &SendOptions,
    abort_after: Option<usize>,
) -> Result<flatcut_grbl::SendReport, SendError> {
    let cancel = CancelToken::new();
    let c = cancel.clone();
    send_with(path, job, o, &cancel, &mut |p| {
        if abort_after.is_some_and(|n| p.lines_acked >= n) {
            c.abort();
        }
    })
}

/// A journal in a directory that lives as long as the test.
struct Bench {
    _dir: tempfile::TempDir,
    journal: PathBuf,
}

fn bench() -> Bench {
    let dir = tempfile::tempdir().unwrap();
    Bench {
        journal: dir.path().join("job.journal"),
        _dir: dir,
    }
}

/// Waits until the simulator's trace stops growing (the machine came to rest).
fn settled(sim: &PtySim) -> Vec<TraceSegment> {
    let mut last = usize::MAX;
    let t0 = Instant::now();
    loop {
        let t = sim.trace();
        if t.len() == last || t0.elapsed() > Duration::from_secs(10) {
            return t;
        }
        last = t.len();
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// Case A: the controller restarts as the port opens (an Uno's DTR) but its banner comes 3 s
/// later (a slow bootloader), after the sender's boot wait (1 s here). The resume does not
/// continue from the zeroed position: with nobody to confirm the origin it refuses, nothing
/// moved.
#[test]
fn case_a_a_late_banner_is_a_restart() {
    let b = bench();
    let job = Job::parse(&strokes(80)).unwrap();
    let sim = PtySim::spawn(SimConfig::default().with_time_scale(8.0).with_boot_ms(3000)).unwrap();
    let e = send(sim.path(), &job, &opts(&b.journal), Some(40)).unwrap_err();
    assert!(matches!(e, SendError::Aborted { .. }), "{e}");
    let ran = settled(&sim).len();
    assert!(Journal::read(&b.journal).unwrap().done_count() > 0);
    // A boot wait shorter than the bootloader: the banner comes after it.
    let o = opts(&b.journal)
        .with_resume(true)
        .with_banner_timeout(Duration::from_millis(1000));
    let resumed = send(sim.path(), &job, &o, None);
    let e = resumed.expect_err("a resume from the zeroed position");
    assert!(
        matches!(&e, SendError::PositionUnknown { why } if why.contains("restarted")),
        "{e}: the controller restarted when the port opened"
    );
    assert_eq!(
        sim.trace().len(),
        ran,
        "the refused resume moved the machine"
    );
    sim.stop();
}

/// Case B: the job is stopped, and the machine loses power (or is reset by hand) while nothing
/// is connected: a board with auto-reset off, so no banner greets the next connection. The
/// journal's stop record (machine position, offsets, parser state) does not match the
/// controller's, so the resume refuses without the operator's word, nothing moved; with it,
/// the job completes.
#[test]
fn case_b_a_restart_while_the_port_was_closed_is_seen() {
    let b = bench();
    let job = Job::parse(&strokes(80)).unwrap();
    let sim = PtySim::spawn(
        SimConfig::default()
            .with_time_scale(8.0)
            .with_dtr_reset(false),
    )
    .unwrap();
    let e = send(sim.path(), &job, &opts(&b.journal), Some(40)).unwrap_err();
    assert!(matches!(e, SendError::Aborted { .. }), "{e}");
    let ran = settled(&sim).len();
    sim.power_cycle();
    std::thread::sleep(Duration::from_millis(300));
    let resumed = send(sim.path(), &job, &opts(&b.journal).with_resume(true), None);
    let e = resumed.expect_err("a resume from the zeroed position");
    assert!(matches!(e, SendError::PositionUnknown { .. }), "{e}");
    assert!(e.to_string().contains("machine position"), "{e}");
    assert_eq!(
        sim.trace().len(),
        ran,
        "the refused resume moved the machine"
    );
    let o = opts(&b.journal)
        .with_resume(true)
        .with_origin_confirmed(true);
    send(sim.path(), &job, &o, None).unwrap_or_else(|e| panic!("{e}"));
    assert!(Journal::read(&b.journal).unwrap().finished);
    sim.stop();
}

/// A pen plotter's square, a program pause (`M0`), and a second square: every line with its own
/// text.
const SQUARES: &str = "G21 G90\nG0 Z2\nG0 X10 Y10\nG1 Z-1 F300\nG1 X40 F1200\nG1 Y40\nG1 X10\n\
G1 Y10.000\nG0 Z2.0\nM0\nG0 X50 Y10\nG1 Z-1.0 F300\nG1 X80 F1200\nG1 Y40.0\nG1 X50\nG1 Y10.0\n\
G0 Z2.00\nG0 X0 Y0\n";

/// Case C: a square, `M0`, a second square. Without an operator the pause aborts the run, but
/// only once the controller reached it (the whole first square cut, the machine at rest): the
/// abort leaves the tool off and the position known (no reset in motion), the journal counts
/// every line before the pause as executed, and the resume continues after the pause with
/// nothing cut twice.
#[test]
fn case_c_a_program_pause_is_acted_on_where_it_is_and_nothing_is_cut_twice() {
    let b = bench();
    let job = Job::parse(SQUARES).unwrap();
    let pause = job.lines.iter().position(|l| l.text == "M0").unwrap();
    // A board that keeps its position, at 4× real time: the M0 arrives while the square is cut.
    let sim = PtySim::spawn(
        SimConfig::default()
            .with_time_scale(4.0)
            .with_dtr_reset(false),
    )
    .unwrap();
    let o = opts(&b.journal).with_on_pause(PausePolicy::Abort);
    let e = send(sim.path(), &job, &o, None).unwrap_err();
    assert!(
        matches!(&e, SendError::PausedByJob { line, .. } if line.index == pause),
        "{e}"
    );
    let first = settled(&sim);
    // The first square whole, nothing of the second; no reset in motion.
    let cut = |t: &[TraceSegment], text: &str| t.iter().filter(|s| s.text == text).count();
    for edge in ["G1X40F1200", "G1Y40", "G1X10", "G1Y10.000"] {
        assert_eq!(cut(&first, edge), 1, "{edge}: {first:?}");
    }
    assert_eq!(cut(&first, "G1X80F1200"), 0);
    let st = Journal::read(&b.journal).unwrap();
    assert!(
        st.done[..=pause].iter().all(|d| *d) && !st.done[pause + 1..].iter().any(|d| *d),
        "journaled as done: {:?}",
        st.done
    );
    assert!(
        !st.notes.iter().any(|n| n.starts_with("ALARM")),
        "{:?}",
        st.notes
    );
    let here = first.last().unwrap().to;
    assert!(close(here, [10.0, 10.0, 2.0]), "stopped at {here:?}");
    // The resume continues after the pause: the position is known, nothing is cut twice.
    let o = opts(&b.journal)
        .with_resume(true)
        .with_on_pause(PausePolicy::Resume);
    send(sim.path(), &job, &o, None).unwrap_or_else(|e| panic!("{e}"));
    let all = settled(&sim);
    for edge in ["G1X40F1200", "G1Y40", "G1X10", "G1Y10.000"] {
        assert_eq!(cut(&all, edge), 1, "{edge} cut twice");
    }
    assert_job_exactly_once(&job, &all);
    sim.stop();
}
