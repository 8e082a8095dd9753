//! 2D pattern pieces: outlines fitted to lines, arcs and cubics, seam allowance, notches, grain
//! lines, labels; SVG and DXF export; SVG and DXF import; the [`Drawing`] that the nester and the G-code
//! writer consume.
//!
//! **Architecture invariant:** this crate is 2D only. It cannot name a surface or a mesh type
//! (the crate graph enforces it); the facade turns a flattened boundary into a piece.
#![warn(missing_docs)]

pub mod colours;
pub mod corner;
pub mod drawing;
pub mod dxf;
pub mod dxf_read;
pub mod error;
pub mod fit;
pub mod graded;
pub mod io;
pub mod label_info;
pub mod piece;
pub mod placement;
pub mod plain_pieces;
pub mod poly;
pub mod room;
pub mod seam;
pub mod svg;

pub use colours::{ColourJob, ColourTable};
pub use corner::CornerStyle;
pub use drawing::{Drawing, Layer, PieceInfo, Stroke, StrokeKind};
pub use error::PatternError;
pub use fit::PathSeg;
pub use io::write_atomic;
pub use piece::{
    EdgeAllowance, EdgeKind, LabelInfo, MIN_LABEL_HEIGHT, Mark, MarkKind, NotchStyle, Piece,
    PieceEdge, PieceInput, PieceOptions, PlacedPiece, Placement, safe_name,
};
