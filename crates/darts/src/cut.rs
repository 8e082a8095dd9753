//! A piece cut open along dart paths: the cut mesh, which of its vertices came from which
//! vertex of the piece, the pairs of edges on the two legs of each dart, and the transfer of a
//! flattening from one cut to a finer one.
//!
//! Cutting keeps the triangles and their order ([`flatcut_mesh::cut_along_seams`]); only
//! vertices on a cut are duplicated, so a triangle's corners name its vertices in every cut of
//! the same piece and a map moves from one cut to the next corner by corner.

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TopologyError, TriMesh, cut_along_seams};

use crate::sewn::EdgePairs;

/// A piece cut along a set of paths.
#[derive(Clone, Debug)]
pub struct CutMesh {
    /// The cut mesh (same triangles, in the same order, as the piece).
    pub mesh: TriMesh,
    /// For every vertex of the cut mesh, the vertex of the piece it is a copy of.
    pub origin: Vec<u32>,
}

impl CutMesh {
    /// Cuts `piece` along `paths` (vertex paths of the piece joined by its edges).
    pub fn new(piece: &TriMesh, paths: &[Vec<u32>]) -> Result<Self, TopologyError> {
        let mesh = cut_along_seams(piece, paths)?;
        let mut origin = vec![0u32; mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                origin[tri[k] as usize] = piece.triangles[t][k];
            }
        }
        Ok(Self { mesh, origin })
    }

    /// A map of `from` (a finer cut of the same piece) carried to this cut: a vertex takes the
    /// position of its copy in `from`, or the mean of its copies where `from` is cut and this
    /// cut is not.
    pub fn merge_from(&self, from: &CutMesh, x: &[DVec2]) -> Vec<DVec2> {
        let n = self.mesh.positions.len();
        let mut copies: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tri) in self.mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let c = &mut copies[tri[k] as usize];
                let old = from.mesh.triangles[t][k];
                if !c.contains(&old) {
                    c.push(old);
                }
            }
        }
        copies
            .iter()
            .map(|c| match c.as_slice() {
                [one] => x[*one as usize],
                many => {
                    many.iter().map(|&v| x[v as usize]).sum::<DVec2>() / many.len().max(1) as f64
                }
            })
            .collect()
    }

    /// A map of `from` (a coarser cut of the same piece) carried to this cut: every copy of a
    /// vertex takes the position its corner had.
    pub fn transfer(&self, from: &CutMesh, x: &[DVec2]) -> Vec<DVec2> {
        let mut out = vec![DVec2::ZERO; self.mesh.positions.len()];
        for (t, tri) in self.mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                out[tri[k] as usize] = x[from.mesh.triangles[t][k] as usize];
            }
        }
        out
    }
}

/// The two sides of a cut path in the cut mesh: per side, the cut-mesh vertex of every path
/// vertex (side 0 is the side of the triangle in which the path's edges run forward).
#[derive(Clone, Debug, PartialEq)]
pub struct Legs {
    /// Side 0's and side 1's cut-mesh vertices (0-based), one per path vertex in path order
    /// (mouth first).
    pub sides: [Vec<u32>; 2],
}

impl Legs {
    /// The legs of `path` (a path of the piece's vertices) in `cut`; `None` when an edge of the
    /// path is not an interior edge of the piece.
    pub fn of(piece_topo: &Topology, piece: &TriMesh, cut: &CutMesh, path: &[u32]) -> Option<Self> {
        let mut sides: [Vec<u32>; 2] = [Vec::new(), Vec::new()];
        for w in path.windows(2) {
            let (a, b) = (w[0], w[1]);
            let e = piece_topo.edges.get(&(a.min(b), a.max(b)))?;
            let (t0, t1) = (e.fwd?, e.rev?);
            // Side 0: the triangle in which the path runs a -> b.
            let runs_forward = |t: u32| {
                let tri = piece.triangles[t as usize];
                (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
            };
            let (s0, s1) = if runs_forward(t0) { (t0, t1) } else { (t1, t0) };
            for (side, t) in [(0usize, s0), (1usize, s1)] {
                let tri = piece.triangles[t as usize];
                let ct = cut.mesh.triangles[t as usize];
                let at = |v: u32| ct[tri.iter().position(|&x| x == v).unwrap_or(0)];
                if sides[side].is_empty() {
                    sides[side].push(at(a));
                }
                sides[side].push(at(b));
            }
        }
        Some(Self { sides })
    }

    /// The edge pairs of these legs: the two copies of every path edge.
    pub fn pairs(&self) -> Vec<[(usize, usize); 2]> {
        let [s0, s1] = &self.sides;
        (0..s0.len().saturating_sub(1))
            .map(|i| {
                [
                    (s0[i] as usize, s0[i + 1] as usize),
                    (s1[i] as usize, s1[i + 1] as usize),
                ]
            })
            .collect()
    }

    /// 2D length of each side (mm).
    pub fn lengths_2d(&self, x: &[DVec2]) -> [f64; 2] {
        self.sides.clone().map(|s| {
            s.windows(2)
                .map(|w| x[w[0] as usize].distance(x[w[1] as usize]))
                .sum()
        })
    }
}

/// The edge pairs of every path's legs.
pub fn all_pairs(legs: &[Legs]) -> EdgePairs {
    let mut pairs = Vec::new();
    let mut groups = Vec::with_capacity(legs.len());
    for l in legs {
        let start = pairs.len();
        pairs.extend(l.pairs());
        groups.push(start..pairs.len());
    }
    EdgePairs {
        pairs,
        legs: groups,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_flatten::testmesh::spherical_cap;

    #[test]
    fn legs_pair_the_copies_of_each_cut_edge() {
        let cap = spherical_cap(100.0, 1.0, 8);
        // Along longitude 0 from the rim (ring 8, first vertex) to ring 4: vertices are the
        // first of each ring.
        let first = |k: usize| (1 + 3 * k * (k - 1)) as u32;
        let path: Vec<u32> = (4..=8).rev().map(first).collect();
        let topo = Topology::build(&cap).unwrap();
        let cut = CutMesh::new(&cap, std::slice::from_ref(&path)).unwrap();
        assert_eq!(cut.mesh.positions.len(), cap.positions.len() + 4);
        let legs = Legs::of(&topo, &cap, &cut, &path).unwrap();
        for s in &legs.sides {
            assert_eq!(s.len(), path.len());
            for (v, p) in s.iter().zip(&path) {
                assert_eq!(cut.origin[*v as usize], *p);
            }
        }
        // The apex is shared, the other vertices are two copies.
        assert_eq!(legs.sides[0][4], legs.sides[1][4]);
        assert!((0..4).all(|i| legs.sides[0][i] != legs.sides[1][i]));
        // A map carried from the uncut piece keeps the copies together.
        let uncut = CutMesh::new(&cap, &[]).unwrap();
        let x: Vec<DVec2> = cap.positions.iter().map(|p| p.truncate()).collect();
        let y = cut.transfer(&uncut, &x);
        assert_eq!(legs.lengths_2d(&y)[0], legs.lengths_2d(&y)[1]);
    }

    /// A dart shortened by two edges: the copies the shorter cut joins take their mean, every
    /// other vertex its own position, to the bit.
    #[test]
    fn a_shorter_cut_merges_the_copies_it_joins() {
        let cap = spherical_cap(100.0, 1.0, 8);
        let first = |k: usize| (1 + 3 * k * (k - 1)) as u32;
        let path: Vec<u32> = (4..=8).rev().map(first).collect();
        let long = CutMesh::new(&cap, std::slice::from_ref(&path)).unwrap();
        let short = CutMesh::new(&cap, &[path[..3].to_vec()]).unwrap();
        assert_eq!(short.mesh.positions.len(), cap.positions.len() + 2);
        // Each vertex of the long cut somewhere of its own.
        let x: Vec<DVec2> = (0..long.mesh.positions.len())
            .map(|i| DVec2::new(i as f64, (i * i % 7) as f64 / 3.0))
            .collect();
        let y = short.merge_from(&long, &x);
        let copies = |c: &CutMesh, p: u32| -> Vec<usize> {
            (0..c.origin.len()).filter(|&v| c.origin[v] == p).collect()
        };
        for (v, &p) in short.origin.iter().enumerate() {
            let (s, l) = (copies(&short, p), copies(&long, p));
            if s.len() == l.len() {
                // Cut alike in both (one copy, or both legs of the remaining dart): its own.
                assert!(l.iter().any(|&w| x[w] == y[v]), "vertex {v}");
            } else {
                assert_eq!((s.len(), l.len()), (1, 2), "vertex {v}");
                assert_eq!(y[v], 0.5 * (x[l[0]] + x[l[1]]), "vertex {v}");
            }
        }
        // Each leg copy of the shorter dart sits where that side's copy was.
        let topo = Topology::build(&cap).unwrap();
        let short_legs = Legs::of(&topo, &cap, &short, &path[..3]).unwrap();
        let long_legs = Legs::of(&topo, &cap, &long, &path).unwrap();
        for side in 0..2 {
            for i in 0..2 {
                let (s, l) = (short_legs.sides[side][i], long_legs.sides[side][i]);
                assert_eq!(y[s as usize], x[l as usize]);
            }
        }
    }
}
