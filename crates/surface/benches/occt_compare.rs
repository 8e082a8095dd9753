//! Side-by-side twin of `../shared/bench/occt/eval_occt.cpp`: the same surfaces, the same
//! N × N grid (outer loop u, inner v), best of REP runs, the same output format, so
//! `tools/bench-occt/run.sh` can print both and their ratio.
//!
//! Usage: `cargo bench -p flatcut-surface --bench occt_compare -- [N] [REP]`.

mod common;

use flatcut_surface::ParamSurface;
use std::hint::black_box;
use std::time::Instant;

fn loop_d1(s: &dyn ParamSurface, g: &[f64]) -> f64 {
    let mut acc = 0.0;
    for &u in g {
        for &v in g {
            let (p, su, sv) = s.deriv1(black_box(u), black_box(v));
            acc += p.z + su.x + sv.y;
        }
    }
    acc
}

fn main() {
    // Criterion-style flags such as `--bench` are passed by cargo; keep only numbers.
    let nums: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let n = nums.first().copied().unwrap_or(1000).max(2);
    let rep = nums.get(1).copied().unwrap_or(5).max(1);
    let g = common::grid(n);
    println!("flatcut-surface, grid {n}x{n}, best of {rep}");
    let cases: [(&str, Box<dyn ParamSurface>); 3] = [
        (
            "BezierPatch::deriv1 (bicubic)",
            Box::new(common::bezier_saddle()),
        ),
        (
            "BSplinePatch::deriv1 (10x10 bicubic)",
            Box::new(common::bspline_wavy()),
        ),
        (
            "BSplinePatch::deriv1 (10x10 bicubic NURBS)",
            Box::new(common::nurbs_wavy()),
        ),
    ];
    for (name, s) in &cases {
        let mut best = f64::INFINITY;
        let mut chk = 0.0;
        for _ in 0..rep {
            let t0 = Instant::now();
            chk = loop_d1(s.as_ref(), &g);
            best = best.min(t0.elapsed().as_secs_f64());
        }
        let evals = (n * n) as f64;
        println!(
            "{name:<52} {best:8.4} s {:9.2} M/s {:8.1} ns/eval  chk={chk:.6}",
            evals / best / 1e6,
            best / evals * 1e9
        );
    }
}
