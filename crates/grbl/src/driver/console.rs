//! [`Console`]: one link to a controller kept open between jobs, for what an operator does at
//! the machine besides running a job: connect and look at it (version, settings, state,
//! position), unlock, home, jog, trace a job's frame, and then run jobs on the same link.
//!
//! What the console learns (settings, the receive buffer's size, banners) carries over from one
//! operation to the next and into the jobs it runs. A banner the console did not ask for (a
//! power-up, the reset of opening the port, a board that restarted by itself) means the
//! controller lost its position: [`Console::restarted`] says so, and a job run on the console is
//! told (see [`SendOptions::controller_restarted`]).

use super::error::SendError;
use super::session::{Known, Session, transport};
use super::{CancelToken, Progress, READ_SLICE, SendOptions, SendReport, run_job};
use crate::job::fmt_num;
use crate::response::{MachineState, StatusReport};
use crate::streamer::Event;
use crate::transport::Transport;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// GRBL's jog-cancel realtime byte (`CMD_JOG_CANCEL`, `config.h`).
const JOG_CANCEL: u8 = 0x85;
/// Longest wait for a homing cycle's `ok` (searching 1.5× a 1 m travel at GRBL's default seek
/// rate takes about 3 minutes).
const HOMING_TIMEOUT: Duration = Duration::from_secs(300);
/// Longest wait for a frame's jogs to finish.
const FRAME_TIMEOUT: Duration = Duration::from_secs(600);

/// What connecting found out about the controller.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerInfo {
    /// Firmware version from the banner (`1.1h`), empty when no banner was seen.
    pub version: String,
    /// Receive buffer, bytes (`[OPT:]`).
    pub rx_size: usize,
    /// Planner blocks (`[OPT:]`).
    pub planner_blocks: usize,
    /// Settings from `$$`.
    pub settings: BTreeMap<u16, f64>,
    /// The controller restarted when the port opened (or since): its position is lost.
    pub restarted: bool,
    /// The state it reported.
    pub state: Option<MachineState>,
}

/// Where the machine is and what it does, from one status report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MachineStatus {
    /// The state.
    pub state: MachineState,
    /// Work position, mm.
    pub work: Option<[f64; 3]>,
    /// Machine position, mm.
    pub machine: Option<[f64; 3]>,
}

/// A jog: a relative move at a feed (mm, mm/min), run by GRBL's `$J=` and stopped at once by
/// [`Console::jog_cancel`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jog {
    /// Distance per axis, mm (0 for an axis that does not move).
    pub by: [f64; 3],
    /// Feed, mm/min.
    pub feed: f64,
}

/// A link to a controller between jobs; see the module docs.
pub struct Console {
    t: Box<dyn Transport + Send>,
    known: Option<Known>,
    restarted: bool,
}

impl std::fmt::Debug for Console {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Console")
            .field("connected", &self.known.is_some())
            .field("restarted", &self.restarted)
            .finish()
    }
}

impl Console {
    /// A console on an opened link; nothing is read or written until it is used.
    pub fn new(t: Box<dyn Transport + Send>) -> Console {
        Console {
            t,
            known: None,
            restarted: false,
        }
    }

    /// Whether [`Console::connect`] (or a job) has talked to the controller on this link.
    pub fn is_connected(&self) -> bool {
        self.known.is_some()
    }

    /// Whether the controller restarted (a banner nobody asked for) since the link opened: its
    /// position and G92 offset are gone.
    pub fn restarted(&self) -> bool {
        self.restarted
    }

    /// Runs `f` on a session that goes on from what the console knows.
    fn session<R>(&mut self, f: impl FnOnce(&mut Session<'_, dyn Transport + Send>) -> R) -> R {
        let mut sess = match self.known.take() {
            Some(k) => Session::resume(&mut *self.t, k),
            None => Session::new(&mut *self.t),
        };
        let seen = sess.restarts();
        let r = f(&mut sess);
        if sess.restarts() > seen {
            self.restarted = true;
        }
        self.known = Some(sess.known());
        r
    }

    /// Connects: waits up to `opts.banner_timeout` for the banner of a controller that restarts
    /// as the port opens, or for an answer to `?` from one that was running; without either, asks for a status (and soft-resets a controller that
    /// does not answer); then reads `$I`, `$$` and a status. Does not reset a controller that
    /// answers, so its work frame (G92, G55..G59) stays as the operator set it.
    pub fn connect(&mut self, opts: &SendOptions) -> Result<ControllerInfo, SendError> {
        let fresh = self.known.is_none();
        let info = self.session(|sess| {
            let banner = fresh
                && sess
                    .wait_boot(opts.banner_timeout)
                    .map_err(|e| transport(e, None))?;
            if !banner
                && sess
                    .query_status(opts.command_timeout)
                    .map_err(|e| transport(e, None))?
                    .is_none()
            {
                let seen = sess.resets;
                sess.soft_reset();
                if !sess
                    .wait_banner_after(seen, opts.banner_timeout)
                    .map_err(|e| transport(e, None))?
                {
                    return Err(SendError::NoBanner(opts.banner_timeout));
                }
            }
            sess.command_ok("$I", opts.command_timeout)?;
            sess.command_ok("$$", opts.command_timeout)?;
            sess.query_status(opts.command_timeout)
                .map_err(|e| transport(e, None))?;
            Ok(ControllerInfo {
                version: sess.version.clone(),
                rx_size: sess.s.rx_size(),
                planner_blocks: sess.blocks,
                settings: sess.settings.clone(),
                restarted: false,
                state: sess.status.as_ref().map(|s| s.state),
            })
        })?;
        Ok(ControllerInfo {
            restarted: self.restarted,
            ..info
        })
    }

    /// Asks for a status report and waits up to `timeout` for it.
    pub fn status(&mut self, timeout: Duration) -> Result<Option<MachineStatus>, SendError> {
        self.session(|sess| {
            let st = sess.query_status(timeout).map_err(|e| transport(e, None))?;
            Ok(st.map(|s| machine_status(sess, &s)))
        })
    }

    /// Reads what the controller says for up to `wait` without asking anything: the last status
    /// report among it, if any. A banner among it marks the controller restarted.
    pub fn listen(&mut self, wait: Duration) -> Result<Option<MachineStatus>, SendError> {
        self.session(|sess| {
            let evs = sess.pump(wait).map_err(|e| transport(e, None))?;
            Ok(evs.iter().rev().find_map(|e| match e {
                Event::Status(s) => Some(machine_status(sess, s)),
                _ => None,
            }))
        })
    }

    /// Sends one line and waits up to `timeout` for its `ok`; `error:N` is
    /// [`SendError::SetupRejected`].
    pub fn command(&mut self, text: &str, timeout: Duration) -> Result<(), SendError> {
        self.session(|sess| sess.command_ok(text, timeout))
    }

    /// Clears an alarm lock with `$X` (only when the machine position is known to be right).
    pub fn unlock(&mut self, opts: &SendOptions) -> Result<(), SendError> {
        self.command("$X", opts.command_timeout)
    }

    /// Homes the machine with `$H` (`$22=1`; GRBL refuses it otherwise with `error:5`), which
    /// also clears an alarm lock; afterwards the position is known again.
    pub fn home(&mut self) -> Result<(), SendError> {
        self.command("$H", HOMING_TIMEOUT)?;
        self.restarted = false;
        Ok(())
    }

    /// Starts a jog (`$J=G91 G21 …`); it runs while the console is used for other things, and
    /// [`Console::jog_cancel`] stops it at once. GRBL refuses a jog beyond the travel with soft
    /// limits on (`error:15`).
    pub fn jog(&mut self, jog: &Jog, opts: &SendOptions) -> Result<(), SendError> {
        let mut line = String::from("$J=G91G21");
        for (a, d) in ['X', 'Y', 'Z'].iter().zip(jog.by) {
            if d != 0.0 {
                line.push_str(&format!("{a}{}", fmt_num(d)));
            }
        }
        line.push_str(&format!("F{}", fmt_num(jog.feed)));
        self.command(&line, opts.command_timeout)
    }

    /// Stops a jog at once (the realtime jog cancel; GRBL ignores it when not jogging).
    pub fn jog_cancel(&mut self) -> Result<(), SendError> {
        self.session(|sess| {
            sess.s.realtime(JOG_CANCEL);
            sess.write().map_err(|e| transport(e, None))
        })
    }

    /// Traces the rectangle `lo`..`hi` (work X and Y, mm) with the tool off at `feed` mm/min,
    /// as jogs at the height the machine stands at, and comes back to where it started; waits
    /// until the machine stands still again. Shows where a job will cut before it does.
    pub fn frame(
        &mut self,
        lo: [f64; 2],
        hi: [f64; 2],
        feed: f64,
        opts: &SendOptions,
    ) -> Result<(), SendError> {
        let start = self
            .status(opts.command_timeout)?
            .and_then(|s| s.work)
            .ok_or(SendError::SetupTimeout {
                command: "?".into(),
                waited: opts.command_timeout,
            })?;
        let corners = [
            [lo[0], lo[1]],
            [hi[0], lo[1]],
            [hi[0], hi[1]],
            [lo[0], hi[1]],
            [lo[0], lo[1]],
            [start[0], start[1]],
        ];
        for c in corners {
            let line = format!(
                "$J=G90G21X{}Y{}F{}",
                fmt_num(c[0]),
                fmt_num(c[1]),
                fmt_num(feed)
            );
            self.command(&line, opts.command_timeout)?;
        }
        let until = Instant::now() + FRAME_TIMEOUT;
        while Instant::now() < until {
            match self.status(opts.command_timeout)? {
                Some(s) if s.state == MachineState::Jog => {
                    self.listen(opts.status_interval.max(READ_SLICE))?;
                }
                _ => return Ok(()),
            }
        }
        Ok(())
    }

    /// Runs a job on this link, as [`super::send_job`] does: on a connected console the job's
    /// handshake soft-resets at once (there is no banner to wait for), and a restart the console
    /// saw counts as one.
    pub fn run_job(
        &mut self,
        job: &crate::job::Job,
        opts: &SendOptions,
        observer: &mut dyn FnMut(&Progress),
        cancel: &CancelToken,
    ) -> Result<SendReport, SendError> {
        let opts = if self.is_connected() {
            let mut o = opts.clone().with_reset_on_connect(true);
            o.controller_restarted |= self.restarted;
            o
        } else {
            opts.clone()
        };
        let r = self.session(|sess| run_job(sess, job, &opts, observer, cancel));
        if r.is_ok() {
            // The job's handshake settled the position question for this link.
            self.restarted = false;
        }
        r
    }
}

fn machine_status<T: Transport + ?Sized>(sess: &Session<'_, T>, s: &StatusReport) -> MachineStatus {
    let k = if sess.report_inches { 25.4 } else { 1.0 };
    let mm = |p: [f64; 3]| [p[0] * k, p[1] * k, p[2] * k];
    MachineStatus {
        state: s.state,
        work: s.work_position(sess.wco).map(mm),
        machine: s.machine_position(sess.wco).map(mm),
    }
}
