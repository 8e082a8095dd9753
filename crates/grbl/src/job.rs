//! A G-code job prepared for streaming: lines stripped the way GRBL's pre-parser strips them,
//! modal state tracked before every line (for resume), path length per line (for progress) and a
//! motion-time estimate from a GRBL-like look-ahead planner (for ETA).
//!
//! The interpreter is written here rather than taken from the `gcode` crate because streaming
//! needs exactly GRBL's view of a line (its stripping rules, the 79-character limit, its modal
//! groups and arc segmentation), not a general G-code AST.

use flatcut_motion::{Estimator, Feed, Limits, arc_chords};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use thiserror::Error;

/// GRBL's line buffer holds 80 bytes including the terminator (`grbl/protocol.h:31-32`).
pub const MAX_LINE_CHARS: usize = 79;
/// Millimetres per inch (G20).
const MM_PER_INCH: f64 = 25.4;
/// Below this length a motion is treated as zero-length (GRBL drops moves of zero steps; at the
/// default 250 steps/mm one step is 0.004 mm, so this is well under a step).
const ZERO_LENGTH_MM: f64 = 1e-9;

/// Errors found while preparing a job.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum JobError {
    /// A stripped line is longer than GRBL's 79-character line buffer (would get `error:11`).
    #[error(
        "line {line}: {len} significant characters after stripping, GRBL accepts at most 79: {text}"
    )]
    LineTooLong {
        /// 1-based line number in the file.
        line: usize,
        /// Stripped length.
        len: usize,
        /// Stripped text.
        text: String,
    },
    /// A tool change (`M6`), which GRBL rejects with `error:20`.
    #[error(
        "line {line}: tool change M6 is not supported by GRBL (error:20); split the job per tool: {text}"
    )]
    ToolChange {
        /// 1-based line number in the file.
        line: usize,
        /// Stripped text.
        text: String,
    },
    /// A word whose value does not parse as a number (would get `error:2`).
    #[error("line {line}: bad number for word '{letter}': {text}")]
    BadNumber {
        /// 1-based line number in the file.
        line: usize,
        /// The word letter.
        letter: char,
        /// Stripped text.
        text: String,
    },
    /// The file holds no line to send.
    #[error("the job has no G-code lines")]
    Empty,
}

/// Length units (G20/G21).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Units {
    /// G21.
    Mm,
    /// G20.
    Inch,
}

/// Motion mode (modal group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MotionMode {
    /// G0.
    Rapid,
    /// G1.
    Linear,
    /// G2.
    ArcCw,
    /// G3.
    ArcCcw,
    /// G80 (or a probe mode, which does not stay modal for our purpose).
    Cancel,
}

/// Spindle / laser / servo-pen state (M3/M4/M5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Spindle {
    /// M5.
    Off,
    /// M3.
    Cw,
    /// M4.
    Ccw,
}

/// The modal state of the G-code interpreter plus the program position, as it stands before a
/// line runs. Lengths are millimetres whatever the job's units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModalState {
    /// G20/G21.
    pub units: Units,
    /// G90 (false) / G91 (true).
    pub incremental: bool,
    /// Motion mode.
    pub motion: MotionMode,
    /// Plane: 17, 18 or 19.
    pub plane: u8,
    /// Work coordinate system 54..=59.
    pub wcs: u8,
    /// G93 inverse-time feed mode.
    pub inverse_time: bool,
    /// Feed rate, mm/min (0 = never set).
    pub feed: f64,
    /// Spindle state.
    pub spindle: Spindle,
    /// S value.
    pub speed: f64,
    /// M7 mist.
    pub mist: bool,
    /// M8 flood.
    pub flood: bool,
    /// Program position (work coordinates including any G92 shift), mm.
    pub position: [f64; 3],
    /// Active G92 offset, mm (position in the G92-free work frame = position + g92).
    pub g92: [f64; 3],
}

impl Default for ModalState {
    /// GRBL's power-up state: G0 G54 G17 G21 G90 G94 M5 M9 F0 S0, at the work origin.
    fn default() -> ModalState {
        ModalState {
            units: Units::Mm,
            incremental: false,
            motion: MotionMode::Rapid,
            plane: 17,
            wcs: 54,
            inverse_time: false,
            feed: 0.0,
            spindle: Spindle::Off,
            speed: 0.0,
            mist: false,
            flood: false,
            position: [0.0; 3],
            g92: [0.0; 3],
        }
    }
}

/// What kind of line this is, for the streamer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LineKind {
    /// G-code that GRBL buffers (character counting applies).
    Gcode,
    /// A `$` system command (send-response: many need IDLE and some write EEPROM).
    System,
    /// Writes EEPROM (`$x=`, `$N..=`, `G10 L2/L20`, `G28.1`, `G30.1`): send-response only, since
    /// the EEPROM write disables the RX interrupt (`interface.md:64-71`).
    EepromWrite,
}

/// One streamable line of a job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobLine {
    /// 1-based line number in the source file.
    pub source_line: usize,
    /// The text to send (stripped, upper-case, no terminator).
    pub text: String,
    /// How to send it.
    pub kind: LineKind,
    /// Motion word given on this line or in effect through modality when it has axis words.
    pub moves: bool,
    /// Path length of this line's motion, mm.
    pub length: f64,
    /// Estimated execution time, seconds (motion with acceleration, plus dwells).
    pub time: f64,
    /// Tool on (spindle/laser on, or pen below Z=0) during this line's motion.
    pub tool_on: bool,
    /// Modal state before the line.
    pub before: ModalState,
    /// For an arc: its chord points as GRBL splits it, start and end included (G92-free work
    /// coordinates, mm); empty for anything else.
    #[serde(default)]
    pub arc: Vec<[f64; 3]>,
}

/// What the sender needs to know of a controller's settings: the motion model's limits
/// (`$100-$102`, `$110-$112`, `$120-$122`, `$11`, `$12`) for the estimate, and `$32`, `$130-$132`,
/// `$22` for the checks before a job runs.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineLimits {
    /// Steps/mm, max rates, accelerations, junction deviation and arc tolerance.
    pub motion: Limits,
    /// Laser mode (`$32`): spindle changes do not stop the planner.
    pub laser_mode: bool,
    /// Max travel per axis, mm (`$130-$132`).
    pub max_travel: [f64; 3],
    /// Homing enabled (`$22`): machine coordinates are meaningful for an absolute envelope check.
    pub homing: bool,
}

impl MachineLimits {
    /// GRBL 1.1h defaults (`defaults.h`, DEFAULTS_GENERIC): [`Limits::GRBL_DEFAULT`], laser mode
    /// off, 200 mm travel, homing off.
    pub const DEFAULT: MachineLimits = MachineLimits {
        motion: Limits::GRBL_DEFAULT,
        laser_mode: false,
        max_travel: [200.0; 3],
        homing: false,
    };

    /// Limits from a `$$` dump; settings that are missing keep their default.
    pub fn from_settings(settings: &BTreeMap<u16, f64>) -> MachineLimits {
        let mut l = MachineLimits::DEFAULT;
        let get = |n: u16, d: f64| {
            settings
                .get(&n)
                .copied()
                .filter(|v| v.is_finite())
                .unwrap_or(d)
        };
        let m = &mut l.motion;
        for a in 0..3 {
            m.steps_per_mm[a] = get(100 + a as u16, m.steps_per_mm[a]);
            m.max_rate[a] = get(110 + a as u16, m.max_rate[a]);
            m.accel[a] = get(120 + a as u16, m.accel[a]);
            l.max_travel[a] = get(130 + a as u16, l.max_travel[a]);
        }
        m.junction_deviation = get(11, m.junction_deviation);
        m.arc_tolerance = get(12, m.arc_tolerance);
        l.laser_mode = get(32, 0.0) != 0.0;
        l.homing = get(22, 0.0) != 0.0;
        l
    }
}

impl Default for MachineLimits {
    fn default() -> MachineLimits {
        MachineLimits::DEFAULT
    }
}

/// A job ready to stream.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// Streamable lines (blank, comment-only and `%` lines are dropped).
    pub lines: Vec<JobLine>,
    /// FNV-1a 64-bit hash of the source text, identifying the job for resume.
    pub hash: u64,
    /// Total path length, mm.
    pub total_length: f64,
    /// Total estimated time, s.
    pub total_time: f64,
    /// Bounding box of all motion endpoints and arc samples (G92-free work coordinates), mm;
    /// `None` if the job never moves.
    pub extent: Option<([f64; 3], [f64; 3])>,
    /// Whether the job uses G92 offsets (resume then has to re-establish them).
    pub uses_g92: bool,
    /// Highest Z reached (the pen-up / safe height used by resume), mm; `None` if Z never moves.
    pub safe_z: Option<f64>,
    /// State after the last line.
    pub end_state: ModalState,
}

/// FNV-1a, 64 bit: a stable, dependency-free content hash (not cryptographic; it guards
/// against resuming the wrong file, not against an adversary).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

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
fn words(text: &str) -> Result<Vec<(char, f64)>, char> {
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

impl Job {
    /// Parses and prepares a job with the default machine limits (call [`Job::retime`] once the
    /// machine's `$$` is known).
    pub fn parse(text: &str) -> Result<Job, JobError> {
        Job::parse_with(text, &MachineLimits::DEFAULT)
    }

    /// Parses and prepares a job, estimating times with `limits`.
    pub fn parse_with(text: &str, limits: &MachineLimits) -> Result<Job, JobError> {
        let mut st = ModalState::default();
        let mut lines = Vec::new();
        let mut uses_g92 = false;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut z_moves = false;
        let mut max_z = f64::NEG_INFINITY;
        for (i, raw) in text.lines().enumerate() {
            let source_line = i + 1;
            let t = strip_line(raw);
            if t.is_empty() {
                continue;
            }
            if t.len() > MAX_LINE_CHARS {
                return Err(JobError::LineTooLong {
                    line: source_line,
                    len: t.len(),
                    text: t,
                });
            }
            let before = st.clone();
            if let Some(rest) = t.strip_prefix('$') {
                let kind = if rest.contains('=') && !rest.starts_with("J=") {
                    LineKind::EepromWrite
                } else {
                    LineKind::System
                };
                lines.push(JobLine {
                    source_line,
                    text: t,
                    kind,
                    moves: false,
                    length: 0.0,
                    time: 0.0,
                    tool_on: false,
                    before,
                    arc: Vec::new(),
                });
                continue;
            }
            let ws = words(&t).map_err(|letter| JobError::BadNumber {
                line: source_line,
                letter,
                text: t.clone(),
            })?;
            let mut kind = LineKind::Gcode;
            let mut axis: [Option<f64>; 3] = [None; 3];
            let mut ijk: [Option<f64>; 3] = [None; 3];
            let mut r_word = None;
            let mut motion_word = None;
            let mut non_modal = None::<f64>;
            for &(l, v) in &ws {
                match l {
                    'G' => {
                        let g = (v * 10.0).round() as i64;
                        match g {
                            0 => motion_word = Some(MotionMode::Rapid),
                            10 => motion_word = Some(MotionMode::Linear),
                            20 => motion_word = Some(MotionMode::ArcCw),
                            30 => motion_word = Some(MotionMode::ArcCcw),
                            800 => motion_word = Some(MotionMode::Cancel),
                            382..=385 => motion_word = Some(MotionMode::Cancel),
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
                                non_modal = Some(v)
                            }
                            _ => {}
                        }
                        if g == 281 || g == 301 {
                            kind = LineKind::EepromWrite;
                        }
                    }
                    'M' => match v.round() as i64 {
                        3 => st.spindle = Spindle::Cw,
                        4 => st.spindle = Spindle::Ccw,
                        5 => st.spindle = Spindle::Off,
                        6 => {
                            return Err(JobError::ToolChange {
                                line: source_line,
                                text: t,
                            });
                        }
                        7 => st.mist = true,
                        8 => st.flood = true,
                        9 => {
                            st.mist = false;
                            st.flood = false;
                        }
                        _ => {}
                    },
                    'F' => {}
                    'S' => st.speed = v,
                    'X' => axis[0] = Some(v),
                    'Y' => axis[1] = Some(v),
                    'Z' => axis[2] = Some(v),
                    'I' => ijk[0] = Some(v),
                    'J' => ijk[1] = Some(v),
                    'K' => ijk[2] = Some(v),
                    'R' => r_word = Some(v),
                    'L' if non_modal == Some(10.0) && (v == 2.0 || v == 20.0) => {
                        kind = LineKind::EepromWrite;
                    }
                    _ => {}
                }
            }
            // F after the units of this line are known (GRBL converts F at parse time).
            let scale = if st.units == Units::Inch {
                MM_PER_INCH
            } else {
                1.0
            };
            if let Some(&(_, f)) = ws.iter().rev().find(|w| w.0 == 'F') {
                st.feed = if st.inverse_time { f } else { f * scale };
            }
            if ws
                .iter()
                .any(|w| w.0 == 'G' && (w.1 * 10.0).round() as i64 == 100)
            {
                // G10 with L after it: also EEPROM.
                if ws.iter().any(|w| w.0 == 'L' && (w.1 == 2.0 || w.1 == 20.0)) {
                    kind = LineKind::EepromWrite;
                }
            }
            if let Some(m) = motion_word {
                st.motion = m;
            }
            let has_axis = axis.iter().any(Option::is_some);
            let mut length = 0.0;
            let mut arc = Vec::new();
            let mut moves = false;
            let start = st.position;
            let to_mm = |v: f64| v * scale;
            match non_modal.map(|v| (v * 10.0).round() as i64) {
                Some(920) => {
                    // G92: current position takes the given values.
                    uses_g92 = true;
                    for a in 0..3 {
                        if let Some(v) = axis[a] {
                            let new = to_mm(v);
                            st.g92[a] += st.position[a] - new;
                            st.position[a] = new;
                        }
                    }
                }
                Some(921) | Some(922) => {
                    uses_g92 = true;
                    for a in 0..3 {
                        st.position[a] += st.g92[a];
                        st.g92[a] = 0.0;
                    }
                }
                // G4, G10, G28/G30 (to a stored position this model does not know), G28.1/G30.1:
                // no tracked motion.
                Some(40) | Some(100) | Some(280) | Some(281) | Some(300) | Some(301)
                | Some(923) => {}
                // G53 (machine coordinates; approximated as work coordinates) or a plain line.
                _ => {
                    if has_axis && st.motion != MotionMode::Cancel {
                        moves = true;
                        let mut target = st.position;
                        for a in 0..3 {
                            if let Some(v) = axis[a] {
                                target[a] = if st.incremental {
                                    st.position[a] + to_mm(v)
                                } else {
                                    to_mm(v)
                                };
                            }
                        }
                        match st.motion {
                            MotionMode::ArcCw | MotionMode::ArcCcw => {
                                let pts = arc_points(
                                    &st,
                                    start,
                                    target,
                                    ijk.map(|o| o.map(to_mm)),
                                    r_word.map(to_mm),
                                    limits.motion.arc_tolerance,
                                );
                                for w in pts.windows(2) {
                                    length += dist(w[0], w[1]);
                                }
                                for p in &pts {
                                    include(&mut lo, &mut hi, add(*p, st.g92));
                                }
                                arc = pts.iter().map(|p| add(*p, st.g92)).collect();
                            }
                            _ => length = dist(start, target),
                        }
                        if (target[2] - start[2]).abs() > ZERO_LENGTH_MM {
                            z_moves = true;
                        }
                        st.position = target;
                    }
                }
            }
            if moves {
                include(&mut lo, &mut hi, add(start, st.g92));
                include(&mut lo, &mut hi, add(st.position, st.g92));
                max_z = max_z
                    .max(start[2] + st.g92[2])
                    .max(st.position[2] + st.g92[2]);
            }
            let tool_on = moves
                && st.motion != MotionMode::Rapid
                && ((st.spindle != Spindle::Off && st.speed > 0.0)
                    || (z_moves && st.position[2] + st.g92[2] < 0.0));
            lines.push(JobLine {
                source_line,
                text: t,
                kind,
                moves,
                length,
                time: 0.0,
                tool_on,
                before,
                arc,
            });
        }
        if lines.is_empty() {
            return Err(JobError::Empty);
        }
        let extent = lo[0].is_finite().then_some((lo, hi));
        let mut job = Job {
            total_length: lines.iter().map(|l| l.length).sum(),
            lines,
            hash: fnv1a64(text.as_bytes()),
            total_time: 0.0,
            extent,
            uses_g92,
            safe_z: z_moves.then_some(max_z),
            end_state: st,
        };
        job.retime(limits);
        Ok(job)
    }

    /// Number of streamable lines.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// True if there is no line (never for a parsed job).
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// Recomputes the per-line time estimate for the given machine limits: a look-ahead planner
    /// model like GRBL's (junction deviation, trapezoidal profiles, arcs split into chords by the
    /// arc tolerance, syncs on dwells/spindle changes/program pauses), plus `G4` dwell times.
    pub fn retime(&mut self, limits: &MachineLimits) {
        let mut est = Estimator::new(&limits.motion);
        for (i, line) in self.lines.iter().enumerate() {
            let before = &line.before;
            let after = self
                .lines
                .get(i + 1)
                .map(|l| &l.before)
                .unwrap_or(&self.end_state);
            let ws = words(&line.text).unwrap_or_default();
            let has_g = |n: i64| {
                ws.iter()
                    .any(|w| w.0 == 'G' && (w.1 * 10.0).round() as i64 == n)
            };
            let has_m = |n: i64| ws.iter().any(|w| w.0 == 'M' && w.1.round() as i64 == n);
            if line.kind != LineKind::Gcode || has_m(0) || has_m(1) || has_m(2) || has_m(30) {
                est.sync();
            }
            if has_g(40) {
                let p = ws.iter().find(|w| w.0 == 'P').map_or(0.0, |p| p.1.max(0.0));
                est.dwell(i, p);
            }
            let spindle_change = before.spindle != after.spindle
                || (before.speed != after.speed && !limits.laser_mode);
            if spindle_change && !limits.laser_mode {
                est.sync();
            }
            if !line.moves {
                continue;
            }
            let pts: Vec<[f64; 3]> = match after.motion {
                MotionMode::ArcCw | MotionMode::ArcCcw => {
                    let mut st = before.clone();
                    st.plane = after.plane;
                    st.motion = after.motion;
                    let scale = if after.units == Units::Inch {
                        MM_PER_INCH
                    } else {
                        1.0
                    };
                    let mut ijk = [None; 3];
                    let mut r = None;
                    for w in &ws {
                        match w.0 {
                            'I' => ijk[0] = Some(w.1 * scale),
                            'J' => ijk[1] = Some(w.1 * scale),
                            'K' => ijk[2] = Some(w.1 * scale),
                            'R' => r = Some(w.1 * scale),
                            _ => {}
                        }
                    }
                    arc_points(
                        &st,
                        before.position,
                        after.position,
                        ijk,
                        r,
                        limits.motion.arc_tolerance,
                    )
                }
                _ => vec![before.position, after.position],
            };
            let feed = if after.motion == MotionMode::Rapid {
                Feed::Rapid
            } else if after.inverse_time {
                Feed::InverseTime {
                    f: after.feed,
                    line_length: line.length,
                }
            } else {
                Feed::PerMinute(after.feed)
            };
            est.polyline(i, &pts, feed);
        }
        let times = est.per_tag(self.lines.len());
        for (l, t) in self.lines.iter_mut().zip(times) {
            l.time = t;
        }
        self.total_time = self.lines.iter().map(|l| l.time).sum();
    }

    /// Lines to send before resuming at line index `next` (0-based) so that the machine is in
    /// the modal state the job had there: tool off, pen/tool up to the job's safe Z, rapid to
    /// the position, back down, tool state, coolant, feed, feed mode, distance mode and units
    /// restored. The lines are stripped and at most 79 characters.
    pub fn resume_preamble(&self, next: usize) -> Vec<String> {
        let st = self.state_before(next);
        self.resume_preamble_from(next, add(st.position, st.g92), true)
    }

    /// The modal state before line `index` (the end state past the last line).
    pub fn state_before(&self, index: usize) -> &ModalState {
        match self.lines.get(index) {
            Some(l) => &l.before,
            None => &self.end_state,
        }
    }

    /// The work position (G92-free, mm) where line `index` ends.
    pub fn end_of(&self, index: usize) -> [f64; 3] {
        let st = self.state_before(index + 1);
        add(st.position, st.g92)
    }

    /// What the job moves, in order: `(text, start, end)` (G92-free work coordinates, mm) of
    /// every line whose motion has length. The reference that a machine's executed trace is
    /// checked against.
    pub fn motions(&self) -> Vec<(String, [f64; 3], [f64; 3])> {
        (0..self.len())
            .filter(|&i| self.lines[i].moves && self.lines[i].length > ZERO_LENGTH_MM)
            .map(|i| (self.lines[i].text.clone(), self.start_of(i), self.end_of(i)))
            .collect()
    }

    /// The work position (G92-free, mm) where line `index` starts.
    pub fn start_of(&self, index: usize) -> [f64; 3] {
        let st = self.state_before(index);
        add(st.position, st.g92)
    }

    /// [`Job::resume_preamble`] for a machine to be put at `at` (G92-free work coordinates, mm)
    /// rather than at the start of line `next`: the point where a stopped run left line `next`
    /// part-way, so that re-sending it (in G90) completes it without repeating the part done.
    /// With `travel` false the machine is known to stand at `at` already and the preamble only
    /// restores the modal state (no tool lift, no travel).
    pub fn resume_preamble_from(&self, next: usize, at: [f64; 3], travel: bool) -> Vec<String> {
        let st = self.state_before(next);
        let f = |v: f64| fmt_num(v);
        let mut out = vec![
            "G21G90G94".to_string(),
            format!("G{}G{}", st.plane, st.wcs),
            "M5M9".to_string(),
        ];
        if self.uses_g92 {
            out.push("G92.1".into());
        }
        // Absolute target in the G92-free frame.
        let p = at;
        if travel {
            if let Some(z) = self.safe_z {
                out.push(format!("G0Z{}", f(z)));
            }
            out.push(format!("G0X{}Y{}", f(p[0]), f(p[1])));
        }
        match st.spindle {
            Spindle::Off => out.push(format!("S{}", f(st.speed))),
            Spindle::Cw => out.push(format!("M3S{}", f(st.speed))),
            Spindle::Ccw => out.push(format!("M4S{}", f(st.speed))),
        }
        if st.mist {
            out.push("M7".into());
        }
        if st.flood {
            out.push("M8".into());
        }
        if self.safe_z.is_some() && travel {
            if st.feed > 0.0 && !st.inverse_time {
                out.push(format!("G1Z{}F{}", f(p[2]), f(st.feed)));
            } else {
                out.push(format!("G0Z{}", f(p[2])));
            }
        }
        if self.uses_g92 {
            // The offset that makes `at` read as the job's own coordinates there.
            out.push(format!(
                "G92X{}Y{}Z{}",
                f(p[0] - st.g92[0]),
                f(p[1] - st.g92[1]),
                f(p[2] - st.g92[2])
            ));
        }
        if st.feed > 0.0 && !st.inverse_time {
            out.push(format!("F{}", f(st.feed)));
        }
        let mut modes = String::new();
        if st.inverse_time {
            modes.push_str("G93");
        }
        if st.incremental {
            modes.push_str("G91");
        }
        if st.units == Units::Inch {
            modes.push_str("G20");
        }
        match st.motion {
            MotionMode::Rapid => modes.push_str("G0"),
            MotionMode::Linear => modes.push_str("G1"),
            // G2/G3 without axis words is an error; the first resumed line gets the word instead
            // (see `resume_line`).
            MotionMode::ArcCw | MotionMode::ArcCcw => {}
            MotionMode::Cancel => modes.push_str("G80"),
        }
        if !modes.is_empty() {
            out.push(modes);
        }
        out
    }

    /// The text to send for line `index` when it is the first line after a resume preamble: an
    /// arc line that relies on a modal G2/G3 gets its motion word back.
    pub fn resume_line(&self, index: usize) -> String {
        let l = &self.lines[index];
        let has_motion = words(&l.text)
            .map(|ws| {
                ws.iter().any(|w| {
                    w.0 == 'G' && matches!((w.1 * 10.0).round() as i64, 0 | 10 | 20 | 30 | 800)
                })
            })
            .unwrap_or(true);
        let prefix = match l.before.motion {
            MotionMode::ArcCw if !has_motion => "G2",
            MotionMode::ArcCcw if !has_motion => "G3",
            _ => "",
        };
        let s = format!("{prefix}{}", l.text);
        if s.len() <= MAX_LINE_CHARS {
            s
        } else {
            l.text.clone()
        }
    }
}

/// Formats a number for G-code: up to 4 decimals, no trailing zeros, no `-0`.
pub fn fmt_num(v: f64) -> String {
    let mut s = format!("{v:.4}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" { "0".into() } else { s }
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
}

fn include(lo: &mut [f64; 3], hi: &mut [f64; 3], p: [f64; 3]) {
    for a in 0..3 {
        lo[a] = lo[a].min(p[a]);
        hi[a] = hi[a].max(p[a]);
    }
}

/// Points along an arc (endpoints included), split into chords the way GRBL's `mc_arc` does
/// (segments = angle·r / sqrt(tol·(2r − tol))). Falls back to the straight chord for an invalid
/// arc (GRBL would reject it with error:33/34; check mode reports that).
fn arc_points(
    st: &ModalState,
    start: [f64; 3],
    target: [f64; 3],
    ijk: [Option<f64>; 3],
    r_word: Option<f64>,
    tol: f64,
) -> Vec<[f64; 3]> {
    let (a0, a1, lin) = match st.plane {
        18 => (2, 0, 1),
        19 => (1, 2, 0),
        _ => (0, 1, 2),
    };
    let cw = st.motion == MotionMode::ArcCw;
    let (sx, sy) = (start[a0], start[a1]);
    let (tx, ty) = (target[a0], target[a1]);
    let (cx, cy) = if let Some(r) = r_word {
        // GRBL gcode.c: centre from radius; negative R = the long way round.
        let (x, y) = (tx - sx, ty - sy);
        let d2 = x * x + y * y;
        let h2 = 4.0 * r * r - d2;
        if d2 <= 0.0 || h2 < 0.0 {
            return vec![start, target];
        }
        let mut h = -h2.sqrt() / d2.sqrt();
        if !cw {
            h = -h;
        }
        if r < 0.0 {
            h = -h;
        }
        (sx + 0.5 * (x - y * h), sy + 0.5 * (y + x * h))
    } else {
        (sx + ijk[a0].unwrap_or(0.0), sy + ijk[a1].unwrap_or(0.0))
    };
    arc_chords(start, target, [cx, cy], (a0, a1, lin), cw, tol)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use flatcut_motion::trapezoid_time;

    #[test]
    fn stripping_follows_grbl_preparser() {
        assert_eq!(strip_line("g1 x10 (move) y2.5 ; tail"), "G1X10Y2.5");
        assert_eq!(strip_line("%"), "");
        assert_eq!(strip_line("/G1 X1\t\r"), "G1X1");
        assert_eq!(strip_line("(only a comment)"), "");
    }

    #[test]
    fn rejects_what_grbl_would_reject() {
        let long = format!("G1X{}", "1".repeat(80));
        assert!(matches!(
            Job::parse(&long),
            Err(JobError::LineTooLong { line: 1, .. })
        ));
        let ok79 = format!("G1X{}", "1".repeat(76));
        assert_eq!(ok79.len(), 79);
        assert!(Job::parse(&format!("G21\n{ok79}")).is_ok());
        assert!(matches!(
            Job::parse("G0X1\nT1 M6\n"),
            Err(JobError::ToolChange { line: 2, .. })
        ));
        assert!(matches!(
            Job::parse("G1 X1..2"),
            Err(JobError::BadNumber { letter: 'X', .. })
        ));
        assert!(matches!(Job::parse("%\n(nothing)\n"), Err(JobError::Empty)));
    }

    #[test]
    fn modal_state_units_distance_and_feed() {
        let job =
            Job::parse("G20 G91\nG1 X1 F10\nX1 Y1\nG21 G90 M3 S500\nG0 Z5\n$32=1\nG10 L20 P1 X0\n")
                .unwrap();
        let l = &job.lines;
        assert_eq!(l[2].before.units, Units::Inch);
        assert!(l[2].before.incremental);
        assert_relative_eq!(l[2].before.feed, 254.0);
        assert_relative_eq!(l[2].before.position[0], 25.4);
        assert_relative_eq!(l[3].before.position[0], 50.8);
        assert_relative_eq!(l[3].before.position[1], 25.4);
        assert_relative_eq!(l[1].length, 25.4);
        assert_relative_eq!(l[2].length, 25.4 * 2f64.sqrt(), epsilon = 1e-12);
        assert_eq!(l[4].before.spindle, Spindle::Cw);
        assert_eq!(l[5].kind, LineKind::EepromWrite);
        assert_eq!(l[6].kind, LineKind::EepromWrite);
        assert_eq!(job.safe_z, Some(5.0));
        assert!(!l[1].tool_on && !l[4].tool_on);
    }

    #[test]
    fn arc_length_and_extent() {
        // Quarter circle of radius 10 about the origin, CCW from (10,0) to (0,10).
        let job = Job::parse("G0X10Y0\nG3X0Y10I-10J0F600\n").unwrap();
        let exact = std::f64::consts::FRAC_PI_2 * 10.0;
        // Chords of sagitta <= 0.002 mm shorten the length by a relative ~ tol/(3r)·... < 1e-4.
        assert!(
            (job.lines[1].length - exact).abs() < 1e-3,
            "{}",
            job.lines[1].length
        );
        let (lo, hi) = job.extent.unwrap();
        assert_relative_eq!(lo[0], 0.0, epsilon = 1e-9);
        assert!(hi[0] >= 10.0 - 1e-9 && hi[1] >= 10.0 - 1e-9);
        // R form: same arc.
        let r = Job::parse("G0X10Y0\nG3X0Y10R10F600\n").unwrap();
        assert_relative_eq!(r.lines[1].length, job.lines[1].length, epsilon = 1e-9);
        // Full circle when start == end.
        let full = Job::parse("G0X10Y0\nG2X10Y0I-10J0F600\n").unwrap();
        assert!((full.lines[1].length - 20.0 * std::f64::consts::PI).abs() < 4e-3);
    }

    #[test]
    fn trapezoid_times_match_kinematics() {
        // 100 mm at 10 mm/s with 10 mm/s²: 1 s up (5 mm), 9 s cruise, 1 s down = 11 s.
        assert_relative_eq!(
            trapezoid_time(100.0, 0.0, 0.0, 10.0, 10.0),
            11.0,
            epsilon = 1e-12
        );
        // 4 mm never reaches 10 mm/s: triangle to sqrt(40) and back = 2·sqrt(40)/10.
        assert_relative_eq!(
            trapezoid_time(4.0, 0.0, 0.0, 10.0, 10.0),
            2.0 * 40f64.sqrt() / 10.0,
            epsilon = 1e-12
        );
        // Feeds are capped by $110-$112; lift the cap so F600 (10 mm/s) is what runs.
        let fast = MachineLimits {
            motion: Limits {
                max_rate: [6000.0; 3],
                ..Limits::GRBL_DEFAULT
            },
            ..MachineLimits::DEFAULT
        };
        let parse = |t: &str| Job::parse_with(t, &fast).unwrap();
        // With the default 500 mm/min cap the same move runs at 8.33 mm/s.
        assert_relative_eq!(
            Job::parse("G1X100F600").unwrap().total_time,
            trapezoid_time(100.0, 0.0, 0.0, 500.0 / 60.0, 10.0),
            epsilon = 1e-9
        );
        let one = parse("G1X100F600\n");
        assert_relative_eq!(one.total_time, 11.0, epsilon = 1e-9);
        // Collinear split: no stop at the junction.
        let two = parse("G1X50F600\nG1X100\n");
        assert_relative_eq!(two.total_time, 11.0, epsilon = 1e-9);
        // A reversal forces a full stop: two independent 50 mm moves.
        let rev = parse("G1X50F600\nG1X0\n");
        assert_relative_eq!(
            rev.total_time,
            2.0 * trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0),
            epsilon = 1e-9
        );
        // A dwell adds its seconds and a spindle change syncs the planner (laser mode off).
        let dw = parse("G1X50F600\nG4P1.5\nG1X100\n");
        assert_relative_eq!(
            dw.total_time,
            1.5 + 2.0 * trapezoid_time(50.0, 0.0, 0.0, 10.0, 10.0),
            epsilon = 1e-9
        );
        // A 90° corner: junction speed from the junction-deviation rule, with the acceleration
        // along the junction vector (-1, 1)/√2, which the 10 mm/s² axis limits allow at 10·√2
        // (`plan_buffer_line`: limit_value_by_axis_maximum on junction_unit_vec).
        let corner = parse("G1X50F600\nG1Y50\n");
        let sin_half = (0.5f64).sqrt();
        let ja = 10.0 * 2.0f64.sqrt();
        let vj = (ja * 0.01 * sin_half / (1.0 - sin_half)).sqrt();
        let expect = 2.0 * trapezoid_time(50.0, 0.0, vj, 10.0, 10.0);
        assert_relative_eq!(corner.total_time, expect, epsilon = 1e-9);
        // Rapids run at $110 (500 mm/min default): 60 mm → 7.2 s cruise plus ramps.
        let g0 = Job::parse("G0X60\n").unwrap();
        assert_relative_eq!(
            g0.total_time,
            trapezoid_time(60.0, 0.0, 0.0, 500.0 / 60.0, 10.0),
            epsilon = 1e-9
        );
    }

    /// Absolute end points of every moving line from index `from` on.
    fn endpoints(job: &Job, from_text: usize) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        for (k, l) in job.lines.iter().enumerate().skip(from_text) {
            if l.moves {
                let after = job
                    .lines
                    .get(k + 1)
                    .map(|n| &n.before)
                    .unwrap_or(&job.end_state);
                let p = add(after.position, after.g92);
                out.push(p.map(|v| (v * 1e6).round() / 1e6));
            }
        }
        out
    }

    #[test]
    fn resume_preamble_restores_state_at_every_line() {
        let src = "G21 G90\nG0 Z5\nG0 X10 Y10\nM3 S800\nG1 Z-1 F300\nG91\nG1 X5 F1200\nY5\nG90 G20\nG1 X1 Y1\nG2 X1.5 Y1.5 I0.25 J0.25\nX1 Y1 I-0.25 J-0.25\nG92 X0 Y0\nG1 X0.5\nG90 G21 M5\nG0 Z5\nG0 X0 Y0\n";
        let job = Job::parse(src).unwrap();
        for k in 1..job.len() {
            let pre = job.resume_preamble(k);
            assert!(
                pre.iter()
                    .all(|l| l.len() <= MAX_LINE_CHARS && strip_line(l) == *l)
            );
            let mut text = pre.join("\n");
            text.push('\n');
            text.push_str(&job.resume_line(k));
            text.push('\n');
            for l in &job.lines[k + 1..] {
                text.push_str(&l.text);
                text.push('\n');
            }
            let resumed = Job::parse(&text).unwrap();
            let skip = pre.len();
            let st_orig = &job.lines[k].before;
            let st_new = &resumed.lines[skip].before;
            assert_eq!(st_new.units, st_orig.units, "resume at {k}");
            assert_eq!(st_new.incremental, st_orig.incremental, "resume at {k}");
            assert_eq!(st_new.spindle, st_orig.spindle, "resume at {k}");
            assert_relative_eq!(st_new.feed, st_orig.feed, epsilon = 1e-9);
            assert_relative_eq!(st_new.speed, st_orig.speed, epsilon = 1e-9);
            assert_eq!(
                endpoints(&resumed, skip),
                endpoints(&job, k),
                "resume at {k}"
            );
        }
    }

    #[test]
    fn machine_limits_from_settings() {
        let mut s = BTreeMap::new();
        s.insert(110, 3000.0);
        s.insert(121, 50.0);
        s.insert(132, 30.0);
        s.insert(32, 1.0);
        let l = MachineLimits::from_settings(&s);
        assert_eq!(l.motion.max_rate, [3000.0, 500.0, 500.0]);
        assert_eq!(l.motion.accel, [10.0, 50.0, 10.0]);
        assert_eq!(l.max_travel, [200.0, 200.0, 30.0]);
        assert!(l.laser_mode && !l.homing);
        let mut job = Job::parse("G0X60\n").unwrap();
        job.retime(&l);
        assert_relative_eq!(
            job.total_time,
            trapezoid_time(60.0, 0.0, 0.0, 50.0, 10.0),
            epsilon = 1e-9
        );
    }

    #[test]
    fn hash_identifies_content() {
        assert_eq!(fnv1a64(b""), 0xcbf29ce484222325);
        assert_eq!(fnv1a64(b"a"), 0xaf63dc4c8601ec8c);
        assert_ne!(
            Job::parse("G0X1").unwrap().hash,
            Job::parse("G0X2").unwrap().hash
        );
        assert_eq!(fmt_num(-0.00001), "0");
        assert_eq!(fmt_num(12.5), "12.5");
        assert_eq!(fmt_num(3.0), "3");
    }
}
