//! The figures `inspect` reports for one piece, whatever it is made of (patches, a mesh, STEP
//! faces): the summary's keys, its ranges, the developability thresholds, and the fundamental
//! forms of a surface at a point, poles included.

use flatcut_surface::diffgeom::FundamentalForms;
use flatcut_surface::{DomainKind, ParamSurface};
use serde::Serialize;

/// A parametric patch is called developable when `max |K| · diag²` over its sample grid stays
/// below this (dimensionless; a hemisphere is about 10, a cylinder 0 up to round-off).
pub const DEVELOPABLE_SCALED_K: f64 = 1e-6;
/// A mesh is called developable when no interior vertex has an angle defect above this (rad).
pub const DEVELOPABLE_ANGLE_DEFECT: f64 = 1e-6;
/// A sample is singular (a pole, a collapsed side) when |r_u × r_v| is below this fraction of
/// max(|r_u|, |r_v|)². The scale is the larger tangent, not the product of both: at a pole one
/// tangent is itself rounding noise, so a ratio to |r_u||r_v| (the angle between them) says
/// nothing there. At the teapot's lid top and bottom centre the ratio is ~1e-17; at a regular
/// point of a sane patch it is ≳ 1e-3.
const SINGULAR_REL: f64 = 1e-8;
/// Parameter step (fraction of the domain's span) by which a singular sample moves toward the
/// domain's centre to evaluate the curvature there as its limit: 0/0 at the pole itself. The
/// point moves ~1e-4 of the patch size (6e-3 mm on the teapot), so the curvature changes by
/// that times its gradient, while r_u × r_v is already ~1e-4 relative, far above round-off.
const POLE_NUDGE: f64 = 1e-4;
/// A range with its mean.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Range3 {
    /// The smallest value.
    pub min: f64,
    /// The largest value.
    pub max: f64,
    /// The mean value.
    pub mean: f64,
    /// The 1st and 99th percentiles of the samples ([`p1_p99`]): the range a few outlying
    /// samples (a pole, a spike in a scanned mesh) do not set. Absent where the samples are not
    /// kept (a STEP model's faces).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p1_p99: Option<[f64; 2]>,
}

/// A range.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Range2 {
    /// The smallest value.
    pub min: f64,
    /// The largest value.
    pub max: f64,
    /// The 1st and 99th percentiles of the samples, as in [`Range3::p1_p99`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p1_p99: Option<[f64; 2]>,
}

/// The 1st and 99th percentiles of `samples` (non-finite ones left out), interpolated linearly
/// between the order statistics at rank p·(n − 1) (numpy's default `percentile`); `None`
/// without a finite sample.
pub fn p1_p99(samples: &[f64]) -> Option<[f64; 2]> {
    let mut v: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let at = |p: f64| {
        let r = p * (v.len() - 1) as f64;
        let (lo, hi) = (r.floor() as usize, r.ceil() as usize);
        v[lo] + (r - lo as f64) * (v[hi] - v[lo])
    };
    Some([at(0.01), at(0.99)])
}

/// ` (1st–99th percentile a .. b)` for the text report, empty without percentiles.
pub fn percentiles_text(p: Option<[f64; 2]>) -> String {
    p.map(|[a, b]| format!(" (1st–99th percentile {a:.4e} .. {b:.4e})"))
        .unwrap_or_default()
}

/// One piece as `inspect --json` reports it (keys are a stable contract).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PieceSummary {
    /// The piece's name.
    pub name: String,
    /// What the piece is made of: `patches`, `mesh` or `step`.
    pub kind: &'static str,
    /// How many to cut.
    pub quantity: u32,
    /// Surface area (mm²).
    pub area_mm2: f64,
    /// Bounding box: lowest corner, then highest (mm).
    pub bbox_mm: [[f64; 3]; 2],
    /// Gaussian curvature in 1/mm² (mean: area-weighted).
    pub gaussian_curvature: Range3,
    /// Mean curvature in 1/mm (sign follows the normal r_u × r_v).
    pub mean_curvature: Range2,
    /// True when the surface flattens without distortion within the developability threshold.
    pub developable: bool,
    /// `max |K| · diag²` (patches) or the largest interior angle defect in rad (meshes).
    pub developability_measure: f64,
    /// Number of surface patches (0 for a mesh).
    pub patches: usize,
    /// Vertices of the tessellation (or of the mesh).
    pub vertices: usize,
    /// Triangles of the tessellation (or of the mesh).
    pub triangles: usize,
    /// Boundary loops; `None` when the mesh's topology is invalid.
    pub boundary_loops: Option<usize>,
    /// Total length of the boundary (mm).
    pub boundary_length_mm: f64,
}

pub(crate) fn singular(d: &flatcut_surface::SurfaceDerivs) -> bool {
    let scale = d.su.length_squared().max(d.sv.length_squared());
    let area = d.su.cross(d.sv).length();
    // NaN (a non-finite derivative) counts as singular too.
    area.is_nan() || area <= SINGULAR_REL * scale
}

/// The fundamental forms at (u, v); at a singular point (a pole) their limit, evaluated a
/// `POLE_NUDGE` step toward the domain's centre. `None` where the surface is singular on a
/// whole neighbourhood (a degenerate patch).
pub fn forms_at(s: &dyn ParamSurface, u: f64, v: f64) -> Option<FundamentalForms> {
    let dd = s.deriv2(u, v);
    if !singular(&dd) {
        return FundamentalForms::from_derivs(&dd);
    }
    let d = s.domain();
    let (uc, vc) = if s.domain_kind() == DomainKind::Triangle {
        (1.0 / 3.0, 1.0 / 3.0)
    } else {
        (0.5 * (d.u.0 + d.u.1), 0.5 * (d.v.0 + d.v.1))
    };
    let step = |x: f64, c: f64, span: f64| x + (c - x).signum() * POLE_NUDGE * span;
    let dd = s.deriv2(step(u, uc, d.u.1 - d.u.0), step(v, vc, d.v.1 - d.v.0));
    if singular(&dd) {
        None
    } else {
        FundamentalForms::from_derivs(&dd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate_between_order_statistics_as_numpy_does() {
        // numpy.percentile(range(101), [1, 99]) == [1, 99]; of range(11): [0.1, 9.9].
        let hundred: Vec<f64> = (0..=100).rev().map(f64::from).collect();
        assert_eq!(p1_p99(&hundred), Some([1.0, 99.0]));
        let ten: Vec<f64> = (0..=10).map(f64::from).collect();
        let [a, b] = p1_p99(&ten).unwrap();
        assert!(
            (a - 0.1).abs() < 1e-12 && (b - 9.9).abs() < 1e-12,
            "{a} {b}"
        );
        // One wild sample among 1000 moves the maximum, not the 99th percentile.
        let mut spiky = vec![1.0; 999];
        spiky.push(1e9);
        assert_eq!(p1_p99(&spiky), Some([1.0, 1.0]));
        assert_eq!(p1_p99(&[f64::NAN]), None);
        assert_eq!(p1_p99(&[2.0, f64::INFINITY]), Some([2.0, 2.0]));
    }
}
