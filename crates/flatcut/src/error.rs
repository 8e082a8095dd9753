//! Why a stage of the pipeline failed: one error type for the stages that need more than one
//! crate, every variant naming the piece or file.

use flatcut_design::DesignError;
use flatcut_flatten::FlattenError;
use flatcut_nest::NestError;
use flatcut_pattern::PatternError;
use flatcut_report::ReportError;

/// Why a pipeline stage failed; every variant names the piece or file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    #[error(transparent)]
    Design(#[from] DesignError),
    #[error("piece '{piece}': {source}")]
    Flatten { piece: String, source: FlattenError },
    #[error("piece '{piece}': {source}")]
    Report { piece: String, source: ReportError },
    #[error(transparent)]
    Pattern(#[from] PatternError),
    #[error(transparent)]
    Nest(#[from] NestError),
    #[error(transparent)]
    Gcode(#[from] flatcut_gcode::GcodeError),
    #[error(transparent)]
    Mesh(#[from] flatcut_mesh::MeshIoError),
    #[error("piece '{piece}': {reason}")]
    Piece { piece: String, reason: String },
    #[error("piece '{piece}': {source}")]
    Darts {
        piece: String,
        source: flatcut_darts::DartError,
    },
    #[error(
        "{file}: pieces '{first}' and '{second}' would share the name '{safe}' in ids and file names; rename one of them"
    )]
    NameClash {
        file: String,
        first: String,
        second: String,
        safe: String,
    },
}
