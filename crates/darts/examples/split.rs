//! Splits a mesh into pieces within limits: `split MESH.obj STRETCH COMPRESS [OUT-PREFIX]`
//! writes `OUT-PREFIX-<k>.obj` per piece. A mesh that is not a disk (closed, of any genus, or
//! with several boundary loops) is opened first.

use flatcut_darts::limits::Band;
use flatcut_darts::split::{SplitOptions, split};
use flatcut_flatten::{FlattenParams, Method, flatten};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut mesh = flatcut_mesh::read_mesh(std::path::Path::new(&args[1])).unwrap();
    mesh.flat = None;
    let s: f64 = args[2].parse().unwrap();
    let c: f64 = args[3].parse().unwrap();
    let t0 = std::time::Instant::now();
    let params = FlattenParams::new(Method::Isometric);
    let disk = flatcut_mesh::check_disk(&mesh).is_ok();
    let max_pieces = std::env::var("MAX_PIECES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SplitOptions::DEFAULT_MAX_PIECES);
    let opts = SplitOptions {
        band: Band::from_pct(Some(s), Some(c)),
        max_pieces,
        keep_out: None,
        visibility: Default::default(),
        time_limit: None,
        seam_allowance_mm: 0.0,
    };
    let result = if !disk {
        flatcut_darts::split::split_surface(&mesh, &params, &opts)
    } else {
        let f = flatten(&mesh, &params).unwrap();
        split(&mesh, &f.uv, &params, &opts)
    };
    match result {
        Ok(r) => {
            println!(
                "pieces {} cuts {:.1} mm excess {:.4}% feasible {} time {:.2}s",
                r.pieces.len(),
                r.total_cut_mm(),
                flatcut_darts::excess_pct(r.excess),
                r.feasible,
                t0.elapsed().as_secs_f64()
            );
            for s in &r.seams {
                println!(
                    "  seam {} of {} vertices",
                    s.name,
                    s.sides[0].vertices.len()
                );
            }
            if let Some(out) = args.get(4) {
                for (k, p) in r.pieces.iter().enumerate() {
                    std::fs::write(
                        format!("{out}-{}.obj", k + 1),
                        flatcut_mesh::io::obj_string(p),
                    )
                    .unwrap();
                }
            }
        }
        Err(e) => println!("error: {e} ({:.2}s)", t0.elapsed().as_secs_f64()),
    }
}
