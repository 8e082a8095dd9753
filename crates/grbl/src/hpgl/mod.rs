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

use std::sync::atomic::{AtomicBool, Ordering};
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
    let t0 = Instant::now();
    let mut link = Link {
        t: transport,
        held: false,
        answer: Vec::new(),
        report: HpglReport::default(),
    };
    let rate = f64::from(opts.baud.max(1)) / 10.0;
    let chunk = opts.chunk.max(1);
    if opts.buffer_query {
        link.report.device_buffer = Some(link.query(QUERY_SIZE)?);
    }
    // Bytes we may still send before asking ESC.B again.
    let mut allowance = usize::MAX;
    let mut sent = 0;
    let mut credit = 0.0f64;
    let mut last = Instant::now();
    while sent < job.len() {
        if abort.load(Ordering::SeqCst) {
            link.t.write_all(ABORT)?;
            link.t.write_all(b"PU;")?;
            link.report.aborted = true;
            return Err(HpglError::Aborted(sent, job.len()));
        }
        link.poll(Duration::ZERO)?;
        if link.held && opts.flow == HpglFlow::XonXoff {
            progress(HpglProgress {
                sent,
                total: job.len(),
                held: true,
            });
            let waited = Instant::now();
            while link.held {
                if abort.load(Ordering::SeqCst) {
                    break;
                }
                if waited.elapsed() > STALL_LIMIT {
                    return Err(HpglError::Stalled(STALL_LIMIT, sent, job.len()));
                }
                link.poll(Duration::from_millis(10))?;
            }
            last = Instant::now();
            continue;
        }
        if opts.buffer_query && allowance == 0 {
            let free = link.query(QUERY_FREE)?;
            let r = &mut link.report.min_free_reported;
            *r = Some(r.map_or(free, |m| m.min(free)));
            allowance = free.saturating_sub(opts.query_reserve);
            if allowance == 0 {
                link.poll(Duration::from_millis(10))?;
                continue;
            }
        }
        if opts.buffer_query && allowance == usize::MAX {
            allowance = 0;
            continue;
        }
        // Pace at the line rate so at most one chunk waits in the OS buffer.
        let now = Instant::now();
        credit = (credit + now.duration_since(last).as_secs_f64() * rate).min(chunk as f64);
        last = now;
        if credit < 1.0 {
            link.poll(Duration::from_millis(2))?;
            continue;
        }
        let n = (credit as usize)
            .min(chunk)
            .min(job.len() - sent)
            .min(allowance);
        link.t.write_all(&job[sent..sent + n])?;
        credit -= n as f64;
        sent += n;
        if opts.buffer_query {
            allowance -= n;
        }
        link.report.bytes_sent = sent;
        progress(HpglProgress {
            sent,
            total: job.len(),
            held: false,
        });
    }
    link.report.elapsed_s = t0.elapsed().as_secs_f64();
    Ok(link.report)
}
