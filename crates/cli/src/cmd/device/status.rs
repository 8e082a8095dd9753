//! How a send's state reads on one line: the phase's name, and "12.3% of path · ETA 1:05 · Run ·
//! X10.000 Y5.000 Z-0.500".

use flatcut_device::grbl::Progress;
use flatcut_device::grbl::driver::Phase;

/// The phase as the progress line names it.
pub(super) fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Connecting => "connecting",
        Phase::Checking => "checking",
        Phase::Streaming => "streaming",
        Phase::Finishing => "finishing",
        Phase::Done => "done",
    }
}

/// "12.3% of path · ETA 1:05 · Run · X10.000 Y5.000 Z-0.500", with "· paused by the job at line
/// 7 (`M0`)" while the job's own pause waits for the operator.
/// `eta_scale` converts the sender's machine-time ETA to wall-clock time (`None`: no ETA).
pub(super) fn status_text(p: &Progress, eta_scale: Option<f64>) -> String {
    let mut s = format!("{:5.1}% of path", 100.0 * p.fraction());
    if let (Some(eta), Some(k)) = (p.eta, eta_scale) {
        let t = (eta.as_secs_f64() * k).round() as u64;
        s.push_str(&format!(" · ETA {}:{:02}", t / 60, t % 60));
    }
    if let Some(st) = &p.state {
        s.push_str(&format!(" · {}", st.name()));
    }
    if p.holding {
        s.push_str(" (held)");
    }
    if let Some(line) = &p.paused_at {
        s.push_str(&format!(" · paused by the job at {line}"));
    }
    if let Some([x, y, z]) = p.position {
        s.push_str(&format!(" · X{x:.3} Y{y:.3} Z{z:.3}"));
    }
    s
}
