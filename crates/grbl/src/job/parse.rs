//! Reading a job the way GRBL reads it: each raw line stripped as GRBL's pre-parser strips it,
//! split into words, and run through a small interpreter that tracks the modal state and the
//! program position, so every line knows the state before it, its path and its length.

use super::arc::arc_points;
use super::modal::{ModalState, MotionMode, Spindle, Units};
use super::{
    Job, JobError, JobLine, LineKind, MAX_LINE_CHARS, MM_PER_INCH, MachineLimits, ZERO_LENGTH_MM,
    add, dist, fnv1a64,
};

/// Strips a raw line the way GRBL's pre-parser does (`protocol.c:120-144`): drops whitespace
/// and control characters, `(...)` and `;` comments and `/`, upper-cases letters; a `%` line
/// becomes empty (GRBL would answer `error:1`).
pub fn strip_line(raw: &str) -> String {
    let mut out = String::with_capacity(raw.len());
    let mut in_paren = false;
    for c in raw.chars() {
        if in_paren {
            if c == ')' {
                in_paren = false;
            }
            continue;
        }
        match c {
            '(' => in_paren = true,
            ';' => break,
            '/' | '%' => {}
            c if c.is_whitespace() || c.is_control() => {}
            c => out.push(c.to_ascii_uppercase()),
        }
    }
    out
}

/// Splits a stripped G-code line into (letter, value) words.
pub(super) fn words(text: &str) -> Result<Vec<(char, f64)>, char> {
    let b = text.as_bytes();
    let mut i = 0;
    let mut out = Vec::new();
    while i < b.len() {
        let letter = b[i] as char;
        i += 1;
        let start = i;
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.' || b[i] == b'-' || b[i] == b'+')
        {
            i += 1;
        }
        let v: f64 = text[start..i].parse().map_err(|_| letter)?;
        if !v.is_finite() {
            return Err(letter);
        }
        out.push((letter, v));
    }
    Ok(out)
}

/// The words of one G-code line the interpreter acts on (modal words are applied to the state
/// as they are read, as GRBL does).
#[derive(Debug, Default)]
struct LineWords {
    kind: Option<LineKind>,
    axis: [Option<f64>; 3],
    ijk: [Option<f64>; 3],
    r: Option<f64>,
    motion: Option<MotionMode>,
    /// The non-modal G command ×10 (G4 = 40, G92.1 = 921, ...).
    non_modal: Option<i64>,
}

/// What one line's motion did.
#[derive(Debug, Default)]
struct LineMotion {
    moves: bool,
    length: f64,
    /// Chord points of an arc (G92-free), empty otherwise.
    arc: Vec<[f64; 3]>,
}

/// The interpreter: modal state and program position, plus what the whole job needs (extent,
/// G92 use, safe Z).
pub(super) struct Interpreter {
    st: ModalState,
    lines: Vec<JobLine>,
    uses_g92: bool,
    lo: [f64; 3],
    hi: [f64; 3],
    z_moves: bool,
    max_z: f64,
    arc_tolerance: f64,
    needs_laser_mode: bool,
}

impl Interpreter {
    /// An interpreter in GRBL's power-up state, splitting arcs within `arc_tolerance` (`$12`).
    pub(super) fn new(arc_tolerance: f64) -> Interpreter {
        Interpreter::starting_at(arc_tolerance, ModalState::default())
    }

    /// An interpreter whose program starts in state `st` (the controller's work coordinate
    /// system, G92 offset and position).
    pub(super) fn starting_at(arc_tolerance: f64, st: ModalState) -> Interpreter {
        Interpreter {
            uses_g92: st.g92 != [0.0; 3],
            st,
            lines: Vec::new(),
            lo: [f64::INFINITY; 3],
            hi: [f64::NEG_INFINITY; 3],
            z_moves: false,
            max_z: f64::NEG_INFINITY,
            arc_tolerance,
            needs_laser_mode: false,
        }
    }

    /// Reads raw line `source_line` (1-based) of the file.
    pub(super) fn line(&mut self, source_line: usize, raw: &str) -> Result<(), JobError> {
        let t = strip_line(raw);
        // A comment saying `$32=1` (flatcut's laser header: "laser: needs $32=1").
        if raw.contains("$32=1") && !t.contains("$32=1") {
            self.needs_laser_mode = true;
        }
        if t.is_empty() {
            return Ok(());
        }
        if let Some(ch) = t
            .chars()
            .find(|c| !c.is_ascii() || matches!(c, '?' | '!' | '~'))
        {
            return Err(JobError::BadCharacter {
                line: source_line,
                ch,
                text: t,
            });
        }
        if t.len() > MAX_LINE_CHARS {
            return Err(JobError::LineTooLong {
                line: source_line,
                len: t.len(),
                text: t,
            });
        }
        let before = self.st.clone();
        if let Some(rest) = t.strip_prefix('$') {
            let kind = if rest.contains('=') && !rest.starts_with("J=") {
                LineKind::EepromWrite
            } else {
                LineKind::System
            };
            self.push(source_line, t, kind, before, LineMotion::default());
            return Ok(());
        }
        let ws = words(&t).map_err(|letter| JobError::BadNumber {
            line: source_line,
            letter,
            text: t.clone(),
        })?;
        let w = self.read_words(&ws).map_err(|()| JobError::ToolChange {
            line: source_line,
            text: t.clone(),
        })?;
        self.set_feed(&ws);
        if let Some(m) = w.motion {
            self.st.motion = m;
        }
        let motion = self.execute(&w);
        self.push(
            source_line,
            t,
            w.kind.unwrap_or(LineKind::Gcode),
            before,
            motion,
        );
        Ok(())
    }

    /// Reads the words of a line, applying modal words to the state. `Err` on a tool change
    /// (`M6`), which GRBL rejects.
    fn read_words(&mut self, ws: &[(char, f64)]) -> Result<LineWords, ()> {
        let mut w = LineWords::default();
        let st = &mut self.st;
        for &(l, v) in ws {
            match l {
                'G' => {
                    let g = (v * 10.0).round() as i64;
                    match g {
                        0 => w.motion = Some(MotionMode::Rapid),
                        10 => w.motion = Some(MotionMode::Linear),
                        20 => w.motion = Some(MotionMode::ArcCw),
                        30 => w.motion = Some(MotionMode::ArcCcw),
                        800 | 382..=385 => w.motion = Some(MotionMode::Cancel),
                        170 => st.plane = 17,
                        180 => st.plane = 18,
                        190 => st.plane = 19,
                        200 => st.units = Units::Inch,
                        210 => st.units = Units::Mm,
                        900 => st.incremental = false,
                        910 => st.incremental = true,
                        930 => st.inverse_time = true,
                        940 => st.inverse_time = false,
                        540..=590 if g % 10 == 0 => st.wcs = (g / 10) as u8,
                        40 | 100 | 280 | 281 | 300 | 301 | 530 | 920 | 921 | 922 | 923 => {
                            w.non_modal = Some(g)
                        }
                        _ => {}
                    }
                    if g == 281 || g == 301 {
                        w.kind = Some(LineKind::EepromWrite);
                    }
                }
                'M' => match v.round() as i64 {
                    3 => st.spindle = Spindle::Cw,
                    4 => st.spindle = Spindle::Ccw,
                    5 => st.spindle = Spindle::Off,
                    6 => return Err(()),
                    7 => st.mist = true,
                    8 => st.flood = true,
                    9 => {
                        st.mist = false;
                        st.flood = false;
                    }
                    _ => {}
                },
                'S' => st.speed = v,
                'X' => w.axis[0] = Some(v),
                'Y' => w.axis[1] = Some(v),
                'Z' => w.axis[2] = Some(v),
                'I' => w.ijk[0] = Some(v),
                'J' => w.ijk[1] = Some(v),
                'K' => w.ijk[2] = Some(v),
                'R' => w.r = Some(v),
                _ => {}
            }
        }
        // G10 L2 / L20 writes a coordinate system to EEPROM (whatever the word order).
        let g10 = ws
            .iter()
            .any(|w| w.0 == 'G' && (w.1 * 10.0).round() as i64 == 100);
        if g10 && ws.iter().any(|w| w.0 == 'L' && (w.1 == 2.0 || w.1 == 20.0)) {
            w.kind = Some(LineKind::EepromWrite);
        }
        Ok(w)
    }

    /// The F word, once the units of this line are known (GRBL converts F at parse time).
    fn set_feed(&mut self, ws: &[(char, f64)]) {
        if let Some(&(_, f)) = ws.iter().rev().find(|w| w.0 == 'F') {
            self.st.feed = if self.st.inverse_time {
                f
            } else {
                f * self.scale()
            };
        }
    }

    /// Millimetres per program unit.
    fn scale(&self) -> f64 {
        if self.st.units == Units::Inch {
            MM_PER_INCH
        } else {
            1.0
        }
    }

    /// Runs the line's non-modal command or motion on the program position.
    fn execute(&mut self, w: &LineWords) -> LineMotion {
        let scale = self.scale();
        let st = &mut self.st;
        match w.non_modal {
            Some(920) => {
                // G92: the current position takes the given values.
                self.uses_g92 = true;
                for a in 0..3 {
                    if let Some(v) = w.axis[a] {
                        let new = v * scale;
                        st.g92[a] += st.position[a] - new;
                        st.position[a] = new;
                    }
                }
                LineMotion::default()
            }
            Some(921) | Some(922) => {
                self.uses_g92 = true;
                for a in 0..3 {
                    st.position[a] += st.g92[a];
                    st.g92[a] = 0.0;
                }
                LineMotion::default()
            }
            // G4, G10, G28/G30 (to a stored position this model does not know), G28.1/G30.1:
            // no tracked motion.
            Some(40) | Some(100) | Some(280) | Some(281) | Some(300) | Some(301) | Some(923) => {
                LineMotion::default()
            }
            // G53 (machine coordinates; approximated as work coordinates) or a plain line.
            _ => self.motion(w),
        }
    }

    /// A motion line: the target, the path (arcs as GRBL's chords) and its length.
    fn motion(&mut self, w: &LineWords) -> LineMotion {
        let scale = self.scale();
        let st = &self.st;
        if !w.axis.iter().any(Option::is_some) || st.motion == MotionMode::Cancel {
            return LineMotion::default();
        }
        let start = st.position;
        let mut target = start;
        for a in 0..3 {
            if let Some(v) = w.axis[a] {
                target[a] = if st.incremental {
                    start[a] + v * scale
                } else {
                    v * scale
                };
            }
        }
        let mut m = LineMotion {
            moves: true,
            ..LineMotion::default()
        };
        match st.motion {
            MotionMode::ArcCw | MotionMode::ArcCcw => {
                let pts = arc_points(
                    st,
                    start,
                    target,
                    w.ijk.map(|o| o.map(|v| v * scale)),
                    w.r.map(|v| v * scale),
                    self.arc_tolerance,
                )
                .points;
                m.length = pts.windows(2).map(|p| dist(p[0], p[1])).sum();
                m.arc = pts.iter().map(|p| add(*p, st.g92)).collect();
            }
            _ => m.length = dist(start, target),
        }
        if (target[2] - start[2]).abs() > ZERO_LENGTH_MM {
            self.z_moves = true;
        }
        let g92 = self.st.g92;
        for p in m.arc.clone() {
            self.include(p);
        }
        self.include(add(start, g92));
        self.include(add(target, g92));
        self.max_z = self.max_z.max(start[2] + g92[2]).max(target[2] + g92[2]);
        self.st.position = target;
        m
    }

    /// Grows the job's extent to hold `p`.
    fn include(&mut self, p: [f64; 3]) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(p[a]);
            self.hi[a] = self.hi[a].max(p[a]);
        }
    }

    /// Records a line.
    fn push(
        &mut self,
        source_line: usize,
        text: String,
        kind: LineKind,
        before: ModalState,
        m: LineMotion,
    ) {
        let st = &self.st;
        let tool_on = m.moves
            && st.motion != MotionMode::Rapid
            && ((st.spindle != Spindle::Off && st.speed > 0.0)
                || (self.z_moves && st.position[2] + st.g92[2] < 0.0));
        self.lines.push(JobLine {
            source_line,
            text,
            kind,
            moves: m.moves,
            length: m.length,
            time: 0.0,
            tool_on,
            before,
            arc: m.arc,
        });
    }

    /// The job read from `text`, timed with `limits`.
    pub(super) fn finish(self, text: &str, limits: &MachineLimits) -> Result<Job, JobError> {
        let laser = self.needs_laser_mode;
        self.finish_lines(fnv1a64(text.as_bytes()), laser, limits)
            .ok_or(JobError::Empty)
    }

    /// The job of the lines read, identified by `hash`, timed with `limits`; `None` without
    /// a line.
    pub(super) fn finish_lines(
        self,
        hash: u64,
        needs_laser_mode: bool,
        limits: &MachineLimits,
    ) -> Option<Job> {
        if self.lines.is_empty() {
            return None;
        }
        let mut job = Job {
            total_length: self.lines.iter().map(|l| l.length).sum(),
            lines: self.lines,
            hash,
            total_time: 0.0,
            extent: self.lo[0].is_finite().then_some((self.lo, self.hi)),
            uses_g92: self.uses_g92,
            safe_z: self.z_moves.then_some(self.max_z),
            end_state: self.st,
            needs_laser_mode: needs_laser_mode || self.needs_laser_mode,
        };
        job.retime(limits);
        Some(job)
    }
}
