//! Welding coincident vertices: points closer than a tolerance become one vertex.
//!
//! A uniform grid of cell size `tol` keyed in a `BTreeMap` (deterministic, no hashing) finds the
//! candidates in the 27 neighbouring cells, so welding is O(n log n). The first vertex (in index
//! order) of a cluster is its representative, which keeps the result independent of map order.

use std::collections::BTreeMap;

use flatcut_geom::DVec3;

use crate::TriMesh;

/// Smallest weld tolerance used for cell sizing: below this the grid key would overflow for
/// coordinates of a few metres, and such a tolerance means "bitwise equal" anyway.
const MIN_CELL_MM: f64 = 1e-12;

/// Clusters points closer than `tol` (mm). Returns the representatives (in first-appearance
/// order) and, for each input point, the index of its representative.
///
/// Clustering is greedy: a point joins the first earlier representative within `tol`, so chains
/// of points each within `tol` of the next are not merged transitively beyond one step.
pub fn weld_points(points: &[DVec3], tol: f64) -> (Vec<DVec3>, Vec<u32>) {
    let cell = tol.max(MIN_CELL_MM);
    let key = |p: DVec3| {
        (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        )
    };
    let mut grid: BTreeMap<(i64, i64, i64), Vec<u32>> = BTreeMap::new();
    let mut reps: Vec<DVec3> = Vec::new();
    let mut remap = Vec::with_capacity(points.len());
    let tol2 = tol * tol;
    for &p in points {
        let (kx, ky, kz) = key(p);
        let mut found: Option<u32> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&(kx + dx, ky + dy, kz + dz)) {
                        for &r in list {
                            let d2 = reps[r as usize].distance_squared(p);
                            if d2 <= tol2 && found.is_none_or(|f| r < f) {
                                found = Some(r);
                            }
                        }
                    }
                }
            }
        }
        let idx = match found {
            Some(r) => r,
            None => {
                let r = reps.len() as u32;
                reps.push(p);
                grid.entry((kx, ky, kz)).or_default().push(r);
                r
            }
        };
        remap.push(idx);
    }
    (reps, remap)
}

impl TriMesh {
    /// Merges vertices closer than `tol` mm, remaps the triangles and drops triangles that
    /// collapse (two corners welded together). Per-vertex data (params, patch, flat) is taken
    /// from each cluster's first vertex.
    pub fn welded(&self, tol: f64) -> TriMesh {
        let (positions, remap) = weld_points(&self.positions, tol);
        let n = positions.len();
        let pick = |src: &Option<Vec<_>>| -> Option<Vec<_>> {
            src.as_ref().map(|v: &Vec<_>| {
                let mut out = vec![None; n];
                for (i, &r) in remap.iter().enumerate() {
                    if out[r as usize].is_none() {
                        out[r as usize] = Some(v[i]);
                    }
                }
                out.into_iter().map(|x| x.unwrap_or_default()).collect()
            })
        };
        let params = pick(&self.params);
        let flat = pick(&self.flat);
        let patch_of_vertex = self.patch_of_vertex.as_ref().map(|v| {
            let mut out = vec![None; n];
            for (i, &r) in remap.iter().enumerate() {
                if out[r as usize].is_none() {
                    out[r as usize] = Some(v[i]);
                }
            }
            out.into_iter().map(|x| x.unwrap_or(0)).collect()
        });
        let triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|v| remap[v as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        TriMesh {
            positions,
            triangles,
            params,
            patch_of_vertex,
            flat,
        }
    }
}

impl TriMesh {
    /// Merges the end points of every edge shorter than `tol` mm (union–find over such edges) and
    /// drops the triangles that collapse. Unlike [`TriMesh::welded`], coincident vertices that
    /// are not joined by an edge stay apart: this closes the collapsed sides of a parameter
    /// domain (sphere poles, a cone apex) without closing a parameter seam.
    pub fn collapsed_short_edges(&self, tol: f64) -> TriMesh {
        let n = self.positions.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        let mut any = false;
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if self.positions[a as usize].distance(self.positions[b as usize]) <= tol {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    if ra != rb {
                        parent[ra.max(rb) as usize] = ra.min(rb);
                        any = true;
                    }
                }
            }
        }
        if !any {
            return self.clone();
        }
        // Keep representatives in index order, renumber densely.
        let mut new_id = vec![u32::MAX; n];
        let mut keep = Vec::new();
        for v in 0..n as u32 {
            let r = find(&mut parent, v);
            if r == v {
                new_id[v as usize] = keep.len() as u32;
                keep.push(v);
            }
        }
        let remap: Vec<u32> = (0..n as u32)
            .map(|v| new_id[find(&mut parent, v) as usize])
            .collect();
        let pick = |src: &Option<Vec<_>>| {
            src.as_ref()
                .map(|s: &Vec<_>| keep.iter().map(|&v| s[v as usize]).collect())
        };
        TriMesh {
            positions: keep.iter().map(|&v| self.positions[v as usize]).collect(),
            triangles: self
                .triangles
                .iter()
                .map(|t| t.map(|v| remap[v as usize]))
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                .collect(),
            params: pick(&self.params),
            patch_of_vertex: self
                .patch_of_vertex
                .as_ref()
                .map(|s| keep.iter().map(|&v| s[v as usize]).collect()),
            flat: pick(&self.flat),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_edges_collapse_but_unconnected_twins_stay() {
        // A strip whose left side is collapsed to one point (like a pole), and whose two
        // right corners coincide with the left ones of another strip but share no edge.
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
            ],
            vec![[0, 2, 3], [0, 3, 1], [4, 5, 3]],
        );
        let c = m.collapsed_short_edges(1e-9);
        assert_eq!(c.positions.len(), 5);
        assert_eq!(c.triangles, vec![[0, 1, 2], [3, 4, 2]]);
    }

    #[test]
    fn close_points_merge_far_points_stay() {
        let pts = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 4e-4),
            DVec3::new(1.0, 2e-3, 0.0),
            DVec3::new(1.0 - 1e-4, 0.0, 0.0),
        ];
        let (reps, remap) = weld_points(&pts, 1e-3);
        assert_eq!(reps.len(), 3);
        assert_eq!(remap, vec![0, 1, 0, 2, 1]);
    }

    #[test]
    fn welding_two_triangles_shares_the_edge_and_drops_collapsed() {
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0 + 1e-7, 0.0),
                DVec3::new(5.0, 5.0, 5.0),
                DVec3::new(5.0, 5.0, 5.0 + 1e-9),
                DVec3::new(6.0, 5.0, 5.0),
            ],
            vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]],
        );
        let w = m.welded(1e-6);
        assert_eq!(w.positions.len(), 6);
        assert_eq!(w.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    }

    proptest::proptest! {
        #[test]
        fn every_point_is_within_tolerance_of_its_representative(
            pts in proptest::collection::vec((-50i32..50, -50i32..50, -5i32..5), 1..200),
        ) {
            let pts: Vec<DVec3> = pts
                .iter()
                .map(|&(x, y, z)| DVec3::new(x as f64 * 0.01, y as f64 * 0.01, z as f64 * 0.01))
                .collect();
            let tol = 0.015;
            let (reps, remap) = weld_points(&pts, tol);
            for (i, &r) in remap.iter().enumerate() {
                proptest::prop_assert!(pts[i].distance(reps[r as usize]) <= tol);
            }
            // Representatives are pairwise farther apart than the tolerance.
            for a in 0..reps.len() {
                for b in a + 1..reps.len() {
                    proptest::prop_assert!(reps[a].distance(reps[b]) > tol);
                }
            }
        }
    }
}
