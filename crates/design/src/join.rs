//! A design's `[[join]]`s as mating seams: each edge found on its piece's boundary, the notches
//! placed on both edges, and the two edges given matching vertices ([`flatcut_mesh::joins`]).

use flatcut_geom::DVec3;
use flatcut_mesh::TriMesh;
use flatcut_mesh::joins::{JoinError, boundary_vertex, match_sides, stretch, vertex_on_side};
use flatcut_mesh::lines::END_REL;
use flatcut_mesh::mating::{MatingSeam, SeamNotch, SeamSide};

use crate::{AssembledPiece, DesignError, JoinDef};

/// The mating seam of a join; the pieces' meshes get the vertices the seam needs.
pub(crate) fn join_seam(
    file: &str,
    j: &JoinDef,
    pieces: &mut [AssembledPiece],
) -> Result<MatingSeam, DesignError> {
    let err = |msg: String| DesignError::Join {
        file: file.to_string(),
        index: j.index,
        join: j.name.clone(),
        msg,
    };
    let find = |name: &str| {
        pieces
            .iter()
            .position(|p| p.def.name == name)
            .ok_or_else(|| err(format!("there is no piece named '{name}'")))
    };
    let idx = [find(&j.a.piece)?, find(&j.b.piece)?];
    let mut meshes: Vec<TriMesh> = pieces
        .iter_mut()
        .map(|p| std::mem::take(&mut p.mesh))
        .collect();
    let result = build(j, idx, &mut meshes).map_err(|(side, e)| err(format!("{side}: {e}")));
    for (p, m) in pieces.iter_mut().zip(meshes) {
        p.mesh = m;
    }
    result
}

fn v3(p: &[f64; 3]) -> DVec3 {
    DVec3::from_array(*p)
}

fn build(
    j: &JoinDef,
    idx: [usize; 2],
    meshes: &mut [TriMesh],
) -> Result<MatingSeam, (&'static str, JoinError)> {
    let mut sides: [SeamSide; 2] = idx.map(|piece| SeamSide {
        piece,
        vertices: Vec::new(),
    });
    let names = ["edge a", "edge b"];
    for (k, e) in [&j.a, &j.b].into_iter().enumerate() {
        let m = &mut meshes[idx[k]];
        let tol = END_REL * m.bbox().diagonal();
        let from = boundary_vertex(m, v3(&e.from), tol, "`from`").map_err(|x| (names[k], x))?;
        let to = boundary_vertex(m, v3(&e.to), tol, "`to`").map_err(|x| (names[k], x))?;
        sides[k].vertices =
            stretch(m, from, to, e.via.as_ref().map(v3)).map_err(|x| (names[k], x))?;
    }
    if idx[0] == idx[1] {
        let shared = sides[0].vertices.windows(2).any(|a| {
            sides[1]
                .vertices
                .windows(2)
                .any(|b| (a[0], a[1]) == (b[0], b[1]) || (a[0], a[1]) == (b[1], b[0]))
        });
        if shared {
            return Err(("edges a and b", JoinError::Overlap));
        }
    }
    // The notches as vertices of both edges.
    let mut notch_vertices = vec![[0u32; 2]; j.notches.len()];
    for (n, p) in j.notches.iter().enumerate() {
        for k in 0..2 {
            let m = &mut meshes[idx[k]];
            let tol = END_REL * m.bbox().diagonal();
            let what = format!("notch {n}");
            let i = vertex_on_side(m, &mut sides[k].vertices, v3(p), tol, &what)
                .map_err(|x| (names[k], x))?;
            notch_vertices[n][k] = sides[k].vertices[i];
        }
    }
    let pos = |k: usize, v: u32| sides[k].vertices.iter().position(|&x| x == v).unwrap_or(0);
    let mut order: Vec<usize> = (0..j.notches.len()).collect();
    order.sort_by_key(|&n| pos(0, notch_vertices[n][0]));
    let mut knots = vec![[0usize, 0]];
    for &n in &order {
        knots.push([pos(0, notch_vertices[n][0]), pos(1, notch_vertices[n][1])]);
    }
    knots.push([sides[0].vertices.len() - 1, sides[1].vertices.len() - 1]);
    let at = match_sides(meshes, &mut sides, &knots).map_err(|x| ("edges a and b", x))?;
    let notches: Vec<SeamNotch> = order
        .iter()
        .enumerate()
        .map(|(r, &n)| SeamNotch {
            name: format!("{} {}", j.name, n + 1),
            index: at[r + 1],
        })
        .collect();
    Ok(MatingSeam {
        name: j.name.clone(),
        sides,
        notches,
    })
}
