//! Phase timings of LSCM on large meshes: with `FLATCUT_BENCH_DIR=/path/to/meshes` it reads the
//! `*_200k.obj` meshes there (or those named by `FLATCUT_BENCH_MESHES`, comma-separated stems)
//! and prints the time of the disk check, the assembly, the symbolic and numeric Cholesky
//! factorizations, the solve and the whole `flatten()` call. Without it, it checks on a
//! generated cap that the phase-by-phase solve and `flatten()` agree. Run with
//! `cargo test -p flatcut-flatten --test lscm_speed -- --nocapture`.

use std::time::Instant;

use flatcut_flatten::ops::{corner_cotans, used_mask};
use flatcut_flatten::sparse::{SpdSolver, SymPattern, SymTriplets};
use flatcut_flatten::{FlattenParams, Method, flatten, lscm, testmesh};
use flatcut_geom::DVec2;
use flatcut_mesh::{TriMesh, check_disk};

fn read_obj(text: &str) -> TriMesh {
    // The mesh crate's reader (line:column errors); bench meshes carry no `vt`.
    let mut m = flatcut_mesh::io::parse_obj(text, std::path::Path::new("bench.obj"))
        .expect("bench mesh parses");
    m.flat = None;
    m
}

/// Solves the LSCM system phase by phase (the same energy as `lscm::solve_pinned`), printing
/// the time of each phase; returns the map before scaling.
fn phases(mesh: &TriMesh, name: &str) -> Vec<DVec2> {
    let t0 = Instant::now();
    let topo = check_disk(mesh).expect("disk");
    let t_check = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let (a, b) = lscm::farthest_boundary_pair(mesh, &topo).expect("pair");
    let n = mesh.positions.len();
    let used = used_mask(mesh);
    let mut free_index = vec![usize::MAX; 2 * n];
    let mut m = 0;
    for v in 0..n {
        if used[v] && v as u32 != a && v as u32 != b {
            free_index[2 * v] = m;
            free_index[2 * v + 1] = m + 1;
            m += 2;
        }
    }
    let d = (mesh.positions[b as usize] - mesh.positions[a as usize]).length();
    let mut x = vec![0.0; 2 * n];
    x[2 * b as usize] = d;
    let mut rhs = vec![0.0; m];
    let mut t = SymTriplets::with_capacity(m, 18 * mesh.triangles.len());
    let add = |t: &mut SymTriplets, rhs: &mut Vec<f64>, i: usize, j: usize, v: f64| match (
        free_index[i],
        free_index[j],
    ) {
        (usize::MAX, usize::MAX) => {}
        (fi, usize::MAX) => rhs[fi] -= v * x[j],
        (usize::MAX, fj) => rhs[fj] -= v * x[i],
        (fi, fj) => t.add(fi, fj, v),
    };
    let cot = corner_cotans(&mesh.positions, &mesh.triangles);
    for (tri, c) in mesh.triangles.iter().zip(&cot) {
        for k in 0..3 {
            let (p, q) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            let w = 0.5 * c[k];
            for o in 0..2 {
                add(&mut t, &mut rhs, 2 * p + o, 2 * p + o, w);
                add(&mut t, &mut rhs, 2 * q + o, 2 * q + o, w);
                add(&mut t, &mut rhs, 2 * p + o, 2 * q + o, -w);
            }
        }
    }
    let lp = &topo.boundary_loops[0];
    for i in 0..lp.len() {
        let (p, q) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
        add(&mut t, &mut rhs, 2 * p, 2 * q + 1, -0.5);
        add(&mut t, &mut rhs, 2 * q, 2 * p + 1, 0.5);
    }
    let t_assemble = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let pattern = SymPattern::new(&t, "lscm").expect("pattern");
    let t_pattern = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let mut solver = SpdSolver::new(pattern, "lscm").expect("symbolic");
    let t_symbolic = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    solver.factor(t.values()).expect("numeric");
    let t_numeric = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    solver.solve_in_place(&mut rhs).expect("solve");
    let t_solve = t0.elapsed().as_secs_f64();
    println!(
        "{name}: check_disk {t_check:.3} s, assembly {t_assemble:.3} s, pattern {t_pattern:.3} s, \
         symbolic {t_symbolic:.3} s, numeric {t_numeric:.3} s, solve {t_solve:.3} s"
    );
    for v in 0..n {
        if free_index[2 * v] != usize::MAX {
            x[2 * v] = rhs[free_index[2 * v]];
            x[2 * v + 1] = rhs[free_index[2 * v + 1]];
        }
    }
    (0..n).map(|v| DVec2::new(x[2 * v], x[2 * v + 1])).collect()
}

/// The whole `flatten()` call; returns the map and its time.
fn whole(mesh: &TriMesh) -> (Vec<DVec2>, f64) {
    let t0 = Instant::now();
    let f = flatten(mesh, &FlattenParams::new(Method::Lscm)).expect("lscm");
    (f.uv, t0.elapsed().as_secs_f64())
}

/// Largest distance between `a` and `b` after scaling `a` to `b`'s size (LSCM scales to area).
fn max_gap_up_to_scale(a: &[DVec2], b: &[DVec2]) -> f64 {
    let (na, nb) = (
        a.iter().map(|p| p.length_squared()).sum::<f64>().sqrt(),
        b.iter().map(|p| p.length_squared()).sum::<f64>().sqrt(),
    );
    let s = nb / na;
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p * s - *q).length())
        .fold(0.0, f64::max)
}

#[test]
fn lscm_phase_timings() {
    let Ok(dir) = std::env::var("FLATCUT_BENCH_DIR") else {
        let mesh = testmesh::spherical_cap(1.0, 1.0, 12);
        let uv = phases(&mesh, "cap");
        let (full, _) = whole(&mesh);
        let diag = mesh.bbox().diagonal();
        assert!(max_gap_up_to_scale(&uv, &full) < 1e-9 * diag);
        return;
    };
    let stems: Vec<String> = match std::env::var("FLATCUT_BENCH_MESHES") {
        Ok(s) => s.split(',').map(str::to_owned).collect(),
        Err(_) => vec!["toe_200k".into(), "sphcap_a100_200k".into()],
    };
    for stem in stems {
        let path = std::path::Path::new(&dir).join(format!("{stem}.obj"));
        let mesh = read_obj(&std::fs::read_to_string(&path).expect("mesh file"));
        let uv = phases(&mesh, &stem);
        let (full, secs) = whole(&mesh);
        let diag = mesh.bbox().diagonal();
        let gap = max_gap_up_to_scale(&uv, &full);
        if let Ok(out) = std::env::var("FLATCUT_BENCH_DUMP") {
            let bytes: Vec<u8> = full
                .iter()
                .flat_map(|p| [p.x.to_le_bytes(), p.y.to_le_bytes()])
                .flatten()
                .collect();
            std::fs::write(format!("{out}/{stem}.uv"), bytes).expect("dump");
        }
        let first = full[0];
        println!(
            "{stem}: flatten(lscm) {secs:.3} s ({} faces); uv[0] = ({:.17e}, {:.17e}); phase/whole gap {:.2e} of diag",
            mesh.triangles.len(),
            first.x,
            first.y,
            gap / diag
        );
    }
}
