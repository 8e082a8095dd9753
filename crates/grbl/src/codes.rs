//! GRBL 1.1h error and alarm code tables (meanings from `doc/csv/error_codes_en_US.csv` and
//! `doc/csv/alarm_codes_en_US.csv` of gnea/grbl 1.1h), so messages can name what went wrong.

/// Meaning of `error:N` as documented for GRBL 1.1h; `None` for a code GRBL 1.1h does not define.
pub fn error_meaning(code: u8) -> Option<&'static str> {
    Some(match code {
        1 => "G-code words consist of a letter and a value; letter was not found",
        2 => "missing the expected G-code word value or numeric value format is not valid",
        3 => "Grbl '$' system command was not recognized or supported",
        4 => "negative value received for an expected positive value",
        5 => "homing cycle failure: homing is not enabled via settings ($22)",
        6 => "minimum step pulse time must be greater than 3 microseconds",
        7 => "an EEPROM read failed; auto-restoring affected EEPROM to default values",
        8 => "Grbl '$' command cannot be used unless Grbl is IDLE",
        9 => "G-code commands are locked out during alarm or jog state",
        10 => "soft limits cannot be enabled without homing also enabled",
        11 => "max characters per line exceeded; received command line was not executed",
        12 => "Grbl '$' setting value causes the step rate to exceed the maximum supported",
        13 => "safety door detected as opened and door state initiated",
        14 => "build info or startup line exceeded EEPROM line length limit; line not stored",
        15 => "jog target exceeds machine travel; jog command has been ignored",
        16 => "jog command has no '=' or contains prohibited g-code",
        17 => "laser mode requires PWM output",
        20 => "unsupported or invalid g-code command found in block",
        21 => "more than one g-code command from same modal group found in block",
        22 => "feed rate has not yet been set or is undefined",
        23 => "g-code command in block requires an integer value",
        24 => "more than one g-code command that requires axis words found in block",
        25 => "repeated g-code word found in block",
        26 => {
            "no axis words found in block for g-code command or current modal state which requires them"
        }
        27 => "line number value is invalid",
        28 => "g-code command is missing a required value word",
        29 => "G59.x work coordinate systems are not supported",
        30 => "G53 only allowed with G0 and G1 motion modes",
        31 => "axis words found in block when no command or current modal state uses them",
        32 => "G2 and G3 arcs require at least one in-plane axis word",
        33 => "motion command target is invalid",
        34 => "arc radius value is invalid",
        35 => "G2 and G3 arcs require at least one in-plane offset word",
        36 => "unused value words found in block",
        37 => "G43.1 dynamic tool length offset is not assigned to configured tool length axis",
        38 => "tool number greater than max supported value",
        _ => return None,
    })
}

/// Meaning of `ALARM:N` as documented for GRBL 1.1h; `None` for a code GRBL 1.1h does not define.
pub fn alarm_meaning(code: u8) -> Option<&'static str> {
    Some(match code {
        1 => {
            "hard limit triggered; machine position is likely lost, re-homing is highly recommended"
        }
        2 => {
            "soft limit alarm: G-code motion target exceeds machine travel; machine position retained"
        }
        3 => {
            "reset while in motion; machine position is likely lost, re-homing is highly recommended"
        }
        4 => {
            "probe fail: the probe is not in the expected initial state before starting the probe cycle"
        }
        5 => "probe fail: the probe did not contact the workpiece within the programmed travel",
        6 => "homing fail: reset during active homing cycle",
        7 => "homing fail: safety door was opened during active homing cycle",
        8 => "homing fail: cycle failed to clear limit switch when pulling off",
        9 => "homing fail: could not find limit switch within search distance",
        10 => "homing fail: on dual axis machines, could not find the second limit switch",
        _ => return None,
    })
}

/// Whether an alarm is critical: GRBL then blocks everything (status reports included) until a
/// soft reset (ALARM:1 hard limit, ALARM:2 soft limit; `grbl/protocol.c:218-237`).
pub fn alarm_is_critical(code: u8) -> bool {
    matches!(code, 1 | 2)
}

/// Display helper: "error:N (meaning)" with a fallback for undefined codes.
pub fn describe_error(code: u8) -> String {
    match error_meaning(code) {
        Some(m) => format!("error:{code} ({m})"),
        None => format!("error:{code} (not a GRBL 1.1h error code)"),
    }
}

/// Display helper: "ALARM:N (meaning)" with a fallback for undefined codes.
pub fn describe_alarm(code: u8) -> String {
    match alarm_meaning(code) {
        Some(m) => format!("ALARM:{code} ({m})"),
        None => format!("ALARM:{code} (not a GRBL 1.1h alarm code)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_documented_code_has_a_meaning_and_gaps_are_none() {
        let defined: Vec<u8> = (0..=60).filter(|&c| error_meaning(c).is_some()).collect();
        let expected: Vec<u8> = (1..=17).chain(20..=38).collect();
        assert_eq!(defined, expected);
        let alarms: Vec<u8> = (0..=20).filter(|&c| alarm_meaning(c).is_some()).collect();
        assert_eq!(alarms, (1..=10).collect::<Vec<u8>>());
    }

    #[test]
    fn descriptions_name_the_code() {
        assert!(describe_error(22).starts_with("error:22 (feed rate"));
        assert!(describe_error(19).contains("not a GRBL"));
        assert!(describe_alarm(2).contains("soft limit"));
        assert!(alarm_is_critical(1) && alarm_is_critical(2) && !alarm_is_critical(3));
    }
}
