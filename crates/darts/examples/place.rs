//! Places darts on a mesh: `place MESH.obj STRETCH COMPRESS [OUT.obj]`.

use flatcut_darts::{DartOptions, place};
use flatcut_flatten::{FlattenParams, Method, flatten};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut mesh = flatcut_mesh::read_mesh(std::path::Path::new(&args[1])).unwrap();
    mesh.flat = None;
    let s: f64 = args[2].parse().unwrap();
    let c: f64 = args[3].parse().unwrap();
    let t0 = std::time::Instant::now();
    let f = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
    let opts = DartOptions::new(Some(s), Some(c));
    match place(&mesh, &f.uv, &opts) {
        Ok(d) => {
            println!(
                "darts {} total {:.1} mm excess {:.4}% feasible {} time {:.2}s",
                d.darts.len(),
                d.total_length_mm(),
                flatcut_darts::excess_pct(d.excess),
                d.feasible,
                t0.elapsed().as_secs_f64()
            );
            for a in &d.attempts {
                println!("  attempt {:?}", a);
            }
            for dt in &d.darts {
                println!(
                    "  dart len {:.1} legs {:.3}/{:.3} opening {:.1}",
                    dt.length_3d_mm, dt.leg_2d_mm[0], dt.leg_2d_mm[1], dt.opening_mm
                );
            }
            if let Some(out) = args.get(4) {
                std::fs::write(out, flatcut_mesh::io::obj_string(&d.mesh)).unwrap();
            }
        }
        Err(e) => println!("error: {e} ({:.2}s)", t0.elapsed().as_secs_f64()),
    }
}
