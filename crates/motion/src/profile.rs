//! The velocity profile of one block: accelerate, cruise, decelerate (or a triangle when the
//! block is too short to reach its cruise speed).

/// Time to travel `len` starting at `vi`, ending at `vf`, cruising at most at `vmax`, with
/// acceleration `a` (all mm, mm/s, mm/s²).
pub fn trapezoid_time(len: f64, vi: f64, vf: f64, vmax: f64, a: f64) -> f64 {
    if len <= 0.0 || vmax <= 0.0 || a <= 0.0 {
        return 0.0;
    }
    let da = ((vmax * vmax - vi * vi) / (2.0 * a)).max(0.0);
    let dd = ((vmax * vmax - vf * vf) / (2.0 * a)).max(0.0);
    if da + dd <= len {
        (vmax - vi).max(0.0) / a + (vmax - vf).max(0.0) / a + (len - da - dd) / vmax
    } else {
        let vp = ((2.0 * a * len + vi * vi + vf * vf) / 2.0).sqrt().min(vmax);
        (vp - vi).max(0.0) / a + (vp - vf).max(0.0) / a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn trapezoid_and_triangle_match_kinematics() {
        // 100 mm at 10 mm/s with 10 mm/s²: 1 s up (5 mm), 9 s cruise, 1 s down = 11 s.
        assert_relative_eq!(trapezoid_time(100.0, 0.0, 0.0, 10.0, 10.0), 11.0);
        // 4 mm never reaches 10 mm/s: a triangle to √40 and back.
        assert_relative_eq!(
            trapezoid_time(4.0, 0.0, 0.0, 10.0, 10.0),
            2.0 * 40f64.sqrt() / 10.0
        );
        // Entering at cruise speed and leaving at it: distance over speed.
        assert_relative_eq!(trapezoid_time(50.0, 10.0, 10.0, 10.0, 10.0), 5.0);
        assert_eq!(trapezoid_time(0.0, 0.0, 0.0, 10.0, 10.0), 0.0);
    }
}
