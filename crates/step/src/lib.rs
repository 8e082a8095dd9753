//! STEP (ISO 10303-21) models as flatcut geometry: trimmed NURBS and analytic faces read from
//! AP203, AP214 and AP242 files, tessellated crack-free at true size.
//!
//! - [`StepFile`] indexes an exchange file (header, data section) and parses instances on demand;
//!   the lexer is `logos`, the grammar our own (see NOTES.md for why not `ruststep`).
//! - [`Model`] is the boundary representation: shells, faces (a surface and loops of oriented
//!   edges), edges (a curve between two vertices), vertices, all in mm (the file's length unit is
//!   converted once, when read). Surfaces and curves are flatcut-surface types ([`Surface`],
//!   [`Curve`]): B-spline/NURBS patches and curves, and the elementary and swept surfaces in
//!   STEP's own parametrisation.
//! - [`Tessellation`] meshes chosen faces to a chordal tolerance: every edge is sampled once and
//!   shared by the faces it bounds, so the shell welds without cracks; developable faces are
//!   meshed along their rulings so they unfold with zero distortion.
//!
//! Errors name the instance (`#1234 = OFFSET_SURFACE: not supported`) or the line; a face that
//! cannot be used keeps its number and error while the others load.
#![warn(missing_docs)]

pub mod adjacency;
pub mod assembly;
pub mod attrs;
pub mod check;
pub mod edge_use;
pub mod error;
pub mod file;
pub mod geom;
pub mod heal;
pub mod lexer;
pub mod model;
pub mod placement;
pub mod reader;
pub mod sew;
pub mod tess;
pub mod trim;

pub use edge_use::EdgeUse;
pub use error::StepError;
pub use file::StepFile;
pub use geom::{Curve, Surface};
pub use model::{
    BodyInstance, Bound, Edge, EdgeGeometry, Face, FaceGeometry, Model, Shell, Vertex,
};
pub use reader::Units;
pub use tess::{EdgeMesh, FaceMesh, Tessellation, face_area};

/// True for the file extensions of STEP files (`.step`, `.stp`, any case).
pub fn is_step_path(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("step") || e.eq_ignore_ascii_case("stp"))
}
