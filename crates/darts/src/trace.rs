//! Dart paths on the surface: the straightest geodesic from a boundary vertex at right angles to
//! the outline, traced across the triangles (each crossed edge unfolds the next triangle into the
//! plane of the last, so the path never turns on the surface), and the path of mesh edges the
//! dart is cut along: the shortest edge path to the geodesic's end inside the corridor of
//! triangles the geodesic crossed, which keeps the cut within one triangle of the geodesic.

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

use flatcut_geom::DVec3;
use flatcut_mesh::{Topology, TriMesh};

/// Which faces meet at each vertex, and the neighbour triangle across each edge.
#[derive(Clone, Debug)]
pub struct Adjacency {
    /// Per triangle and corner k, the triangle across edge (k, k+1), if any.
    pub across: Vec<[Option<u32>; 3]>,
    /// Per vertex, the triangles using it.
    pub faces_of: Vec<Vec<u32>>,
    /// Per vertex, the neighbouring vertices (sorted).
    pub neighbours: Vec<Vec<u32>>,
    /// True for vertices on the boundary.
    pub on_boundary: Vec<bool>,
}

impl Adjacency {
    /// The adjacency of `mesh`, from its topology `topo`.
    pub fn new(mesh: &TriMesh, topo: &Topology) -> Self {
        let n = mesh.positions.len();
        let mut across = vec![[None; 3]; mesh.triangles.len()];
        for (&(a, b), e) in &topo.edges {
            if let (Some(f), Some(r)) = (e.fwd, e.rev) {
                for (t, other) in [(f, r), (r, f)] {
                    let tri = mesh.triangles[t as usize];
                    for k in 0..3 {
                        let (p, q) = (tri[k], tri[(k + 1) % 3]);
                        if (p.min(q), p.max(q)) == (a, b) {
                            across[t as usize][k] = Some(other);
                        }
                    }
                }
            }
        }
        let mut faces_of = vec![Vec::new(); n];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                faces_of[v as usize].push(t as u32);
            }
        }
        let mut on_boundary = vec![false; n];
        for lp in &topo.boundary_loops {
            for &v in lp {
                on_boundary[v as usize] = true;
            }
        }
        Self {
            across,
            faces_of,
            neighbours: flatcut_mesh::seams::vertex_neighbours(mesh),
            on_boundary,
        }
    }
}

/// Unit normal of triangle `t`.
fn face_normal(mesh: &TriMesh, t: usize) -> DVec3 {
    let [a, b, c] = mesh.corners(t);
    (b - a).cross(c - a).normalize_or_zero()
}

/// The inward direction at boundary vertex `v` of `lp` (a boundary loop, interior on the
/// left): perpendicular to the outline in the surface's tangent plane there.
pub fn inward_direction(mesh: &TriMesh, adj: &Adjacency, lp: &[u32], i: usize) -> DVec3 {
    let n = lp.len();
    let (prev, v, next) = (lp[(i + n - 1) % n], lp[i], lp[(i + 1) % n]);
    let p = |k: u32| mesh.positions[k as usize];
    let tangent = (p(next) - p(prev)).normalize_or_zero();
    let mut normal = DVec3::ZERO;
    for &t in &adj.faces_of[v as usize] {
        normal += face_normal(mesh, t as usize) * mesh.triangle_area(t as usize);
    }
    // Interior on the left of the loop's direction: left = normal × tangent.
    normal
        .normalize_or_zero()
        .cross(tangent)
        .normalize_or_zero()
}

/// A geodesic traced from a vertex: the points where it crosses edges, from the start vertex to
/// its end, and the triangles it crossed in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geodesic {
    /// The start vertex's position, then each edge crossing, then the end (3D, mm).
    pub points: Vec<DVec3>,
    /// The triangles crossed, in order (0-based).
    pub faces: Vec<u32>,
    /// Length traced (mm).
    pub length: f64,
    /// True when the trace stopped at the boundary before reaching the length asked for.
    pub hit_boundary: bool,
}

impl Geodesic {
    /// The point at arc length `s` from the start (clamped to the ends).
    pub fn point_at(&self, s: f64) -> DVec3 {
        let mut acc = 0.0;
        for w in self.points.windows(2) {
            let l = w[0].distance(w[1]);
            if acc + l >= s && l > 0.0 {
                return w[0].lerp(w[1], ((s - acc) / l).clamp(0.0, 1.0));
            }
            acc += l;
        }
        self.points.last().copied().unwrap_or(DVec3::ZERO)
    }
}

/// Where a start direction that misses the fan is put: this fraction of the corner from its
/// nearer side.
const START_INSET: f64 = 0.05;

/// Most triangles a trace crosses before it gives up (a guard against cycling on a degenerate
/// mesh; far more than any dart crosses).
const MAX_STEPS: usize = 1_000_000;

/// The triangle of vertex `v`'s fan whose corner at `v` contains the direction `dir` (projected
/// into its plane), and the projected direction; `skip` excludes a triangle (the one a trace
/// arrived through). At a rim vertex the direction may miss the fan by round-off or by the
/// rim's bend: it is then turned into the nearest corner, just inside it.
fn leave_vertex(
    mesh: &TriMesh,
    adj: &Adjacency,
    v: u32,
    dir: DVec3,
    skip: Option<u32>,
) -> Option<(u32, DVec3)> {
    let mut nearest: Option<(f64, u32, DVec3)> = None;
    for &t in &adj.faces_of[v as usize] {
        if Some(t) == skip {
            continue;
        }
        let tri = mesh.triangles[t as usize];
        let k = tri.iter().position(|&x| x == v).unwrap_or(0);
        let p0 = mesh.positions[v as usize];
        let p1 = mesh.positions[tri[(k + 1) % 3] as usize];
        let p2 = mesh.positions[tri[(k + 2) % 3] as usize];
        let nrm = face_normal(mesh, t as usize);
        let d = (dir - nrm * dir.dot(nrm)).normalize_or_zero();
        let (e1, e2) = ((p1 - p0).normalize_or_zero(), (p2 - p0).normalize_or_zero());
        // d inside the corner: e1 × d and d × e2 both along the normal.
        let (a, b) = (e1.cross(d).dot(nrm), d.cross(e2).dot(nrm));
        if a >= 0.0 && b >= 0.0 && d.dot(e1 + e2) > 0.0 {
            return Some((t, d));
        }
        // How far outside (angle) and the corner's direction just inside its nearer side.
        let miss = if d.dot(e1) > d.dot(e2) {
            (
                d.dot(e1).clamp(-1.0, 1.0).acos(),
                e1.lerp(e2, START_INSET).normalize_or_zero(),
            )
        } else {
            (
                d.dot(e2).clamp(-1.0, 1.0).acos(),
                e2.lerp(e1, START_INSET).normalize_or_zero(),
            )
        };
        if nearest.is_none_or(|(m, _, _)| miss.0 < m) {
            nearest = Some((miss.0, t, miss.1));
        }
    }
    nearest.map(|(_, t, d)| (t, d))
}

/// The straightest continuation through interior vertex `w` of a ray arriving in triangle
/// `t_in` with direction `d` (Polthier and Schmies' straightest geodesics): the outgoing
/// direction leaves equal angle on either side, half the vertex's total angle from the incoming
/// ray. Returns the triangle it enters and the direction in its plane.
fn straightest_through(
    mesh: &TriMesh,
    adj: &Adjacency,
    w: u32,
    t_in: u32,
    d: DVec3,
) -> Option<(u32, DVec3)> {
    // The fan of w in counter-clockwise order from t_in: (triangle, first side, corner angle).
    let pw = mesh.positions[w as usize];
    let mut fan: Vec<(u32, DVec3, DVec3, f64)> = Vec::new();
    let mut t = t_in;
    for _ in 0..adj.faces_of[w as usize].len() {
        let tri = mesh.triangles[t as usize];
        let k = tri.iter().position(|&x| x == w)?;
        let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
        let e1 = (mesh.positions[a as usize] - pw).normalize_or_zero();
        let e2 = (mesh.positions[b as usize] - pw).normalize_or_zero();
        fan.push((t, e1, e2, e1.dot(e2).clamp(-1.0, 1.0).acos()));
        // Next triangle counter-clockwise: across the side (w, b).
        let side = (k + 2) % 3;
        t = adj.across[t as usize][side]?;
        if t == t_in {
            break;
        }
    }
    if t != t_in {
        return None;
    }
    let total: f64 = fan.iter().map(|f| f.3).sum();
    // The incoming ray seen from w points back along −d, inside t_in's corner at angle φ from
    // its first side.
    let (_, e1, _, _) = fan[0];
    let nrm = face_normal(mesh, t_in as usize);
    let back = -(d - nrm * d.dot(nrm)).normalize_or_zero();
    let phi = e1.cross(back).dot(nrm).atan2(e1.dot(back)).max(0.0);
    let mut target = (phi + 0.5 * total) % total;
    for &(tf, e1, _, ang) in &fan {
        if target <= ang {
            let n = face_normal(mesh, tf as usize);
            let dir = e1 * target.cos() + n.cross(e1) * target.sin();
            return Some((tf, dir.normalize_or_zero()));
        }
        target -= ang;
    }
    None
}

/// Where along an edge (fraction of its length) a crossing counts as passing through its end.
const THROUGH_VERTEX: f64 = 1e-7;

/// Traces the straightest geodesic from vertex `v` in the tangent direction `dir` for `length`
/// mm, or until it reaches the boundary. Through a vertex it goes on in the same direction, into
/// the triangle whose corner holds it.
pub fn trace(mesh: &TriMesh, adj: &Adjacency, v: u32, dir: DVec3, length: f64) -> Geodesic {
    let mut out = Geodesic {
        points: vec![mesh.positions[v as usize]],
        ..Geodesic::default()
    };
    let Some((mut t, mut d)) = leave_vertex(mesh, adj, v, dir, None) else {
        return out;
    };
    let mut p = mesh.positions[v as usize];
    // The edge the trace came in through, or the vertex it left from.
    let mut from_edge: Option<usize> = None;
    let mut from_vertex: Option<u32> = Some(v);
    for _ in 0..MAX_STEPS {
        out.faces.push(t);
        let tri = mesh.triangles[t as usize];
        let c = mesh.corners(t as usize);
        let nrm = face_normal(mesh, t as usize);
        // Exit: the edge (k, k+1) the ray p + s d crosses first (s > 0), other than the one
        // it came in through or the two at the vertex it left.
        let mut exit: Option<(usize, f64, f64)> = None;
        for k in 0..3 {
            let at_from_vertex = from_vertex.is_some_and(|w| tri[k] == w || tri[(k + 1) % 3] == w);
            if Some(k) == from_edge || at_from_vertex {
                continue;
            }
            let (a, b) = (c[k], c[(k + 1) % 3]);
            // Solve p + s d = a + u (b − a) in the plane.
            let e = b - a;
            let denom = d.cross(e).dot(nrm);
            if denom.abs() <= 1e-15 * e.length() {
                continue;
            }
            let s = (a - p).cross(e).dot(nrm) / denom;
            let u = (a - p).cross(d).dot(nrm) / denom;
            if s > 0.0 && (-1e-9..=1.0 + 1e-9).contains(&u) && exit.is_none_or(|(_, s0, _)| s < s0)
            {
                exit = Some((k, s, u.clamp(0.0, 1.0)));
            }
        }
        let Some((k, s, u)) = exit else {
            break;
        };
        let remaining = length - out.length;
        if s >= remaining {
            out.points.push(p + d * remaining);
            out.length = length;
            return out;
        }
        p += d * s;
        out.points.push(p);
        out.length += s;
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        // Through a vertex: go on from it.
        if u <= THROUGH_VERTEX || u >= 1.0 - THROUGH_VERTEX {
            let w = if u <= THROUGH_VERTEX { a } else { b };
            p = mesh.positions[w as usize];
            if adj.on_boundary[w as usize] {
                out.hit_boundary = true;
                return out;
            }
            let Some((next, nd)) = straightest_through(mesh, adj, w, t, d) else {
                break;
            };
            t = next;
            d = nd;
            from_edge = None;
            from_vertex = Some(w);
            continue;
        }
        let Some(next) = adj.across[t as usize][k] else {
            out.hit_boundary = true;
            return out;
        };
        // Unfold: rotate d about the shared edge from this triangle's plane into the next's.
        let axis = (mesh.positions[b as usize] - mesh.positions[a as usize]).normalize_or_zero();
        let n2 = face_normal(mesh, next as usize);
        let along = axis * d.dot(axis);
        let perp_len = (d - along).length();
        // In the next plane, the perpendicular part points away from the shared edge, into it.
        let into = n2.cross(axis);
        let nt = mesh.triangles[next as usize];
        let third = nt.iter().copied().find(|&x| x != a && x != b).unwrap_or(a);
        let sign = if (mesh.positions[third as usize] - mesh.positions[a as usize]).dot(into) >= 0.0
        {
            1.0
        } else {
            -1.0
        };
        d = (along + into * sign * perp_len).normalize_or_zero();
        from_edge = (0..3).find(|&j| {
            let (x, y) = (nt[j], nt[(j + 1) % 3]);
            (x.min(y), x.max(y)) == (a.min(b), a.max(b))
        });
        from_vertex = None;
        t = next;
    }
    out
}

/// Total order on distances for the queue.
#[derive(Clone, Copy)]
struct D(f64);
impl PartialEq for D {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o).is_eq()
    }
}
impl Eq for D {}
impl PartialOrd for D {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for D {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// The shortest path along mesh edges from `a` to `b` through vertices for which `allowed` is
/// true (`a` and `b` always allowed); `None` if there is none.
pub fn edge_path(
    mesh: &TriMesh,
    adj: &Adjacency,
    a: u32,
    b: u32,
    allowed: &dyn Fn(u32) -> bool,
) -> Option<Vec<u32>> {
    let mut dist: BTreeMap<u32, (f64, u32)> = BTreeMap::new();
    let mut heap = BinaryHeap::new();
    dist.insert(a, (0.0, a));
    heap.push(Reverse((D(0.0), a)));
    while let Some(Reverse((D(d), v))) = heap.pop() {
        if v == b {
            break;
        }
        if dist.get(&v).is_some_and(|&(dv, _)| d > dv) {
            continue;
        }
        for &w in &adj.neighbours[v as usize] {
            if w != b && !allowed(w) {
                continue;
            }
            let nd = d + mesh.positions[v as usize].distance(mesh.positions[w as usize]);
            if dist.get(&w).is_none_or(|&(dw, _)| nd < dw) {
                dist.insert(w, (nd, v));
                heap.push(Reverse((D(nd), w)));
            }
        }
    }
    dist.get(&b)?;
    let mut path = vec![b];
    let mut v = b;
    while v != a {
        v = dist.get(&v)?.1;
        path.push(v);
    }
    path.reverse();
    Some(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_flatten::testmesh::spherical_cap;

    #[test]
    fn geodesics_from_the_rim_of_a_cap_run_along_meridians() {
        let r = 100.0;
        let alpha = 1.2;
        let cap = spherical_cap(r, alpha, 30);
        let topo = Topology::build(&cap).unwrap();
        let adj = Adjacency::new(&cap, &topo);
        let lp = &topo.boundary_loops[0];
        for i in [0, lp.len() / 3, lp.len() / 2 + 7] {
            let dir = inward_direction(&cap, &adj, lp, i);
            let v = lp[i];
            let start = cap.positions[v as usize];
            let g = trace(&cap, &adj, v, dir, 80.0);
            assert!(
                !g.hit_boundary && (g.length - 80.0).abs() < 1e-9,
                "rim vertex {i}: {} mm, boundary {}",
                g.length,
                g.hit_boundary
            );
            let end = *g.points.last().unwrap();
            // Same longitude, 80 mm (0.8 rad) closer to the pole.
            let lon = |p: DVec3| p.y.atan2(p.x);
            let d_lon = (lon(end) - lon(start)).sin().abs();
            let polar = (end.z / end.length()).acos();
            assert!(d_lon < 0.02, "rim vertex {i}: longitude drift {d_lon}");
            assert!((polar - (alpha - 0.8)).abs() < 0.01, "polar {polar}");
        }
    }

    #[test]
    fn corridor_edge_path_stays_near_the_geodesic() {
        let cap = spherical_cap(100.0, 1.2, 30);
        let topo = Topology::build(&cap).unwrap();
        let adj = Adjacency::new(&cap, &topo);
        let lp = &topo.boundary_loops[0];
        let i = 17;
        let g = trace(&cap, &adj, lp[i], inward_direction(&cap, &adj, lp, i), 70.0);
        let end = *g.points.last().unwrap();
        let corridor: std::collections::BTreeSet<u32> = g
            .faces
            .iter()
            .flat_map(|&t| cap.triangles[t as usize])
            .collect();
        let apex = *corridor
            .iter()
            .min_by(|&&a, &&b| {
                cap.positions[a as usize]
                    .distance(end)
                    .total_cmp(&cap.positions[b as usize].distance(end))
            })
            .unwrap();
        let path = edge_path(&cap, &adj, lp[i], apex, &|v| corridor.contains(&v)).unwrap();
        let len: f64 = path
            .windows(2)
            .map(|w| cap.positions[w[0] as usize].distance(cap.positions[w[1] as usize]))
            .sum();
        assert!(len < 70.0 * 1.15 && len > 70.0 * 0.95, "{len}");
    }
}
