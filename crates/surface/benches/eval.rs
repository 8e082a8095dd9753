//! Throughput of point + first partials (`deriv1`) on the OpenCASCADE benchmark surfaces.

mod common;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use flatcut_surface::ParamSurface;
use std::hint::black_box;

/// Grid side per iteration: 100 × 100 = 10 000 evaluations, enough to amortize timer overhead.
const N: usize = 100;

fn sweep(s: &dyn ParamSurface, g: &[f64]) -> f64 {
    let mut acc = 0.0;
    for &u in g {
        for &v in g {
            let (p, su, sv) = s.deriv1(black_box(u), black_box(v));
            acc += p.z + su.x + sv.y;
        }
    }
    acc
}

fn bench(c: &mut Criterion) {
    let g = common::grid(N);
    let surfaces: [(&str, Box<dyn ParamSurface>); 3] = [
        ("bezier_bicubic", Box::new(common::bezier_saddle())),
        ("bspline_10x10_bicubic", Box::new(common::bspline_wavy())),
        ("nurbs_10x10_bicubic", Box::new(common::nurbs_wavy())),
    ];
    let mut group = c.benchmark_group("deriv1");
    group.throughput(Throughput::Elements((N * N) as u64));
    for (name, s) in &surfaces {
        group.bench_function(*name, |b| b.iter(|| sweep(s.as_ref(), &g)));
    }
    group.finish();
    let mut group = c.benchmark_group("deriv2");
    group.throughput(Throughput::Elements((N * N) as u64));
    for (name, s) in &surfaces {
        group.bench_function(*name, |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &u in &g {
                    for &v in &g {
                        acc += s.deriv2(black_box(u), black_box(v)).suv.z;
                    }
                }
                acc
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
