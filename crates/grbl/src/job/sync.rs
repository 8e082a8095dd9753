//! Lines GRBL answers only after every motion before them has finished: the ones whose
//! execution starts with `protocol_buffer_synchronize`. Their `ok` proves that the lines before
//! them ran, which the sender's books use to confirm them.

use super::modal::Spindle;
use super::parse::words;
use super::{Job, LineKind};

impl Job {
    /// Whether GRBL 1.1h answers line `index` only once every motion queued before it has
    /// finished (and the line itself has executed): a dwell (`G4`, `mc_dwell`), a program pause or
    /// end (`M0`, `M2`, `M30`), a spindle or laser switched on, off or reversed (`spindle_sync`,
    /// in laser mode too), a new speed while the spindle runs (unless in laser mode on a line that
    /// moves: `$32=1` changes the power in the motion instead), a coolant change
    /// (`coolant_sync`). Conservative: a line not listed may sync too (a `G10` written to
    /// EEPROM), but one listed always does. `M1` does not (GRBL 1.1h ignores it).
    pub fn answer_waits_for_motion(&self, index: usize, laser_mode: bool) -> bool {
        let Some(line) = self.lines.get(index) else {
            return false;
        };
        if line.kind != LineKind::Gcode {
            return false;
        }
        let before = &line.before;
        let after = self.state_before(index + 1);
        let ws = words(&line.text).unwrap_or_default();
        let dwell = ws
            .iter()
            .any(|w| w.0 == 'G' && (w.1 * 10.0).round() as i64 == 40);
        let flow = ws
            .iter()
            .any(|w| w.0 == 'M' && matches!(w.1.round() as i64, 0 | 2 | 30) && w.1.fract() == 0.0);
        let spindle_state = before.spindle != after.spindle;
        let speed = before.spindle != Spindle::Off
            && before.speed != after.speed
            && !(laser_mode && line.moves);
        let coolant = before.mist != after.mist || before.flood != after.flood;
        dwell || flow || spindle_state || speed || coolant
    }
}

#[cfg(test)]
mod tests {
    use crate::job::Job;

    #[test]
    fn dwells_program_flow_spindle_and_coolant_changes_wait_for_motion() {
        let job = Job::parse(
            "G21 G90\nG1 X10 F600\nM3 S1000\nG1 X20\nS500\nG4 P0.1\nG1 X30 S200\nM8\nM1\nM5\nM0\nG1 X0\nM2\n",
        )
        .unwrap();
        let waits: Vec<&str> = (0..job.len())
            .filter(|&i| job.answer_waits_for_motion(i, false))
            .map(|i| job.lines[i].text.as_str())
            .collect();
        assert_eq!(
            waits,
            [
                "M3S1000",
                "S500",
                "G4P0.1",
                "G1X30S200",
                "M8",
                "M5",
                "M0",
                "M2"
            ]
        );
        // Laser mode: a new power on a moving line is part of the motion, not a sync.
        assert!(!job.answer_waits_for_motion(6, true));
        assert!(job.answer_waits_for_motion(4, true));
    }
}
