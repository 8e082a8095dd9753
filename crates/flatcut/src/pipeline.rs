//! The pipeline's stages that need more than one crate, one module each, named here in the
//! order a project runs them ([`crate::run`] runs them all):
//!
//! 1. [`crate::flattening`]: a design (or a mesh or STEP model) to flattened pieces
//!    ([`FlatPiece`]), with their material ([`crate::material`]), darts ([`crate::darting`]),
//!    splits ([`crate::splitting`]) and report;
//! 2. [`crate::piece_build`]: a flattened piece to a 2D pattern piece;
//! 3. [`crate::nesting`]: pattern pieces placed on sheets, a roll or hides.
//!
//! Their one error type is [`PipelineError`] ([`crate::error`]).

pub use crate::error::PipelineError;
pub use crate::flat_piece::{FlatNotch, FlatPiece};
pub use crate::flattening::{
    FlatDesign, check_unique_names, flatten_design, flatten_loaded, report_piece,
};
pub use crate::nesting::{Layout, NestGroup, nest_groups, nest_groups_on_hides};
pub use crate::piece_build::{PieceContext, flat_boundary, piece_from_flat};
