//! The evidence the embedded simulator leaves, written where the flags ask: every motion it
//! executed (JSON lines) and an SVG of what it drew or cut. Written here rather than by the
//! simulator so that a failure is an error of the command, not a warning.

use anyhow::Context;
use flatcut_device::sim::TraceSegment;

use super::args::StreamArgs;

/// Writes the trace to `--sim-trace` and its SVG to `--sim-svg`, where given.
pub(super) fn write_sim_files(trace: &[TraceSegment], args: &StreamArgs) -> anyhow::Result<()> {
    if let Some(p) = &args.sim_trace {
        let mut s = String::new();
        for seg in trace {
            s.push_str(&serde_json::to_string(seg)?);
            s.push('\n');
        }
        crate::cmd::common::write(p, s.as_bytes())
            .with_context(|| format!("cannot write the simulator trace {}", p.display()))?;
    }
    if let Some(p) = &args.sim_svg {
        crate::cmd::common::write(p, flatcut_device::sim::trace_svg(trace).as_bytes())
            .with_context(|| format!("cannot write the simulator SVG {}", p.display()))?;
    }
    Ok(())
}
