//! Mesh topology: undirected edges with their incident triangles, boundary loops, connected
//! components, and the checks a flattening needs (manifold, one component, disk-like).

use std::collections::BTreeMap;

use crate::TriMesh;

/// Why a mesh cannot be flattened as it is. Messages name the element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TopologyError {
    #[error("the mesh has no triangles")]
    /// The mesh has no triangles.
    Empty,
    #[error("triangle {triangle} refers to vertex {vertex}, but the mesh has {count} vertices")]
    /// A triangle refers to a vertex the mesh does not have.
    BadIndex {
        /// 0-based index of the triangle.
        triangle: usize,
        /// The vertex it refers to.
        vertex: u32,
        /// Vertices the mesh has.
        count: usize,
    },
    #[error("triangle {triangle} is degenerate (repeated vertex {vertex})")]
    /// A triangle uses one vertex twice.
    RepeatedVertex {
        /// 0-based index of the triangle.
        triangle: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    #[error("triangle {triangle} has zero area (collinear corners {a}, {b}, {c})")]
    /// A triangle's corners are collinear.
    ZeroArea {
        /// 0-based index of the triangle.
        triangle: usize,
        /// Its first corner.
        a: u32,
        /// Its second corner.
        b: u32,
        /// Its third corner.
        c: u32,
    },
    #[error("triangles {first} and {second} are duplicates (same three vertices)")]
    /// Two triangles have the same three vertices.
    DuplicateTriangle {
        /// 0-based index of the first triangle.
        first: usize,
        /// 0-based index of its duplicate.
        second: usize,
    },
    #[error("vertex {vertex} has a non-finite coordinate")]
    /// A vertex has a NaN or infinite coordinate.
    NonFinite {
        /// 0-based index of the vertex.
        vertex: usize,
    },
    #[error(
        "edge {a}-{b} is shared by {count} triangles (non-manifold edge); split the mesh there"
    )]
    /// An edge is shared by more than two triangles.
    NonManifoldEdge {
        /// One end of the edge.
        a: u32,
        /// The other end.
        b: u32,
        /// Triangles sharing it.
        count: usize,
    },
    #[error(
        "edge {a}-{b} is used twice in the same direction: triangles {t0} and {t1} have inconsistent orientation"
    )]
    /// Two triangles run an edge in the same direction: their orientations disagree.
    InconsistentOrientation {
        /// One end of the edge.
        a: u32,
        /// The other end.
        b: u32,
        /// 0-based index of the first triangle.
        t0: usize,
        /// 0-based index of the second.
        t1: usize,
    },
    #[error("vertex {vertex} is non-manifold (its triangles form {fans} separate fans)")]
    /// A vertex's triangles form more than one fan (two surfaces touch at a point).
    NonManifoldVertex {
        /// 0-based index of the vertex.
        vertex: u32,
        /// Separate fans around it.
        fans: usize,
    },
    #[error(
        "the mesh is closed (no boundary): add a seam (a path of mesh vertices) to cut it open"
    )]
    /// The mesh is closed: it needs a seam to open it.
    NoBoundary,
    #[error(
        "the mesh has {count} boundary loops: it is not a disk; add seams joining the holes to the outer boundary (or flatten each region separately)"
    )]
    /// The mesh has holes: more than one boundary loop.
    SeveralBoundaries {
        /// Boundary loops.
        count: usize,
    },
    #[error("the mesh has {count} connected components: flatten each one separately")]
    /// The mesh falls apart into several pieces.
    SeveralComponents {
        /// Connected components.
        count: usize,
    },
    #[error("the mesh has Euler characteristic {chi}, a disk has 1: add seams to cut handles open")]
    /// The mesh has handles: its Euler characteristic is not a disk's 1.
    NotADisk {
        /// The Euler characteristic V − E + F.
        chi: i64,
    },
    #[error("seam {seam}: vertex {vertex} does not exist (the mesh has {count} vertices)")]
    /// A seam names a vertex the mesh does not have.
    SeamBadVertex {
        /// 0-based index of the seam.
        seam: usize,
        /// The vertex it names.
        vertex: u32,
        /// Vertices the mesh has.
        count: usize,
    },
    #[error("seam {seam}: vertices {a} and {b} are consecutive but not joined by a mesh edge")]
    /// Two consecutive vertices of a seam are not joined by a mesh edge.
    SeamNotAnEdge {
        /// 0-based index of the seam.
        seam: usize,
        /// The first vertex.
        a: u32,
        /// The vertex after it.
        b: u32,
    },
    #[error(
        "seam {seam}: point {point} cannot be reached from the previous point along mesh edges"
    )]
    /// A seam point cannot be reached from the one before along mesh edges.
    SeamUnreachable {
        /// 0-based index of the seam.
        seam: usize,
        /// 0-based index of the point in the seam.
        point: usize,
    },
}

/// An undirected edge `(min, max)` with the triangles on each side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeInfo {
    /// Triangle in which the edge runs `lo -> hi`, if any.
    pub fwd: Option<u32>,
    /// Triangle in which the edge runs `hi -> lo`, if any.
    pub rev: Option<u32>,
}

impl EdgeInfo {
    /// True when the edge has a triangle on one side only.
    pub fn is_boundary(&self) -> bool {
        self.fwd.is_none() || self.rev.is_none()
    }
}

/// The half-edges of `triangles` (every vertex below `n`) as (undirected key, occurrence
/// `3t + k`, whether it runs from the key's smaller vertex to its larger), sorted by key, each
/// key's occurrences in scan order.
fn sorted_half_edges(triangles: &[[u32; 3]], n: usize) -> Vec<(u64, u32, bool)> {
    let half = triangles.iter().enumerate().flat_map(|(t, tri)| {
        (0..3).map(move |k| {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
            (key, (3 * t + k) as u32, a < b)
        })
    });
    sorted_by_vertex(half, n, |&(key, ..)| (key >> 32) as u32)
}

/// The distinct `items` in sorted order, when each item's order starts with `vertex(item)`, a
/// vertex below `n`: a counting sort on the vertex (its groups, a vertex's few edges or
/// triangles, stay in the order given), then each group sorted in place. The same order as
/// sorting the whole array, in linear time rather than the `m log m` comparisons that were most
/// of the time of a million-face topology.
fn sorted_by_vertex<T: Ord + Copy + Default>(
    items: impl Iterator<Item = T> + Clone,
    n: usize,
    vertex: impl Fn(&T) -> u32,
) -> Vec<T> {
    // start[v]..start[v + 1]: where the items of vertex v go.
    let mut start = vec![0usize; n + 1];
    for x in items.clone() {
        start[vertex(&x) as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut out = vec![T::default(); start[n]];
    let mut next = start.clone();
    for x in items {
        let at = &mut next[vertex(&x) as usize];
        out[*at] = x;
        *at += 1;
    }
    for v in 0..n {
        out[start[v]..start[v + 1]].sort_unstable();
    }
    out
}

/// Edge adjacency of a mesh, built once.
#[derive(Clone, Debug)]
pub struct Topology {
    /// Every undirected edge, keyed `(lo, hi)` with `lo < hi`, in sorted (deterministic) order.
    pub edges: BTreeMap<(u32, u32), EdgeInfo>,
    /// Boundary loops as vertex sequences, each oriented like the triangles (interior on the left).
    pub boundary_loops: Vec<Vec<u32>>,
    /// Connected component index of each triangle.
    pub component_of_triangle: Vec<u32>,
    /// Number of connected components (the largest index in `component_of_triangle` plus one).
    pub component_count: usize,
}

impl Topology {
    /// Builds the adjacency. Fails on bad indices, repeated vertices, non-manifold edges and
    /// inconsistent orientation (the conditions under which boundary loops are undefined).
    ///
    /// The edges are found by sorting the `3F` half-edges by their undirected key (flat
    /// vectors, no tree insertions, a counting sort on the key's smaller vertex); the map of [`Topology::edges`] is then bulk-built from the
    /// sorted run. Errors are the ones a triangle-by-triangle scan meets first.
    pub fn build(mesh: &TriMesh) -> Result<Self, TopologyError> {
        let n = mesh.positions.len();
        let nt = mesh.triangles.len();
        // The first triangle with a bad index or a repeated vertex: triangles before it are
        // scanned for edge conflicts, which a sequential scan would report first.
        let mut bad: Option<(usize, TopologyError)> = None;
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                bad = Some((
                    t,
                    TopologyError::BadIndex {
                        triangle: t,
                        vertex: v,
                        count: n,
                    },
                ));
                break;
            }
            if let Some(k) = (0..3).find(|&k| tri[k] == tri[(k + 1) % 3]) {
                bad = Some((
                    t,
                    TopologyError::RepeatedVertex {
                        triangle: t,
                        vertex: tri[k],
                    },
                ));
                break;
            }
        }
        let scanned = bad.as_ref().map_or(nt, |b| b.0);
        let half = sorted_half_edges(&mesh.triangles[..scanned], n);
        // A half-edge's tail, head and triangle.
        let dir_of = |key: u64, occ: u32, forward: bool| {
            let (lo, hi) = ((key >> 32) as u32, key as u32);
            let (a, b) = if forward { (lo, hi) } else { (hi, lo) };
            (a, b, occ / 3)
        };
        let mut edge_list: Vec<((u32, u32), EdgeInfo)> = Vec::with_capacity(half.len() / 2 + 1);
        // The earliest conflicting occurrence (a half-edge whose side is already taken).
        let mut conflict: Option<(u32, TopologyError)> = None;
        let mut i = 0;
        while i < half.len() {
            let key = half[i].0;
            let mut j = i;
            let mut e = EdgeInfo {
                fwd: None,
                rev: None,
            };
            while j < half.len() && half[j].0 == key {
                let (a, b, t) = dir_of(key, half[j].1, half[j].2);
                let slot = if a < b { &mut e.fwd } else { &mut e.rev };
                if let Some(prev) = *slot {
                    let occ = half[j].1;
                    if conflict.as_ref().is_none_or(|c| occ < c.0) {
                        let count = j - i + 1;
                        let err = if count > 2 {
                            TopologyError::NonManifoldEdge {
                                a: (key >> 32) as u32,
                                b: key as u32,
                                count,
                            }
                        } else {
                            TopologyError::InconsistentOrientation {
                                a,
                                b,
                                t0: prev as usize,
                                t1: t as usize,
                            }
                        };
                        conflict = Some((occ, err));
                    }
                    // Later occurrences of this edge come after the conflict in scan order.
                    while j < half.len() && half[j].0 == key {
                        j += 1;
                    }
                    break;
                }
                *slot = Some(t);
                j += 1;
            }
            edge_list.push((((key >> 32) as u32, key as u32), e));
            i = j;
        }
        if let Some((_, err)) = conflict {
            return Err(err);
        }
        if let Some((_, err)) = bad {
            return Err(err);
        }
        drop(half);

        // Components by union-find over shared edges. The root of a set is always its smallest
        // triangle, so the labels do not depend on the union order.
        let mut parent: Vec<u32> = (0..nt as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        fn union(p: &mut [u32], a: u32, b: u32) {
            let (ra, rb) = (find(p, a), find(p, b));
            if ra != rb {
                p[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        for (_, e) in &edge_list {
            if let (Some(a), Some(b)) = (e.fwd, e.rev) {
                union(&mut parent, a, b);
            }
        }
        // Triangles sharing only a vertex are also connected.
        let mut first_tri_of_vertex: Vec<u32> = vec![u32::MAX; n];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                match first_tri_of_vertex[v as usize] {
                    u32::MAX => first_tri_of_vertex[v as usize] = t as u32,
                    o => union(&mut parent, o, t as u32),
                }
            }
        }
        let mut label: Vec<u32> = vec![u32::MAX; nt];
        let mut component_count = 0usize;
        let mut component_of_triangle = Vec::with_capacity(nt);
        for t in 0..nt as u32 {
            let r = find(&mut parent, t) as usize;
            if label[r] == u32::MAX {
                label[r] = component_count as u32;
                component_count += 1;
            }
            component_of_triangle.push(label[r]);
        }

        // Boundary loops: directed boundary half-edges a->b (as in their triangle), grouped by
        // their tail vertex in edge order (a stable sort keeps that order within a vertex).
        let mut bnd: Vec<(u32, u32)> = edge_list
            .iter()
            .filter_map(|&((lo, hi), e)| match (e.fwd, e.rev) {
                (Some(_), None) => Some((lo, hi)),
                (None, Some(_)) => Some((hi, lo)),
                _ => None,
            })
            .collect();
        bnd.sort_by_key(|&(a, _)| a);
        let mut used = vec![false; bnd.len()];
        let outs = |v: u32| {
            let s = bnd.partition_point(|&(a, _)| a < v);
            let e = bnd.partition_point(|&(a, _)| a <= v);
            s..e
        };
        let mut boundary_loops = Vec::new();
        for h in 0..bnd.len() {
            if used[h] {
                continue;
            }
            let (start, first) = bnd[h];
            let mut lp = vec![start];
            used[h] = true;
            let mut cur = first;
            let mut guard = 0usize;
            while cur != start && guard <= edge_list.len() {
                lp.push(cur);
                let Some(nx) = outs(cur).find(|&g| !used[g]) else {
                    break;
                };
                used[nx] = true;
                cur = bnd[nx].1;
                guard += 1;
            }
            boundary_loops.push(lp);
        }
        Ok(Self {
            edges: edge_list.into_iter().collect(),
            boundary_loops,
            component_of_triangle,
            component_count,
        })
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }
}

/// Checks that the mesh is a single manifold topological disk with finite, non-degenerate
/// triangles, the input every flattening method needs. Returns its topology.
pub fn check_disk(mesh: &TriMesh) -> Result<Topology, TopologyError> {
    if mesh.triangles.is_empty() {
        return Err(TopologyError::Empty);
    }
    if let Some(v) = mesh
        .positions
        .iter()
        .position(|p| !flatcut_geom::finite3(*p))
    {
        return Err(TopologyError::NonFinite { vertex: v });
    }
    let topo = Topology::build(mesh)?;
    // Duplicate triangles: sort the vertex-sorted keys; the first duplicate in scan order is
    // the smallest second occurrence, reported with the first occurrence of its key.
    let keys = mesh.triangles.iter().enumerate().map(|(t, tri)| {
        let mut key = *tri;
        key.sort_unstable();
        (key, t as u32)
    });
    let keys = sorted_by_vertex(keys, mesh.positions.len(), |&(key, _)| key[0]);
    let mut duplicate: Option<(usize, usize)> = None;
    for group in keys.chunk_by(|x, y| x.0 == y.0) {
        if let [first, second, ..] = group
            && duplicate.is_none_or(|d| (second.1 as usize) < d.1)
        {
            duplicate = Some((first.1 as usize, second.1 as usize));
        }
    }
    let first_zero_area = (0..mesh.triangles.len()).find(|&t| {
        let [a, b, c] = mesh.corners(t);
        let scale = (b - a).length().max((c - a).length()).max((c - b).length());
        // Relative area test: a sliver whose area is below round-off of its edge lengths.
        (b - a).cross(c - a).length() <= 1e-14 * scale * scale
    });
    match (duplicate, first_zero_area) {
        (Some((first, second)), z) if z.is_none_or(|z| second <= z) => {
            return Err(TopologyError::DuplicateTriangle { first, second });
        }
        (_, Some(t)) => {
            let tri = mesh.triangles[t];
            return Err(TopologyError::ZeroArea {
                triangle: t,
                a: tri[0],
                b: tri[1],
                c: tri[2],
            });
        }
        _ => {}
    }
    if topo.component_count > 1 {
        return Err(TopologyError::SeveralComponents {
            count: topo.component_count,
        });
    }
    // Non-manifold vertex: a vertex on more than one boundary passage.
    let mut boundary_visits = vec![0usize; mesh.positions.len()];
    for lp in &topo.boundary_loops {
        for &v in lp {
            boundary_visits[v as usize] += 1;
        }
    }
    if let Some((v, &k)) = boundary_visits.iter().enumerate().find(|(_, k)| **k > 1) {
        return Err(TopologyError::NonManifoldVertex {
            vertex: v as u32,
            fans: k,
        });
    }
    match topo.boundary_loops.len() {
        0 => return Err(TopologyError::NoBoundary),
        1 => {}
        k => return Err(TopologyError::SeveralBoundaries { count: k }),
    }
    let used_vertices = {
        let mut u = vec![false; mesh.positions.len()];
        for tri in &mesh.triangles {
            for &v in tri {
                u[v as usize] = true;
            }
        }
        u.iter().filter(|&&b| b).count() as i64
    };
    let chi = used_vertices - topo.edges.len() as i64 + mesh.triangles.len() as i64;
    if chi != 1 {
        return Err(TopologyError::NotADisk { chi });
    }
    Ok(topo)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    fn grid(n: usize) -> TriMesh {
        crate::test_grid::grid_mesh(n, n, |i, j| DVec3::new(i as f64, j as f64, 0.0))
    }

    #[test]
    fn grid_is_a_disk_with_one_ccw_loop() {
        let m = grid(3);
        let topo = check_disk(&m).unwrap();
        assert_eq!(topo.boundary_loops.len(), 1);
        assert_eq!(topo.boundary_loops[0].len(), 12);
        // Counter-clockwise: positive signed area of the loop in the xy plane.
        let lp = &topo.boundary_loops[0];
        let area: f64 = (0..lp.len())
            .map(|i| {
                let a = m.positions[lp[i] as usize];
                let b = m.positions[lp[(i + 1) % lp.len()] as usize];
                a.x * b.y - b.x * a.y
            })
            .sum();
        assert!(area > 0.0);
    }

    #[test]
    fn half_edges_sorted_by_vertex_are_the_whole_array_sorted() {
        // A grid whose vertices are renumbered and triangles reordered out of any sweep order,
        // so that groups are filled out of order and hold several keys.
        let mut m = grid(12);
        let n = m.positions.len() as u32;
        let scramble = |v: u32| (v * 37 + 11) % n;
        for tri in &mut m.triangles {
            *tri = tri.map(scramble);
        }
        m.triangles.reverse();
        m.triangles.rotate_left(50);
        let mut want: Vec<(u64, u32, bool)> = Vec::new();
        for (t, tri) in m.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                want.push((key, (3 * t + k) as u32, a < b));
            }
        }
        want.sort_unstable();
        assert_eq!(sorted_half_edges(&m.triangles, n as usize), want);
    }

    #[test]
    fn errors_name_the_element() {
        let mut m = grid(2);
        m.triangles.push(m.triangles[0]);
        assert!(matches!(
            check_disk(&m),
            Err(TopologyError::InconsistentOrientation { .. }
                | TopologyError::NonManifoldEdge { .. })
        ));
        let mut m = grid(2);
        m.positions[4].x = f64::NAN;
        assert_eq!(
            check_disk(&m).unwrap_err(),
            TopologyError::NonFinite { vertex: 4 }
        );
        let mut m = grid(2);
        let k = m.positions.len() as u32;
        m.positions.extend([
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(11.0, 0.0, 0.0),
            DVec3::new(10.0, 1.0, 0.0),
        ]);
        m.triangles.push([k, k + 1, k + 2]);
        assert_eq!(
            check_disk(&m).unwrap_err(),
            TopologyError::SeveralComponents { count: 2 }
        );
    }

    #[test]
    fn first_error_in_scan_order_is_reported() {
        // A triangle and its reverse: consistent edges, a duplicate.
        let mut m = grid(1);
        m.triangles = vec![[0, 1, 3], [0, 3, 1]];
        assert_eq!(
            check_disk(&m).unwrap_err(),
            TopologyError::DuplicateTriangle {
                first: 0,
                second: 1
            }
        );
        // Reversing a grid triangle puts a third triangle on its interior edge 0-4.
        let mut m = grid(2);
        let [a, b, c] = m.triangles[0];
        m.triangles.push([a, c, b]);
        assert_eq!(
            check_disk(&m).unwrap_err(),
            TopologyError::NonManifoldEdge {
                a: 0,
                b: 4,
                count: 3
            }
        );
        // Triangle 8 reuses edge 0->1 of triangle 0 in the same direction; triangle 9 has a bad
        // index, met later in the scan.
        let mut m = grid(2);
        m.triangles.push([0, 1, 7]);
        m.triangles.push([0, 1, 99]);
        assert_eq!(
            Topology::build(&m).unwrap_err(),
            TopologyError::InconsistentOrientation {
                a: 0,
                b: 1,
                t0: 0,
                t1: 8
            }
        );
        let mut m = grid(2);
        m.triangles.push([0, 0, 1]);
        assert_eq!(
            Topology::build(&m).unwrap_err(),
            TopologyError::RepeatedVertex {
                triangle: 8,
                vertex: 0
            }
        );
    }
}
