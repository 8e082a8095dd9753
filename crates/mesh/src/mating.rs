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
    pub piece: usize,
    pub vertices: Vec<u32>,
}

/// A notch on a mating seam: its name and the index of its vertex along the seam.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeamNotch {
    pub name: String,
    pub index: usize,
}

/// Two boundary stretches sewn together.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MatingSeam {
    pub name: String,
    pub sides: [SeamSide; 2],
    pub notches: Vec<SeamNotch>,
}

/// What is wrong with a mating seam.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MatingError {
    #[error("mating seam '{seam}': its sides have {a} and {b} vertices (they must match)")]
    Count { seam: String, a: usize, b: usize },
    #[error("mating seam '{seam}': a side needs at least two vertices")]
    Short { seam: String },
    #[error("mating seam '{seam}': side {side} names piece {piece}, but there are {count}")]
    Piece {
        seam: String,
        side: usize,
        piece: usize,
        count: usize,
    },
    #[error("mating seam '{seam}': side {side} names vertex {vertex}, but its piece has {count}")]
    Vertex {
        seam: String,
        side: usize,
        vertex: u32,
        count: usize,
    },
    #[error("mating seam '{seam}': notch '{notch}' is at index {index}, past the seam's end")]
    Notch {
        seam: String,
        notch: String,
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
