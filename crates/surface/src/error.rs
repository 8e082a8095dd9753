//! Construction errors of curves and surfaces.

/// Why a curve or a surface could not be built. Messages name the offending element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// The number of control points does not match the degree / knot vector.
    #[error("wrong number of control points: expected {expected}, got {got}")]
    ControlPointCount { expected: usize, got: usize },
    /// Knots must be non-decreasing; `index` is the first knot that decreases.
    #[error("knot vector is decreasing at index {index} ({prev} > {next})")]
    DecreasingKnots { index: usize, prev: f64, next: f64 },
    /// A knot vector of the wrong length for its degree and control-point count.
    #[error("knot vector has {got} knots, expected {expected}")]
    KnotCount { expected: usize, got: usize },
    /// NURBS weights must be finite and strictly positive.
    #[error("weight {index} is {value}: weights must be finite and > 0")]
    BadWeight { index: usize, value: f64 },
    /// A coordinate is NaN or infinite.
    #[error("{what} {index} has a non-finite coordinate")]
    NonFinite { what: &'static str, index: usize },
    /// A degree of zero or one that is too high for the data.
    #[error("invalid degree {degree}: {reason}")]
    BadDegree { degree: usize, reason: &'static str },
    /// Any other invalid input, with a message.
    #[error("{0}")]
    Invalid(String),
}
