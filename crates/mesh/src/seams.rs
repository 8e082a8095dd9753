//! Seams: cutting a mesh open along polylines of its edges so that a closed surface (or one with
//! several boundaries) becomes a disk a flattening can handle, and finding such polylines from
//! points the user gives in 3D or in (u, v).
//!
//! Cutting works on triangle corners: two corners of the same vertex stay one vertex when they
//! are joined through an uncut edge around that vertex (union–find), so each "wedge" of triangles
//! between cut edges gets its own copy of the vertex. The first copy keeps the original index
//! (seams given as vertex lists remain valid) and extra copies are appended.

use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

use flatcut_geom::{DVec2, DVec3};

use crate::{Topology, TopologyError, TriMesh};

/// Total order on f64 distances for the priority queue (all values are finite, non-negative).
#[derive(Clone, Copy, PartialEq)]
pub(crate) struct Dist(pub f64);
impl Eq for Dist {}
impl PartialOrd for Dist {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Dist {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Cuts the mesh along each seam (a polyline of vertex indices joined by mesh edges; a closed
/// loop repeats its first vertex at the end). Vertices on a seam are duplicated so the two sides
/// become separate boundary; per-vertex data (params, patch, flat) is copied.
pub fn cut_along_seams(mesh: &TriMesh, seams: &[Vec<u32>]) -> Result<TriMesh, TopologyError> {
    let topo = Topology::build(mesh)?;
    let n = mesh.positions.len();
    let mut cut: BTreeSet<(u32, u32)> = BTreeSet::new();
    for (si, seam) in seams.iter().enumerate() {
        for &v in seam {
            if v as usize >= n {
                return Err(TopologyError::SeamBadVertex {
                    seam: si,
                    vertex: v,
                    count: n,
                });
            }
        }
        for w in seam.windows(2) {
            if w[0] == w[1] {
                continue;
            }
            let k = (w[0].min(w[1]), w[0].max(w[1]));
            if !topo.edges.contains_key(&k) {
                return Err(TopologyError::SeamNotAnEdge {
                    seam: si,
                    a: w[0],
                    b: w[1],
                });
            }
            cut.insert(k);
        }
    }
    // Corner c = 3 t + k. Union corners of the same vertex across uncut interior edges.
    let nc = mesh.triangles.len() * 3;
    let mut parent: Vec<usize> = (0..nc).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let corner_of = |t: u32, v: u32| -> usize {
        let tri = mesh.triangles[t as usize];
        let k = tri.iter().position(|&x| x == v).unwrap_or(0);
        3 * t as usize + k
    };
    for (&(a, b), e) in &topo.edges {
        if cut.contains(&(a, b)) {
            continue;
        }
        if let (Some(t1), Some(t2)) = (e.fwd, e.rev) {
            for v in [a, b] {
                let (c1, c2) = (corner_of(t1, v), corner_of(t2, v));
                let (r1, r2) = (find(&mut parent, c1), find(&mut parent, c2));
                if r1 != r2 {
                    parent[r1.max(r2)] = r1.min(r2);
                }
            }
        }
    }
    // Assign vertex ids: first class of each vertex (by smallest corner) keeps the index.
    let mut class_vertex: Vec<u32> = vec![u32::MAX; nc];
    let mut first_used = vec![false; n];
    let mut origin: Vec<u32> = (0..n as u32).collect();
    let mut triangles = mesh.triangles.clone();
    for c in 0..nc {
        let r = find(&mut parent, c);
        let v = mesh.triangles[c / 3][c % 3];
        if class_vertex[r] == u32::MAX {
            class_vertex[r] = if !first_used[v as usize] {
                first_used[v as usize] = true;
                v
            } else {
                origin.push(v);
                (origin.len() - 1) as u32
            };
        }
        triangles[c / 3][c % 3] = class_vertex[r];
    }
    fn pick<T: Copy>(origin: &[u32], src: &[T]) -> Vec<T> {
        origin.iter().map(|&o| src[o as usize]).collect()
    }
    let copy = |src: &Vec<DVec3>| pick(&origin, src);
    Ok(TriMesh {
        positions: copy(&mesh.positions),
        triangles,
        params: mesh.params.as_ref().map(|p| pick(&origin, p)),
        patch_of_vertex: mesh.patch_of_vertex.as_ref().map(|p| pick(&origin, p)),
        flat: mesh.flat.as_ref().map(|p| pick(&origin, p)),
    })
}

/// Vertex adjacency lists (sorted, deduplicated) of the mesh's edges.
pub fn vertex_neighbours(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3]);
            if a < adj.len() && (b as usize) < adj.len() {
                adj[a].push(b);
                adj[b as usize].push(a as u32);
            }
        }
    }
    for l in &mut adj {
        l.sort_unstable();
        l.dedup();
    }
    adj
}

/// Shortest path along mesh edges from `a` to `b` (Dijkstra, Euclidean edge lengths).
pub fn edge_path(mesh: &TriMesh, adj: &[Vec<u32>], a: u32, b: u32) -> Option<Vec<u32>> {
    let n = mesh.positions.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut prev = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    dist[a as usize] = 0.0;
    heap.push(Reverse((Dist(0.0), a)));
    while let Some(Reverse((Dist(d), v))) = heap.pop() {
        if v == b {
            break;
        }
        if d > dist[v as usize] {
            continue;
        }
        for &w in &adj[v as usize] {
            let nd = d + mesh.positions[v as usize].distance(mesh.positions[w as usize]);
            if nd < dist[w as usize] {
                dist[w as usize] = nd;
                prev[w as usize] = v;
                heap.push(Reverse((Dist(nd), w)));
            }
        }
    }
    if !dist[b as usize].is_finite() {
        return None;
    }
    let mut path = vec![b];
    let mut v = b;
    while v != a {
        v = prev[v as usize];
        path.push(v);
    }
    path.reverse();
    Some(path)
}

fn path_through(mesh: &TriMesh, anchors: &[u32], seam: usize) -> Result<Vec<u32>, TopologyError> {
    let adj = vertex_neighbours(mesh);
    let mut out: Vec<u32> = Vec::new();
    for (i, w) in anchors.windows(2).enumerate() {
        let p = edge_path(mesh, &adj, w[0], w[1])
            .ok_or(TopologyError::SeamUnreachable { seam, point: i + 1 })?;
        let skip = usize::from(!out.is_empty());
        out.extend_from_slice(&p[skip..]);
    }
    if anchors.len() == 1 {
        out.push(anchors[0]);
    }
    Ok(out)
}

/// A seam through the mesh vertices nearest to the given 3D points, joined by shortest edge
/// paths. Returns an empty seam for no points or an empty mesh; fails when consecutive points
/// lie on disconnected parts of the mesh.
pub fn seam_from_points(mesh: &TriMesh, points: &[DVec3]) -> Result<Vec<u32>, TopologyError> {
    if mesh.positions.is_empty() {
        return Ok(Vec::new());
    }
    let anchors: Vec<u32> = points
        .iter()
        .map(|p| nearest_vertex(&mesh.positions, *p))
        .collect();
    path_through(mesh, &dedup(anchors), 0)
}

/// A seam through the vertices whose surface parameters are nearest to the given (u, v) points
/// (for meshes tessellated from one patch); `None` when the mesh has no parameters.
pub fn seam_from_params(mesh: &TriMesh, uv: &[DVec2]) -> Option<Result<Vec<u32>, TopologyError>> {
    let params = mesh.params.as_ref()?;
    let anchors: Vec<u32> = uv
        .iter()
        .map(|q| {
            let mut best = (f64::INFINITY, 0u32);
            for (i, p) in params.iter().enumerate() {
                let d = p.distance_squared(*q);
                if d < best.0 {
                    best = (d, i as u32);
                }
            }
            best.1
        })
        .collect();
    Some(path_through(mesh, &dedup(anchors), 0))
}

fn dedup(mut v: Vec<u32>) -> Vec<u32> {
    v.dedup();
    v
}

/// Index of the position nearest to `p` (the first on ties).
pub fn nearest_vertex(positions: &[DVec3], p: DVec3) -> u32 {
    let mut best = (f64::INFINITY, 0u32);
    for (i, q) in positions.iter().enumerate() {
        let d = q.distance_squared(p);
        if d < best.0 {
            best = (d, i as u32);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check_disk;
    use std::f64::consts::PI;

    /// A closed cylinder sleeve (no seam): `n` around, `m` along, radius 10, height 30.
    fn sleeve(n: usize, m: usize) -> TriMesh {
        let mut p = Vec::new();
        for j in 0..=m {
            for i in 0..n {
                let a = 2.0 * PI * i as f64 / n as f64;
                p.push(DVec3::new(
                    10.0 * a.cos(),
                    10.0 * a.sin(),
                    30.0 * j as f64 / m as f64,
                ));
            }
        }
        let id = |i: usize, j: usize| (j * n + i % n) as u32;
        let mut t = Vec::new();
        for j in 0..m {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        TriMesh::new(p, t)
    }

    #[test]
    fn sleeve_cut_along_a_generator_is_a_disk() {
        let m = sleeve(12, 5);
        assert!(matches!(
            check_disk(&m),
            Err(TopologyError::SeveralBoundaries { count: 2 })
        ));
        let seam = seam_from_points(
            &m,
            &[DVec3::new(10.0, 0.0, 0.0), DVec3::new(10.0, 0.0, 30.0)],
        )
        .unwrap();
        assert_eq!(seam, vec![0, 12, 24, 36, 48, 60]);
        let c = cut_along_seams(&m, &[seam]).unwrap();
        let topo = check_disk(&c).unwrap();
        assert_eq!(c.vertex_count(), m.vertex_count() + 6);
        assert_eq!(topo.boundary_loops[0].len(), 2 * 12 + 2 * 5);
        assert!((c.area() - m.area()).abs() < 1e-9);
        // Original indices survive.
        assert_eq!(&c.positions[..m.vertex_count()], &m.positions[..]);
    }

    #[test]
    fn closed_surface_with_open_slit_becomes_a_disk() {
        // Octahedron: closed; a seam from the top through the equator to the bottom opens it.
        let p = vec![
            DVec3::X,
            DVec3::Y,
            -DVec3::X,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        let t = vec![
            [0, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [3, 0, 4],
            [1, 0, 5],
            [2, 1, 5],
            [3, 2, 5],
            [0, 3, 5],
        ];
        let m = TriMesh::new(p, t);
        assert_eq!(check_disk(&m).unwrap_err(), TopologyError::NoBoundary);
        let c = cut_along_seams(&m, &[vec![4, 0, 5]]).unwrap();
        check_disk(&c).unwrap();
        assert_eq!(c.vertex_count(), 7);
    }

    #[test]
    fn bad_seams_are_reported() {
        let m = sleeve(8, 2);
        assert_eq!(
            cut_along_seams(&m, &[vec![0, 2]]).unwrap_err(),
            TopologyError::SeamNotAnEdge {
                seam: 0,
                a: 0,
                b: 2
            }
        );
        assert!(matches!(
            cut_along_seams(&m, &[vec![0, 8], vec![0, 99]]),
            Err(TopologyError::SeamBadVertex {
                seam: 1,
                vertex: 99,
                ..
            })
        ));
    }
}
