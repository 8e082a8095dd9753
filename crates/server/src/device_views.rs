//! The device panel's JSON: a job's progress (lines, path, wall-clock ETA, live work position),
//! the sender's report, the controller, a status report, a question, and what the embedded
//! simulator executed — the keys `API.md` documents for `/api/devices`, `/api/jobs` and the
//! `device` and `job` events.

use flatcut_device::Asked;
use flatcut_device::grbl::{ControllerInfo, MachineState, MachineStatus, Progress, SendReport};
use flatcut_device::sim::SimReport;
use serde_json::{Value as Json, json};

/// A question for the operator: its number, the whole story and the yes/no prompt.
pub fn question_view(a: &Asked) -> Json {
    json!({ "id": a.id, "text": a.question.to_string(), "prompt": a.question.prompt() })
}

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
