//! Solve time of the nonlinear methods on a generated 20k-face spherical cap (geodesic radius
//! 1 rad, sphere radius 100 mm): isometric (projected Newton) is the one compared with libigl's
//! SLIM (flattening-anchors.md); min-max is timed on a 2k-face cap (its cost is dominated by the
//! geodesic samples and the L-BFGS stages, not by a linear solve).

use criterion::{Criterion, criterion_group, criterion_main};
use flatcut_flatten::{FlattenParams, Method, flatten, testmesh};

fn solve(c: &mut Criterion) {
    // 58 rings of 6k triangles each: 6·58² = 20,184 faces, as the bench's 20k meshes.
    let cap20k = testmesh::spherical_cap(100.0, 1.0, 58);
    // 6·18² = 1,944 faces, as the bench's 2k meshes.
    let cap2k = testmesh::spherical_cap(100.0, 1.0, 18);
    let mut g = c.benchmark_group("nonlinear");
    g.sample_size(10);
    g.bench_function("isometric_cap_20k", |b| {
        b.iter(|| flatten(&cap20k, &FlattenParams::new(Method::Isometric)).expect("flatten"))
    });
    g.bench_function("conformal_cap_20k", |b| {
        b.iter(|| flatten(&cap20k, &FlattenParams::new(Method::Conformal)).expect("flatten"))
    });
    g.bench_function("minmax_cap_2k", |b| {
        b.iter(|| flatten(&cap2k, &FlattenParams::new(Method::Minmax)).expect("flatten"))
    });
    g.finish();
}

criterion_group!(benches, solve);
criterion_main!(benches);
