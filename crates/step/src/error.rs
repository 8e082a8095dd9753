//! Why a STEP file could not be read, or a part of it could not be used. Messages name the
//! entity instance (`#1234 = OFFSET_SURFACE: not supported`) or the line of a syntax error.

use std::path::PathBuf;

/// An error reading or interpreting a STEP file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StepError {
    #[error("{}: {message}", path.display())]
    Io { path: PathBuf, message: String },
    /// The file is larger than the reader accepts.
    #[error("the file has {bytes} bytes; the limit is {limit}")]
    TooLarge { bytes: u64, limit: u64 },
    /// Not an ISO 10303-21 file, or a header that breaks the format.
    #[error("line {line}: {message}")]
    Header { line: usize, message: String },
    /// A lexing or grammar error in the data section, with the entity being read if known.
    #[error("line {line}{}: {message}", entity.map(|e| format!(" (#{e})")).unwrap_or_default())]
    Syntax {
        line: usize,
        entity: Option<u64>,
        message: String,
    },
    /// Two instances with the same name.
    #[error("#{id} is defined twice (lines {first_line} and {second_line})")]
    Duplicate {
        id: u64,
        first_line: usize,
        second_line: usize,
    },
    /// A reference to an instance the file does not define.
    #[error("#{from} refers to #{to}, which the file does not define")]
    Dangling { from: u64, to: u64 },
    /// An instance that (indirectly) refers to itself where a tree is required.
    #[error("#{id} refers to itself through #{through} (a cyclic reference)")]
    Cycle { id: u64, through: u64 },
    /// An instance that cannot be used: wrong attributes, an unsupported type, bad values.
    #[error("#{id} = {name}: {message}")]
    Entity {
        id: u64,
        name: String,
        message: String,
    },
    /// The file holds no shell of faces.
    #[error(
        "the file holds no shell (no MANIFOLD_SOLID_BREP, SHELL_BASED_SURFACE_MODEL, CLOSED_SHELL or OPEN_SHELL)"
    )]
    NoShells,
    /// A face index beyond the model's faces.
    #[error("face {index} does not exist: the model has {count} faces (0 to {})", count.saturating_sub(1))]
    NoSuchFace { index: usize, count: usize },
    /// A face could be read but not tessellated.
    #[error("face {index} (#{entity}): {message}")]
    Face {
        index: usize,
        entity: u64,
        message: String,
    },
}

impl StepError {
    /// An [`StepError::Entity`] error.
    pub fn entity(id: u64, name: &str, message: impl Into<String>) -> Self {
        StepError::Entity {
            id,
            name: name.to_string(),
            message: message.into(),
        }
    }
}
