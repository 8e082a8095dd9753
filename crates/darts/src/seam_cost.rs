//! What a seam costs the maker: its length (sewing work), its visibility and its straightness.
//!
//! Visibility is a factor per vertex, multiplied into the length of the seam through it:
//! - **curvature**: a seam in a concave crease (a limb's armpit, the neck, under a chin) hides in
//!   the fold; one over a convex bulge shows. The mean curvature at a vertex (the umbrella
//!   operator along the vertex normal) made scale-free by the radius of the sphere of the same
//!   area gives the factor `1 + CURVATURE_WEIGHT · tanh(κ·R)`: ½ deep in a crease, 1 where flat,
//!   1½ on a sharp bulge;
//! - **a hidden side** (the design's `seam_hidden` direction, e.g. the underside `[0, 0, -1]`):
//!   `1 − ¼(1 + n·d)` → ½ facing it, 1 facing away;
//! - **hidden regions** (the design's `seam_hidden_regions`): [`HIDDEN_REGION`] inside;
//! - **no_cut** regions: [`NO_CUT`], so a cut that must open the surface goes round them if it
//!   can (the splits refuse them outright).
//!
//! A seam's cost is its visibility-weighted length plus [`TURN_MM_PER_RAD`] millimetres per
//! radian it turns on the surface (a straight seam is cut and sewn faster).

use flatcut_geom::DVec3;
use flatcut_mesh::TriMesh;
use flatcut_mesh::nearest::Bvh;

/// How far curvature moves the visibility factor (±).
pub const CURVATURE_WEIGHT: f64 = 0.5;
/// Visibility factor inside a design's hidden region.
pub const HIDDEN_REGION: f64 = 0.3;
/// Visibility factor of a no_cut vertex: far dearer than any detour.
pub const NO_CUT: f64 = 1000.0;
/// Cost of turning, in millimetres of seam per radian.
pub const TURN_MM_PER_RAD: f64 = 5.0;

/// Where seams should hide.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Visibility {
    /// The side seams should face (unit vector), e.g. the underside.
    pub hidden_dir: Option<DVec3>,
    /// Vertices of the surface in a hidden region (indexed like the mesh), or empty.
    pub hidden: Vec<bool>,
    /// Vertices no cut should pass (no_cut regions, marks), or empty.
    pub blocked: Vec<bool>,
}

impl Visibility {
    /// The visibility factor of every vertex of `mesh` (see the module documentation).
    pub fn vertex_factors(&self, mesh: &TriMesh) -> Vec<f64> {
        let (normals, curvature) = normals_and_curvature(mesh);
        let radius = (mesh.area() / (4.0 * std::f64::consts::PI)).sqrt();
        (0..mesh.positions.len())
            .map(|v| {
                let mut f = 1.0 + CURVATURE_WEIGHT * (curvature[v] * radius).tanh();
                if let Some(d) = self.hidden_dir {
                    f *= 1.0 - 0.25 * (1.0 + normals[v].dot(d));
                }
                if self.hidden.get(v).copied().unwrap_or(false) {
                    f *= HIDDEN_REGION;
                }
                if self.blocked.get(v).copied().unwrap_or(false) {
                    f = NO_CUT;
                }
                f
            })
            .collect()
    }
}

/// A seam's length (mm), visibility-weighted length (mm) and turning (rad).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SeamCost {
    /// Length along the surface (mm).
    pub length_mm: f64,
    /// Length weighted by each point's visibility factor (mm; at most `length_mm` where the
    /// factors are at most 1).
    pub visible_mm: f64,
    /// Sum of the angles between consecutive segments (radians; 0 for a straight seam).
    pub turning_rad: f64,
}

impl SeamCost {
    /// The cost that ranks seams: the visible length plus the turning's price.
    pub fn total(&self) -> f64 {
        self.visible_mm + TURN_MM_PER_RAD * self.turning_rad
    }

    /// The cost of the seam through `points` (3D, on the surface of `mesh`), each point taking
    /// the factor of its nearest vertex in `factors`.
    pub fn of_points(mesh: &TriMesh, factors: &[f64], points: &[DVec3]) -> Self {
        Self::of_points_in(
            mesh,
            &Bvh::new(&mesh.positions, &mesh.triangles),
            factors,
            points,
        )
    }

    /// [`SeamCost::of_points`] with the nearest-point hierarchy of `mesh` already built (`bvh`,
    /// from its positions and triangles): a split costs dozens of candidate cuts of one surface
    /// at every step, and building the hierarchy of a 100k-face scan for each took longer than
    /// costing the cut.
    pub fn of_points_in(mesh: &TriMesh, bvh: &Bvh, factors: &[f64], points: &[DVec3]) -> Self {
        let f: Vec<f64> = points
            .iter()
            .map(|&p| {
                bvh.nearest(&mesh.positions, &mesh.triangles, p)
                    .and_then(|(t, b, _)| {
                        let k = if b.x >= b.y && b.x >= b.z {
                            0
                        } else if b.y >= b.z {
                            1
                        } else {
                            2
                        };
                        factors.get(mesh.triangles[t][k] as usize).copied()
                    })
                    .unwrap_or(1.0)
            })
            .collect();
        let mut c = SeamCost::default();
        for k in 1..points.len() {
            let l = points[k].distance(points[k - 1]);
            c.length_mm += l;
            c.visible_mm += l * 0.5 * (f[k] + f[k - 1]);
        }
        for k in 1..points.len().saturating_sub(1) {
            let (a, b) = (points[k] - points[k - 1], points[k + 1] - points[k]);
            if let (Some(a), Some(b)) = (a.try_normalize(), b.try_normalize()) {
                c.turning_rad += a.dot(b).clamp(-1.0, 1.0).acos();
            }
        }
        c
    }
}

/// Area-weighted vertex normals and the mean curvature at every vertex (1/mm, positive on a
/// bulge), from the umbrella operator: twice the offset of a vertex from the mean of its
/// neighbours along its normal over their mean squared distance.
fn normals_and_curvature(mesh: &TriMesh) -> (Vec<DVec3>, Vec<f64>) {
    let n = mesh.positions.len();
    let mut normals = vec![DVec3::ZERO; n];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let w = (b - a).cross(c - a);
        for &v in t {
            normals[v as usize] += w;
        }
    }
    let normals: Vec<DVec3> = normals
        .into_iter()
        .map(|v| v.try_normalize().unwrap_or(DVec3::ZERO))
        .collect();
    let adj = flatcut_mesh::seams::vertex_neighbours(mesh);
    let curvature = (0..n)
        .map(|v| {
            let p = mesh.positions[v];
            let k = adj[v].len();
            if k == 0 {
                return 0.0;
            }
            let mean = adj[v]
                .iter()
                .map(|&w| mesh.positions[w as usize])
                .sum::<DVec3>()
                / k as f64;
            let d2 = adj[v]
                .iter()
                .map(|&w| mesh.positions[w as usize].distance_squared(p))
                .sum::<f64>()
                / k as f64;
            if d2 <= 0.0 {
                0.0
            } else {
                2.0 * (p - mean).dot(normals[v]) / d2
            }
        })
        .collect();
    (normals, curvature)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron subdivided and pushed onto a sphere of radius `r` (outward triangles).
    fn sphere(r: f64, levels: usize) -> TriMesh {
        let mut p = vec![
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        let mut t: Vec<[u32; 3]> = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        for _ in 0..levels {
            let mut mid = std::collections::BTreeMap::new();
            let mut next = Vec::new();
            for tri in &t {
                let m: Vec<u32> = (0..3)
                    .map(|k| {
                        let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                        *mid.entry((a, b)).or_insert_with(|| {
                            p.push((p[a as usize] + p[b as usize]).normalize());
                            (p.len() - 1) as u32
                        })
                    })
                    .collect();
                next.push([tri[0], m[0], m[2]]);
                next.push([m[0], tri[1], m[1]]);
                next.push([m[2], m[1], tri[2]]);
                next.push([m[0], m[1], m[2]]);
            }
            t = next;
        }
        TriMesh::new(p.into_iter().map(|v| v * r).collect(), t)
    }

    #[test]
    fn a_sphere_bulges_everywhere_and_its_underside_is_cheaper() {
        let m = sphere(50.0, 4);
        let plain = Visibility::default().vertex_factors(&m);
        // κR = 1 on a sphere: every factor 1 + ½ tanh 1 ≈ 1.38.
        for f in &plain {
            assert!((f - (1.0 + 0.5 * 1f64.tanh())).abs() < 0.02, "{f}");
        }
        let under = Visibility {
            hidden_dir: Some(-DVec3::Z),
            ..Default::default()
        }
        .vertex_factors(&m);
        let (bottom, top) = (
            m.positions.iter().position(|p| p.z < -49.9).unwrap(),
            m.positions.iter().position(|p| p.z > 49.9).unwrap(),
        );
        assert!((under[bottom] / plain[bottom] - 0.5).abs() < 0.01);
        assert!((under[top] / plain[top] - 1.0).abs() < 0.01);
    }

    #[test]
    fn a_seam_costs_its_length_times_its_visibility_and_its_turns() {
        let m = sphere(50.0, 2);
        let f = vec![2.0; m.positions.len()];
        let pts = [DVec3::ZERO, DVec3::X * 10.0, DVec3::new(10.0, 10.0, 0.0)];
        let c = SeamCost::of_points(&m, &f, &pts);
        assert!((c.length_mm - 20.0).abs() < 1e-12);
        assert!((c.visible_mm - 40.0).abs() < 1e-12);
        assert!((c.turning_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((c.total() - (40.0 + TURN_MM_PER_RAD * std::f64::consts::FRAC_PI_2)).abs() < 1e-9);
    }
}
