//! Arcs as GRBL reads them: the centre from `I J K` or from `R` (`gcode.c`), then the chords
//! `mc_arc` splits them into.

use super::modal::{ModalState, MotionMode};
use flatcut_motion::arc_chords;

/// Points along an arc (endpoints included), split into chords the way GRBL's `mc_arc` does
/// (segments = angle·r / sqrt(tol·(2r − tol))). Falls back to the straight chord for an invalid
/// arc (GRBL would reject it with error:33/34; check mode reports that).
pub(super) fn arc_points(
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
