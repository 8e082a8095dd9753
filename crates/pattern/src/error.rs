//! Typed errors of the pattern crate; every message names the piece and what is wrong.

use thiserror::Error;

/// What can go wrong while building, writing or reading pattern pieces.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PatternError {
    /// The outline has too few points, repeated points only, or zero area.
    #[error("piece `{piece}`: degenerate outline ({reason})")]
    DegenerateOutline { piece: String, reason: String },
    /// A coordinate or width is NaN or infinite.
    #[error("piece `{piece}`: non-finite value in {what}")]
    NonFinite { piece: String, what: String },
    /// Two edges of the outline cross.
    #[error(
        "piece `{piece}`: outline is self-intersecting (edge {edge_a} crosses edge {edge_b} near ({x:.3}, {y:.3}) mm)"
    )]
    SelfIntersecting {
        piece: String,
        edge_a: usize,
        edge_b: usize,
        x: f64,
        y: f64,
    },
    /// A seam width is negative, or so large that the allowance closes over the piece (it would
    /// trap material in a hole or swallow a notch).
    #[error("piece `{piece}`: seam allowance too large: {reason}")]
    AllowanceTooLarge { piece: String, reason: String },
    /// Seam widths, marks or options that do not fit the outline.
    #[error("piece `{piece}`: invalid input: {reason}")]
    InvalidInput { piece: String, reason: String },
    /// The offset/boolean engine failed (panicked or returned an invalid result).
    #[error("piece `{piece}`: seam-allowance offset failed: {reason}")]
    OffsetFailed { piece: String, reason: String },
    /// An SVG file could not be parsed.
    #[error("SVG `{source_name}`: {reason}")]
    Svg { source_name: String, reason: String },
    /// A DXF file could not be parsed.
    #[error("DXF line {line}: {reason}")]
    Dxf { line: usize, reason: String },
    /// Writing a file failed; nothing was left half-written.
    #[error("writing `{path}`: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
}
