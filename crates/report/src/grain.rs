//! A piece's strain along its material's grain, as the report states it: the largest stretch
//! and compression of the warp (`_along`), the weft (`_across`) and the 45° bias (`_bias`), the
//! material's limits in those directions, how many faces exceed them, the share of the strain
//! taken on the bias, and where the grain runs on the surface. The per-face measure is
//! `flatcut_mesh::grain_strain`, the one the orthotropic flattening uses.

use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;
use flatcut_mesh::grain_strain::{DirectionalLimits, central_face, grain_strain, warp_at};
use serde::Serialize;

/// The grain section of a piece's report (flattened into the report's JSON).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GrainReport {
    /// The material the limits come from.
    pub material: String,
    /// True when the grain was chosen by the flattening (`grain = "auto"` or no grain given).
    pub grain_auto: bool,
    /// The warp's direction on the surface (unit) in the face nearest the piece's centroid.
    pub grain_3d: [f64; 3],
    /// Largest stretch of the warp over the faces (percent, at least 0).
    pub stretch_max_pct_along: f64,
    /// Largest stretch of the weft (percent, at least 0).
    pub stretch_max_pct_across: f64,
    /// Largest stretch of either 45° bias thread (percent, at least 0).
    pub stretch_max_pct_bias: f64,
    /// Largest compression of the warp (percent, positive, at least 0).
    pub compress_max_pct_along: f64,
    /// Largest compression of the weft (percent, positive, at least 0).
    pub compress_max_pct_across: f64,
    /// Largest compression of either bias thread (percent, positive, at least 0).
    pub compress_max_pct_bias: f64,
    /// The material's stretch limit along the warp (percent).
    pub limit_stretch_pct_along: f64,
    /// The material's stretch limit along the weft (percent).
    pub limit_stretch_pct_across: f64,
    /// The material's stretch limit on the bias (percent).
    pub limit_stretch_pct_bias: f64,
    /// The material's compression limit along the warp (percent, positive).
    pub limit_compress_pct_along: f64,
    /// The material's compression limit along the weft (percent, positive).
    pub limit_compress_pct_across: f64,
    /// The material's compression limit on the bias (percent, positive).
    pub limit_compress_pct_bias: f64,
    /// Faces whose warp, weft or bias strain exceeds the material's limits.
    pub faces_over_material_limits: usize,
    /// Largest excess over the material's limits (percentage points; negative: the margin).
    pub material_excess_pct: f64,
    /// Area-weighted share of the squared Green strain that is shear (on the bias).
    pub bias_strain_share: f64,
    /// Each face's largest excess over the limits (percentage points), for the heat map.
    #[serde(skip)]
    pub face_excess_pct: Vec<f64>,
}

impl GrainReport {
    /// Measures the flattening `uv` of `mesh` with the warp along the pattern direction `u`
    /// (unit) against `limits`. `None` when the map is degenerate.
    pub fn compute(
        material: &str,
        grain_auto: bool,
        mesh: &TriMesh,
        uv: &[DVec2],
        u: DVec2,
        limits: &DirectionalLimits,
    ) -> Option<GrainReport> {
        let mut r = GrainReport {
            material: material.to_string(),
            grain_auto,
            grain_3d: warp_at(mesh, uv, u, central_face(mesh)?)?.to_array(),
            stretch_max_pct_along: 0.0,
            stretch_max_pct_across: 0.0,
            stretch_max_pct_bias: 0.0,
            compress_max_pct_along: 0.0,
            compress_max_pct_across: 0.0,
            compress_max_pct_bias: 0.0,
            limit_stretch_pct_along: limits.stretch_pct.along,
            limit_stretch_pct_across: limits.stretch_pct.across,
            limit_stretch_pct_bias: limits.stretch_pct.bias,
            limit_compress_pct_along: limits.compress_pct.along,
            limit_compress_pct_across: limits.compress_pct.across,
            limit_compress_pct_bias: limits.compress_pct.bias,
            faces_over_material_limits: 0,
            material_excess_pct: f64::NEG_INFINITY,
            bias_strain_share: 0.0,
            face_excess_pct: Vec::with_capacity(mesh.triangles.len()),
        };
        let (mut shear, mut all) = (0.0, 0.0);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let c = mesh.corners(t);
            let g = grain_strain(c, tri.map(|v| uv[v as usize]), u)?;
            let (s, p) = (g.stretch_pct(), g.compress_pct());
            r.stretch_max_pct_along = r.stretch_max_pct_along.max(s.along);
            r.stretch_max_pct_across = r.stretch_max_pct_across.max(s.across);
            r.stretch_max_pct_bias = r.stretch_max_pct_bias.max(s.bias);
            r.compress_max_pct_along = r.compress_max_pct_along.max(p.along);
            r.compress_max_pct_across = r.compress_max_pct_across.max(p.across);
            r.compress_max_pct_bias = r.compress_max_pct_bias.max(p.bias);
            let e = g.excess(limits);
            r.faces_over_material_limits += usize::from(e > 0.0);
            r.material_excess_pct = r.material_excess_pct.max(e);
            r.face_excess_pct.push(e);
            let area = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length();
            let (sh, a) = g.bias_share_parts();
            shear += area * sh;
            all += area * a;
        }
        r.bias_strain_share = if all > 0.0 { shear / all } else { 0.0 };
        Some(r)
    }

    /// True when no face exceeds the material's limits.
    pub fn within(&self) -> bool {
        self.faces_over_material_limits == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;
    use flatcut_mesh::grain_strain::ByDirection;

    #[test]
    fn a_square_stretched_along_its_warp_is_over_the_warp_limit_only() {
        let mut mesh = TriMesh::new(
            vec![
                DVec3::ZERO,
                DVec3::new(10.0, 0.0, 0.0),
                DVec3::new(10.0, 10.0, 0.0),
                DVec3::new(0.0, 10.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let uv: Vec<DVec2> = mesh
            .positions
            .iter()
            .map(|p| DVec2::new(p.x * 1.02, p.y))
            .collect();
        mesh.flat = Some(uv.clone());
        let lim = DirectionalLimits {
            stretch_pct: ByDirection {
                along: 1.0,
                across: 1.0,
                bias: 5.0,
            },
            compress_pct: ByDirection {
                along: 1.0,
                across: 1.0,
                bias: 5.0,
            },
        };
        let r = GrainReport::compute("m", false, &mesh, &uv, DVec2::X, &lim).unwrap();
        assert!((r.stretch_max_pct_along - 2.0).abs() < 1e-9, "{r:?}");
        assert!(r.stretch_max_pct_across < 1e-9);
        assert!(r.stretch_max_pct_bias > 0.9 && r.stretch_max_pct_bias < 1.1);
        assert_eq!(r.faces_over_material_limits, 2);
        assert!((r.material_excess_pct - 1.0).abs() < 1e-9);
        assert_eq!(r.grain_3d, [1.0, 0.0, 0.0]);
        // The same map with the grain across: the weft carries the 2 % now.
        let r = GrainReport::compute("m", false, &mesh, &uv, DVec2::Y, &lim).unwrap();
        assert!((r.stretch_max_pct_across - 2.0).abs() < 1e-9, "{r:?}");
        assert!(r.stretch_max_pct_along < 1e-9);
        let json = serde_json::to_string(&r).unwrap();
        assert!(json.contains("\"stretch_max_pct_bias\""), "{json}");
    }
}
