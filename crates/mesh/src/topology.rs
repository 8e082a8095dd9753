//! Mesh topology: undirected edges with their incident triangles, boundary loops, connected
//! components, and the checks a flattening needs (manifold, one component, disk-like).

use std::collections::BTreeMap;

use crate::TriMesh;

/// Why a mesh cannot be flattened as it is. Messages name the element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TopologyError {
    #[error("the mesh has no triangles")]
    Empty,
    #[error("triangle {triangle} refers to vertex {vertex}, but the mesh has {count} vertices")]
    BadIndex {
        triangle: usize,
        vertex: u32,
        count: usize,
    },
    #[error("triangle {triangle} is degenerate (repeated vertex {vertex})")]
    RepeatedVertex { triangle: usize, vertex: u32 },
    #[error("triangle {triangle} has zero area (collinear corners {a}, {b}, {c})")]
    ZeroArea {
        triangle: usize,
        a: u32,
        b: u32,
        c: u32,
    },
    #[error("triangles {first} and {second} are duplicates (same three vertices)")]
    DuplicateTriangle { first: usize, second: usize },
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite { vertex: usize },
    #[error(
        "edge {a}-{b} is shared by {count} triangles (non-manifold edge); split the mesh there"
    )]
    NonManifoldEdge { a: u32, b: u32, count: usize },
    #[error(
        "edge {a}-{b} is used twice in the same direction: triangles {t0} and {t1} have inconsistent orientation"
    )]
    InconsistentOrientation {
        a: u32,
        b: u32,
        t0: usize,
        t1: usize,
    },
    #[error("vertex {vertex} is non-manifold (its triangles form {fans} separate fans)")]
    NonManifoldVertex { vertex: u32, fans: usize },
    #[error(
        "the mesh is closed (no boundary): add a seam (a path of mesh vertices) to cut it open"
    )]
    NoBoundary,
    #[error(
        "the mesh has {count} boundary loops: it is not a disk; add seams joining the holes to the outer boundary (or flatten each region separately)"
    )]
    SeveralBoundaries { count: usize },
    #[error("the mesh has {count} connected components: flatten each one separately")]
    SeveralComponents { count: usize },
    #[error("the mesh has Euler characteristic {chi}, a disk has 1: add seams to cut handles open")]
    NotADisk { chi: i64 },
    #[error("seam {seam}: vertex {vertex} does not exist (the mesh has {count} vertices)")]
    SeamBadVertex {
        seam: usize,
        vertex: u32,
        count: usize,
    },
    #[error("seam {seam}: vertices {a} and {b} are consecutive but not joined by a mesh edge")]
    SeamNotAnEdge { seam: usize, a: u32, b: u32 },
    #[error(
        "seam {seam}: point {point} cannot be reached from the previous point along mesh edges"
    )]
    SeamUnreachable { seam: usize, point: usize },
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
    pub fn is_boundary(&self) -> bool {
        self.fwd.is_none() || self.rev.is_none()
    }
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
    pub component_count: usize,
}

impl Topology {
    /// Builds the adjacency. Fails on bad indices, repeated vertices, non-manifold edges and
    /// inconsistent orientation (the conditions under which boundary loops are undefined).
    pub fn build(mesh: &TriMesh) -> Result<Self, TopologyError> {
        let n = mesh.positions.len();
        let mut edges: BTreeMap<(u32, u32), EdgeInfo> = BTreeMap::new();
        let mut counts: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                if v as usize >= n {
                    return Err(TopologyError::BadIndex {
                        triangle: t,
                        vertex: v,
                        count: n,
                    });
                }
            }
            for k in 0..3 {
                if tri[k] == tri[(k + 1) % 3] {
                    return Err(TopologyError::RepeatedVertex {
                        triangle: t,
                        vertex: tri[k],
                    });
                }
            }
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                *counts.entry(key).or_insert(0) += 1;
                let e = edges.entry(key).or_insert(EdgeInfo {
                    fwd: None,
                    rev: None,
                });
                let slot = if a < b { &mut e.fwd } else { &mut e.rev };
                if let Some(prev) = *slot {
                    if counts[&key] > 2 {
                        return Err(TopologyError::NonManifoldEdge {
                            a: key.0,
                            b: key.1,
                            count: counts[&key],
                        });
                    }
                    return Err(TopologyError::InconsistentOrientation {
                        a,
                        b,
                        t0: prev as usize,
                        t1: t,
                    });
                }
                *slot = Some(t as u32);
            }
        }
        if let Some((&(a, b), &count)) = counts.iter().find(|(_, c)| **c > 2) {
            return Err(TopologyError::NonManifoldEdge { a, b, count });
        }

        // Components by union-find over shared edges.
        let mut parent: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        for e in edges.values() {
            if let (Some(a), Some(b)) = (e.fwd, e.rev) {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
        // Triangles sharing only a vertex are also connected.
        let mut first_tri_of_vertex: Vec<Option<u32>> = vec![None; n];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                match first_tri_of_vertex[v as usize] {
                    None => first_tri_of_vertex[v as usize] = Some(t as u32),
                    Some(o) => {
                        let (ra, rb) = (find(&mut parent, o), find(&mut parent, t as u32));
                        if ra != rb {
                            parent[ra.max(rb) as usize] = ra.min(rb);
                        }
                    }
                }
            }
        }
        let mut label: BTreeMap<u32, u32> = BTreeMap::new();
        let mut component_of_triangle = Vec::with_capacity(mesh.triangles.len());
        for t in 0..mesh.triangles.len() as u32 {
            let r = find(&mut parent, t);
            let next = label.len() as u32;
            component_of_triangle.push(*label.entry(r).or_insert(next));
        }

        // Boundary loops: directed boundary half-edges a->b (as in their triangle).
        let mut next_of: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
        for (&(lo, hi), e) in &edges {
            match (e.fwd, e.rev) {
                (Some(_), None) => next_of.entry(lo).or_default().push(hi),
                (None, Some(_)) => next_of.entry(hi).or_default().push(lo),
                _ => {}
            }
        }
        let mut boundary_loops = Vec::new();
        let mut used: BTreeMap<(u32, u32), bool> = BTreeMap::new();
        for (&start, outs) in &next_of {
            for &first in outs {
                if used.contains_key(&(start, first)) {
                    continue;
                }
                let mut lp = vec![start];
                used.insert((start, first), true);
                let mut cur = first;
                let mut guard = 0usize;
                while cur != start && guard <= edges.len() {
                    lp.push(cur);
                    let nexts = next_of.get(&cur).cloned().unwrap_or_default();
                    let Some(&nx) = nexts.iter().find(|&&x| !used.contains_key(&(cur, x))) else {
                        break;
                    };
                    used.insert((cur, nx), true);
                    cur = nx;
                    guard += 1;
                }
                boundary_loops.push(lp);
            }
        }
        Ok(Self {
            edges,
            boundary_loops,
            component_of_triangle,
            component_count: label.len(),
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
    let mut seen: BTreeMap<[u32; 3], usize> = BTreeMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut key = *tri;
        key.sort_unstable();
        if let Some(&first) = seen.get(&key) {
            return Err(TopologyError::DuplicateTriangle { first, second: t });
        }
        seen.insert(key, t);
        let [a, b, c] = mesh.corners(t);
        let scale = (b - a).length().max((c - a).length()).max((c - b).length());
        // Relative area test: a sliver whose area is below round-off of its edge lengths.
        if (b - a).cross(c - a).length() <= 1e-14 * scale * scale {
            return Err(TopologyError::ZeroArea {
                triangle: t,
                a: tri[0],
                b: tri[1],
                c: tri[2],
            });
        }
    }
    if topo.component_count > 1 {
        return Err(TopologyError::SeveralComponents {
            count: topo.component_count,
        });
    }
    // Non-manifold vertex: a vertex on more than one boundary passage.
    let mut boundary_visits: BTreeMap<u32, usize> = BTreeMap::new();
    for lp in &topo.boundary_loops {
        for &v in lp {
            *boundary_visits.entry(v).or_insert(0) += 1;
        }
    }
    if let Some((&v, &k)) = boundary_visits.iter().find(|(_, k)| **k > 1) {
        return Err(TopologyError::NonManifoldVertex { vertex: v, fans: k });
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
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let mut t = Vec::new();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        TriMesh::new(p, t)
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
}
