//! A scripted in-memory GRBL for deterministic unit tests of the driver: a 128-byte RX buffer
//! that drops on overflow, a few lines parsed per read (so flow control matters), instant
//! motion, `$I`/`$$`/`$X`/`$C`, realtime bytes and injectable faults.

use crate::transport::{Transport, TransportError};
use std::collections::VecDeque;
use std::time::Duration;

/// Lines the sender writes on its own, not from the job: the dwell that proves the planner
/// empty at the end, and the tool-off sequence after a stop.
pub(crate) const HOUSEKEEPING: [&str; 4] = ["G4P0.01", "M5", "S0", "M9"];

pub(crate) struct FakeGrbl {
    rx: VecDeque<u8>,
    pub rx_cap: usize,
    out: VecDeque<u8>,
    /// G-code lines executed (motion or not), in order, apart from the sender's own
    /// housekeeping ([`HOUSEKEEPING`]).
    pub executed: Vec<String>,
    /// The sender's housekeeping lines executed (the end-of-job dwell, the tool-off sequence).
    pub housekeeping: Vec<String>,
    /// Every line received, in order.
    pub received: Vec<String>,
    pub max_rx_fill: usize,
    pub dropped: usize,
    pub lines_per_read: usize,
    pub pos: [f64; 3],
    incremental: bool,
    inch: bool,
    pub alarm: bool,
    check: bool,
    hold: bool,
    pub settings: Vec<(u16, f64)>,
    pub error_at: Option<(usize, u8)>,
    pub alarm_at: Option<(usize, u8)>,
    pub reset_at: Option<usize>,
    pub hangup_at: Option<usize>,
    pub swallow_at: Option<usize>,
    pub corrupt_at: Option<usize>,
    pub reject: fn(&str) -> Option<u8>,
    hung: bool,
    pub realtime_log: Vec<u8>,
    /// A send-response violation: a `$x=` line arrived with other bytes still buffered.
    pub eeprom_violation: bool,
}

fn no_reject(_: &str) -> Option<u8> {
    None
}

impl FakeGrbl {
    pub fn new(banner_on_start: bool) -> FakeGrbl {
        let mut f = FakeGrbl {
            rx: VecDeque::new(),
            rx_cap: 128,
            out: VecDeque::new(),
            executed: Vec::new(),
            housekeeping: Vec::new(),
            received: Vec::new(),
            max_rx_fill: 0,
            dropped: 0,
            lines_per_read: 2,
            pos: [0.0; 3],
            incremental: false,
            inch: false,
            alarm: false,
            check: false,
            hold: false,
            settings: vec![
                (10, 1.0),
                (11, 0.01),
                (12, 0.002),
                (110, 5000.0),
                (111, 5000.0),
                (112, 500.0),
            ],
            error_at: None,
            alarm_at: None,
            reset_at: None,
            hangup_at: None,
            swallow_at: None,
            corrupt_at: None,
            reject: no_reject,
            hung: false,
            realtime_log: Vec::new(),
            eeprom_violation: false,
        };
        if banner_on_start {
            f.banner();
        }
        f
    }

    fn say(&mut self, s: &str) {
        self.out.extend(s.as_bytes());
        self.out.extend(b"\r\n");
    }

    fn banner(&mut self) {
        self.say("");
        self.say("Grbl 1.1h ['$' for help]");
        if self.alarm {
            self.say("[MSG:'$H'|'$X' to unlock]");
        }
    }

    pub fn start_locked(mut self) -> FakeGrbl {
        self.alarm = true;
        self.out.clear();
        self.banner();
        self
    }

    fn status(&mut self) {
        let st = if self.alarm {
            "Alarm"
        } else if self.hold {
            "Hold:0"
        } else if self.check {
            "Check"
        } else {
            "Idle"
        };
        let p = self.pos;
        let s = format!(
            "<{st}|MPos:{:.3},{:.3},{:.3}|FS:0,0|WCO:0.000,0.000,0.000>",
            p[0], p[1], p[2]
        );
        self.say(&s);
    }

    fn soft_reset(&mut self) {
        self.rx.clear();
        self.check = false;
        self.hold = false;
        self.incremental = false;
        self.inch = false;
        self.banner();
    }

    fn line(&mut self, line: String) {
        self.received.push(line.clone());
        let n = self.received.len();
        if self.hangup_at == Some(n) {
            self.hung = true;
            return;
        }
        if self.reset_at == Some(n) {
            self.soft_reset();
            return;
        }
        if self.swallow_at == Some(n) {
            return;
        }
        if let Some((at, code)) = self.error_at
            && at == n
        {
            self.say(&format!("error:{code}"));
            return;
        }
        if line.is_empty() {
            self.say("ok");
            return;
        }
        if let Some(cmd) = line.strip_prefix('$') {
            match cmd {
                "I" => {
                    self.say("[VER:1.1h.20190830:]");
                    self.say("[OPT:V,15,128]");
                }
                "$" => {
                    for (k, v) in self.settings.clone() {
                        self.say(&format!("${k}={v:.3}"));
                    }
                }
                "G" => self.say("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"),
                "X" => {
                    self.alarm = false;
                    self.say("[MSG:Caution: Unlocked]");
                }
                "C" => {
                    self.check = !self.check;
                    if self.check {
                        self.say("[MSG:Enabled]");
                    } else {
                        self.say("[MSG:Disabled]");
                        self.say("ok");
                        self.soft_reset();
                        return;
                    }
                }
                c if c.contains('=') => {
                    if !self.rx.is_empty() {
                        self.eeprom_violation = true;
                    }
                    self.executed.push(line.clone());
                }
                _ => {
                    self.say("error:3");
                    return;
                }
            }
            self.say("ok");
            return;
        }
        if self.alarm {
            self.say("error:9");
            return;
        }
        if let Some(code) = (self.reject)(&line) {
            self.say(&format!("error:{code}"));
            return;
        }
        if self.check {
            self.say("ok");
            return;
        }
        if HOUSEKEEPING.contains(&line.as_str()) {
            self.housekeeping.push(line);
            self.say("ok");
            return;
        }
        self.execute(&line, n);
        self.say("ok");
        if let Some((at, code)) = self.alarm_at
            && at == n
        {
            self.alarm = true;
            self.say(&format!("ALARM:{code}"));
        }
    }

    fn execute(&mut self, line: &str, n: usize) {
        let b = line.as_bytes();
        let mut i = 0;
        let mut target = self.pos;
        let mut has_axis = false;
        while i < b.len() {
            let l = b[i];
            i += 1;
            let s = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.' || b[i] == b'-') {
                i += 1;
            }
            let v: f64 = line[s..i].parse().unwrap_or(0.0);
            let k = if self.inch { 25.4 } else { 1.0 };
            match l {
                b'G' if v == 90.0 => self.incremental = false,
                b'G' if v == 91.0 => self.incremental = true,
                b'G' if v == 20.0 => self.inch = true,
                b'G' if v == 21.0 => self.inch = false,
                b'X' | b'Y' | b'Z' => {
                    let a = (l - b'X') as usize;
                    has_axis = true;
                    let mut val = v * k;
                    if self.corrupt_at == Some(n) && a == 0 {
                        val += 1.0;
                    }
                    target[a] = if self.incremental {
                        self.pos[a] + val
                    } else {
                        val
                    };
                }
                _ => {}
            }
        }
        if has_axis {
            self.pos = target;
        }
        self.executed.push(line.to_string());
    }
}

impl Transport for FakeGrbl {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        if self.hung {
            return Err(TransportError::HangUp("fake device closed".into()));
        }
        for &b in bytes {
            match b {
                b'?' | b'!' | b'~' | 0x18 | 0x80..=0xff => {
                    self.realtime_log.push(b);
                    match b {
                        b'?' => self.status(),
                        b'!' => self.hold = true,
                        b'~' => self.hold = false,
                        0x18 => self.soft_reset(),
                        _ => {}
                    }
                }
                _ => {
                    if self.rx.len() < self.rx_cap {
                        self.rx.push_back(b);
                        self.max_rx_fill = self.max_rx_fill.max(self.rx.len());
                    } else {
                        self.dropped += 1;
                    }
                }
            }
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout: Duration) -> Result<usize, TransportError> {
        if self.hung {
            return Err(TransportError::HangUp("fake device closed".into()));
        }
        let mut done = 0;
        while done < self.lines_per_read && !self.hold {
            let Some(end) = self.rx.iter().position(|&b| b == b'\n') else {
                break;
            };
            let bytes: Vec<u8> = self.rx.drain(..=end).collect();
            let text = String::from_utf8_lossy(&bytes[..bytes.len() - 1]).into_owned();
            self.line(text);
            done += 1;
            if self.hung {
                return Err(TransportError::HangUp("fake device closed".into()));
            }
        }
        let n = buf.len().min(self.out.len());
        for (i, b) in self.out.drain(..n).enumerate() {
            buf[i] = b;
        }
        Ok(n)
    }
}
