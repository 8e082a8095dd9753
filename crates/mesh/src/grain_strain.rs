//! Strain of one triangle's flat map along a material's grain: the stretch factors of the warp,
//! the weft and the two 45° bias threads, and the Green strain in the warp's frame. The one
//! definition the orthotropic flattening (its grain frames), its `grain = "auto"` search and the
//! report's per-direction limits share.
//!
//! A woven or knitted material's threads are straight in the cut piece: the warp runs along the
//! pattern's grain direction `u` (a unit vector of the plane), the weft along `w = u⊥`, the bias
//! along `(u ± w)/√2`. A thread along the 2D direction `d` lies on the surface along
//! `J⁻¹d` (J: the triangle's map, 3D frame → plane), so its stretch factor, in the flattener's
//! convention (flat length over 3D length, as σ1 and σ2), is `1/|J⁻¹d|`; it lies between σ2 and
//! σ1. The Green strain E = ½(FᵀF − I) of F = J·[a b], a = J⁻¹u/|J⁻¹u| the warp's 3D direction
//! and b its perpendicular in the triangle's plane, is the strain the orthotropic energy
//! weighs: E_aa along the warp, E_bb across it, E_ab the shear (the bias).

use glam::{DMat2, DVec2, DVec3};

use crate::TriMesh;
use crate::distortion::local_frame;

/// Limits in percent along the warp, across it (the weft) and on the 45° bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ByDirection {
    /// Along the warp (percent).
    pub along: f64,
    /// Across the warp, along the weft (percent).
    pub across: f64,
    /// On the 45° bias (percent).
    pub bias: f64,
}

impl ByDirection {
    /// The smallest of the three.
    pub fn min(&self) -> f64 {
        self.along.min(self.across).min(self.bias)
    }
}

/// A material's stretch and compression limits per direction (percent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLimits {
    /// The largest stretch per direction (percent, ≥ 0).
    pub stretch_pct: ByDirection,
    /// The largest compression per direction (percent, ≥ 0).
    pub compress_pct: ByDirection,
}

/// One triangle's strain in the material's directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrainStrain {
    /// Stretch factor of the warp (1 = unchanged).
    pub along: f64,
    /// Stretch factor of the weft.
    pub across: f64,
    /// The larger stretch factor of the two bias threads.
    pub bias_max: f64,
    /// The smaller stretch factor of the two bias threads.
    pub bias_min: f64,
    /// Green strain along the warp, across it, and the shear, in the warp's 3D frame.
    pub e_aa: f64,
    /// Green strain across the warp.
    pub e_bb: f64,
    /// Green shear strain between warp and weft.
    pub e_ab: f64,
}

impl GrainStrain {
    /// The share of the squared Green strain that is shear (on the bias):
    /// 2E_ab² / (E_aa² + E_bb² + 2E_ab²), 0 for an undistorted triangle.
    pub fn bias_share_parts(&self) -> (f64, f64) {
        let shear = 2.0 * self.e_ab * self.e_ab;
        (shear, self.e_aa * self.e_aa + self.e_bb * self.e_bb + shear)
    }
}

impl GrainStrain {
    /// Stretch in percent (positive part) along, across and on the bias.
    pub fn stretch_pct(&self) -> ByDirection {
        let p = |s: f64| ((s - 1.0) * 100.0).max(0.0);
        ByDirection {
            along: p(self.along),
            across: p(self.across),
            bias: p(self.bias_max),
        }
    }

    /// Compression in percent (positive part) along, across and on the bias.
    pub fn compress_pct(&self) -> ByDirection {
        let p = |s: f64| ((1.0 - s) * 100.0).max(0.0);
        ByDirection {
            along: p(self.along),
            across: p(self.across),
            bias: p(self.bias_min),
        }
    }

    /// The largest excess over the limits of the warp, weft or bias strain, in percentage
    /// points (negative: within them by that margin).
    pub fn excess(&self, l: &DirectionalLimits) -> f64 {
        let over = |s: f64, lim: f64| (s - 1.0) * 100.0 - lim;
        let under = |s: f64, lim: f64| (1.0 - s) * 100.0 - lim;
        [
            over(self.along, l.stretch_pct.along),
            over(self.across, l.stretch_pct.across),
            over(self.bias_max, l.stretch_pct.bias),
            under(self.along, l.compress_pct.along),
            under(self.across, l.compress_pct.across),
            under(self.bias_min, l.compress_pct.bias),
        ]
        .into_iter()
        .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// The map of a triangle: J (3D frame → plane) from its 3D and 2D corners, `None` for a
/// degenerate 3D triangle or a degenerate image.
pub fn triangle_jacobian(tri3: [DVec3; 3], tri2: [DVec2; 3]) -> Option<DMat2> {
    let (loc, _, _) = local_frame(tri3[0], tri3[1], tri3[2])?;
    let s = DMat2::from_cols(loc[1] - loc[0], loc[2] - loc[0]);
    let t = DMat2::from_cols(tri2[1] - tri2[0], tri2[2] - tri2[0]);
    let j = t * s.inverse();
    (j.determinant().is_finite() && j.determinant() != 0.0).then_some(j)
}

/// The warp's direction on the surface for the pattern grain `u`: J⁻¹u normalised, in the
/// triangle's local frame (`None` for a degenerate map).
pub fn warp_in_frame(j: DMat2, u: DVec2) -> Option<DVec2> {
    let a = j.inverse() * u;
    let l = a.length();
    (l.is_finite() && l > 0.0).then(|| a / l)
}

/// The strain of map `j` (3D frame → plane) in the material's directions for the unit pattern
/// grain `u`.
pub fn grain_strain_of(j: DMat2, u: DVec2) -> Option<GrainStrain> {
    let inv = j.inverse();
    let w = u.perp();
    let stretch = |d: DVec2| 1.0 / (inv * d).length();
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let (b1, b2) = (stretch((u + w) * r), stretch((u - w) * r));
    let a = warp_in_frame(j, u)?;
    let (p, q) = (j * a, j * a.perp());
    let g = GrainStrain {
        along: stretch(u),
        across: stretch(w),
        bias_max: b1.max(b2),
        bias_min: b1.min(b2),
        e_aa: 0.5 * (p.dot(p) - 1.0),
        e_bb: 0.5 * (q.dot(q) - 1.0),
        e_ab: 0.5 * p.dot(q),
    };
    [g.along, g.across, g.bias_max, g.bias_min]
        .iter()
        .all(|v| v.is_finite())
        .then_some(g)
}

/// The strain of the map taking triangle `tri3` to `tri2` in the material's directions for the
/// unit pattern grain `u`; `None` for a degenerate triangle or image.
pub fn grain_strain(tri3: [DVec3; 3], tri2: [DVec2; 3], u: DVec2) -> Option<GrainStrain> {
    grain_strain_of(triangle_jacobian(tri3, tri2)?, u)
}

/// The pattern direction of the 3D direction `d` drawn at `centre` in the map `uv` of `mesh`:
/// the area-weighted mean image of its projection on the faces whose centroids lie within
/// `radius` of `centre` (the nearest face when none does), unit length; `None` where `d` is
/// normal to the surface there or the map is degenerate. Local, because on a closed or wrapped
/// piece a fixed 3D vector's projections cancel over the whole surface.
pub fn pattern_direction_near(
    mesh: &TriMesh,
    uv: &[DVec2],
    d: DVec3,
    centre: DVec3,
    radius: f64,
) -> Option<DVec2> {
    let image = |t: usize| -> Option<DVec2> {
        let c = mesh.corners(t);
        let (_, ex, ey) = local_frame(c[0], c[1], c[2])?;
        let j = triangle_jacobian(c, mesh.triangles[t].map(|v| uv[v as usize]))?;
        let area = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length();
        Some(area * (j * DVec2::new(d.dot(ex), d.dot(ey))))
    };
    let near: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&t| centroid(mesh, t).distance(centre) <= radius)
        .collect();
    let faces = if near.is_empty() {
        nearest_face(mesh, centre).into_iter().collect()
    } else {
        near
    };
    let s: DVec2 = faces.into_iter().filter_map(image).sum();
    let l = s.length();
    (l.is_finite() && l > 0.0).then(|| s / l)
}

/// The centroid of face `t`.
pub fn centroid(mesh: &TriMesh, t: usize) -> DVec3 {
    let c = mesh.corners(t);
    (c[0] + c[1] + c[2]) / 3.0
}

/// The face whose centroid is nearest to `p` (the first of equals); `None` for no faces.
pub fn nearest_face(mesh: &TriMesh, p: DVec3) -> Option<usize> {
    (0..mesh.triangles.len()).min_by(|&a, &b| {
        centroid(mesh, a)
            .distance_squared(p)
            .total_cmp(&centroid(mesh, b).distance_squared(p))
    })
}

/// The face nearest to the area-weighted centroid of the surface: where a piece's grain is
/// stated when no grain line is drawn.
pub fn central_face(mesh: &TriMesh) -> Option<usize> {
    let (mut s, mut w) = (DVec3::ZERO, 0.0);
    for t in 0..mesh.triangles.len() {
        let c = mesh.corners(t);
        let a = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length();
        s += a * centroid(mesh, t);
        w += a;
    }
    nearest_face(mesh, if w > 0.0 { s / w } else { DVec3::ZERO })
}

/// The 3D direction (unit) of the warp that runs along the pattern direction `u`, in face `t`
/// of the map `uv` of `mesh`.
pub fn warp_at(mesh: &TriMesh, uv: &[DVec2], u: DVec2, t: usize) -> Option<DVec3> {
    let c = mesh.corners(t);
    let (_, ex, ey) = local_frame(c[0], c[1], c[2])?;
    let j = triangle_jacobian(c, mesh.triangles[t].map(|v| uv[v as usize]))?;
    let a = warp_in_frame(j, u)?;
    Some(ex * a.x + ey * a.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tri() -> [DVec3; 3] {
        [DVec3::ZERO, DVec3::X, DVec3::Y]
    }

    #[test]
    fn stretch_along_the_warp_is_seen_along_only() {
        // The warp along x stretched by 3 %: the weft is unchanged; a bias thread of the
        // pattern lies on the surface along (1/1.03, 1)/√2, so its stretch is
        // 1/√((1/1.03² + 1)/2), about half the warp's.
        let t2 = [DVec2::ZERO, DVec2::new(1.03, 0.0), DVec2::new(0.0, 1.0)];
        let g = grain_strain(unit_tri(), t2, DVec2::X).unwrap();
        assert!((g.along - 1.03).abs() < 1e-12, "{g:?}");
        assert!((g.across - 1.0).abs() < 1e-12);
        let bias = 1.0 / ((1.0 / (1.03f64 * 1.03) + 1.0) / 2.0).sqrt();
        assert!((g.bias_max - bias).abs() < 1e-12 && (g.bias_min - bias).abs() < 1e-12);
        assert!((g.e_aa - 0.5 * (1.03 * 1.03 - 1.0)).abs() < 1e-12);
        assert!(g.e_bb.abs() < 1e-12 && g.e_ab.abs() < 1e-12);
        // The same map seen with the grain across: the roles swap.
        let h = grain_strain(unit_tri(), t2, DVec2::Y).unwrap();
        assert!((h.across - 1.03).abs() < 1e-12 && (h.along - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_pure_shear_is_on_the_bias() {
        // Simple shear of the warp/weft square: the threads keep their lengths to first order,
        // one bias thread lengthens and the other shortens.
        let k = 0.05;
        let t2 = [DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::new(k, 1.0)];
        let g = grain_strain(unit_tri(), t2, DVec2::X).unwrap();
        assert!((g.along - 1.0).abs() < 1e-12);
        assert!((g.across - 1.0).abs() < 2e-3);
        assert!(g.bias_max > 1.02 && g.bias_min < 0.98, "{g:?}");
        let (s, t) = g.bias_share_parts();
        assert!(s / t > 0.99, "{}", s / t);
    }
}
