//! The interpreter's modal state (units, distance mode, motion mode, plane, work coordinate
//! system, feed, spindle, coolant) and the program position, as it stands before each line.

use serde::{Deserialize, Serialize};

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
