//! The geometry testkit: a tensor-grid mesh of `nu` × `nv` quads, each split into two triangles,
//! with the vertex of grid node (i, j) placed by the caller. The one fixture the workspace's tests
//! build their flat grids, jittered grids, bent strips and L-shapes from (this crate's tests, and
//! other crates' through the `testkit` feature; not part of the public API).

use flatcut_geom::DVec3;

use crate::TriMesh;

/// Which diagonal splits a grid's quads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Diagonal {
    /// Every quad along the same diagonal, (i, j)–(i+1, j+1).
    Rising,
    /// The rising diagonal where i + j is even, the falling one, (i+1, j)–(i, j+1), where it is
    /// odd: the triangles are not all alike.
    Alternating,
}

/// The grid mesh split along the rising diagonal; `at(i, j)` for i in 0..=nu, j in 0..=nv is the
/// vertex of node (i, j). The quad (i, j) → (i+1, j) → (i+1, j+1) → (i, j+1) runs
/// counter-clockwise in the (i, j) plane.
pub fn grid_mesh(nu: usize, nv: usize, at: impl Fn(usize, usize) -> DVec3) -> TriMesh {
    grid_mesh_split(nu, nv, Diagonal::Rising, at)
}

/// [`grid_mesh`] with its quads split along `diagonal`.
pub fn grid_mesh_split(
    nu: usize,
    nv: usize,
    diagonal: Diagonal,
    at: impl Fn(usize, usize) -> DVec3,
) -> TriMesh {
    TriMesh::new(
        grid_points(nu, nv, at),
        grid_triangles(nu, nv, diagonal, |_, _| true),
    )
}

/// The nodes of the grid, row by row (`nu + 1` a row): `at(i, j)` at index `j (nu + 1) + i`.
pub fn grid_points(nu: usize, nv: usize, at: impl Fn(usize, usize) -> DVec3) -> Vec<DVec3> {
    let mut p = Vec::with_capacity((nu + 1) * (nv + 1));
    for j in 0..=nv {
        for i in 0..=nu {
            p.push(at(i, j));
        }
    }
    p
}

/// The triangles of the quads (i, j) that `keep` keeps, row by row, each quad split along
/// `diagonal` into two counter-clockwise triangles (indices of [`grid_points`]).
pub fn grid_triangles(
    nu: usize,
    nv: usize,
    diagonal: Diagonal,
    keep: impl Fn(usize, usize) -> bool,
) -> Vec<[u32; 3]> {
    let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    let mut t = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            if !keep(i, j) {
                continue;
            }
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if diagonal == Diagonal::Rising || (i + j) % 2 == 0 {
                t.extend([[a, b, c], [a, c, d]]);
            } else {
                t.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    t
}
