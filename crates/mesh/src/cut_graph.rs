//! Cut graphs: the edges along which a connected surface of any genus, with any number of
//! boundary loops, is cut open into one disk.
//!
//! Method (Erickson & Whittlesey 2005, the greedy system of loops, as tree–cotree): a
//! shortest-path tree T of the vertices from a root, the edge lengths weighted by a per-vertex
//! cost (a seam is cheaper where it is hidden); a *maximum* spanning tree C of the dual graph
//! over the interior edges not in T, each dual edge weighed by the length of the loop it closes
//! with T (root → u, the edge, v → root). The edges in neither tree close the shortest loops
//! through the root that generate the surface's first homology (2g of them on a closed surface
//! of genus g, plus one per extra boundary loop). Every edge not in C is the cut graph: the
//! triangles joined across C form a tree of triangles, a disk. Dangling branches of the tree are
//! pruned (a branch cut open and sewn again changes nothing), leaving the handle loops, the
//! paths that join the boundary loops, and the boundary itself.
//!
//! The loops of a greedy system all pass through the root; [`tighten`] then shortens each path
//! of the graph between its branch points, holding the ends: the shortest weighted edge path in a
//! strip of triangles around it that avoids the rest of the graph, repeated while it gains, the
//! cut kept only while the surface still opens into one disk. That moves each path toward the
//! geodesic of its homotopy class as far as the mesh's edges allow.
//!
//! On a surface with boundary the tree is grown from every boundary vertex at once (the boundary
//! is the root): the leftover edges then close the loops around the handles through the
//! boundary and the paths that join one boundary loop to another.
//!
//! A closed surface of genus 0 has an empty cut graph (a sphere has no handle to cut): its
//! opening is the caller's choice (a slit, a loop).

use std::cmp::Reverse;
use std::collections::{BTreeMap, BTreeSet, BinaryHeap};

use crate::seams::{Dist, cut_along_seams};
use crate::{Topology, TopologyError, TriMesh, check_disk};

/// The topology of one connected surface: its genus and number of boundary loops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SurfaceType {
    /// The number of handles g (0 for a disk or sphere, 1 for a torus or a tube with a handle).
    pub genus: usize,
    /// The number of boundary loops b (0 for a closed surface).
    pub boundaries: usize,
}

/// Genus and boundary count of a connected, manifold mesh (χ = 2 − 2g − b).
pub fn surface_type(mesh: &TriMesh, topo: &Topology) -> SurfaceType {
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let v = used.iter().filter(|&&u| u).count() as i64;
    let chi = v - topo.edges.len() as i64 + mesh.triangles.len() as i64;
    let b = topo.boundary_loops.len() as i64;
    SurfaceType {
        genus: ((2 - b - chi).max(0) / 2) as usize,
        boundaries: b as usize,
    }
}

/// An edge key `(min, max)`.
fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// The weighted length of edge `a`–`b`: its length times the mean cost of its ends.
fn weight(mesh: &TriMesh, cost: &[f64], a: u32, b: u32) -> f64 {
    let (a, b) = (a as usize, b as usize);
    mesh.positions[a].distance(mesh.positions[b]) * 0.5 * (cost[a] + cost[b])
}

/// Weighted shortest-path distances and tree from `sources` over the edges of `topo` whose
/// both ends `allowed` accepts (sources always). `parent[v]` is the previous vertex.
pub(crate) fn dijkstra(
    mesh: &TriMesh,
    adj: &[Vec<u32>],
    cost: &[f64],
    sources: &[u32],
    allowed: impl Fn(u32) -> bool,
) -> (Vec<f64>, Vec<u32>) {
    let n = mesh.positions.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        dist[s as usize] = 0.0;
        heap.push(Reverse((Dist(0.0), s)));
    }
    while let Some(Reverse((Dist(d), v))) = heap.pop() {
        if d > dist[v as usize] {
            continue;
        }
        for &w in &adj[v as usize] {
            if !allowed(w) {
                continue;
            }
            let nd = d + weight(mesh, cost, v, w);
            if nd < dist[w as usize] {
                dist[w as usize] = nd;
                parent[w as usize] = v;
                heap.push(Reverse((Dist(nd), w)));
            }
        }
    }
    (dist, parent)
}

/// The cut graph of a connected manifold mesh (see the module documentation) as paths of
/// interior edges between the graph's branch points (vertices of degree other than 2, and
/// boundary vertices); a closed path repeats its first vertex. `cost` (one positive factor per
/// vertex) weighs the edge lengths; `root` is the base of the loops. Empty for a disk and for a
/// closed surface of genus 0.
pub fn cut_graph(mesh: &TriMesh, cost: &[f64], root: u32) -> Result<Vec<Vec<u32>>, TopologyError> {
    let topo = Topology::build(mesh)?;
    if topo.component_count > 1 {
        return Err(TopologyError::SeveralComponents {
            count: topo.component_count,
        });
    }
    let adj = crate::seams::vertex_neighbours(mesh);
    // On a surface with boundary the loops start and end on it: the tree is a forest grown from
    // every boundary vertex, each of its trees a slit from the boundary that cuts nothing apart.
    let bnd = on_boundary(mesh, &topo);
    let sources: Vec<u32> = if topo.boundary_loops.is_empty() {
        vec![root]
    } else {
        (0..mesh.positions.len() as u32)
            .filter(|&v| bnd[v as usize])
            .collect()
    };
    let (dist, parent) = dijkstra(mesh, &adj, cost, &sources, |_| true);
    let tree: BTreeSet<(u32, u32)> = parent
        .iter()
        .enumerate()
        .filter(|&(_, &p)| p != u32::MAX)
        .map(|(v, &p)| key(v as u32, p))
        .collect();
    // Dual edges by the length of the loop they close, longest first (ties by key).
    let mut dual: Vec<(f64, (u32, u32), u32, u32)> = topo
        .edges
        .iter()
        .filter(|(k, _)| !tree.contains(k))
        .filter_map(|(&(a, b), e)| {
            let (f, g) = (e.fwd?, e.rev?);
            let l = dist[a as usize] + weight(mesh, cost, a, b) + dist[b as usize];
            Some((l, (a, b), f, g))
        })
        .collect();
    dual.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    let mut faces: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    let mut cotree: BTreeSet<(u32, u32)> = BTreeSet::new();
    for &(_, k, f, g) in &dual {
        let (rf, rg) = (find(&mut faces, f), find(&mut faces, g));
        if rf != rg {
            faces[rf.max(rg) as usize] = rf.min(rg);
            cotree.insert(k);
        }
    }
    // The graph: every edge not in the cotree; prune vertices of degree one.
    let mut graph: BTreeMap<u32, BTreeSet<u32>> = BTreeMap::new();
    for &(a, b) in topo.edges.keys() {
        if !cotree.contains(&(a, b)) {
            graph.entry(a).or_default().insert(b);
            graph.entry(b).or_default().insert(a);
        }
    }
    let mut leaves: Vec<u32> = graph
        .iter()
        .filter(|(_, n)| n.len() == 1)
        .map(|(&v, _)| v)
        .collect();
    while let Some(v) = leaves.pop() {
        let Some(nb) = graph.get(&v) else { continue };
        let Some(&w) = nb.iter().next() else { continue };
        if nb.len() != 1 {
            continue;
        }
        graph.remove(&v);
        if let Some(nw) = graph.get_mut(&w) {
            nw.remove(&v);
            match nw.len() {
                0 => {
                    graph.remove(&w);
                }
                1 => leaves.push(w),
                _ => {}
            }
        }
    }
    let boundary: BTreeSet<(u32, u32)> = topo
        .edges
        .iter()
        .filter(|(_, e)| e.is_boundary())
        .map(|(&k, _)| k)
        .collect();
    Ok(paths_of(&graph, &boundary, &bnd))
}

/// Per vertex: does it lie on the boundary?
fn on_boundary(mesh: &TriMesh, topo: &Topology) -> Vec<bool> {
    let mut b = vec![false; mesh.positions.len()];
    for lp in &topo.boundary_loops {
        for &v in lp {
            b[v as usize] = true;
        }
    }
    b
}

/// The interior edges of `graph` as paths between branch points (degree ≠ 2 or on the
/// boundary); a cycle of degree-2 vertices is one closed path.
fn paths_of(
    graph: &BTreeMap<u32, BTreeSet<u32>>,
    boundary: &BTreeSet<(u32, u32)>,
    on_bnd: &[bool],
) -> Vec<Vec<u32>> {
    let interior = |a: u32, b: u32| !boundary.contains(&key(a, b));
    let degree = |v: u32| {
        graph
            .get(&v)
            .map_or(0, |n| n.iter().filter(|&&w| interior(v, w)).count())
    };
    let is_branch = |v: u32| on_bnd[v as usize] || degree(v) != 2;
    let mut used: BTreeSet<(u32, u32)> = BTreeSet::new();
    let mut out = Vec::new();
    let walk = |start: u32, first: u32, used: &mut BTreeSet<(u32, u32)>| {
        let mut path = vec![start, first];
        used.insert(key(start, first));
        let (mut prev, mut cur) = (start, first);
        while !is_branch(cur) && cur != start {
            let next = graph[&cur]
                .iter()
                .copied()
                .find(|&w| w != prev && interior(cur, w) && !used.contains(&key(cur, w)));
            let Some(next) = next else { break };
            used.insert(key(cur, next));
            path.push(next);
            (prev, cur) = (cur, next);
        }
        path
    };
    let vertices: Vec<u32> = graph.keys().copied().collect();
    for &v in vertices.iter().filter(|&&v| is_branch(v)) {
        for &w in &graph[&v] {
            if interior(v, w) && !used.contains(&key(v, w)) {
                out.push(walk(v, w, &mut used));
            }
        }
    }
    // Cycles with no branch point.
    for &v in &vertices {
        for &w in &graph[&v] {
            if interior(v, w) && !used.contains(&key(v, w)) {
                out.push(walk(v, w, &mut used));
            }
        }
    }
    out
}

/// True when cutting `mesh` along `paths` leaves one disk.
pub fn opens_to_disk(mesh: &TriMesh, paths: &[Vec<u32>]) -> bool {
    cut_along_seams(mesh, paths).is_ok_and(|m| check_disk(&m).is_ok())
}

/// Rings of triangles around a path that its tightened version may use.
const STRIP_RINGS: usize = 3;
/// Rounds of tightening (each path shortened in turn, the strip following it).
const TIGHTEN_ROUNDS: usize = 3;

/// Shortens every path of a cut graph between its fixed ends (see the module documentation),
/// keeping a change only while the cut still opens the surface into one disk. `cost` weighs
/// the lengths as for [`cut_graph`].
pub fn tighten(mesh: &TriMesh, paths: &[Vec<u32>], cost: &[f64]) -> Vec<Vec<u32>> {
    let Ok(topo) = Topology::build(mesh) else {
        return paths.to_vec();
    };
    let bnd = on_boundary(mesh, &topo);
    let adj = crate::seams::vertex_neighbours(mesh);
    let mut out = paths.to_vec();
    let length = |p: &[u32]| -> f64 { p.windows(2).map(|w| weight(mesh, cost, w[0], w[1])).sum() };
    for _ in 0..TIGHTEN_ROUNDS {
        let mut gained = false;
        for i in 0..out.len() {
            let path = &out[i];
            let closed = path.len() > 2 && path.first() == path.last();
            let (a, b) = (path[0], path[path.len() - 1]);
            // Vertices of the other paths (their ends included) are off limits.
            let mut blocked = vec![false; mesh.positions.len()];
            for (j, p) in out.iter().enumerate() {
                if j != i {
                    p.iter().for_each(|&v| blocked[v as usize] = true);
                }
            }
            let strip = rings(&adj, path, STRIP_RINGS);
            let allowed = |v: u32| {
                v == a || v == b || (strip[v as usize] && !blocked[v as usize] && !bnd[v as usize])
            };
            let candidate = if closed {
                tighten_loop(mesh, &adj, cost, path, &allowed)
            } else {
                let (_, parent) = dijkstra(mesh, &adj, cost, &[a], |v| v != a && allowed(v));
                trace_back(&parent, a, b)
            };
            let Some(c) = candidate else { continue };
            if length(&c) + 1e-12 < length(&out[i]) {
                let mut trial = out.clone();
                trial[i] = c;
                if opens_to_disk(mesh, &trial) {
                    out = trial;
                    gained = true;
                }
            }
        }
        if !gained {
            break;
        }
    }
    out
}

/// A closed path (its first vertex repeated) shortened: the loop through its start is split at
/// its middle vertex and both halves are shortened between the two, then the loop closed again.
fn tighten_loop(
    mesh: &TriMesh,
    adj: &[Vec<u32>],
    cost: &[f64],
    path: &[u32],
    allowed: &impl Fn(u32) -> bool,
) -> Option<Vec<u32>> {
    let a = path[0];
    let m = path[path.len() / 2];
    let half = |part: &[u32], other: &[u32]| {
        let other: BTreeSet<u32> = other
            .iter()
            .copied()
            .filter(|&v| v != a && v != m)
            .collect();
        let (_, parent) = dijkstra(mesh, adj, cost, &[part[0]], |v| {
            v != part[0] && !other.contains(&v) && allowed(v)
        });
        trace_back(&parent, part[0], *part.last()?)
    };
    let first = &path[..=path.len() / 2];
    let second = &path[path.len() / 2..];
    let p1 = half(first, second)?;
    let p2 = half(second, &p1)?;
    let mut out = p1;
    out.extend_from_slice(&p2[1..]);
    Some(out)
}

/// The path from `a` to `b` in a shortest-path tree rooted at `a`.
fn trace_back(parent: &[u32], a: u32, b: u32) -> Option<Vec<u32>> {
    let mut path = vec![b];
    let mut v = b;
    while v != a {
        v = parent[v as usize];
        if v == u32::MAX || path.len() > parent.len() {
            return None;
        }
        path.push(v);
    }
    path.reverse();
    Some(path)
}

/// The vertices within `k` edge rings of `path`.
fn rings(adj: &[Vec<u32>], path: &[u32], k: usize) -> Vec<bool> {
    let mut inside = vec![false; adj.len()];
    let mut front: Vec<u32> = path.to_vec();
    front.iter().for_each(|&v| inside[v as usize] = true);
    for _ in 0..k {
        let mut next = Vec::new();
        for &v in &front {
            for &w in &adj[v as usize] {
                if !inside[w as usize] {
                    inside[w as usize] = true;
                    next.push(w);
                }
            }
        }
        front = next;
    }
    inside
}

/// The weighted shortest edge path from `a` to `b`.
pub fn shortest_path(mesh: &TriMesh, cost: &[f64], a: u32, b: u32) -> Option<Vec<u32>> {
    let adj = crate::seams::vertex_neighbours(mesh);
    let (_, parent) = dijkstra(mesh, &adj, cost, &[a], |_| true);
    trace_back(&parent, a, b)
}

/// The vertex farthest (weighted) from `sources`, and its distance.
pub fn farthest(mesh: &TriMesh, cost: &[f64], sources: &[u32]) -> Option<(u32, f64)> {
    let adj = crate::seams::vertex_neighbours(mesh);
    let (dist, _) = dijkstra(mesh, &adj, cost, sources, |_| true);
    dist.iter()
        .enumerate()
        .filter(|(_, d)| d.is_finite())
        .max_by(|x, y| x.1.total_cmp(y.1).then(y.0.cmp(&x.0)))
        .map(|(v, &d)| (v as u32, d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    use crate::test_shapes::torus;

    #[test]
    fn a_torus_opens_along_a_meridian_and_a_longitude_into_one_disk() {
        let m = torus(40.0, 10.0, 48, 16);
        let topo = Topology::build(&m).unwrap();
        assert_eq!(
            surface_type(&m, &topo),
            SurfaceType {
                genus: 1,
                boundaries: 0
            }
        );
        let cost = vec![1.0; m.positions.len()];
        let paths = cut_graph(&m, &cost, 0).unwrap();
        assert!(opens_to_disk(&m, &paths));
        let len = |ps: &[Vec<u32>]| -> f64 {
            ps.iter()
                .flat_map(|p| p.windows(2))
                .map(|w| m.positions[w[0] as usize].distance(m.positions[w[1] as usize]))
                .sum()
        };
        // The shortest loops of a torus: a meridian (2π·10 at the outer equator) and a longitude
        // (2π·30 on the inner equator at best); the mesh's polygons are a little shorter.
        let tight = tighten(&m, &paths, &cost);
        assert!(opens_to_disk(&m, &tight));
        let (before, after) = (len(&paths), len(&tight));
        assert!(after <= before + 1e-9, "{after} > {before}");
        let ideal = std::f64::consts::TAU * (10.0 + 30.0);
        assert!(after < 1.25 * ideal, "{after} against {ideal}");
    }

    #[test]
    fn a_disk_has_no_cut_and_an_annulus_one_path_between_its_loops() {
        let grid = crate::test_grid::grid_mesh(4, 4, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        let cost = vec![1.0; grid.positions.len()];
        assert!(cut_graph(&grid, &cost, 6).unwrap().is_empty());
        // The grid with its middle quad's two triangles removed: two boundary loops.
        let mut ring = grid.clone();
        ring.triangles
            .retain(|t| !(t.contains(&6) && t.contains(&12)));
        let paths = cut_graph(&ring, &cost, 0).unwrap();
        assert_eq!(paths.len(), 1);
        assert!(opens_to_disk(&ring, &paths));
    }
}
