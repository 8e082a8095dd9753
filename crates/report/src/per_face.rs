//! Per-face figures for other tools to plot: each face's index, 3D centroid and Duncan's
//! measures, in the JSON report when asked for (`per_face`).

use flatcut_mesh::TriMesh;
use serde::Serialize;

use crate::Report;

/// One face's figures (the JSON contract of `per_face`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FaceRow {
    /// 0-based index into the mesh's triangles.
    pub face: usize,
    /// Mean of the face's three 3D corners (mm).
    pub centroid_3d: [f64; 3],
    /// The face's area on the surface (mm²).
    pub area_3d_mm2: f64,
    /// Duncan's μ1 and μ2: the squared singular values of the map (σ1², σ2²).
    pub mu1: f64,
    /// Duncan's μ2 = σ2² (see `mu1`).
    pub mu2: f64,
    /// Conformal distortion δ1 = log(μ1/μ2) (dimensionless).
    pub delta1: f64,
    /// Isometric distortion δ2 = (μ1 + 1/μ1 + μ2 + 1/μ2 − 4)/2 (dimensionless).
    pub delta2: f64,
    /// σ1σ2 with its sign: negative for a flipped face.
    pub area_ratio: f64,
    /// Stretch (σ1 − 1)·100 (percent, at least 0).
    pub stretch_pct: f64,
    /// Compression (1 − σ2)·100 (percent, at least 0).
    pub compress_pct: f64,
    /// True when the flat image is reversed or degenerate (σ1σ2 ≤ 0).
    pub flipped: bool,
    /// With a material: the largest excess over its limits along, across or on the bias
    /// (percentage points; negative: the margin).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material_excess_pct: Option<f64>,
}

/// A report with its per-face rows, serialised as the report's keys plus `per_face`.
#[derive(Clone, Debug, Serialize)]
pub struct ReportWithFaces<'a> {
    /// The report; its keys are written at the top level.
    #[serde(flatten)]
    pub report: &'a Report,
    /// One row per face, in triangle order.
    pub per_face: Vec<FaceRow>,
}

/// The per-face rows of `report`, which must have been computed from `mesh`.
pub fn per_face_rows(report: &Report, mesh: &TriMesh) -> Vec<FaceRow> {
    report
        .per_face
        .iter()
        .zip(&mesh.triangles)
        .enumerate()
        .map(|(face, (m, t))| {
            let c = (mesh.positions[t[0] as usize]
                + mesh.positions[t[1] as usize]
                + mesh.positions[t[2] as usize])
                / 3.0;
            FaceRow {
                face,
                centroid_3d: c.to_array(),
                area_3d_mm2: m.area_3d,
                mu1: m.mu1,
                mu2: m.mu2,
                delta1: m.delta1,
                delta2: m.delta2,
                area_ratio: m.area_ratio,
                stretch_pct: m.stretch_pct,
                compress_pct: m.compress_pct,
                flipped: m.flipped,
                material_excess_pct: m.material_excess_pct,
            }
        })
        .collect()
}

/// `report` with its per-face rows.
pub fn with_faces<'a>(report: &'a Report, mesh: &TriMesh) -> ReportWithFaces<'a> {
    ReportWithFaces {
        report,
        per_face: per_face_rows(report, mesh),
    }
}
