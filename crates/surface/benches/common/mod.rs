//! The benchmark surfaces, identical to `../shared/bench/occt/surfaces_def.py` and `eval_occt.cpp`.

use flatcut_geom::DVec3;
use flatcut_surface::{BSplinePatch, BezierPatch};
use std::f64::consts::PI;

/// Bicubic Bézier saddle: `P_ij = (x_i, y_j, x_i y_j / 100)`, `x_i = −100 + 200 i/3` mm.
pub fn bezier_saddle() -> BezierPatch {
    let xs: Vec<f64> = (0..4).map(|i| -100.0 + 200.0 * i as f64 / 3.0).collect();
    let mut pts = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            pts.push(DVec3::new(xs[i], xs[j], xs[i] * xs[j] / 100.0));
        }
    }
    BezierPatch::new(3, 3, pts).expect("valid Bézier net")
}

fn wavy_poles() -> Vec<DVec3> {
    let xs: Vec<f64> = (0..10).map(|i| -100.0 + 200.0 * i as f64 / 9.0).collect();
    let mut pts = Vec::new();
    for i in 0..10 {
        for j in 0..10 {
            let z = 20.0 * (PI * i as f64 / 3.0).sin() * (PI * j as f64 / 4.0).cos();
            pts.push(DVec3::new(xs[i], xs[j], z));
        }
    }
    pts
}

fn clamped_knots() -> Vec<f64> {
    let mut k = vec![0.0; 3];
    k.extend((0..8).map(|i| i as f64 / 7.0));
    k.extend([1.0; 3]);
    k
}

/// 10×10-pole bicubic B-spline, uniform clamped knots (unique 0, 1/7, …, 1).
pub fn bspline_wavy() -> BSplinePatch {
    BSplinePatch::new(
        3,
        3,
        clamped_knots(),
        clamped_knots(),
        10,
        10,
        wavy_poles(),
        None,
    )
    .expect("valid B-spline")
}

/// The same net as a NURBS with non-uniform weights `1 + 0.25 ((i + j) mod 3)`.
pub fn nurbs_wavy() -> BSplinePatch {
    let w = (0..100)
        .map(|k| 1.0 + 0.25 * ((k / 10 + k % 10) % 3) as f64)
        .collect();
    BSplinePatch::new(
        3,
        3,
        clamped_knots(),
        clamped_knots(),
        10,
        10,
        wavy_poles(),
        Some(w),
    )
    .expect("valid NURBS")
}

/// `n` parameters `a/(n−1)`, as in the OCCT harness.
pub fn grid(n: usize) -> Vec<f64> {
    (0..n).map(|a| a as f64 / (n - 1) as f64).collect()
}
