//! Solve time of the linear methods on a 20k-face spherical cap (geodesic radius 1 rad).

use criterion::{Criterion, criterion_group, criterion_main};
use flatcut_flatten::{FlattenParams, Method, flatten, testmesh};

fn solve(c: &mut Criterion) {
    // 58 rings of 6k triangles each: 6·58² = 20,184 faces.
    let mesh = testmesh::spherical_cap(100.0, 1.0, 58);
    let mut g = c.benchmark_group("cap_20k");
    g.sample_size(10);
    for m in [Method::Lscm, Method::Arap, Method::ConformalBoundary] {
        g.bench_function(m.name(), |b| {
            b.iter(|| flatten(&mesh, &FlattenParams::new(m)).expect("flatten"))
        });
    }
    g.finish();
}

criterion_group!(benches, solve);
criterion_main!(benches);
