//! Cuts through a cone: a vertex whose 3D angle sum lies far from a full turn (a toe's tip, the
//! fold where a trunk meets a head) cannot be inside a flat piece within tight limits, however
//! small the piece: flat, the angles round an inside vertex add up to a full turn, so its faces
//! must absorb the whole angle defect between them, and a corner's angle changes by at most a
//! few degrees within a few percent of stretch. On a piece's outline the vertex is free (its
//! angles there add up to whatever they are). A chord of the flat map through the worst face
//! passes beside such a vertex and leaves it inside one side, split after split; the cut here
//! runs from the outline to the vertex and on to the outline again, so the vertex lies on both
//! sides' outlines.
//!
//! The path is the shortest way over the piece's edges, each vertex weighted by
//! `1 / (1 + CONE_PULL·|defect|)`, so a cut bends to pass the other cones near its way.

use flatcut_geom::DVec3;
use flatcut_mesh::{Topology, TriMesh};

/// How strongly a cut is drawn through other cones on its way (per radian of angle defect).
const CONE_PULL: f64 = 4.0;
/// Arcs of the outline the second end of a cut is sought in (the first end is the outline vertex
/// nearest the cone, arc 0): the ends are at least one arc apart round the outline.
const ARCS: usize = 6;

/// Angle defect (2π less the 3D angle sum, radians) at every vertex; 0 on the outline.
pub fn angle_defects(mesh: &TriMesh, topo: &Topology) -> Vec<f64> {
    let mut sum = vec![0.0; mesh.positions.len()];
    for t in &mesh.triangles {
        let p = t.map(|v| mesh.positions[v as usize]);
        for k in 0..3 {
            let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            sum[t[k] as usize] += a.angle_between(b);
        }
    }
    let mut rim = vec![false; mesh.positions.len()];
    for l in &topo.boundary_loops {
        for &v in l {
            rim[v as usize] = true;
        }
    }
    sum.iter()
        .zip(rim)
        .map(|(&s, r)| if r { 0.0 } else { std::f64::consts::TAU - s })
        .collect()
}

/// The inside vertex of largest angle defect (either sign) among the corners of face `t` and
/// their neighbours; `None` when all of them are on the outline.
pub fn worst_cone(mesh: &TriMesh, defects: &[f64], t: usize) -> Option<u32> {
    let corners = mesh.triangles.get(t)?;
    let near: Vec<u32> = mesh
        .triangles
        .iter()
        .filter(|f| f.iter().any(|v| corners.contains(v)))
        .flatten()
        .copied()
        .collect();
    near.into_iter()
        .filter(|&v| defects[v as usize] != 0.0)
        .max_by(|&a, &b| {
            defects[a as usize]
                .abs()
                .total_cmp(&defects[b as usize].abs())
                .then(b.cmp(&a))
        })
}

/// Cuts from the outline `rim` through vertex `cone` to the outline again (3D points along the
/// piece's edges): the first end is the outline vertex nearest the cone, the second the nearest
/// in each of the middle arcs of the outline opposite it (the outline in six arcs from the
/// first end).
pub fn cuts_through(mesh: &TriMesh, defects: &[f64], rim: &[u32], cone: u32) -> Vec<Vec<DVec3>> {
    let n = rim.len();
    if n < ARCS {
        return Vec::new();
    }
    let cost: Vec<f64> = defects
        .iter()
        .map(|d| 1.0 / (1.0 + CONE_PULL * d.abs()))
        .collect();
    let d = flatcut_mesh::geodesic::distances_from(mesh, cone);
    let p = &mesh.positions;
    let mut along = vec![0.0; n + 1];
    for i in 0..n {
        along[i + 1] = along[i] + p[rim[i] as usize].distance(p[rim[(i + 1) % n] as usize]);
    }
    let round = along[n];
    let nearest = |ok: &dyn Fn(usize) -> bool| {
        (0..n)
            .filter(|&i| ok(i) && d[rim[i] as usize].is_finite())
            .min_by(|&a, &b| {
                d[rim[a] as usize]
                    .total_cmp(&d[rim[b] as usize])
                    .then(a.cmp(&b))
            })
    };
    let Some(a) = nearest(&|_| true) else {
        return Vec::new();
    };
    let leg = |from: u32| flatcut_mesh::cut_graph::shortest_path(mesh, &cost, from, cone);
    let Some(first) = leg(rim[a]) else {
        return Vec::new();
    };
    (2..ARCS - 1)
        .filter_map(|k| {
            let arc = |i: usize| {
                let s = (along[i] - along[a]).rem_euclid(round) / round * ARCS as f64;
                s >= (k as f64 - 0.5) && s < (k as f64 + 0.5)
            };
            let b = nearest(&arc)?;
            let mut second = leg(rim[b])?;
            second.reverse();
            let path: Vec<u32> = first.iter().chain(&second[1..]).copied().collect();
            // A path that returns to a vertex it passed cuts off no disk.
            let mut seen = std::collections::BTreeSet::new();
            path.iter()
                .all(|v| seen.insert(*v))
                .then(|| path.iter().map(|&v| p[v as usize]).collect())
        })
        .collect()
}
