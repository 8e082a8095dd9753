//! Cutting a surface open into a disk, the topology a flattening needs: first along given seams
//! (a periodic face's own seam edge, where a CAD model already has it cut), then each hole to the
//! outer boundary along the shortest path of interior edges.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::seams::{Dist, cut_along_seams, vertex_neighbours};
use crate::{Topology, TopologyError, TriMesh, check_disk};

/// Holes connected at most (each cut merges one hole into the outer boundary).
const MAX_HOLES: usize = 4096;

/// The mesh cut into a disk: unchanged if it is one; else cut along `seams` (vertex paths along
/// mesh edges; those that are not paths of the mesh are ignored) while that still leaves a
/// connected surface, then every boundary loop but the longest joined to the longest by a
/// shortest path of interior vertices. Fails when no such cut exists (a closed surface with no
/// boundary, or several components), with the reason [`check_disk`] gives.
pub fn cut_to_disk(mesh: &TriMesh, seams: &[Vec<u32>]) -> Result<TriMesh, TopologyError> {
    if check_disk(mesh).is_ok() {
        return Ok(mesh.clone());
    }
    let mut m = mesh.clone();
    let topo = Topology::build(&m)?;
    let usable: Vec<Vec<u32>> = seams
        .iter()
        .filter(|s| {
            s.len() >= 2
                && s.windows(2).all(|w| {
                    w[0] == w[1] || topo.edges.contains_key(&(w[0].min(w[1]), w[0].max(w[1])))
                })
        })
        .cloned()
        .collect();
    if !usable.is_empty() {
        let cut = cut_along_seams(&m, &usable)?;
        if Topology::build(&cut).is_ok_and(|t| t.component_count == 1) {
            m = cut;
        }
    }
    for _ in 0..MAX_HOLES {
        let topo = Topology::build(&m)?;
        if topo.boundary_loops.len() < 2 {
            break;
        }
        let len = |lp: &Vec<u32>| -> f64 {
            (0..lp.len())
                .map(|k| {
                    m.positions[lp[k] as usize]
                        .distance(m.positions[lp[(k + 1) % lp.len()] as usize])
                })
                .sum()
        };
        let outer = (0..topo.boundary_loops.len())
            .max_by(|&a, &b| len(&topo.boundary_loops[a]).total_cmp(&len(&topo.boundary_loops[b])))
            .unwrap_or(0);
        let hole = if outer == 0 { 1 } else { 0 };
        let Some(path) = hole_path(&m, &topo, hole, outer) else {
            break;
        };
        m = cut_along_seams(&m, &[path])?;
    }
    check_disk(&m)?;
    Ok(m)
}

/// The shortest edge path from boundary loop `from` to boundary loop `to` whose inner vertices
/// are interior (not on any boundary).
fn hole_path(m: &TriMesh, topo: &Topology, from: usize, to: usize) -> Option<Vec<u32>> {
    let n = m.positions.len();
    let mut on_boundary = vec![usize::MAX; n];
    for (k, lp) in topo.boundary_loops.iter().enumerate() {
        for &v in lp {
            on_boundary[v as usize] = k;
        }
    }
    let adj = vertex_neighbours(m);
    let mut dist = vec![f64::INFINITY; n];
    let mut prev = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    for &v in &topo.boundary_loops[from] {
        dist[v as usize] = 0.0;
        heap.push(Reverse((Dist(0.0), v)));
    }
    while let Some(Reverse((Dist(d), v))) = heap.pop() {
        if d > dist[v as usize] {
            continue;
        }
        if on_boundary[v as usize] == to {
            let mut path = vec![v];
            let mut w = v;
            while prev[w as usize] != u32::MAX {
                w = prev[w as usize];
                path.push(w);
            }
            path.reverse();
            return Some(path);
        }
        // Only the start loop's vertices and interior vertices are passed through.
        if on_boundary[v as usize] != usize::MAX && on_boundary[v as usize] != from {
            continue;
        }
        for &w in &adj[v as usize] {
            let wb = on_boundary[w as usize];
            if wb == from || (wb != usize::MAX && wb != to) {
                continue;
            }
            // An edge between two boundary vertices is a boundary chord: it would cut the
            // surface apart, not open it.
            if on_boundary[v as usize] == from && wb == to {
                let k = (v.min(w), v.max(w));
                if topo.edges.get(&k).is_some_and(|e| e.is_boundary()) {
                    continue;
                }
            }
            let nd = d + m.positions[v as usize].distance(m.positions[w as usize]);
            if nd < dist[w as usize] {
                dist[w as usize] = nd;
                prev[w as usize] = v;
                heap.push(Reverse((Dist(nd), w)));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    /// An annulus of `n` sectors between radii 1 and 2, with a middle ring at 1.5.
    fn annulus(n: usize) -> TriMesh {
        let mut pos = Vec::new();
        for r in [1.0, 1.5, 2.0] {
            for k in 0..n {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                pos.push(DVec3::new(r * a.cos(), r * a.sin(), 0.0));
            }
        }
        let mut tris = Vec::new();
        for ring in 0..2 {
            for k in 0..n {
                let (a, b) = ((ring * n + k) as u32, (ring * n + (k + 1) % n) as u32);
                let (c, d) = (a + n as u32, b + n as u32);
                tris.push([a, b, d]);
                tris.push([a, d, c]);
            }
        }
        TriMesh::new(pos, tris)
    }

    #[test]
    fn an_annulus_is_cut_into_a_disk() {
        let m = annulus(16);
        assert!(check_disk(&m).is_err());
        let d = cut_to_disk(&m, &[]).unwrap();
        let t = check_disk(&d).unwrap();
        assert_eq!(t.boundary_loops.len(), 1);
        // The cut runs across the annulus through the middle ring: 3 vertices duplicated.
        assert_eq!(d.positions.len(), m.positions.len() + 3);
        assert!((d.area() - m.area()).abs() < 1e-12);
    }

    #[test]
    fn a_given_seam_is_preferred_and_a_closed_surface_is_refused() {
        let m = annulus(16);
        // The radial seam at angle 0: vertices 0, 16, 32.
        let d = cut_to_disk(&m, &[vec![0, 16, 32]]).unwrap();
        assert!(check_disk(&d).is_ok());
        assert_eq!(d.positions.len(), m.positions.len() + 3);
        let tet = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        );
        assert!(cut_to_disk(&tet, &[]).is_err());
    }
}
