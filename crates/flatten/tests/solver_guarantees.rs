//! The projected-Newton solver on hard inputs and under the caller's control: slivers (smallest
//! angles of a fraction of a degree, as on scanned meshes) converge flip-free in few Newton
//! steps; the parallel assembly gives the same bits with one thread or two; the cancel flag, the
//! time limit and the iteration cap are honoured; progress is reported.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use flatcut_flatten::{
    FlattenError, FlattenHooks, FlattenParams, FlattenProgress, Flattening, Method, flatten,
    testmesh,
};
use flatcut_mesh::TriMesh;

/// Newton steps allowed on the slivered surfaces (issue 21's goal for hard meshes).
const HARD_MESH_STEPS: usize = 30;

fn smallest_angle_deg(mesh: &TriMesh) -> f64 {
    let mut best = f64::INFINITY;
    for t in 0..mesh.triangles.len() {
        let p = mesh.corners(t);
        for k in 0..3 {
            let a = p[(k + 1) % 3] - p[k];
            let b = p[(k + 2) % 3] - p[k];
            best = best.min(a.cross(b).length().atan2(a.dot(b)).to_degrees());
        }
    }
    best
}

fn assert_flip_free(mesh: &TriMesh, f: &Flattening) {
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| f.uv[v as usize]);
        assert!((b - a).perp_dot(c - a) > 0.0, "triangle {t} flipped");
    }
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(f)
}

#[test]
fn slivered_surfaces_converge_flip_free_in_few_steps() {
    for (name, base) in [
        ("cap", testmesh::spherical_cap(80.0, 1.2, 14)),
        ("saddle", testmesh::saddle(80.0, 16)),
    ] {
        let mesh = testmesh::slivered(&base, 3, 0.01);
        let angle = smallest_angle_deg(&mesh);
        assert!(angle < 1.0, "{name}: smallest angle {angle}° is no sliver");
        let plain = flatten(&base, &FlattenParams::new(Method::Isometric)).unwrap();
        let f = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
        assert_flip_free(&mesh, &f);
        assert!(
            f.info.iterations <= HARD_MESH_STEPS,
            "{name}: {} Newton steps",
            f.info.iterations
        );
        // Splitting edges adds freedom on the same surface: the optimum cannot be worse.
        assert!(
            f.info.final_energy <= plain.info.final_energy * (1.0 + 1e-6),
            "{name}: δ2 {} with slivers against {} without",
            f.info.final_energy,
            plain.info.final_energy
        );
    }
}

#[test]
fn one_thread_and_two_give_the_same_bits() {
    let mesh = testmesh::slivered(&testmesh::spherical_cap(80.0, 1.2, 40), 5, 0.02);
    assert!(mesh.triangles.len() > 8192, "more than one assembly block");
    for method in [Method::Isometric, Method::Conformal] {
        let p = FlattenParams::new(method);
        let one = in_pool(1, || flatten(&mesh, &p).unwrap());
        let two = in_pool(2, || flatten(&mesh, &p).unwrap());
        assert_eq!(one.info.iterations, two.info.iterations, "{method}");
        assert!(
            one.uv
                .iter()
                .zip(&two.uv)
                .all(|(a, b)| a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits()),
            "{method}: the maps differ between one and two threads"
        );
    }
    let small = testmesh::saddle(60.0, 8);
    let p = FlattenParams::new(Method::BoundaryIsometric);
    let one = in_pool(1, || flatten(&small, &p).unwrap());
    let two = in_pool(2, || flatten(&small, &p).unwrap());
    assert_eq!(one.uv, two.uv, "boundary-isometric");
}

/// The solve takes chord steps in its tail (the last factorisation reused) and may end on one
/// instead of a last Newton step: the energy it stops at must still be within the tolerance of
/// the converged one.
#[test]
fn a_solve_ended_by_a_chord_step_is_converged_to_the_tolerance() {
    for (name, mesh) in [
        ("cap", testmesh::spherical_cap(80.0, 1.2, 14)),
        ("saddle", testmesh::saddle(80.0, 16)),
        (
            "slivered cap",
            testmesh::slivered(&testmesh::spherical_cap(80.0, 1.2, 14), 3, 0.01),
        ),
    ] {
        let p = FlattenParams::new(Method::Isometric);
        let f = flatten(&mesh, &p).unwrap();
        let mut tight = FlattenParams::new(Method::Isometric);
        tight.rel_tolerance = 1e-15;
        let r = flatten(&mesh, &tight).unwrap();
        assert!(r.info.iterations >= f.info.iterations, "{name}");
        let gap = (f.info.final_energy - r.info.final_energy) / r.info.final_energy;
        assert!(
            (0.0..=p.rel_tolerance).contains(&gap),
            "{name}: stopped {gap:.2e} above the converged energy"
        );
    }
}

#[test]
fn cancel_flag_stops_every_iterative_method() {
    let mesh = testmesh::spherical_cap(80.0, 1.2, 10);
    for method in [
        Method::Isometric,
        Method::Conformal,
        Method::Minmax,
        Method::BoundaryIsometric,
    ] {
        let flag = Arc::new(AtomicBool::new(false));
        let setter = flag.clone();
        // Cancel from the progress callback after the first report, as a UI thread would.
        let hooks = FlattenHooks::default()
            .with_cancel(flag)
            .with_progress(Arc::new(move |_: &FlattenProgress| {
                setter.store(true, Ordering::Relaxed)
            }));
        let r = flatten(&mesh, &FlattenParams::new(method).with_hooks(hooks));
        assert!(
            matches!(r, Err(FlattenError::Cancelled { method: m }) if m == method),
            "{method}: {r:?}"
        );
    }
}

#[test]
fn time_limit_returns_a_flip_free_map_with_a_warning() {
    let mesh = testmesh::slivered(&testmesh::spherical_cap(80.0, 1.2, 16), 3, 0.01);
    for method in [Method::Isometric, Method::Minmax, Method::BoundaryIsometric] {
        let p = FlattenParams::new(method).with_time_limit(Some(Duration::ZERO));
        let f = flatten(&mesh, &p).unwrap();
        assert_flip_free(&mesh, &f);
        assert!(
            f.info.warnings.iter().any(|w| w.contains("time limit")),
            "{method}: {:?}",
            f.info.warnings
        );
    }
}

#[test]
fn progress_is_reported_and_minmax_keeps_its_iteration_cap() {
    let mesh = testmesh::spherical_cap(80.0, 1.0, 10);
    let seen = Arc::new(AtomicUsize::new(0));
    let last = Arc::new(Mutex::new(None::<FlattenProgress>));
    let (s, l) = (seen.clone(), last.clone());
    let hooks = FlattenHooks::default().with_progress(Arc::new(move |p: &FlattenProgress| {
        s.fetch_add(1, Ordering::Relaxed);
        *l.lock().unwrap() = Some(p.clone());
    }));
    let cap = 37;
    let f = flatten(
        &mesh,
        &FlattenParams::new(Method::Minmax)
            .with_max_iters(cap)
            .with_hooks(hooks),
    )
    .unwrap();
    // Two stages, the isometric start and the descent, each within the cap.
    let names: Vec<&str> = f.info.stages.iter().map(|s| s.stage).collect();
    assert_eq!(names, ["min-max start", "minmax"]);
    assert!(
        f.info
            .stages
            .iter()
            .all(|s| s.iterations <= cap && s.cap == cap),
        "{:?}",
        f.info.stages
    );
    let total: usize = f.info.stages.iter().map(|s| s.iterations).sum();
    assert_eq!(f.info.iterations, total);
    assert!(seen.load(Ordering::Relaxed) >= f.info.stages[1].iterations);
    let last = last.lock().unwrap().clone().expect("a progress report");
    assert_eq!(last.stage, "minmax");
    assert!(last.iteration <= cap && last.max_iterations == cap);
}
