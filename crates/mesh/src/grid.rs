//! Ruling-aligned grid tessellation of a developable patch.
//!
//! The adaptive tessellator splits triangles at their longest edge, so its vertices do not lie on
//! the rulings of a developable surface and the polyhedral surface has small angle defects: an
//! exact unfolding would refuse it. A developable patch parametrised along its rulings (cones,
//! cylinders, the two-rail developables) is tessellated here on a tensor grid instead: every
//! grid quad spans two rulings and is planar, so the mesh is exactly developable and unfolds
//! with zero distortion. Grid lines are refined where the chordal error along either parameter
//! direction exceeds the tolerance (whole rows/columns, which keeps the grid structure).

use flatcut_geom::{DVec2, Tolerances};
use flatcut_surface::{DomainKind, ParamSurface};

use crate::TriMesh;
use crate::tessellate::TessError;

/// Samples per grid interval used to measure the chordal error.
const PROBES: usize = 4;
/// Refinement passes at most (each may double the lines of one direction).
const MAX_PASSES: usize = 24;
/// Longest grid line count per direction (a safety cap: 2^12 lines).
const MAX_LINES: usize = 4096;

/// Chordal error of the segment `(a, b)` in one parameter direction at the other parameter `w`.
fn chord_error(s: &dyn ParamSurface, along_u: bool, a: f64, b: f64, w: f64) -> f64 {
    let at = |t: f64| if along_u { s.eval(t, w) } else { s.eval(w, t) };
    let (pa, pb) = (at(a), at(b));
    let mut worst: f64 = 0.0;
    for k in 1..PROBES {
        let f = k as f64 / PROBES as f64;
        let p = at(a + (b - a) * f);
        let q = pa + (pb - pa) * f;
        worst = worst.max(p.distance(q));
    }
    worst
}

/// Refines the lines of one direction until every interval's chordal error, measured along
/// every line of the other direction, is within `tol`.
fn refine(
    s: &dyn ParamSurface,
    along_u: bool,
    lines: &mut Vec<f64>,
    other: &[f64],
    tol: f64,
) -> bool {
    let mut changed = false;
    let mut out = vec![lines[0]];
    for w in lines.windows(2) {
        let err = other
            .iter()
            .map(|&o| chord_error(s, along_u, w[0], w[1], o))
            .fold(0.0, f64::max);
        if err > tol && lines.len() < MAX_LINES {
            out.push(0.5 * (w[0] + w[1]));
            changed = true;
        }
        out.push(w[1]);
    }
    *lines = out;
    changed
}

/// Tessellates a rectangular-domain patch on a grid within the chordal tolerance. Degenerate
/// grid rows (a cone's apex) collapse to one vertex; the result has `params` set.
pub fn tessellate_grid(s: &dyn ParamSurface, tol: &Tolerances) -> Result<TriMesh, TessError> {
    if !(tol.chord_mm.is_finite() && tol.chord_mm > 0.0) {
        return Err(TessError::BadTolerance(tol.chord_mm));
    }
    if s.domain_kind() != DomainKind::Rectangle {
        return Err(TessError::BadDomain { patch: 0 });
    }
    let d = s.domain();
    let mut us: Vec<f64> = (0..=4)
        .map(|k| d.u.0 + (d.u.1 - d.u.0) * k as f64 / 4.0)
        .collect();
    let mut vs: Vec<f64> = (0..=4)
        .map(|k| d.v.0 + (d.v.1 - d.v.0) * k as f64 / 4.0)
        .collect();
    // The error of a grid quad's diagonal is bounded by the errors of its sides for a ruled quad;
    // 0.5 of the tolerance along each direction keeps the quad interior within it.
    let t = 0.5 * tol.chord_mm;
    for _ in 0..MAX_PASSES {
        let a = refine(s, true, &mut us, &vs, t);
        let b = refine(s, false, &mut vs, &us, t);
        if !a && !b {
            break;
        }
    }
    let (nu, nv) = (us.len(), vs.len());
    let mut positions = Vec::with_capacity(nu * nv);
    let mut params = Vec::with_capacity(nu * nv);
    for &u in &us {
        for &v in &vs {
            let p = s.eval(u, v);
            if !flatcut_geom::finite3(p) {
                return Err(TessError::BadDomain { patch: 0 });
            }
            positions.push(p);
            params.push(DVec2::new(u, v));
        }
    }
    // A grid line that collapses to a point (a cone's apex, a pole) becomes one vertex; parameter
    // seams of closed surfaces stay open (the piece must stay a disk), so no general welding.
    let collapsed_v: Vec<bool> = (0..nv)
        .map(|j| (1..nu).all(|i| positions[i * nv + j].distance(positions[j]) <= tol.weld_mm))
        .collect();
    let collapsed_u: Vec<bool> = (0..nu)
        .map(|i| (1..nv).all(|j| positions[i * nv + j].distance(positions[i * nv]) <= tol.weld_mm))
        .collect();
    let id = |i: usize, j: usize| -> u32 {
        if collapsed_v[j] {
            j as u32
        } else if collapsed_u[i] {
            (i * nv) as u32
        } else {
            (i * nv + j) as u32
        }
    };
    let mut triangles = Vec::with_capacity(2 * (nu - 1) * (nv - 1));
    for i in 0..nu - 1 {
        for j in 0..nv - 1 {
            for t in [
                [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
            ] {
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    triangles.push(t);
                }
            }
        }
    }
    // Drop the vertices no triangle uses any more and renumber.
    let mut used = vec![u32::MAX; positions.len()];
    let mut keep = Vec::new();
    for t in &triangles {
        for &v in t {
            if used[v as usize] == u32::MAX {
                used[v as usize] = 0;
            }
        }
    }
    let mut next = 0u32;
    for (v, u) in used.iter_mut().enumerate() {
        if *u == 0 {
            *u = next;
            next += 1;
            keep.push(v);
        }
    }
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|v| used[v as usize]))
        .collect();
    let mut m = TriMesh::new(keep.iter().map(|&v| positions[v]).collect(), triangles);
    m.params = Some(keep.iter().map(|&v| params[v]).collect());
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;
    use flatcut_surface::BSplinePatch;

    fn max_angle_defect(m: &TriMesh) -> f64 {
        let bnd = crate::stats::boundary_vertices(m);
        let mut sum = vec![0.0f64; m.positions.len()];
        for (t, tri) in m.triangles.iter().enumerate() {
            let p = m.corners(t);
            for k in 0..3 {
                sum[tri[k] as usize] +=
                    (p[(k + 1) % 3] - p[k]).angle_between(p[(k + 2) % 3] - p[k]);
            }
        }
        (0..sum.len())
            .filter(|&v| !bnd[v])
            .map(|v| (std::f64::consts::TAU - sum[v]).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn cone_grid_is_exactly_developable_and_a_disk() {
        let cone = BSplinePatch::cone(DVec3::ZERO, 150.0, 80.0, 200.0).unwrap();
        let m = tessellate_grid(&cone, &Tolerances::DEFAULT.with_chord_mm(0.1)).unwrap();
        crate::check_disk(&m).expect("an open cone is a disk");
        assert!(max_angle_defect(&m) < 1e-9, "{}", max_angle_defect(&m));
        // Every triangle's centroid within the tolerance of the cone (radial distance at its
        // height bounds the distance to the surface).
        let radius_at = |z: f64| 150.0 + (80.0 - 150.0) * z / 200.0;
        for t in 0..m.triangles.len() {
            let p = m.corners(t);
            let c = (p[0] + p[1] + p[2]) / 3.0;
            assert!(
                (c.truncate().length() - radius_at(c.z)).abs() <= 0.1 + 1e-9,
                "triangle {t}"
            );
        }
    }
}
