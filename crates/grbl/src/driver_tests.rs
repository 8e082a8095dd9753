//! Driver tests against the scripted in-memory device.

use super::*;
use crate::fake::FakeGrbl;
use crate::journal::Journal;

fn zigzag(n: usize) -> String {
    let mut s = String::from("G21 G90\nG0 Z1\nG0 X0 Y0\nG1 Z-0.5 F300\n");
    for i in 1..=n {
        s.push_str(&format!(
            "G1 X{:.1} Y{} F3000\n",
            i as f64 * 0.5,
            (i % 2) * 5
        ));
    }
    s.push_str("G0 Z2\n");
    s
}

fn fast() -> SendOptions {
    SendOptions::default()
        .with_banner_timeout(Duration::from_millis(100))
        .with_status_interval(Duration::from_millis(5))
        .with_idle_ack_timeout(Duration::from_millis(100))
        .with_silence_timeout(Duration::from_secs(2))
        .with_progress_interval(Duration::ZERO)
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flatcut-grbl-driver-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    let _ = std::fs::remove_file(&p);
    p
}

/// Job lines executed by the device, as job indices (texts of the job are unique where used).
fn job_indices(job: &Job, executed: &[String]) -> Vec<usize> {
    executed
        .iter()
        .filter_map(|t| job.lines.iter().position(|l| &l.text == t))
        .collect()
}

fn assert_exactly_once(job: &Job, runs: &[&[String]]) {
    // Lines whose text is unique in the job (and never written by a resume preamble) must run
    // exactly once over all runs.
    let preamble: std::collections::BTreeSet<String> = (1..job.len())
        .flat_map(|k| job.resume_preamble(k))
        .collect();
    for (i, l) in job.lines.iter().enumerate() {
        if job.lines.iter().filter(|m| m.text == l.text).count() != 1 || preamble.contains(&l.text)
        {
            continue;
        }
        let n: usize = runs
            .iter()
            .map(|r| r.iter().filter(|t| **t == l.text).count())
            .sum();
        assert_eq!(n, 1, "job line {i} `{}` ran {n} times", l.text);
    }
}

#[test]
fn streams_a_long_job_in_order_within_the_rx_buffer() {
    let job = Job::parse(&zigzag(2000)).unwrap();
    let mut dev = FakeGrbl::new(true);
    dev.settings.push((130, 2000.0));
    let mut calls = 0;
    let mut last = None;
    let rep = send_job(
        &mut dev,
        &job,
        &fast(),
        &mut |p| {
            calls += 1;
            last = Some(p.clone());
        },
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(
        job_indices(&job, &dev.executed),
        (0..job.len()).collect::<Vec<_>>()
    );
    assert_eq!(dev.dropped, 0);
    assert!(dev.max_rx_fill <= 128, "{}", dev.max_rx_fill);
    // The buffer was really used: several lines in flight at once.
    assert!(rep.max_in_flight_bytes > 100, "{}", rep.max_in_flight_bytes);
    assert_eq!(rep.rx_size, 128);
    assert_eq!(rep.planner_blocks, 15);
    assert_eq!(rep.lines_sent, job.len());
    assert_eq!(rep.version, "1.1h");
    assert_eq!(rep.settings.get(&110), Some(&5000.0));
    assert!(calls >= 2);
    let p = last.unwrap();
    assert_eq!(p.phase, Phase::Done);
    assert_eq!(p.fraction(), 1.0);
    assert_eq!(rep.final_position, Some([1000.0, 0.0, 2.0]));
    // Nothing but `\n` terminators.
    assert!(dev.received.iter().all(|l| !l.contains('\r')));
}

#[test]
fn soft_reset_when_no_banner_arrives() {
    let job = Job::parse("G0X1\n").unwrap();
    let mut dev = FakeGrbl::new(false);
    send_job(&mut dev, &job, &fast(), &mut |_| {}, &CancelToken::new()).unwrap();
    // It first asks whether the controller is moving (a reset then would lose position).
    assert_eq!(dev.realtime_log.first(), Some(&b'?'));
    assert_eq!(dev.realtime_log.iter().find(|&&b| b != b'?'), Some(&0x18));
    // The work frame is read before the reset clears it, and again after.
    assert_eq!(dev.received[..6], ["$#", "$G", "$I", "$$", "$#", "$G"]);
}

#[test]
fn alarm_lock_needs_unlock_permission() {
    let job = Job::parse("G0X1\n").unwrap();
    let mut dev = FakeGrbl::new(false).start_locked();
    let err = send_job(&mut dev, &job, &fast(), &mut |_| {}, &CancelToken::new()).unwrap_err();
    assert!(matches!(err, SendError::AlarmLocked { .. }), "{err}");
    assert!(
        err.to_string().contains("unlocking it was not allowed"),
        "{err}"
    );
    // The library states the condition; the command line names its flags.
    assert!(!err.to_string().contains("--"), "{err}");
    assert!(dev.executed.is_empty());
    let mut dev = FakeGrbl::new(false).start_locked();
    send_job(
        &mut dev,
        &job,
        &fast().with_unlock(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    assert!(dev.received.contains(&"$X".to_string()));
    assert_eq!(dev.executed, vec!["G0X1".to_string()]);
}

#[test]
fn refuses_a_job_larger_than_the_travel() {
    let job = Job::parse("G0X0Y0\nG1X150Y10F1000\n").unwrap();
    let mut dev = FakeGrbl::new(true);
    dev.settings.push((130, 100.0));
    let err = send_job(&mut dev, &job, &fast(), &mut |_| {}, &CancelToken::new()).unwrap_err();
    match &err {
        SendError::OutOfTravel {
            axis: 'X',
            travel,
            size,
            ..
        } => {
            assert_eq!(*travel, 100.0);
            assert_eq!(*size, 150.0);
        }
        e => panic!("{e}"),
    }
    assert!(err.to_string().contains("$130"), "{err}");
    assert!(dev.executed.is_empty());
}

#[test]
fn check_mode_reports_every_bad_line_and_moves_nothing() {
    let job = Job::parse("G0X1\nG5X2\nG1X3F100\nG5X4\n").unwrap();
    let mut dev = FakeGrbl::new(true);
    dev.reject = |l| l.starts_with("G5").then_some(20);
    let err = send_job(
        &mut dev,
        &job,
        &fast().with_check(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap_err();
    let SendError::CheckFailed { errors } = &err else {
        panic!("{err}")
    };
    assert_eq!(
        errors
            .iter()
            .map(|e| e.line.source_line)
            .collect::<Vec<_>>(),
        vec![2, 4]
    );
    assert!(
        err.to_string().contains("unsupported or invalid g-code"),
        "{err}"
    );
    assert!(dev.executed.is_empty());
    assert_eq!(dev.received.iter().filter(|l| *l == "$C").count(), 2);
    // A clean job passes the check and then runs.
    let ok = Job::parse("G0X1\nG1X3F100\n").unwrap();
    let mut dev = FakeGrbl::new(true);
    let rep = send_job(
        &mut dev,
        &ok,
        &fast().with_check(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    assert!(rep.checked);
    assert_eq!(
        dev.executed,
        vec!["G0X1".to_string(), "G1X3F100".to_string()]
    );
}

#[test]
fn settings_writes_go_send_response() {
    let job = Job::parse("G0X1\nG0X2\nG0X3\n$32=0\nG0X4\n").unwrap();
    let mut dev = FakeGrbl::new(true);
    dev.lines_per_read = 1;
    send_job(&mut dev, &job, &fast(), &mut |_| {}, &CancelToken::new()).unwrap();
    assert!(!dev.eeprom_violation);
    assert_eq!(dev.executed.len(), 5);
}

/// Runs the job with a fault, then resumes from the journal on a fresh device that starts where
/// the first stopped; returns both devices' executions.
fn fault_then_resume(
    job: &Job,
    name: &str,
    set: impl FnOnce(&mut FakeGrbl),
    expect: impl FnOnce(&SendError),
) -> (Vec<String>, Vec<String>) {
    let jp = tmp(name);
    let mut dev = FakeGrbl::new(true);
    set(&mut dev);
    let err = send_job(
        &mut dev,
        job,
        &fast().with_journal(&jp),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap_err();
    expect(&err);
    let st = Journal::read(&jp).unwrap();
    assert!(!st.finished);
    let mut dev2 = FakeGrbl::new(true);
    dev2.pos = dev.pos;
    // The fresh device restarted (a banner at connect): the operator confirms the origin.
    let rep = send_job(
        &mut dev2,
        job,
        &fast()
            .with_journal(&jp)
            .with_resume(true)
            .with_origin_confirmed(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(rep.previously_done, st.done_count());
    assert!(Journal::read(&jp).unwrap().finished);
    // Resuming a finished job sends nothing but the handshake.
    (dev.executed, dev2.executed)
}

#[test]
fn error_stops_names_the_line_and_resume_finishes_exactly_once() {
    let job = Job::parse(&zigzag(300)).unwrap();
    let (a, b) = fault_then_resume(
        &job,
        "err.journal",
        |d| d.error_at = Some((104, 33)),
        |e| {
            let SendError::LineRejected { error, .. } = e else {
                panic!("{e}")
            };
            assert_eq!(error.code, 33);
            // Received line 104 = job line index 99 (after $I, $$, $# and $G) = source line 100.
            assert_eq!(error.line.index, 99);
            assert!(e.to_string().contains("line 100"), "{e}");
            assert!(
                e.to_string().contains("motion command target is invalid"),
                "{e}"
            );
        },
    );
    assert!(a.len() > 90);
    assert_exactly_once(&job, &[&a, &b]);
}

#[test]
fn unexpected_reset_then_resume_finishes_exactly_once() {
    let job = Job::parse(&zigzag(300)).unwrap();
    let (a, b) = fault_then_resume(
        &job,
        "reset.journal",
        |d| d.reset_at = Some(150),
        |e| {
            assert!(matches!(e, SendError::UnexpectedReset { .. }), "{e}");
        },
    );
    assert_exactly_once(&job, &[&a, &b]);
}

#[test]
fn alarm_then_resume_finishes_exactly_once() {
    let job = Job::parse(&zigzag(300)).unwrap();
    let (a, b) = fault_then_resume(
        &job,
        "alarm.journal",
        |d| d.alarm_at = Some((200, 1)),
        |e| {
            let SendError::Alarm { code: 1, last_done } = e else {
                panic!("{e}")
            };
            assert!(last_done.is_some());
            assert!(e.to_string().contains("hard limit"), "{e}");
        },
    );
    assert_exactly_once(&job, &[&a, &b]);
}

#[test]
fn hang_up_reports_last_executed_line_and_resume_skips_nothing() {
    let job = Job::parse(&zigzag(300)).unwrap();
    let jp = tmp("hangup.journal");
    let mut dev = FakeGrbl::new(true);
    dev.hangup_at = Some(180);
    let err = send_job(
        &mut dev,
        &job,
        &fast().with_journal(&jp),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap_err();
    let SendError::Transport {
        source: TransportError::HangUp(_),
        last_done,
    } = &err
    else {
        panic!("{err}")
    };
    let last = last_done.clone().unwrap();
    let ran = job_indices(&job, &dev.executed);
    assert!(ran.contains(&last.index));
    let st = Journal::read(&jp).unwrap();
    // The controller restarted (banner on connect): which queued lines ran before is unknown,
    // so resuming needs the operator's choice and names the lines in doubt.
    let mut dev2 = FakeGrbl::new(true);
    let err = send_job(
        &mut dev2,
        &job,
        &fast().with_journal(&jp).with_resume(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap_err();
    let SendError::ResumeUncertain { from, to, .. } = &err else {
        panic!("{err}")
    };
    assert_eq!(Some(from.index), st.unconfirmed.first().copied(), "{err}");
    assert!(to.index >= *st.unconfirmed.last().unwrap());
    assert!(dev2.executed.is_empty());
    let mut dev2 = FakeGrbl::new(true);
    send_job(
        &mut dev2,
        &job,
        &fast()
            .with_journal(&jp)
            .with_resume_from(Some(from.index))
            .with_origin_confirmed(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    // Nothing skipped; a re-run is confined to lines the journal could not confirm (acknowledged
    // but unconfirmed, or executed with their `ok` lost in the hang-up).
    let ran2 = job_indices(&job, &dev2.executed);
    for i in 0..job.len() {
        assert!(ran.contains(&i) || ran2.contains(&i), "line {i} never ran");
    }
    // (A preamble may write the same text as a job line: the plunge at the job's own feed.)
    let preamble: std::collections::BTreeSet<String> = (1..job.len())
        .flat_map(|k| job.resume_preamble(k))
        .collect();
    for i in ran2.iter().filter(|i| ran.contains(i)) {
        if preamble.contains(&job.lines[*i].text) {
            continue;
        }
        assert!(!st.done[*i], "line {i} was journaled as done but ran again");
    }
}

#[test]
fn lost_bytes_are_reported_not_waited_for_forever() {
    let job = Job::parse(&zigzag(50)).unwrap();
    let mut dev = FakeGrbl::new(true);
    dev.swallow_at = Some(20);
    let err = send_job(&mut dev, &job, &fast(), &mut |_| {}, &CancelToken::new()).unwrap_err();
    assert!(matches!(err, SendError::LostAck { .. }), "{err}");
}

#[test]
fn corrupted_motion_is_caught_at_the_end() {
    let job = Job::parse(&zigzag(50)).unwrap();
    let mut dev = FakeGrbl::new(true);
    dev.corrupt_at = Some(job.len() + 3);
    let err = send_job(&mut dev, &job, &fast(), &mut |_| {}, &CancelToken::new()).unwrap_err();
    assert!(matches!(err, SendError::PositionMismatch { .. }), "{err}");
}

#[test]
fn hold_resume_and_abort_from_the_control_handle() {
    let job = Job::parse(&zigzag(400)).unwrap();
    let token = CancelToken::new();
    let mut dev = FakeGrbl::new(true);
    let t2 = token.clone();
    let mut step = 0;
    send_job(
        &mut dev,
        &job,
        &fast(),
        &mut |p| {
            if p.phase == Phase::Streaming && p.lines_acked > 50 {
                match step {
                    0 => t2.hold(),
                    20 => t2.resume(),
                    _ => {}
                }
                step += 1;
            }
        },
        &token,
    )
    .unwrap();
    assert!(dev.realtime_log.contains(&b'!') && dev.realtime_log.contains(&b'~'));
    assert_eq!(job_indices(&job, &dev.executed).len(), job.len());

    let jp = tmp("abort.journal");
    let token = CancelToken::new();
    let t2 = token.clone();
    let mut dev = FakeGrbl::new(true);
    let err = send_job(
        &mut dev,
        &job,
        &fast().with_journal(&jp),
        &mut |p| {
            if p.lines_acked > 100 {
                t2.abort();
            }
        },
        &token,
    )
    .unwrap_err();
    assert!(matches!(err, SendError::Aborted { .. }), "{err}");
    let bang = dev.realtime_log.iter().position(|&b| b == b'!').unwrap();
    let reset = dev.realtime_log.iter().rposition(|&b| b == 0x18).unwrap();
    assert!(bang < reset, "feed hold before the reset");
    assert_eq!(dev.housekeeping, ["M5", "M9"], "tool off after the reset");
    assert_eq!(
        dev.received.last().map(String::as_str),
        Some("$G"),
        "and confirmed"
    );
    let a = dev.executed.clone();
    let mut dev2 = FakeGrbl::new(true);
    dev2.pos = dev.pos;
    send_job(
        &mut dev2,
        &job,
        &fast()
            .with_journal(&jp)
            .with_resume(true)
            .with_origin_confirmed(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    assert_exactly_once(&job, &[&a, &dev2.executed]);
}

#[test]
fn resume_needs_a_journal() {
    let job = Job::parse("G0X1\n").unwrap();
    let mut dev = FakeGrbl::new(true);
    let err = send_job(
        &mut dev,
        &job,
        &fast().with_resume(true),
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap_err();
    assert!(matches!(err, SendError::NoJournal));
}

fn state_with_unconfirmed(job: &Job, unconfirmed: Vec<usize>) -> JournalState {
    let n = job.len();
    let mut done = vec![false; n];
    for d in done.iter_mut().take(unconfirmed[0]) {
        *d = true;
    }
    JournalState {
        hash: job.hash,
        lines: n,
        done,
        rejected: vec![None; n],
        runs: 1,
        finished: false,
        last_acked: unconfirmed.last().copied(),
        notes: Vec::new(),
        unconfirmed,
        partial: None,
        uncertain: None,
        start: None,
        origin: None,
        texts: Vec::new(),
        stop: None,
        sent: None,
    }
}

#[test]
fn resume_position_settles_the_window_or_names_it() {
    // A square drawn twice round: (10,0) is reached at the end of lines 1 and 5.
    let job = Job::parse("G0X0Y0\nG1X10F600\nY10\nX0\nY0\nX10\n").unwrap();
    let st = state_with_unconfirmed(&job, vec![1, 2, 3]);
    let tol = 0.003;
    let settle = |p: [f64; 3]| resolve_resume(&job, &st, None, Some(p), 128, tol, false);
    // Inside line 3 (X0 from (10,10)): lines 1 and 2 ran, line 3 finishes from there.
    let r = settle([4.0, 10.0, 0.0]).unwrap().unwrap();
    assert_eq!(
        r,
        Resolution {
            from: 1,
            cut: 3,
            partial: Some((3, [4.0, 10.0, 0.0]))
        }
    );
    // At the end of line 2 (within a step): lines 1 and 2 ran.
    let r = settle([10.0, 10.001, 0.0]).unwrap().unwrap();
    assert_eq!((r.cut, r.partial), (3, None));
    // (10,0) is the end of line 1 and of line 5, both in the window (everything fits in
    // 128 bytes): the sender will not guess.
    let e = settle([10.0, 0.0, 0.0]).unwrap_err();
    assert!(matches!(e, SendError::ResumeUncertain { .. }), "{e}");
    assert!(e.to_string().contains("2 times"), "{e}");
    assert!(e.to_string().contains("resume explicitly"), "{e}");
    // Off the path altogether.
    let e = settle([3.0, 3.0, 0.0]).unwrap_err();
    assert!(e.to_string().contains("on none of these lines"), "{e}");
    // A controller that restarted cannot be asked.
    let e = resolve_resume(&job, &st, None, None, 128, tol, true).unwrap_err();
    assert!(e.to_string().contains("restarted"), "{e}");
    // The operator's choice wins and is checked.
    let r = resolve_resume(&job, &st, Some(4), None, 128, tol, true)
        .unwrap()
        .unwrap();
    assert_eq!((r.from, r.cut), (0, 4));
    assert!(matches!(
        resolve_resume(&job, &st, Some(99), None, 128, tol, true),
        Err(SendError::ResumeFromOutOfRange { .. })
    ));
}

#[test]
fn a_stop_at_a_sharp_vertex_finishes_the_later_line_and_g91_is_refused() {
    // A narrow V: near (2,4) both legs lie within a step of the stop position.
    let job = Job::parse("G0X0Y0\nG1X0.2Y4F600\nX0.4Y0\nX0.6Y4\n").unwrap();
    let st = state_with_unconfirmed(&job, vec![1, 2]);
    let p = [0.2, 3.964, 0.0];
    let r = resolve_resume(&job, &st, None, Some(p), 128, 0.0031, false)
        .unwrap()
        .unwrap();
    assert_eq!(r.partial, Some((2, p)), "{r:?}");
    // Relative moves: a position cannot say which line ran.
    let rel = Job::parse("G91\nG1X1F600\nX1\nX1\n").unwrap();
    let st = state_with_unconfirmed(&rel, vec![1, 2]);
    let e = resolve_resume(&rel, &st, None, Some([2.0, 0.0, 0.0]), 128, 0.003, false).unwrap_err();
    assert!(e.to_string().contains("relative (G91)"), "{e}");
}

#[test]
fn a_stop_inside_a_line_with_unrecorded_lines_before_it_is_not_guessed() {
    // A journal that records line 1 as run and the stop inside line 4, but nothing of lines 2
    // and 3 in between (their answers were on the wire when the run stopped): they ran, but the
    // journal cannot say so, and a resume from line 2 would cut them again.
    let job = Job::parse("G0X0Y0\nG1X10F600\nY10\nX0\nY0\nX10\n").unwrap();
    let mut st = state_with_unconfirmed(&job, vec![2]);
    st.unconfirmed.clear();
    st.partial = Some((4, [0.0, 5.0, 0.0]));
    let e = resolve_resume(&job, &st, None, Some([0.0, 5.0, 0.0]), 128, 0.003, false).unwrap_err();
    let SendError::ResumeUncertain { from, to, .. } = &e else {
        panic!("{e}");
    };
    assert_eq!((from.index, to.index), (2, 4), "{e}");
    assert!(e.to_string().contains("answers still on the wire"), "{e}");
    // The operator's line to continue from settles it.
    let r = resolve_resume(&job, &st, Some(4), None, 128, 0.003, false)
        .unwrap()
        .unwrap();
    assert_eq!((r.from, r.cut), (0, 4));
    // Lines all recorded: nothing to settle.
    st.done[2] = true;
    st.done[3] = true;
    assert_eq!(
        resolve_resume(&job, &st, None, None, 128, 0.003, false).unwrap(),
        None
    );
}
