//! Drag-knife compensation: the blade tip trails the tool axis by the blade offset `r`, so the axis
//! must run ahead of the wanted cut by `r` along the direction of travel, and swivel around the
//! tip on a circle of radius `r` at corners sharper than the swivel threshold. Closed loops are
//! cut past their start by the overcut so the piece comes free.
//!
//! The blade is assumed aligned with the first segment when it plunges (the usual practice is to
//! start each contour on a straight stretch; the first millimetre self-aligns otherwise).

use flatcut_geom::DVec2;

use crate::moves::Move;
use crate::profile::KnifeConfig;

/// Shortest segment kept when computing directions (mm): shorter ones carry no direction.
const MIN_SEGMENT_MM: f64 = 1e-6;

/// Extends a closed loop `pts` (first point repeated at the end) by `len` mm along its start.
pub fn with_overcut(pts: &[DVec2], len: f64) -> Vec<DVec2> {
    let mut out = pts.to_vec();
    let mut left = len;
    for w in pts.windows(2) {
        if left <= 0.0 {
            break;
        }
        let l = w[0].distance(w[1]);
        if l <= MIN_SEGMENT_MM {
            continue;
        }
        if l >= left {
            out.push(w[0] + (w[1] - w[0]) * (left / l));
            left = 0.0;
        } else {
            out.push(w[1]);
            left -= l;
        }
    }
    out
}

/// The axis path for cutting the polyline `pts` (already extended by any overcut) with a drag
/// knife: the start point and the moves (lines and swivel arcs).
pub fn compensate(pts: &[DVec2], cfg: &KnifeConfig) -> (DVec2, Vec<Move>) {
    let pts: Vec<DVec2> = {
        let mut v: Vec<DVec2> = Vec::with_capacity(pts.len());
        for &p in pts {
            if v.last()
                .is_none_or(|q: &DVec2| q.distance(p) > MIN_SEGMENT_MM)
            {
                v.push(p);
            }
        }
        v
    };
    let r = cfg.blade_offset_mm;
    if pts.len() < 2 || r <= 0.0 {
        let start = pts.first().copied().unwrap_or(DVec2::ZERO);
        return (start, pts.iter().skip(1).map(|&p| Move::Line(p)).collect());
    }
    let dirs: Vec<DVec2> = pts.windows(2).map(|w| (w[1] - w[0]).normalize()).collect();
    let threshold = cfg.swivel_angle_deg.to_radians();
    let start = pts[0] + dirs[0] * r;
    let mut moves = Vec::with_capacity(pts.len() * 2);
    for k in 1..pts.len() {
        let arrive = pts[k] + dirs[k - 1] * r;
        moves.push(Move::Line(arrive));
        if k < dirs.len() {
            let (d0, d1) = (dirs[k - 1], dirs[k]);
            let turn = d0.angle_to(d1);
            if turn.abs() > threshold {
                moves.push(Move::Arc {
                    to: pts[k] + d1 * r,
                    center: pts[k],
                    ccw: turn > 0.0,
                });
            } else if turn != 0.0 {
                moves.push(Move::Line(pts[k] + d1 * r));
            }
        }
    }
    (start, moves)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(r: f64) -> KnifeConfig {
        KnifeConfig {
            blade_offset_mm: r,
            swivel_angle_deg: 20.0,
            overcut_mm: 1.0,
            z_up: 3.0,
            z_down: -1.0,
            plunge_mm_min: 300.0,
        }
    }

    /// Simulates the trailing blade: the tip follows the axis at distance r (tractrix), starting
    /// aligned with the first segment. Returns the tip positions.
    fn trail(start: DVec2, moves: &[Move], r: f64, first_dir: DVec2) -> Vec<DVec2> {
        let mut axis = start;
        let mut tip = start - first_dir * r;
        let mut out = vec![tip];
        for m in moves {
            let pts = match *m {
                Move::Line(to) => (1..=200)
                    .map(|k| axis + (to - axis) * (k as f64 / 200.0))
                    .collect::<Vec<_>>(),
                Move::Arc { to, center, ccw } => {
                    crate::arcs::sample_arc(axis, to, center, ccw, 1e-5)
                }
            };
            for p in pts {
                axis = p;
                let d = axis - tip;
                if d.length() > r {
                    tip = axis - d.normalize() * r;
                }
                out.push(tip);
            }
        }
        out
    }

    #[test]
    fn the_tip_cuts_the_square_corners() {
        let sq = vec![
            DVec2::ZERO,
            DVec2::new(20.0, 0.0),
            DVec2::new(20.0, 20.0),
            DVec2::new(0.0, 20.0),
            DVec2::ZERO,
        ];
        let r = 0.5;
        let (start, moves) = compensate(&sq, &cfg(r));
        assert_eq!(start, DVec2::new(0.5, 0.0));
        // Three swivels at the three inner corners.
        assert_eq!(
            moves
                .iter()
                .filter(|m| matches!(m, Move::Arc { .. }))
                .count(),
            3
        );
        let tips = trail(start, &moves, r, DVec2::X);
        // The tip passes within 0.01 mm of every corner and never strays from the square's edges.
        for c in &sq[1..4] {
            let best = tips
                .iter()
                .map(|t| t.distance(*c))
                .fold(f64::INFINITY, f64::min);
            assert!(best < 0.01, "corner {c:?} missed by {best}");
        }
        for t in &tips {
            let d_edge =
                t.x.abs()
                    .min((t.x - 20.0).abs())
                    .min(t.y.abs())
                    .min((t.y - 20.0).abs());
            assert!(d_edge < 0.01, "tip {t:?} off the outline by {d_edge}");
        }
    }

    #[test]
    fn overcut_extends_along_the_start() {
        let sq = vec![
            DVec2::ZERO,
            DVec2::new(20.0, 0.0),
            DVec2::new(20.0, 20.0),
            DVec2::new(0.0, 20.0),
            DVec2::ZERO,
        ];
        let o = with_overcut(&sq, 1.5);
        assert_eq!(*o.last().unwrap(), DVec2::new(1.5, 0.0));
    }
}
