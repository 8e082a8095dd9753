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
//!
//! How far "a few degrees" goes is exact: a map whose principal stretches lie within
//! `[C, S]` turns a direction by at most `asin((S − C)/(S + C))` against the others, so it
//! changes a corner's angle by at most twice that ([`corner_reach`], 0.2003 rad at ±10 %). An
//! inside vertex whose defect exceeds that times its corners ([`beyond_reach`]) lies inside no
//! piece within the limits: it must be on a seam. A smooth surface has none (the largest defect
//! of the 75k-face bunny is 0.13 rad); a raw scan has them where its triangles spike (the
//! 100k-face Nefertiti bust: 33, most of them corners of three faces raised 0.6–1.5 rad out of
//! the plane), and every split that leaves one inside a part ends beyond the limits there,
//! however small the part.

use flatcut_geom::DVec3;
use flatcut_mesh::{Topology, TriMesh};

use crate::band::Band;

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

/// The most a corner's angle can change (radians) under a map whose principal stretches lie
/// within `band`: `2·asin((S − C)/(S + C))`; π when either side is open.
pub fn corner_reach(band: Band) -> f64 {
    let (s, c) = (band.s_max(), band.s_min());
    if !s.is_finite() || c.is_nan() || c <= 0.0 {
        return std::f64::consts::PI;
    }
    2.0 * ((s - c) / (s + c)).clamp(0.0, 1.0).asin()
}

/// Whether each vertex is an inside vertex whose angle defect (`defects`,
/// [`angle_defects`]) exceeds what its corners can absorb within `band`
/// ([`corner_reach`] times their number): no piece within the band holds it inside.
pub fn beyond_reach(mesh: &TriMesh, defects: &[f64], band: Band) -> Vec<bool> {
    let mut corners = vec![0usize; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            corners[v as usize] += 1;
        }
    }
    let reach = corner_reach(band);
    defects
        .iter()
        .zip(corners)
        .map(|(d, k)| d.abs() > reach * k as f64)
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of `n` triangles round an apex raised `h` above a unit circle (a cone's tip), its
    /// outline the circle: the apex is vertex 0.
    fn fan(n: usize, h: f64) -> TriMesh {
        let mut p = vec![DVec3::new(0.0, 0.0, h)];
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            p.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        let t = (0..n as u32)
            .map(|k| [0, 1 + k, 1 + (k + 1) % n as u32])
            .collect();
        TriMesh::new(p, t)
    }

    /// The apex's defect, `2π − n·θ` with θ the angle at the apex of one isosceles face.
    fn apex_defect(n: usize, h: f64) -> f64 {
        let half = (std::f64::consts::PI / n as f64).sin();
        let side = (1.0 + h * h).sqrt();
        std::f64::consts::TAU - n as f64 * 2.0 * (half / side).asin()
    }

    #[test]
    fn a_corner_turns_by_at_most_twice_the_asin_of_the_band() {
        let band = Band::from_pct(Some(10.0), Some(10.0));
        assert!((corner_reach(band) - 2.0 * 0.1f64.asin()).abs() < 1e-12);
        // The map diag(S, C) turns the diagonal of a right angle's corner by exactly that much
        // at the direction where it turns most: tan φ = √(S/C).
        let (s, c): (f64, f64) = (1.1, 0.9);
        let phi = (s / c).sqrt().atan();
        let turned = phi - (c / s * phi.tan()).atan();
        assert!((2.0 * turned - corner_reach(band)).abs() < 1e-12);
        assert_eq!(
            corner_reach(Band::from_pct(None, Some(10.0))),
            std::f64::consts::PI
        );
        assert_eq!(corner_reach(Band::from_pct(Some(0.0), Some(0.0))), 0.0);
    }

    #[test]
    fn a_spike_beyond_what_its_corners_absorb_must_be_on_a_seam() {
        let band = Band::from_pct(Some(10.0), Some(10.0));
        let reach = corner_reach(band);
        // Three faces round a raised apex: beyond reach once its defect passes 3 × 0.2 rad.
        for (h, beyond) in [(0.3, false), (0.5, true), (2.0, true)] {
            let m = fan(3, h);
            let topo = Topology::build(&m).unwrap();
            let d = angle_defects(&m, &topo);
            assert!((d[0] - apex_defect(3, h)).abs() < 1e-12);
            assert_eq!(d[0].abs() > 3.0 * reach, beyond, "h = {h}: defect {}", d[0]);
            let b = beyond_reach(&m, &d, band);
            assert_eq!(b[0], beyond);
            // The outline is free.
            assert!(b[1..].iter().all(|&x| !x));
        }
        // The same rise round eight faces is within reach: each corner gives a little.
        let m = fan(8, 0.5);
        let topo = Topology::build(&m).unwrap();
        let d = angle_defects(&m, &topo);
        assert!(d[0] < 8.0 * reach);
        assert!(!beyond_reach(&m, &d, band)[0]);
    }
}
