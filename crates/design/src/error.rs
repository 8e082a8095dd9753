//! Why a design could not be loaded or built, and the context (file, piece) every message names.

use std::path::PathBuf;

use flatcut_mesh::TessError;
use flatcut_mesh::io::MeshIoError;
use flatcut_step::StepError;
use flatcut_surface::SurfaceError;

use crate::PieceDef;

/// Why a design could not be loaded or built. Messages name the file, the piece and the problem.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DesignError {
    #[error("{}: {source}", path.display())]
    /// The design file (or a file it refers to) could not be read.
    Io {
        /// The file that could not be read.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    #[error("{file}:{line}:{col}: {msg}")]
    /// The file is not valid TOML or JSON, or does not fit the schema.
    Syntax {
        /// The design file's path as given.
        file: String,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        col: usize,
        /// The parser's description of the problem.
        msg: String,
    },
    #[error("{file}: the design has no [[piece]] and no [[part]]")]
    /// The design defines nothing to cut.
    NoPieces {
        /// The design file's path as given.
        file: String,
    },
    #[error("{file}: part {index} '{part}': {msg}")]
    /// A `[[part]]` that cannot be built: its style lines, pieces or edges are wrong.
    Part {
        /// The design file's path as given.
        file: String,
        /// The part's 0-based position among the file's parts.
        index: usize,
        /// The part's name.
        part: String,
        /// What is wrong with the part.
        msg: String,
    },
    #[error("{file}: [grading]{}: {msg}", size.as_ref().map(|s| format!(" size '{s}'")).unwrap_or_default())]
    /// The `[grading]` table, or one of its sizes, is wrong.
    Grading {
        /// The design file's path as given.
        file: String,
        /// The size at fault; `None` when the problem is in the table itself.
        size: Option<String>,
        /// What is wrong.
        msg: String,
    },
    #[error("{file}: join {index} '{join}': {msg}")]
    /// A `[[join]]` whose edges cannot be found or do not match.
    Join {
        /// The design file's path as given.
        file: String,
        /// The join's 0-based position among the file's joins.
        index: usize,
        /// The join's name.
        join: String,
        /// What is wrong with the join.
        msg: String,
    },
    #[error("{file}: piece {index} '{piece}': {msg}")]
    /// A piece whose keys are wrong or inconsistent.
    Piece {
        /// The design file's path as given.
        file: String,
        /// The piece's 0-based position among the file's pieces.
        index: usize,
        /// The piece's name.
        piece: String,
        /// What is wrong with the piece.
        msg: String,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    /// A piece's surface could not be built from its definition.
    Surface {
        /// The design file's path as given.
        file: String,
        /// The piece's 0-based position among the file's pieces.
        index: usize,
        /// The piece's name.
        piece: String,
        /// Why the surface could not be built.
        source: SurfaceError,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    /// A piece's mesh file could not be read.
    Mesh {
        /// The design file's path as given.
        file: String,
        /// The piece's 0-based position among the file's pieces.
        index: usize,
        /// The piece's name.
        piece: String,
        /// Why the mesh file could not be read (it names the mesh file).
        source: Box<MeshIoError>,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    /// A piece's surface could not be tessellated into a mesh.
    Tessellation {
        /// The design file's path as given.
        file: String,
        /// The piece's 0-based position among the file's pieces.
        index: usize,
        /// The piece's name.
        piece: String,
        /// Why the tessellation failed.
        source: TessError,
    },
    /// A piece's STEP model could not be read. When the STEP file is the design itself (a
    /// `.step` loaded as a design), the message names it once, without the piece it stands for.
    #[error("{}", step_read_message(file, *index, piece, path, source))]
    StepRead {
        /// The design file's path as given (the STEP file's, for a `.step` loaded as a design).
        file: String,
        /// The piece's 0-based position among the file's pieces.
        index: usize,
        /// The piece's name.
        piece: String,
        /// The STEP file as read (joined to the design's folder).
        path: PathBuf,
        /// Why it could not be read (the line or the entity); boxed, so the error stays small.
        source: Box<StepError>,
    },
}

/// Error context: file, piece index and name.
pub(crate) struct Ctx {
    pub(crate) file: String,
    pub(crate) index: usize,
    pub(crate) piece: String,
}

/// The text of [`DesignError::StepRead`]: each file named once.
fn step_read_message(
    file: &str,
    index: usize,
    piece: &str,
    path: &std::path::Path,
    source: &StepError,
) -> String {
    // A read error names the STEP file itself; any other is about its content.
    let names_path = matches!(source, StepError::Io { .. });
    let step = if names_path {
        source.to_string()
    } else {
        format!("{}: {source}", path.display())
    };
    if std::path::Path::new(file) == path {
        step
    } else {
        format!("{file}: piece {index} '{piece}': {step}")
    }
}

impl Ctx {
    pub(crate) fn of(p: &PieceDef) -> Ctx {
        Ctx {
            file: p.file.clone(),
            index: p.index,
            piece: p.name.clone(),
        }
    }
    pub(crate) fn err(&self, msg: String) -> DesignError {
        DesignError::Piece {
            file: self.file.clone(),
            index: self.index,
            piece: self.piece.clone(),
            msg,
        }
    }
    pub(crate) fn step_read(&self, path: &std::path::Path, source: StepError) -> DesignError {
        DesignError::StepRead {
            file: self.file.clone(),
            index: self.index,
            piece: self.piece.clone(),
            path: path.to_path_buf(),
            source: Box::new(source),
        }
    }
    pub(crate) fn surf(&self, what: &str, e: SurfaceError) -> DesignError {
        self.err(format!("{what}: {e}"))
    }
}
