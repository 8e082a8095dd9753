//! The g-code parser of GRBL 1.1h (`gcode.c`): word import, modal groups, the error checks in GRBL's order,
//! and the execution plan of a valid block as a list of [`Action`]s for the protocol loop.
//!
//! Written here rather than taken from a g-code crate because the point of the simulator is to reproduce GRBL's
//! exact acceptance rules and error numbers (e.g. `G2` with an R that is too small → `error:34`), which general
//! parsers do not model.

use crate::settings::{N_AXIS, Settings};
use crate::status::Status;

/// Millimetres per inch (`MM_PER_INCH`).
pub const MM_PER_INCH: f64 = 25.4;
/// `MAX_LINE_NUMBER` of GRBL.
const MAX_LINE_NUMBER: f64 = 10_000_000.0;
/// `MAX_TOOL_NUMBER` of GRBL.
const MAX_TOOL_NUMBER: f64 = 255.0;
/// Arc end-point radius mismatch accepted without check, mm (`gcode.c`: 0.005 mm).
const ARC_RADIUS_SLACK_MM: f64 = 0.005;
/// Arc end-point radius mismatch always rejected, mm (`gcode.c`: 0.5 mm).
const ARC_RADIUS_MAX_ERROR_MM: f64 = 0.5;
/// Relative arc radius mismatch rejected above the slack (`gcode.c`: 0.1 % of the radius).
const ARC_RADIUS_REL_ERROR: f64 = 0.001;
/// `ARC_ANGULAR_TRAVEL_EPSILON` of `motion_control.c`: a full circle when start and end coincide.
const ARC_ANGULAR_TRAVEL_EPSILON: f64 = 5e-7;

/// Modal motion mode (group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// G0 rapid.
    Seek,
    /// G1 linear feed.
    Linear,
    /// G2 clockwise arc.
    Cw,
    /// G3 counter-clockwise arc.
    Ccw,
    /// G38.2/3/4/5 probing (the digit after the point).
    Probe(u8),
    /// G80 motion cancel.
    None,
}

impl Motion {
    /// Name used in the trace and in `$G`.
    pub fn name(self) -> String {
        match self {
            Motion::Seek => "G0".into(),
            Motion::Linear => "G1".into(),
            Motion::Cw => "G2".into(),
            Motion::Ccw => "G3".into(),
            Motion::Probe(k) => format!("G38.{k}"),
            Motion::None => "G80".into(),
        }
    }
}

/// Spindle direction (group M7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spindle {
    /// M5.
    Off,
    /// M3.
    Cw,
    /// M4.
    Ccw,
}

/// Program flow (group M4) as `$G` shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Running.
    Running,
    /// M0.
    Paused,
    /// M2.
    End,
    /// M30.
    EndRewind,
}

/// The parser state `gc_state` of GRBL.
#[derive(Debug, Clone, PartialEq)]
pub struct GcState {
    /// Motion mode.
    pub motion: Motion,
    /// G93 inverse time.
    pub inverse_time: bool,
    /// G20.
    pub inches: bool,
    /// G91.
    pub incremental: bool,
    /// 0 = G17, 1 = G18, 2 = G19.
    pub plane: u8,
    /// 0..=5 for G54..G59.
    pub coord_select: usize,
    /// M0/M2/M30.
    pub flow: Flow,
    /// M3/M4/M5.
    pub spindle: Spindle,
    /// M8.
    pub flood: bool,
    /// M7.
    pub mist: bool,
    /// T.
    pub tool: u8,
    /// F, mm/min (G94) or 1/min (G93).
    pub feed: f64,
    /// S.
    pub spindle_speed: f64,
    /// Parser position, machine mm.
    pub position: [f64; N_AXIS],
    /// Active work offset (G54..G59 data), mm.
    pub coord_system: [f64; N_AXIS],
    /// G92 offset, mm.
    pub coord_offset: [f64; N_AXIS],
    /// G43.1 offset, mm.
    pub tool_length_offset: f64,
}

impl GcState {
    /// `gc_init`: power-up / reset modes at the given machine position.
    pub fn new(position: [f64; N_AXIS], coord_system: [f64; N_AXIS]) -> Self {
        GcState {
            motion: Motion::Seek,
            inverse_time: false,
            inches: false,
            incremental: false,
            plane: 0,
            coord_select: 0,
            flow: Flow::Running,
            spindle: Spindle::Off,
            flood: false,
            mist: false,
            tool: 0,
            feed: 0.0,
            spindle_speed: 0.0,
            position,
            coord_system,
            coord_offset: [0.0; N_AXIS],
            tool_length_offset: 0.0,
        }
    }

    /// Work coordinate offset (what `WCO:` reports).
    pub fn wco(&self) -> [f64; N_AXIS] {
        let mut w = [0.0; N_AXIS];
        for i in 0..N_AXIS {
            w[i] = self.coord_system[i] + self.coord_offset[i];
        }
        w[2] += self.tool_length_offset;
        w
    }

    /// The `$G` report line; the feed is shown in inches only when `$13=1` (`report_inches`), as GRBL does.
    pub fn report(&self, report_inches: bool) -> String {
        let mut s = String::from("[GC:");
        s.push_str(&self.motion.name());
        s.push_str(&format!(" G{}", 54 + self.coord_select));
        s.push_str(&format!(" G{}", 17 + self.plane));
        s.push_str(if self.inches { " G20" } else { " G21" });
        s.push_str(if self.incremental { " G91" } else { " G90" });
        s.push_str(if self.inverse_time { " G93" } else { " G94" });
        match self.flow {
            Flow::Running => {}
            Flow::Paused => s.push_str(" M0"),
            Flow::End => s.push_str(" M2"),
            Flow::EndRewind => s.push_str(" M30"),
        }
        s.push_str(match self.spindle {
            Spindle::Off => " M5",
            Spindle::Cw => " M3",
            Spindle::Ccw => " M4",
        });
        if !self.flood && !self.mist {
            s.push_str(" M9");
        } else {
            if self.mist {
                s.push_str(" M7");
            }
            if self.flood {
                s.push_str(" M8");
            }
        }
        s.push_str(&format!(" T{}", self.tool));
        let (f, decimals) = if report_inches {
            (self.feed / MM_PER_INCH, 1)
        } else {
            (self.feed, 0)
        };
        s.push_str(&format!(" F{}", crate::settings::fmt_float(f, decimals)));
        s.push_str(&format!(
            " S{}]",
            crate::settings::fmt_float(self.spindle_speed, 0)
        ));
        s
    }
}

/// EEPROM-kept parameters: work offsets G54..G59, G28/G30 positions, startup lines.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Persist {
    /// G54..G59 offsets, mm.
    pub coord: [[f64; N_AXIS]; 6],
    /// G28 position, machine mm.
    pub g28: [f64; N_AXIS],
    /// G30 position, machine mm.
    pub g30: [f64; N_AXIS],
    /// `$N0`, `$N1`.
    pub startup: [String; 2],
}

/// One straight planner move, machine mm.
#[derive(Debug, Clone, PartialEq)]
pub struct LineMove {
    /// Target, machine mm.
    pub target: [f64; N_AXIS],
    /// Rapid (G0, G28/G30 legs) at the axis max rates.
    pub rapid: bool,
    /// Feed in mm/min (for inverse time already converted per move: see `inverse_time`).
    pub feed: f64,
    /// F is inverse time (1/min for this move).
    pub inverse_time: bool,
    /// A jog move (not affected by feed override, no soft-limit alarm).
    pub jog: bool,
}

/// A traced motion: one g-code motion command (an arc is one, although it runs as many chords).
#[derive(Debug, Clone, PartialEq)]
pub struct MotionCmd {
    /// `G0`, `G1`, `G2`, `G3`, `G28`, `G30`, `G38.2`, `JOG`.
    pub name: String,
    /// The planner moves that realise it.
    pub moves: Vec<LineMove>,
    /// Arc centre, machine mm.
    pub arc_center: Option<[f64; N_AXIS]>,
    /// Programmed feed, mm/min (0 for rapids).
    pub feed: f64,
    /// Laser should be off for this motion (laser mode and not G1/G2/G3).
    pub laser_off: bool,
}

/// What the protocol loop must do, in order, to carry out a parsed block.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Wait until the planner is empty and motion stopped (`protocol_buffer_synchronize`).
    Sync,
    /// Queue a motion (waits for planner room for each move).
    Motion(MotionCmd),
    /// Dwell, seconds (after a Sync).
    Dwell(f64),
    /// Set the spindle output.
    Spindle(Spindle, f64),
    /// Set the coolant outputs (flood, mist).
    Coolant(bool, bool),
    /// M0: feed hold until cycle start.
    Pause,
    /// Print `[MSG:…]`.
    Message(&'static str),
    /// Flag a work-offset change (forces `WCO:` in the next report).
    WcoChanged,
    /// End of a probing move: (kind digit).
    ProbeEnd(u8),
    /// Wait for cycle start (`~`) after an M0 pause.
    WaitResume,
    /// End of the homing cycle: back to IDLE.
    HomingDone,
    /// An EEPROM write of this many changed bytes (the RX interrupt is off meanwhile).
    EepromWrite(u32),
    /// M2/M30 put the overrides back to 100 % (`RESTORE_OVERRIDES_AFTER_PROGRAM_END`, on in `config.h`).
    RestoreOverrides,
}

/// Bytes GRBL writes for one coordinate record: three floats and a checksum.
pub const COORD_RECORD_BYTES: u32 = 4 * N_AXIS as u32 + 1;

const G_NONMODAL: u32 = 1 << 0;
const G_MOTION: u32 = 1 << 1;
const G_PLANE: u32 = 1 << 2;
const G_DISTANCE: u32 = 1 << 3;
const G_ARC_DISTANCE: u32 = 1 << 4;
const G_FEED_MODE: u32 = 1 << 5;
const G_UNITS: u32 = 1 << 6;
const G_CUTTER: u32 = 1 << 7;
const G_TLO: u32 = 1 << 8;
const G_COORD: u32 = 1 << 9;
const G_CONTROL: u32 = 1 << 10;
const M_STOP: u32 = 1 << 11;
const M_SPINDLE: u32 = 1 << 12;
const M_COOLANT: u32 = 1 << 13;

const W_F: u16 = 1 << 0;
const W_I: u16 = 1 << 1;
const W_J: u16 = 1 << 2;
const W_K: u16 = 1 << 3;
const W_L: u16 = 1 << 4;
const W_N: u16 = 1 << 5;
const W_P: u16 = 1 << 6;
const W_R: u16 = 1 << 7;
const W_S: u16 = 1 << 8;
const W_T: u16 = 1 << 9;
const W_X: u16 = 1 << 10;
const W_Y: u16 = 1 << 11;
const W_Z: u16 = 1 << 12;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NonModal {
    None,
    Dwell,
    SetCoordData,
    GoHome0,
    SetHome0,
    GoHome1,
    SetHome1,
    AbsoluteOverride,
    SetCoordOffset,
    ResetCoordOffset,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AxisCommand {
    None,
    NonModal,
    MotionMode,
    ToolLengthOffset,
}

/// Reads a number as GRBL's `read_float` does: optional sign, digits with at most one point, at least one digit.
pub fn read_float(line: &[u8], pos: &mut usize) -> Option<f64> {
    let start = *pos;
    let mut p = *pos;
    if p < line.len() && (line[p] == b'-' || line[p] == b'+') {
        p += 1;
    }
    let mut digits = 0;
    let mut point = false;
    while p < line.len() {
        let c = line[p];
        if c.is_ascii_digit() {
            digits += 1;
        } else if c == b'.' && !point {
            point = true;
        } else {
            break;
        }
        p += 1;
    }
    if digits == 0 {
        return None;
    }
    let text = std::str::from_utf8(&line[start..p]).ok()?;
    let v: f64 = text.parse().ok()?;
    *pos = p;
    Some(v)
}

/// Plane axes (axis_0, axis_1, linear) for G17/G18/G19.
fn plane_axes(plane: u8) -> (usize, usize, usize) {
    match plane {
        1 => (2, 0, 1),
        2 => (1, 2, 0),
        _ => (0, 1, 2),
    }
}

/// Everything the parser needs besides the line.
pub struct Context<'a> {
    /// Parser state, updated only when the block is valid.
    pub gc: &'a mut GcState,
    /// Settings.
    pub settings: &'a Settings,
    /// EEPROM data (G10, G28.1 …).
    pub persist: &'a mut Persist,
    /// Machine position (for G28.1/G30.1), mm.
    pub machine_position: [f64; N_AXIS],
    /// `$C` check mode: program end leaves the coordinate system data and outputs alone.
    pub check_mode: bool,
}

/// Parses and plans one pre-processed line (upper-case, no spaces/comments). `jog` is true for `$J=` lines
/// (the line passed is the part after `$J=`).
pub fn execute(line: &[u8], jog: bool, ctx: &mut Context<'_>) -> Result<Vec<Action>, Status> {
    let st = &*ctx.gc;
    let mut motion = if jog { Motion::Linear } else { st.motion };
    let mut inverse_time = if jog { false } else { st.inverse_time };
    let mut inches = st.inches;
    let mut incremental = st.incremental;
    let mut plane = st.plane;
    let mut coord_select = st.coord_select;
    let mut flow = Flow::Running;
    let mut spindle = st.spindle;
    let mut flood = st.flood;
    let mut mist = st.mist;
    let mut tlo_mode: Option<bool> = None; // Some(true) = G43.1, Some(false) = G49
    let mut non_modal = NonModal::None;
    let mut axis_command = AxisCommand::None;
    let mut command_words = 0u32;
    let mut value_words = 0u16;
    let mut axis_words = 0u8;
    let mut ijk_words = 0u8;
    let mut xyz = [0.0f64; N_AXIS];
    let mut ijk = [0.0f64; N_AXIS];
    let (mut f, mut l, mut n, mut p, mut r, mut s, mut t) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);

    // STEP 2: import words.
    let mut pos = 0;
    while pos < line.len() {
        let letter = line[pos];
        if !letter.is_ascii_uppercase() {
            return Err(Status::ExpectedCommandLetter);
        }
        pos += 1;
        let value = read_float(line, &mut pos).ok_or(Status::BadNumberFormat)?;
        let int_value = value.trunc() as i64;
        let mut mantissa = ((value - int_value as f64) * 100.0).round() as i64;
        match letter {
            b'G' => {
                let group;
                match int_value {
                    10 | 28 | 30 | 92 | 4 | 53 => {
                        if matches!(int_value, 10 | 28 | 30 | 92) && mantissa == 0 {
                            if axis_command != AxisCommand::None {
                                return Err(Status::AxisCommandConflict);
                            }
                            axis_command = AxisCommand::NonModal;
                        }
                        group = G_NONMODAL;
                        non_modal = match (int_value, mantissa) {
                            (4, _) => NonModal::Dwell,
                            (10, _) => NonModal::SetCoordData,
                            (53, _) => NonModal::AbsoluteOverride,
                            (28, 0) => NonModal::GoHome0,
                            (28, 10) => NonModal::SetHome0,
                            (30, 0) => NonModal::GoHome1,
                            (30, 10) => NonModal::SetHome1,
                            (92, 0) => NonModal::SetCoordOffset,
                            (92, 10) => NonModal::ResetCoordOffset,
                            _ => return Err(Status::UnsupportedCommand),
                        };
                        if matches!(int_value, 28 | 30 | 92) {
                            mantissa = 0;
                        }
                    }
                    0..=3 | 38 | 80 => {
                        if int_value != 80 {
                            if axis_command != AxisCommand::None {
                                return Err(Status::AxisCommandConflict);
                            }
                            axis_command = AxisCommand::MotionMode;
                        }
                        group = G_MOTION;
                        motion = match int_value {
                            0 => Motion::Seek,
                            1 => Motion::Linear,
                            2 => Motion::Cw,
                            3 => Motion::Ccw,
                            80 => Motion::None,
                            _ => {
                                if !matches!(mantissa, 20 | 30 | 40 | 50) {
                                    return Err(Status::UnsupportedCommand);
                                }
                                let k = (mantissa / 10) as u8;
                                mantissa = 0;
                                Motion::Probe(k)
                            }
                        };
                    }
                    17..=19 => {
                        group = G_PLANE;
                        plane = (int_value - 17) as u8;
                    }
                    90 | 91 => {
                        if mantissa == 0 {
                            group = G_DISTANCE;
                            incremental = int_value == 91;
                        } else {
                            group = G_ARC_DISTANCE;
                            if mantissa != 10 || int_value == 90 {
                                return Err(Status::UnsupportedCommand);
                            }
                            mantissa = 0;
                        }
                    }
                    93 | 94 => {
                        group = G_FEED_MODE;
                        inverse_time = int_value == 93;
                    }
                    20 | 21 => {
                        group = G_UNITS;
                        inches = int_value == 20;
                    }
                    40 => group = G_CUTTER,
                    43 | 49 => {
                        group = G_TLO;
                        if axis_command != AxisCommand::None {
                            return Err(Status::AxisCommandConflict);
                        }
                        axis_command = AxisCommand::ToolLengthOffset;
                        if int_value == 49 {
                            tlo_mode = Some(false);
                        } else if mantissa == 10 {
                            tlo_mode = Some(true);
                        } else {
                            return Err(Status::UnsupportedCommand);
                        }
                        mantissa = 0;
                    }
                    54..=59 => {
                        group = G_COORD;
                        coord_select = (int_value - 54) as usize;
                    }
                    61 => {
                        group = G_CONTROL;
                        if mantissa != 0 {
                            return Err(Status::UnsupportedCommand);
                        }
                    }
                    _ => return Err(Status::UnsupportedCommand),
                }
                if mantissa > 0 {
                    return Err(Status::CommandValueNotInteger);
                }
                if command_words & group != 0 {
                    return Err(Status::ModalGroupViolation);
                }
                command_words |= group;
            }
            b'M' => {
                if mantissa > 0 {
                    return Err(Status::CommandValueNotInteger);
                }
                let group;
                match int_value {
                    0 | 1 | 2 | 30 => {
                        group = M_STOP;
                        flow = match int_value {
                            0 => Flow::Paused,
                            1 => Flow::Running, // M1 optional stop is not supported: ignored.
                            2 => Flow::End,
                            _ => Flow::EndRewind,
                        };
                    }
                    3..=5 => {
                        group = M_SPINDLE;
                        spindle = match int_value {
                            3 => Spindle::Cw,
                            4 => Spindle::Ccw,
                            _ => Spindle::Off,
                        };
                    }
                    8 | 9 => {
                        group = M_COOLANT;
                        if int_value == 8 {
                            flood = true;
                        } else {
                            flood = false;
                            mist = false;
                        }
                    }
                    _ => return Err(Status::UnsupportedCommand),
                }
                if command_words & group != 0 {
                    return Err(Status::ModalGroupViolation);
                }
                command_words |= group;
            }
            _ => {
                let bit = match letter {
                    b'F' => {
                        f = value;
                        W_F
                    }
                    b'I' => {
                        ijk[0] = value;
                        ijk_words |= 1;
                        W_I
                    }
                    b'J' => {
                        ijk[1] = value;
                        ijk_words |= 2;
                        W_J
                    }
                    b'K' => {
                        ijk[2] = value;
                        ijk_words |= 4;
                        W_K
                    }
                    b'L' => {
                        l = value;
                        W_L
                    }
                    b'N' => {
                        n = value.trunc();
                        W_N
                    }
                    b'P' => {
                        p = value;
                        W_P
                    }
                    b'R' => {
                        r = value;
                        W_R
                    }
                    b'S' => {
                        s = value;
                        W_S
                    }
                    b'T' => {
                        if value > MAX_TOOL_NUMBER {
                            return Err(Status::MaxValueExceeded);
                        }
                        t = value;
                        W_T
                    }
                    b'X' => {
                        xyz[0] = value;
                        axis_words |= 1;
                        W_X
                    }
                    b'Y' => {
                        xyz[1] = value;
                        axis_words |= 2;
                        W_Y
                    }
                    b'Z' => {
                        xyz[2] = value;
                        axis_words |= 4;
                        W_Z
                    }
                    _ => return Err(Status::UnsupportedCommand),
                };
                if value_words & bit != 0 {
                    return Err(Status::WordRepeated);
                }
                if bit & (W_F | W_N | W_P | W_T | W_S) != 0 && value < 0.0 {
                    return Err(Status::NegativeValue);
                }
                value_words |= bit;
            }
        }
    }

    // STEP 3: error checks.
    if axis_words != 0 && axis_command == AxisCommand::None {
        axis_command = AxisCommand::MotionMode;
    }
    if value_words & W_N != 0 && n > MAX_LINE_NUMBER {
        return Err(Status::InvalidLineNumber);
    }
    // Feed rate.
    if jog {
        if value_words & W_F == 0 {
            return Err(Status::UndefinedFeedRate);
        }
        if inches {
            f *= MM_PER_INCH;
        }
    } else if inverse_time {
        if axis_command == AxisCommand::MotionMode
            && !matches!(motion, Motion::None | Motion::Seek)
            && value_words & W_F == 0
        {
            return Err(Status::UndefinedFeedRate);
        }
    } else if !st.inverse_time {
        if value_words & W_F != 0 {
            if inches {
                f *= MM_PER_INCH;
            }
        } else {
            f = st.feed;
        }
    }
    // Switching from G93 to G94 takes F as given, without the inch conversion (as `gcode.c` does).
    if value_words & W_S == 0 {
        s = st.spindle_speed;
    }
    // Dwell.
    if non_modal == NonModal::Dwell {
        if value_words & W_P == 0 {
            return Err(Status::ValueWordMissing);
        }
        value_words &= !W_P;
    }
    let (axis_0, axis_1, axis_linear) = plane_axes(plane);
    if inches {
        for i in 0..N_AXIS {
            if axis_words & (1 << i) != 0 {
                xyz[i] *= MM_PER_INCH;
            }
        }
    }
    // Tool length offset.
    let mut tool_length_offset = st.tool_length_offset;
    if axis_command == AxisCommand::ToolLengthOffset {
        match tlo_mode {
            Some(true) => {
                if axis_words ^ 4 != 0 {
                    return Err(Status::G43DynamicAxisError);
                }
                tool_length_offset = xyz[2];
            }
            _ => tool_length_offset = 0.0,
        }
    } else if tlo_mode == Some(false) {
        tool_length_offset = 0.0;
    }
    // Work coordinate system of the block.
    let mut block_coord_system = st.coord_system;
    if command_words & G_COORD != 0 {
        block_coord_system = ctx.persist.coord[coord_select];
    }
    // Non-modal actions.
    let mut coord_data_write: Option<(usize, [f64; N_AXIS])> = None;
    let mut coord_offset = st.coord_offset;
    let mut go_home: Option<[f64; N_AXIS]> = None;
    match non_modal {
        NonModal::SetCoordData => {
            if axis_words == 0 {
                return Err(Status::NoAxisWords);
            }
            if value_words & (W_P | W_L) == 0 {
                return Err(Status::ValueWordMissing);
            }
            let p_int = p.trunc() as usize;
            if p_int > 6 {
                return Err(Status::UnsupportedCoordSys);
            }
            let lv = l.trunc() as i64;
            if lv != 20 {
                if lv == 2 {
                    if value_words & W_R != 0 {
                        return Err(Status::UnsupportedCommand);
                    }
                } else {
                    return Err(Status::UnsupportedCommand);
                }
            }
            value_words &= !(W_L | W_P);
            let idx = if p_int > 0 { p_int - 1 } else { coord_select };
            let mut data = ctx.persist.coord[idx];
            for i in 0..N_AXIS {
                if axis_words & (1 << i) != 0 {
                    if lv == 20 {
                        data[i] = st.position[i] - coord_offset[i] - xyz[i];
                        if i == 2 {
                            data[i] -= tool_length_offset;
                        }
                    } else {
                        data[i] = xyz[i];
                    }
                }
            }
            coord_data_write = Some((idx, data));
        }
        NonModal::SetCoordOffset => {
            for i in 0..N_AXIS {
                if axis_words & (1 << i) != 0 {
                    coord_offset[i] = st.position[i] - block_coord_system[i] - xyz[i];
                    if i == 2 {
                        coord_offset[i] -= tool_length_offset;
                    }
                }
            }
        }
        NonModal::ResetCoordOffset => coord_offset = [0.0; N_AXIS],
        _ => {
            if axis_command != AxisCommand::ToolLengthOffset && axis_words != 0 {
                for i in 0..N_AXIS {
                    if axis_words & (1 << i) == 0 {
                        xyz[i] = st.position[i];
                    } else if non_modal != NonModal::AbsoluteOverride {
                        if incremental {
                            xyz[i] += st.position[i];
                        } else {
                            xyz[i] += block_coord_system[i] + coord_offset[i];
                            if i == 2 {
                                xyz[i] += tool_length_offset;
                            }
                        }
                    }
                }
            }
            match non_modal {
                NonModal::GoHome0 | NonModal::GoHome1 => {
                    go_home = Some(if non_modal == NonModal::GoHome0 {
                        ctx.persist.g28
                    } else {
                        ctx.persist.g30
                    });
                    if axis_words == 0 {
                        axis_command = AxisCommand::None;
                    }
                }
                NonModal::SetHome0 | NonModal::SetHome1 => {}
                NonModal::AbsoluteOverride if !matches!(motion, Motion::Seek | Motion::Linear) => {
                    return Err(Status::G53InvalidMotionMode);
                }
                _ => {}
            }
        }
    }
    // Motion checks.
    let mut arc: Option<([f64; N_AXIS], f64, bool)> = None; // (ijk offsets mm, radius, clockwise)
    if motion == Motion::None {
        if axis_words != 0 {
            return Err(Status::AxisWordsExist);
        }
    } else if axis_command == AxisCommand::MotionMode {
        if motion == Motion::Seek {
            if axis_words == 0 {
                axis_command = AxisCommand::None;
            }
        } else {
            if f == 0.0 {
                return Err(Status::UndefinedFeedRate);
            }
            match motion {
                Motion::Linear if axis_words == 0 => {
                    axis_command = AxisCommand::None;
                }
                Motion::Cw | Motion::Ccw => {
                    if axis_words == 0 {
                        return Err(Status::NoAxisWords);
                    }
                    if axis_words & ((1 << axis_0) | (1 << axis_1)) == 0 {
                        return Err(Status::NoAxisWordsInPlane);
                    }
                    let mut x = xyz[axis_0] - st.position[axis_0];
                    let mut y = xyz[axis_1] - st.position[axis_1];
                    let radius;
                    if value_words & W_R != 0 {
                        value_words &= !W_R;
                        if st.position == xyz {
                            return Err(Status::InvalidTarget);
                        }
                        if inches {
                            r *= MM_PER_INCH;
                        }
                        let mut h = 4.0 * r * r - x * x - y * y;
                        if h < 0.0 {
                            return Err(Status::ArcRadiusError);
                        }
                        h = -h.sqrt() / x.hypot(y);
                        if motion == Motion::Ccw {
                            h = -h;
                        }
                        if r < 0.0 {
                            h = -h;
                            r = -r;
                        }
                        ijk[axis_0] = 0.5 * (x - y * h);
                        ijk[axis_1] = 0.5 * (y + x * h);
                        radius = r;
                    } else {
                        if ijk_words & ((1 << axis_0) | (1 << axis_1)) == 0 {
                            return Err(Status::NoOffsetsInPlane);
                        }
                        value_words &= !(W_I | W_J | W_K);
                        if inches {
                            for v in &mut ijk {
                                *v *= MM_PER_INCH;
                            }
                        }
                        x -= ijk[axis_0];
                        y -= ijk[axis_1];
                        let target_r = x.hypot(y);
                        radius = ijk[axis_0].hypot(ijk[axis_1]);
                        let delta_r = (target_r - radius).abs();
                        if delta_r > ARC_RADIUS_SLACK_MM
                            && (delta_r > ARC_RADIUS_MAX_ERROR_MM
                                || delta_r > ARC_RADIUS_REL_ERROR * radius)
                        {
                            return Err(Status::InvalidTarget);
                        }
                    }
                    arc = Some((ijk, radius, motion == Motion::Cw));
                }
                Motion::Probe(_) if st.position == xyz => {
                    return Err(Status::InvalidTarget);
                }
                _ => {}
            }
        }
    }
    // Unused words.
    value_words &= !(W_N | W_F | W_S | W_T);
    if axis_command != AxisCommand::None {
        value_words &= !(W_X | W_Y | W_Z);
    }
    if value_words != 0 {
        return Err(Status::UnusedWords);
    }
    if jog {
        if command_words & !(G_DISTANCE | G_UNITS | G_NONMODAL) != 0 {
            return Err(Status::InvalidJogCommand);
        }
        if !matches!(non_modal, NonModal::None | NonModal::AbsoluteOverride) {
            return Err(Status::InvalidJogCommand);
        }
    }

    // STEP 4: commit and plan. Nothing below fails.
    let laser = ctx.settings.laser_mode;
    let mut actions = Vec::new();
    let gc = &mut *ctx.gc;
    if jog {
        // A jog leaves the parser modes alone (`jog_execute`); only the position follows.
        if axis_words != 0 {
            actions.push(Action::Motion(MotionCmd {
                name: "JOG".into(),
                moves: vec![LineMove {
                    target: xyz,
                    rapid: false,
                    feed: f,
                    inverse_time: false,
                    jog: true,
                }],
                arc_center: None,
                feed: f,
                laser_off: true,
            }));
            gc.position = xyz;
        }
        return Ok(actions);
    }
    let motion_in_block = axis_command == AxisCommand::MotionMode
        && matches!(motion, Motion::Linear | Motion::Cw | Motion::Ccw);
    gc.inverse_time = inverse_time;
    gc.feed = f;
    // Spindle speed: a sync in GRBL unless laser mode and the block moves.
    if gc.spindle_speed != s {
        if gc.spindle != Spindle::Off && spindle == gc.spindle && !(laser && motion_in_block) {
            actions.push(Action::Sync);
            actions.push(Action::Spindle(gc.spindle, s));
        }
        gc.spindle_speed = s;
    }
    if value_words & W_T != 0 || t != 0.0 {
        gc.tool = t as u8;
    }
    if gc.spindle != spindle {
        actions.push(Action::Sync);
        actions.push(Action::Spindle(spindle, gc.spindle_speed));
        gc.spindle = spindle;
    }
    if gc.flood != flood || gc.mist != mist {
        actions.push(Action::Sync);
        actions.push(Action::Coolant(flood, mist));
        gc.flood = flood;
        gc.mist = mist;
    }
    if non_modal == NonModal::Dwell {
        actions.push(Action::Sync);
        actions.push(Action::Dwell(p));
    }
    gc.plane = plane;
    gc.inches = inches;
    if (axis_command == AxisCommand::ToolLengthOffset || tlo_mode.is_some())
        && gc.tool_length_offset != tool_length_offset
    {
        gc.tool_length_offset = tool_length_offset;
        actions.push(Action::WcoChanged);
    }
    if gc.coord_select != coord_select
        || command_words & G_COORD != 0 && gc.coord_system != block_coord_system
    {
        gc.coord_select = coord_select;
        gc.coord_system = block_coord_system;
        actions.push(Action::WcoChanged);
    }
    gc.incremental = incremental;
    let rapid_feed = 0.0;
    match non_modal {
        NonModal::SetCoordData => {
            let (idx, data) = coord_data_write.unwrap_or((0, [0.0; N_AXIS]));
            actions.push(Action::Sync);
            actions.push(Action::EepromWrite(COORD_RECORD_BYTES)); // EEPROM write syncs the buffer (FORCE_BUFFER_SYNC_DURING_EEPROM_WRITE)
            ctx.persist.coord[idx] = data;
            if idx == gc.coord_select {
                gc.coord_system = data;
                actions.push(Action::WcoChanged);
            }
        }
        NonModal::GoHome0 | NonModal::GoHome1 => {
            let name = if non_modal == NonModal::GoHome0 {
                "G28"
            } else {
                "G30"
            };
            if axis_command != AxisCommand::None {
                actions.push(Action::Motion(MotionCmd {
                    name: name.into(),
                    moves: vec![LineMove {
                        target: xyz,
                        rapid: true,
                        feed: rapid_feed,
                        inverse_time: false,
                        jog: false,
                    }],
                    arc_center: None,
                    feed: rapid_feed,
                    laser_off: true,
                }));
            }
            let home = go_home.unwrap_or(gc.position);
            actions.push(Action::Motion(MotionCmd {
                name: name.into(),
                moves: vec![LineMove {
                    target: home,
                    rapid: true,
                    feed: rapid_feed,
                    inverse_time: false,
                    jog: false,
                }],
                arc_center: None,
                feed: rapid_feed,
                laser_off: true,
            }));
            gc.position = home;
        }
        NonModal::SetHome0 => {
            actions.push(Action::Sync);
            actions.push(Action::EepromWrite(COORD_RECORD_BYTES));
            ctx.persist.g28 = ctx.machine_position;
        }
        NonModal::SetHome1 => {
            actions.push(Action::Sync);
            actions.push(Action::EepromWrite(COORD_RECORD_BYTES));
            ctx.persist.g30 = ctx.machine_position;
        }
        NonModal::SetCoordOffset | NonModal::ResetCoordOffset => {
            gc.coord_offset = coord_offset;
            actions.push(Action::WcoChanged);
        }
        _ => {}
    }
    gc.motion = motion;
    if motion != Motion::None && axis_command == AxisCommand::MotionMode {
        let start = gc.position;
        let laser_off = laser && !motion_in_block;
        match motion {
            Motion::Seek => actions.push(Action::Motion(MotionCmd {
                name: "G0".into(),
                moves: vec![LineMove {
                    target: xyz,
                    rapid: true,
                    feed: 0.0,
                    inverse_time: false,
                    jog: false,
                }],
                arc_center: None,
                feed: 0.0,
                laser_off,
            })),
            Motion::Linear | Motion::Probe(_) => {
                actions.push(Action::Motion(MotionCmd {
                    name: motion.name(),
                    moves: vec![LineMove {
                        target: xyz,
                        rapid: false,
                        feed: f,
                        inverse_time,
                        jog: false,
                    }],
                    arc_center: None,
                    feed: if inverse_time { 0.0 } else { f },
                    laser_off,
                }));
                if let Motion::Probe(k) = motion {
                    actions.push(Action::ProbeEnd(k));
                }
            }
            Motion::Cw | Motion::Ccw => {
                let (off, radius, cw) = arc.unwrap_or(([0.0; N_AXIS], 0.0, true));
                let (moves, center) = arc_moves(
                    start,
                    xyz,
                    off,
                    radius,
                    (axis_0, axis_1, axis_linear),
                    cw,
                    ctx.settings.arc_tolerance,
                    f,
                    inverse_time,
                );
                actions.push(Action::Motion(MotionCmd {
                    name: motion.name(),
                    moves,
                    arc_center: Some(center),
                    feed: if inverse_time { 0.0 } else { f },
                    laser_off,
                }));
            }
            Motion::None => {}
        }
        gc.position = xyz;
    }
    match flow {
        Flow::Paused => {
            actions.push(Action::Sync);
            actions.push(Action::Pause);
        }
        Flow::End | Flow::EndRewind => {
            actions.push(Action::Sync);
            gc.motion = Motion::Linear;
            gc.plane = 0;
            gc.incremental = false;
            gc.inverse_time = false;
            // GRBL 1.1h resets only modal groups 1, 2, 3, 5, 7, 12 and M7-M9 at program end
            // (`gcode.c`): the G92 offset, the tool length offset and F, S, T stay.
            gc.coord_select = 0;
            gc.spindle = Spindle::Off;
            gc.flood = false;
            gc.mist = false;
            if !ctx.check_mode {
                gc.coord_system = ctx.persist.coord[0];
                actions.push(Action::WcoChanged);
                actions.push(Action::Spindle(Spindle::Off, 0.0));
                actions.push(Action::Coolant(false, false));
            }
            actions.push(Action::RestoreOverrides);
            actions.push(Action::Message("Pgm End"));
        }
        Flow::Running => {}
    }
    Ok(actions)
}

/// `mc_arc`: chords of an arc within `$12` of the true circle, ending exactly at the target.
fn arc_moves(
    position: [f64; N_AXIS],
    target: [f64; N_AXIS],
    offset: [f64; N_AXIS],
    radius: f64,
    (a0, a1, al): (usize, usize, usize),
    clockwise: bool,
    arc_tolerance: f64,
    feed: f64,
    inverse_time: bool,
) -> (Vec<LineMove>, [f64; N_AXIS]) {
    let c0 = position[a0] + offset[a0];
    let c1 = position[a1] + offset[a1];
    let mut center = position;
    center[a0] = c0;
    center[a1] = c1;
    let r0 = -offset[a0];
    let r1 = -offset[a1];
    let rt0 = target[a0] - c0;
    let rt1 = target[a1] - c1;
    let mut angular = (r0 * rt1 - r1 * rt0).atan2(r0 * rt0 + r1 * rt1);
    if clockwise {
        if angular >= -ARC_ANGULAR_TRAVEL_EPSILON {
            angular -= 2.0 * std::f64::consts::PI;
        }
    } else if angular <= ARC_ANGULAR_TRAVEL_EPSILON {
        angular += 2.0 * std::f64::consts::PI;
    }
    let tol = arc_tolerance.max(1e-6);
    let denom = (tol * (2.0 * radius - tol)).max(1e-12).sqrt();
    let segments = ((0.5 * angular * radius).abs() / denom).floor().min(1.0e6) as usize;
    let mut moves = Vec::with_capacity(segments.max(1));
    let (seg_feed, seg_inverse) = if inverse_time && segments > 0 {
        (feed * segments as f64, true)
    } else {
        (feed, inverse_time)
    };
    if segments > 0 {
        let theta = angular / segments as f64;
        let lin = (target[al] - position[al]) / segments as f64;
        for i in 1..segments {
            let (sn, cs) = (theta * i as f64).sin_cos();
            let mut p = position;
            p[a0] = c0 + r0 * cs - r1 * sn;
            p[a1] = c1 + r0 * sn + r1 * cs;
            p[al] = position[al] + lin * i as f64;
            moves.push(LineMove {
                target: p,
                rapid: false,
                feed: seg_feed,
                inverse_time: seg_inverse,
                jog: false,
            });
        }
    }
    moves.push(LineMove {
        target,
        rapid: false,
        feed: seg_feed,
        inverse_time: seg_inverse,
        jog: false,
    });
    (moves, center)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_float_follows_grbl() {
        let cases: &[(&str, Option<f64>, usize)] = &[
            ("1.5X", Some(1.5), 3),
            ("-.5", Some(-0.5), 3),
            ("+2", Some(2.0), 2),
            ("1.2.3", Some(1.2), 3),
            ("-", None, 0),
            (".", None, 0),
            ("X", None, 0),
        ];
        for (text, want, end) in cases {
            let mut p = 0;
            assert_eq!(read_float(text.as_bytes(), &mut p), *want, "{text}");
            assert_eq!(p, *end, "{text}");
        }
    }

    fn run(line: &str, gc: &mut GcState) -> Result<Vec<Action>, Status> {
        let settings = Settings::default();
        let mut persist = Persist::default();
        let mut ctx = Context {
            gc,
            settings: &settings,
            persist: &mut persist,
            machine_position: [0.0; 3],
            check_mode: false,
        };
        execute(line.as_bytes(), false, &mut ctx)
    }

    #[test]
    fn radius_arc_centre_matches_the_offset_form() {
        // Quarter circle from (0,0) to (10,10), radius 10, CW: centre (10,0) (the short way).
        let mut gc = GcState::new([0.0; 3], [0.0; 3]);
        let a = run("G2X10Y10R10F100", &mut gc).unwrap();
        let Action::Motion(m) = &a[0] else {
            panic!("{a:?}")
        };
        let c = m.arc_center.unwrap();
        assert!((c[0] - 10.0).abs() < 1e-12 && c[1].abs() < 1e-12, "{c:?}");
        // Negative R takes the long way: centre (0,10).
        let mut gc = GcState::new([0.0; 3], [0.0; 3]);
        let a = run("G2X10Y10R-10F100", &mut gc).unwrap();
        let Action::Motion(m) = &a[0] else {
            panic!("{a:?}")
        };
        let c = m.arc_center.unwrap();
        assert!(c[0].abs() < 1e-12 && (c[1] - 10.0).abs() < 1e-12, "{c:?}");
        // Chords: every vertex on the circle, chord sagitta within $12.
        let r: f64 = 10.0;
        for mv in &m.moves {
            let d = (mv.target[0] - c[0]).hypot(mv.target[1] - c[1]);
            assert!((d - r).abs() < 1e-9);
        }
        let n = m.moves.len() as f64;
        let theta = 1.5 * std::f64::consts::PI / n;
        // `mc_arc` floors the segment count, so a chord may exceed the tolerance by that rounding only.
        let sagitta = r * (1.0 - (theta / 2.0).cos());
        assert!(sagitta <= 0.002 * ((n + 1.0) / n).powi(2), "{sagitta}");
        assert!(sagitta > 0.0018);
    }

    #[test]
    fn inches_and_incremental() {
        let mut gc = GcState::new([0.0; 3], [0.0; 3]);
        run("G20G91G0X1", &mut gc).unwrap();
        run("X1", &mut gc).unwrap();
        assert!((gc.position[0] - 50.8).abs() < 1e-12);
        assert_eq!(
            gc.report(false),
            "[GC:G0 G54 G17 G20 G91 G94 M5 M9 T0 F0 S0]"
        );
        // A rejected line changes nothing.
        let before = gc.clone();
        assert_eq!(run("G90G1X0", &mut gc), Err(Status::UndefinedFeedRate));
        assert_eq!(gc, before);
    }
}
