//! Bench driver for the nonlinear methods: with `FLATCUT_BENCH_DIR=/path/to/meshes` it flattens
//! every `*.obj` there with `isometric`, prints the solve time and writes `NAME.isometric.obj`
//! (`v` + `vt`) next to it for the bench's `metrics.py`; without it, it checks the same path on
//! a generated cap. Run with `cargo test -p flatcut-flatten --test nonlinear_bench -- --nocapture`.

use std::time::Instant;

use flatcut_flatten::{FlattenParams, Method, flatten};
use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;

fn read_obj(text: &str) -> TriMesh {
    // The mesh crate's reader (line:column errors); bench meshes carry no `vt`.
    let mut m = flatcut_mesh::io::parse_obj(text, std::path::Path::new("bench.obj"))
        .expect("bench mesh parses");
    m.flat = None;
    m
}

fn write_obj(mesh: &TriMesh, uv: &[DVec2]) -> String {
    let mut m = mesh.clone();
    m.flat = Some(uv.to_vec());
    flatcut_mesh::io::obj_string(&m)
}

#[test]
fn bench_isometric() {
    let method = std::env::var("FLATCUT_BENCH_METHOD")
        .ok()
        .and_then(|m| Method::from_name(&m))
        .unwrap_or(Method::Isometric);
    let Ok(dir) = std::env::var("FLATCUT_BENCH_DIR") else {
        let mesh = flatcut_flatten::testmesh::spherical_cap(80.0, 1.0, 14);
        let text = write_obj(&mesh, &vec![DVec2::ZERO; mesh.positions.len()]);
        let back = read_obj(&text);
        assert_eq!(back.triangles, mesh.triangles);
        let f = flatten(&back, &FlattenParams::new(method)).unwrap();
        for t in 0..back.triangles.len() {
            let [a, b, c] = back.triangles[t].map(|v| f.uv[v as usize]);
            assert!((b - a).perp_dot(c - a) > 0.0, "triangle {t} flipped");
        }
        return;
    };
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|e| e == "obj")
                && !p.to_string_lossy().contains(".isometric.")
                && !p.to_string_lossy().contains(".out.")
        })
        .collect();
    names.sort();
    for p in names {
        let mesh = read_obj(&std::fs::read_to_string(&p).unwrap());
        let t0 = Instant::now();
        let f = flatten(&mesh, &FlattenParams::new(method)).unwrap();
        let dt = t0.elapsed().as_secs_f64();
        println!(
            "{} faces={} s={dt:.3} iters={} energy={:.6e}",
            p.file_name().unwrap().to_string_lossy(),
            mesh.triangles.len(),
            f.info.iterations,
            f.info.final_energy
        );
        let out = p.with_extension(format!("{}.out.obj", method.name()));
        std::fs::write(out, write_obj(&mesh, &f.uv)).unwrap();
    }
}
