//! Why a STEP file could not be read, or a part of it could not be used. Messages name the
//! entity instance (`#1234 = OFFSET_SURFACE: not supported`) or the line of a syntax error.

use std::path::PathBuf;

/// An error reading or interpreting a STEP file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StepError {
    #[error("{}: {message}", path.display())]
    /// The file could not be read.
    Io {
        /// The file's path.
        path: PathBuf,
        /// The operating system's reason.
        message: String,
    },
    /// The file is larger than the reader accepts.
    #[error("the file has {bytes} bytes; the limit is {limit}")]
    TooLarge {
        /// The file's size.
        bytes: u64,
        /// The largest size accepted ([`crate::file::MAX_FILE_BYTES`]).
        limit: u64,
    },
    /// Not an ISO 10303-21 file, or a header that breaks the format.
    #[error("line {line}: {message}")]
    Header {
        /// 1-based line of the problem.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A lexing or grammar error in the data section, with the entity being read if known.
    #[error("line {line}{}: {message}", entity.map(|e| format!(" (#{e})")).unwrap_or_default())]
    Syntax {
        /// 1-based line of the problem.
        line: usize,
        /// The instance being read, when known.
        entity: Option<u64>,
        /// What is wrong.
        message: String,
    },
    /// Two instances with the same name.
    #[error("#{id} is defined twice (lines {first_line} and {second_line})")]
    Duplicate {
        /// The instance number defined twice.
        id: u64,
        /// 1-based line of its first definition.
        first_line: usize,
        /// 1-based line of its second definition.
        second_line: usize,
    },
    /// A reference to an instance the file does not define.
    #[error("#{from} refers to #{to}, which the file does not define")]
    Dangling {
        /// The instance holding the reference.
        from: u64,
        /// The instance number it refers to.
        to: u64,
    },
    /// An instance that (indirectly) refers to itself where a tree is required.
    #[error("#{id} refers to itself through #{through} (a cyclic reference)")]
    Cycle {
        /// The instance that refers to itself.
        id: u64,
        /// An instance on the cycle it refers through.
        through: u64,
    },
    /// An instance that cannot be used: wrong attributes, an unsupported type, bad values.
    #[error("#{id} = {name}: {message}")]
    Entity {
        /// The instance's number.
        id: u64,
        /// Its entity type name, e.g. `OFFSET_SURFACE`.
        name: String,
        /// What is wrong with it.
        message: String,
    },
    /// The file holds no shell of faces.
    #[error(
        "the file holds no shell (no MANIFOLD_SOLID_BREP, SHELL_BASED_SURFACE_MODEL, CLOSED_SHELL or OPEN_SHELL)"
    )]
    NoShells,
    /// A face index beyond the model's faces.
    #[error("face {index} does not exist: the model has {count} faces (0 to {})", count.saturating_sub(1))]
    NoSuchFace {
        /// The face asked for (0-based).
        index: usize,
        /// The model's number of faces.
        count: usize,
    },
    /// A face could be read but not tessellated.
    #[error("face {index} (#{entity}): {message}")]
    Face {
        /// The face's 0-based index in the model.
        index: usize,
        /// The face's instance number (`#id`).
        entity: u64,
        /// Why it could not be tessellated.
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
