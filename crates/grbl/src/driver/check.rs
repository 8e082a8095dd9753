//! Checks before anything moves: the job against the machine travel (`$130-$132`), and the
//! optional `$C` check-mode pass.

use super::error::line_ref;
use super::error::{LineError, SendError};
use super::session::{Session, transport};
use super::{POSITION_TOL_MM, READ_SLICE, SendOptions};
use crate::job::{Job, LineKind, MachineLimits};
use crate::streamer::{Event, SendMode, Tag};
use crate::transport::Transport;
use std::collections::BTreeMap;
use std::time::Instant;

/// G28/G30/G53, probing (G38.x stops where the probe touches) and `$` motion (homing, jog) go
/// to places this model does not track; so does a tool length offset (G43.1), which moves the
/// reported work position.
pub(super) fn job_uses_unknown_moves(job: &Job) -> bool {
    job.lines.iter().any(|l| {
        l.kind != LineKind::Gcode
            || ["G28", "G30", "G53", "G38", "G43"]
                .iter()
                .any(|g| l.text.contains(g))
    })
}

/// Refuses a job that does not fit the machine: longer than the travel on an axis, or (with
/// homing and soft limits) outside the machine space; `origin` is the machine position of the
/// job's G92-free work origin.
pub(super) fn check_travel(
    job: &Job,
    limits: &MachineLimits,
    settings: &BTreeMap<u16, f64>,
    origin: [f64; 3],
) -> Result<(), SendError> {
    let Some((lo, hi)) = job.extent else {
        return Ok(());
    };
    let soft_limits = settings.get(&20).copied().unwrap_or(0.0) != 0.0;
    for a in 0..3 {
        let travel = limits.max_travel[a];
        let size = hi[a] - lo[a];
        let (mlo, mhi) = (lo[a] + origin[a], hi[a] + origin[a]);
        // Absolute check only where GRBL itself enforces it (homing + soft limits: machine
        // space is [-travel, 0]); otherwise the job must at least fit the travel.
        let out = size > travel + POSITION_TOL_MM
            || (limits.homing
                && soft_limits
                && (mlo < -travel - POSITION_TOL_MM || mhi > POSITION_TOL_MM));
        if out {
            return Err(SendError::OutOfTravel {
                axis: ['X', 'Y', 'Z'][a],
                lo: lo[a],
                hi: hi[a],
                size,
                mlo,
                mhi,
                travel,
            });
        }
    }
    Ok(())
}

pub(super) fn check_pass<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    job: &Job,
    opts: &SendOptions,
) -> Result<(), SendError> {
    sess.command_ok("$C", opts.command_timeout)?;
    for (i, l) in job.lines.iter().enumerate() {
        if l.kind == LineKind::Gcode {
            sess.s
                .push(Tag::Job(i), l.text.clone(), SendMode::CharCount);
        }
    }
    let mut errors = Vec::new();
    let mut last = Instant::now();
    while sess.s.queued() > 0 || sess.s.in_flight() > 0 {
        let evs = sess.pump(READ_SLICE).map_err(|e| transport(e, None))?;
        if !evs.is_empty() {
            last = Instant::now();
        }
        for e in evs {
            match e {
                Event::Rejected(Tag::Job(i), code) => errors.push(LineError {
                    line: line_ref(job, i),
                    code,
                }),
                Event::Reset { .. } => {
                    return Err(SendError::UnexpectedReset {
                        lost: 0,
                        last_done: None,
                    });
                }
                Event::Alarm(code) => {
                    return Err(SendError::Alarm {
                        code,
                        last_done: None,
                    });
                }
                _ => {}
            }
        }
        if last.elapsed() > opts.silence_timeout {
            return Err(SendError::DeviceSilent {
                waited: last.elapsed(),
                last_done: None,
            });
        }
    }
    // Leaving check mode soft-resets GRBL: wait for the banner.
    let seen = sess.resets;
    sess.reset_caused();
    sess.command_ok("$C", opts.command_timeout)?;
    if !sess
        .wait_banner_after(seen, opts.banner_timeout)
        .map_err(|e| transport(e, None))?
    {
        return Err(SendError::NoBanner(opts.banner_timeout));
    }
    if !errors.is_empty() {
        return Err(SendError::CheckFailed { errors });
    }
    Ok(())
}
