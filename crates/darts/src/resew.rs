//! Parts sewn back together where a cut is no longer needed: the two sides of a slit that ends
//! inside a part, and two neighbouring parts whose union lies within the limits on its own.
//!
//! - **Slits.** A sphere is opened along a slit ([`crate::open`]); once the splits have cut it
//!   into parts, the stretch of the slit that runs into a part and ends there is a seam sewn to
//!   itself: flat it is a V of a few degrees (the cone angle the tip vertex lacks), no wider than
//!   a millimetre near its tip. No seam allowance fits in it and no sewer can close it, so it is
//!   sewn shut ([`close_slits`]): its two copies of each vertex, walked from the tip outward while
//!   they meet, become one again. A slit that is all of a part's outline (the opened sphere
//!   itself) is left open: closing it would close the surface.
//! - **Neighbours.** [`merge`] welds two parts along every vertex they share; the caller keeps
//!   the union only when it is one disk and lies within the limits flat (the fewest pieces for
//!   the limits).
//!
//! Vertices keep their coordinates exactly, so the seams are found again by their coincident
//! vertices ([`flatcut_mesh::mating::coincident_seams`]). A part changed here loses its map.

use std::collections::BTreeMap;

use flatcut_geom::DVec3;
use flatcut_mesh::{Topology, TriMesh, check_disk};

/// `part` with every slit that ends inside it sewn shut (see the module documentation), or
/// `None` when it has no such slit (or closing one would not leave a disk).
pub fn close_slits(part: &TriMesh) -> Option<TriMesh> {
    let topo = Topology::build(part).ok()?;
    let p = &part.positions;
    let mut into: BTreeMap<u32, u32> = BTreeMap::new();
    for l in &topo.boundary_loops {
        let n = l.len();
        if n < 4 {
            continue;
        }
        let at = |i: isize| l[i.rem_euclid(n as isize) as usize];
        for tip in 0..n as isize {
            // A tip: the outline arrives and leaves along the same 3D edge.
            let (a, b) = (at(tip - 1), at(tip + 1));
            if a == b || p[a as usize] != p[b as usize] {
                continue;
            }
            let mut pairs = Vec::new();
            let mut k = 1;
            while 2 * k < n as isize {
                let (a, b) = (at(tip - k), at(tip + k));
                if a == b || p[a as usize] != p[b as usize] {
                    break;
                }
                pairs.push((b, a));
                k += 1;
            }
            // The whole loop a slit: closing it closes the surface.
            if 2 * k >= n as isize - 1 {
                continue;
            }
            into.extend(pairs);
        }
    }
    if into.is_empty() {
        return None;
    }
    let closed = relabel(part, |v| into.get(&v).copied().unwrap_or(v));
    check_disk(&closed).ok()?;
    Some(closed)
}

/// Parts `a` and `b` welded along every vertex of `b` at the place of one of `a` (the union's
/// vertices are `a`'s, then `b`'s others). `None` when `a` has two vertices at one place that
/// `b` would join (which of them is ambiguous) or the union is not one disk.
pub fn merge(a: &TriMesh, b: &TriMesh) -> Option<TriMesh> {
    let key = |q: DVec3| [q.x.to_bits(), q.y.to_bits(), q.z.to_bits()];
    let mut of_a: BTreeMap<[u64; 3], u32> = BTreeMap::new();
    let mut twice: Vec<[u64; 3]> = Vec::new();
    for (i, &q) in a.positions.iter().enumerate() {
        if of_a.insert(key(q), i as u32).is_some() {
            twice.push(key(q));
        }
    }
    let mut positions = a.positions.clone();
    let mut map = Vec::with_capacity(b.positions.len());
    let mut shared = false;
    for &q in &b.positions {
        if twice.contains(&key(q)) {
            return None;
        }
        map.push(match of_a.get(&key(q)) {
            Some(&i) => {
                shared = true;
                i
            }
            None => {
                positions.push(q);
                (positions.len() - 1) as u32
            }
        });
    }
    if !shared {
        return None;
    }
    let mut triangles = a.triangles.clone();
    triangles.extend(b.triangles.iter().map(|t| t.map(|v| map[v as usize])));
    let union = TriMesh::new(positions, triangles);
    check_disk(&union).ok()?;
    Some(union)
}

/// `mesh` with each vertex `v` replaced by `to(v)`, the vertices no triangle uses dropped (the
/// rest keep their order); no map.
fn relabel(mesh: &TriMesh, to: impl Fn(u32) -> u32) -> TriMesh {
    let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.map(&to)).collect();
    let mut used = vec![false; mesh.positions.len()];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut index = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    for (v, &u) in used.iter().enumerate() {
        if u {
            index[v] = positions.len() as u32;
            positions.push(mesh.positions[v]);
        }
    }
    TriMesh::new(
        positions,
        tris.iter().map(|t| t.map(|v| index[v as usize])).collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square grid of `n` × `n` unit cells (10 mm) in the plane z = 0.
    fn grid(n: usize) -> TriMesh {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(DVec3::new(10.0 * i as f64, 10.0 * j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        TriMesh::new(p, t)
    }

    /// `mesh` cut along the edge path `path` (from the outline inward): the triangles on the
    /// left of each path edge get copies of its vertices but the path's last.
    fn slit(mesh: &TriMesh, path: &[u32]) -> TriMesh {
        flatcut_mesh::cut_along_seams(mesh, &[path.to_vec()]).unwrap()
    }

    #[test]
    fn a_slit_from_the_outline_into_a_part_is_sewn_shut() {
        let g = grid(4);
        // From the middle of the bottom edge (2, 0) up to the centre (2, 2).
        let cut = slit(&g, &[2, 7, 12]);
        assert!(cut.positions.len() > g.positions.len());
        let closed = close_slits(&cut).unwrap();
        assert_eq!(closed.positions.len(), g.positions.len());
        assert_eq!(closed.triangles.len(), g.triangles.len());
        assert!((closed.area() - g.area()).abs() < 1e-9);
        check_disk(&closed).unwrap();
        let topo = Topology::build(&closed).unwrap();
        assert_eq!(topo.boundary_loops[0].len(), 16);
        // Nothing left to close.
        assert!(close_slits(&closed).is_none());
        assert!(close_slits(&g).is_none());
    }

    #[test]
    fn two_halves_merge_into_the_whole_and_strangers_do_not() {
        let g = grid(4);
        let (left, right): (Vec<_>, Vec<_>) = g
            .triangles
            .iter()
            .partition(|t| t.iter().map(|&v| g.positions[v as usize].x).sum::<f64>() <= 60.0);
        let half = |t: Vec<&[u32; 3]>| {
            relabel(
                &TriMesh::new(g.positions.clone(), t.into_iter().copied().collect()),
                |v| v,
            )
        };
        let (a, b) = (half(left), half(right));
        let whole = merge(&a, &b).unwrap();
        assert_eq!(whole.positions.len(), g.positions.len());
        assert!((whole.area() - g.area()).abs() < 1e-9);
        let mut far = grid(1);
        for q in &mut far.positions {
            q.z += 100.0;
        }
        assert!(merge(&a, &far).is_none());
    }
}
