//! The g-code parser of GRBL 1.1h (`gcode.c`): word import, modal groups, the error checks in GRBL's order,
//! and the execution plan of a valid block as a list of [`Action`]s for the protocol loop. This file holds the
//! parser's types and [`execute`], which runs the steps of `gc_execute_line` in order: `import` (STEP 2),
//! `check` (STEP 3) and `plan` (STEP 4).
//!
//! Written here rather than taken from a g-code crate because the point of the simulator is to reproduce GRBL's
//! exact acceptance rules and error numbers (e.g. `G2` with an R that is too small → `error:34`), which general
//! parsers do not model.

use crate::settings::{N_AXIS, Settings};
use crate::status::Status;

mod check;
mod import;
mod plan;

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

/// The block being parsed (`gc_block` of GRBL), carried from the word import through the checks to the plan.
/// The modes start as the parser state's; the checks turn the words into machine millimetres.
struct Block {
    /// A `$J=` line.
    jog: bool,
    /// Group 1.
    motion: Motion,
    /// G93.
    inverse_time: bool,
    /// G20.
    inches: bool,
    /// G91.
    incremental: bool,
    /// 0 = G17, 1 = G18, 2 = G19.
    plane: u8,
    /// 0..=5 for G54..G59.
    coord_select: usize,
    /// M0/M2/M30 of this block (program flow is not modal).
    flow: Flow,
    /// M3/M4/M5.
    spindle: Spindle,
    /// M8.
    flood: bool,
    /// M7.
    mist: bool,
    /// `Some(true)` = G43.1, `Some(false)` = G49.
    tlo_mode: Option<bool>,
    /// Group 0.
    non_modal: NonModal,
    /// Which command the axis words belong to.
    axis_command: AxisCommand,
    /// Modal groups seen (`G_*`, `M_*` bits).
    command_words: u32,
    /// Value words seen and not yet used (`W_*` bits).
    value_words: u16,
    /// Axis words seen (bit i = axis i).
    axis_words: u8,
    /// I/J/K words seen (bit i = axis i).
    ijk_words: u8,
    /// X/Y/Z as given, then the target in machine mm.
    xyz: [f64; N_AXIS],
    /// I/J/K as given, then the arc centre offset in mm.
    ijk: [f64; N_AXIS],
    /// F, then the block's feed in mm/min (or 1/min in G93).
    f: f64,
    /// L.
    l: f64,
    /// N.
    n: f64,
    /// P.
    p: f64,
    /// R.
    r: f64,
    /// S (modal: the parser's unless the block gives one).
    s: f64,
    /// T.
    t: f64,
    /// Tool length offset after the block, mm.
    tool_length_offset: f64,
    /// Work coordinate system of the block (G54..G59 data), mm.
    coord_system: [f64; N_AXIS],
    /// G92 offset after the block, mm.
    coord_offset: [f64; N_AXIS],
    /// G10 write: (G54..G59 index, data).
    coord_data_write: Option<(usize, [f64; N_AXIS])>,
    /// G28/G30 stored position to go to.
    go_home: Option<[f64; N_AXIS]>,
    /// Arc: (centre offset mm, radius mm, clockwise).
    arc: Option<([f64; N_AXIS], f64, bool)>,
}

/// Parses and plans one pre-processed line (upper-case, no spaces/comments). `jog` is true for `$J=` lines
/// (the line passed is the part after `$J=`). The steps and their order are those of `gc_execute_line`, so a
/// line with several errors reports the one GRBL reports.
pub fn execute(line: &[u8], jog: bool, ctx: &mut Context<'_>) -> Result<Vec<Action>, Status> {
    let st = &*ctx.gc;
    // STEP 2: import words.
    let mut block = Block::import(line, jog, st)?;
    // STEP 3: error checks, each group in GRBL's order.
    block.check_line_number()?;
    block.check_feed_and_units(st)?;
    block.check_dwell()?;
    block.check_tool_length_offset()?;
    block.select_coordinate_system(ctx.persist);
    block.check_non_modal(st, ctx.persist)?;
    block.check_motion(st)?;
    block.check_unused_words()?;
    block.check_jog()?;
    // STEP 4: commit and plan. Nothing below fails.
    Ok(block.plan_actions(ctx))
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
