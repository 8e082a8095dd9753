//! GRBL 1.1h status (`error:N`) and alarm (`ALARM:N`) codes, numbered as in `report.h` and `system.h`.

/// A status code answered to a line: `error:N` (`grbl/report.h:24-61`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Status {
    /// 1: a word did not start with a letter (e.g. `%`).
    ExpectedCommandLetter,
    /// 2: missing or malformed number.
    BadNumberFormat,
    /// 3: `$` statement not understood.
    InvalidStatement,
    /// 4: negative value where it is not allowed.
    NegativeValue,
    /// 5: setting disabled (e.g. `$H` with `$22=0`).
    SettingDisabled,
    /// 6: step pulse under 3 µs.
    SettingStepPulseMin,
    /// 8: `$` command needs IDLE.
    IdleError,
    /// 9: G-code locked out in ALARM or JOG.
    SystemGcLock,
    /// 10: soft limits need homing.
    SoftLimitError,
    /// 11: line longer than 79 characters.
    Overflow,
    /// 12: step rate above 30 kHz.
    MaxStepRateExceeded,
    /// 15: jog target exceeds travel.
    TravelExceeded,
    /// 16: invalid jog command.
    InvalidJogCommand,
    /// 20: unsupported or invalid g-code command.
    UnsupportedCommand,
    /// 21: two commands of one modal group.
    ModalGroupViolation,
    /// 22: feed rate undefined.
    UndefinedFeedRate,
    /// 23: command needs an integer value.
    CommandValueNotInteger,
    /// 24: two commands that both use axis words.
    AxisCommandConflict,
    /// 25: a word repeated in the block.
    WordRepeated,
    /// 26: command needs axis words.
    NoAxisWords,
    /// 27: line number out of range.
    InvalidLineNumber,
    /// 28: a required P or L value is missing.
    ValueWordMissing,
    /// 29: unsupported work coordinate system.
    UnsupportedCoordSys,
    /// 30: G53 needs G0 or G1.
    G53InvalidMotionMode,
    /// 31: axis words with G80.
    AxisWordsExist,
    /// 32: arc without axis words in the plane.
    NoAxisWordsInPlane,
    /// 33: invalid motion target.
    InvalidTarget,
    /// 34: arc radius error.
    ArcRadiusError,
    /// 35: arc without IJK offset in the plane.
    NoOffsetsInPlane,
    /// 36: words left unused by the block.
    UnusedWords,
    /// 37: G43.1 offset not on the tool-length axis.
    G43DynamicAxisError,
    /// 38: tool number above 255.
    MaxValueExceeded,
    /// Any other code (used by fault injection).
    Other(u8),
}

impl Status {
    /// The number printed after `error:`.
    pub fn code(self) -> u8 {
        use Status::*;
        match self {
            ExpectedCommandLetter => 1,
            BadNumberFormat => 2,
            InvalidStatement => 3,
            NegativeValue => 4,
            SettingDisabled => 5,
            SettingStepPulseMin => 6,
            IdleError => 8,
            SystemGcLock => 9,
            SoftLimitError => 10,
            Overflow => 11,
            MaxStepRateExceeded => 12,
            TravelExceeded => 15,
            InvalidJogCommand => 16,
            UnsupportedCommand => 20,
            ModalGroupViolation => 21,
            UndefinedFeedRate => 22,
            CommandValueNotInteger => 23,
            AxisCommandConflict => 24,
            WordRepeated => 25,
            NoAxisWords => 26,
            InvalidLineNumber => 27,
            ValueWordMissing => 28,
            UnsupportedCoordSys => 29,
            G53InvalidMotionMode => 30,
            AxisWordsExist => 31,
            NoAxisWordsInPlane => 32,
            InvalidTarget => 33,
            ArcRadiusError => 34,
            NoOffsetsInPlane => 35,
            UnusedWords => 36,
            G43DynamicAxisError => 37,
            MaxValueExceeded => 38,
            Other(n) => n,
        }
    }
}

/// Alarm codes sent as `ALARM:N` (`grbl/system.h:41-50`).
pub mod alarm {
    /// Hard limit triggered; position lost.
    pub const HARD_LIMIT: u8 = 1;
    /// Soft limit: target exceeds the travel; position kept.
    pub const SOFT_LIMIT: u8 = 2;
    /// Reset while in motion; position lost.
    pub const ABORT_CYCLE: u8 = 3;
    /// Reset during homing.
    pub const HOMING_FAIL_RESET: u8 = 6;
}
