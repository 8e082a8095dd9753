//! Tutte's embedding: a flip-free initial map of a disk, the boundary on a convex polygon of the
//! true boundary length and every interior vertex at the average of its neighbours.
//!
//! Tutte (1963) and Floater (2003): with positive edge weights and the boundary mapped onto a
//! strictly convex polygon, the solution of the discrete Laplace equation is a bijection with
//! no flipped triangle. The boundary vertices are placed on a circle, spaced by the 3D arc
//! length of the boundary, and the circle's radius is chosen so that the inscribed polygon has
//! exactly the 3D boundary length (a circle of radius L/2π would give a polygon slightly shorter
//! than L). Uniform weights are used because cotangent weights can be negative and then lose
//! the guarantee. The map is the flip-free start of the nonlinear methods and ARAP's fallback.

use crate::internal::InternalError;
use std::f64::consts::TAU;

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use crate::FlattenError;
use crate::ops::{first_flip, laplace, used_mask};

/// Tutte's embedding of the disk `mesh` (topology `topo` from `check_disk`), in mm: the
/// boundary polygon has the 3D boundary length. Vertices used by no triangle are put at the
/// origin. Guaranteed flip-free up to round-off; a flip (which only round-off on an extremely
/// thin mesh can cause) is reported as [`FlattenError::NoConvergence`].
pub fn tutte(mesh: &TriMesh, topo: &Topology) -> Result<Vec<DVec2>, FlattenError> {
    let n = mesh.positions.len();
    let lp = match topo.boundary_loops.as_slice() {
        [lp] => lp,
        other => {
            return Err(FlattenError::Internal(InternalError::TutteLoops {
                loops: other.len(),
            }));
        }
    };
    let boundary = convex_boundary(mesh, lp);
    let mut fixed = vec![false; n];
    let mut u = vec![0.0; n];
    let mut v = vec![0.0; n];
    for (i, &b) in lp.iter().enumerate() {
        fixed[b as usize] = true;
        u[b as usize] = boundary[i].x;
        v[b as usize] = boundary[i].y;
    }
    for (i, used) in used_mask(mesh).into_iter().enumerate() {
        if !used {
            fixed[i] = true;
        }
    }
    if fixed.iter().all(|&f| f) {
        // Every used vertex is on the boundary: the polygon is the map.
        return finish(mesh, u, v);
    }
    // Half a unit per triangle corner: every edge with a free end is shared by two triangles,
    // so each such edge gets weight 1 (uniform Tutte weights).
    let w = vec![[0.5; 3]; mesh.triangles.len()];
    let sys = laplace(&mesh.triangles, &w, &fixed, "tutte embedding")?;
    let mut fields = vec![u, v];
    sys.solve(&mut fields, None)?;
    let v = fields.pop().unwrap_or_default();
    let u = fields.pop().unwrap_or_default();
    finish(mesh, u, v)
}

fn finish(mesh: &TriMesh, u: Vec<f64>, v: Vec<f64>) -> Result<Vec<DVec2>, FlattenError> {
    let uv: Vec<DVec2> = u
        .into_iter()
        .zip(v)
        .map(|(x, y)| DVec2::new(x, y))
        .collect();
    if let Some(t) = first_flip(&mesh.triangles, &uv) {
        return Err(FlattenError::NoConvergence {
            method: crate::Method::Isometric,
            reason: format!(
                "the Tutte start map has triangle {t} degenerate (the mesh is too thin for double precision there)"
            ),
        });
    }
    Ok(uv)
}

/// The boundary loop `lp` placed counter-clockwise on a circle, spaced by 3D arc length, with
/// the radius that gives the polygon the 3D boundary length.
pub fn convex_boundary(mesh: &TriMesh, lp: &[u32]) -> Vec<DVec2> {
    let m = lp.len();
    let len: Vec<f64> = (0..m)
        .map(|i| {
            (mesh.positions[lp[(i + 1) % m] as usize] - mesh.positions[lp[i] as usize]).length()
        })
        .collect();
    let total: f64 = len.iter().sum();
    let mut theta = Vec::with_capacity(m);
    let mut acc = 0.0;
    for l in &len {
        theta.push(TAU * acc / total);
        acc += l;
    }
    // Perimeter of the inscribed polygon of the unit circle with these central angles.
    let unit_perimeter: f64 = len
        .iter()
        .map(|l| 2.0 * (0.5 * TAU * l / total).sin())
        .sum();
    let r = total / unit_perimeter;
    theta
        .iter()
        .map(|t| DVec2::new(r * t.cos(), r * t.sin()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh;
    use flatcut_mesh::check_disk;

    #[test]
    fn tutte_is_flip_free_and_has_the_true_boundary_length() {
        for mesh in [
            testmesh::spherical_cap(100.0, 1.4, 12),
            testmesh::saddle(80.0, 10),
            testmesh::cylinder_patch(50.0, 2.0, 60.0, 12, 6),
        ] {
            let topo = check_disk(&mesh).unwrap();
            let uv = tutte(&mesh, &topo).unwrap();
            assert_eq!(crate::ops::count_flips(&mesh.triangles, &uv), 0);
            let lp = &topo.boundary_loops[0];
            let len3: f64 = (0..lp.len())
                .map(|i| {
                    (mesh.positions[lp[(i + 1) % lp.len()] as usize]
                        - mesh.positions[lp[i] as usize])
                        .length()
                })
                .sum();
            let len2: f64 = (0..lp.len())
                .map(|i| (uv[lp[(i + 1) % lp.len()] as usize] - uv[lp[i] as usize]).length())
                .sum();
            assert!((len2 - len3).abs() < 1e-9 * len3, "{len2} vs {len3}");
            // Interior vertices are at the average of their neighbours.
            let b = crate::ops::boundary_mask(mesh.positions.len(), &topo);
            let mut sum = vec![DVec2::ZERO; uv.len()];
            let mut cnt = vec![0.0; uv.len()];
            for &(a, c) in topo.edges.keys() {
                sum[a as usize] += uv[c as usize];
                cnt[a as usize] += 1.0;
                sum[c as usize] += uv[a as usize];
                cnt[c as usize] += 1.0;
            }
            for i in 0..uv.len() {
                if !b[i] {
                    assert!((sum[i] / cnt[i] - uv[i]).length() < 1e-9 * len3);
                }
            }
        }
    }
}
