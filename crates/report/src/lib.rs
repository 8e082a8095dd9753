//! The distortion report: how much a flattened piece stretches, where, and whether it stays
//! within the material's limits.
//!
//! [`Report::compute`] measures a flattened [`TriMesh`](flatcut_mesh::TriMesh) (3D positions plus a 2D position per
//! vertex, mm) with Duncan's measures per face (μ1, μ2, δ1, δ2, area ratio, principal
//! directions), aggregates them over the surface area, computes Duncan's global distortion δ0
//! exactly (intrinsic distances in the flat piece against geodesic distances on the surface,
//! [`delta0`]), and checks seam lengths. [`heatmap_svg`], [`render_png`] and
//! [`html_report`] draw it; the PNG is rendered from the very SVG so the two cannot disagree.
//!
//! **Architecture invariant:** the per-face kernel is `flatcut_mesh::face_distortion`, the same the
//! flattener uses, so the report and the optimiser can never disagree on a number.
#![warn(missing_docs)]

pub mod darts;
pub mod delta0;
pub mod draw;
pub mod face;
pub mod grain;
pub mod measure;
pub mod per_face;
pub mod seams;

pub use darts::DartReport;
pub use draw::{Column, DIVERGING_STOPS, heatmap_svg, histogram_svg, html_report, render_png};
pub use face::FaceMeasure;
pub use grain::GrainReport;
pub use measure::{BoundarySegment, Measure, Region, Report, ReportError, ReportOptions, Stats};
pub use per_face::{FaceRow, ReportWithFaces, per_face_rows, with_faces};
pub use seams::{DEFAULT_SEAM_TOLERANCE_MM, MatingSeamReport, NotchOffset, measure_seam};
