//! Arc fitting: runs of short polyline segments become circular arcs (`G2`/`G3`) when every vertex
//! and every chord of the run lies within the tolerance of one circle.
//!
//! Greedy: from each vertex the run is extended while a circle through its first, middle and last
//! vertex fits all vertices (radial error ≤ tol) and all chords (sagitta ≤ tol), turns one way
//! only, and sweeps less than a full turn. Cost is O(n·L) for n vertices and runs of length L
//! (capped by [`MAX_RUN`]).

use flatcut_geom::DVec2;
use flatcut_geom::num::{GoldenStop, golden_section_min};

use crate::moves::Move;

/// At least this many segments make an arc worth a line of G-code.
pub const MIN_SEGMENTS: usize = 3;
/// Longest run tried (bounds the cost on very long smooth curves; a new arc simply starts).
pub const MAX_RUN: usize = 400;
/// Radii above this are left as lines (an almost straight run gains nothing and GRBL's arc
/// arithmetic loses precision).
pub const MAX_RADIUS_MM: f64 = 5000.0;
/// Radii below this are left as lines (GRBL's radius check, error:33, would bite after rounding).
pub const MIN_RADIUS_MM: f64 = 0.5;

/// The circle through three points: (centre, radius), or `None` when they are collinear.
pub fn circle3(a: DVec2, b: DVec2, c: DVec2) -> Option<(DVec2, f64)> {
    let (ab, ac) = (b - a, c - a);
    let d = 2.0 * ab.perp_dot(ac);
    let scale = ab.length_squared().max(ac.length_squared());
    if d.abs() <= 1e-12 * scale {
        return None;
    }
    let ux = (ac.y * ab.length_squared() - ab.y * ac.length_squared()) / d;
    let uy = (ab.x * ac.length_squared() - ac.x * ab.length_squared()) / d;
    let center = a + DVec2::new(ux, uy);
    Some((center, center.distance(a)))
}

/// Largest radial deviation of the run (vertices and whole chords) from the circle, or `None` when
/// the run does not turn monotonically one way around `center` or sweeps (almost) a full turn.
fn deviation(pts: &[DVec2], center: DVec2, r: f64, ccw: bool) -> Option<f64> {
    let mut sweep = 0.0;
    let mut dev: f64 = 0.0;
    for w in pts.windows(2) {
        let (a, b) = (w[0] - center, w[1] - center);
        let turn = a.perp_dot(b);
        if (turn > 0.0) != ccw || turn == 0.0 {
            return None;
        }
        sweep += a.angle_to(b).abs();
        // Radial deviation of the whole chord: its endpoints and its point nearest the centre.
        let ab = w[1] - w[0];
        let t =
            ((center - w[0]).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        let nearest = (w[0] + ab * t).distance(center);
        dev = dev
            .max((a.length() - r).abs())
            .max((b.length() - r).abs())
            .max((nearest - r).abs());
    }
    (sweep < std::f64::consts::TAU * 0.95).then_some(dev)
}

/// Golden-section iterations when centring the arc (precision 0.618^40 of the bracket).
const CENTRE_ITERS: usize = 40;

/// The best arc from the run's first to its last point: the centre lies on the chord's
/// perpendicular bisector (so start and end radii agree exactly, as GRBL requires), placed to
/// minimise the largest deviation from the run. Returns (centre, radius, ccw, deviation).
fn best_arc(run: &[DVec2]) -> Option<(DVec2, f64, bool, f64)> {
    let (a, b) = (run[0], run[run.len() - 1]);
    let (c0, r0) = circle3(a, run[run.len() / 2], b)?;
    let ccw = (run[1] - run[0]).perp_dot(run[2] - run[1]) > 0.0;
    let m = 0.5 * (a + b);
    let n = (b - a).perp().normalize();
    let s0 = (c0 - m).dot(n);
    let eval = |s: f64| {
        let c = m + n * s;
        deviation(run, c, c.distance(a), ccw).unwrap_or(f64::INFINITY)
    };
    let best = golden_section_min(
        eval,
        s0 - 0.5 * r0,
        s0 + 0.5 * r0,
        GoldenStop::Iterations(CENTRE_ITERS),
    );
    let (s, f) = (best.x, best.fx);
    let f0 = eval(s0);
    let (s, f) = if f0 <= f { (s0, f0) } else { (s, f) };
    let c = m + n * s;
    f.is_finite().then(|| (c, c.distance(a), ccw, f))
}

fn arc_ok(run: &[DVec2], tol: f64) -> Option<(DVec2, bool)> {
    let (c, r, ccw, dev) = best_arc(run)?;
    ((MIN_RADIUS_MM..=MAX_RADIUS_MM).contains(&r) && dev <= tol).then_some((c, ccw))
}

/// Converts the polyline `pts` (starting at `pts[0]`) into moves: lines and arcs, every arc within
/// `tol` of the run of segments it replaces (Hausdorff distance). `tol <= 0` gives lines only.
pub fn fit(pts: &[DVec2], tol: f64) -> Vec<Move> {
    let mut out = Vec::new();
    if pts.len() < 2 {
        return out;
    }
    if tol <= 0.0 {
        return pts[1..].iter().map(|&p| Move::Line(p)).collect();
    }
    let mut i = 0;
    while i + 1 < pts.len() {
        // Exponential then binary search for the longest run that fits (in practice a longer run
        // never fits better).
        let mut best: Option<(usize, DVec2, bool)> = None;
        let last = (pts.len() - 1).min(i + MAX_RUN);
        let mut lo = i + MIN_SEGMENTS;
        let mut hi = lo;
        let mut step = MIN_SEGMENTS;
        while hi <= last {
            match arc_ok(&pts[i..=hi], tol) {
                Some((c, ccw)) => {
                    best = Some((hi, c, ccw));
                    lo = hi + 1;
                    if hi == last {
                        break;
                    }
                    step *= 2;
                    hi = (i + step).min(last);
                }
                None => break,
            }
        }
        if best.is_some() {
            let mut top = hi.min(last + 1);
            while lo < top {
                let mid = (lo + top) / 2;
                match arc_ok(&pts[i..=mid], tol) {
                    Some((c, ccw)) => {
                        best = Some((mid, c, ccw));
                        lo = mid + 1;
                    }
                    None => top = mid,
                }
            }
        }
        match best {
            Some((j, center, ccw)) => {
                out.push(Move::Arc {
                    to: pts[j],
                    center,
                    ccw,
                });
                i = j;
            }
            None => {
                out.push(Move::Line(pts[i + 1]));
                i += 1;
            }
        }
    }
    out
}

/// Samples an arc from `from` to `to` around `center` into points at most `tol` from the arc
/// (excluding `from`, including `to`).
pub fn sample_arc(from: DVec2, to: DVec2, center: DVec2, ccw: bool, tol: f64) -> Vec<DVec2> {
    let r = from.distance(center);
    let a0 = (from - center).to_angle();
    let mut sweep = (to - center).to_angle() - a0;
    if ccw && sweep <= 0.0 {
        sweep += std::f64::consts::TAU;
    }
    if !ccw && sweep >= 0.0 {
        sweep -= std::f64::consts::TAU;
    }
    let step = if r > tol {
        2.0 * (1.0 - tol / r).clamp(-1.0, 1.0).acos()
    } else {
        std::f64::consts::PI
    };
    let n = ((sweep.abs() / step.max(1e-6)).ceil() as usize).max(1);
    (1..=n)
        .map(|k| {
            if k == n {
                to
            } else {
                center + DVec2::from_angle(a0 + sweep * k as f64 / n as f64) * r
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_of_a_circle_becomes_few_arcs_within_tolerance() {
        let c = DVec2::new(50.0, 40.0);
        let pts: Vec<DVec2> = (0..=90)
            .map(|k| c + DVec2::from_angle(k as f64 * 0.05) * 20.0)
            .collect();
        let moves = fit(&pts, 0.01);
        assert!(moves.len() <= 2, "{} moves", moves.len());
        let mut at = pts[0];
        for m in &moves {
            match *m {
                Move::Arc { to, center, ccw } => {
                    assert!(ccw);
                    assert!((center - c).length() < 0.01 && (to - c).length() - 20.0 < 0.01);
                    at = to;
                }
                Move::Line(to) => at = to,
            }
        }
        assert_eq!(at, pts[90]);
    }

    #[test]
    fn zigzag_stays_lines_and_corners_are_kept() {
        let pts: Vec<DVec2> = (0..10)
            .map(|k| DVec2::new(k as f64, (k % 2) as f64))
            .collect();
        assert!(fit(&pts, 0.01).iter().all(|m| matches!(m, Move::Line(_))));
        // A square: no arcs across its corners.
        let sq = [
            DVec2::ZERO,
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 10.0),
            DVec2::new(0.0, 10.0),
            DVec2::ZERO,
        ];
        assert_eq!(fit(&sq, 0.01).len(), 4);
    }

    #[test]
    fn sampled_arc_is_within_tolerance() {
        let c = DVec2::new(1.0, 2.0);
        let pts = sample_arc(
            c + DVec2::new(5.0, 0.0),
            c + DVec2::new(0.0, 5.0),
            c,
            true,
            0.001,
        );
        for w in pts.windows(2) {
            let mid = 0.5 * (w[0] + w[1]);
            assert!(5.0 - mid.distance(c) <= 0.001 + 1e-12);
        }
        assert_eq!(*pts.last().unwrap(), c + DVec2::new(0.0, 5.0));
    }
}
