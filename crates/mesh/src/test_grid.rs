//! Test support: a tensor-grid mesh of `nu` × `nv` quads, each split into two triangles along
//! the same diagonal, with the vertex of grid node (i, j) placed by the caller. The fixture the
//! crate's tests build their flat grids, jittered grids and cylinders from.

use flatcut_geom::DVec3;

use crate::TriMesh;

/// The grid mesh; `at(i, j)` for i in 0..=nu, j in 0..=nv is the vertex of node (i, j). The quad
/// (i, j) → (i+1, j) → (i+1, j+1) → (i, j+1) runs counter-clockwise in the (i, j) plane.
pub(crate) fn grid_mesh(nu: usize, nv: usize, at: impl Fn(usize, usize) -> DVec3) -> TriMesh {
    let mut p = Vec::with_capacity((nu + 1) * (nv + 1));
    for j in 0..=nv {
        for i in 0..=nu {
            p.push(at(i, j));
        }
    }
    let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    let mut t = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(p, t)
}
