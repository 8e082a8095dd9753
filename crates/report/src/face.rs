//! One face's distortion measures, the record every report figure is aggregated from: the
//! report's statistics ([`crate::measure`]) and δ0 ([`crate::delta0`]) both read it.

use flatcut_geom::DVec2;
use serde::Serialize;

/// One face's distortion, at true scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FaceMeasure {
    /// Duncan's μ1 = σ1², the larger squared singular value of the map (1: no stretch).
    pub mu1: f64,
    /// Duncan's μ2 = σ2², the smaller squared singular value.
    pub mu2: f64,
    /// Conformal distortion δ1 = log(μ1/μ2) (dimensionless, ≥ 0).
    pub delta1: f64,
    /// Isometric distortion δ2 = (μ1 + 1/μ1 + μ2 + 1/μ2 − 4)/2 (dimensionless, ≥ 0).
    pub delta2: f64,
    /// σ1σ2 with its sign: negative for a flipped face.
    pub area_ratio: f64,
    /// (σ1 − 1)·100, at least 0.
    pub stretch_pct: f64,
    /// (1 − σ2)·100, at least 0.
    pub compress_pct: f64,
    /// True when the flat image is reversed or degenerate (σ1σ2 ≤ 0).
    pub flipped: bool,
    /// Direction of largest stretch in the plane.
    pub dir_max_2d: DVec2,
    /// 3D area of the face, mm².
    pub area_3d: f64,
    /// With a material: the face's largest excess over the material's limits along, across or
    /// on the bias (percentage points; negative: the margin) — [`crate::GrainReport`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material_excess_pct: Option<f64>,
}
