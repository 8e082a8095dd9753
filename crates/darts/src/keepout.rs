//! Where no dart may go: `no_cut` regions (polygons on the surface), marks (stitch lines,
//! drill and reference points, notches) and seams, as a mask over the piece's vertices.
//!
//! A region is the part of the surface its polygon encloses: the polygon is joined along mesh
//! edges (shortest edge paths between its points), the faces on either side of that loop are
//! flooded without crossing it, and the smaller side (by area) is the region. A dart path is a
//! path of mesh edges, so it crosses a line only at a shared vertex: keeping dart paths off the
//! vertices of a line and of the ring around them keeps them from crossing it.

use std::collections::BTreeSet;

use flatcut_geom::DVec3;
use flatcut_mesh::TriMesh;
use flatcut_mesh::seams::{nearest_vertex, seam_from_points};

/// Vertices no dart may use (indexed like the piece's vertices).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KeepOut {
    /// Per vertex (0-based, the piece's order), true when no dart may use it.
    pub blocked: Vec<bool>,
}

/// Why a keep-out cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum KeepOutError {
    /// A region's outline has fewer than three points.
    #[error("no_cut region {region}: it needs at least three points")]
    TooFewPoints {
        /// 0-based index of the region in the design's list.
        region: usize,
    },
    /// A region's outline cannot be traced on the surface between its points.
    #[error("no_cut region {region}: {reason}")]
    Path {
        /// 0-based index of the region in the design's list.
        region: usize,
        /// Why the tracing failed.
        reason: String,
    },
}

impl KeepOut {
    /// Nothing blocked.
    pub fn none(mesh: &TriMesh) -> Self {
        Self {
            blocked: vec![false; mesh.positions.len()],
        }
    }

    /// True when vertex `v` is blocked; false for an index beyond the keep-out.
    pub fn is_blocked(&self, v: u32) -> bool {
        self.blocked.get(v as usize).copied().unwrap_or(false)
    }

    /// Blocks every vertex within `radius` (mm, straight distance) of each point, and at least
    /// the nearest vertex.
    pub fn block_points(&mut self, mesh: &TriMesh, points: &[DVec3], radius: f64) {
        for p in points {
            self.blocked[nearest_vertex(&mesh.positions, *p) as usize] = true;
            for (v, q) in mesh.positions.iter().enumerate() {
                if q.distance(*p) <= radius {
                    self.blocked[v] = true;
                }
            }
        }
    }

    /// Blocks a line drawn on the surface (its points joined by shortest edge paths) and the
    /// vertices next to it.
    pub fn block_line(&mut self, mesh: &TriMesh, points: &[DVec3]) -> Result<(), String> {
        let path = seam_from_points(mesh, points).map_err(|e| e.to_string())?;
        let adj = flatcut_mesh::seams::vertex_neighbours(mesh);
        for &v in &path {
            self.blocked[v as usize] = true;
            for &w in &adj[v as usize] {
                self.blocked[w as usize] = true;
            }
        }
        Ok(())
    }

    /// Blocks the region a polygon of surface points encloses (see the module doc), its
    /// outline and the vertices next to the outline.
    pub fn block_region(
        &mut self,
        mesh: &TriMesh,
        polygon: &[DVec3],
        region: usize,
    ) -> Result<(), KeepOutError> {
        if polygon.len() < 3 {
            return Err(KeepOutError::TooFewPoints { region });
        }
        let mut closed = polygon.to_vec();
        closed.push(polygon[0]);
        let lp = seam_from_points(mesh, &closed).map_err(|e| KeepOutError::Path {
            region,
            reason: e.to_string(),
        })?;
        let cut: BTreeSet<(u32, u32)> = lp
            .windows(2)
            .map(|w| (w[0].min(w[1]), w[0].max(w[1])))
            .collect();
        // Flood faces across uncut edges.
        let mut edge_faces: std::collections::BTreeMap<(u32, u32), Vec<usize>> = Default::default();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                edge_faces.entry((a.min(b), a.max(b))).or_default().push(t);
            }
        }
        let nt = mesh.triangles.len();
        let mut label = vec![usize::MAX; nt];
        let mut areas = Vec::new();
        for seed in 0..nt {
            if label[seed] != usize::MAX {
                continue;
            }
            let id = areas.len();
            let mut area = 0.0;
            let mut stack = vec![seed];
            label[seed] = id;
            while let Some(t) = stack.pop() {
                area += mesh.triangle_area(t);
                let tri = mesh.triangles[t];
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    let key = (a.min(b), a.max(b));
                    if cut.contains(&key) {
                        continue;
                    }
                    for &u in &edge_faces[&key] {
                        if label[u] == usize::MAX {
                            label[u] = id;
                            stack.push(u);
                        }
                    }
                }
            }
            areas.push(area);
        }
        // The smallest component is the enclosed region (a loop splits a disk in two; a region
        // that touches the outline still leaves the larger part outside).
        let inside = (0..areas.len())
            .min_by(|&a, &b| areas[a].total_cmp(&areas[b]))
            .unwrap_or(0);
        if areas.len() > 1 {
            for (t, tri) in mesh.triangles.iter().enumerate() {
                if label[t] == inside {
                    for &v in tri {
                        self.blocked[v as usize] = true;
                    }
                }
            }
        }
        let adj = flatcut_mesh::seams::vertex_neighbours(mesh);
        for &v in &lp {
            self.blocked[v as usize] = true;
            for &w in &adj[v as usize] {
                self.blocked[w as usize] = true;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_flatten::testmesh::spherical_cap;

    #[test]
    fn a_region_blocks_what_it_encloses_and_nothing_far_outside() {
        let cap = spherical_cap(100.0, 1.0, 20);
        let mut k = KeepOut::none(&cap);
        // A square around the pole, 20 mm on a side (projected onto the sphere).
        let sq: Vec<DVec3> = [(-20.0, -20.0), (20.0, -20.0), (20.0, 20.0), (-20.0, 20.0)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 100.0).normalize() * 100.0)
            .collect();
        k.block_region(&cap, &sq, 0).unwrap();
        let pole = nearest_vertex(&cap.positions, DVec3::new(0.0, 0.0, 100.0));
        assert!(k.is_blocked(pole));
        for (v, p) in cap.positions.iter().enumerate() {
            let r = (p.x * p.x + p.y * p.y).sqrt();
            if r > 45.0 {
                assert!(!k.blocked[v], "vertex {v} at r = {r} blocked");
            }
        }
        assert!(matches!(
            k.block_region(&cap, &sq[..2], 3),
            Err(KeepOutError::TooFewPoints { region: 3 })
        ));
    }
}
