//! Evidence that the controller is where the journal left it. A stop records what the
//! controller said once it stood still (machine position, `$#` offsets, `$G` parser state: a
//! [`StopRecord`]); a resume compares it with what the controller says before this sender
//! touches it. A power cycle or a hand reset while nothing was connected leaves no banner for
//! the next connection to see, but it zeroes the machine position and clears G92: only this
//! comparison notices it.

use super::frame::{self, Frame};
use super::session::Session;
use crate::journal::StopRecord;
use crate::transport::Transport;
use std::time::Duration;

/// The G and M words of a `[GC:...]` parser state, in order (feed, speed and tool number are
/// values, not state a reset or power cycle would change back).
pub(super) fn modal_words(gc: &str) -> String {
    gc.trim_start_matches("GC:")
        .split_whitespace()
        .filter(|w| w.starts_with('G') || w.starts_with('M'))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Reads where the controller stands now, in its frame, with its parser state: a status
/// report, `$#` and `$G`. `None` when it does not answer them (in motion, or silent).
pub(super) fn read<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    timeout: Duration,
) -> Option<StopRecord> {
    sess.query_status(timeout).ok()??;
    let f = frame::read(sess, timeout).ok()?.ok()?;
    record(sess, &f)
}

/// The record of where the controller stands, from its last status report, the frame `f` read
/// just after it (in the controller's report units) and the parser state `$G` gave with it.
pub(super) fn record<T: Transport + ?Sized>(
    sess: &Session<'_, T>,
    f: &Frame,
) -> Option<StopRecord> {
    let st = sess.status.as_ref()?;
    let modal = modal_words(sess.last_gc.as_deref()?);
    let machine = match st.mpos {
        Some(m) => m,
        None => {
            // `$10` reports the work position: add the offsets `$#` just gave, not a `WCO:`
            // that may be many reports old.
            let (w, o) = (st.wpos?, f.origin_of(f.wcs));
            [0, 1, 2].map(|a| w[a] + o[a] + f.g92[a])
        }
    };
    let k = if sess.report_inches { 25.4 } else { 1.0 };
    let f = f.in_mm(sess.report_inches);
    Some(StopRecord {
        machine: machine.map(|v| v * k),
        wcs: f.wcs,
        g92: f.g92,
        tlo: f.tlo,
        modal,
    })
}

fn xyz(p: [f64; 3]) -> String {
    format!("X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2])
}

fn far(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).any(|i| (a[i] - b[i]).abs() > tol)
}

/// Why the controller found (`found`) is not known to be where the journal's stop record
/// (`stop`) left it, if it is not: a machine position, coordinate system, offset or parser
/// state that differs by more than `tol` (mm), or positions that agree only by both being
/// exactly machine zero on a machine that does not home (`homes`: `$22=1`), which is where
/// every power-up counts from. `None` when they agree, or when there is nothing to compare.
pub(super) fn disagreement(
    stop: Option<&StopRecord>,
    found: Option<&StopRecord>,
    homes: bool,
    tol: f64,
) -> Option<String> {
    let (s, f) = (stop?, found?);
    if far(s.machine, f.machine, tol) {
        return Some(format!(
            "the controller's machine position {} is not where the job stopped ({}, journal): it lost power or was reset or moved since",
            xyz(f.machine),
            xyz(s.machine)
        ));
    }
    if !homes && s.machine == [0.0; 3] && f.machine == [0.0; 3] {
        return Some(
            "the controller reports machine position X0 Y0 Z0, as after a power-up, and so does the journal's stop record: on a machine that does not home that proves nothing".into(),
        );
    }
    if s.wcs != f.wcs {
        return Some(format!(
            "the controller is in G{}, the job stopped in G{} (journal)",
            f.wcs, s.wcs
        ));
    }
    if far(s.g92, f.g92, tol) || (s.tlo - f.tlo).abs() > tol {
        return Some(format!(
            "the controller's G92 offset {} and tool length offset {:.3} are not the ones the job stopped with ({}, {:.3}, journal)",
            xyz(f.g92),
            f.tlo,
            xyz(s.g92),
            s.tlo
        ));
    }
    if s.modal != f.modal {
        return Some(format!(
            "the controller's parser state `{}` is not the one the job stopped with (`{}`, journal)",
            f.modal, s.modal
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(machine: [f64; 3]) -> StopRecord {
        StopRecord {
            machine,
            wcs: 54,
            g92: [0.0; 3],
            tlo: 0.0,
            modal: "G0 G54 G17 G21 G90 G94 M5 M9".into(),
        }
    }

    #[test]
    fn the_same_controller_agrees_and_a_power_cycle_does_not() {
        let stop = rec([11.244, 10.416, 3.0]);
        assert_eq!(disagreement(Some(&stop), Some(&stop), false, 0.003), None);
        let moved = rec([11.246, 10.416, 3.0]);
        assert_eq!(disagreement(Some(&stop), Some(&moved), false, 0.003), None);
        let why = disagreement(Some(&stop), Some(&rec([0.0; 3])), false, 0.003).unwrap();
        assert!(why.contains("X0.000 Y0.000 Z0.000"), "{why}");
        assert!(why.contains("X11.244 Y10.416 Z3.000"), "{why}");
        assert_eq!(disagreement(None, Some(&stop), false, 0.003), None);
    }

    #[test]
    fn both_at_machine_zero_is_unknown_unless_the_machine_homes() {
        let zero = rec([0.0; 3]);
        assert!(disagreement(Some(&zero), Some(&zero), false, 0.003).is_some());
        assert_eq!(disagreement(Some(&zero), Some(&zero), true, 0.003), None);
    }

    #[test]
    fn offsets_and_parser_state_count() {
        let stop = rec([1.0, 2.0, 3.0]);
        let mut f = stop.clone();
        f.g92 = [5.0, 0.0, 0.0];
        assert!(
            disagreement(Some(&stop), Some(&f), false, 0.003)
                .unwrap()
                .contains("G92")
        );
        let mut f = stop.clone();
        f.wcs = 55;
        assert!(
            disagreement(Some(&stop), Some(&f), false, 0.003)
                .unwrap()
                .contains("G55")
        );
        let mut f = stop.clone();
        f.modal = "G0 G54 G17 G20 G90 G94 M5 M9".into();
        assert!(
            disagreement(Some(&stop), Some(&f), false, 0.003)
                .unwrap()
                .contains("G20")
        );
        assert_eq!(
            modal_words("GC:G1 G54 G17 G21 G90 G94 M5 M9 T0 F500 S0"),
            "G1 G54 G17 G21 G90 G94 M5 M9"
        );
    }
}
