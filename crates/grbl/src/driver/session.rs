//! One connection to the controller: the streamer, the transport, and what the controller has
//! said so far (status, offsets, settings, banners); plus the small waits every phase uses.

use super::error::{LineRef, SendError};
use super::{DEFAULT_PLANNER_BLOCKS, DRAIN_ON_CONNECT_LIMIT, READ_SLICE, SendOptions};
use crate::journal::Journal;
use crate::response::{MachineState, StatusReport};
use crate::streamer::{Event, SendMode, Streamer, Tag};
use crate::transport::{Transport, TransportError};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The connection: transport, streamer and what the controller said.
pub(super) struct Session<'a, T: Transport + ?Sized> {
    pub(super) t: &'a mut T,
    pub(super) s: Streamer,
    pub(super) last_rx: Instant,
    pub(super) status: Option<StatusReport>,
    pub(super) status_seq: u64,
    pub(super) wco: [f64; 3],
    pub(super) report_inches: bool,
    pub(super) version: String,
    pub(super) blocks: usize,
    pub(super) settings: BTreeMap<u16, f64>,
    pub(super) messages: Vec<String>,
    pub(super) alarm_lock: bool,
    pub(super) setup_seq: u32,
    /// Banners seen so far.
    pub(super) resets: u64,
    /// Banners this sender caused (its own soft resets, leaving check mode).
    pub(super) resets_caused: u64,
    /// The last `[GC:...]` parser state (`$G`).
    pub(super) last_gc: Option<String>,
    /// Other `[...]` feedback (`$#` lines), at most [`FEEDBACK_KEPT`]; cleared by whoever reads it.
    pub(super) feedback: Vec<String>,
}

/// First status poll after opening, and the poll interval after it while booting.
const BOOT_POLL: Duration = Duration::from_millis(100);

/// Feedback lines kept for the reader of `$#` (it prints ten).
const FEEDBACK_KEPT: usize = 64;

/// What a session learnt about the controller, carried from one session on a link to the next
/// (a console between jobs): everything but the transport.
#[derive(Debug, Clone)]
pub(super) struct Known {
    s: Streamer,
    status: Option<StatusReport>,
    status_seq: u64,
    wco: [f64; 3],
    report_inches: bool,
    version: String,
    blocks: usize,
    settings: BTreeMap<u16, f64>,
    alarm_lock: bool,
    setup_seq: u32,
    resets: u64,
    resets_caused: u64,
}

impl<'a, T: Transport + ?Sized> Session<'a, T> {
    /// A session on `t`, knowing nothing of the controller yet.
    pub(super) fn new(t: &'a mut T) -> Self {
        Session {
            t,
            s: Streamer::default(),
            last_rx: Instant::now(),
            status: None,
            status_seq: 0,
            wco: [0.0; 3],
            report_inches: false,
            version: String::new(),
            blocks: DEFAULT_PLANNER_BLOCKS,
            settings: BTreeMap::new(),
            messages: Vec::new(),
            alarm_lock: false,
            setup_seq: 0,
            resets: 0,
            resets_caused: 0,
            last_gc: None,
            feedback: Vec::new(),
        }
    }

    /// A session on `t` that goes on from what an earlier one on the same link learnt.
    pub(super) fn resume(t: &'a mut T, k: Known) -> Self {
        Session {
            t,
            s: k.s,
            last_rx: Instant::now(),
            status: k.status,
            status_seq: k.status_seq,
            wco: k.wco,
            report_inches: k.report_inches,
            version: k.version,
            blocks: k.blocks,
            settings: k.settings,
            messages: Vec::new(),
            alarm_lock: k.alarm_lock,
            setup_seq: k.setup_seq,
            resets: k.resets,
            resets_caused: k.resets_caused,
            last_gc: None,
            feedback: Vec::new(),
        }
    }

    /// What this session learnt, for the next one on the same link.
    pub(super) fn known(&self) -> Known {
        Known {
            s: self.s.clone(),
            status: self.status.clone(),
            status_seq: self.status_seq,
            wco: self.wco,
            report_inches: self.report_inches,
            version: self.version.clone(),
            blocks: self.blocks,
            settings: self.settings.clone(),
            alarm_lock: self.alarm_lock,
            setup_seq: self.setup_seq,
            resets: self.resets,
            resets_caused: self.resets_caused,
        }
    }

    /// Soft-resets the controller (0x18); its banner is this sender's doing, not a restart.
    pub(super) fn soft_reset(&mut self) {
        self.s.realtime(0x18);
        self.reset_caused();
    }

    /// A banner is coming that this sender caused (a soft reset, leaving check mode).
    pub(super) fn reset_caused(&mut self) {
        self.resets_caused += 1;
    }

    /// Banners nobody here asked for: the controller restarted by itself (power, a reset on
    /// opening the port, a watchdog) that many times.
    pub(super) fn restarts(&self) -> u64 {
        self.resets.saturating_sub(self.resets_caused)
    }

    pub(super) fn write(&mut self) -> Result<(), TransportError> {
        while let Some(bytes) = self.s.poll_transmit() {
            self.t.write_all(&bytes)?;
        }
        Ok(())
    }

    pub(super) fn pump(&mut self, wait: Duration) -> Result<Vec<Event>, TransportError> {
        self.write()?;
        let mut buf = [0u8; 1024];
        let n = self.t.read(&mut buf, wait)?;
        if n == 0 {
            return Ok(Vec::new());
        }
        self.last_rx = Instant::now();
        let events = self.s.receive(&buf[..n]);
        for e in &events {
            match e {
                Event::Status(st) => {
                    if let Some(w) = st.wco {
                        self.wco = w;
                    }
                    self.alarm_lock = st.state == MachineState::Alarm;
                    self.status = Some(st.clone());
                    self.status_seq += 1;
                }
                Event::Options { blocks, .. } => self.blocks = *blocks as usize,
                Event::Setting(n, v) => {
                    self.settings.insert(*n, *v);
                    if *n == 13 {
                        self.report_inches = *v != 0.0;
                    }
                }
                Event::Message(m) => {
                    if m.contains("unlock") {
                        self.alarm_lock = true;
                    }
                    self.messages.push(m.clone());
                }
                Event::Alarm(_) => self.alarm_lock = true,
                Event::Feedback(f) if f.starts_with("GC:") => self.last_gc = Some(f.clone()),
                Event::Feedback(f) if self.feedback.len() < FEEDBACK_KEPT => {
                    self.feedback.push(f.clone());
                }
                Event::Reset { version, .. } => {
                    self.resets += 1;
                    self.version = version.clone();
                    self.wco = [0.0; 3];
                }
                _ => {}
            }
        }
        Ok(events)
    }

    /// Waits up to `boot_wait` for the controller to show that it runs: its banner (it just
    /// started: power-up, or the reset of opening the port after its bootloader) or an answer to
    /// `?`, asked every [`BOOT_POLL`] (it was running already; a controller in its bootloader
    /// answers nothing). True for a banner; a banner later than this is still seen as a restart
    /// (see `handshake::connect`).
    pub(super) fn wait_boot(&mut self, boot_wait: Duration) -> Result<bool, TransportError> {
        let (resets, seq) = (self.resets, self.status_seq);
        let t0 = Instant::now();
        let mut poll = t0 + BOOT_POLL;
        while t0.elapsed() < boot_wait {
            if self.resets > resets {
                // Let the push messages after the banner (an alarm lock) arrive.
                let settle = Instant::now() + Duration::from_millis(30);
                while Instant::now() < settle {
                    self.pump(Duration::from_millis(10))?;
                }
                return Ok(true);
            }
            if self.status_seq != seq {
                return Ok(false);
            }
            if Instant::now() >= poll {
                self.s.realtime(b'?');
                poll = Instant::now() + BOOT_POLL;
            }
            self.pump(READ_SLICE)?;
        }
        Ok(self.resets > resets)
    }

    pub(super) fn wait_banner(&mut self, timeout: Duration) -> Result<bool, TransportError> {
        let seen = self.resets;
        self.wait_banner_after(seen, timeout)
    }

    /// Waits until more than `seen` banners have arrived (one may already have come in while
    /// waiting for something else), then lets the push messages that follow it arrive.
    pub(super) fn wait_banner_after(
        &mut self,
        seen: u64,
        timeout: Duration,
    ) -> Result<bool, TransportError> {
        let until = Instant::now() + timeout;
        while self.resets <= seen {
            if Instant::now() >= until {
                return Ok(false);
            }
            self.pump(READ_SLICE)?;
        }
        let settle = Instant::now() + Duration::from_millis(30);
        while Instant::now() < settle {
            self.pump(Duration::from_millis(10))?;
        }
        Ok(true)
    }

    /// Ends whatever partial line an earlier host left in GRBL's line buffer (a sender killed
    /// mid-line), so the next command is read alone: a bare newline, whose answer (`ok`, or the
    /// partial line's error) nobody waits for, then a short wait for that answer.
    pub(super) fn clear_line(&mut self) -> Result<(), TransportError> {
        self.t.write_all(b"\n")?;
        let until = Instant::now() + Duration::from_millis(250);
        while Instant::now() < until {
            if self
                .pump(READ_SLICE)?
                .iter()
                .any(|e| matches!(e, Event::Unmatched(_)))
            {
                break;
            }
        }
        Ok(())
    }

    /// Sends one command with send-response and waits for its answer.
    pub(super) fn command(
        &mut self,
        text: &str,
        timeout: Duration,
    ) -> Result<Result<(), u8>, SendError> {
        self.setup_seq += 1;
        let tag = Tag::Setup(self.setup_seq);
        self.s.push(tag, text, SendMode::SendResponse);
        let until = Instant::now() + timeout;
        while Instant::now() < until {
            let evs = self.pump(READ_SLICE).map_err(|e| transport(e, None))?;
            for e in evs {
                match e {
                    Event::Ack(t) if t == tag => return Ok(Ok(())),
                    Event::Rejected(t, code) if t == tag => return Ok(Err(code)),
                    Event::Reset { lost, .. } if lost.contains(&tag) => {
                        // Re-send after an unexpected reset during the handshake.
                        self.s.push(tag, text, SendMode::SendResponse);
                    }
                    _ => {}
                }
            }
        }
        Err(SendError::SetupTimeout {
            command: text.into(),
            waited: timeout,
        })
    }

    pub(super) fn command_ok(&mut self, text: &str, timeout: Duration) -> Result<(), SendError> {
        match self.command(text, timeout)? {
            Ok(()) => Ok(()),
            Err(code) => Err(SendError::SetupRejected {
                command: text.into(),
                code,
            }),
        }
    }

    /// Requests a status report and waits for it.
    pub(super) fn query_status(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<StatusReport>, TransportError> {
        self.query_status_seeing(timeout, &mut |_| {})
    }

    /// [`Session::query_status`], handing everything else the controller says meanwhile (the
    /// answers to lines still in flight) to `seen`, in order.
    pub(super) fn query_status_seeing(
        &mut self,
        timeout: Duration,
        seen: &mut dyn FnMut(Event),
    ) -> Result<Option<StatusReport>, TransportError> {
        let seq = self.status_seq;
        self.s.realtime(b'?');
        let until = Instant::now() + timeout;
        let mut resend = Instant::now() + Duration::from_millis(250);
        while Instant::now() < until {
            for e in self.pump(READ_SLICE)? {
                seen(e);
            }
            if self.status_seq != seq {
                return Ok(self.status.clone());
            }
            if Instant::now() > resend {
                // A `?` right before or after a reset may go unanswered.
                self.s.realtime(b'?');
                resend = Instant::now() + Duration::from_millis(250);
            }
        }
        Ok(None)
    }

    pub(super) fn work_position(&self) -> Option<[f64; 3]> {
        let p = self.status.as_ref()?.work_position(self.wco)?;
        let k = if self.report_inches { 25.4 } else { 1.0 };
        Some([p[0] * k, p[1] * k, p[2] * k])
    }
}

/// Stops a run: records why in the journal, makes the journal durable, and returns `err`.
pub(super) fn stop_noted<T>(
    journal: &mut Option<Journal>,
    why: &str,
    err: SendError,
) -> Result<T, SendError> {
    if let Some(j) = journal.as_mut() {
        j.note(why);
        j.sync()?;
    }
    Err(err)
}

pub(super) fn transport(source: TransportError, last_done: Option<LineRef>) -> SendError {
    SendError::Transport { source, last_done }
}

/// Waits while the controller reports motion (`Run`, `Jog`, `Home`, a hold still braking): the
/// planner it kept running while no host was connected must finish before anything resets it.
pub(super) fn wait_until_still<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    opts: &SendOptions,
) -> Result<(), TransportError> {
    let until = Instant::now() + DRAIN_ON_CONNECT_LIMIT;
    while Instant::now() < until {
        match sess.query_status(Duration::from_millis(500))? {
            Some(st)
                if matches!(
                    st.state,
                    MachineState::Run
                        | MachineState::Jog
                        | MachineState::Home
                        | MachineState::Hold { complete: false }
                ) =>
            {
                let next = Instant::now() + opts.status_interval;
                while Instant::now() < next {
                    sess.pump(READ_SLICE)?;
                }
            }
            _ => return Ok(()),
        }
    }
    Ok(())
}
