//! Streaming HP-GL to a plotter or vinyl cutter over a serial line, with the flow control such
//! devices use: XON/XOFF (the device sends XOFF when its buffer nearly fills; nothing more is
//! sent until XON), the `ESC.B` buffer-space query where the device answers it (never more
//! bytes sent than it said were free), or RTS/CTS (the serial driver holds the bytes; the port
//! is opened with hardware flow control).
//!
//! Bytes are written in small chunks paced at the line's own rate, so that no more than a
//! chunk sits in the operating system's buffer when an XOFF arrives: the device's XOFF margin
//! must exceed one chunk plus the bytes on the wire during one read (documented in
//! [`HpglStreamOptions::chunk`]). Progress is reported after every chunk; an abort sends
//! `ESC.K` (abort: the device clears its buffer) and `PU;` so the tool lifts.
//!
//! A stream steered by an [`HpglControl`] can also pause: the feed stops at the end of an
//! instruction (the next `;`), `PU;` lifts the pen if it was down, and on resume `PD;` puts it
//! back where it was before the rest of the job follows. HP-GL has no acknowledgements: what a
//! stream knows is the bytes the link accepted (and, with the buffer query, what the device says
//! is still free), never what the device has drawn.

mod control;

pub use control::{HpglControl, Steering};

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use serde::Serialize;
use thiserror::Error;

use crate::transport::{Transport, TransportError};

/// XON (DC1).
pub const XON: u8 = 0x11;
/// XOFF (DC3).
pub const XOFF: u8 = 0x13;
/// `ESC.B`: how many bytes are free in the device's buffer.
pub const QUERY_FREE: &[u8] = b"\x1b.B";
/// `ESC.L`: the size of the device's buffer.
pub const QUERY_SIZE: &[u8] = b"\x1b.L";
/// `ESC.K`: abort — the device drops what it has buffered.
pub const ABORT: &[u8] = b"\x1b.K";
/// Longest wait for an XON or a query answer before the device is declared stalled.
pub const STALL_LIMIT: Duration = Duration::from_secs(60);

/// Flow control of the link.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum HpglFlow {
    /// Software flow control: the device sends XOFF (0x13) when its buffer fills and XON (0x11)
    /// when it has room.
    XonXoff,
    /// Hardware flow control on the RTS/CTS lines, handled by the serial port.
    RtsCts,
}

/// How to stream.
#[derive(Clone, Debug, PartialEq)]
pub struct HpglStreamOptions {
    /// How the device holds the sender back.
    pub flow: HpglFlow,
    /// Ask the device for its free buffer space (`ESC.B`) and never exceed it.
    pub buffer_query: bool,
    /// Baud rate of the link: writes are paced at baud/10 bytes per second.
    pub baud: u32,
    /// Largest write (bytes). 16 bytes at 9600 baud is 17 ms on the wire.
    pub chunk: usize,
    /// Bytes kept in reserve below what `ESC.B` reported.
    pub query_reserve: usize,
}

impl HpglStreamOptions {
    /// Largest write by default (bytes).
    pub const DEFAULT_CHUNK: usize = 16;
    /// Options for a link with `flow`, asking for the free buffer when `buffer_query`, paced for
    /// `baud`; default chunk and a 16-byte reserve.
    pub fn new(flow: HpglFlow, buffer_query: bool, baud: u32) -> Self {
        Self {
            flow,
            buffer_query,
            baud,
            chunk: Self::DEFAULT_CHUNK,
            query_reserve: 16,
        }
    }
}

/// Where a stream stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HpglProgress {
    /// Bytes of the job written so far.
    pub sent: usize,
    /// Bytes in the job.
    pub total: usize,
    /// Waiting for XON.
    pub held: bool,
    /// Paused by the operator at an instruction boundary (the pen lifted).
    pub paused: bool,
    /// Whether the pen is down after the last instruction sent (as the job left it; the lift of
    /// a pause is not counted).
    pub pen_down: bool,
    /// The free bytes the device reported last (`ESC.B`), when it is asked.
    pub device_free: Option<usize>,
}

/// What a stream did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HpglReport {
    /// Bytes of the job written to the device.
    pub bytes_sent: usize,
    /// XOFF bytes the device sent.
    pub xoff_received: u64,
    /// XON bytes the device sent.
    pub xon_received: u64,
    /// Buffer queries (`ESC.B`) sent.
    pub queries: u64,
    /// The device's buffer size, when it answered `ESC.L`.
    pub device_buffer: Option<usize>,
    /// Fewest free bytes any `ESC.B` answer reported.
    pub min_free_reported: Option<usize>,
    /// Wall time of the stream (s).
    pub elapsed_s: f64,
    /// True when the stream was aborted (`ESC.K` sent) before the job's end.
    pub aborted: bool,
    /// Pauses (the feed stopped at an instruction boundary, the pen lifted).
    pub pauses: u64,
}

/// Why a stream stopped.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum HpglError {
    #[error(transparent)]
    /// The link failed.
    Transport(#[from] TransportError),
    #[error("the device sent XOFF and no XON for {0:?} (byte {1} of {2} sent): it has stopped")]
    /// XOFF held the stream longer than [`STALL_LIMIT`]: how long, bytes sent, bytes in the job.
    Stalled(Duration, usize, usize),
    #[error("the device did not answer the buffer query ESC.{0} within {1:?}")]
    /// A query (`ESC.B` or `ESC.L`: its letter) went unanswered for the given time.
    NoAnswer(char, Duration),
    #[error(
        "aborted after {0} of {1} bytes: the device was told to drop its buffer (ESC.K) and lift the tool"
    )]
    /// The stream was stopped: bytes sent, bytes in the job.
    Aborted(usize, usize),
}

struct Link<'a, T: Transport> {
    t: &'a mut T,
    held: bool,
    answer: Vec<u8>,
    report: HpglReport,
}

impl<T: Transport> Link<'_, T> {
    /// Reads what the device sent: flow bytes change `held`, other bytes form query answers.
    fn poll(&mut self, timeout: Duration) -> Result<(), HpglError> {
        let mut buf = [0u8; 64];
        let n = self.t.read(&mut buf, timeout)?;
        for &b in &buf[..n] {
            match b {
                XOFF => {
                    self.held = true;
                    self.report.xoff_received += 1;
                }
                XON => {
                    self.held = false;
                    self.report.xon_received += 1;
                }
                _ => self.answer.push(b),
            }
        }
        Ok(())
    }

    /// Sends a query and reads its decimal answer (terminated by CR or LF).
    fn query(&mut self, q: &[u8]) -> Result<usize, HpglError> {
        self.answer.clear();
        self.t.write_all(q)?;
        self.report.queries += 1;
        let t0 = Instant::now();
        loop {
            if let Some(end) = self.answer.iter().position(|b| *b == b'\r' || *b == b'\n') {
                let text = String::from_utf8_lossy(&self.answer[..end])
                    .trim()
                    .to_string();
                self.answer.drain(..=end);
                if let Ok(v) = text.parse::<usize>() {
                    return Ok(v);
                }
                continue;
            }
            if t0.elapsed() > Duration::from_secs(2) {
                return Err(HpglError::NoAnswer(q[2] as char, Duration::from_secs(2)));
            }
            self.poll(Duration::from_millis(20))?;
        }
    }
}

/// Streams `job` (HP-GL bytes) to the device; `abort` stops it (ESC.K, then `PU;`).
pub fn stream_hpgl<T: Transport>(
    transport: &mut T,
    job: &[u8],
    opts: &HpglStreamOptions,
    abort: &AtomicBool,
    progress: &mut dyn FnMut(HpglProgress),
) -> Result<HpglReport, HpglError> {
    stream_hpgl_steered(transport, job, opts, abort, progress)
}

/// Streams `job` (HP-GL bytes) to the device, steered by `control`: a pause stops the feed at
/// the next instruction boundary and lifts the pen (`PU;`), a resume puts it back (`PD;`) and
/// goes on, an abort sends `ESC.K` and `PU;` and ends the stream with [`HpglError::Aborted`].
pub fn stream_hpgl_steered<T: Transport>(
    transport: &mut T,
    job: &[u8],
    opts: &HpglStreamOptions,
    control: &dyn Steering,
    progress: &mut dyn FnMut(HpglProgress),
) -> Result<HpglReport, HpglError> {
    let t0 = Instant::now();
    let mut s = Stream {
        link: Link {
            t: transport,
            held: false,
            answer: Vec::new(),
            report: HpglReport::default(),
        },
        job,
        opts,
        sent: 0,
        pen: Pen::default(),
        // Bytes we may still send before asking ESC.B again.
        allowance: usize::MAX,
        credit: 0.0,
        last: Instant::now(),
        device_free: None,
    };
    if opts.buffer_query {
        s.link.report.device_buffer = Some(s.link.query(QUERY_SIZE)?);
    }
    let rate = f64::from(opts.baud.max(1)) / 10.0;
    let chunk = opts.chunk.max(1);
    while s.sent < job.len() {
        if control.aborted() {
            s.extra(ABORT)?;
            s.extra(b"PU;")?;
            s.link.report.aborted = true;
            return Err(HpglError::Aborted(s.sent, job.len()));
        }
        s.link.poll(Duration::ZERO)?;
        if s.link.held && opts.flow == HpglFlow::XonXoff {
            s.wait_xon(control, progress)?;
            continue;
        }
        if control.paused() && s.at_boundary() {
            s.pause(control, progress)?;
            continue;
        }
        if !s.allowed()? {
            continue;
        }
        // Pace at the line rate so at most one chunk waits in the OS buffer.
        let now = Instant::now();
        s.credit = (s.credit + now.duration_since(s.last).as_secs_f64() * rate).min(chunk as f64);
        s.last = now;
        if s.credit < 1.0 {
            s.link.poll(Duration::from_millis(2))?;
            continue;
        }
        let mut n = (s.credit as usize)
            .min(chunk)
            .min(job.len() - s.sent)
            .min(s.allowance);
        if control.paused() {
            n = n.min(s.next_boundary() - s.sent);
        }
        s.send(n)?;
        progress(s.progress(false));
    }
    s.link.report.elapsed_s = t0.elapsed().as_secs_f64();
    Ok(s.link.report)
}

/// Whether the pen is down, from the instructions sent: `PD` puts it down, `PU`, `SP` and `IN`
/// lift it.
#[derive(Default)]
struct Pen {
    /// Where the instruction being sent starts.
    start: usize,
    down: bool,
}

impl Pen {
    /// Takes in the instructions completed by bytes `at..at + n` of the job.
    fn advance(&mut self, job: &[u8], at: usize, n: usize) {
        for (i, b) in job.iter().enumerate().take(at + n).skip(at) {
            if *b != b';' {
                continue;
            }
            let instr: Vec<u8> = job[self.start..i]
                .iter()
                .filter(|b| b.is_ascii_alphabetic())
                .take(2)
                .map(u8::to_ascii_uppercase)
                .collect();
            match instr.as_slice() {
                b"PD" => self.down = true,
                b"PU" | b"SP" | b"IN" => self.down = false,
                _ => {}
            }
            self.start = i + 1;
        }
    }
}

struct Stream<'a, 'j, T: Transport> {
    link: Link<'a, T>,
    job: &'j [u8],
    opts: &'j HpglStreamOptions,
    sent: usize,
    pen: Pen,
    allowance: usize,
    credit: f64,
    last: Instant,
    device_free: Option<usize>,
}

impl<T: Transport> Stream<'_, '_, T> {
    fn progress(&self, paused: bool) -> HpglProgress {
        HpglProgress {
            sent: self.sent,
            total: self.job.len(),
            held: self.link.held,
            paused,
            pen_down: self.pen.down,
            device_free: self.device_free,
        }
    }

    /// Whether the next byte ends an instruction boundary: nothing sent, or a `;` last.
    fn at_boundary(&self) -> bool {
        self.sent == 0 || self.job[self.sent - 1] == b';'
    }

    /// The end of the instruction being sent (just past its `;`).
    fn next_boundary(&self) -> usize {
        self.job[self.sent..]
            .iter()
            .position(|b| *b == b';')
            .map_or(self.job.len(), |k| self.sent + k + 1)
    }

    /// Writes `n` bytes of the job.
    fn send(&mut self, n: usize) -> Result<(), HpglError> {
        let at = self.sent;
        self.link.t.write_all(&self.job[at..at + n])?;
        self.credit -= n as f64;
        self.sent += n;
        if self.opts.buffer_query {
            self.allowance -= n;
        }
        self.pen.advance(self.job, at, n);
        self.link.report.bytes_sent = self.sent;
        Ok(())
    }

    /// Writes bytes that are not the job's (a pause's `PU;`, an abort), counted against the
    /// buffer the device reported.
    fn extra(&mut self, bytes: &[u8]) -> Result<(), HpglError> {
        self.link.t.write_all(bytes)?;
        if self.opts.buffer_query && self.allowance != usize::MAX {
            self.allowance = self.allowance.saturating_sub(bytes.len());
        }
        Ok(())
    }

    /// With the buffer query: whether bytes may be sent now (asking `ESC.B` when the allowance
    /// is spent, waiting a little when the device has no room).
    fn allowed(&mut self) -> Result<bool, HpglError> {
        if !self.opts.buffer_query {
            return Ok(true);
        }
        if self.allowance == usize::MAX {
            self.allowance = 0;
        }
        if self.allowance > 0 {
            return Ok(true);
        }
        let free = self.link.query(QUERY_FREE)?;
        self.device_free = Some(free);
        let r = &mut self.link.report.min_free_reported;
        *r = Some(r.map_or(free, |m| m.min(free)));
        self.allowance = free.saturating_sub(self.opts.query_reserve);
        if self.allowance == 0 {
            self.link.poll(Duration::from_millis(10))?;
            return Ok(false);
        }
        Ok(true)
    }

    /// Waits for XON (an abort ends the wait); [`STALL_LIMIT`] without it is a stall.
    fn wait_xon(
        &mut self,
        control: &dyn Steering,
        progress: &mut dyn FnMut(HpglProgress),
    ) -> Result<(), HpglError> {
        progress(self.progress(false));
        let waited = Instant::now();
        while self.link.held {
            if control.aborted() {
                break;
            }
            if waited.elapsed() > STALL_LIMIT {
                return Err(HpglError::Stalled(STALL_LIMIT, self.sent, self.job.len()));
            }
            self.link.poll(Duration::from_millis(10))?;
        }
        self.last = Instant::now();
        Ok(())
    }

    /// A pause at an instruction boundary: the pen lifted if it was down, the feed stopped until
    /// the resume (the pen then put back down) or an abort.
    fn pause(
        &mut self,
        control: &dyn Steering,
        progress: &mut dyn FnMut(HpglProgress),
    ) -> Result<(), HpglError> {
        let lift = self.pen.down;
        if lift {
            self.extra(b"PU;")?;
        }
        self.link.report.pauses += 1;
        progress(self.progress(true));
        while control.paused() && !control.aborted() {
            self.link.poll(Duration::from_millis(10))?;
        }
        if control.aborted() {
            return Ok(());
        }
        if lift {
            self.extra(b"PD;")?;
        }
        self.last = Instant::now();
        progress(self.progress(false));
        Ok(())
    }
}
