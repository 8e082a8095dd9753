//! Mating seams: two boundary stretches that are sewn together, on two meshes or on one (a dart,
//! a tube's seam), given as equally long lists of boundary vertices so that vertex k of one side
//! is sewn to vertex k of the other. Both sides run from the seam's start to its end; notches
//! sit at seam vertices, so a notch is at the same place on both sides by construction.
//!
//! The flattener keeps each pair of corresponding edges equally long; the report measures the
//! two sides' lengths and the notches' offsets from the seam's start.

use flatcut_geom::{DVec2, DVec3};

use crate::TriMesh;

/// One side of a mating seam: a piece (an index into the meshes the seam belongs to) and its
/// vertices along the seam.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeamSide {
    /// The piece (index into the meshes the seam belongs to).
    pub piece: usize,
    /// The piece's boundary vertices along the seam, in sewing order; as many as the other side's.
    pub vertices: Vec<u32>,
}

/// A notch on a mating seam: its name and the index of its vertex along the seam.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeamNotch {
    /// The notch's name.
    pub name: String,
    /// 0-based index of its vertex in each side's `vertices`.
    pub index: usize,
}

/// Two boundary stretches sewn together.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MatingSeam {
    /// The seam's name, used in the report and on notches.
    pub name: String,
    /// The two sides; `vertices[i]` of one is sewn to `vertices[i]` of the other.
    pub sides: [SeamSide; 2],
    /// The notches on the seam.
    pub notches: Vec<SeamNotch>,
}

/// What is wrong with a mating seam.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MatingError {
    #[error("mating seam '{seam}': its sides have {a} and {b} vertices (they must match)")]
    /// The sides have different numbers of vertices.
    Count {
        /// The seam's name.
        seam: String,
        /// Vertices of side 0.
        a: usize,
        /// Vertices of side 1.
        b: usize,
    },
    #[error("mating seam '{seam}': a side needs at least two vertices")]
    /// A side has fewer than two vertices.
    Short {
        /// The seam's name.
        seam: String,
    },
    #[error("mating seam '{seam}': side {side} names piece {piece}, but there are {count}")]
    /// A side names a piece that does not exist.
    Piece {
        /// The seam's name.
        seam: String,
        /// The side, 0 or 1.
        side: usize,
        /// The piece it names.
        piece: usize,
        /// Pieces there are.
        count: usize,
    },
    #[error("mating seam '{seam}': side {side} names vertex {vertex}, but its piece has {count}")]
    /// A side names a vertex its piece does not have.
    Vertex {
        /// The seam's name.
        seam: String,
        /// The side, 0 or 1.
        side: usize,
        /// The vertex it names.
        vertex: u32,
        /// Vertices the piece has.
        count: usize,
    },
    #[error("mating seam '{seam}': notch '{notch}' is at index {index}, past the seam's end")]
    /// A notch lies past the seam's end.
    Notch {
        /// The seam's name.
        seam: String,
        /// The notch's name.
        notch: String,
        /// Its index along the seam.
        index: usize,
    },
}

impl MatingSeam {
    /// Checks the seam against the meshes it refers to.
    pub fn check(&self, meshes: &[&TriMesh]) -> Result<(), MatingError> {
        let seam = || self.name.clone();
        let (a, b) = (self.sides[0].vertices.len(), self.sides[1].vertices.len());
        if a != b {
            return Err(MatingError::Count { seam: seam(), a, b });
        }
        if a < 2 {
            return Err(MatingError::Short { seam: seam() });
        }
        for (k, s) in self.sides.iter().enumerate() {
            let mesh = meshes.get(s.piece).ok_or(MatingError::Piece {
                seam: seam(),
                side: k,
                piece: s.piece,
                count: meshes.len(),
            })?;
            if let Some(&v) = s
                .vertices
                .iter()
                .find(|&&v| v as usize >= mesh.positions.len())
            {
                return Err(MatingError::Vertex {
                    seam: seam(),
                    side: k,
                    vertex: v,
                    count: mesh.positions.len(),
                });
            }
        }
        if let Some(n) = self.notches.iter().find(|n| n.index >= a) {
            return Err(MatingError::Notch {
                seam: seam(),
                notch: n.name.clone(),
                index: n.index,
            });
        }
        Ok(())
    }

    /// The 3D polyline of side `k`.
    pub fn points_3d(&self, k: usize, meshes: &[&TriMesh]) -> Vec<DVec3> {
        let s = &self.sides[k];
        s.vertices
            .iter()
            .map(|&v| meshes[s.piece].positions[v as usize])
            .collect()
    }

    /// The flat polyline of side `k`, when its mesh is flattened.
    pub fn points_2d(&self, k: usize, meshes: &[&TriMesh]) -> Option<Vec<DVec2>> {
        let s = &self.sides[k];
        let flat = meshes[s.piece].flat.as_ref()?;
        Some(s.vertices.iter().map(|&v| flat[v as usize]).collect())
    }
}

/// Arc length from a polyline's start to each of its points, with `dist` the length of a step.
pub fn arc_lengths<P>(points: &[P], dist: impl Fn(&P, &P) -> f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += dist(&points[i - 1], p);
        }
        out.push(s);
    }
    out
}

/// The mating seams of meshes written from one split surface (`flatten`'s `OUT-<piece>.obj`
/// files): boundary stretches of two meshes (or two stretches of one) whose vertices sit at
/// identical 3D coordinates, edge for edge. Each maximal run of such edges is a seam named
/// `"<a>/<b>"` (`"<a>/<b>-2"`, … when the pair shares several); `names` names the meshes. The
/// sides run along the first mesh's boundary loop.
pub fn coincident_seams(meshes: &[&TriMesh], names: &[&str]) -> Vec<MatingSeam> {
    use std::collections::BTreeMap;
    let key = |p: DVec3| p.to_array().map(f64::to_bits);
    let loops: Vec<Vec<Vec<u32>>> = meshes
        .iter()
        .map(|m| {
            crate::Topology::build(m)
                .map(|t| t.boundary_loops)
                .unwrap_or_default()
        })
        .collect();
    // Boundary vertices by position, and boundary edges (either way) per mesh.
    let mut at: BTreeMap<[u64; 3], Vec<(usize, u32)>> = BTreeMap::new();
    let mut edges: Vec<std::collections::BTreeSet<(u32, u32)>> = Vec::new();
    for (i, ls) in loops.iter().enumerate() {
        let mut e = std::collections::BTreeSet::new();
        for lp in ls {
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                e.insert((a.min(b), a.max(b)));
                at.entry(key(meshes[i].positions[a as usize]))
                    .or_default()
                    .push((i, a));
            }
        }
        edges.push(e);
    }
    // The partner of boundary edge (a, b) of mesh i on mesh j, if any.
    // The partner edge is the boundary edge of mesh j between copies of the two ends (any copy:
    // where a cut branches or ends, one point has several, or on one mesh only itself); an
    // edge is never its own partner.
    let partner = |i: usize, a: u32, b: u32, j: usize| -> Option<(u32, u32)> {
        let copies = |v: u32| -> Vec<u32> {
            at.get(&key(meshes[i].positions[v as usize]))
                .map(|s| {
                    s.iter()
                        .filter(|&&(m, _)| m == j)
                        .map(|&(_, w)| w)
                        .collect()
                })
                .unwrap_or_default()
        };
        let (ca, cb) = (copies(a), copies(b));
        ca.iter()
            .flat_map(|&pa| cb.iter().map(move |&pb| (pa, pb)))
            .find(|&(pa, pb)| {
                let k = (pa.min(pb), pa.max(pb));
                !(i == j && k == (a.min(b), a.max(b))) && pa != pb && edges[j].contains(&k)
            })
    };
    let mut out: Vec<MatingSeam> = Vec::new();
    for i in 0..meshes.len() {
        for j in i..meshes.len() {
            let mut runs: Vec<[Vec<u32>; 2]> = Vec::new();
            for lp in &loops[i] {
                let n = lp.len();
                let paired: Vec<Option<(u32, u32)>> = (0..n)
                    .map(|k| partner(i, lp[k], lp[(k + 1) % n], j))
                    .collect();
                // Start each run where the previous edge is unpaired (or anywhere for a loop
                // paired all round).
                let start = (0..n)
                    .find(|&k| paired[(k + n - 1) % n].is_none())
                    .unwrap_or(0);
                let mut k = 0;
                while k < n {
                    let e = (start + k) % n;
                    let Some((pa, pb)) = paired[e] else {
                        k += 1;
                        continue;
                    };
                    let mut run = [vec![lp[e], lp[(e + 1) % n]], vec![pa, pb]];
                    k += 1;
                    while k < n {
                        let e = (start + k) % n;
                        match paired[e] {
                            Some((qa, qb)) if qa == *run[1].last().expect("non-empty") => {
                                run[0].push(lp[(e + 1) % n]);
                                run[1].push(qb);
                                k += 1;
                            }
                            _ => break,
                        }
                    }
                    runs.push(run);
                }
            }
            // On one mesh each seam is found from both of its sides: keep it once.
            if i == j {
                let mut kept: Vec<[Vec<u32>; 2]> = Vec::new();
                for r in runs {
                    let mut rev = [r[1].clone(), r[0].clone()];
                    rev.iter_mut().for_each(|s| s.reverse());
                    let same = |x: &[Vec<u32>; 2]| *x == rev || *x == r;
                    if !kept.iter().any(same) {
                        kept.push(r);
                    }
                }
                runs = kept;
            }
            let several = runs.len() > 1;
            for (k, [a, b]) in runs.into_iter().enumerate() {
                let base = format!("{}/{}", names[i], names[j]);
                out.push(MatingSeam {
                    name: if several {
                        format!("{base}-{}", k + 1)
                    } else {
                        base
                    },
                    sides: [
                        SeamSide {
                            piece: i,
                            vertices: a,
                        },
                        SeamSide {
                            piece: j,
                            vertices: b,
                        },
                    ],
                    notches: Vec::new(),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regions::split_along_lines;

    #[test]
    fn the_pieces_of_a_split_grid_pair_up_by_their_coordinates() {
        // A 4 × 4 grid split along x = 2: two meshes sharing the line's five vertices.
        let m = crate::test_grid::grid_mesh(4, 4, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        let id = |i: u32, j: u32| j * 5 + i;
        let line: Vec<u32> = (0..=4).map(|j| id(2, j)).collect();
        let s = split_along_lines(&m, &[line]).unwrap();
        let meshes: Vec<&TriMesh> = s.regions.iter().map(|r| &r.mesh).collect();
        let seams = coincident_seams(&meshes, &["a", "b"]);
        assert_eq!(seams.len(), 1);
        let seam = &seams[0];
        assert_eq!(seam.name, "a/b");
        assert_eq!(seam.sides[0].vertices.len(), 5);
        assert_eq!(seam.points_3d(0, &meshes), seam.points_3d(1, &meshes));
        seam.check(&meshes).unwrap();
    }
}
