//! Checks that what the simulator executed (its trace) is the job's motion: every motion once,
//! in order, at the right place.

use flatcut_firmware_sim::TraceSegment;
use flatcut_grbl::Job;
use std::collections::BTreeSet;
use std::path::Path;

/// Position tolerance, mm: the simulator moves in whole steps (0.004 mm at 250 steps/mm) and
/// the test jobs' coordinates lie on that grid, so agreement is exact up to float formatting.
pub const TOL: f64 = 1e-3;

/// Whether two positions agree within [`TOL`].
pub fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= TOL)
}

/// The segments that moved.
pub fn moving(trace: &[TraceSegment]) -> Vec<&TraceSegment> {
    trace.iter().filter(|s| !close(s.from, s.to)).collect()
}

/// A trace written by the simulator as JSON lines.
pub fn read_trace(path: &Path) -> Vec<TraceSegment> {
    std::fs::read_to_string(path)
        .expect("read the trace")
        .lines()
        .map(|l| serde_json::from_str(l).expect("a trace segment"))
        .collect()
}

/// Moving segments, with a line stopped part-way and completed later (same text, the second
/// starting where the first ended) joined into one.
pub fn joined(trace: &[TraceSegment]) -> Vec<TraceSegment> {
    let mut out: Vec<TraceSegment> = Vec::new();
    for s in trace.iter().filter(|s| !close(s.from, s.to)) {
        if let Some(last) = out.last_mut()
            && last.text == s.text
            && close(last.to, s.from)
        {
            last.to = s.to;
            continue;
        }
        out.push(s.clone());
    }
    out
}

/// The trace of one run is the job's motion, segment by segment.
pub fn assert_trace_is_job(job: &Job, trace: &[TraceSegment]) {
    let want = job.motions();
    let got = moving(trace);
    assert_eq!(got.len(), want.len(), "segment count");
    for (k, (w, g)) in want.iter().zip(&got).enumerate() {
        assert_eq!(g.text, w.0, "segment {k}");
        assert!(
            close(g.from, w.1) && close(g.to, w.2),
            "segment {k}: {g:?} vs {w:?}"
        );
    }
}

/// Over the traces of all runs (a line stopped part-way joined to its completion), the job's
/// motion ran exactly once, in order, at the right place.
pub fn assert_job_exactly_once(job: &Job, trace: &[TraceSegment]) {
    let want = job.motions();
    let got = joined(trace);
    for (k, (w, g)) in want.iter().zip(&got).enumerate() {
        assert!(
            g.text == w.0 && close(g.from, w.1) && close(g.to, w.2),
            "motion {k}: ran `{}` {:?} -> {:?}, the job has `{}` {:?} -> {:?}; ran next: {:?}",
            g.text,
            g.from,
            g.to,
            w.0,
            w.1,
            w.2,
            got[k + 1..(k + 4).min(got.len())]
                .iter()
                .map(|s| (&s.text, s.from, s.to))
                .collect::<Vec<_>>()
        );
    }
    assert_eq!(got.len(), want.len(), "number of motions");
}

/// Every job motion with a unique text (not also written by a resume preamble) ran exactly once
/// over the traces of all runs, ending where the job says. Returns how many were checked.
pub fn assert_exactly_once(job: &Job, traces: &[&[TraceSegment]]) -> usize {
    assert_exactly_once_except(job, traces, &BTreeSet::new())
}

/// [`assert_exactly_once`], leaving out the lines in `except` (a line cut short that ran again).
pub fn assert_exactly_once_except(
    job: &Job,
    traces: &[&[TraceSegment]],
    except: &BTreeSet<String>,
) -> usize {
    let preamble: BTreeSet<String> = (1..job.len())
        .flat_map(|k| job.resume_preamble(k))
        .collect();
    let mut checked = 0;
    for (text, _, to) in job.motions() {
        if preamble.contains(&text)
            || except.contains(&text)
            || job.lines.iter().filter(|l| l.text == text).count() != 1
        {
            continue;
        }
        let hits: Vec<&TraceSegment> = traces
            .iter()
            .flat_map(|t| t.iter())
            .filter(|s| s.text == text)
            .collect();
        assert_eq!(hits.len(), 1, "`{text}` ran {} times", hits.len());
        assert!(
            close(hits[0].to, to),
            "`{text}` ended at {:?}, want {to:?}",
            hits[0].to
        );
        checked += 1;
    }
    checked
}
