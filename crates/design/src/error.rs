//! Why a design could not be loaded or built, and the context (file, piece) every message names.

use std::path::PathBuf;

use flatcut_mesh::TessError;
use flatcut_mesh::io::MeshIoError;
use flatcut_surface::SurfaceError;

use crate::PieceDef;

/// Why a design could not be loaded or built. Messages name the file, the piece and the problem.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DesignError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}:{line}:{col}: {msg}")]
    Syntax {
        file: String,
        line: usize,
        col: usize,
        msg: String,
    },
    #[error("{file}: the design has no [[piece]] and no [[part]]")]
    NoPieces { file: String },
    #[error("{file}: part {index} '{part}': {msg}")]
    Part {
        file: String,
        index: usize,
        part: String,
        msg: String,
    },
    #[error("{file}: [grading]{}: {msg}", size.as_ref().map(|s| format!(" size '{s}'")).unwrap_or_default())]
    Grading {
        file: String,
        size: Option<String>,
        msg: String,
    },
    #[error("{file}: join {index} '{join}': {msg}")]
    Join {
        file: String,
        index: usize,
        join: String,
        msg: String,
    },
    #[error("{file}: piece {index} '{piece}': {msg}")]
    Piece {
        file: String,
        index: usize,
        piece: String,
        msg: String,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    Surface {
        file: String,
        index: usize,
        piece: String,
        source: SurfaceError,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    Mesh {
        file: String,
        index: usize,
        piece: String,
        source: Box<MeshIoError>,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    Tessellation {
        file: String,
        index: usize,
        piece: String,
        source: TessError,
    },
}

/// Error context: file, piece index and name.
pub(crate) struct Ctx {
    pub(crate) file: String,
    pub(crate) index: usize,
    pub(crate) piece: String,
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
    pub(crate) fn surf(&self, what: &str, e: SurfaceError) -> DesignError {
        self.err(format!("{what}: {e}"))
    }
}
