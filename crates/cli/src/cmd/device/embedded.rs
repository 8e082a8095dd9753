//! The embedded simulator as the device: its configuration from the flags (and a bed as large as
//! the job), fault injection, and the evidence files it leaves (trace, SVG).

use anyhow::Context;
use flatcut_firmware_sim::{
    DEFAULT_INJECTED_ALARM, DEFAULT_INJECTED_ERROR, Faults, SimArgs, SimConfig, TraceSegment,
    line_code,
};
use flatcut_grbl::Job;

use super::StreamArgs;

/// Extra travel given to the embedded simulator beyond the job's extent, mm, so a job that
/// exactly fills the bed is not refused for rounding.
const SIM_TRAVEL_MARGIN_MM: f64 = 10.0;

/// The embedded simulator's configuration: the flags, plus a bed (`$130-$132`) at least as large
/// as the job so a big nest is not refused by the travel check of a machine that does not exist.
pub(super) fn sim_config(job: &Job, args: &StreamArgs) -> anyhow::Result<SimConfig> {
    let mut cfg = SimConfig::default()
        .with_baud(args.baud)
        .with_time_scale(args.sim_speed)
        .with_instant_motion(args.sim_instant)
        .with_faults(Faults {
            error_at_line: args
                .sim_error_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ERROR, "--sim-error-at"))
                .transpose()?,
            alarm_at_line: args
                .sim_alarm_at
                .as_deref()
                .map(|a| line_code(a, DEFAULT_INJECTED_ALARM, "--sim-alarm-at"))
                .transpose()?,
            hangup_at_line: args.sim_hangup_at,
            reset_at_line: args.sim_reset_at,
            drop_digit_at_line: args.sim_drop_digit_at,
            ..Faults::default()
        });
    let flags = SimArgs {
        laser: args.sim_laser,
        set: args.sim_set.clone(),
        ..SimArgs::default()
    };
    cfg.settings = flags
        .settings()
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().replacen("--set", "--sim-set", 1)))?;
    if let Some((lo, hi)) = job.extent {
        let default_travel = flatcut_firmware_sim::Settings::default().max_travel;
        for a in 0..3 {
            let size = hi[a] - lo[a];
            let set = cfg.settings.iter().any(|s| s.0 == 130 + a as u16);
            if size.is_finite() && size > default_travel[a] && !set {
                cfg = cfg.with_setting(130 + a as u16, (size + SIM_TRAVEL_MARGIN_MM).ceil());
            }
        }
    }
    cfg.validate()
        .context("the embedded simulator's options are invalid")?;
    Ok(cfg)
}

/// Writes the embedded simulator's trace (JSON lines) and SVG where asked. Written here rather
/// than by the simulator so that a failure is an error of the command, not a warning.
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
        crate::cmd::common::write(p, flatcut_firmware_sim::trace_svg(trace).as_bytes())
            .with_context(|| format!("cannot write the simulator SVG {}", p.display()))?;
    }
    Ok(())
}
