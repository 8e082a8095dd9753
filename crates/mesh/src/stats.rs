//! Per-vertex differential quantities and whole-mesh statistics (what `inspect` reports).
//!
//! Curvature follows Meyer, Desbrun, Schröder and Barr, "Discrete differential-geometry operators
//! for triangulated 2-manifolds" (2003): Gaussian curvature is the angle defect over the mixed
//! (Voronoi, or barycentric-corrected for obtuse triangles) area; the mean curvature vector is the
//! cotangent Laplacian of the position, H = (Δx · n)/2 with the sign convention of the seed texts:
//! positive when the surface bends towards its normal (a cylinder with inward normals has
//! H = +1/(2r)). Boundary vertices have no curvature estimate (their angle defect measures the
//! boundary's turning, not the surface).

use flatcut_geom::{Aabb3, DVec3};

use crate::TriMesh;

/// Area-weighted vertex normals (unit, or zero for a vertex without non-degenerate triangles).
pub fn vertex_normals(mesh: &TriMesh) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = mesh.corners(t);
        let w = (b - a).cross(c - a);
        for &v in tri {
            n[v as usize] += w;
        }
    }
    n.into_iter().map(|x| x.normalize_or_zero()).collect()
}

/// Number of distinct edge neighbours of each vertex.
pub fn vertex_valence(mesh: &TriMesh) -> Vec<usize> {
    crate::seams::vertex_neighbours(mesh)
        .iter()
        .map(|l| l.len())
        .collect()
}

/// True for each vertex on a boundary edge (an edge with one incident triangle).
pub fn boundary_vertices(mesh: &TriMesh) -> Vec<bool> {
    let mut count: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut on = vec![false; mesh.positions.len()];
    for (&(a, b), &c) in &count {
        if c == 1 {
            on[a as usize] = true;
            on[b as usize] = true;
        }
    }
    on
}

/// Total length of the boundary edges in mm.
pub fn boundary_length(mesh: &TriMesh) -> f64 {
    let mut count: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    count
        .iter()
        .filter(|(_, c)| **c == 1)
        .map(|(&(a, b), _)| mesh.positions[a as usize].distance(mesh.positions[b as usize]))
        .sum()
}

/// Per-vertex angle sum, mixed area and cotangent Laplacian of the position.
struct Local {
    angle: Vec<f64>,
    area: Vec<f64>,
    lap: Vec<DVec3>,
}

fn local(mesh: &TriMesh) -> Local {
    let n = mesh.positions.len();
    let mut angle = vec![0.0; n];
    let mut area = vec![0.0; n];
    let mut lap = vec![DVec3::ZERO; n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let p = mesh.corners(t);
        let tri_area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        if tri_area.is_nan() || tri_area <= 0.0 {
            continue;
        }
        let ang: [f64; 3] = std::array::from_fn(|k| {
            let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            e1.angle_between(e2)
        });
        let cot: [f64; 3] = std::array::from_fn(|k| {
            let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            e1.dot(e2) / e1.cross(e2).length()
        });
        let obtuse = ang.iter().position(|&a| a > std::f64::consts::FRAC_PI_2);
        for k in 0..3 {
            let v = tri[k] as usize;
            angle[v] += ang[k];
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            // Edge k->i is opposite corner j; edge k->j opposite corner i.
            let (dki, dkj) = (p[i] - p[k], p[j] - p[k]);
            lap[v] += dki * cot[j] + dkj * cot[i];
            area[v] += match obtuse {
                None => (dki.length_squared() * cot[j] + dkj.length_squared() * cot[i]) / 8.0,
                Some(o) if o == k => tri_area / 2.0,
                Some(_) => tri_area / 4.0,
            };
        }
    }
    Local { angle, area, lap }
}

/// Discrete Gaussian curvature (1/mm²) per vertex; `None` on the boundary and for isolated
/// vertices.
pub fn gaussian_curvature(mesh: &TriMesh) -> Vec<Option<f64>> {
    let l = local(mesh);
    let bnd = boundary_vertices(mesh);
    (0..mesh.positions.len())
        .map(|v| {
            (!bnd[v] && l.area[v] > 0.0)
                .then(|| (2.0 * std::f64::consts::PI - l.angle[v]) / l.area[v])
        })
        .collect()
}

/// Discrete mean curvature (1/mm) per vertex, signed (positive when the surface bends towards
/// the vertex normal); `None` on the boundary and for isolated vertices.
pub fn mean_curvature(mesh: &TriMesh) -> Vec<Option<f64>> {
    let l = local(mesh);
    let bnd = boundary_vertices(mesh);
    let normals = vertex_normals(mesh);
    (0..mesh.positions.len())
        .map(|v| {
            (!bnd[v] && l.area[v] > 0.0)
                .then(|| (l.lap[v] / (2.0 * l.area[v])).dot(normals[v]) / 2.0)
        })
        .collect()
}

/// Summary of a mesh for `inspect`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshStats {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Surface area in mm².
    pub area: f64,
    /// Bounding box of the vertices (mm).
    pub bbox: Aabb3,
    /// Number of boundary loops (0 for a closed surface); `None` if the topology is invalid.
    pub boundary_loops: Option<usize>,
    /// Connected components; `None` if the topology is invalid.
    pub components: Option<usize>,
    /// Euler characteristic V − E + F over the used vertices.
    pub euler: i64,
    /// Total boundary length in mm.
    pub boundary_length: f64,
    /// Shortest, mean and longest edge in mm.
    pub edge_min: f64,
    /// Mean edge length in mm.
    pub edge_mean: f64,
    /// Longest edge in mm.
    pub edge_max: f64,
    /// Most triangles around one vertex.
    pub valence_max: usize,
    /// Range of the interior vertices' Gaussian curvature (1/mm²), if any interior vertex.
    pub gaussian_range: Option<(f64, f64)>,
    /// Range of the interior vertices' mean curvature (1/mm).
    pub mean_range: Option<(f64, f64)>,
    /// Total angle defect of the interior vertices (radians); 2πχ for a closed surface.
    pub total_angle_defect: f64,
    /// Whether the mesh carries a flattening (`vt`).
    pub has_flat: bool,
}

impl std::fmt::Display for MeshStats {
    /// A human-readable summary, one fact per line (what `inspect` prints for a mesh).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let opt = |x: Option<usize>| x.map_or("invalid topology".to_string(), |v| v.to_string());
        writeln!(f, "vertices          {}", self.vertices)?;
        writeln!(f, "triangles         {}", self.triangles)?;
        writeln!(f, "area              {:.3} mm²", self.area)?;
        let s = self.bbox.size();
        writeln!(
            f,
            "bounding box      {:.3} x {:.3} x {:.3} mm",
            s.x, s.y, s.z
        )?;
        writeln!(f, "components        {}", opt(self.components))?;
        writeln!(f, "boundary loops    {}", opt(self.boundary_loops))?;
        writeln!(f, "boundary length   {:.3} mm", self.boundary_length)?;
        writeln!(f, "euler             {}", self.euler)?;
        writeln!(
            f,
            "edges             {:.4} / {:.4} / {:.4} mm (min / mean / max)",
            self.edge_min, self.edge_mean, self.edge_max
        )?;
        writeln!(f, "max valence       {}", self.valence_max)?;
        if let Some((lo, hi)) = self.gaussian_range {
            writeln!(f, "gaussian K        {lo:.3e} .. {hi:.3e} 1/mm²")?;
        }
        if let Some((lo, hi)) = self.mean_range {
            writeln!(f, "mean H            {lo:.3e} .. {hi:.3e} 1/mm")?;
        }
        writeln!(f, "angle defect      {:.6} rad", self.total_angle_defect)?;
        write!(
            f,
            "flattening (vt)   {}",
            if self.has_flat { "yes" } else { "no" }
        )
    }
}

fn range(v: &[Option<f64>]) -> Option<(f64, f64)> {
    v.iter().flatten().fold(None, |acc, &x| match acc {
        None => Some((x, x)),
        Some((lo, hi)) => Some((lo.min(x), hi.max(x))),
    })
}

impl MeshStats {
    /// Computes the statistics. Never fails: invalid topology is reported as `None` fields.
    pub fn of(mesh: &TriMesh) -> MeshStats {
        let topo = crate::Topology::build(mesh).ok();
        let mut edges: std::collections::BTreeSet<(u32, u32)> = Default::default();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        let n = mesh.positions.len();
        let lens: Vec<f64> = edges
            .iter()
            .filter(|(a, b)| (*a as usize) < n && (*b as usize) < n)
            .map(|&(a, b)| mesh.positions[a as usize].distance(mesh.positions[b as usize]))
            .collect();
        let used = {
            let mut u = vec![false; n];
            for t in &mesh.triangles {
                for &v in t {
                    if (v as usize) < n {
                        u[v as usize] = true;
                    }
                }
            }
            u.iter().filter(|&&x| x).count() as i64
        };
        let k = gaussian_curvature(mesh);
        let l = local(mesh);
        let bnd = boundary_vertices(mesh);
        let total_angle_defect = (0..n)
            .filter(|&v| !bnd[v] && l.area[v] > 0.0)
            .map(|v| 2.0 * std::f64::consts::PI - l.angle[v])
            .sum();
        MeshStats {
            vertices: n,
            triangles: mesh.triangles.len(),
            area: mesh.area(),
            bbox: mesh.bbox(),
            boundary_loops: topo.as_ref().map(|t| t.boundary_loops.len()),
            components: topo.as_ref().map(|t| t.component_count),
            euler: used - edges.len() as i64 + mesh.triangles.len() as i64,
            boundary_length: boundary_length(mesh),
            edge_min: lens
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
                .min(f64::MAX),
            edge_mean: if lens.is_empty() {
                0.0
            } else {
                lens.iter().sum::<f64>() / lens.len() as f64
            },
            edge_max: lens.iter().copied().fold(0.0, f64::max),
            valence_max: vertex_valence(mesh).into_iter().max().unwrap_or(0),
            gaussian_range: range(&k),
            mean_range: range(&mean_curvature(mesh)),
            total_angle_defect,
            has_flat: mesh.flat.is_some(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{cut_along_seams, tessellate};
    use flatcut_geom::Tolerances;
    use flatcut_surface::{Domain2, ParamSurface, SurfaceDerivs};
    use std::f64::consts::PI;

    /// Cylinder (r cos v, r sin v, u) as in TV28: normal su × sv points inwards.
    #[derive(Debug)]
    struct Cyl(f64);
    impl ParamSurface for Cyl {
        fn domain(&self) -> Domain2 {
            Domain2 {
                u: (0.0, 60.0),
                v: (0.0, 2.0 * PI),
            }
        }
        fn eval(&self, u: f64, v: f64) -> DVec3 {
            DVec3::new(self.0 * v.cos(), self.0 * v.sin(), u)
        }
        fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
            (
                self.eval(u, v),
                DVec3::Z,
                DVec3::new(-self.0 * v.sin(), self.0 * v.cos(), 0.0),
            )
        }
        fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
            let (p, su, sv) = self.deriv1(u, v);
            SurfaceDerivs {
                p,
                su,
                sv,
                ..Default::default()
            }
        }
    }

    /// Closed sphere of radius r as a latitude–longitude mesh with pole vertices.
    fn uv_sphere(r: f64, n: usize, m: usize) -> TriMesh {
        let mut p = vec![DVec3::new(0.0, 0.0, r)];
        for j in 1..m {
            let th = PI * j as f64 / m as f64;
            for i in 0..n {
                let ph = 2.0 * PI * i as f64 / n as f64;
                p.push(r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
            }
        }
        p.push(DVec3::new(0.0, 0.0, -r));
        let ring = |j: usize, i: usize| (1 + (j - 1) * n + i % n) as u32;
        let south = (p.len() - 1) as u32;
        let mut t = Vec::new();
        for i in 0..n {
            t.push([0, ring(1, i), ring(1, i + 1)]);
            t.push([ring(m - 1, i), south, ring(m - 1, i + 1)]);
        }
        for j in 1..m - 1 {
            for i in 0..n {
                t.push([ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)]);
                t.push([ring(j, i), ring(j + 1, i + 1), ring(j, i + 1)]);
            }
        }
        TriMesh::new(p, t)
    }

    #[test]
    fn closed_sphere_obeys_gauss_bonnet_and_curvatures_match() {
        let m = uv_sphere(50.0, 48, 24);
        let s = MeshStats::of(&m);
        assert_eq!(s.euler, 2);
        assert_eq!(s.boundary_loops, Some(0));
        assert!((s.total_angle_defect - 4.0 * PI).abs() < 1e-9);
        let text = s.to_string();
        assert!(text.contains("boundary loops    0") && text.contains("euler             2"));
        assert!((s.area - 4.0 * PI * 2500.0).abs() / (4.0 * PI * 2500.0) < 1e-2);
        // Away from the poles K ≈ 1/r², H ≈ −1/r (outward normals bend away).
        let k = gaussian_curvature(&m);
        let h = mean_curvature(&m);
        let normals = vertex_normals(&m);
        for v in 1..m.vertex_count() - 1 {
            let z = m.positions[v].z / 50.0;
            if z.abs() < 0.7 {
                let kv = k[v].unwrap();
                assert!((kv * 2500.0 - 1.0).abs() < 0.02, "K {kv}");
                let hv = h[v].unwrap();
                assert!((hv * 50.0 + 1.0).abs() < 0.02, "H {hv}");
                assert!(normals[v].dot(m.positions[v] / 50.0) > 0.999);
            }
        }
    }

    #[test]
    fn cylinder_has_zero_gaussian_and_tv28_mean_curvature() {
        // TV28: cylinder (2 cos v, 2 sin v, u): K = 0, H = 1/4 (normal su × sv inwards). At
        // r = 20: H = 1/40.
        let m = tessellate(&Cyl(20.0), &Tolerances::DEFAULT.with_chord_mm(0.02)).unwrap();
        let s = MeshStats::of(&m);
        let (k0, k1) = s.gaussian_range.unwrap();
        assert!(k0.abs() < 1e-6 && k1.abs() < 1e-6, "{k0} {k1}");
        let h = mean_curvature(&m);
        let inner: Vec<f64> = h.iter().flatten().copied().collect();
        assert!(!inner.is_empty());
        let mean = inner.iter().sum::<f64>() / inner.len() as f64;
        assert!((mean * 40.0 - 1.0).abs() < 0.02, "mean H {mean}");
        assert_eq!(s.boundary_loops, Some(1));
        let exact = 2.0 * (60.0 + 2.0 * PI * 20.0);
        assert!((s.boundary_length - exact).abs() / exact < 1e-3);
    }

    #[test]
    fn valence_and_normals_of_a_flat_fan() {
        let m = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y],
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]],
        );
        assert_eq!(vertex_valence(&m), vec![4, 3, 3, 3, 3]);
        assert!(vertex_normals(&m).iter().all(|n| *n == DVec3::Z));
        assert_eq!(gaussian_curvature(&m)[0], Some(0.0));
        let cut = cut_along_seams(&m, &[vec![0, 1]]).unwrap();
        assert_eq!(MeshStats::of(&cut).boundary_loops, Some(1));
    }
}
