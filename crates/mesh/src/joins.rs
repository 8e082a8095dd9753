//! Joins: mating seams between boundary stretches of pieces that were not cut from one surface
//! (a collar sewn to a neckline, a vamp to a quarter drawn as separate patches).
//!
//! A stretch is given by two 3D points on a piece's boundary; each point becomes a boundary
//! vertex exactly where it falls (the boundary triangle there is split in two). Notches become
//! vertices the same way on both stretches. Then, between consecutive notches, every vertex of
//! one stretch gets a partner on the other at the same fraction of the 3D length, so that vertex
//! k of one side is sewn to vertex k of the other and a notch sits at the same index on both.

use flatcut_geom::DVec3;

use crate::mating::SeamSide;
use crate::{Topology, TopologyError, TriMesh};

/// Fractions of a stretch's length closer than this are the same point (round-off).
const SAME_FRACTION: f64 = 1e-9;

/// Why a join cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum JoinError {
    #[error(transparent)]
    /// The mesh's topology does not allow the join.
    Topology(#[from] TopologyError),
    #[error(
        "{what} ({x:.2}, {y:.2}, {z:.2}) is {dist:.2} mm from the boundary (at most {tol:.2} mm)"
    )]
    /// A point of the join lies too far from the mesh's boundary.
    OffBoundary {
        /// Which point, as the caller names it, e.g. "`from`".
        what: String,
        /// x of the point (mm).
        x: f64,
        /// y of the point (mm).
        y: f64,
        /// z of the point (mm).
        z: f64,
        /// Its distance from the boundary (mm).
        dist: f64,
        /// The largest distance accepted (mm).
        tol: f64,
    },
    #[error("the two end points lie on different boundary loops")]
    /// The stretch's two ends lie on different boundary loops.
    DifferentLoops,
    #[error("the two end points are the same boundary vertex")]
    /// The stretch's two ends are one vertex: the stretch is empty.
    Empty,
    #[error("the notches come in a different order along the two edges")]
    /// The notches do not come in the same order along both edges.
    NotchOrder,
    #[error("the two edges of one piece overlap")]
    /// Two edges of one piece share part of its boundary.
    Overlap,
}

/// Splits the boundary edge (u, v) at parameter `t` ∈ (0, 1): its triangle becomes two, and
/// per-vertex data (surface parameters, patch, flattening) is interpolated or copied.
fn split_boundary_edge(mesh: &mut TriMesh, u: u32, v: u32, t: f64) -> u32 {
    let (pu, pv) = (mesh.positions[u as usize], mesh.positions[v as usize]);
    let x = mesh.positions.len() as u32;
    mesh.positions.push(pu + (pv - pu) * t);
    if let Some(p) = &mut mesh.params {
        let q = p[u as usize] + (p[v as usize] - p[u as usize]) * t;
        p.push(q);
    }
    if let Some(p) = &mut mesh.patch_of_vertex {
        let q = p[u as usize];
        p.push(q);
    }
    if let Some(p) = &mut mesh.flat {
        let q = p[u as usize] + (p[v as usize] - p[u as usize]) * t;
        p.push(q);
    }
    let found = mesh.triangles.iter().enumerate().find_map(|(f, tri)| {
        (0..3).find_map(|k| {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            ((a, b) == (u, v) || (a, b) == (v, u)).then_some((f, k))
        })
    });
    if let Some((f, k)) = found {
        let tri = mesh.triangles[f];
        let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        mesh.triangles[f] = [a, x, c];
        mesh.triangles.push([x, b, c]);
    }
    x
}

/// The edge of `edges` nearest to `p`: (distance, edge index, parameter along it).
fn nearest_edge(mesh: &TriMesh, edges: &[(u32, u32)], p: DVec3) -> (f64, usize, f64) {
    let mut best = (f64::INFINITY, 0usize, 0.0);
    for (k, &(u, v)) in edges.iter().enumerate() {
        let (pu, pv) = (mesh.positions[u as usize], mesh.positions[v as usize]);
        let uv = pv - pu;
        let t = ((p - pu).dot(uv) / uv.length_squared()).clamp(0.0, 1.0);
        let d = p.distance(pu + uv * t);
        if d < best.0 {
            best = (d, k, t);
        }
    }
    best
}

/// The point at parameter `t` of boundary edge (u, v) as a vertex: `None` when it is `u` (within
/// round-off), else `v` (within round-off) or a new vertex splitting the edge.
fn vertex_at(mesh: &mut TriMesh, (u, v): (u32, u32), t: f64) -> Option<u32> {
    let len = mesh.positions[u as usize].distance(mesh.positions[v as usize]);
    let same = SAME_FRACTION * mesh.bbox().diagonal();
    if t * len <= same {
        None
    } else if (1.0 - t) * len <= same {
        Some(v)
    } else {
        Some(split_boundary_edge(mesh, u, v, t))
    }
}

/// The error of a point `dist` mm from the boundary, beyond `tol`.
fn off_boundary(what: &str, p: DVec3, dist: f64, tol: f64) -> JoinError {
    JoinError::OffBoundary {
        what: what.to_string(),
        x: p.x,
        y: p.y,
        z: p.z,
        dist,
        tol,
    }
}

/// The boundary point nearest to `p` as a vertex: an existing vertex within round-off, else a
/// new one splitting the boundary edge. `what` names the point in errors; `tol` is the largest
/// distance from the boundary accepted.
pub fn boundary_vertex(
    mesh: &mut TriMesh,
    p: DVec3,
    tol: f64,
    what: &str,
) -> Result<u32, JoinError> {
    let topo = Topology::build(mesh)?;
    let edges: Vec<(u32, u32)> = topo
        .boundary_loops
        .iter()
        .flat_map(|lp| (0..lp.len()).map(move |i| (lp[i], lp[(i + 1) % lp.len()])))
        .collect();
    let (d, k, t) = nearest_edge(mesh, &edges, p);
    if d.is_nan() || d > tol {
        return Err(off_boundary(what, p, d, tol));
    }
    Ok(vertex_at(mesh, edges[k], t).unwrap_or(edges[k].0))
}

/// The boundary vertices from `a` to `b` along their loop: the shorter way round, or the way
/// that passes nearest to `via`.
pub fn stretch(mesh: &TriMesh, a: u32, b: u32, via: Option<DVec3>) -> Result<Vec<u32>, JoinError> {
    if a == b {
        return Err(JoinError::Empty);
    }
    let topo = Topology::build(mesh)?;
    let lp = topo
        .boundary_loops
        .iter()
        .find(|l| l.contains(&a) && l.contains(&b))
        .ok_or(JoinError::DifferentLoops)?;
    let n = lp.len();
    let ia = lp.iter().position(|&v| v == a).expect("on the loop");
    let ib = lp.iter().position(|&v| v == b).expect("on the loop");
    let forward: Vec<u32> = (0..=((ib + n - ia) % n))
        .map(|k| lp[(ia + k) % n])
        .collect();
    let backward: Vec<u32> = (0..=((ia + n - ib) % n))
        .map(|k| lp[(ia + n - k) % n])
        .collect();
    let len = |s: &[u32]| -> f64 {
        s.windows(2)
            .map(|w| mesh.positions[w[0] as usize].distance(mesh.positions[w[1] as usize]))
            .sum()
    };
    let near = |s: &[u32], p: DVec3| -> f64 {
        s.iter()
            .map(|&v| mesh.positions[v as usize].distance(p))
            .fold(f64::INFINITY, f64::min)
    };
    let take_forward = match via {
        Some(p) => near(&forward, p) <= near(&backward, p),
        None => len(&forward) <= len(&backward),
    };
    Ok(if take_forward { forward } else { backward })
}

/// Inserts the point of `side` nearest to `p` into it as a vertex (exactly where it falls, an
/// existing vertex within round-off) and returns its index along the side.
pub fn vertex_on_side(
    mesh: &mut TriMesh,
    side: &mut Vec<u32>,
    p: DVec3,
    tol: f64,
    what: &str,
) -> Result<usize, JoinError> {
    let edges: Vec<(u32, u32)> = side.windows(2).map(|w| (w[0], w[1])).collect();
    let (d, i, t) = nearest_edge(mesh, &edges, p);
    if d.is_nan() || d > tol {
        return Err(off_boundary(what, p, d, tol));
    }
    Ok(match vertex_at(mesh, edges[i], t) {
        None => i,
        Some(x) if x == side[i + 1] => i + 1,
        Some(x) => {
            side.insert(i + 1, x);
            i + 1
        }
    })
}

/// Fractions of the 3D length from `side[from]` at each vertex up to `side[to]`.
fn fractions(mesh: &TriMesh, side: &[u32], from: usize, to: usize) -> Vec<f64> {
    let mut acc = vec![0.0];
    for i in from..to {
        let d = mesh.positions[side[i] as usize].distance(mesh.positions[side[i + 1] as usize]);
        acc.push(acc[acc.len() - 1] + d);
    }
    let total = acc[acc.len() - 1];
    acc.iter()
        .map(|s| if total > 0.0 { s / total } else { 0.0 })
        .collect()
}

/// Makes the two sides correspond vertex for vertex: between consecutive knots (index pairs,
/// the first `[0, 0]`, the last both ends), each side gets a vertex at every fraction of the 3D
/// length where the other has one. Returns the knots' new indices.
pub fn match_sides(
    meshes: &mut [TriMesh],
    sides: &mut [SeamSide; 2],
    knots: &[[usize; 2]],
) -> Result<Vec<usize>, JoinError> {
    if knots
        .windows(2)
        .any(|w| w[1][0] <= w[0][0] || w[1][1] <= w[0][1])
    {
        return Err(JoinError::NotchOrder);
    }
    let mut new: [Vec<u32>; 2] = [Vec::new(), Vec::new()];
    let mut at = Vec::with_capacity(knots.len());
    for w in knots.windows(2) {
        let f: [Vec<f64>; 2] = [0, 1].map(|s| {
            fractions(
                &meshes[sides[s].piece],
                &sides[s].vertices,
                w[0][s],
                w[1][s],
            )
        });
        // The merged fractions (each side's, one copy where both have one).
        let mut merged: Vec<f64> = f[0].iter().chain(&f[1]).copied().collect();
        merged.sort_by(f64::total_cmp);
        merged.dedup_by(|a, b| (*a - *b).abs() <= SAME_FRACTION);
        if at.is_empty() {
            at.push(0);
            for s in 0..2 {
                new[s].push(sides[s].vertices[w[0][s]]);
            }
        }
        // The last vertex placed on each side and its fraction: a new vertex splits the edge
        // from it to the side's next own vertex.
        let mut prev = [0, 1].map(|s| (sides[s].vertices[w[0][s]], 0.0));
        for &u in &merged[1..] {
            for s in 0..2 {
                let side = &sides[s];
                let fr = &f[s];
                let i = fr.partition_point(|&x| x < u - SAME_FRACTION);
                let v = if (fr[i] - u).abs() <= SAME_FRACTION {
                    side.vertices[w[0][s] + i]
                } else {
                    let (a, fa) = prev[s];
                    let b = side.vertices[w[0][s] + i];
                    let t = (u - fa) / (fr[i] - fa);
                    split_boundary_edge(&mut meshes[side.piece], a, b, t)
                };
                new[s].push(v);
                prev[s] = (v, u);
            }
        }
        at.push(new[0].len() - 1);
    }
    for s in 0..2 {
        sides[s].vertices = std::mem::take(&mut new[s]);
    }
    Ok(at)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` unit squares along x, z = 0.
    fn strip(n: usize, y0: f64) -> TriMesh {
        let mut p = Vec::new();
        for i in 0..=n {
            p.push(DVec3::new(i as f64, y0, 0.0));
            p.push(DVec3::new(i as f64, y0 + 1.0, 0.0));
        }
        let mut t = Vec::new();
        for i in 0..n as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
        TriMesh::new(p, t)
    }

    #[test]
    fn two_strips_joined_along_their_long_edges_correspond_vertex_for_vertex() {
        // The lower strip's top edge (y = 1, 4 segments) against the upper strip's bottom
        // edge (y = 1, 3 segments of 4/3): vertices at 0, 1, 2, 3, 4 and 0, 4/3, 8/3, 4.
        let mut meshes = vec![strip(4, 0.0), strip(3, 1.0)];
        meshes[1]
            .positions
            .iter_mut()
            .for_each(|p| p.x *= 4.0 / 3.0);
        let mut sides = [0usize, 1].map(|k| SeamSide {
            piece: k,
            vertices: Vec::new(),
        });
        for (k, y) in [(0, 1.0), (1, 1.0)] {
            let m = &mut meshes[k];
            let a = boundary_vertex(m, DVec3::new(0.0, y, 0.0), 1e-6, "from").unwrap();
            let b = boundary_vertex(m, DVec3::new(4.0, y, 0.0), 1e-6, "to").unwrap();
            sides[k].vertices = stretch(m, a, b, None).unwrap();
        }
        // A notch at x = 2.5 on both.
        let mut knots = vec![[0, 0]];
        let mut n = [0usize; 2];
        for k in 0..2 {
            let mut v = sides[k].vertices.clone();
            n[k] = vertex_on_side(&mut meshes[k], &mut v, DVec3::new(2.5, 1.0, 0.0), 1e-6, "n")
                .unwrap();
            sides[k].vertices = v;
        }
        knots.push(n);
        knots.push([sides[0].vertices.len() - 1, sides[1].vertices.len() - 1]);
        let at = match_sides(&mut meshes, &mut sides, &knots).unwrap();
        assert_eq!(sides[0].vertices.len(), sides[1].vertices.len());
        let xs = |k: usize| -> Vec<f64> {
            sides[k]
                .vertices
                .iter()
                .map(|&v| meshes[k].positions[v as usize].x)
                .collect()
        };
        let (a, b) = (xs(0), xs(1));
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).abs() < 1e-12, "{a:?} vs {b:?}");
        }
        assert!((a[at[1]] - 2.5).abs() < 1e-12);
        for m in &meshes {
            crate::check_disk(m).unwrap();
            assert!(
                m.triangles
                    .iter()
                    .enumerate()
                    .all(|(t, _)| m.triangle_area(t) > 0.0)
            );
        }
    }
}
