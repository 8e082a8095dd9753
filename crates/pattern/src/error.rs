//! Typed errors of the pattern crate; every message names the piece and what is wrong.

use thiserror::Error;

/// What can go wrong while building, writing or reading pattern pieces.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PatternError {
    /// The outline has too few points, repeated points only, or zero area.
    #[error("piece `{piece}`: degenerate outline ({reason})")]
    DegenerateOutline {
        /// The piece's name.
        piece: String,
        /// What makes the outline degenerate.
        reason: String,
    },
    /// A coordinate or width is NaN or infinite.
    #[error("piece `{piece}`: non-finite value in {what}")]
    NonFinite {
        /// The piece's name.
        piece: String,
        /// Which input holds the value, e.g. "outline".
        what: String,
    },
    /// Two edges of the outline cross.
    #[error(
        "piece `{piece}`: outline is self-intersecting (edge {edge_a} crosses edge {edge_b} near ({x:.3}, {y:.3}) mm)"
    )]
    SelfIntersecting {
        /// The piece's name.
        piece: String,
        /// 0-based index of the first edge (from outline vertex `edge_a`).
        edge_a: usize,
        /// 0-based index of the edge it crosses.
        edge_b: usize,
        /// x of the crossing in the piece's flat frame (mm).
        x: f64,
        /// y of the crossing in the piece's flat frame (mm).
        y: f64,
    },
    /// A seam width is negative, or so large that the allowance closes over the piece (it would
    /// trap material in a hole or swallow a notch).
    #[error("piece `{piece}`: seam allowance too large: {reason}")]
    AllowanceTooLarge {
        /// The piece's name.
        piece: String,
        /// Which width or feature is at fault, and why.
        reason: String,
    },
    /// Seam widths, marks or options that do not fit the outline.
    #[error("piece `{piece}`: invalid input: {reason}")]
    InvalidInput {
        /// The piece's name.
        piece: String,
        /// Which input does not fit, and why.
        reason: String,
    },
    /// The offset/boolean engine failed (panicked or returned an invalid result).
    #[error("piece `{piece}`: seam-allowance offset failed: {reason}")]
    OffsetFailed {
        /// The piece's name.
        piece: String,
        /// What the engine reported.
        reason: String,
    },
    /// An SVG file could not be parsed.
    #[error("SVG `{source_name}`: {reason}")]
    Svg {
        /// The file's name, or what the text came from.
        source_name: String,
        /// What is wrong.
        reason: String,
    },
    /// A DXF file could not be parsed.
    #[error("DXF line {line}: {reason}")]
    Dxf {
        /// 1-based line of the problem.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// Writing a file failed; nothing was left half-written.
    #[error("writing `{path}`: {source}")]
    Io {
        /// The file being written.
        path: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
}
