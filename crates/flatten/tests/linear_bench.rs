//! Bench driver for the linear methods: with `FLATCUT_BENCH_DIR=/path/to/meshes` it flattens
//! every `*.obj` there (not already an output) with each method of `FLATCUT_BENCH_METHODS`
//! (default `lscm,arap,conformal-boundary`), prints the solve time and writes
//! `NAME.METHOD.obj` (`v` + `vt`) next to it for the bench's `metrics.py`. Without it, it runs
//! the same path on a generated cap. Run with
//! `cargo test -p flatcut-flatten --test linear_bench -- --nocapture`.

use std::time::Instant;

use flatcut_flatten::{FlattenParams, Method, flatten, testmesh};
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

fn methods() -> Vec<Method> {
    std::env::var("FLATCUT_BENCH_METHODS")
        .unwrap_or_else(|_| "lscm,arap,conformal-boundary".into())
        .split(',')
        .filter_map(|s| Method::from_name(s.trim()))
        .collect()
}

#[test]
fn linear_bench() {
    let Ok(dir) = std::env::var("FLATCUT_BENCH_DIR") else {
        let mesh = testmesh::spherical_cap(100.0, 1.0, 12);
        for m in methods() {
            let f = flatten(&mesh, &FlattenParams::new(m)).expect("flatten");
            let obj = write_obj(&mesh, &f.uv);
            let back = read_obj(&obj);
            assert_eq!(back.triangles, mesh.triangles);
            assert_eq!(f.uv.len(), mesh.positions.len());
        }
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("bench dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.ends_with(".obj") && name.matches('.').count() == 1
        })
        .collect();
    files.sort();
    for path in files {
        let mesh = read_obj(&std::fs::read_to_string(&path).expect("read"));
        for m in methods() {
            let t0 = Instant::now();
            let r = flatten(&mesh, &FlattenParams::new(m));
            let s = t0.elapsed().as_secs_f64();
            match r {
                Ok(f) => {
                    let out = path.with_extension(format!("{}.obj", m.name()));
                    std::fs::write(&out, write_obj(&mesh, &f.uv)).expect("write");
                    println!(
                        "{} {} {:.3} s iters={} warnings={:?}",
                        path.display(),
                        m,
                        s,
                        f.info.iterations,
                        f.info.warnings
                    );
                }
                Err(e) => println!("{} {} failed after {s:.3} s: {e}", path.display(), m),
            }
        }
    }
}
