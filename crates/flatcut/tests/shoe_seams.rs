//! The bundled shoe upper flattened as its pieces are sewn (the joint solve `flatcut run` uses),
//! without material limits: no piece stretches much more than it does flattened on its own, and
//! the style lines leave no sliver triangles beside them. Before the mesh around the lines was
//! tidied, the embedding left needle triangles (smallest angle 1.6°) and 0.2 mm zig-zags where
//! the vamp lines pass close to mesh vertices, and the joint solve put a 19.5 % stretch on two
//! 0.06 mm² faces of each quarter (1.5 % when the quarter is flattened alone), which made
//! `flatcut pattern patterns/shoe/design.toml` fail with a seam allowance across the quarter.

use std::path::{Path, PathBuf};

use flatcut::design::Design;
use flatcut::flatten::assembly::flatten_assembly;
use flatcut::flatten::{FlattenParams, Method, flatten};
use flatcut::geom::{DVec2, Tolerances};
use flatcut::mesh::TriMesh;
use flatcut::mesh::distortion::face_distortion;

/// Smallest angle a triangle beside a style line may have (the tessellation's own triangles
/// have 10° or more; the embedding left 1.6° before).
const MIN_ANGLE_DEG: f64 = 5.0;
/// How much more (percentage points) a piece may stretch sewn to the others than alone: the
/// seams make neighbours agree, which costs a little, never a spike.
const SEWN_EXTRA_PCT: f64 = 2.0;

fn shoe() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../patterns/shoe")
}

/// Largest stretch (σ1 − 1, in %) over the faces of a flattening.
fn worst_stretch_pct(m: &TriMesh, uv: &[DVec2]) -> f64 {
    m.triangles
        .iter()
        .filter_map(|t| {
            face_distortion(
                t.map(|v| m.positions[v as usize]),
                t.map(|v| uv[v as usize]),
            )
        })
        .map(|d| (d.sigma1 - 1.0) * 100.0)
        .fold(0.0, f64::max)
}

fn min_angle_deg(m: &TriMesh, t: [u32; 3]) -> f64 {
    let p = t.map(|v| m.positions[v as usize]);
    (0..3)
        .map(|k| {
            let (u, w) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            u.angle_between(w).to_degrees()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn the_shoe_flattened_sewn_stretches_like_its_pieces_alone_and_its_lines_leave_no_slivers() {
    let dir = shoe();
    let d = Design::load(&dir.join("design.toml")).unwrap();
    let a = d.assemble(&dir, &Tolerances::DEFAULT).unwrap();
    let meshes: Vec<&TriMesh> = a.pieces.iter().map(|p| &p.mesh).collect();
    let params = FlattenParams::new(Method::Isometric);
    let sewn = flatten_assembly(&meshes, &a.seams, &params).unwrap();
    for (k, p) in a.pieces.iter().enumerate() {
        let alone = flatten(&p.mesh, &params).unwrap();
        let (s_sewn, s_alone) = (
            worst_stretch_pct(&p.mesh, &sewn[k].uv),
            worst_stretch_pct(&p.mesh, &alone.uv),
        );
        eprintln!(
            "{}: worst stretch {s_sewn:.2} % sewn, {s_alone:.2} % alone",
            p.def.name
        );
        assert!(
            s_sewn <= s_alone + SEWN_EXTRA_PCT,
            "{}: {s_sewn:.2} % sewn against {s_alone:.2} % alone",
            p.def.name
        );
        // Triangles with a corner on a seam (a style line).
        let mut on_seam = vec![false; p.mesh.positions.len()];
        for s in &a.seams {
            for side in s.sides.iter().filter(|side| side.piece == k) {
                for &v in &side.vertices {
                    on_seam[v as usize] = true;
                }
            }
        }
        let beside: Vec<[u32; 3]> = p
            .mesh
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().any(|&v| on_seam[v as usize]))
            .collect();
        assert!(!beside.is_empty(), "{}", p.def.name);
        let worst = beside
            .iter()
            .map(|&t| min_angle_deg(&p.mesh, t))
            .fold(f64::INFINITY, f64::min);
        eprintln!("{}: smallest angle beside a line {worst:.2}°", p.def.name);
        assert!(worst >= MIN_ANGLE_DEG, "{}: {worst:.2}°", p.def.name);
    }
}
