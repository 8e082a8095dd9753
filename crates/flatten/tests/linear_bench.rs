//! Bench driver for the linear methods: with `FLATCUT_BENCH_DIR=/path/to/meshes` it flattens
//! every `*.obj` there (not already an output) with each method of `FLATCUT_BENCH_METHODS`
//! (default `lscm,arap,conformal-boundary`), prints the solve time and writes
//! `NAME.METHOD.obj` (`v` + `vt`) next to it for the bench's `metrics.py`. Without it, it runs
//! the same path on a generated cap. Run with
//! `cargo test -p flatcut-flatten --test linear_bench -- --nocapture`.

use std::time::Instant;

use flatcut_flatten::{FlattenParams, Method, flatten, testmesh};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;

fn read_obj(text: &str) -> TriMesh {
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|s| s.parse().expect("number")).collect();
                pos.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let v: Vec<u32> = it
                    .map(|s| {
                        s.split('/')
                            .next()
                            .unwrap_or("")
                            .parse::<u32>()
                            .expect("index")
                            - 1
                    })
                    .collect();
                for k in 1..v.len() - 1 {
                    tris.push([v[0], v[k], v[k + 1]]);
                }
            }
            _ => {}
        }
    }
    TriMesh::new(pos, tris)
}

fn write_obj(mesh: &TriMesh, uv: &[DVec2]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for p in &mesh.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for q in uv {
        let _ = writeln!(s, "vt {} {}", q.x, q.y);
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "f {0}/{0} {1}/{1} {2}/{2}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
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
