//! Connecting: the banner (or a soft reset when none comes), `$I`, `$$`, a first status, and the
//! alarm-lock policy.

use super::SendOptions;
use super::error::SendError;
use super::session::{Session, transport, wait_until_still};
use crate::transport::Transport;

/// What connecting found out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Link {
    /// A banner came by itself: the controller just restarted (power-up, or the DTR pulse of
    /// opening the port), so its planner and position are gone.
    pub restarted: bool,
    /// The controller was alarm-locked and this sender unlocked it with `$X` (no homing): its
    /// position is whatever it was when the alarm struck.
    pub unlocked: bool,
}

/// Connects: waits for the power-up banner (or, with `reset_on_connect` or when none comes,
/// resets the controller once it stands still), reads `$I` and `$$`, asks for a status, and
/// unlocks an alarm lock only when the options allow it.
pub(super) fn connect<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    opts: &SendOptions,
) -> Result<Link, SendError> {
    let restarted = !opts.reset_on_connect
        && sess
            .wait_banner(opts.banner_timeout)
            .map_err(|e| transport(e, None))?;
    if !restarted {
        if !opts.reset_on_connect {
            // A controller that kept running while the host was away may still be draining its
            // planner: a reset now would stop it mid-move (ALARM:3, position lost).
            wait_until_still(sess, opts).map_err(|e| transport(e, None))?;
        }
        sess.s.realtime(0x18);
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
    if sess.alarm_lock {
        let reason = sess
            .messages
            .iter()
            .rev()
            .find(|m| m.contains("unlock") || m.contains("Reset"))
            .cloned()
            .unwrap_or_else(|| "state Alarm".into());
        // A resume on a machine that homes re-establishes its position with `$H` itself.
        let homes = sess.settings.get(&22).is_some_and(|v| *v != 0.0);
        if opts.resume && homes && !opts.unlock {
            return Ok(Link {
                restarted: true,
                unlocked: false,
            });
        }
        if !opts.unlock {
            return Err(SendError::AlarmLocked { reason });
        }
        sess.command_ok("$X", opts.command_timeout)?;
        sess.alarm_lock = false;
        sess.query_status(opts.command_timeout)
            .map_err(|e| transport(e, None))?;
        return Ok(Link {
            restarted,
            unlocked: true,
        });
    }
    Ok(Link {
        restarted,
        unlocked: false,
    })
}
