//! Shared helpers of the flatcut-step tests: the OpenCASCADE reference files and point-to-mesh
//! distances.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use flatcut_geom::DVec3;
use flatcut_mesh::TriMesh;
use serde::Deserialize;

/// One face as OpenCASCADE reports it (tools/step/make_models.py).
#[derive(Debug, Deserialize)]
pub struct RefFace {
    #[serde(rename = "type")]
    pub kind: String,
    pub area_mm2: f64,
    pub centroid: [f64; 3],
    pub bbox: [[f64; 3]; 2],
    pub samples: Vec<[f64; 3]>,
}

/// A model's reference figures.
#[derive(Debug, Deserialize)]
pub struct Reference {
    pub model: String,
    pub unit: String,
    pub shells: usize,
    pub faces: Vec<RefFace>,
    pub edges: usize,
}

pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

pub fn reference(name: &str) -> Reference {
    let text = std::fs::read_to_string(data_dir().join(format!("{name}.ref.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The models written by tools/step/make_models.py.
pub const MODELS: [&str; 10] = [
    "dome",
    "cylinder",
    "cone",
    "torus",
    "sphere_cap",
    "extrusion",
    "revolution",
    "hull",
    "fillet_box",
    "bracket_inch",
];

/// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5).
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Distances from points to a triangle mesh, with a uniform grid over the triangles' boxes.
pub struct MeshDistance<'a> {
    mesh: &'a TriMesh,
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    cells: Vec<Vec<u32>>,
}

impl<'a> MeshDistance<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let b = mesh.bbox();
        let n = mesh.triangles.len().max(1) as f64;
        let ext = (b.max - b.min).max(DVec3::splat(1e-9));
        let cell = (ext.x * ext.y * ext.z / n)
            .cbrt()
            .max(ext.max_element() / 256.0)
            * 2.0;
        let dims = [0, 1, 2].map(|k| ((ext[k] / cell).ceil() as usize).clamp(1, 512));
        let mut cells = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let lo = b.min;
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = tri.map(|v| mesh.positions[v as usize]);
            let tmin = p[0].min(p[1]).min(p[2]);
            let tmax = p[0].max(p[1]).max(p[2]);
            let i0 = [0, 1, 2].map(|k| (((tmin[k] - lo[k]) / cell) as usize).min(dims[k] - 1));
            let i1 = [0, 1, 2].map(|k| (((tmax[k] - lo[k]) / cell) as usize).min(dims[k] - 1));
            for x in i0[0]..=i1[0] {
                for y in i0[1]..=i1[1] {
                    for z in i0[2]..=i1[2] {
                        cells[(x * dims[1] + y) * dims[2] + z].push(t as u32);
                    }
                }
            }
        }
        Self {
            mesh,
            lo,
            cell,
            dims,
            cells,
        }
    }

    /// Distance from p to the mesh (searching growing shells of cells).
    pub fn distance(&self, p: DVec3) -> f64 {
        let c = [0, 1, 2].map(|k| ((p[k] - self.lo[k]) / self.cell).floor() as isize);
        let mut best = f64::INFINITY;
        let maxr = *self.dims.iter().max().unwrap() as isize + 1;
        for r in 0..=maxr {
            for x in c[0] - r..=c[0] + r {
                for y in c[1] - r..=c[1] + r {
                    for z in c[2] - r..=c[2] + r {
                        let on_shell =
                            (x - c[0]).abs() == r || (y - c[1]).abs() == r || (z - c[2]).abs() == r;
                        if !on_shell {
                            continue;
                        }
                        if x < 0 || y < 0 || z < 0 {
                            continue;
                        }
                        let (x, y, z) = (x as usize, y as usize, z as usize);
                        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
                            continue;
                        }
                        for &t in &self.cells[(x * self.dims[1] + y) * self.dims[2] + z] {
                            let [a, b, cc] = self.mesh.corners(t as usize);
                            best = best.min(closest_on_triangle(p, a, b, cc).distance(p));
                        }
                    }
                }
            }
            // Everything within r cells has been seen.
            if best <= r as f64 * self.cell {
                break;
            }
        }
        best
    }
}

/// The area-weighted centroid of a mesh.
pub fn centroid(mesh: &TriMesh) -> DVec3 {
    let (mut c, mut a) = (DVec3::ZERO, 0.0);
    for t in 0..mesh.triangles.len() {
        let [p, q, r] = mesh.corners(t);
        let w = 0.5 * (q - p).cross(r - p).length();
        c += (p + q + r) / 3.0 * w;
        a += w;
    }
    c / a
}

/// A Python that has cadquery-ocp (OpenCASCADE): `$FLATCUT_PYTHON`, else `python3`; `None`
/// (with the reason printed) when there is none, so the caller skips its check.
pub fn python_with_occt() -> Option<std::ffi::OsString> {
    let py = std::env::var_os("FLATCUT_PYTHON").unwrap_or_else(|| "python3".into());
    let ok = std::process::Command::new(&py)
        .args(["-c", "import OCP"])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        Some(py)
    } else {
        eprintln!(
            "SKIPPED: needs a Python with cadquery-ocp (pip install -r tools/requirements.txt, or set FLATCUT_PYTHON)"
        );
        None
    }
}
