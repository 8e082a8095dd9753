//! The sans-IO streaming core: a queue of lines to send, the character-counting FIFO of lines
//! in flight, realtime bytes, and the matching of `ok`/`error:N` to lines. It never touches a
//! port: the caller writes what [`Streamer::poll_transmit`] returns and feeds what it reads to
//! [`Streamer::receive`], which returns [`Event`]s.
//!
//! Flow control (`interface.md:35-45`): a line of `n` bytes (plus its `\n`) is only sent when
//! the bytes of all unanswered lines plus `n + 1` fit in the device's RX buffer; every `ok` or
//! `error:` retires the oldest entry. Send-response lines ([`SendMode::SendResponse`]) wait for
//! an empty FIFO and block the FIFO until answered (for EEPROM writes and `$` commands).

use crate::response::{Response, StatusReport, parse_response};
use std::collections::VecDeque;

/// GRBL's serial RX buffer on an Uno (`grbl/serial.h:26-27`), used until `[OPT:..]` says
/// otherwise.
pub const DEFAULT_RX_SIZE: usize = 128;

/// Who a line belongs to, so that responses can be routed back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Tag {
    /// A line of the driver's own (handshake, `$I`, `$$`, `$X`, `$C`, ...), numbered by caller.
    Setup(u32),
    /// The n-th line of a resume preamble.
    Preamble(u32),
    /// The job line with this 0-based index.
    Job(usize),
}

/// How a line is flow-controlled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SendMode {
    /// Character counting: many lines in flight within the RX buffer.
    CharCount,
    /// Send-response: sent alone, nothing else until it is answered.
    SendResponse,
}

/// Something the device said, matched to our lines where it is a stream response.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Event {
    /// `ok` for this line.
    Ack(Tag),
    /// `error:N` for this line.
    Rejected(Tag, u8),
    /// `ALARM:N`.
    Alarm(u8),
    /// A status report.
    Status(StatusReport),
    /// The banner: the controller (re)started; these in-flight lines were discarded unanswered.
    Reset {
        /// Firmware version from the banner.
        version: String,
        /// Lines that were in flight and are lost (in send order).
        lost: Vec<Tag>,
    },
    /// `[OPT:..]`: the streamer has adopted `rx` as the RX buffer size.
    Options {
        /// Planner blocks.
        blocks: u32,
        /// RX buffer bytes.
        rx: u32,
    },
    /// `$n=v` from a settings dump.
    Setting(u16, f64),
    /// `[MSG:..]`.
    Message(String),
    /// Other `[..]` feedback (`VER`, `GC`, ...), verbatim without brackets.
    Feedback(String),
    /// An `ok`/`error` with nothing in flight: the link lost sync.
    Unmatched(Response),
    /// A line that is none of the above (garbage, startup echo, ...).
    Other(String),
}

#[derive(Debug, Clone)]
struct Pending {
    tag: Tag,
    text: String,
    mode: SendMode,
}

#[derive(Debug, Clone)]
struct InFlight {
    tag: Tag,
    bytes: usize,
    mode: SendMode,
}

/// The protocol core. See the module docs.
#[derive(Debug, Clone)]
pub struct Streamer {
    rx_size: usize,
    queue: VecDeque<Pending>,
    in_flight: VecDeque<InFlight>,
    in_flight_bytes: usize,
    realtime: Vec<u8>,
    partial: Vec<u8>,
    feeding: bool,
    bytes_written: u64,
    max_in_flight_bytes: usize,
    last_sent: Option<Tag>,
}

impl Default for Streamer {
    fn default() -> Streamer {
        Streamer::new(DEFAULT_RX_SIZE)
    }
}

impl Streamer {
    /// A streamer for a device with an RX buffer of `rx_size` bytes.
    pub fn new(rx_size: usize) -> Streamer {
        Streamer {
            rx_size: rx_size.max(2),
            queue: VecDeque::new(),
            in_flight: VecDeque::new(),
            in_flight_bytes: 0,
            realtime: Vec::new(),
            partial: Vec::new(),
            feeding: true,
            bytes_written: 0,
            max_in_flight_bytes: 0,
            last_sent: None,
        }
    }

    /// The RX buffer size in use.
    pub fn rx_size(&self) -> usize {
        self.rx_size
    }

    /// Sets the RX buffer size (from `[OPT:..,rx]`).
    pub fn set_rx_size(&mut self, rx: usize) {
        self.rx_size = rx.max(2);
    }

    /// Queues a line (stripped text, no terminator). Returns false (and queues nothing) if the
    /// line could never fit the RX buffer.
    pub fn push(&mut self, tag: Tag, text: impl Into<String>, mode: SendMode) -> bool {
        let text = text.into();
        if text.len() + 1 > self.rx_size {
            return false;
        }
        self.queue.push_back(Pending { tag, text, mode });
        true
    }

    /// Queues a realtime byte (`?`, `!`, `~`, 0x18, overrides); it goes out before any line.
    pub fn realtime(&mut self, byte: u8) {
        self.realtime.push(byte);
    }

    /// Stops (false) or resumes (true) taking lines from the queue; realtime bytes still go.
    pub fn set_feeding(&mut self, on: bool) {
        self.feeding = on;
    }

    /// Whether lines are being taken from the queue.
    pub fn feeding(&self) -> bool {
        self.feeding
    }

    /// Drops every queued, unsent line and returns their tags.
    pub fn clear_queue(&mut self) -> Vec<Tag> {
        self.queue.drain(..).map(|p| p.tag).collect()
    }

    /// Forgets the lines in flight (after a reset the device discarded them) and returns them.
    pub fn forget_in_flight(&mut self) -> Vec<Tag> {
        self.in_flight_bytes = 0;
        self.in_flight.drain(..).map(|f| f.tag).collect()
    }

    /// Number of lines sent and not yet answered.
    pub fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    /// Tags of the lines in flight, oldest first.
    pub fn in_flight_tags(&self) -> Vec<Tag> {
        self.in_flight.iter().map(|f| f.tag).collect()
    }

    /// Bytes of the lines in flight (what the device's RX buffer may hold).
    pub fn in_flight_bytes(&self) -> usize {
        self.in_flight_bytes
    }

    /// The largest number of bytes ever in flight.
    pub fn max_in_flight_bytes(&self) -> usize {
        self.max_in_flight_bytes
    }

    /// Number of queued, unsent lines.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// The tag of the last line handed out by [`Streamer::poll_transmit`].
    pub fn last_sent(&self) -> Option<Tag> {
        self.last_sent
    }

    /// Total bytes handed out by [`Streamer::poll_transmit`].
    pub fn bytes_written(&self) -> u64 {
        self.bytes_written
    }

    /// True when nothing is queued, in flight, or waiting as a realtime byte.
    pub fn is_idle(&self) -> bool {
        self.queue.is_empty() && self.in_flight.is_empty() && self.realtime.is_empty()
    }

    /// The highest job line the next [`Streamer::poll_transmit`] would hand out, if any: what a
    /// write-ahead journal records before the bytes go to the port.
    pub fn next_job_line(&self) -> Option<usize> {
        if !self.feeding {
            return None;
        }
        let mut bytes = self.in_flight_bytes;
        let mut sr = self
            .in_flight
            .iter()
            .any(|f| f.mode == SendMode::SendResponse);
        let mut empty = self.in_flight.is_empty();
        let mut last = None;
        for p in &self.queue {
            let need = p.text.len() + 1;
            let fits = match p.mode {
                SendMode::CharCount => !sr && bytes + need <= self.rx_size,
                SendMode::SendResponse => empty,
            };
            if !fits {
                break;
            }
            bytes += need;
            sr |= p.mode == SendMode::SendResponse;
            empty = false;
            if let Tag::Job(i) = p.tag {
                last = Some(last.map_or(i, |l: usize| l.max(i)));
            }
        }
        last
    }

    /// The next bytes to write, if any may be written now: pending realtime bytes first, then as
    /// many queued lines as the flow control allows, each terminated by a single `\n` (never
    /// `\r\n`, which GRBL answers with two `ok`s).
    pub fn poll_transmit(&mut self) -> Option<Vec<u8>> {
        let mut out = std::mem::take(&mut self.realtime);
        while self.feeding {
            let Some(next) = self.queue.front() else {
                break;
            };
            let need = next.text.len() + 1;
            let blocked_by_sr = self
                .in_flight
                .iter()
                .any(|f| f.mode == SendMode::SendResponse);
            let fits = match next.mode {
                SendMode::CharCount => {
                    !blocked_by_sr && self.in_flight_bytes + need <= self.rx_size
                }
                SendMode::SendResponse => self.in_flight.is_empty(),
            };
            if !fits {
                break;
            }
            let Some(p) = self.queue.pop_front() else {
                break;
            };
            out.extend_from_slice(p.text.as_bytes());
            out.push(b'\n');
            self.in_flight_bytes += need;
            self.max_in_flight_bytes = self.max_in_flight_bytes.max(self.in_flight_bytes);
            self.last_sent = Some(p.tag);
            self.in_flight.push_back(InFlight {
                tag: p.tag,
                bytes: need,
                mode: p.mode,
            });
        }
        if out.is_empty() {
            None
        } else {
            self.bytes_written += out.len() as u64;
            Some(out)
        }
    }

    fn retire(&mut self) -> Option<Tag> {
        let f = self.in_flight.pop_front()?;
        self.in_flight_bytes -= f.bytes;
        Some(f.tag)
    }

    /// Consumes bytes read from the device and returns what they mean. Partial lines are kept
    /// until their terminator arrives.
    pub fn receive(&mut self, bytes: &[u8]) -> Vec<Event> {
        let mut events = Vec::new();
        for &b in bytes {
            if b == b'\n' || b == b'\r' {
                if self.partial.is_empty() {
                    continue;
                }
                let line = String::from_utf8_lossy(&self.partial).into_owned();
                self.partial.clear();
                if let Some(e) = self.receive_line(&line) {
                    events.push(e);
                }
            } else {
                self.partial.push(b);
            }
        }
        events
    }

    /// Consumes one complete received line.
    pub fn receive_line(&mut self, line: &str) -> Option<Event> {
        let r = parse_response(line);
        Some(match r {
            Response::Ok => match self.retire() {
                Some(tag) => Event::Ack(tag),
                None => Event::Unmatched(Response::Ok),
            },
            Response::Error(code) => match self.retire() {
                Some(tag) => Event::Rejected(tag, code),
                None => Event::Unmatched(Response::Error(code)),
            },
            Response::Alarm(code) => Event::Alarm(code),
            Response::Status(s) => Event::Status(s),
            Response::Banner { version } => {
                let lost = self.forget_in_flight();
                Event::Reset { version, lost }
            }
            Response::Options { blocks, rx, .. } => {
                self.set_rx_size(rx as usize);
                Event::Options { blocks, rx }
            }
            Response::Setting(n, v) => Event::Setting(n, v),
            Response::Message(m) => Event::Message(m),
            Response::Version(v) => Event::Feedback(format!("VER:{v}")),
            Response::ParserState(g) => Event::Feedback(format!("GC:{g}")),
            Response::Feedback(f) => Event::Feedback(f),
            Response::StartupLine(s) => Event::Other(format!(">{s}")),
            Response::Other(s) if s.is_empty() => return None,
            Response::Other(s) => Event::Other(s),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn character_counting_fills_but_never_overflows() {
        let mut s = Streamer::new(20);
        for i in 0..5 {
            assert!(s.push(Tag::Job(i), "G1X1", SendMode::CharCount)); // 5 bytes with \n
        }
        let out = s.poll_transmit().unwrap();
        assert_eq!(out, b"G1X1\nG1X1\nG1X1\nG1X1\n"); // 20 bytes exactly
        assert_eq!(s.in_flight_bytes(), 20);
        assert!(s.poll_transmit().is_none());
        assert_eq!(s.receive(b"ok\r\n"), vec![Event::Ack(Tag::Job(0))]);
        assert_eq!(s.poll_transmit().unwrap(), b"G1X1\n");
        assert_eq!(s.max_in_flight_bytes(), 20);
    }

    #[test]
    fn error_retires_the_oldest_line_and_partial_lines_wait() {
        let mut s = Streamer::default();
        s.push(Tag::Job(0), "G1X1", SendMode::CharCount);
        s.push(Tag::Job(1), "G1X2", SendMode::CharCount);
        s.poll_transmit();
        assert!(s.receive(b"err").is_empty());
        assert_eq!(
            s.receive(b"or:20\r\nok\r\n"),
            vec![Event::Rejected(Tag::Job(0), 20), Event::Ack(Tag::Job(1))]
        );
        assert_eq!(s.receive(b"ok\r\n"), vec![Event::Unmatched(Response::Ok)]);
    }

    #[test]
    fn send_response_lines_go_alone() {
        let mut s = Streamer::default();
        s.push(Tag::Job(0), "G1X1", SendMode::CharCount);
        s.push(Tag::Job(1), "$100=80", SendMode::SendResponse);
        s.push(Tag::Job(2), "G1X2", SendMode::CharCount);
        assert_eq!(s.poll_transmit().unwrap(), b"G1X1\n");
        assert!(s.poll_transmit().is_none());
        s.receive(b"ok\n");
        assert_eq!(s.poll_transmit().unwrap(), b"$100=80\n");
        assert!(s.poll_transmit().is_none());
        s.receive(b"ok\n");
        assert_eq!(s.poll_transmit().unwrap(), b"G1X2\n");
    }

    #[test]
    fn realtime_bytes_jump_the_queue_and_banner_loses_in_flight() {
        let mut s = Streamer::new(8);
        s.push(Tag::Job(0), "G1X10", SendMode::CharCount);
        s.push(Tag::Job(1), "G1X20", SendMode::CharCount);
        s.poll_transmit();
        s.realtime(b'?');
        s.realtime(0x85);
        assert_eq!(s.poll_transmit().unwrap(), vec![b'?', 0x85]);
        let ev = s.receive(b"\r\nGrbl 1.1h ['$' for help]\r\n");
        assert_eq!(
            ev,
            vec![Event::Reset {
                version: "1.1h".into(),
                lost: vec![Tag::Job(0)]
            }]
        );
        assert_eq!(s.in_flight_bytes(), 0);
        assert_eq!(s.poll_transmit().unwrap(), b"G1X20\n");
    }

    #[test]
    fn options_set_the_rx_size_and_oversize_lines_are_refused() {
        let mut s = Streamer::new(8);
        assert!(!s.push(Tag::Job(0), "G1X100Y100", SendMode::CharCount));
        assert_eq!(
            s.receive(b"[OPT:V,15,128]\r\n"),
            vec![Event::Options {
                blocks: 15,
                rx: 128
            }]
        );
        assert_eq!(s.rx_size(), 128);
        assert!(s.push(Tag::Job(0), "G1X100Y100", SendMode::CharCount));
    }
}
