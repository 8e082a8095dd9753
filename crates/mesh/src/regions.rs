//! Splitting a mesh into regions along lines of its edges (style lines embedded by
//! [`crate::lines`]): every connected set of triangles between the lines becomes a mesh of its
//! own, and every stretch of a line with the same region on each side becomes a seam whose two
//! sides list the regions' own vertices along it, in the line's direction.
//!
//! The regions are found on triangle corners, as [`crate::seams::cut_along_seams`] cuts: two
//! corners of a vertex stay one vertex when an uncut edge joins them, so a line whose two sides
//! lie in the same region (a tube cut open along its length) gives that region two copies of
//! the line's vertices, one per side.

use std::collections::BTreeSet;

use crate::mating::SeamSide;
use crate::{Topology, TopologyError, TriMesh};

/// One region of the split mesh.
#[derive(Clone, Debug)]
pub struct Region {
    /// The region's triangles with their own vertices (positions copied from the input, so the
    /// vertices of a line carry the same coordinates in the regions on both sides of it).
    pub mesh: TriMesh,
    /// The input vertex of each vertex of `mesh`.
    pub origin: Vec<u32>,
    /// The input triangle of each triangle of `mesh`.
    pub faces: Vec<u32>,
}

/// A stretch of one line with the same region on each side, ordered like the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeamRun {
    /// The line (index into the lines the mesh was split along).
    pub line: usize,
    /// The index in the line's vertex path of each vertex of the seam.
    pub path_index: Vec<usize>,
    /// The side on the left of the line's direction (the triangles in which the line's edges
    /// run forward, seen from the surface's normal side), then the right side; each side's
    /// `piece` is a region index.
    pub sides: [SeamSide; 2],
}

/// A mesh split along lines.
#[derive(Clone, Debug)]
pub struct Split {
    /// The regions the lines cut the mesh into.
    pub regions: Vec<Region>,
    /// The stretches of lines between regions.
    pub seams: Vec<SeamRun>,
    /// The region of each input triangle.
    pub region_of_face: Vec<u32>,
}

/// Why a mesh cannot be split along the lines.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RegionError {
    #[error(transparent)]
    /// The mesh's topology does not allow the split.
    Topology(#[from] TopologyError),
    #[error("line {line}: vertices {a} and {b} are consecutive but not joined by a mesh edge")]
    /// Two consecutive vertices of a line are not joined by a mesh edge.
    NotAnEdge {
        /// 0-based index of the line.
        line: usize,
        /// The first vertex.
        a: u32,
        /// The vertex after it.
        b: u32,
    },
    #[error(
        "line {line} runs along the surface boundary near ({x:.2}, {y:.2}, {z:.2}): it separates nothing there"
    )]
    /// A line runs along the surface's boundary, so it separates nothing.
    AlongBoundary {
        /// 0-based index of the line.
        line: usize,
        /// x of a point where it does (mm).
        x: f64,
        /// y of a point where it does (mm).
        y: f64,
        /// z of a point where it does (mm).
        z: f64,
    },
}

/// Splits `mesh` along `lines` (vertex paths joined by mesh edges).
pub fn split_along_lines(mesh: &TriMesh, lines: &[Vec<u32>]) -> Result<Split, RegionError> {
    let topo = Topology::build(mesh)?;
    let mut cut: BTreeSet<(u32, u32)> = BTreeSet::new();
    for (line, l) in lines.iter().enumerate() {
        for w in l.windows(2) {
            if w[0] == w[1] {
                continue;
            }
            let key = (w[0].min(w[1]), w[0].max(w[1]));
            let e = topo.edges.get(&key).ok_or(RegionError::NotAnEdge {
                line,
                a: w[0],
                b: w[1],
            })?;
            if e.is_boundary() {
                let m = 0.5 * (mesh.positions[w[0] as usize] + mesh.positions[w[1] as usize]);
                return Err(RegionError::AlongBoundary {
                    line,
                    x: m.x,
                    y: m.y,
                    z: m.z,
                });
            }
            cut.insert(key);
        }
    }
    let nt = mesh.triangles.len();
    let corner = |t: u32, v: u32| -> usize {
        let tri = mesh.triangles[t as usize];
        3 * t as usize + tri.iter().position(|&x| x == v).unwrap_or(0)
    };
    let mut corners = UnionFind::new(3 * nt);
    let mut faces = UnionFind::new(nt);
    for (key, e) in &topo.edges {
        if cut.contains(key) {
            continue;
        }
        if let (Some(t1), Some(t2)) = (e.fwd, e.rev) {
            faces.union(t1 as usize, t2 as usize);
            for v in [key.0, key.1] {
                corners.union(corner(t1, v), corner(t2, v));
            }
        }
    }
    // Regions numbered by their first triangle; vertices numbered per region by first use.
    let mut region_of_root = vec![u32::MAX; nt];
    let mut region_of_face = vec![0u32; nt];
    let mut regions: Vec<Region> = Vec::new();
    let mut local_of_root = vec![u32::MAX; 3 * nt];
    for t in 0..nt {
        let root = faces.find(t);
        if region_of_root[root] == u32::MAX {
            region_of_root[root] = regions.len() as u32;
            regions.push(Region {
                mesh: TriMesh::default(),
                origin: Vec::new(),
                faces: Vec::new(),
            });
        }
        let r = region_of_root[root];
        region_of_face[t] = r;
        let reg = &mut regions[r as usize];
        let mut tri = [0u32; 3];
        for k in 0..3 {
            let c = corners.find(3 * t + k);
            if local_of_root[c] == u32::MAX {
                local_of_root[c] = reg.origin.len() as u32;
                reg.origin.push(mesh.triangles[t][k]);
            }
            tri[k] = local_of_root[c];
        }
        reg.mesh.triangles.push(tri);
        reg.faces.push(t as u32);
    }
    for reg in &mut regions {
        reg.mesh.positions = reg
            .origin
            .iter()
            .map(|&o| mesh.positions[o as usize])
            .collect();
        reg.mesh.params = mesh
            .params
            .as_ref()
            .map(|p| reg.origin.iter().map(|&o| p[o as usize]).collect());
        reg.mesh.patch_of_vertex = mesh
            .patch_of_vertex
            .as_ref()
            .map(|p| reg.origin.iter().map(|&o| p[o as usize]).collect());
        reg.mesh.flat = mesh
            .flat
            .as_ref()
            .map(|p| reg.origin.iter().map(|&o| p[o as usize]).collect());
    }
    let mut seams = Vec::new();
    for (line, l) in lines.iter().enumerate() {
        let mut runs: Vec<SeamRun> = Vec::new();
        for i in 0..l.len().saturating_sub(1) {
            let (a, b) = (l[i], l[i + 1]);
            if a == b {
                continue;
            }
            let e = topo.edges[&(a.min(b), a.max(b))];
            let (fwd, rev) = (e.fwd.expect("interior edge"), e.rev.expect("interior edge"));
            let (left, right) = if a < b { (fwd, rev) } else { (rev, fwd) };
            let side = |t: u32| {
                let loc = |v: u32| local_of_root[corners.find_const(corner(t, v))];
                (region_of_face[t as usize] as usize, loc(a), loc(b))
            };
            let (rl, la, lb) = side(left);
            let (rr, ra, rb) = side(right);
            let chained = runs.last().is_some_and(|r: &SeamRun| {
                r.sides[0].piece == rl
                    && r.sides[1].piece == rr
                    && r.sides[0].vertices.last() == Some(&la)
                    && r.sides[1].vertices.last() == Some(&ra)
                    && r.path_index.last() == Some(&i)
            });
            if chained {
                let r = runs.last_mut().expect("chained");
                r.sides[0].vertices.push(lb);
                r.sides[1].vertices.push(rb);
                r.path_index.push(i + 1);
            } else {
                runs.push(SeamRun {
                    line,
                    path_index: vec![i, i + 1],
                    sides: [
                        SeamSide {
                            piece: rl,
                            vertices: vec![la, lb],
                        },
                        SeamSide {
                            piece: rr,
                            vertices: vec![ra, rb],
                        },
                    ],
                });
            }
        }
        // A closed line's first and last runs are one seam when they chain across its start.
        let closed = l.len() > 2 && l.first() == l.last();
        if closed && runs.len() > 1 {
            let (first, last) = (&runs[0], &runs[runs.len() - 1]);
            let joins = (0..2).all(|s| {
                first.sides[s].piece == last.sides[s].piece
                    && last.sides[s].vertices.last() == first.sides[s].vertices.first()
            });
            if joins {
                let first = runs.remove(0);
                let last = runs.last_mut().expect("more than one run");
                for s in 0..2 {
                    last.sides[s]
                        .vertices
                        .extend_from_slice(&first.sides[s].vertices[1..]);
                }
                last.path_index
                    .extend(first.path_index[1..].iter().copied());
            }
        }
        seams.extend(runs);
    }
    Ok(Split {
        regions,
        seams,
        region_of_face,
    })
}

/// Disjoint sets with path halving; the representative is the smallest member, so the
/// numbering does not depend on the order of the unions.
struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    /// `find` without path compression (for shared borrows).
    fn find_const(&self, mut x: usize) -> usize {
        while self.parent[x] != x {
            x = self.parent[x];
        }
        x
    }

    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    /// A unit-spaced n × n grid in the plane z = 0, triangles CCW from +z.
    fn grid(n: usize) -> TriMesh {
        crate::test_grid::grid_mesh(n, n, |i, j| DVec3::new(i as f64, j as f64, 0.0))
    }

    #[test]
    fn a_line_across_a_grid_makes_two_regions_and_one_seam() {
        let m = grid(4);
        // The vertical line x = 2 from the bottom to the top.
        let line: Vec<u32> = (0..=4).map(|j| (j * 5 + 2) as u32).collect();
        let s = split_along_lines(&m, &[line]).unwrap();
        assert_eq!(s.regions.len(), 2);
        let area: f64 = s.regions.iter().map(|r| r.mesh.area()).sum();
        assert!((area - 16.0).abs() < 1e-12);
        assert_eq!(s.seams.len(), 1);
        let seam = &s.seams[0];
        // Going up (+y) with +z up, the left side is x < 2.
        let left = &s.regions[seam.sides[0].piece];
        assert!(left.mesh.positions.iter().all(|p| p.x <= 2.0));
        for side in &seam.sides {
            let reg = &s.regions[side.piece];
            let pts: Vec<DVec3> = side
                .vertices
                .iter()
                .map(|&v| reg.mesh.positions[v as usize])
                .collect();
            assert_eq!(pts.len(), 5);
            for (j, p) in pts.iter().enumerate() {
                assert_eq!(*p, DVec3::new(2.0, j as f64, 0.0));
            }
        }
        assert_eq!(seam.path_index, vec![0, 1, 2, 3, 4]);
        for r in &s.regions {
            crate::check_disk(&r.mesh).unwrap();
        }
    }

    #[test]
    fn crossing_lines_make_four_regions_and_four_seams() {
        let m = grid(4);
        let v: Vec<u32> = (0..=4).map(|j| (j * 5 + 2) as u32).collect();
        let h: Vec<u32> = (0..=4).map(|i| (2 * 5 + i) as u32).collect();
        let s = split_along_lines(&m, &[v, h]).unwrap();
        assert_eq!(s.regions.len(), 4);
        assert_eq!(s.seams.len(), 4);
        assert!(s.seams.iter().all(|r| r.sides[0].piece != r.sides[1].piece));
    }

    #[test]
    fn a_line_with_the_same_region_on_both_sides_is_a_seam_of_one_region() {
        // A tube: the grid's left and right columns glued (x = 0 ≡ x = 4), cut along x = 2.
        let mut m = grid(4);
        for t in &mut m.triangles {
            for v in t.iter_mut() {
                if *v % 5 == 4 {
                    *v -= 4;
                }
            }
        }
        let line: Vec<u32> = (0..=4).map(|j| (j * 5 + 2) as u32).collect();
        let s = split_along_lines(&m, &[line]).unwrap();
        assert_eq!(s.regions.len(), 1);
        let seam = &s.seams[0];
        assert_eq!(seam.sides[0].piece, seam.sides[1].piece);
        assert_ne!(seam.sides[0].vertices, seam.sides[1].vertices);
        crate::check_disk(&s.regions[0].mesh).unwrap();
    }

    #[test]
    fn a_line_along_the_boundary_is_refused() {
        let m = grid(2);
        let err = split_along_lines(&m, &[vec![0, 1, 2]]).unwrap_err();
        assert!(matches!(err, RegionError::AlongBoundary { line: 0, .. }));
    }
}
