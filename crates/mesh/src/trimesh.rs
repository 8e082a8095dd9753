//! The indexed triangle mesh.

use flatcut_geom::{Aabb2, Aabb3, DVec2, DVec3};

/// An indexed triangle mesh: 3D positions in mm, counter-clockwise triangles, and optionally the
/// surface parameters of each vertex and a flattened 2D position of each vertex (mm).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions in mm.
    pub positions: Vec<DVec3>,
    /// Triangles as vertex indices, counter-clockwise seen from the outside (normal side).
    pub triangles: Vec<[u32; 3]>,
    /// Surface parameters (u, v) of each vertex, when the mesh was tessellated from a patch.
    pub params: Option<Vec<DVec2>>,
    /// Index of the patch each vertex came from, for multi-patch models (parallel to `params`).
    pub patch_of_vertex: Option<Vec<u32>>,
    /// A 2D position per vertex in mm: a flattening of the mesh (OBJ `vt` when read from a file).
    pub flat: Option<Vec<DVec2>>,
}

impl TriMesh {
    /// A mesh from positions and triangles, with no parameters and no flattening.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
            ..Self::default()
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// The three flattened corners of triangle `t`; `None` if the mesh has no flattening.
    pub fn flat_corners(&self, t: usize) -> Option<[DVec2; 3]> {
        let f = self.flat.as_ref()?;
        let [a, b, c] = self.triangles[t];
        Some([f[a as usize], f[b as usize], f[c as usize]])
    }

    /// Area of triangle `t` in mm².
    pub fn triangle_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.corners(t);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Total surface area in mm².
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| self.triangle_area(t))
            .sum()
    }

    /// Total signed area of the flattening in mm² (positive for counter-clockwise triangles).
    pub fn flat_area(&self) -> Option<f64> {
        let f = self.flat.as_ref()?;
        Some(
            self.triangles
                .iter()
                .map(|&[a, b, c]| {
                    let (a, b, c) = (f[a as usize], f[b as usize], f[c as usize]);
                    0.5 * (b - a).perp_dot(c - a)
                })
                .sum(),
        )
    }

    /// Bounding box of the 3D positions (mm).
    pub fn bbox(&self) -> Aabb3 {
        Aabb3::from_points(self.positions.iter().copied())
    }

    /// Bounding box of the flattening (mm), if the mesh carries one.
    pub fn flat_bbox(&self) -> Option<Aabb2> {
        Some(Aabb2::from_points(self.flat.as_ref()?.iter().copied()))
    }
}
