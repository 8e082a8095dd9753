//! The edges a STEP model's faces share, where the faces land in different pieces, as mating
//! seams: pieces expanded from one model are meshed with every shared edge sampled the same way
//! on both sides, so the edge is a run of boundary vertices at identical coordinates on the two
//! pieces ([`flatcut_mesh::mating::coincident_seams`]). Each run becomes a join between the two
//! pieces (its ends and a middle point given in 3D), built like a `[[join]]` once the pieces'
//! notch marks are in their meshes, so a notch on either side finds its counterpart on the other.

use std::sync::Arc;

use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::coincident_seams;

use crate::{AssembledPiece, JoinDef, JoinEdgeDef, SurfaceDef};

/// The joins along the shared edges of the STEP pieces among `pieces` (numbered from
/// `first_index` for messages), pieces of one model only, in the order of the pieces.
pub(crate) fn shared_edge_joins(pieces: &[AssembledPiece], first_index: usize) -> Vec<JoinDef> {
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
        let meshes: Vec<&TriMesh> = members.iter().map(|&k| &pieces[k].mesh).collect();
        let names: Vec<&str> = members
            .iter()
            .map(|&k| pieces[k].def.name.as_str())
            .collect();
        for s in coincident_seams(&meshes, &names) {
            let [a, b] = &s.sides;
            if a.piece == b.piece || a.vertices.len() < 2 {
                continue;
            }
            let (pa, pb) = (members[a.piece], members[b.piece]);
            let at = |v: u32| pieces[pa].mesh.positions[a.vertices[v as usize] as usize];
            let n = a.vertices.len() as u32;
            let closed = at(0) == at(n - 1);
            // A closed run is two joins (a join's ends must differ).
            let spans: Vec<(u32, u32)> = if closed {
                vec![(0, n / 2), (n / 2, n - 1)]
            } else {
                vec![(0, n - 1)]
            };
            for (h, &(i, j)) in spans.iter().enumerate() {
                let (from, to) = (at(i).to_array(), at(j).to_array());
                let via = (j > i + 1).then(|| at((i + j) / 2).to_array());
                let edge = |piece: usize| JoinEdgeDef {
                    piece: pieces[piece].def.name.clone(),
                    from,
                    to,
                    via,
                };
                let name = if spans.len() > 1 {
                    format!("{}-{}", s.name, h + 1)
                } else {
                    s.name.clone()
                };
                out.push(JoinDef {
                    name,
                    a: edge(pa),
                    b: edge(pb),
                    notches: Vec::new(),
                    index: first_index + out.len(),
                });
            }
        }
    }
    out
}
