//! Arcs as GRBL reads them: the centre from `I J K` or from `R` (`gcode.c`), then the chords
//! `mc_arc` splits them into.

use super::modal::{ModalState, MotionMode};
use flatcut_motion::{ArcChords, mc_arc};

/// An arc split into chords the way GRBL's `mc_arc` does (segments = |½·angle·r| /
/// √(tol·(2r − tol)), floored), with the radius GRBL's parser hands it: `hypot(I, J)`, or `|R|`.
/// Falls back to the straight chord for an invalid arc (GRBL would reject it with error:33/34;
/// check mode reports that).
pub(super) fn arc_points(
    st: &ModalState,
    start: [f64; 3],
    target: [f64; 3],
    ijk: [Option<f64>; 3],
    r_word: Option<f64>,
    tol: f64,
) -> ArcChords {
    let straight = ArcChords {
        points: vec![start, target],
        segments: 0,
    };
    let (a0, a1, lin) = match st.plane {
        18 => (2, 0, 1),
        19 => (1, 2, 0),
        _ => (0, 1, 2),
    };
    let cw = st.motion == MotionMode::ArcCw;
    let (sx, sy) = (start[a0], start[a1]);
    let (tx, ty) = (target[a0], target[a1]);
    let ((cx, cy), radius) = if let Some(r) = r_word {
        // GRBL gcode.c: centre from radius; negative R = the long way round.
        let (x, y) = (tx - sx, ty - sy);
        let d2 = x * x + y * y;
        let h2 = 4.0 * r * r - d2;
        if d2 <= 0.0 || h2 < 0.0 {
            return straight;
        }
        let mut h = -h2.sqrt() / d2.sqrt();
        if !cw {
            h = -h;
        }
        if r < 0.0 {
            h = -h;
        }
        ((sx + 0.5 * (x - y * h), sy + 0.5 * (y + x * h)), r.abs())
    } else {
        let (i, j) = (ijk[a0].unwrap_or(0.0), ijk[a1].unwrap_or(0.0));
        ((sx + i, sy + j), i.hypot(j))
    };
    let offset = [cx - sx, cy - sy];
    mc_arc(start, target, offset, radius, (a0, a1, lin), cw, tol)
}
