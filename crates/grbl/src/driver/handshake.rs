//! Connecting: the banner (or a soft reset when none comes), `$I`, `$$`, a first status, and the
//! alarm-lock policy.

use super::SendOptions;
use super::error::SendError;
use super::frame::{self, Frame};
use super::session::{Session, transport, wait_until_still};
use crate::transport::Transport;

/// What connecting found out.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Link {
    /// A banner came by itself: the controller just restarted (power-up, or the DTR pulse of
    /// opening the port), so its planner and position are gone.
    pub restarted: bool,
    /// The controller was alarm-locked and this sender unlocked it with `$X` (no homing): its
    /// position is whatever it was when the alarm struck.
    pub unlocked: bool,
    /// The work frame the controller is in now (after any restore).
    pub frame: Frame,
    /// What happened to the frame the soft reset cleared, for the report.
    pub frame_notice: Option<String>,
}

/// Connects: waits for the power-up banner (or, with `reset_on_connect` or when none comes,
/// resets the controller once it stands still), reads `$I` and `$$`, asks for a status, and
/// unlocks an alarm lock only when the options allow it.
pub(super) fn connect<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    opts: &SendOptions,
) -> Result<Link, SendError> {
    let banner = !opts.reset_on_connect
        && sess
            .wait_banner(opts.banner_timeout)
            .map_err(|e| transport(e, None))?;
    let restarted = banner || opts.controller_restarted;
    // The frame a reset would clear; none to read when the controller just restarted.
    let mut before = None;
    if !banner {
        if !opts.reset_on_connect {
            // A controller that kept running while the host was away may still be draining its
            // planner: a reset now would stop it mid-move (ALARM:3, position lost).
            wait_until_still(sess, opts).map_err(|e| transport(e, None))?;
        }
        sess.clear_line().map_err(|e| transport(e, None))?;
        before = Some(frame::read(sess, opts)?);
        sess.soft_reset();
        if !sess
            .wait_banner(opts.banner_timeout)
            .map_err(|e| transport(e, None))?
        {
            return Err(SendError::NoBanner(opts.banner_timeout));
        }
    }
    sess.command_ok("$I", opts.command_timeout)?;
    sess.command_ok("$$", opts.command_timeout)?;
    sess.query_status(opts.command_timeout)
        .map_err(|e| transport(e, None))?;
    let inches = sess.report_inches;
    let before = before.map(|b| b.map(|f| f.in_mm(inches)));
    let (restarted, unlocked) = match unlock_policy(sess, opts)? {
        Some(AlarmOutcome::LeftForHoming) => (true, false),
        Some(AlarmOutcome::Unlocked) => (restarted, true),
        None => (restarted, false),
    };
    // G-code is refused while alarm-locked (a resume homes first and restores the frame with
    // its preamble).
    let frame_notice = match before {
        Some(b) if !sess.alarm_lock => frame::restore(sess, b, opts)?,
        _ => None,
    };
    let frame = match frame::read(sess, opts)? {
        Ok(f) => f.in_mm(inches),
        Err(code) => {
            return Err(SendError::SetupRejected {
                command: "$#".into(),
                code,
            });
        }
    };
    // The position in the frame as it now stands.
    sess.query_status(opts.command_timeout)
        .map_err(|e| transport(e, None))?;
    Ok(Link {
        restarted,
        unlocked,
        frame,
        frame_notice,
    })
}

/// How an alarm lock at connection was handled.
enum AlarmOutcome {
    /// Left locked: a resume on a machine that homes re-establishes its position with `$H`.
    LeftForHoming,
    /// Unlocked with `$X` (the options allow it).
    Unlocked,
}

/// Unlocks an alarm lock only when the options allow it; `None` when there was none.
fn unlock_policy<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    opts: &SendOptions,
) -> Result<Option<AlarmOutcome>, SendError> {
    if !sess.alarm_lock {
        return Ok(None);
    }
    let reason = sess
        .messages
        .iter()
        .rev()
        .find(|m| m.contains("unlock") || m.contains("Reset"))
        .cloned()
        .unwrap_or_else(|| "state Alarm".into());
    let homes = sess.settings.get(&22).is_some_and(|v| *v != 0.0);
    if opts.resume && homes && !opts.unlock {
        return Ok(Some(AlarmOutcome::LeftForHoming));
    }
    if !opts.unlock {
        return Err(SendError::AlarmLocked { reason });
    }
    sess.command_ok("$X", opts.command_timeout)?;
    sess.alarm_lock = false;
    sess.query_status(opts.command_timeout)
        .map_err(|e| transport(e, None))?;
    Ok(Some(AlarmOutcome::Unlocked))
}
