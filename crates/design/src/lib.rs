//! The design file: the TOML (or JSON) a pattern maker writes by hand to describe pieces as
//! parametric surfaces or meshes, with seams, marks, grain and material per piece.
//!
//! ```toml
//! units = "mm"                 # "mm" (default), "cm", "m", "in": converted to mm at load time
//! [[piece]]
//! name = "saddle"
//! quantity = 2
//! [piece.surface]
//! type = "bezier"
//! degree = [1, 1]
//! points = [[0, 0, 0], [0, 100, 0], [100, 0, 0], [100, 100, 20]]   # v varying fastest
//! ```
//!
//! Surface types: `bezier`, `hermite`, `bspline`, `nurbs`, `coons`, `gordon`, `ruled`,
//! `developable`, `sphere`, `cylinder`, `cone`, `torus`, `triangular-bezier`, `patches` (a list of
//! surfaces forming one piece), `mesh` (`file = "x.obj"`, relative to the design file) and `step`
//! (faces of a STEP model, expanded into pieces when the design is loaded). Curves
//! (for coons, gordon, ruled, developable): `bezier`, `bspline`, `nurbs`, `polyline`, `hermite`,
//! `arc`, `spline` (interpolating cubic through points).
//!
//! Unknown keys are errors (`deny_unknown_fields`) so a typo never silently drops data. Every
//! error names the file, the piece (index and name) and what is wrong; parse errors carry the
//! parser's line and column.
//!
//! **Architecture invariant:** this crate only translates the file into surfaces and meshes; all
//! geometry lives in flatcut-surface and flatcut-mesh.
#![warn(missing_docs)]

mod assemble;
mod build;
mod check;
mod edge;
mod error;
mod grading;
mod join;
mod load;
pub mod material;
mod part;
mod schema;
mod step;
mod step_seams;
mod units;

pub use assemble::{AssembledPiece, Assembly, PartRegions};
pub use build::PieceGeometry;
pub use edge::{EdgeDef, EdgeKind, OutlineEdge};
pub use error::DesignError;
pub use grading::{GradingDef, SizeDef, SizedDesign};
pub use load::Design;
pub use part::{JoinDef, JoinEdgeDef, LineDef, PartDef, PartPieceDef};
pub use schema::{
    Blend, CurveDef, DartPress, DartsDef, GrainDef, MarkDef, MarkKind, P3, PieceDef, PieceSize,
    SeamDef, SurfaceDef, Units,
};
pub use step::{StepFaces, StepGroup, StepModel, StepPiece};
pub use units::Axes;

#[cfg(test)]
mod edge_tests;
#[cfg(test)]
mod part_tests;
#[cfg(test)]
mod tests;
