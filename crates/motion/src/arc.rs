//! Arcs as GRBL runs them: `mc_arc` (`motion_control.c`) splits an arc into
//! `floor(|½·sweep·r| / √(tol·(2r − tol)))` chords (`$12` = tol), places their ends by a
//! small-angle rotation of the radius vector and puts it back on the exact circle every
//! `N_ARC_CORRECTION` chords; the planner then sees only those chords.
//!
//! The arithmetic is the firmware's: single precision, as on the Uno (whose `double` is a
//! `float` too), so the chord ends are the ones GRBL plans between.

/// GRBL's `ARC_ANGULAR_TRAVEL_EPSILON` (rad): an arc whose end meets its start within this angle
/// is a full circle.
pub const FULL_CIRCLE_EPS: f64 = 5e-7;
/// GRBL's `N_ARC_CORRECTION` (`config.h`): the radius vector is rotated by the small-angle
/// approximation this many times, then computed exactly.
pub const N_ARC_CORRECTION: usize = 12;
/// Most chords one arc is split into: `mc_arc` counts them in a `uint16_t`.
const MAX_CHORDS: f32 = u16::MAX as f32;

/// The chords of one arc as `mc_arc` makes them.
#[derive(Debug, Clone, PartialEq)]
pub struct ArcChords {
    /// Chord ends, the arc's start first and its target last.
    pub points: Vec<[f64; 3]>,
    /// `mc_arc`'s `segments`: 0 when the arc is one straight line to the target (too short to
    /// split), else the number of chords. With 1 or more, GRBL runs an inverse-time (`G93`) arc
    /// at `F × segments` mm/min (it multiplies the feed and clears the inverse-time flag).
    pub segments: usize,
}

/// The chord points of an arc (start and target included) the way `mc_arc` splits it, from its
/// centre (the `I J K` form: the radius is the distance from the start to the centre). `axes` =
/// (first plane axis, second plane axis, linear axis); `center` is in the plane (first, second
/// axis), `cw` the direction. The linear axis moves in proportion (a helix).
pub fn arc_chords(
    start: [f64; 3],
    target: [f64; 3],
    center: [f64; 2],
    axes: (usize, usize, usize),
    cw: bool,
    tol: f64,
) -> Vec<[f64; 3]> {
    let offset = [center[0] - start[axes.0], center[1] - start[axes.1]];
    let radius = offset[0].hypot(offset[1]);
    mc_arc(start, target, offset, radius, axes, cw, tol).points
}

/// `mc_arc` itself: `offset` is the centre relative to the start (in the plane), `radius` the
/// radius GRBL's parser hands it (`hypot(I, J)`, or `|R|` for the radius form), `tol` = `$12`.
/// A radius that is zero or not finite gives the straight chord (GRBL refuses such an arc before
/// it gets here).
pub fn mc_arc(
    start: [f64; 3],
    target: [f64; 3],
    offset: [f64; 2],
    radius: f64,
    axes: (usize, usize, usize),
    cw: bool,
    tol: f64,
) -> ArcChords {
    let straight = ArcChords {
        points: vec![start, target],
        segments: 0,
    };
    let (a0, a1, lin) = axes;
    if !(radius > 0.0 && radius.is_finite()) {
        return straight;
    }
    let pos: [f32; 3] = start.map(|v| v as f32);
    let tgt: [f32; 3] = target.map(|v| v as f32);
    let off = [offset[0] as f32, offset[1] as f32];
    let (radius, tol) = (radius as f32, tol as f32);
    let center = [pos[a0] + off[0], pos[a1] + off[1]];
    let (mut r0, mut r1) = (-off[0], -off[1]);
    let (rt0, rt1) = (tgt[a0] - center[0], tgt[a1] - center[1]);
    let mut angular = (r0 * rt1 - r1 * rt0).atan2(r0 * rt0 + r1 * rt1);
    let eps = FULL_CIRCLE_EPS as f32;
    let tau = std::f32::consts::TAU;
    if cw {
        if angular >= -eps {
            angular -= tau;
        }
    } else if angular <= eps {
        angular += tau;
    }
    let n = ((0.5 * angular * radius).abs() / (tol * (2.0 * radius - tol)).sqrt()).floor();
    if !n.is_finite() || n < 1.0 {
        return straight;
    }
    let segments = n.min(MAX_CHORDS) as usize;
    let theta = angular / segments as f32;
    let linear = (tgt[lin] - pos[lin]) / segments as f32;
    // Third-order small-angle rotation (`mc_arc`'s constants).
    let mut cos_t = 2.0 - theta * theta;
    let sin_t = theta * 0.166_666_67 * (cos_t + 4.0);
    cos_t *= 0.5;
    let mut points = Vec::with_capacity(segments + 1);
    points.push(start);
    let mut p = pos;
    let mut count = 0;
    for i in 1..segments {
        if count < N_ARC_CORRECTION {
            let ri = r0 * sin_t + r1 * cos_t;
            r0 = r0 * cos_t - r1 * sin_t;
            r1 = ri;
            count += 1;
        } else {
            let (sin_i, cos_i) = (i as f32 * theta).sin_cos();
            r0 = -off[0] * cos_i + off[1] * sin_i;
            r1 = -off[0] * sin_i - off[1] * cos_i;
            count = 0;
        }
        p[a0] = center[0] + r0;
        p[a1] = center[1] + r1;
        p[lin] += linear;
        points.push(p.map(f64::from));
    }
    points.push(target);
    ArcChords { points, segments }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quarter(tol: f64) -> ArcChords {
        mc_arc(
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [-10.0, 0.0],
            10.0,
            (0, 1, 2),
            false,
            tol,
        )
    }

    #[test]
    fn segment_count_is_mc_arcs() {
        // Quarter circle r = 10, $12 = 0.002: floor(½·π/2·10 / √(0.002·19.998)) = 39 chords.
        let q = quarter(0.002);
        assert_eq!(q.segments, 39);
        assert_eq!(q.points.len(), 40);
        // $12 = 0.01: floor(7.853982 / √(0.01·19.99)) = floor(17.5655) = 17.
        assert_eq!(quarter(0.01).segments, 17);
        // Too short to split: one straight line, inverse time kept.
        // r = 0.005: floor(0.003927 / √(0.002·0.008)) = floor(0.98) = 0.
        let tiny = mc_arc(
            [0.005, 0.0, 0.0],
            [0.0, 0.005, 0.0],
            [-0.005, 0.0],
            0.005,
            (0, 1, 2),
            false,
            0.002,
        );
        assert_eq!(tiny.segments, 0);
        assert_eq!(tiny.points.len(), 2);
    }

    /// The rotation drifts off the circle by the third-order approximation's error between
    /// corrections; every 13th point is exact again (to single precision).
    #[test]
    fn rotation_with_exact_correction_every_n_arc_correction() {
        // A full circle of r = 50 with a coarse tolerance: θ per chord is large enough that the
        // approximation's drift shows.
        let full = mc_arc(
            [50.0, 0.0, 0.0],
            [50.0, 0.0, 0.0],
            [-50.0, 0.0],
            50.0,
            (0, 1, 2),
            true,
            0.5,
        );
        // floor(½·2π·50 / √(0.5·99.5)) = floor(157.0796 / 7.0534) = 22.
        assert_eq!(full.segments, 22);
        let theta = -std::f64::consts::TAU / 22.0;
        let err = |i: usize| {
            let p = full.points[i];
            let exact = [
                50.0 * (i as f64 * theta).cos(),
                50.0 * (i as f64 * theta).sin(),
            ];
            (p[0] - exact[0]).hypot(p[1] - exact[1])
        };
        // Point 13 is the exact correction; 12 carries twelve approximated rotations.
        assert!(err(13) < 2e-5, "{}", err(13));
        assert!(err(12) > 1e-4, "{}", err(12));
        // The drift of one rotation is the Taylor remainder: θ⁴/24 of the radius, about.
        let per_step = theta.powi(4) / 24.0 * 50.0;
        assert!(
            err(1) > 0.5 * per_step && err(1) < 2.0 * per_step,
            "{}",
            err(1)
        );
        assert_eq!(*full.points.last().unwrap(), [50.0, 0.0, 0.0]);
        // The IJK wrapper is the same split.
        let via_center = arc_chords(
            [50.0, 0.0, 0.0],
            [50.0, 0.0, 0.0],
            [0.0, 0.0],
            (0, 1, 2),
            true,
            0.5,
        );
        assert_eq!(via_center, full.points);
    }

    #[test]
    fn helix_moves_the_linear_axis_in_proportion() {
        let h = mc_arc(
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 4.0],
            [-10.0, 0.0],
            10.0,
            (0, 1, 2),
            false,
            0.01,
        );
        for (i, p) in h.points.iter().enumerate() {
            let want = 4.0 * i as f64 / h.segments as f64;
            assert!((p[2] - want).abs() < 1e-5, "{i}: {} vs {want}", p[2]);
        }
    }
}
