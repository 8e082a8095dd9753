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
    /// The design could not be loaded or built.
    Design(#[from] DesignError),
    #[error("piece '{piece}': {source}")]
    /// A piece could not be flattened.
    Flatten {
        /// The piece's name.
        piece: String,
        /// Why the flattening failed.
        source: FlattenError,
    },
    #[error("piece '{piece}': {source}")]
    /// A piece's distortion report could not be made.
    Report {
        /// The piece's name.
        piece: String,
        /// Why the report failed.
        source: ReportError,
    },
    #[error(transparent)]
    /// A pattern piece could not be built or written.
    Pattern(#[from] PatternError),
    #[error(transparent)]
    /// The pieces could not be nested.
    Nest(#[from] NestError),
    #[error(transparent)]
    /// A sheet's job could not be planned.
    Gcode(#[from] flatcut_gcode::GcodeError),
    #[error(transparent)]
    /// A mesh file could not be read or written.
    Mesh(#[from] flatcut_mesh::MeshIoError),
    /// The piece's material file cannot be read or is invalid.
    #[error("piece '{piece}': {source}")]
    Material {
        /// The piece's name.
        piece: String,
        /// What is wrong with the material.
        source: flatcut_design::material::MaterialError,
    },
    /// A file the piece is read from cannot be read.
    #[error("piece '{piece}': {}: {source}", path.display())]
    Read {
        /// The piece's name.
        piece: String,
        /// The file.
        path: std::path::PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A flat OBJ's dart lines ([`crate::dart_lines`]) are not a dart's sew line.
    #[error("piece '{piece}': {}: {reason}", path.display())]
    DartLines {
        /// The piece's name.
        piece: String,
        /// The flat OBJ.
        path: std::path::PathBuf,
        /// What is wrong with its dart lines.
        reason: String,
    },
    /// A flat OBJ's notch points ([`crate::notch_points`]) are not notches on its outline.
    #[error("piece '{piece}': {}: {reason}", path.display())]
    NotchPoints {
        /// The piece's name.
        piece: String,
        /// The flat OBJ.
        path: std::path::PathBuf,
        /// What is wrong with its notch points.
        reason: String,
    },
    /// Pieces joined by seams cannot be flattened together.
    #[error("{file}: {source}")]
    Assembly {
        /// The design file's path.
        file: String,
        /// Why the assembly failed.
        source: flatcut_flatten::assembly::AssemblyError,
    },
    /// The piece's mesh is not a surface the pattern can be drawn from.
    #[error("piece '{piece}': {source}")]
    Topology {
        /// The piece's name.
        piece: String,
        /// What is wrong with the mesh.
        source: flatcut_mesh::TopologyError,
    },
    /// The piece has no flat map to draw.
    #[error("piece '{piece}': the mesh has no flattening")]
    NotFlattened {
        /// The piece's name.
        piece: String,
    },
    /// The flat piece has no outline.
    #[error("piece '{piece}': the flattened mesh has no boundary")]
    NoBoundary {
        /// The piece's name.
        piece: String,
    },
    /// A notch's vertex is not on the flat outline.
    #[error("piece '{piece}': notch '{notch}' is not on the piece's outline")]
    NotchOffOutline {
        /// The piece's name.
        piece: String,
        /// The notch's name.
        notch: String,
    },
    /// The grain line's two points fall on one point of the flat piece.
    #[error("piece '{piece}': the grain line's two points map to the same place")]
    GrainCollapsed {
        /// The piece's name.
        piece: String,
    },
    /// A line mark strays farther from the surface than `max_offset_pct` of the part's size.
    #[error(
        "piece '{piece}': mark '{mark}': the line leaves the surface (a point is farther than {max_offset_pct:.0} % of the part size from it)"
    )]
    LineOffSurface {
        /// The piece's name.
        piece: String,
        /// The mark's name.
        mark: String,
        /// The largest distance accepted, in percent of the part's size.
        max_offset_pct: f64,
    },
    /// A point mark is not on the surface.
    #[error(
        "piece '{piece}': mark '{mark}': point ({:.2}, {:.2}, {:.2}) is not on the surface",
        point.x, point.y, point.z
    )]
    PointOffSurface {
        /// The piece's name.
        piece: String,
        /// The mark's name.
        mark: String,
        /// The point (mm).
        point: flatcut_geom::DVec3,
    },
    /// A `no_cut` region of the piece cannot be laid on its surface.
    #[error("piece '{piece}': {source}")]
    NoCut {
        /// The piece's name.
        piece: String,
        /// Why the region cannot be laid on the surface.
        source: flatcut_darts::keepout::KeepOutError,
    },
    /// A line mark of the piece cannot be laid on its surface to keep darts clear of it.
    #[error("piece '{piece}': mark '{mark}': {reason}")]
    MarkKeepOut {
        /// The piece's name.
        piece: String,
        /// The mark's name.
        mark: String,
        /// Why the mark cannot be laid on the surface.
        reason: String,
    },
    /// A `seam_hidden_regions` region of the piece cannot be laid on its surface.
    #[error("piece '{piece}': seam_hidden_regions {index}: {source}")]
    SeamHidden {
        /// The piece's name.
        piece: String,
        /// 0-based index of the region.
        index: usize,
        /// Why the region cannot be laid on the surface.
        source: flatcut_darts::keepout::KeepOutError,
    },
    /// The darts failed after their stage ran out of iterations or time: a larger cap may help.
    #[error(
        "piece '{piece}': darts: {source}, after the darts stopped at their cap ({count}; --max-iters, --flatten-time)"
    )]
    DartsStopped {
        /// The piece's name.
        piece: String,
        /// Why the darts failed.
        source: flatcut_darts::DartError,
        /// Boxed: the error stays small for every caller.
        count: Box<flatcut_flatten::StageCount>,
    },
    /// A part of a split piece is named as another piece is.
    #[error(
        "piece '{piece}': a part of a split piece takes the name of another piece; rename that piece"
    )]
    SplitNameClash {
        /// The piece's name.
        piece: String,
    },
    /// The mirror plane asked for (`--symmetry x|y|z`, `--symmetry-plane`) is not one of the
    /// surface.
    #[error("piece '{piece}': no mirrored split: {reason}")]
    Symmetry {
        /// The piece's name.
        piece: String,
        /// How far the surface is from its mirror image, or why it cannot be cut there.
        reason: String,
    },
    /// A bug: the pipeline broke its own invariant.
    #[error("piece '{piece}': internal error: {what}")]
    Internal {
        /// The piece's name.
        piece: String,
        /// The invariant that broke.
        what: &'static str,
    },
    #[error("piece '{piece}': {source}")]
    /// The piece's darts could not be cut.
    Darts {
        /// The piece's name.
        piece: String,
        /// Why the darts failed.
        source: flatcut_darts::DartError,
    },
    #[error(
        "{file}: pieces '{first}' and '{second}' would share the name '{safe}' in ids and file names; rename one of them"
    )]
    /// Two pieces' names become the same once made safe for ids and file names.
    NameClash {
        /// The design file's path.
        file: String,
        /// The first piece's name.
        first: String,
        /// The second piece's name.
        second: String,
        /// The name both would take.
        safe: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Callers tell the causes apart by variant, and each message still names the piece and
    /// what is wrong.
    #[test]
    fn errors_say_their_cause_by_variant_and_name_the_piece() {
        let e = crate::piece_build::flat_boundary("vamp", &flatcut_mesh::TriMesh::default())
            .unwrap_err();
        assert!(matches!(&e, PipelineError::NotFlattened { piece } if piece == "vamp"));
        assert_eq!(e.to_string(), "piece 'vamp': the mesh has no flattening");

        let design = flatcut_design::Design::from_toml_str(
            "[[piece]]\nname = \"cap\"\nmaterial_properties = \"no-such-cloth\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 10\n",
            "d.toml",
        )
        .unwrap();
        let e = crate::material::of_piece(&design.pieces[0], std::path::Path::new("."), None)
            .unwrap_err();
        assert!(matches!(
            &e,
            PipelineError::Material {
                piece,
                source: flatcut_design::material::MaterialError::NotFound { name, .. },
            } if piece == "cap" && name == "no-such-cloth"
        ));
        assert!(
            e.to_string()
                .starts_with("piece 'cap': material 'no-such-cloth': no bundled material"),
            "{e}"
        );
    }
}
