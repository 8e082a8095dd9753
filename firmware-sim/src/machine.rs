//! The sans-IO GRBL core: RX ring, line pre-parser, protocol loop, `$` commands, realtime commands, status
//! reports, alarms, resets and the motion trace, all on a virtual clock advanced by [`Grbl::tick`].

use crate::gcode::{self, Action, Context, GcState, MotionCmd, Persist, Spindle};
use crate::planner::{PLANNER_BLOCKS, Planner, StepEvents};
use crate::rng::Rng;
use crate::settings::{N_AXIS, Settings, fmt_float};
use crate::status::{Status, alarm};
use crate::{Faults, RX_BUFFER_SIZE, RxOverflow, SimConfig, SimStats, TraceSegment};
use std::collections::{BTreeMap, VecDeque};

/// Power-up and reset banner (`report.c:172`).
pub const BANNER: &str = "\r\nGrbl 1.1h ['$' for help]\r\n";
/// `LINE_BUFFER_SIZE` 80 minus the terminator: longest line after pre-parsing (`protocol.h`).
pub const LINE_MAX: usize = 79;
/// Executor time step, s. Small against the 10 ms segments GRBL plans (`ACCELERATION_TICKS_PER_SECOND` 100).
const STEP_S: f64 = 0.001;
/// What is left of the step idle delay below this, s, is clock rounding: the delay is over.
const IDLE_LOCK_EPS: f64 = 1e-9;
/// `DWELL_TIME_STEP` (`config.h`), s: `delay_sec` waits in whole steps of it.
const DWELL_TIME_STEP_S: f64 = 0.05;

/// How long `G4 P<p>` waits: `delay_sec` loops `ceil(1000 / DWELL_TIME_STEP × p)` times over
/// `DWELL_TIME_STEP` ms, in the Uno's single precision (`P0.01` waits 50 ms).
fn dwell_seconds(p: f64) -> f64 {
    let steps = (20.0f32 * p as f32).ceil();
    f64::from(steps.max(0.0)) * DWELL_TIME_STEP_S
}
/// Build date string of `$I` (`grbl.h`).
const BUILD: &str = "1.1h.20190830";
/// Time the ATmega328P needs to program one EEPROM byte, s (datasheet: 3.3 ms). GRBL keeps interrupts off while it
/// waits, so the UART loses what arrives meanwhile except about one byte per write.
const EEPROM_BYTE_S: f64 = 0.0034;
/// Changed bytes of one `$x=` write: a float and the checksum.
const SETTING_WRITE_BYTES: u32 = 5;
/// `SAFETY_DOOR_SPINDLE_DELAY` (s): spin-up wait when resuming from a door stop (not in laser mode).
const DOOR_SPINDLE_DELAY_S: f64 = 4.0;
/// `SAFETY_DOOR_COOLANT_DELAY` (s).
const DOOR_COOLANT_DELAY_S: f64 = 1.0;
/// Override limits and steps (`config.h:241-260`), percent.
const FEED_OVR_RANGE: (u8, u8) = (10, 200);
const SPINDLE_OVR_RANGE: (u8, u8) = (10, 200);
/// Status-report refresh counts of the `WCO:` and `Ov:` fields (`config.h:285-288`).
const WCO_REFRESH_IDLE: u8 = 10;
const WCO_REFRESH_BUSY: u8 = 30;
const OVR_REFRESH_IDLE: u8 = 10;
const OVR_REFRESH_BUSY: u8 = 20;

/// Machine state as the status report names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum State {
    /// Idle.
    Idle,
    /// Run (cycle).
    Cycle,
    /// Feed hold.
    Hold,
    /// Jogging.
    Jog,
    /// Alarm lock.
    Alarm,
    /// `$C` check mode.
    CheckMode,
    /// Homing cycle.
    Homing,
    /// `$SLP`.
    Sleep,
    /// Safety door (0x84): stopped with spindle and coolant off until cycle start.
    Door,
}

/// Something the I/O layer must act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimEvent {
    /// Fault injection: close the device now.
    Hangup,
}

/// What follows the `ok` of a `$` command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AfterOk {
    Nothing,
    Reset,
    Sleep,
}

#[derive(Debug, Clone)]
struct Record {
    seg: TraceSegment,
    started: bool,
    live: usize,
    all_queued: bool,
    alarm: Option<u8>,
    last_target: [f64; N_AXIS],
}

#[derive(Debug, Clone)]
struct ActiveMotion {
    cmd: MotionCmd,
    next: usize,
    record: usize,
}

/// The simulated controller.
#[derive(Debug, Clone)]
pub struct Grbl {
    settings: Settings,
    persist: Persist,
    build_info: String,
    gc: GcState,
    state: State,
    hold_complete: bool,
    jog_cancel: bool,
    m0_pause: bool,
    critical: bool,
    soft_limit_wait: bool,
    rx: VecDeque<u8>,
    rx_overflow: RxOverflow,
    line: Vec<u8>,
    comment_paren: bool,
    comment_semi: bool,
    line_overflow: bool,
    pending: VecDeque<Action>,
    active_motion: Option<ActiveMotion>,
    line_active: bool,
    after_ok: AfterOk,
    cur_line_no: u32,
    cur_line_text: String,
    cur_line_alarm: Option<u8>,
    planner: Planner,
    instant: bool,
    dwell_left: f64,
    /// `st_go_idle`'s `delay_ms($1)` after the steppers stop, s left: the main loop waits.
    idle_lock_left: f64,
    /// The steppers were running at the end of the last executor step.
    stepping: bool,
    out: Vec<u8>,
    clock: f64,
    records: BTreeMap<usize, Record>,
    next_record: usize,
    trace: Vec<TraceSegment>,
    feed_ovr: u8,
    rapid_ovr: u8,
    spindle_ovr: u8,
    spindle_out: Spindle,
    spindle_speed_out: f64,
    spindle_stop_ovr: bool,
    flood_out: bool,
    mist_out: bool,
    wco_counter: u8,
    ovr_counter: u8,
    faults: Faults,
    rng: Rng,
    lines_received: u32,
    stats: SimStats,
    /// Powered off, or in the bootloader: nothing runs and received bytes are lost.
    off: bool,
    events: Vec<SimEvent>,
    probe_pos: [f64; N_AXIS],
    door_restore_left: f64,
    door_saved: (Spindle, f64, bool, bool),
    eeprom_left: f64,
    eeprom_total: f64,
    eeprom_slot: i64,
}

fn axes(v: [f64; N_AXIS], inches: bool) -> String {
    let (scale, d) = if inches {
        (1.0 / crate::gcode::MM_PER_INCH, 4)
    } else {
        (1.0, 3)
    };
    v.iter()
        .map(|x| fmt_float(x * scale, d))
        .collect::<Vec<_>>()
        .join(",")
}

impl Default for Grbl {
    fn default() -> Self {
        Grbl::new(&SimConfig::default())
    }
}

impl Grbl {
    /// A powered-up controller: settings applied, banner in the output, alarm-locked if homing is enabled.
    pub fn new(config: &SimConfig) -> Self {
        let mut settings = Settings::default();
        for &(n, v) in &config.settings {
            // Soft limits need homing: apply in an order that lets a config enable both.
            if n == 20 && v != 0.0 {
                settings.homing = true;
            }
            let _ = settings.store(u32::from(n), v);
        }
        let planner = Planner::new([0.0; N_AXIS], &settings);
        let persist = Persist::default();
        let mut g = Grbl {
            gc: GcState::new([0.0; N_AXIS], persist.coord[0]),
            persist,
            build_info: String::new(),
            state: if settings.homing {
                State::Alarm
            } else {
                State::Idle
            },
            settings,
            hold_complete: false,
            jog_cancel: false,
            m0_pause: false,
            critical: false,
            soft_limit_wait: false,
            rx: VecDeque::with_capacity(RX_BUFFER_SIZE),
            rx_overflow: config.rx_overflow,
            line: Vec::with_capacity(LINE_MAX + 1),
            comment_paren: false,
            comment_semi: false,
            line_overflow: false,
            pending: VecDeque::new(),
            active_motion: None,
            line_active: false,
            after_ok: AfterOk::Nothing,
            cur_line_no: 0,
            cur_line_text: String::new(),
            cur_line_alarm: None,
            planner,
            instant: config.instant_motion,
            dwell_left: 0.0,
            idle_lock_left: 0.0,
            stepping: false,
            out: Vec::new(),
            clock: 0.0,
            records: BTreeMap::new(),
            next_record: 0,
            trace: Vec::new(),
            feed_ovr: 100,
            rapid_ovr: 100,
            spindle_ovr: 100,
            spindle_out: Spindle::Off,
            spindle_speed_out: 0.0,
            spindle_stop_ovr: false,
            flood_out: false,
            mist_out: false,
            wco_counter: 0,
            ovr_counter: 0,
            faults: config.faults.clone(),
            rng: Rng::new(config.seed),
            lines_received: 0,
            stats: SimStats::default(),
            off: false,
            events: Vec::new(),
            probe_pos: [0.0; N_AXIS],
            door_restore_left: 0.0,
            door_saved: (Spindle::Off, 0.0, false, false),
            eeprom_left: 0.0,
            eeprom_total: 0.0,
            eeprom_slot: -1,
        };
        g.startup();
        g
    }

    // ----- accessors -------------------------------------------------------------------------------------------

    /// Current state.
    pub fn state(&self) -> State {
        self.state
    }
    /// Hold completed (`Hold:0`).
    pub fn hold_complete(&self) -> bool {
        self.hold_complete
    }
    /// Settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }
    /// Parser state.
    pub fn gc_state(&self) -> &GcState {
        &self.gc
    }
    /// Executed machine position, mm (rounded to whole steps, as GRBL reports it).
    pub fn machine_position(&self) -> [f64; N_AXIS] {
        let mut p = [0.0; N_AXIS];
        for i in 0..N_AXIS {
            let spm = self.settings.steps_per_mm[i];
            p[i] = (self.planner.pos[i] * spm).round() / spm;
        }
        p
    }
    /// Virtual clock, s.
    pub fn clock(&self) -> f64 {
        self.clock
    }
    /// Bytes waiting in the RX ring.
    pub fn rx_len(&self) -> usize {
        self.rx.len()
    }
    /// Free RX bytes.
    pub fn rx_free(&self) -> usize {
        RX_BUFFER_SIZE - self.rx.len()
    }
    /// Blocks in the planner.
    pub fn planner_len(&self) -> usize {
        self.planner.blocks.len()
    }
    /// Lines received so far.
    pub fn lines_received(&self) -> u32 {
        self.lines_received
    }
    /// Counters.
    pub fn stats(&self) -> SimStats {
        let mut s = self.stats.clone();
        s.lines_received = self.lines_received;
        s
    }
    /// Executed motions so far.
    pub fn trace(&self) -> &[TraceSegment] {
        &self.trace
    }
    /// Nothing to do: idle, no pending line, empty planner and RX.
    pub fn is_quiescent(&self) -> bool {
        self.pending.is_empty()
            && !self.line_active
            && self.planner.blocks.is_empty()
            && self.rx.is_empty()
            && self.dwell_left <= 0.0
            && self.idle_lock_left <= 0.0
    }
    /// Takes the bytes answered so far.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }
    /// Takes pending I/O events.
    pub fn take_events(&mut self) -> Vec<SimEvent> {
        std::mem::take(&mut self.events)
    }

    // ----- input -----------------------------------------------------------------------------------------------

    /// One byte from the link: faults, then realtime commands (never buffered), then the RX ring, which drops the
    /// byte when full (or, with [`RxOverflow::Block`], refuses it: returns false and the caller keeps it).
    pub fn receive(&mut self, byte: u8) -> bool {
        if self.rx_overflow == RxOverflow::Block
            && self.rx.len() >= RX_BUFFER_SIZE
            && !is_realtime(byte)
        {
            return false;
        }
        self.stats.bytes_received += 1;
        if self.off {
            // The bootloader (or nothing, powered off) reads the line: GRBL never sees it.
            self.stats.bytes_dropped_boot += 1;
            return true;
        }
        if self.eeprom_left > 0.0 {
            // Interrupts are off while the EEPROM programs; one byte per write survives in the UART.
            let slot = ((self.eeprom_total - self.eeprom_left) / EEPROM_BYTE_S).floor() as i64;
            if slot == self.eeprom_slot {
                self.stats.bytes_dropped_eeprom += 1;
                return true;
            }
            self.eeprom_slot = slot;
        }
        if self.rng.chance(self.faults.drop_rate) {
            self.stats.bytes_dropped_fault += 1;
            return true;
        }
        let mut byte = byte;
        if self.rng.chance(self.faults.corrupt_rate) {
            byte ^= 1 << (self.rng.next_u64() % 8);
            self.stats.bytes_corrupted += 1;
        }
        if self.realtime(byte) {
            return true;
        }
        if byte > 0x7f {
            return true; // Unknown extended byte: thrown away (`serial.c`).
        }
        if self.rx.len() >= RX_BUFFER_SIZE {
            self.stats.bytes_dropped_overflow += 1;
            return true;
        }
        self.rx.push_back(byte);
        self.stats.max_rx_fill = self.stats.max_rx_fill.max(self.rx.len());
        true
    }

    /// Feeds a whole slice (no time passes).
    pub fn receive_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.receive(b);
        }
    }

    fn realtime(&mut self, byte: u8) -> bool {
        match byte {
            0x18 => {
                self.soft_reset();
            }
            b'?' => {
                if !self.critical {
                    self.status_report();
                }
            }
            b'!' => self.feed_hold(),
            b'~' => self.cycle_start(),
            0x85 => {
                if self.state == State::Jog {
                    self.jog_cancel = true;
                }
            }
            0x90..=0x94 => {
                let v = i16::from(self.feed_ovr);
                let nv = match byte {
                    0x90 => 100,
                    0x91 => v + 10,
                    0x92 => v - 10,
                    0x93 => v + 1,
                    _ => v - 1,
                };
                let nv = nv.clamp(i16::from(FEED_OVR_RANGE.0), i16::from(FEED_OVR_RANGE.1)) as u8;
                if nv != self.feed_ovr {
                    self.feed_ovr = nv;
                    self.ovr_counter = 0;
                    self.replan();
                }
            }
            0x95..=0x97 => {
                let nv = match byte {
                    0x95 => 100,
                    0x96 => 50,
                    _ => 25,
                };
                if nv != self.rapid_ovr {
                    self.rapid_ovr = nv;
                    self.ovr_counter = 0;
                    self.replan();
                }
            }
            0x99..=0x9d => {
                let v = i16::from(self.spindle_ovr);
                let nv = match byte {
                    0x99 => 100,
                    0x9a => v + 10,
                    0x9b => v - 10,
                    0x9c => v + 1,
                    _ => v - 1,
                };
                let nv = nv.clamp(
                    i16::from(SPINDLE_OVR_RANGE.0),
                    i16::from(SPINDLE_OVR_RANGE.1),
                ) as u8;
                if nv != self.spindle_ovr {
                    self.spindle_ovr = nv;
                    self.ovr_counter = 0;
                }
            }
            0x9e => {
                if self.state == State::Hold {
                    self.spindle_stop_ovr = !self.spindle_stop_ovr;
                }
            }
            0xa0 => {
                if matches!(self.state, State::Idle | State::Cycle | State::Hold) {
                    self.flood_out = !self.flood_out;
                    self.gc.flood = self.flood_out;
                    self.ovr_counter = 0;
                }
            }
            0x84 => self.safety_door(),
            0xa1 => {} // Mist coolant needs ENABLE_M7, which the Uno build leaves out.
            _ => return false,
        }
        true
    }

    fn replan(&mut self) {
        self.planner
            .recalculate(f64::from(self.feed_ovr), f64::from(self.rapid_ovr));
    }

    fn feed_hold(&mut self) {
        if self.critical {
            return;
        }
        match self.state {
            State::Cycle => {
                self.state = State::Hold;
                self.hold_complete = false;
            }
            State::Idle => {
                self.state = State::Hold;
                self.hold_complete = true;
            }
            State::Jog => self.jog_cancel = true,
            _ => {}
        }
    }

    /// 0x84: stop like a feed hold and switch spindle and coolant off. The simulated door switch closes again at
    /// once, so the state reads `Door:2` while braking and `Door:0` (ready to resume) once stopped.
    fn safety_door(&mut self) {
        if self.critical || matches!(self.state, State::Alarm | State::CheckMode | State::Sleep) {
            return;
        }
        self.emit_line("[MSG:Check Door]");
        match self.state {
            State::Jog => self.jog_cancel = true,
            State::Door => {}
            _ => {
                self.door_saved = (
                    self.spindle_out,
                    self.spindle_speed_out,
                    self.flood_out,
                    self.mist_out,
                );
                self.spindle_out = Spindle::Off;
                self.spindle_speed_out = 0.0;
                self.flood_out = false;
                self.mist_out = false;
                self.hold_complete = self.planner.blocks.is_empty() || self.planner.v <= 0.0;
                self.door_restore_left = 0.0;
                self.state = State::Door;
            }
        }
    }

    fn cycle_start(&mut self) {
        if self.critical {
            return;
        }
        match self.state {
            State::Door if self.hold_complete && self.door_restore_left <= 0.0 => {
                let (sp, speed, flood, mist) = self.door_saved;
                let mut delay = 0.0;
                if sp != Spindle::Off && !self.settings.laser_mode {
                    delay += DOOR_SPINDLE_DELAY_S;
                }
                if flood || mist {
                    delay += DOOR_COOLANT_DELAY_S;
                }
                (
                    self.spindle_out,
                    self.spindle_speed_out,
                    self.flood_out,
                    self.mist_out,
                ) = (sp, speed, flood, mist);
                if delay > 0.0 {
                    self.door_restore_left = delay;
                } else {
                    self.finish_door_restore();
                }
            }
            State::Hold if self.hold_complete => {
                self.m0_pause = false;
                self.spindle_stop_ovr = false;
                self.hold_complete = false;
                self.state = if self.planner.blocks.is_empty() {
                    State::Idle
                } else {
                    State::Cycle
                };
            }
            State::Idle if !self.planner.blocks.is_empty() => self.state = State::Cycle,
            _ => {}
        }
    }

    fn finish_door_restore(&mut self) {
        self.door_restore_left = 0.0;
        self.hold_complete = false;
        self.state = if self.planner.blocks.is_empty() {
            State::Idle
        } else {
            State::Cycle
        };
    }

    // ----- output ----------------------------------------------------------------------------------------------

    fn emit(&mut self, s: &str) {
        self.out.extend_from_slice(s.as_bytes());
        self.stats.bytes_sent += s.len() as u64;
    }

    fn emit_line(&mut self, s: &str) {
        self.emit(s);
        self.emit("\r\n");
    }

    fn respond(&mut self, result: Result<(), Status>) {
        match result {
            Ok(()) => {
                self.stats.oks += 1;
                self.emit_line("ok");
            }
            Err(e) => {
                self.stats.errors += 1;
                self.emit_line(&format!("error:{}", e.code()));
            }
        }
    }

    fn status_report(&mut self) {
        let state = match self.state {
            State::Idle => "Idle".to_string(),
            State::Cycle => "Run".to_string(),
            State::Hold => format!("Hold:{}", if self.hold_complete { 0 } else { 1 }),
            State::Jog => "Jog".to_string(),
            State::Alarm => "Alarm".to_string(),
            State::CheckMode => "Check".to_string(),
            State::Homing => "Home".to_string(),
            State::Sleep => "Sleep".to_string(),
            State::Door => {
                let n = if self.door_restore_left > 0.0 {
                    3
                } else if self.hold_complete {
                    0
                } else {
                    2
                };
                format!("Door:{n}")
            }
        };
        let inches = self.settings.report_inches;
        let mpos = self.machine_position();
        let wco = self.gc.wco();
        let mut s = format!("<{state}|");
        if self.settings.status_mask & 1 != 0 {
            s.push_str(&format!("MPos:{}", axes(mpos, inches)));
        } else {
            let mut w = mpos;
            for i in 0..N_AXIS {
                w[i] -= wco[i];
            }
            s.push_str(&format!("WPos:{}", axes(w, inches)));
        }
        if self.settings.status_mask & 2 != 0 {
            s.push_str(&format!(
                "|Bf:{},{}",
                PLANNER_BLOCKS - self.planner.blocks.len(),
                self.rx_free()
            ));
        }
        let feed = self.planner.v * 60.0;
        let feed_s = if inches {
            fmt_float(feed / crate::gcode::MM_PER_INCH, 1)
        } else {
            fmt_float(feed, 0)
        };
        // `spindle_compute_pwm_value`: the override scales S, then $30/$31 clamp it.
        let rpm = if self.spindle_out == Spindle::Off || self.spindle_stop_ovr {
            0.0
        } else {
            (self.spindle_speed_out * f64::from(self.spindle_ovr) / 100.0)
                .clamp(self.settings.rpm_min, self.settings.rpm_max)
        };
        s.push_str(&format!("|FS:{},{}", feed_s, fmt_float(rpm, 0)));
        let busy = matches!(
            self.state,
            State::Cycle | State::Hold | State::Jog | State::Homing | State::Door
        );
        if self.wco_counter > 0 {
            self.wco_counter -= 1;
        } else {
            self.wco_counter = if busy {
                WCO_REFRESH_BUSY - 1
            } else {
                WCO_REFRESH_IDLE - 1
            };
            if self.ovr_counter == 0 {
                self.ovr_counter = 1;
            }
            s.push_str(&format!("|WCO:{}", axes(wco, inches)));
        }
        if self.ovr_counter > 0 {
            self.ovr_counter -= 1;
        } else {
            self.ovr_counter = if busy {
                OVR_REFRESH_BUSY - 1
            } else {
                OVR_REFRESH_IDLE - 1
            };
            s.push_str(&format!(
                "|Ov:{},{},{}",
                self.feed_ovr, self.rapid_ovr, self.spindle_ovr
            ));
            let mut a = String::new();
            match self.spindle_out {
                Spindle::Cw => a.push('S'),
                Spindle::Ccw => a.push('C'),
                Spindle::Off => {}
            }
            if self.flood_out {
                a.push('F');
            }
            if self.mist_out {
                a.push('M');
            }
            if !a.is_empty() {
                s.push_str(&format!("|A:{a}"));
            }
        }
        s.push('>');
        self.emit_line(&s);
    }

    // ----- reset and alarms ------------------------------------------------------------------------------------

    /// Whether a reset now aborts motion (`mc_reset`): a cycle, jog or homing, or a hold still braking. A hold that
    /// has come to rest clears `STEP_CONTROL_EXECUTE_HOLD` (`protocol_exec_rt_system`), so resetting it loses no
    /// step and raises no alarm.
    fn moving(&self) -> bool {
        matches!(self.state, State::Cycle | State::Jog | State::Homing)
            || (matches!(self.state, State::Hold | State::Door)
                && !self.planner.blocks.is_empty()
                && !self.hold_complete)
    }

    /// Soft reset (0x18, `$C` off, `$RST`, faults): `mc_reset` then the re-initialisation of `main.c`.
    pub fn soft_reset(&mut self) {
        self.stats.resets += 1;
        if !self.critical && self.moving() {
            let code = if self.state == State::Homing {
                alarm::HOMING_FAIL_RESET
            } else {
                alarm::ABORT_CYCLE
            };
            self.stats.alarms += 1;
            self.emit_line(&format!("ALARM:{code}"));
            self.state = State::Alarm;
        }
        // The line whose execution the reset interrupted still returns to the main loop and reports `ok`.
        if self.line_active {
            self.respond(Ok(()));
            self.line_active = false;
        }
        self.stop_motion();
        self.critical = false;
        self.soft_limit_wait = false;
        self.rx.clear();
        self.line.clear();
        self.comment_paren = false;
        self.comment_semi = false;
        self.line_overflow = false;
        self.pending.clear();
        self.active_motion = None;
        self.after_ok = AfterOk::Nothing;
        self.dwell_left = 0.0;
        self.idle_lock_left = 0.0;
        self.stepping = false;
        self.eeprom_left = 0.0;
        self.hold_complete = false;
        self.jog_cancel = false;
        self.m0_pause = false;
        self.spindle_stop_ovr = false;
        self.feed_ovr = 100;
        self.rapid_ovr = 100;
        self.spindle_ovr = 100;
        self.spindle_out = Spindle::Off;
        self.spindle_speed_out = 0.0;
        self.flood_out = false;
        self.mist_out = false;
        self.wco_counter = 0;
        self.ovr_counter = 0;
        self.state = match self.state {
            State::Alarm | State::Sleep => State::Alarm,
            _ => State::Idle,
        };
        self.gc = GcState::new(self.machine_position(), self.persist.coord[0]);
        self.startup();
    }

    /// Power cycle (the device was unplugged and plugged in again): motion and output are gone, the position is
    /// zero, settings and EEPROM data are kept, and the banner comes as at power-up.
    pub fn power_cycle(&mut self) {
        self.power_off();
        self.power_on();
    }

    /// Power off (or a hardware reset, which holds the chip until its bootloader hands over): motion and output
    /// are gone, the position is zero (and with it the work offsets that live in RAM: G92, the tool length
    /// offset), settings and EEPROM data are kept; until [`Grbl::power_on`] nothing runs and every byte received
    /// is lost.
    pub fn power_off(&mut self) {
        self.out.clear();
        self.line_active = false;
        self.critical = false;
        self.pending.clear();
        self.active_motion = None;
        self.stop_motion();
        self.planner.pos = [0.0; N_AXIS];
        self.planner.sync_position(&self.settings);
        self.rx.clear();
        self.off = true;
    }

    /// GRBL starts (power-up, or the bootloader handed over): the banner, and alarm-locked where homing is on.
    pub fn power_on(&mut self) {
        self.off = false;
        self.state = if self.settings.homing {
            State::Alarm
        } else {
            State::Idle
        };
        self.soft_reset();
    }

    /// Whether the controller is off (powered down, or in the bootloader after a reset).
    pub fn is_off(&self) -> bool {
        self.off
    }

    fn startup(&mut self) {
        self.emit(BANNER);
        if self.state == State::Alarm {
            self.emit_line("[MSG:'$H'|'$X' to unlock]");
            return;
        }
        for i in 0..2 {
            let line = self.persist.startup[i].clone();
            if line.is_empty() {
                continue;
            }
            let r = self.gcode_line(line.as_bytes(), false);
            match r {
                Ok(actions) => {
                    self.emit_line(&format!(">{line}:ok"));
                    self.pending.extend(actions);
                }
                Err(e) => self.emit_line(&format!(">{line}:error:{}", e.code())),
            }
        }
    }

    /// Stops the executor where it is and closes the trace records in progress.
    fn stop_motion(&mut self) {
        let pos = self.machine_position();
        let ids: Vec<usize> = self.records.keys().copied().collect();
        for id in ids {
            if let Some(mut r) = self.records.remove(&id)
                && r.started
            {
                r.seg.to = pos;
                r.seg.t_end = self.clock;
                self.trace.push(r.seg);
            }
        }
        self.planner.pos = pos;
        self.planner.clear(&self.settings);
    }

    /// Raises `ALARM:code`. Critical alarms (1, 2) lock everything until a reset; the others reset at once and
    /// come back alarm-locked, as `mc_reset` does in the firmware.
    fn raise_alarm(&mut self, code: u8) {
        self.stop_motion();
        self.stats.alarms += 1;
        self.emit_line(&format!("ALARM:{code}"));
        self.state = State::Alarm;
        if code == alarm::HARD_LIMIT || code == alarm::SOFT_LIMIT {
            self.emit_line("[MSG:Reset to continue]");
            self.critical = true;
        } else {
            self.soft_reset();
        }
    }

    // ----- time ------------------------------------------------------------------------------------------------

    /// Advances the virtual clock by `dt` seconds: runs the protocol loop and the motion.
    pub fn tick(&mut self, dt: f64) {
        if self.off {
            self.clock += dt;
            return;
        }
        self.process();
        let mut left = dt;
        while left > 0.0 {
            let busy = !self.planner.blocks.is_empty()
                || self.dwell_left > 0.0
                || self.idle_lock_left > 0.0
                || self.door_restore_left > 0.0
                || self.eeprom_left > 0.0;
            if !busy {
                self.clock += left;
                break;
            }
            let h = left.min(STEP_S);
            self.advance(h);
            left -= h;
            self.process();
        }
        self.process();
    }

    /// Runs until nothing is left to do or `max_s` simulated seconds have passed; returns the time used.
    pub fn run_until_idle(&mut self, max_s: f64) -> f64 {
        let t0 = self.clock;
        while self.clock - t0 < max_s {
            self.tick(0.01);
            if self.is_quiescent()
                && !matches!(self.state, State::Cycle | State::Jog | State::Homing)
            {
                break;
            }
            if self.critical || (self.state == State::Hold && self.hold_complete) {
                break;
            }
        }
        self.clock - t0
    }

    fn advance(&mut self, h: f64) {
        let t0 = self.clock;
        if self.dwell_left > 0.0 {
            self.dwell_left -= h;
        }
        if self.idle_lock_left > 0.0 {
            self.idle_lock_left -= h;
            if self.idle_lock_left <= IDLE_LOCK_EPS {
                self.idle_lock_left = 0.0;
            }
        }
        if self.eeprom_left > 0.0 {
            self.eeprom_left -= h;
        }
        let holding = matches!(self.state, State::Hold | State::Door)
            || self.jog_cancel
            || self.soft_limit_wait;
        if self.door_restore_left > 0.0 {
            self.door_restore_left -= h;
            if self.door_restore_left <= 0.0 {
                self.finish_door_restore();
            }
        }
        let had_blocks = !self.planner.blocks.is_empty();
        let ev = self.planner.step(
            h,
            holding,
            f64::from(self.feed_ovr),
            f64::from(self.rapid_ovr),
        );
        self.clock = t0 + h;
        self.handle_events(ev, t0);
        if had_blocks && self.planner.blocks.is_empty() && matches!(self.state, State::Cycle) {
            self.stats.planner_starvations += 1;
        }
        let stopped = self.planner.v <= 0.0 || self.planner.blocks.is_empty();
        // The steppers stop when the planner runs empty or a hold has braked to rest: then
        // `st_go_idle` holds them for `$1` ms in the stepper interrupt, and only after that does
        // the main loop see the cycle stop (Idle, or the hold complete).
        let stepping = !(self.planner.blocks.is_empty() || holding && stopped);
        if self.stepping && !stepping && self.state != State::Homing {
            self.idle_lock_left = self.settings.step_idle_delay_s();
        }
        self.stepping = stepping;
        if self.idle_lock_left > 0.0 {
            return;
        }
        match self.state {
            State::Cycle if self.planner.blocks.is_empty() => self.state = State::Idle,
            State::Hold | State::Door if !self.hold_complete && stopped => {
                self.hold_complete = true
            }
            State::Jog if self.planner.blocks.is_empty() => {
                self.state = State::Idle;
                self.jog_cancel = false;
            }
            State::Jog if self.jog_cancel && stopped => {
                self.stop_motion();
                self.gc.position = self.machine_position();
                self.state = State::Idle;
                self.jog_cancel = false;
            }
            State::Homing if self.planner.blocks.is_empty() => {}
            _ => {}
        }
        if self.soft_limit_wait && stopped {
            self.soft_limit_wait = false;
            self.raise_alarm(alarm::SOFT_LIMIT);
        }
    }

    fn handle_events(&mut self, ev: StepEvents, t_start: f64) {
        for (id, dt) in ev.started {
            let mut alarm_now = None;
            if let Some(r) = self.records.get_mut(&id)
                && !r.started
            {
                r.started = true;
                r.seg.t_start = t_start + dt;
                alarm_now = r.alarm.take();
            }
            if let Some(code) = alarm_now {
                self.raise_alarm(code);
                return;
            }
        }
        for (id, dt) in ev.finished {
            let done = if let Some(r) = self.records.get_mut(&id) {
                r.live = r.live.saturating_sub(1);
                r.live == 0 && r.all_queued
            } else {
                false
            };
            if done {
                self.finish_record_at(id, t_start + dt);
            }
        }
    }

    fn finish_record(&mut self, id: usize) {
        self.finish_record_at(id, self.clock);
    }

    fn finish_record_at(&mut self, id: usize, t: f64) {
        if let Some(mut r) = self.records.remove(&id)
            && r.started
        {
            r.seg.to = r.last_target;
            r.seg.t_end = t;
            self.trace.push(r.seg);
        }
    }

    // ----- protocol loop ---------------------------------------------------------------------------------------

    /// The main loop of `protocol.c`: finish the line in execution, then read and execute more lines.
    fn process(&mut self) {
        loop {
            // The stepper interrupt's `delay_ms($1)` holds the main loop too.
            if self.critical || self.state == State::Sleep || self.idle_lock_left > 0.0 {
                return;
            }
            if self.line_active || !self.pending.is_empty() {
                if !self.run_pending() {
                    return;
                }
                if self.line_active {
                    self.line_active = false;
                    if let Some(code) = self.cur_line_alarm.take() {
                        self.respond(Ok(()));
                        self.raise_alarm(code);
                        continue;
                    }
                    self.respond(Ok(()));
                    match std::mem::replace(&mut self.after_ok, AfterOk::Nothing) {
                        AfterOk::Nothing => {}
                        AfterOk::Reset => self.soft_reset(),
                        AfterOk::Sleep => {
                            self.stop_motion();
                            self.state = State::Sleep;
                            self.emit_line("[MSG:Sleeping]");
                        }
                    }
                }
                continue;
            }
            let Some(c) = self.rx.pop_front() else { return };
            if c == b'\n' || c == b'\r' {
                self.end_of_line();
            } else if self.comment_paren || self.comment_semi || self.line_overflow {
                if c == b')' && self.comment_paren {
                    self.comment_paren = false;
                }
            } else if c <= b' ' || c == b'/' {
                // Whitespace and control characters are dropped; block delete is not supported.
            } else if c == b'(' {
                self.comment_paren = true;
            } else if c == b';' {
                self.comment_semi = true;
            } else if self.line.len() >= LINE_MAX {
                self.line_overflow = true;
            } else {
                self.line.push(c.to_ascii_uppercase());
            }
        }
    }

    fn end_of_line(&mut self) {
        let mut line = std::mem::take(&mut self.line);
        let overflow = self.line_overflow;
        self.comment_paren = false;
        self.comment_semi = false;
        self.line_overflow = false;
        self.lines_received += 1;
        let n = self.lines_received;
        if self.faults.drop_digit_at_line == Some(n) {
            drop_a_digit(&mut line);
        }
        if self.faults.reset_at_line == Some(n) {
            self.soft_reset();
            return;
        }
        // The line arrived whole, so it runs; the link drops right after it (bytes still in the RX ring run too,
        // as on a controller whose USB adapter vanished).
        if self.faults.hangup_at_line == Some(n) {
            self.events.push(SimEvent::Hangup);
        }
        if let Some((at, code)) = self.faults.error_at_line
            && at == n
        {
            self.respond(Err(Status::Other(code)));
            return;
        }
        self.cur_line_no = n;
        self.cur_line_text = String::from_utf8_lossy(&line).into_owned();
        self.cur_line_alarm = match self.faults.alarm_at_line {
            Some((at, code)) if at == n => Some(code),
            _ => None,
        };
        if overflow {
            self.respond(Err(Status::Overflow));
        } else if line.is_empty() {
            self.respond(Ok(()));
        } else if line[0] == b'$' {
            match self.system_command(&line) {
                Ok(()) => {
                    self.line_active = true;
                }
                Err(e) => self.respond(Err(e)),
            }
        } else if matches!(self.state, State::Alarm | State::Jog) {
            self.respond(Err(Status::SystemGcLock));
        } else {
            match self.gcode_line(&line, false) {
                Ok(actions) => {
                    self.pending.extend(actions);
                    self.line_active = true;
                }
                Err(e) => self.respond(Err(e)),
            }
        }
    }

    fn gcode_line(&mut self, line: &[u8], jog: bool) -> Result<Vec<Action>, Status> {
        let machine_position = self.machine_position();
        let mut ctx = Context {
            gc: &mut self.gc,
            settings: &self.settings,
            persist: &mut self.persist,
            machine_position,
            check_mode: self.state == State::CheckMode,
        };
        gcode::execute(line, jog, &mut ctx)
    }

    /// Executes queued actions; false while blocked (planner full, sync, dwell, pause).
    fn run_pending(&mut self) -> bool {
        let check = self.state == State::CheckMode;
        loop {
            if self.critical || self.soft_limit_wait {
                return false;
            }
            if let Some(mut am) = self.active_motion.take() {
                while am.next < am.cmd.moves.len() {
                    let mv = am.cmd.moves[am.next].clone();
                    if self.settings.soft_limits && !mv.jog && self.outside_travel(&mv.target) {
                        self.active_motion = None;
                        self.pending.clear();
                        self.close_record(am.record);
                        if !check && !self.planner.blocks.is_empty() && self.state == State::Cycle {
                            self.soft_limit_wait = true;
                            self.state = State::Hold;
                            self.hold_complete = false;
                        } else {
                            self.raise_alarm(alarm::SOFT_LIMIT);
                        }
                        return false;
                    }
                    if check {
                        am.next += 1;
                        continue;
                    }
                    if self.planner.is_full() {
                        self.active_motion = Some(am);
                        return false;
                    }
                    let queued = self.planner.push(
                        mv.target,
                        mv.rapid,
                        mv.feed,
                        mv.inverse_time,
                        mv.jog,
                        am.record,
                        &self.settings,
                        f64::from(self.feed_ovr),
                        f64::from(self.rapid_ovr),
                    );
                    am.next += 1;
                    if queued {
                        let back = self.planner.blocks.back().map(|b| (b.start, b.target));
                        if let (Some(r), Some((start, target))) =
                            (self.records.get_mut(&am.record), back)
                        {
                            if r.live == 0 && !r.started && r.seg.from == [f64::MAX; 3] {
                                r.seg.from = start;
                            }
                            r.last_target = target;
                            r.live += 1;
                        }
                        self.stats.max_planner_fill =
                            self.stats.max_planner_fill.max(self.planner.blocks.len());
                        match self.state {
                            State::Idle => {
                                self.state = if mv.jog { State::Jog } else { State::Cycle };
                            }
                            State::Hold if self.hold_complete && self.planner.blocks.len() == 1 => {
                            }
                            _ => {}
                        }
                        if self.instant {
                            let t = self.clock;
                            let ev = self.planner.complete_all();
                            self.handle_events(ev, t);
                            if self.critical || self.state == State::Alarm {
                                return false;
                            }
                            if matches!(self.state, State::Cycle | State::Jog) {
                                self.state = State::Idle;
                            }
                        }
                    }
                }
                self.close_record(am.record);
                continue;
            }
            let Some(action) = self.pending.pop_front() else {
                return true;
            };
            match action {
                Action::Sync => {
                    if !self.planner.blocks.is_empty()
                        || self.dwell_left > 0.0
                        || self.eeprom_left > 0.0
                    {
                        self.pending.push_front(Action::Sync);
                        return false;
                    }
                }
                Action::Motion(cmd) => {
                    let record = self.open_record(&cmd);
                    self.active_motion = Some(ActiveMotion {
                        cmd,
                        next: 0,
                        record,
                    });
                }
                Action::Dwell(p) => {
                    if !check {
                        self.dwell_left = dwell_seconds(p);
                        self.pending.push_front(Action::Sync);
                        return false;
                    }
                }
                Action::Spindle(dir, speed) => {
                    if !check {
                        self.spindle_out = dir;
                        self.spindle_speed_out = if dir == Spindle::Off { 0.0 } else { speed };
                        self.ovr_counter = 0;
                    }
                }
                Action::Coolant(flood, mist) => {
                    if !check {
                        self.flood_out = flood;
                        self.mist_out = mist;
                        self.ovr_counter = 0;
                    }
                }
                Action::Pause => {
                    if !check {
                        self.m0_pause = true;
                        self.state = State::Hold;
                        self.hold_complete = true;
                        self.pending.push_front(Action::WaitResume);
                        return false;
                    }
                }
                Action::Message(m) => self.emit_line(&format!("[MSG:{m}]")),
                Action::WaitResume => {
                    if self.m0_pause {
                        self.pending.push_front(Action::WaitResume);
                        return false;
                    }
                }
                Action::EepromWrite(n) => {
                    self.eeprom_total = f64::from(n) * EEPROM_BYTE_S;
                    self.eeprom_left = self.eeprom_total;
                    self.eeprom_slot = -1;
                    self.pending.push_front(Action::Sync);
                    return false;
                }
                Action::RestoreOverrides => {
                    if (self.feed_ovr, self.rapid_ovr, self.spindle_ovr) != (100, 100, 100) {
                        (self.feed_ovr, self.rapid_ovr, self.spindle_ovr) = (100, 100, 100);
                        self.ovr_counter = 0;
                    }
                }
                Action::HomingDone => {
                    if self.state == State::Homing {
                        self.state = State::Idle;
                    }
                }
                Action::WcoChanged => self.wco_counter = 0,
                Action::ProbeEnd(k) => {
                    if !self.planner.blocks.is_empty() {
                        self.pending.push_front(Action::ProbeEnd(k));
                        return false;
                    }
                    if check {
                        continue;
                    }
                    // No probe input is wired in the simulation: the move never touches.
                    self.probe_pos = self.machine_position();
                    if k == 2 || k == 4 {
                        self.respond(Ok(()));
                        self.line_active = false;
                        self.raise_alarm(5);
                        return false;
                    }
                    let p = axes(self.probe_pos, false);
                    self.emit_line(&format!("[PRB:{p}:0]"));
                }
            }
        }
    }

    fn outside_travel(&self, target: &[f64; N_AXIS]) -> bool {
        // `system_check_travel_limits`: the machine space is [-max_travel, 0] on every axis.
        (0..N_AXIS).any(|i| target[i] > 0.0 || target[i] < -self.settings.max_travel[i])
    }

    fn open_record(&mut self, cmd: &MotionCmd) -> usize {
        let id = self.next_record;
        self.next_record += 1;
        let laser = self.settings.laser_mode;
        let spindle_on = self.gc.spindle != Spindle::Off && self.gc.spindle_speed > 0.0;
        let power = if cmd.laser_off || self.gc.spindle == Spindle::Off {
            0.0
        } else {
            self.gc.spindle_speed * f64::from(self.spindle_ovr) / 100.0
        };
        let wco_z = self.gc.wco()[2];
        let start_z = self.planner.position_mm(&self.settings)[2] - wco_z;
        let end_z = cmd.moves.last().map_or(start_z + wco_z, |m| m.target[2]) - wco_z;
        let pen_down = !laser && start_z < 0.0 && end_z < 0.0;
        let tool_on = (spindle_on && !cmd.laser_off) || pen_down;
        let alarm = if cmd.moves.is_empty() {
            None
        } else {
            self.cur_line_alarm.take()
        };
        self.records.insert(
            id,
            Record {
                seg: TraceSegment {
                    line: self.cur_line_no,
                    text: self.cur_line_text.clone(),
                    motion: cmd.name.clone(),
                    from: [f64::MAX; 3],
                    to: [0.0; 3],
                    arc_center: cmd.arc_center,
                    feed: cmd.feed,
                    tool_on,
                    power,
                    t_start: 0.0,
                    t_end: 0.0,
                },
                started: false,
                live: 0,
                all_queued: false,
                alarm,
                last_target: [0.0; N_AXIS],
            },
        );
        id
    }

    fn close_record(&mut self, id: usize) {
        let finish = match self.records.get_mut(&id) {
            Some(r) => {
                r.all_queued = true;
                if r.live == 0
                    && let Some(code) = r.alarm.take()
                {
                    self.cur_line_alarm = Some(code);
                }
                r.live == 0
            }
            None => false,
        };
        if finish {
            self.finish_record(id);
        }
    }

    // ----- `$` commands ----------------------------------------------------------------------------------------

    /// `system_execute_line`. Ok(()) means the `ok` is due once pending actions finish.
    fn system_command(&mut self, line: &[u8]) -> Result<(), Status> {
        let c1 = line.get(1).copied().unwrap_or(0);
        let c2 = line.get(2).copied().unwrap_or(0);
        match c1 {
            0 => {
                self.emit_line(
                    "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]",
                );
                Ok(())
            }
            b'J' => {
                if !matches!(self.state, State::Idle | State::Jog) {
                    return Err(Status::IdleError);
                }
                if c2 != b'=' {
                    return Err(Status::InvalidStatement);
                }
                let actions = self.gcode_line(&line[3..], true)?;
                if self.settings.soft_limits {
                    for a in &actions {
                        if let Action::Motion(m) = a
                            && m.moves.iter().any(|mv| self.outside_travel(&mv.target))
                        {
                            // Undo the parser position update: the jog is refused.
                            self.gc.position = self.planner.position_mm(&self.settings);
                            return Err(Status::TravelExceeded);
                        }
                    }
                }
                self.pending.extend(actions);
                Ok(())
            }
            b'$' | b'G' | b'C' | b'X' => {
                if c2 != 0 {
                    return Err(Status::InvalidStatement);
                }
                match c1 {
                    b'$' => {
                        if matches!(self.state, State::Cycle | State::Hold) {
                            return Err(Status::IdleError);
                        }
                        let l = self.settings.listing();
                        self.emit(&l);
                    }
                    b'G' => {
                        let r = self.gc.report(self.settings.report_inches);
                        self.emit_line(&r);
                    }
                    b'C' => {
                        if self.state == State::CheckMode {
                            self.emit_line("[MSG:Disabled]");
                            self.after_ok = AfterOk::Reset;
                        } else {
                            if self.state != State::Idle {
                                return Err(Status::IdleError);
                            }
                            self.state = State::CheckMode;
                            self.emit_line("[MSG:Enabled]");
                        }
                    }
                    _ => {
                        if self.state == State::Alarm {
                            self.emit_line("[MSG:Caution: Unlocked]");
                            self.state = State::Idle;
                        }
                    }
                }
                Ok(())
            }
            _ => {
                if !matches!(self.state, State::Idle | State::Alarm) {
                    return Err(Status::IdleError);
                }
                match c1 {
                    b'#' => {
                        if c2 != 0 {
                            return Err(Status::InvalidStatement);
                        }
                        self.report_ngc();
                        Ok(())
                    }
                    b'H' => {
                        if !self.settings.homing {
                            return Err(Status::SettingDisabled);
                        }
                        if c2 != 0 {
                            return Err(Status::InvalidStatement);
                        }
                        self.home();
                        Ok(())
                    }
                    b'S' => {
                        if &line[1..] != b"SLP" {
                            return Err(Status::InvalidStatement);
                        }
                        self.after_ok = AfterOk::Sleep;
                        Ok(())
                    }
                    b'I' => {
                        if c2 == 0 {
                            let s = format!("[VER:{BUILD}:{}]", self.build_info);
                            self.emit_line(&s);
                            self.emit_line(&format!("[OPT:V,{PLANNER_BLOCKS},{RX_BUFFER_SIZE}]"));
                            Ok(())
                        } else if c2 == b'=' {
                            self.build_info = String::from_utf8_lossy(&line[3..]).into_owned();
                            self.pending
                                .push_back(Action::EepromWrite(line.len() as u32 - 2));
                            Ok(())
                        } else {
                            Err(Status::InvalidStatement)
                        }
                    }
                    b'R' => {
                        if line.len() != 6 || &line[1..5] != b"RST=" {
                            return Err(Status::InvalidStatement);
                        }
                        let old_listing = self.settings.listing();
                        match line[5] {
                            b'$' => self.settings = Settings::default(),
                            b'#' => self.persist.coord = Default::default(),
                            b'*' => {
                                self.settings = Settings::default();
                                self.persist = Persist::default();
                            }
                            _ => return Err(Status::InvalidStatement),
                        }
                        // Charge the changed settings and records (all of them when everything differs).
                        let changed = old_listing
                            .lines()
                            .zip(self.settings.listing().lines())
                            .filter(|(a, b)| a != b)
                            .count() as u32;
                        let records = if line[5] == b'$' {
                            0
                        } else {
                            8 * gcode::COORD_RECORD_BYTES
                        };
                        self.pending.push_back(Action::EepromWrite(
                            changed * SETTING_WRITE_BYTES + records + 1,
                        ));
                        self.emit_line("[MSG:Restoring defaults]");
                        self.after_ok = AfterOk::Reset;
                        Ok(())
                    }
                    b'N' if c2 == 0 => {
                        for i in 0..2 {
                            let s = format!("$N{i}={}", self.persist.startup[i]);
                            self.emit_line(&s);
                        }
                        Ok(())
                    }
                    _ => {
                        let mut pos = 1;
                        let startup = c1 == b'N';
                        if startup {
                            if self.state != State::Idle {
                                return Err(Status::IdleError);
                            }
                            pos = 2;
                        }
                        let parameter =
                            gcode::read_float(line, &mut pos).ok_or(Status::BadNumberFormat)?;
                        if line.get(pos) != Some(&b'=') {
                            return Err(Status::InvalidStatement);
                        }
                        pos += 1;
                        if startup {
                            let idx = parameter.trunc();
                            if !(0.0..2.0).contains(&idx) {
                                return Err(Status::InvalidStatement);
                            }
                            let text = line[pos..].to_vec();
                            // The firmware executes the block to validate it before storing it.
                            let actions = self.gcode_line(&text, false)?;
                            self.persist.startup[idx as usize] =
                                String::from_utf8_lossy(&text).into_owned();
                            self.pending.extend(actions);
                            self.pending
                                .push_back(Action::EepromWrite(text.len() as u32 + 1));
                            return Ok(());
                        }
                        let value =
                            gcode::read_float(line, &mut pos).ok_or(Status::BadNumberFormat)?;
                        if pos != line.len() || parameter > 255.0 {
                            return Err(Status::InvalidStatement);
                        }
                        self.settings.store(parameter.trunc() as u32, value)?;
                        self.pending
                            .push_back(Action::EepromWrite(SETTING_WRITE_BYTES));
                        Ok(())
                    }
                }
            }
        }
    }

    fn report_ngc(&mut self) {
        for i in 0..6 {
            let s = format!("[G{}:{}]", 54 + i, axes(self.persist.coord[i], false));
            self.emit_line(&s);
        }
        let s = format!("[G28:{}]", axes(self.persist.g28, false));
        self.emit_line(&s);
        let s = format!("[G30:{}]", axes(self.persist.g30, false));
        self.emit_line(&s);
        let s = format!("[G92:{}]", axes(self.gc.coord_offset, false));
        self.emit_line(&s);
        let s = format!("[TLO:{}]", fmt_float(self.gc.tool_length_offset, 3));
        self.emit_line(&s);
        let s = format!("[PRB:{}:0]", axes(self.probe_pos, false));
        self.emit_line(&s);
    }

    /// Simulated homing: the switches sit at machine 0 (or at -travel for axes whose `$23` bit is set); Z homes
    /// first, then X and Y together, at the seek rate, then pull off by `$27`.
    fn home(&mut self) {
        self.state = State::Homing;
        let cur = self.planner.position_mm(&self.settings);
        let mut switch = [0.0; N_AXIS];
        let mut done = [0.0; N_AXIS];
        for i in 0..N_AXIS {
            let inverted = self.settings.homing_dir_mask & (1 << i) != 0;
            switch[i] = if inverted {
                -self.settings.max_travel[i]
            } else {
                0.0
            };
            done[i] = if inverted {
                switch[i] + self.settings.homing_pulloff
            } else {
                -self.settings.homing_pulloff
            };
        }
        let z_first = [cur[0], cur[1], switch[2]];
        let xy = switch;
        let seek = self.settings.homing_seek;
        let feed = self.settings.homing_feed;
        let mv = |target, f| gcode::LineMove {
            target,
            rapid: false,
            feed: f,
            inverse_time: false,
            jog: true,
        };
        let cmd = MotionCmd {
            name: "HOME".into(),
            moves: vec![mv(z_first, seek), mv(xy, seek), mv(done, feed)],
            arc_center: None,
            feed: seek,
            laser_off: true,
        };
        self.pending.push_back(Action::Motion(cmd));
        self.pending.push_back(Action::Sync);
        self.pending.push_back(Action::HomingDone);
        self.gc.position = done;
    }
}

/// True for the bytes GRBL's RX interrupt takes out as realtime commands (or throws away).
pub fn is_realtime(b: u8) -> bool {
    matches!(b, b'?' | b'!' | b'~' | 0x18) || b > 0x7f
}

/// The sans-IO core under its other common name.
pub type Machine = Grbl;

/// The fault `drop_digit_at_line`: removes the first digit after the line's first decimal point, else its last
/// digit.
fn drop_a_digit(line: &mut Vec<u8>) {
    let after_point = line.iter().position(|&c| c == b'.').and_then(|p| {
        line.get(p + 1)
            .filter(|c| c.is_ascii_digit())
            .map(|_| p + 1)
    });
    if let Some(k) = after_point.or_else(|| line.iter().rposition(u8::is_ascii_digit)) {
        line.remove(k);
    }
}
