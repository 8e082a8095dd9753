//! Arcs as GRBL runs them: `mc_arc` splits an arc into chords whose sagitta stays within the arc
//! tolerance `$12`; the planner then sees only those chords.

/// GRBL's `ARC_ANGULAR_TRAVEL_EPSILON` (rad): an arc whose end meets its start within this angle
/// is a full circle.
pub const FULL_CIRCLE_EPS: f64 = 5e-7;
/// Most chords one arc is split into here (a guard against absurd radii, far above what GRBL's
/// 79-character lines can ask for at a sane tolerance).
const MAX_CHORDS: usize = 100_000;

/// The chord points of an arc (start and target included) the way `mc_arc` splits it:
/// `floor(|sweep|·r / √(tol·(2r − tol)))` segments, at least one. `axes` = (first plane axis,
/// second plane axis, linear axis); `center` is in the plane (first, second axis), `cw` the
/// direction. The linear axis moves in proportion (a helix). Returns the straight chord when the
/// radius is zero or not finite.
pub fn arc_chords(
    start: [f64; 3],
    target: [f64; 3],
    center: [f64; 2],
    axes: (usize, usize, usize),
    cw: bool,
    tol: f64,
) -> Vec<[f64; 3]> {
    let (a0, a1, lin) = axes;
    let (cx, cy) = (center[0], center[1]);
    let (sx, sy) = (start[a0], start[a1]);
    let (tx, ty) = (target[a0], target[a1]);
    let r = ((sx - cx).powi(2) + (sy - cy).powi(2)).sqrt();
    if r <= 1e-9 || !r.is_finite() {
        return vec![start, target];
    }
    let ang_s = (sy - cy).atan2(sx - cx);
    let ang_t = (ty - cy).atan2(tx - cx);
    let mut sweep = ang_t - ang_s;
    if cw {
        if sweep >= -FULL_CIRCLE_EPS {
            sweep -= std::f64::consts::TAU;
        }
    } else if sweep <= FULL_CIRCLE_EPS {
        sweep += std::f64::consts::TAU;
    }
    let tol = tol.max(1e-6).min(r);
    let n = ((sweep.abs() * r) / (tol * (2.0 * r - tol)).sqrt())
        .floor()
        .max(1.0) as usize;
    let n = n.min(MAX_CHORDS);
    let mut pts = Vec::with_capacity(n + 1);
    for k in 0..n {
        let s = k as f64 / n as f64;
        let a = ang_s + sweep * s;
        let mut p = start;
        p[a0] = cx + r * a.cos();
        p[a1] = cy + r * a.sin();
        p[lin] = start[lin] + (target[lin] - start[lin]) * s;
        pts.push(p);
    }
    pts.push(target);
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chords_follow_mc_arc_segment_count_and_stay_on_the_circle() {
        // Quarter circle r = 10, tol 0.002: floor(π/2·10 / √(0.002·19.998)) = 78 segments.
        let pts = arc_chords(
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [0.0, 0.0],
            (0, 1, 2),
            false,
            0.002,
        );
        assert_eq!(pts.len(), 79);
        for p in &pts {
            assert!(((p[0] * p[0] + p[1] * p[1]).sqrt() - 10.0).abs() < 1e-9);
        }
        assert_eq!(*pts.last().unwrap(), [0.0, 10.0, 0.0]);
        // Start = end: a full circle.
        let full = arc_chords(
            [10.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 0.0],
            (0, 1, 2),
            true,
            0.01,
        );
        let len: f64 = full
            .windows(2)
            .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
            .sum();
        assert!((len - 20.0 * std::f64::consts::PI).abs() < 0.01, "{len}");
    }
}
