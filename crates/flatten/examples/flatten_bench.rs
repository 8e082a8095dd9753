//! Benchmark driver: flattens meshes and prints one JSON line per mesh (faces, Newton steps,
//! solve seconds, true-scale mean δ2, flipped triangles, largest relative boundary-edge error,
//! where the time went, warnings), writing the map as OBJ (`v` + `vt`) for the bench's `metrics.py`.
//!
//! ```text
//! cargo run --release -p flatcut-flatten --example flatten_bench -- \
//!     [--method isometric] [--threads N] [--out DIR] [--time-limit S] [--trace] \
//!     [--cap RINGS] MESH.obj…
//! ```
//! `--cap RINGS` flattens a generated spherical cap of 6·RINGS² faces (radius 100 mm, geodesic
//! radius 1 rad; 408 rings ≈ 1M faces). `--threads` sizes rayon's pool (the result is the same
//! bits with any number). `--trace` prints every iteration's energy to stderr. Peak memory is
//! the process's: run one mesh per process under `/usr/bin/time -v` to measure it.
//! `tools/flatten/bench.py` runs this against libigl's SLIM in one run.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use flatcut_flatten::{FlattenHooks, FlattenParams, FlattenProgress, Method, flatten, testmesh};
use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh, face_distortion};

struct Args {
    method: Method,
    threads: Option<usize>,
    out: Option<PathBuf>,
    time_limit: Option<Duration>,
    trace: bool,
    cap: Option<usize>,
    meshes: Vec<PathBuf>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        method: Method::Isometric,
        threads: None,
        out: None,
        time_limit: None,
        trace: false,
        cap: None,
        meshes: Vec::new(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(s) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match s.as_str() {
            "--method" => {
                let m = value("--method")?;
                a.method = Method::from_name(&m).ok_or(format!("unknown method {m}"))?;
            }
            "--threads" => {
                a.threads = Some(
                    value("--threads")?
                        .parse()
                        .map_err(|e| format!("--threads: {e}"))?,
                )
            }
            "--out" => a.out = Some(PathBuf::from(value("--out")?)),
            "--time-limit" => {
                let s: f64 = value("--time-limit")?
                    .parse()
                    .map_err(|e| format!("--time-limit: {e}"))?;
                a.time_limit = Some(Duration::from_secs_f64(s));
            }
            "--trace" => a.trace = true,
            "--cap" => a.cap = Some(value("--cap")?.parse().map_err(|e| format!("--cap: {e}"))?),
            _ if s.starts_with("--") => return Err(format!("unknown option {s}")),
            _ => a.meshes.push(PathBuf::from(s)),
        }
    }
    Ok(a)
}

fn read_obj(path: &Path) -> TriMesh {
    let text = std::fs::read_to_string(path).expect("mesh file reads");
    let mut m = flatcut_mesh::io::parse_obj(&text, path).expect("mesh parses");
    m.flat = None;
    m
}

/// Area-weighted mean δ2 at true scale, flipped triangles and the largest relative
/// boundary-edge length error.
fn score(mesh: &TriMesh, uv: &[DVec2]) -> (f64, usize, f64) {
    let (mut wsum, mut asum, mut flips) = (0.0, 0.0, 0);
    for t in &mesh.triangles {
        let p = t.map(|v| mesh.positions[v as usize]);
        let q = t.map(|v| uv[v as usize]);
        let Some(d) = face_distortion(p, q) else {
            flips += 1;
            continue;
        };
        if d.flipped() {
            flips += 1;
            continue;
        }
        let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        wsum += area * d.delta2();
        asum += area;
    }
    let mut bnd = 0.0f64;
    if let Ok(topo) = Topology::build(mesh) {
        for lp in &topo.boundary_loops {
            for i in 0..lp.len() {
                let (a, b) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
                let l3 = (mesh.positions[b] - mesh.positions[a]).length();
                bnd = bnd.max(((uv[b] - uv[a]).length() - l3).abs() / l3);
            }
        }
    }
    (wsum / asum, flips, bnd)
}

fn json_str(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

fn bench(a: &Args, name: &str, mesh: &TriMesh, out: Option<PathBuf>) {
    let mut params = FlattenParams::new(a.method).with_time_limit(a.time_limit);
    if a.trace {
        let t0 = Instant::now();
        params = params.with_hooks(FlattenHooks::default().with_progress(Arc::new(
            move |p: &FlattenProgress| {
                eprintln!(
                    "{:8.3} s {} {}/{} {:.9e}",
                    t0.elapsed().as_secs_f64(),
                    p.stage,
                    p.iteration,
                    p.max_iterations,
                    p.energy
                )
            },
        )));
    }
    let t0 = Instant::now();
    let f = flatten(mesh, &params);
    let seconds = t0.elapsed().as_secs_f64();
    let f = match f {
        Ok(f) => f,
        Err(e) => {
            println!(
                "{{\"mesh\":{},\"faces\":{},\"method\":\"{}\",\"error\":{}}}",
                json_str(name),
                mesh.triangles.len(),
                a.method,
                json_str(&e.to_string())
            );
            return;
        }
    };
    let (delta2, flips, bnd) = score(mesh, &f.uv);
    let warnings: Vec<String> = f.info.warnings.iter().map(|w| json_str(w)).collect();
    let t = &f.info.timings;
    let timings = format!(
        "{{\"start\":{:.4},\"ordering\":{:.4},\"assembly\":{:.4},\"factorisation\":{:.4},\"factorisations\":{},\"solve\":{:.4},\"line_search\":{:.4}}}",
        t.start.as_secs_f64(),
        t.ordering.as_secs_f64(),
        t.assembly.as_secs_f64(),
        t.factorisation.as_secs_f64(),
        t.factorisations,
        t.solve.as_secs_f64(),
        t.line_search.as_secs_f64()
    );
    println!(
        "{{\"mesh\":{},\"faces\":{},\"method\":\"{}\",\"threads\":{},\"iterations\":{},\"seconds\":{seconds:.4},\"delta2_mean\":{delta2:.9e},\"flips\":{flips},\"boundary_rel_max\":{bnd:.3e},\"timings\":{timings},\"warnings\":[{}]}}",
        json_str(name),
        mesh.triangles.len(),
        a.method,
        rayon::current_num_threads(),
        f.info.iterations,
        warnings.join(",")
    );
    if let Some(out) = out {
        let mut m = mesh.clone();
        m.flat = Some(f.uv);
        if let Err(e) = std::fs::write(&out, flatcut_mesh::io::obj_string(&m)) {
            eprintln!("bench: {}: {e}", out.display());
            std::process::exit(1);
        }
    }
}

fn main() {
    let a = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("bench: {e}");
            std::process::exit(2);
        }
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = a.threads {
        pool = pool.num_threads(n);
    }
    if let Some(dir) = &a.out
        && let Err(e) = std::fs::create_dir_all(dir)
    {
        eprintln!("bench: --out {}: {e}", dir.display());
        std::process::exit(2);
    }
    let pool = pool.build().expect("thread pool");
    pool.install(|| {
        let out_for = |stem: &str| {
            a.out
                .as_ref()
                .map(|d| d.join(format!("{stem}.{}.flatcut.obj", a.method)))
        };
        if let Some(rings) = a.cap {
            let mesh = testmesh::spherical_cap(100.0, 1.0, rings);
            let name = format!("cap_{}", mesh.triangles.len());
            bench(&a, &name, &mesh, out_for(&name));
        }
        for p in &a.meshes {
            let mesh = read_obj(p);
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            bench(&a, &stem, &mesh, out_for(&stem));
        }
    });
}
