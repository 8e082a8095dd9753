//! The device panel's JSON: a job's progress (lines, path, wall-clock ETA, live work position),
//! the sender's report, the controller, a status report, a question, and what the embedded
//! simulator executed, the lines a refused resume leaves in doubt — the keys `API.md` documents for `/api/devices`, `/api/jobs` and the
//! `device` and `job` events.

use flatcut_device::grbl::hpgl::HpglReport;
use flatcut_device::grbl::{
    ControllerInfo, Job, MachineState, MachineStatus, Progress, SendError, SendReport,
};
use flatcut_device::sim::SimReport;
use flatcut_device::{Asked, PlotProgress, PlotterReport};
use serde_json::{Value as Json, json};

/// A question for the operator: its number, the whole story and the yes/no prompt.
pub fn question_view(a: &Asked) -> Json {
    json!({ "id": a.id, "text": a.question.to_string(), "prompt": a.question.prompt() })
}

/// The machine state as GRBL writes it in a status report (`Idle`, `Run`, `Hold:0`, `Alarm`, …).
pub fn state_name(s: MachineState) -> String {
    s.name()
}

/// A job's progress for the page: lines, path, ETA (wall clock), live work position.
pub fn progress_view(p: &Progress, wall_per_machine_s: Option<f64>) -> Json {
    json!({
        "phase": format!("{:?}", p.phase).to_lowercase(),
        "lines_acked": p.lines_acked,
        "lines_done": p.lines_done,
        "lines_total": p.lines_total,
        "length_done_mm": p.length_done,
        "length_total_mm": p.length_total,
        "fraction": p.fraction(),
        "eta_s": p.eta.zip(wall_per_machine_s).map(|(e, k)| e.as_secs_f64() * k),
        "elapsed_s": p.elapsed.as_secs_f64(),
        "machine_state": p.state.map(state_name),
        "position": p.position,
        "holding": p.holding,
        "paused_at": p.paused_at.as_ref().map(|l| json!({"line": l.source_line, "text": l.text})),
    })
}

/// A plot's progress for the page. HP-GL has no acknowledgements: `progress_basis` says the
/// fraction is of the bytes the link accepted (`bytes_sent`), not of what the plotter drew; the
/// ETA is of the rest of the bytes at the rate so far (wall clock, pauses not counted).
pub fn plot_progress_view(p: &PlotProgress) -> Json {
    json!({
        "progress_basis": "bytes_sent",
        "bytes_sent": p.bytes_sent,
        "bytes_total": p.bytes_total,
        "fraction": p.fraction(),
        "eta_s": p.eta.map(|e| e.as_secs_f64()),
        "elapsed_s": p.elapsed.as_secs_f64(),
        "device_holding": p.held,
        "paused": p.paused,
        "pen_down": p.pen_down,
        "device_buffer_free": p.device_free,
    })
}

/// A finished plot's report: bytes sent, flow control seen, buffer queries, pauses, time (s).
pub fn plot_report_view(r: &HpglReport) -> Json {
    json!({
        "bytes_sent": r.bytes_sent,
        "xoff_received": r.xoff_received,
        "xon_received": r.xon_received,
        "queries": r.queries,
        "device_buffer": r.device_buffer,
        "min_free_reported": r.min_free_reported,
        "pauses": r.pauses,
        "stream_time_s": r.elapsed_s,
    })
}

/// What the embedded HP-GL plotter drew: its pen-down strokes (mm), its pen now, its counters.
pub fn plotter_view(r: &PlotterReport) -> Json {
    let strokes: Vec<Json> = r
        .strokes
        .iter()
        .map(|s| json!({ "from": s.from, "to": s.to, "pen": s.pen }))
        .collect();
    let st = &r.stats;
    json!({
        "strokes": strokes,
        "pen_down": r.pen_down,
        "idle": r.idle,
        "bytes_received": st.bytes_received,
        "bytes_lost": st.bytes_lost,
        "high_water": st.high_water,
        "xoff_sent": st.xoff_sent,
        "xon_sent": st.xon_sent,
        "queries": st.queries,
        "aborts": st.aborts,
        "commands": st.commands,
    })
}

/// A finished job's send report: lines sent, times (s), the controller's buffer figures,
/// version and notices.
pub fn report_view(r: &SendReport) -> Json {
    json!({
        "lines_sent": r.lines_sent,
        "previously_done": r.previously_done,
        "preamble_lines": r.preamble_lines,
        "final_position": r.final_position,
        "stream_time_s": r.stream_time.as_secs_f64(),
        "total_time_s": r.total_time.as_secs_f64(),
        "estimated_time_s": r.estimated_time,
        "max_in_flight_bytes": r.max_in_flight_bytes,
        "rx_size": r.rx_size,
        "version": r.version,
        "notices": r.notices,
    })
}

/// What the controller said when connected: version, receive buffer (bytes), planner blocks,
/// state, and the work area from its `$130`/`$131` max travel (mm; null when unset).
pub fn controller_view(i: &ControllerInfo) -> Json {
    json!({
        "version": i.version,
        "rx_size": i.rx_size,
        "planner_blocks": i.planner_blocks,
        "restarted": i.restarted,
        "state": i.state.map(state_name),
        "work_area_mm": [i.settings.get(&130), i.settings.get(&131)],
    })
}

/// A status report: the state and the work and machine positions (mm).
pub fn status_view(s: &MachineStatus) -> Json {
    json!({ "state": state_name(s.state), "work": s.work, "machine": s.machine })
}

/// What the embedded simulator executed: its motions (machine mm), counters and time.
pub fn sim_view(r: &SimReport) -> Json {
    let motions: Vec<Json> = r
        .trace
        .iter()
        .map(|s| {
            json!({
                "line": s.line, "text": s.text, "motion": s.motion, "from": s.from, "to": s.to,
                "tool_on": s.tool_on, "feed": s.feed,
            })
        })
        .collect();
    json!({
        "motions": motions,
        "lines_received": r.stats.lines_received,
        "resets": r.stats.resets,
        "errors": r.stats.errors,
        "alarms": r.stats.alarms,
        "bytes_dropped_overflow": r.stats.bytes_dropped_overflow,
        "sim_time_s": r.sim_time,
    })
}

/// The lines a stopped or refused job leaves to the operator's word, as the page shows them:
/// `{from, to, reason, lines}` (1-based lines of the file) when the sender cannot tell which of
/// them ran (a resume whose journal and machine cannot settle it, a line damaged on the link).
/// `lines` are those lines as sent, each with where it moves the tool (work mm: its start and
/// end, an arc's chord points between) and whether the tool cuts, so the page can show them over
/// the layout while the operator looks at the work; the page then asks for the line to continue
/// from (`resume_from`).
pub fn doubt_view(e: &SendError, job: &Job) -> Option<Json> {
    let (from, to, reason) = match e {
        SendError::ResumeUncertain { from, to, reason } => (from, to, reason.clone()),
        SendError::OffPath(off) => (
            &off.from,
            &off.to,
            "the machine left the job's path: a line was probably damaged on the link".into(),
        ),
        _ => return None,
    };
    let lines: Vec<Json> = (from.index..=to.index.min(from.index + MAX_DOUBT_LINES - 1))
        .filter_map(|i| job.lines.get(i).map(|l| (i, l)))
        .map(|(i, l)| {
            let path: Vec<[f64; 3]> = match (l.moves && l.length > 0.0, l.arc.is_empty()) {
                (false, _) => Vec::new(),
                (true, true) => vec![job.start_of(i), job.end_of(i)],
                (true, false) => l.arc.clone(),
            };
            json!({ "line": l.source_line, "text": l.text, "cuts": l.tool_on, "path": path })
        })
        .collect();
    Some(json!({
        "from": from.source_line,
        "to": to.source_line,
        "reason": reason,
        "lines": lines,
    }))
}

/// Most lines in doubt the view lists (a damaged line's doubt spans what the controller's buffer
/// held: tens of lines).
const MAX_DOUBT_LINES: usize = 1000;

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_device::grbl::driver::LineRef;

    fn line(job: &Job, index: usize) -> LineRef {
        LineRef {
            index,
            source_line: job.lines[index].source_line,
            text: job.lines[index].text.clone(),
        }
    }

    #[test]
    fn a_refused_resume_names_the_lines_in_doubt_by_the_files_numbers_and_where_they_move() {
        let job = Job::parse(
            "G21 G90\n(the square)\nG0 X10 Y0\nM3 S1000\nG1 X20 F600\nG2 X30 Y10 I0 J10\nM5\n",
        )
        .unwrap();
        let e = SendError::ResumeUncertain {
            from: line(&job, 1),
            to: line(&job, 4),
            reason: "the path passes the machine's position 2 times".into(),
        };
        let d = doubt_view(&e, &job).expect("lines in doubt");
        assert_eq!((d["from"].as_u64(), d["to"].as_u64()), (Some(3), Some(6)));
        assert!(d["reason"].as_str().unwrap().contains("2 times"));
        let lines = d["lines"].as_array().unwrap();
        let numbers: Vec<u64> = lines.iter().map(|l| l["line"].as_u64().unwrap()).collect();
        assert_eq!(numbers, [3, 4, 5, 6]);
        // The rapid to (10, 0) does not cut; the spindle line moves nothing; the feed cuts along
        // X; the arc's chords run from (20, 0) to (30, 10) about its centre (20, 10).
        assert_eq!(lines[0]["path"], json!([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]));
        assert_eq!(lines[0]["cuts"], false);
        assert_eq!(lines[1]["path"], json!([]));
        assert_eq!(
            lines[2]["path"],
            json!([[10.0, 0.0, 0.0], [20.0, 0.0, 0.0]])
        );
        assert_eq!(lines[2]["cuts"], true);
        let arc = lines[3]["path"].as_array().unwrap();
        assert!(arc.len() > 2, "{arc:?}");
        let xy = |p: &Json| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        // GRBL splits arcs in single precision: the chords' ends are on the circle to 1e-3 mm.
        for p in arc {
            let (x, y) = xy(p);
            assert!(((x - 20.0).hypot(y - 10.0) - 10.0).abs() < 1e-3, "{p}");
        }
        let ((x0, y0), (x1, y1)) = (xy(&arc[0]), xy(&arc[arc.len() - 1]));
        assert!((x0 - 20.0).hypot(y0) < 1e-3 && (x1 - 30.0).hypot(y1 - 10.0) < 1e-3);
        // A stop whose lines all are known needs no line from the operator.
        let stop = SendError::Aborted { last_done: None };
        assert!(doubt_view(&stop, &job).is_none());
    }
}
