//! Times reading and tessellating STEP models (the flatcut side of tools/step/bench.py): for each
//! file, the median over several runs of `Model::read` + `Tessellation::new` of every face at the
//! chordal tolerance, one JSON line per file; with `--obj DIR` the meshes are written as OBJ with
//! one group per face (`g face<N>`) for the accuracy check.
//!
//! `cargo run --release -p flatcut-step --example step_bench -- [--chord 0.1] [--runs 5] [--obj DIR] FILE…`

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use flatcut_geom::Tolerances;
use flatcut_mesh::tessellate::TessOptions;
use flatcut_step::{Model, Tessellation};

fn main() {
    let mut chord = 0.1;
    let mut runs = 5usize;
    let mut obj: Option<PathBuf> = None;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--chord" => {
                chord = args
                    .next()
                    .and_then(|x| x.parse().ok())
                    .expect("--chord MM")
            }
            "--runs" => runs = args.next().and_then(|x| x.parse().ok()).expect("--runs N"),
            "--obj" => obj = args.next().map(PathBuf::from),
            _ => files.push(PathBuf::from(a)),
        }
    }
    let tol = Tolerances::DEFAULT.with_chord_mm(chord);
    for f in files {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..runs.max(1) {
            let t0 = Instant::now();
            let model = Model::read(&f).expect("readable model");
            let all: Vec<usize> = (0..model.faces.len()).collect();
            let t =
                Tessellation::new(&model, &all, &tol, &TessOptions::DEFAULT).expect("tessellates");
            times.push(t0.elapsed().as_secs_f64());
            last = Some(t);
        }
        times.sort_by(f64::total_cmp);
        let t = last.expect("one run");
        let triangles: usize = t.faces.iter().map(|f| f.mesh.triangles.len()).sum();
        println!(
            "{{\"file\": \"{}\", \"faces\": {}, \"triangles\": {}, \"vertices\": {}, \"seconds\": {:.6}}}",
            f.display(),
            t.faces.len(),
            triangles,
            t.positions.len(),
            times[times.len() / 2]
        );
        if let Some(dir) = &obj {
            let mut s = String::new();
            for p in &t.positions {
                let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
            }
            for fm in &t.faces {
                let _ = writeln!(s, "g face{}", fm.face);
                for tri in &fm.mesh.triangles {
                    let g = tri.map(|v| fm.global[v as usize] + 1);
                    let _ = writeln!(s, "f {} {} {}", g[0], g[1], g[2]);
                }
            }
            let name = f
                .file_stem()
                .map(|x| x.to_string_lossy().into_owned())
                .unwrap_or_default();
            std::fs::create_dir_all(dir).expect("output directory");
            std::fs::write(dir.join(format!("{name}.obj")), s).expect("writable");
        }
    }
}
