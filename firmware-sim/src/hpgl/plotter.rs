//! The plotter's serial side: a receive buffer of a fixed size that drops bytes arriving when
//! it is full (counted), XOFF sent when the free space falls to a threshold and XON when it
//! recovers, `ESC.B` (free bytes) and `ESC.L` (buffer size) answered at once with a decimal
//! number and CR, `ESC.K` (abort) clearing the buffer, and instructions executed from the
//! buffer at the device's own pace (a fixed time per byte plus the pen's travel at its speed).

use std::collections::VecDeque;

use serde::Serialize;

use super::interp::Interpreter;
use super::{XOFF, XON};

/// Device settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotterConfig {
    /// Receive buffer size, bytes (HP 7475A: 1024; small vinyl cutters: 256–1024).
    pub buffer: usize,
    /// XOFF is sent when at most this many bytes are free.
    pub xoff_free: usize,
    /// XON is sent when at least this many bytes are free again.
    pub xon_free: usize,
    /// Time to parse one byte, s.
    pub byte_time_s: f64,
    /// Pen speed when the job sets none, mm/s.
    pub speed_mm_s: f64,
    /// Answer `ESC.B`/`ESC.L`.
    pub buffer_query: bool,
}

impl Default for PlotterConfig {
    fn default() -> Self {
        Self {
            buffer: 512,
            xoff_free: 128,
            xon_free: 384,
            byte_time_s: 2e-4,
            speed_mm_s: 200.0,
            buffer_query: true,
        }
    }
}

/// What happened on the device's side.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PlotterStats {
    pub bytes_received: u64,
    /// Bytes that arrived while the buffer was full: lost.
    pub bytes_lost: u64,
    /// Most bytes ever waiting in the buffer.
    pub high_water: usize,
    pub xoff_sent: u64,
    pub xon_sent: u64,
    pub queries: u64,
    pub aborts: u64,
    pub commands: u64,
}

/// The device core (no I/O): bytes in, bytes out, a clock.
#[derive(Debug)]
pub struct Plotter {
    pub config: PlotterConfig,
    pub interp: Interpreter,
    pub stats: PlotterStats,
    buf: VecDeque<u8>,
    out: Vec<u8>,
    /// Escape sequence being received (`ESC`, `.`, letter).
    esc: Vec<u8>,
    instr: String,
    xoff: bool,
    busy_s: f64,
    clock: f64,
}

impl Plotter {
    pub fn new(config: PlotterConfig) -> Self {
        Self {
            config,
            interp: Interpreter::default(),
            stats: PlotterStats::default(),
            buf: VecDeque::new(),
            out: Vec::new(),
            esc: Vec::new(),
            instr: String::new(),
            xoff: false,
            busy_s: 0.0,
            clock: 0.0,
        }
    }

    /// Free bytes in the receive buffer.
    pub fn free(&self) -> usize {
        self.config.buffer - self.buf.len()
    }

    /// Bytes from the line.
    pub fn receive(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.stats.bytes_received += 1;
            if !self.esc.is_empty() || b == 0x1b {
                self.esc.push(b);
                self.escape();
                continue;
            }
            if self.buf.len() >= self.config.buffer {
                self.stats.bytes_lost += 1;
                continue;
            }
            self.buf.push_back(b);
            self.stats.high_water = self.stats.high_water.max(self.buf.len());
        }
        self.flow();
    }

    /// Device-control escapes are handled on arrival, not queued.
    fn escape(&mut self) {
        match self.esc.as_slice() {
            [0x1b] | [0x1b, b'.'] => {}
            [0x1b, b'.', c] => {
                let c = *c;
                self.esc.clear();
                match c {
                    b'B' if self.config.buffer_query => {
                        self.stats.queries += 1;
                        let s = format!("{}\r", self.free());
                        self.out.extend_from_slice(s.as_bytes());
                    }
                    b'L' if self.config.buffer_query => {
                        self.stats.queries += 1;
                        let s = format!("{}\r", self.config.buffer);
                        self.out.extend_from_slice(s.as_bytes());
                    }
                    b'K' => {
                        self.stats.aborts += 1;
                        self.buf.clear();
                        self.instr.clear();
                        self.interp.pen_down = false;
                    }
                    _ => {}
                }
            }
            _ => self.esc.clear(),
        }
    }

    fn flow(&mut self) {
        if !self.xoff && self.free() <= self.config.xoff_free {
            self.xoff = true;
            self.stats.xoff_sent += 1;
            self.out.push(XOFF);
        } else if self.xoff && self.free() >= self.config.xon_free {
            self.xoff = false;
            self.stats.xon_sent += 1;
            self.out.push(XON);
        }
    }

    /// Advances the device's clock by `dt` seconds, executing from the buffer.
    pub fn tick(&mut self, dt: f64) {
        self.clock += dt;
        self.busy_s -= dt;
        while self.busy_s <= 0.0 {
            let Some(b) = self.buf.pop_front() else {
                self.busy_s = 0.0;
                break;
            };
            self.busy_s += self.config.byte_time_s;
            if b == b';' {
                let before = self.interp.travel_mm;
                let instr = std::mem::take(&mut self.instr);
                self.interp.execute(&instr);
                self.stats.commands = self.interp.commands;
                let speed = self
                    .interp
                    .velocity_cm_s
                    .map_or(self.config.speed_mm_s, |v| v * 10.0);
                self.busy_s += (self.interp.travel_mm - before) / speed.max(1e-3);
            } else if !b.is_ascii_control() && self.instr.len() < 4096 {
                self.instr.push(b as char);
            }
        }
        self.flow();
    }

    /// Bytes the device sends back (XON/XOFF, query answers).
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// True when everything received has been executed.
    pub fn idle(&self) -> bool {
        self.buf.is_empty() && self.busy_s <= 0.0
    }

    pub fn clock(&self) -> f64 {
        self.clock
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrun_loses_bytes_and_xoff_comes_first() {
        let mut p = Plotter::new(PlotterConfig {
            buffer: 20,
            xoff_free: 4,
            xon_free: 12,
            ..PlotterConfig::default()
        });
        // Pen 1 selected, then one pen-down move; the overrun cuts the second move's tail.
        p.receive(b"SP1;PU0,0;PD40,0;PD40,40;");
        assert_eq!(p.stats.bytes_lost, 25 - 20);
        assert_eq!(p.take_output(), vec![XOFF]);
        p.receive(b"\x1b.B\x1b.L");
        assert_eq!(p.take_output(), b"0\r20\r".to_vec());
        for _ in 0..1000 {
            p.tick(0.01);
        }
        assert!(p.idle());
        assert_eq!(p.take_output(), vec![XON]);
        assert_eq!(p.interp.pos, [40, 0]);
        assert_eq!(p.interp.trace.len(), 1);
    }
}
