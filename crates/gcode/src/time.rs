//! Run-time estimate with GRBL's motion model: each line is a block with a nominal feed; junction
//! speeds follow GRBL's junction-deviation rule (`planner.c`), and a forward/backward pass gives
//! trapezoidal (or triangular) velocity profiles under the acceleration limit. Dwells (and tool
//! changes that precede them) stop the planner.

/// One timed element of a job.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    Move {
        from: [f64; 3],
        to: [f64; 3],
        feed_mm_min: f64,
    },
    Dwell(f64),
}

/// Seconds to run `motions` with acceleration `accel` (mm/s²) and junction deviation `jd` (mm).
pub fn estimate(motions: &[Motion], accel: f64, jd: f64) -> f64 {
    let mut total = 0.0;
    let mut block: Vec<([f64; 3], f64, f64)> = Vec::new(); // (unit dir, length, nominal mm/s)
    let flush = |block: &mut Vec<([f64; 3], f64, f64)>, total: &mut f64| {
        *total += run_block(block, accel, jd);
        block.clear();
    };
    for m in motions {
        match *m {
            Motion::Move {
                from,
                to,
                feed_mm_min,
            } => {
                let d = [to[0] - from[0], to[1] - from[1], to[2] - from[2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if len <= 1e-9 {
                    continue;
                }
                block.push((
                    [d[0] / len, d[1] / len, d[2] / len],
                    len,
                    feed_mm_min / 60.0,
                ));
            }
            Motion::Dwell(s) => {
                flush(&mut block, &mut total);
                total += s;
            }
        }
    }
    flush(&mut block, &mut total);
    total
}

/// Time of a sequence of segments that starts and ends at rest.
fn run_block(segs: &[([f64; 3], f64, f64)], a: f64, jd: f64) -> f64 {
    let n = segs.len();
    if n == 0 {
        return 0.0;
    }
    // Max entry speed² at each junction.
    let mut entry_max = vec![0.0f64; n + 1];
    for k in 1..n {
        let (u0, _, f0) = segs[k - 1];
        let (u1, _, f1) = segs[k];
        let cos_theta = -(u0[0] * u1[0] + u0[1] * u1[1] + u0[2] * u1[2]);
        let vj2 = if cos_theta > 0.999999 {
            0.0 // reversal
        } else if cos_theta < -0.999999 {
            f64::INFINITY // straight on
        } else {
            let sin_half = (0.5 * (1.0 - cos_theta)).sqrt();
            a * jd * sin_half / (1.0 - sin_half)
        };
        entry_max[k] = vj2.min(f0 * f0).min(f1 * f1);
    }
    // Backward then forward pass.
    let mut v2 = entry_max.clone();
    v2[n] = 0.0;
    for k in (0..n).rev() {
        v2[k] = v2[k].min(v2[k + 1] + 2.0 * a * segs[k].1);
    }
    v2[0] = 0.0;
    for k in 0..n {
        v2[k + 1] = v2[k + 1].min(v2[k] + 2.0 * a * segs[k].1);
    }
    let mut t = 0.0;
    for k in 0..n {
        let (_, len, f) = segs[k];
        let (vi2, vo2, vn2) = (v2[k], v2[k + 1], f * f);
        let (vi, vo) = (vi2.sqrt(), vo2.sqrt());
        // Distance to accelerate to nominal and to decelerate from it.
        let d_acc = ((vn2 - vi2) / (2.0 * a)).max(0.0);
        let d_dec = ((vn2 - vo2) / (2.0 * a)).max(0.0);
        if d_acc + d_dec <= len {
            t += (f - vi) / a + (f - vo) / a + (len - d_acc - d_dec) / f;
        } else {
            // Triangle: peak speed where acceleration meets deceleration.
            let vp2 = (2.0 * a * len + vi2 + vo2) / 2.0;
            let vp = vp2.sqrt();
            t += (vp - vi) / a + (vp - vo) / a;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_straight_move_is_distance_over_feed_plus_ramps() {
        // 100 mm at 60 mm/s with a = 100: ramps take 0.6 s each and cover 18 mm each.
        let m = [Motion::Move {
            from: [0.0; 3],
            to: [100.0, 0.0, 0.0],
            feed_mm_min: 3600.0,
        }];
        let t = estimate(&m, 100.0, 0.01);
        let expect = 0.6 + 0.6 + (100.0 - 36.0) / 60.0;
        assert!((t - expect).abs() < 1e-9, "{t} vs {expect}");
    }

    #[test]
    fn short_move_is_triangular_and_corners_slow_down() {
        let m = [Motion::Move {
            from: [0.0; 3],
            to: [1.0, 0.0, 0.0],
            feed_mm_min: 6000.0,
        }];
        // Triangle: t = 2 sqrt(L/a).
        assert!((estimate(&m, 100.0, 0.01) - 2.0 * (0.01f64).sqrt()).abs() < 1e-9);
        let straight = [
            Motion::Move {
                from: [0.0; 3],
                to: [50.0, 0.0, 0.0],
                feed_mm_min: 3000.0,
            },
            Motion::Move {
                from: [50.0, 0.0, 0.0],
                to: [100.0, 0.0, 0.0],
                feed_mm_min: 3000.0,
            },
        ];
        let corner = [
            Motion::Move {
                from: [0.0; 3],
                to: [50.0, 0.0, 0.0],
                feed_mm_min: 3000.0,
            },
            Motion::Move {
                from: [50.0, 0.0, 0.0],
                to: [50.0, 50.0, 0.0],
                feed_mm_min: 3000.0,
            },
        ];
        // Straight: 2.5 s. Corner: each leg ramps up to 50 mm/s and down to ~1.55 mm/s: ~2.97 s.
        let (c, s) = (
            estimate(&corner, 100.0, 0.01),
            estimate(&straight, 100.0, 0.01),
        );
        assert!((s - 2.5).abs() < 1e-9 && (c - 2.97).abs() < 0.01, "{c} {s}");
        let dwell = [Motion::Dwell(1.5)];
        assert_eq!(estimate(&dwell, 100.0, 0.01), 1.5);
    }
}
