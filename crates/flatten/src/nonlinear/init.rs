//! Flip-free starting maps for the nonlinear methods: Tutte's barycentric embedding
//! ([`crate::tutte`]: uniform weights, boundary on a circle spaced by 3D arc length), scaled to
//! the 3D area so that the distortion energies start near their scale optimum. By Tutte's
//! theorem every triangle of a disk mesh keeps its orientation, which is what the flip-free
//! line searches need to start from.

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use crate::FlattenError;

/// Tutte embedding of a disk mesh, scaled to the total 3D area, centred at the origin.
pub fn tutte(mesh: &TriMesh, topo: &Topology) -> Result<Vec<DVec2>, FlattenError> {
    let mut uv = crate::tutte::tutte(mesh, topo)?;
    scale_to_area(mesh, &mut uv);
    Ok(uv)
}

/// The least-squares conformal map (part of [`crate::lscm`], two free pins) scaled to the 3D
/// area, if it is flip-free; otherwise [`tutte`]. On curved patches LSCM is far closer to the
/// isometric optimum than Tutte (its only distortion is the area scale), so projected Newton
/// needs several times fewer iterations from it; LSCM is not guaranteed flip-free, hence the
/// check and the fallback.
pub fn lscm_or_tutte(mesh: &TriMesh, topo: &Topology) -> Result<Vec<DVec2>, FlattenError> {
    if let Ok((mut uv, _)) = crate::lscm::conformal_map(mesh, topo, &[]) {
        let total: f64 = (0..mesh.triangles.len())
            .map(|t| signed_area(mesh, &uv, t))
            .sum();
        if total < 0.0 {
            // A mirrored solution is as good: reflect it.
            uv.iter_mut().for_each(|p| p.x = -p.x);
        }
        if uv.iter().all(|p| p.is_finite())
            && (0..mesh.triangles.len()).all(|t| signed_area(mesh, &uv, t) > 0.0)
        {
            scale_to_area(mesh, &mut uv);
            return Ok(uv);
        }
    }
    tutte(mesh, topo)
}

/// Signed area of the 2D image of triangle `t`.
pub fn signed_area(mesh: &TriMesh, uv: &[DVec2], t: usize) -> f64 {
    let [a, b, c] = mesh.triangles[t];
    let (a, b, c) = (uv[a as usize], uv[b as usize], uv[c as usize]);
    0.5 * (b - a).perp_dot(c - a)
}

/// Scales `uv` uniformly about its area centroid so that the total (signed) 2D area equals the
/// 3D area.
pub fn scale_to_area(mesh: &TriMesh, uv: &mut [DVec2]) {
    let a3 = mesh.area();
    let mut a2 = 0.0;
    let mut c = DVec2::ZERO;
    for t in 0..mesh.triangles.len() {
        let s = signed_area(mesh, uv, t);
        let [i, j, k] = mesh.triangles[t];
        c += s * (uv[i as usize] + uv[j as usize] + uv[k as usize]) / 3.0;
        a2 += s;
    }
    if a2 > 0.0 && a3 > 0.0 {
        c /= a2;
        let f = (a3 / a2).sqrt();
        for p in uv.iter_mut() {
            *p = (*p - c) * f;
        }
    }
}
