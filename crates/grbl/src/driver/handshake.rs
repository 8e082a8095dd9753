//! Connecting: the banner or a first status (a soft reset when no banner came), `$I`, `$$`, a
//! first status, the alarm-lock policy, and what the controller said before anything changed it
//! (the evidence a resume weighs).

use super::SendOptions;
use super::error::SendError;
use super::evidence;
use super::frame::{self, Frame};
use super::session::{Session, transport, wait_until_still};
use crate::journal::StopRecord;
use crate::transport::Transport;

/// What connecting found out.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Link {
    /// The controller restarted as this sender connected: a banner it did not cause came at
    /// any moment of the handshake (power-up, the DTR pulse of opening the port, a bootloader
    /// slower than the boot wait), so its planner and position are gone.
    pub restarted: bool,
    /// The controller was alarm-locked and this sender unlocked it with `$X` (no homing): its
    /// position is whatever it was when the alarm struck.
    pub unlocked: bool,
    /// The work frame the controller is in now (after any restore).
    pub frame: Frame,
    /// What happened to the frame the soft reset cleared, for the report.
    pub frame_notice: Option<String>,
    /// Where the controller stood, in which frame and parser state, before this sender
    /// changed anything (`None` when it had just restarted, or did not say).
    pub found: Option<StopRecord>,
    /// Banners nobody asked for that the session had seen before this connection: one more
    /// later is a restart (see [`Session::restarts`]).
    pub restarts_before: u64,
}

/// Connects: waits for the controller to show it runs (a banner, or an answer to `?`; with
/// `reset_on_connect` it resets at once), resets a controller that was running already once it
/// stands still (its frame read first and put back after), reads `$I` and `$$`, asks for a
/// status, and unlocks an alarm lock only when the options allow it. A banner this sender did
/// not cause, whenever it comes, is a restart.
pub(super) fn connect<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    opts: &SendOptions,
) -> Result<Link, SendError> {
    let restarts_before = sess.restarts();
    let banner = !opts.reset_on_connect
        && sess
            .wait_boot(opts.banner_timeout)
            .map_err(|e| transport(e, None))?;
    // The frame a reset would clear; none to read when the controller just restarted.
    let mut before = None;
    let mut found = None;
    if !banner {
        if !opts.reset_on_connect {
            // A controller that kept running while the host was away may still be draining its
            // planner: a reset now would stop it mid-move (ALARM:3, position lost).
            wait_until_still(sess, opts).map_err(|e| transport(e, None))?;
        }
        sess.clear_line().map_err(|e| transport(e, None))?;
        sess.query_status(opts.command_timeout)
            .map_err(|e| transport(e, None))?;
        let b = frame::read(sess, opts.command_timeout)?;
        found = b.as_ref().ok().and_then(|f| evidence::record(sess, f));
        before = Some(b);
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
    let restarted = banner || opts.controller_restarted || sess.restarts() > restarts_before;
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
    let frame = match frame::read(sess, opts.command_timeout)? {
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
        found,
        restarts_before,
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
