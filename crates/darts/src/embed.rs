//! A dart's geodesic made part of the mesh: every point where it crosses an edge becomes a
//! vertex and the crossed triangles are split along it, so the dart is cut exactly along the
//! geodesic instead of along a staircase of old edges.
//!
//! New vertices lie on the old edges, so the surface does not move; every triangle remembers the
//! triangle of the original piece it lies in ([`Embedded::parent`]), which is how a flattening is
//! carried from one set of darts to another ([`transfer`]). A crossing within [`SNAP_REL`] of an
//! edge's length from one of its ends goes through that end instead (no sliver triangles); the
//! dart's point is its last crossing.

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;

use crate::trace::Geodesic;

/// A crossing this close to an edge's end (fraction of the edge's length) goes through the end:
/// no triangle gets an angle much below a tenth of its neighbours'.
pub const SNAP_REL: f64 = 0.12;

/// A piece with paths embedded in it.
#[derive(Clone, Debug)]
pub struct Embedded {
    /// The piece re-triangulated so every path runs along its edges.
    pub mesh: TriMesh,
    /// Per triangle, the triangle of the original piece it lies in.
    pub parent: Vec<u32>,
}

impl Embedded {
    /// The piece itself, nothing embedded.
    pub fn new(piece: &TriMesh) -> Self {
        Self {
            mesh: TriMesh::new(piece.positions.clone(), piece.triangles.clone()),
            parent: (0..piece.triangles.len() as u32).collect(),
        }
    }
}

/// A point of a path: an existing vertex, or a point on the edge (a, b) at parameter u.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Node {
    Vertex(u32),
    Edge(u32, u32, f64),
}

/// Embeds `g` (traced on `e.mesh` from vertex `start`) and returns the mesh with the path's
/// vertices from `start` to the dart's point. `None` when the geodesic crosses no edge.
pub fn embed(e: &Embedded, start: u32, g: &Geodesic) -> Option<(Embedded, Vec<u32>)> {
    let mesh = &e.mesh;
    // The nodes: the start, then each crossing (the last point is inside a triangle: dropped).
    let mut nodes: Vec<(Node, u32)> = vec![(Node::Vertex(start), u32::MAX)];
    for (j, &t) in g.faces.iter().enumerate() {
        let Some(&p) = g.points.get(j + 1) else { break };
        if j + 2 >= g.points.len() && !g.hit_boundary {
            // The end of the trace, inside triangle t: not a crossing.
            break;
        }
        let tri = mesh.triangles[t as usize];
        // The edge of t the point lies on.
        let mut best = (f64::INFINITY, 0usize, 0.0);
        for k in 0..3 {
            let (a, b) = (
                mesh.positions[tri[k] as usize],
                mesh.positions[tri[(k + 1) % 3] as usize],
            );
            let ab = b - a;
            let u = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            let d = (a + ab * u).distance(p);
            if d < best.0 {
                best = (d, k, u);
            }
        }
        let (_, k, u) = best;
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        let node = if u < SNAP_REL {
            Node::Vertex(a)
        } else if u > 1.0 - SNAP_REL {
            Node::Vertex(b)
        } else {
            Node::Edge(a, b, u)
        };
        nodes.push((node, t));
    }
    if g.hit_boundary {
        // A dart must end inside: drop crossings on the outline.
        nodes.pop();
    }
    // Consecutive snaps to the same vertex are one node.
    nodes.dedup_by(|x, y| x.0 == y.0);
    if nodes.len() < 2 {
        return None;
    }
    // New vertices for the edge points, shared by both triangles of the edge.
    let mut positions = mesh.positions.clone();
    let mut node_vertex: Vec<u32> = Vec::with_capacity(nodes.len());
    let mut edge_points: Vec<((u32, u32), f64, u32)> = Vec::new();
    for (node, _) in &nodes {
        let v = match *node {
            Node::Vertex(v) => v,
            Node::Edge(a, b, u) => {
                let v = positions.len() as u32;
                positions.push(mesh.positions[a as usize].lerp(mesh.positions[b as usize], u));
                // Stored with the parameter from the smaller index.
                let (key, uu) = if a < b {
                    ((a, b), u)
                } else {
                    ((b, a), 1.0 - u)
                };
                edge_points.push((key, uu, v));
                v
            }
        };
        node_vertex.push(v);
    }
    // Chords: consecutive path vertices, each inside one triangle of the current mesh.
    let chords: Vec<(u32, u32)> = node_vertex.windows(2).map(|w| (w[0], w[1])).collect();
    let mut triangles = Vec::with_capacity(mesh.triangles.len() + 3 * nodes.len());
    let mut parent = Vec::with_capacity(triangles.capacity());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        // The polygon: corners and edge points in order around the triangle.
        let mut poly: Vec<u32> = Vec::with_capacity(6);
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            poly.push(a);
            let key = (a.min(b), a.max(b));
            if let Some(&(_, u, v)) = edge_points.iter().find(|(kk, _, _)| *kk == key) {
                let _ = u;
                poly.push(v);
            }
        }
        // A chord of this polygon, if the path runs through it.
        let chord = chords.iter().find(|&&(p, q)| {
            let (ip, iq) = (
                poly.iter().position(|&x| x == p),
                poly.iter().position(|&x| x == q),
            );
            match (ip, iq) {
                (Some(i), Some(j)) => {
                    let n = poly.len();
                    // Not already a side of the polygon.
                    (i + 1) % n != j && (j + 1) % n != i
                }
                _ => false,
            }
        });
        let pieces: Vec<Vec<u32>> = match chord {
            Some(&(p, q)) => {
                let n = poly.len();
                let i = poly.iter().position(|&x| x == p).unwrap_or(0);
                let j = poly.iter().position(|&x| x == q).unwrap_or(0);
                let walk = |from: usize, to: usize| {
                    let mut out = vec![poly[from]];
                    let mut k = from;
                    while k != to {
                        k = (k + 1) % n;
                        out.push(poly[k]);
                    }
                    out
                };
                vec![walk(i, j), walk(j, i)]
            }
            None => vec![poly],
        };
        for piece in pieces {
            for f in fan(&positions, &piece) {
                triangles.push(f);
                parent.push(e.parent[t]);
            }
        }
    }
    let out = Embedded {
        mesh: TriMesh::new(positions, triangles),
        parent,
    };
    Some((out, node_vertex))
}

/// Triangulates a convex polygon (points on a triangle's sides, in order) by the fan from the
/// corner that keeps the smallest triangle largest.
fn fan(pos: &[DVec3], poly: &[u32]) -> Vec<[u32; 3]> {
    let n = poly.len();
    if n == 3 {
        return vec![[poly[0], poly[1], poly[2]]];
    }
    let area = |a: u32, b: u32, c: u32| {
        let (a, b, c) = (pos[a as usize], pos[b as usize], pos[c as usize]);
        0.5 * (b - a).cross(c - a).length()
    };
    let mut best = (f64::NEG_INFINITY, 0usize);
    for s in 0..n {
        let worst = (1..n - 1)
            .map(|k| area(poly[s], poly[(s + k) % n], poly[(s + k + 1) % n]))
            .fold(f64::INFINITY, f64::min);
        if worst > best.0 {
            best = (worst, s);
        }
    }
    let s = best.1;
    (1..n - 1)
        .map(|k| [poly[s], poly[(s + k) % n], poly[(s + k + 1) % n]])
        .collect()
}

/// Barycentric coordinates of `p` in the 3D triangle (a, b, c) (in its plane).
fn barycentric(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= f64::MIN_POSITIVE {
        return [1.0, 0.0, 0.0];
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    [1.0 - v - w, v, w]
}

/// A flattening of one cut (`from`, with its embedding's parents `from_parent`) carried to
/// another cut of the same piece (`to`, parents `to_parent`): every vertex of `to` takes the
/// value of the map of the `from` triangle it lies in, on the side of one of its own triangles.
pub fn transfer(
    from: &TriMesh,
    from_parent: &[u32],
    x: &[DVec2],
    to: &TriMesh,
    to_parent: &[u32],
) -> Vec<DVec2> {
    let nb = from_parent
        .iter()
        .chain(to_parent)
        .copied()
        .max()
        .map_or(0, |m| m as usize + 1);
    let mut children: Vec<Vec<u32>> = vec![Vec::new(); nb];
    for (t, &p) in from_parent.iter().enumerate() {
        children[p as usize].push(t as u32);
    }
    let mut out = vec![DVec2::ZERO; to.positions.len()];
    let mut done = vec![false; to.positions.len()];
    for (t2, tri) in to.triangles.iter().enumerate() {
        let c = to.corners(t2);
        let centre = (c[0] + c[1] + c[2]) / 3.0;
        for k in 0..3 {
            let v = tri[k] as usize;
            if done[v] {
                continue;
            }
            // A point just inside this triangle next to the vertex says which side.
            let probe = c[k].lerp(centre, 1e-3);
            let mut best: Option<(f64, u32, [f64; 3])> = None;
            for &t1 in &children[to_parent[t2] as usize] {
                let f = from.corners(t1 as usize);
                let l = barycentric(probe, f[0], f[1], f[2]);
                let inside = l.iter().copied().fold(f64::INFINITY, f64::min);
                if best.is_none_or(|(b, _, _)| inside > b) {
                    best = Some((inside, t1, barycentric(c[k], f[0], f[1], f[2])));
                }
            }
            if let Some((_, t1, l)) = best {
                let ft = from.triangles[t1 as usize];
                out[v] =
                    x[ft[0] as usize] * l[0] + x[ft[1] as usize] * l[1] + x[ft[2] as usize] * l[2];
                done[v] = true;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::{Adjacency, inward_direction, trace};
    use flatcut_flatten::testmesh::spherical_cap;
    use flatcut_mesh::{Topology, check_disk};

    #[test]
    fn an_embedded_geodesic_is_a_path_of_edges_and_the_surface_does_not_change() {
        let cap = spherical_cap(100.0, 1.2, 16);
        let topo = Topology::build(&cap).unwrap();
        let adj = Adjacency::new(&cap, &topo);
        let lp = &topo.boundary_loops[0];
        let i = 5;
        let g = trace(&cap, &adj, lp[i], inward_direction(&cap, &adj, lp, i), 60.0);
        let e = Embedded::new(&cap);
        let (out, path) = embed(&e, lp[i], &g).unwrap();
        check_disk(&out.mesh).unwrap();
        assert!((out.mesh.area() - cap.area()).abs() < 1e-9 * cap.area());
        // Every step of the path is an edge of the new mesh.
        let t2 = Topology::build(&out.mesh).unwrap();
        for w in path.windows(2) {
            assert!(
                t2.edges.contains_key(&(w[0].min(w[1]), w[0].max(w[1]))),
                "{w:?}"
            );
        }
        // The path follows the geodesic: its vertices are on the traced polyline.
        for &v in &path {
            let p = out.mesh.positions[v as usize];
            let d = g
                .points
                .windows(2)
                .map(|s| {
                    let ab = s[1] - s[0];
                    let u = ((p - s[0]).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                    (s[0] + ab * u).distance(p)
                })
                .fold(f64::INFINITY, f64::min);
            assert!(d < 2.0, "vertex {v} is {d} mm off the geodesic");
        }
        // Parents: every triangle lies in its parent.
        for (t, &p) in out.parent.iter().enumerate() {
            let c = out.mesh.corners(t);
            let centre = (c[0] + c[1] + c[2]) / 3.0;
            let f = cap.corners(p as usize);
            let l = barycentric(centre, f[0], f[1], f[2]);
            assert!(
                l.iter().all(|&x| x > -1e-9),
                "triangle {t} outside its parent"
            );
        }
        // A linear map carried over stays the same linear map.
        let x: Vec<DVec2> = cap
            .positions
            .iter()
            .map(|p| DVec2::new(p.x, 2.0 * p.y))
            .collect();
        let y = transfer(&cap, &e.parent, &x, &out.mesh, &out.parent);
        for (v, p) in out.mesh.positions.iter().enumerate() {
            assert!(
                (y[v] - DVec2::new(p.x, 2.0 * p.y)).length() < 1e-3,
                "vertex {v}"
            );
        }
    }
}
