//! Exact resume over a real pseudo-terminal, on a controller that keeps its position across
//! reconnects (firmware-sim with DTR auto-reset off): a hang-up while moving, a feed hold followed
//! by a soft reset, and a reset in motion (ALARM:3). In each case the simulator's trace over all
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
