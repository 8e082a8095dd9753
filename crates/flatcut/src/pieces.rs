//! Pattern pieces from flattened pieces, and the plain row in which a pattern sheet shows them.

use flatcut_geom::DVec2;
use flatcut_pattern::{CornerStyle, Piece, PieceOptions, PlacedPiece, Placement};

use crate::flat::Flat;
use crate::pipeline::{self, PieceContext, PipelineError};

/// How pattern pieces are built beyond what the design says.
#[derive(Clone, Copy, Debug)]
pub struct PieceSettings {
    pub options: PieceOptions,
    /// Seam allowance (mm) where the design gives none.
    pub seam_mm: Option<f64>,
    pub corner: CornerStyle,
}

impl Default for PieceSettings {
    fn default() -> Self {
        Self {
            options: PieceOptions::DEFAULT,
            seam_mm: None,
            corner: CornerStyle::default(),
        }
    }
}

/// Builds the pattern piece of each flattened piece.
pub fn build_pieces(flats: &[Flat], s: &PieceSettings) -> Result<Vec<Piece>, PipelineError> {
    flats
        .iter()
        .map(|f| {
            let ctx = PieceContext {
                def: f.def.as_ref(),
                report: Some(&f.report),
                seam_mm: s.seam_mm,
                size: String::new(),
                corner: s.corner,
            };
            pipeline::piece_from_flat(&f.name, &f.mesh, &ctx, &s.options)
        })
        .collect()
}

/// Gap between pieces laid out in a row (mm).
pub const ROW_GAP_MM: f64 = 10.0;

/// Places pieces left to right with their lowest points on y = 0, one instance each.
pub fn row_layout(pieces: &[Piece]) -> Vec<PlacedPiece<'_>> {
    let mut x = 0.0;
    pieces
        .iter()
        .map(|p| {
            let b = p.bbox();
            let pl = Placement {
                rotation: 0.0,
                mirror: false,
                translation: DVec2::new(x - b.min.x, -b.min.y),
            };
            x += b.width() + ROW_GAP_MM;
            PlacedPiece {
                piece: p,
                instance: 1,
                placement: pl,
            }
        })
        .collect()
}
