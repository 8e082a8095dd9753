//! Times reading and tessellating STEP models (the flatcut side of tools/step/bench.py): for each
//! file, the median (and the fastest) over several runs of `Model::read` + `Tessellation::new` of every face at the
//! chordal tolerance, one JSON line per file (with, outside the timing, the faces' area on their
//! trimmed domains, their repairs and the open edges of the welded closed shells); with
//! `--obj DIR` the meshes are written as OBJ with one group per face (`g face<N>`) for the
//! accuracy check, with `DIR/<name>.faces.json` beside: per face its index, `#id`, surface,
//! area on its trimmed domain (`area_mm2`, [`face_area`]), the area the mesh's chord loops
//! bound (`chord_loops_area_mm2`) and repairs (tools/step/check_faces.py).
//!
//! `cargo run --release -p flatcut-step --example step_bench -- [--chord 0.1] [--angle RAD] [--runs 5] [--obj DIR] FILE…`
//! (`--angle`: the largest turn of the normal across a triangle, default flatcut's 20°)

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use flatcut_geom::Tolerances;
use flatcut_mesh::tessellate::TessOptions;
use flatcut_step::{Model, Tessellation, face_area};

fn main() {
    let mut chord = 0.1;
    let mut opts = TessOptions::DEFAULT;
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
            "--angle" => {
                opts = opts.with_max_normal_turn(
                    args.next()
                        .and_then(|x| x.parse().ok())
                        .expect("--angle RADIANS"),
                )
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
        let mut failed = None;
        for _ in 0..runs.max(1) {
            let t0 = Instant::now();
            let run = Model::read(&f).and_then(|model| {
                let all: Vec<usize> = (0..model.faces.len()).collect();
                Tessellation::new(&model, &all, &tol, &opts).map(|t| (model, t))
            });
            times.push(t0.elapsed().as_secs_f64());
            match run {
                Ok(x) => last = Some(x),
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        times.sort_by(f64::total_cmp);
        let Some((model, t)) = last.filter(|_| failed.is_none()) else {
            let why = failed.map(|e| e.to_string()).unwrap_or_default();
            println!("{{\"file\": \"{}\", \"error\": {:?}}}", f.display(), why);
            continue;
        };
        let triangles: usize = t.faces.iter().map(|f| f.mesh.triangles.len()).sum();
        let area: f64 = (0..model.faces.len())
            .map(|i| face_area(&model, i).expect("area of a tessellated face"))
            .sum();
        let repairs: usize = t.faces.iter().map(|f| f.repairs.len()).sum();
        println!(
            "{{\"file\": \"{}\", \"faces\": {}, \"triangles\": {}, \"vertices\": {}, \"seconds\": {:.6}, \"min_seconds\": {:.6}, \"area_mm2\": {area}, \"repairs\": {repairs}, \"open_edges\": {}}}",
            f.display(),
            t.faces.len(),
            triangles,
            t.positions.len(),
            times[times.len() / 2],
            times[0],
            t.open_edges(&model)
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
            let faces: Vec<serde_json::Value> = t
                .faces
                .iter()
                .map(|fm| {
                    serde_json::json!({
                        "face": fm.face,
                        "entity": model.faces[fm.face].entity,
                        "surface": model.face(fm.face).map(|g| g.surface.name()).unwrap_or(""),
                        "area_mm2": face_area(&model, fm.face).expect("area of a tessellated face"),
                        "chord_loops_area_mm2": fm.trim_area_mm2,
                        "repairs": fm.repairs,
                    })
                })
                .collect();
            std::fs::write(
                dir.join(format!("{name}.faces.json")),
                serde_json::to_string_pretty(&faces).expect("json"),
            )
            .expect("writable");
        }
    }
}
