//! A mirrored layout: a surface symmetric across a plane ([`flatcut_mesh::symmetry`]) is cut
//! along the plane, one half split as any surface is ([`crate::split::split_surface`]), and
//! the other half's pieces made as the mirror images of the first's, so the pattern comes in
//! left and right pairs, as garment and plush patterns are drafted: one side drawn, cut twice,
//! once reversed.
//!
//! The other half is the first half's mirror image vertex for vertex (the surface made
//! symmetric: its second half replaced by the reflection of the first, which the detection
//! found within its tolerance of it). So each mirrored piece's flat map is its twin's map
//! reflected: every face's singular values are its twin's (the limits hold), every seam between
//! two mirrored pieces has its twin's flat lengths, and a seam across the plane joins a piece to
//! its own twin along the same vertices (both sides equal edge for edge). The vertices on the
//! plane are shared by both halves at the same coordinates, so the seams across it are found by
//! their coincident vertices like every other ([`flatcut_mesh::mating::coincident_seams`]).

use std::collections::BTreeSet;

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::mating::coincident_seams;
use flatcut_mesh::symmetry::MirrorPlane;
use flatcut_mesh::{Topology, TriMesh};

use crate::DartError;
use crate::split::Split;

/// The names of the sides of a pair: the first half's pieces, then their mirror images.
pub const SIDES: [&str; 2] = ["L", "R"];

/// The split of the whole surface from the split of its first half (`half`, whose pieces lie on
/// `plane`'s normal side): its pieces followed by their mirror images in the same order (piece
/// `k` and piece `k + n` are a pair, `n` being the half's piece count), the seams between all of
/// them (named `"<k> L/<j> R"` after the pieces' 1-based numbers in their half), and the cuts
/// being every seam. `on_plane` are the half's vertices on the plane: a piece's vertex at one of
/// them is shared with its mirror image rather than reflected. With `closed` (the surface had no
/// boundary), the pieces welded by their vertices must close it again, or the result is refused.
pub fn mirror_split(
    half: Split,
    plane: &MirrorPlane,
    on_plane: &[DVec3],
    closed: bool,
) -> Result<Split, DartError> {
    let shared: BTreeSet<[u64; 3]> = on_plane.iter().map(|&p| key(p)).collect();
    let n = half.pieces.len();
    let mut pieces = half.pieces;
    let images: Vec<TriMesh> = pieces
        .iter()
        .map(|p| mirror_piece(p, plane, &shared))
        .collect();
    pieces.extend(images);
    let names: Vec<String> = (0..2 * n)
        .map(|k| format!("{} {}", k % n + 1, SIDES[k / n.max(1)]))
        .collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let refs: Vec<&TriMesh> = pieces.iter().collect();
    let seams = coincident_seams(&refs, &names);
    if closed {
        check_closed(&pieces)?;
    }
    let cuts = seams.iter().map(|s| s.points_3d(0, &refs)).collect();
    // The vertices beyond reach of the half, then their images.
    let mut beyond_reach = half.beyond_reach.clone();
    beyond_reach.extend(half.beyond_reach.iter().map(|&p| plane.reflect(p)));
    Ok(Split {
        pieces,
        seams,
        cuts,
        beyond_reach,
        ..half
    })
}

/// The mirror image of a piece: its vertices reflected (those on the plane kept), its triangles
/// turned round so they still face out, and its flat map reflected (u → −u) so each face keeps
/// its singular values and its winding.
pub fn mirror_piece(piece: &TriMesh, plane: &MirrorPlane, shared: &BTreeSet<[u64; 3]>) -> TriMesh {
    let positions = piece
        .positions
        .iter()
        .map(|&p| {
            if shared.contains(&key(p)) {
                p
            } else {
                plane.reflect(p)
            }
        })
        .collect();
    let triangles = piece.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
    let mut out = TriMesh::new(positions, triangles);
    out.flat = piece
        .flat
        .as_ref()
        .map(|uv| uv.iter().map(|q| DVec2::new(-q.x, q.y)).collect());
    out
}

/// The exact coordinates of a point, as the seams match them.
fn key(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

/// The pieces welded by their coincident vertices leave no edge unsewn.
fn check_closed(pieces: &[TriMesh]) -> Result<(), DartError> {
    let mut all: Vec<DVec3> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    for p in pieces {
        let base = all.len() as u32;
        all.extend_from_slice(&p.positions);
        tris.extend(p.triangles.iter().map(|t| t.map(|v| v + base)));
    }
    let (points, map) = flatcut_mesh::weld::weld_points(&all, 0.0);
    let welded = TriMesh::new(
        points,
        tris.iter().map(|t| t.map(|v| map[v as usize])).collect(),
    );
    let topo = Topology::build(&welded)?;
    match topo.boundary_loops.first().and_then(|l| l.first()) {
        Some(&v) => Err(DartError::Internal(format!(
            "the mirrored pieces leave a gap at ({:.2}, {:.2}, {:.2})",
            welded.positions[v as usize].x,
            welded.positions[v as usize].y,
            welded.positions[v as usize].z
        ))),
        None => Ok(()),
    }
}

#[cfg(test)]
#[path = "mirror_tests.rs"]
mod tests;
