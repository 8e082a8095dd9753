//! Least-squares B-spline approximation of digitised points within a tolerance (Piegl & Tiller
//! §9.4.1), for seams and outlines read from files as noisy polylines.
//!
//! Chord-length parameters, knots placed by averaging so every span holds data (the
//! Schoenberg–Whitney condition, which keeps the normal equations non-singular), end points
//! interpolated, interior control points by least squares, then parameter correction (each
//! point's parameter is moved to its foot point and the system solved again). The control-point
//! count grows until the largest point-to-curve distance is within the tolerance; at worst the
//! curve interpolates every point.
//!
//! The normal matrix `NᵀN` is banded (half-bandwidth = degree) and symmetric positive definite;
//! it is assembled and factored in banded form, so a fit costs `O(m·p² + n·p²)` for `m` points
//! and `n` control points.

use glam::DVec3;

use super::BSpline;
use super::basis::{basis_funs, find_span};
use super::bezier::check_finite;
use crate::{ParamCurve, SurfaceError};

/// Most parameter-correction rounds per control-point count: each moves every parameter to its
/// foot point by Newton steps and solves again; rounds stop early once the sum of squared
/// errors improves by less than [`CORRECTION_MIN_GAIN`].
const CORRECTION_ROUNDS: usize = 8;
/// Relative improvement of the largest error below which correction stops.
const CORRECTION_MIN_GAIN: f64 = 0.01;
/// Newton steps per point and round of parameter correction.
const CORRECTION_NEWTON_STEPS: usize = 3;

/// The result of [`fit_bspline`].
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The approximating curve, on `[0, 1]`.
    pub curve: BSpline,
    /// The parameter of each input point on the curve (after correction).
    pub params: Vec<f64>,
    /// The largest distance from an input point to its curve point, in mm.
    pub max_error: f64,
}

/// Fits a clamped B-spline of `degree` to `points` so that every point lies within `tol` mm of
/// the curve (measured at the point's corrected parameter), with as few control points as the
/// doubling-then-refining search finds. The first and last points are interpolated.
///
/// Errors: fewer than 2 points, non-finite points, consecutive coincident points, `degree` 0,
/// or a non-positive tolerance.
pub fn fit_bspline(points: &[DVec3], degree: usize, tol: f64) -> Result<Fit, SurfaceError> {
    check_finite(points, "fit point")?;
    if degree == 0 {
        return Err(SurfaceError::BadDegree {
            degree,
            reason: "a fitted curve must be at least linear",
        });
    }
    if !tol.is_finite() || tol <= 0.0 {
        return Err(SurfaceError::BadTolerance {
            what: "fit tolerance",
            value: tol,
        });
    }
    let m = points.len();
    if m < 2 {
        return Err(SurfaceError::ControlPointCount {
            expected: 2,
            got: m,
        });
    }
    // Chord-length parameters on [0, 1].
    let mut u = Vec::with_capacity(m);
    u.push(0.0);
    for (i, w) in points.windows(2).enumerate() {
        let d = w[0].distance(w[1]);
        if d == 0.0 {
            return Err(SurfaceError::FitPointsCoincide {
                first: i,
                second: i + 1,
            });
        }
        u.push(u[i] + d);
    }
    let total = u[m - 1];
    for v in u.iter_mut() {
        *v /= total;
    }
    u[m - 1] = 1.0;
    let p = degree.min(m - 1);
    // Search the control-point count: grow geometrically until the tolerance holds, then bisect
    // between the last failing and the first passing count.
    let mut lo = p; // fails (or is below the minimum)
    let mut n = p + 1;
    let mut best: Option<Fit>;
    loop {
        let fit = fit_with(points, &u, p, n)?;
        if fit.max_error <= tol {
            best = Some(fit);
            break;
        }
        if n == m {
            // Interpolation: the residual is rounding only.
            best = Some(fit);
            break;
        }
        lo = n;
        n = (n + n.div_ceil(2)).min(m);
    }
    let mut hi = n;
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        let fit = fit_with(points, &u, p, mid)?;
        if fit.max_error <= tol {
            hi = mid;
            best = Some(fit);
        } else {
            lo = mid;
        }
    }
    best.ok_or(SurfaceError::NoFit)
}

/// Least-squares fit with `n` control points and parameter correction.
fn fit_with(points: &[DVec3], u0: &[f64], p: usize, n: usize) -> Result<Fit, SurfaceError> {
    let m = points.len();
    let knots = averaged_knots(u0, p, n);
    let residuals = |c: &BSpline, u: &[f64]| {
        points
            .iter()
            .zip(u)
            .fold((0.0, 0.0f64), |(sse, mx), (q, &t)| {
                let d = c.eval(t).distance(*q);
                (sse + d * d, mx.max(d))
            })
    };
    let mut u = u0.to_vec();
    let mut curve = solve_lsq(points, &u, p, n, &knots)?;
    let (mut sse, mut err) = residuals(&curve, &u);
    if n < m {
        for _ in 0..CORRECTION_ROUNDS {
            let mut u_new = u.clone();
            for k in 1..m - 1 {
                u_new[k] = foot_param(&curve, points[k], u[k]);
            }
            let c_new = solve_lsq(points, &u_new, p, n, &knots)?;
            let (sse_new, err_new) = residuals(&c_new, &u_new);
            // Projection then least squares never raises the sum of squares; the first round
            // typically gains 10×, later ones ~0.1 % each (first-order convergence), so stop
            // once a round gains little.
            if sse_new.is_nan() || sse_new >= sse {
                break;
            }
            let gain = (sse - sse_new) / sse;
            (curve, u, sse, err) = (c_new, u_new, sse_new, err_new);
            if gain < CORRECTION_MIN_GAIN {
                break;
            }
        }
    }
    Ok(Fit {
        curve,
        params: u,
        max_error: err,
    })
}

/// Piegl & Tiller (9.69): interior knots averaged over the parameters so that each span
/// contains at least one parameter. For `n == m` (interpolation) this is (9.8)-like averaging.
fn averaged_knots(u: &[f64], p: usize, n: usize) -> Vec<f64> {
    let m = u.len();
    let mut knots = vec![0.0; p + 1];
    if n == m {
        // Interpolation: de Boor's averaging t_{j+p} = (u_j + … + u_{j+p−1}) / p.
        for j in 1..n - p {
            knots.push(u[j..j + p].iter().sum::<f64>() / p as f64);
        }
    } else {
        let d = m as f64 / (n - p) as f64;
        for j in 1..n - p {
            let x = j as f64 * d;
            let i = x.floor() as usize;
            let a = x - i as f64;
            knots.push((1.0 - a) * u[i - 1] + a * u[i.min(m - 1)]);
        }
    }
    knots.extend(std::iter::repeat_n(1.0, p + 1));
    knots
}

/// Solves the banded normal equations for the interior control points, ends interpolated.
fn solve_lsq(
    q: &[DVec3],
    u: &[f64],
    p: usize,
    n: usize,
    knots: &[f64],
) -> Result<BSpline, SurfaceError> {
    let m = q.len();
    let (q0, qm) = (q[0], q[m - 1]);
    let ni = n - 2; // unknowns P_1..P_{n−2}
    let bw = p; // half-bandwidth
    // Banded storage: a[i][bw + (j − i)] for |i − j| ≤ bw.
    let mut a = vec![0.0; ni * (2 * bw + 1)];
    let mut rhs = vec![DVec3::ZERO; ni];
    let mut nb = vec![0.0; p + 1];
    for k in 1..m - 1 {
        let span = find_span(n, p, u[k], knots);
        basis_funs(span, u[k], p, knots, &mut nb);
        let first = span - p;
        let mut r = q[k];
        for (j, &b) in nb.iter().enumerate() {
            let idx = first + j;
            if idx == 0 {
                r -= b * q0;
            } else if idx == n - 1 {
                r -= b * qm;
            }
        }
        for (j1, &b1) in nb.iter().enumerate() {
            let i1 = first + j1;
            if i1 == 0 || i1 == n - 1 {
                continue;
            }
            rhs[i1 - 1] += b1 * r;
            for (j2, &b2) in nb.iter().enumerate() {
                let i2 = first + j2;
                if i2 == 0 || i2 == n - 1 {
                    continue;
                }
                // Row i1−1, column i2−1 in banded storage (|i2 − i1| ≤ p by construction).
                a[(i1 - 1) * (2 * bw + 1) + bw + i2 - i1] += b1 * b2;
            }
        }
    }
    let x = banded_cholesky_solve(&mut a, ni, bw, rhs)
        .ok_or(SurfaceError::FitSingular { control_points: n })?;
    let mut pts = Vec::with_capacity(n);
    pts.push(q0);
    pts.extend(x);
    pts.push(qm);
    BSpline::new(p, knots.to_vec(), pts)
}

/// In-place banded Cholesky (LLᵀ) and solve; `None` when the matrix is not positive definite.
fn banded_cholesky_solve(
    a: &mut [f64],
    n: usize,
    bw: usize,
    mut b: Vec<DVec3>,
) -> Option<Vec<DVec3>> {
    let w = 2 * bw + 1;
    let at = |i: usize, j: usize| i * w + bw + j - i; // valid for i − bw ≤ j ≤ i + bw
    // Factor: L stored in the lower band (j ≤ i).
    for i in 0..n {
        let j0 = i.saturating_sub(bw);
        for j in j0..=i {
            let mut s = a[at(i, j)];
            let k0 = i.saturating_sub(bw).max(j.saturating_sub(bw));
            for k in k0..j {
                s -= a[at(i, k)] * a[at(j, k)];
            }
            if i == j {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                a[at(i, i)] = s.sqrt();
            } else {
                a[at(i, j)] = s / a[at(j, j)];
            }
        }
    }
    // Forward: L y = b.
    for i in 0..n {
        let mut s = b[i];
        for k in i.saturating_sub(bw)..i {
            s -= a[at(i, k)] * b[k];
        }
        b[i] = s / a[at(i, i)];
    }
    // Backward: Lᵀ x = y.
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..(i + bw + 1).min(n) {
            s -= a[at(k, i)] * b[k];
        }
        b[i] = s / a[at(i, i)];
    }
    Some(b)
}

/// Newton steps on `(C(t) − q)·C'(t) = 0` from `t`, clamped to `[0, 1]`.
fn foot_param(c: &BSpline, q: DVec3, mut t: f64) -> f64 {
    for _ in 0..CORRECTION_NEWTON_STEPS {
        let r = c.eval(t) - q;
        let d1 = c.deriv(t, 1);
        let d2 = c.deriv(t, 2);
        let g = r.dot(d1);
        let gp = d1.length_squared() + r.dot(d2);
        if gp.is_nan() || gp <= 0.0 {
            break;
        }
        t = (t - g / gp).clamp(0.0, 1.0);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CurveExt;

    #[test]
    fn exact_data_is_reproduced_with_few_control_points() {
        // Points on a cubic, sampled uniformly in its own parameter (not in chord length).
        let pts: Vec<DVec3> = (0..=40)
            .map(|i| {
                let t = i as f64 / 40.0;
                DVec3::new(100.0 * t, 30.0 * t * t - 20.0 * t * t * t, 5.0 * t)
            })
            .collect();
        let fit = fit_bspline(&pts, 3, 0.01).unwrap();
        assert!(fit.max_error <= 0.01);
        assert_eq!(fit.curve.points().len(), 4, "a single cubic span suffices");
        // Parameter correction converges only linearly, so a tight tolerance costs control
        // points, but still far fewer than the data.
        let fine = fit_bspline(&pts, 3, 1e-5).unwrap();
        assert!(fine.max_error <= 1e-5);
        assert!(
            fine.curve.points().len() <= 20,
            "{}",
            fine.curve.points().len()
        );
        assert_eq!(fit.curve.eval(0.0), pts[0]);
        assert_eq!(fit.curve.eval(1.0), pts[40]);
    }

    #[test]
    fn noisy_circle_within_tolerance() {
        // A digitised circle of radius 60 mm with ±0.02 mm deterministic noise.
        let m = 400;
        let pts: Vec<DVec3> = (0..m)
            .map(|i| {
                let a = 3.0 * i as f64 / (m - 1) as f64;
                let noise = 0.02 * ((i * 7919 % 101) as f64 / 50.0 - 1.0);
                (60.0 + noise) * DVec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        for tol in [0.5, 0.05] {
            let fit = fit_bspline(&pts, 3, tol).unwrap();
            assert!(fit.max_error <= tol);
            // Every point really is within tol of the curve (not only at its parameter).
            for q in &pts {
                let (_, d) = fit.curve.nearest(*q, 1e-9);
                assert!(d <= tol + 1e-9);
            }
            // Far fewer control points than data points, and a fair curve: radius of curvature
            // stays near 60 mm.
            let n = fit.curve.points().len();
            assert!(n < 40, "tol {tol}: {n} control points");
            for i in 1..20 {
                let k = fit.curve.curvature(i as f64 / 20.0).unwrap();
                assert!(
                    (1.0 / k - 60.0).abs() < 15.0,
                    "tol {tol}: radius {}",
                    1.0 / k
                );
            }
        }
    }

    #[test]
    fn tight_tolerance_falls_back_to_interpolation_and_errors_are_named() {
        let pts = [
            DVec3::ZERO,
            DVec3::new(1.0, 3.0, 0.0),
            DVec3::new(2.0, -1.0, 0.0),
            DVec3::new(3.0, 2.0, 1.0),
            DVec3::new(4.0, 0.0, 0.0),
        ];
        let fit = fit_bspline(&pts, 3, 1e-12).unwrap();
        assert!(fit.max_error < 1e-9);
        assert_eq!(fit.curve.points().len(), 5);
        assert!(fit_bspline(&pts[..1], 3, 0.1).is_err());
        assert!(fit_bspline(&pts, 0, 0.1).is_err());
        assert!(fit_bspline(&pts, 3, 0.0).is_err());
        assert!(fit_bspline(&[DVec3::ZERO, DVec3::ZERO, DVec3::X], 3, 0.1).is_err());
        // Two points: the straight segment.
        let fit = fit_bspline(&pts[..2], 3, 0.1).unwrap();
        assert!((fit.curve.eval(0.5) - 0.5 * pts[1]).length() < 1e-12);
    }
}
