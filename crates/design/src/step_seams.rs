//! The edges a STEP model's faces share, where the faces land in different pieces, as mating
//! seams: one per shared edge, of its full length. The pieces of one model are meshed from one
//! tessellation ([`crate::step::StepSource::tessellation`]), so an edge is the same polyline on
//! both pieces; each side is that polyline found on the piece's boundary, point for point (a
//! notch mark put on the edge is a vertex between two of its points, and must be on both sides).
//! A closed edge (a rim) is two seams, one per half. A shared edge that cannot be found on both
//! pieces' boundaries is an error naming it: never a seam left unsewn.

use std::collections::BTreeMap;
use std::sync::Arc;

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::mating::{MatingSeam, SeamSide};
use flatcut_mesh::{Topology, TriMesh};

use crate::{AssembledPiece, DesignError, StepFaces, SurfaceDef};

/// A point lies on a segment of the edge's polyline when it is this close to it, relative to
/// the segment's length (a notch inserted there).
const ON_SEGMENT_REL: f64 = 1e-9;

fn key(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

/// A piece's boundary loops and where each boundary vertex sits in them, by exact position.
struct Boundary {
    loops: Vec<Vec<u32>>,
    at: BTreeMap<[u64; 3], Vec<(usize, usize)>>,
}

impl Boundary {
    fn of(m: &TriMesh) -> Self {
        let loops = Topology::build(m)
            .map(|t| t.boundary_loops)
            .unwrap_or_default();
        let mut at: BTreeMap<[u64; 3], Vec<(usize, usize)>> = BTreeMap::new();
        for (l, lp) in loops.iter().enumerate() {
            for (i, &v) in lp.iter().enumerate() {
                at.entry(key(m.positions[v as usize]))
                    .or_default()
                    .push((l, i));
            }
        }
        Self { loops, at }
    }

    /// The boundary vertices along the polyline `pts` (from its first point to its last, every
    /// point of it in order, and any vertex between two of them on their segment), if the
    /// boundary runs along it without a break.
    fn along(&self, m: &TriMesh, pts: &[DVec3]) -> Option<Vec<u32>> {
        let starts = self.at.get(&key(pts[0]))?;
        starts
            .iter()
            .flat_map(|&s| [(s, 1isize), (s, -1)])
            .find_map(|(s, dir)| self.walk(m, pts, s, dir).filter(|w| w.1 == pts.len()))
            .map(|w| w.0)
    }

    /// Walks the boundary from loop position `(l, i)` in direction `dir` along `pts`: the
    /// vertices passed and how many of the points were reached.
    fn walk(
        &self,
        m: &TriMesh,
        pts: &[DVec3],
        (l, i): (usize, usize),
        dir: isize,
    ) -> Option<(Vec<u32>, usize)> {
        let lp = &self.loops[l];
        let len = lp.len();
        if m.positions[lp[i] as usize] != pts[0] {
            return None;
        }
        let mut out = vec![lp[i]];
        let mut k = 1;
        let mut j = i as isize;
        for _ in 0..len {
            if k == pts.len() {
                break;
            }
            j = (j + dir).rem_euclid(len as isize);
            let v = lp[j as usize];
            let p = m.positions[v as usize];
            if p == pts[k] {
                out.push(v);
                k += 1;
            } else if on_segment(p, pts[k - 1], pts[k]) {
                out.push(v);
            } else {
                break;
            }
        }
        (k > 1).then_some((out, k))
    }

    /// The indices of the points of `pts` where the boundary leaves the polyline and takes it up
    /// again at another copy of the point (a cut of the piece meets the edge there), if the
    /// boundary runs along the whole polyline that way.
    fn breaks(&self, m: &TriMesh, pts: &[DVec3]) -> Option<Vec<usize>> {
        let mut out = Vec::new();
        let mut from = 0;
        while from + 1 < pts.len() {
            let rest = &pts[from..];
            let best = self
                .at
                .get(&key(rest[0]))?
                .iter()
                .flat_map(|&s| [(s, 1isize), (s, -1)])
                .filter_map(|(s, dir)| self.walk(m, rest, s, dir))
                .map(|w| w.1)
                .max()?;
            if best < 2 {
                return None;
            }
            from += best - 1;
            if from + 1 < pts.len() {
                out.push(from);
            }
        }
        Some(out)
    }
}

fn on_segment(p: DVec3, a: DVec3, b: DVec3) -> bool {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return false;
    }
    let t = (p - a).dot(ab) / l2;
    t > 0.0 && t < 1.0 && (a + ab * t).distance(p) <= ON_SEGMENT_REL * l2.sqrt()
}

/// The mating seams along the edges shared by STEP pieces of one model (pieces of different
/// models never share an edge), in the order of the pieces and the edges.
pub(crate) fn shared_edge_seams(
    pieces: &[AssembledPiece],
    tol: &Tolerances,
) -> Result<Vec<MatingSeam>, DesignError> {
    // The STEP pieces, grouped by the model they were expanded from (by identity).
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        let SurfaceDef::Step { model: Some(m), .. } = &p.def.surface else {
            continue;
        };
        let id = Arc::as_ptr(&m.0) as usize;
        match groups.iter_mut().find(|(g, _)| *g == id) {
            Some((_, members)) => members.push(k),
            None => groups.push((id, vec![k])),
        }
    }
    let mut out = Vec::new();
    for (_, members) in groups.iter().filter(|(_, m)| m.len() > 1) {
        let first = &pieces[members[0]];
        let SurfaceDef::Step {
            model: Some(sm), ..
        } = &first.def.surface
        else {
            continue;
        };
        let err = |k: usize, msg: String| DesignError::Piece {
            file: pieces[k].def.file.clone(),
            index: pieces[k].def.index,
            piece: pieces[k].def.name.clone(),
            msg,
        };
        let (model, t) =
            sm.0.tessellation(tol)
                .map_err(|e| err(members[0], e.to_string()))?;
        // The piece each face is in.
        let mut piece_of: BTreeMap<usize, usize> = BTreeMap::new();
        for &k in members {
            if let SurfaceDef::Step {
                faces: StepFaces::List(fs),
                ..
            } = &pieces[k].def.surface
            {
                for &f in fs {
                    piece_of.insert(f, k);
                }
            }
        }
        let bounds: BTreeMap<usize, Boundary> = members
            .iter()
            .map(|&k| (k, Boundary::of(&pieces[k].mesh)))
            .collect();
        for em in &t.edges {
            let edge = &model.edges[em.edge];
            let [fa, fb] = edge.faces.as_slice() else {
                continue;
            };
            let (Some(&pa), Some(&pb)) = (piece_of.get(fa), piece_of.get(fb)) else {
                continue;
            };
            if pa == pb {
                continue;
            }
            let pts: Vec<DVec3> = em
                .vertices
                .iter()
                .map(|&v| t.positions[v as usize])
                .collect();
            let n = pts.len();
            let missing = |k: usize| {
                err(
                    k,
                    format!(
                        "the edge #{} it shares with piece '{}' is not on its boundary: the seam cannot be sewn",
                        edge.entity,
                        pieces[if k == pa { pb } else { pa }].def.name
                    ),
                )
            };
            // Split where a closed edge comes round, and where either piece is cut open.
            let mut cuts: Vec<usize> = vec![0, n - 1];
            if pts[0] == pts[n - 1] && n > 2 {
                cuts.push(n / 2);
            }
            for k in [pa, pb] {
                cuts.extend(
                    bounds[&k]
                        .breaks(&pieces[k].mesh, &pts)
                        .ok_or_else(|| missing(k))?,
                );
            }
            cuts.sort_unstable();
            cuts.dedup();
            let runs: Vec<&[DVec3]> = cuts.windows(2).map(|w| &pts[w[0]..=w[1]]).collect();
            for (h, half) in runs.iter().enumerate() {
                let side = |k: usize| {
                    bounds[&k]
                        .along(&pieces[k].mesh, half)
                        .ok_or_else(|| missing(k))
                };
                let (a, b) = (side(pa)?, side(pb)?);
                if a.len() != b.len() {
                    return Err(err(
                        pa,
                        format!(
                            "the edge #{} it shares with piece '{}' has {} points on it and {} on the other (a notch mark on one side only: mark it on both)",
                            edge.entity,
                            pieces[pb].def.name,
                            a.len(),
                            b.len()
                        ),
                    ));
                }
                let mut name = format!(
                    "{}/{} #{}",
                    pieces[pa].def.name, pieces[pb].def.name, edge.entity
                );
                if runs.len() > 1 {
                    name = format!("{name}-{}", h + 1);
                }
                out.push(MatingSeam {
                    name,
                    sides: [
                        SeamSide {
                            piece: pa,
                            vertices: a,
                        },
                        SeamSide {
                            piece: pb,
                            vertices: b,
                        },
                    ],
                    notches: Vec::new(),
                });
            }
        }
    }
    Ok(out)
}
