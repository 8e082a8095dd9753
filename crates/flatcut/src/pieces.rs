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

/// Builds the pattern pieces of the flattened pieces: one per piece, and for a piece cut in
/// pairs (`pairs = N`) two — as drawn and mirrored, their labels saying which (`QUARTER L`,
/// `QUARTER R`, or the design's `pair_labels`). Each piece's label says how many to cut
/// (`label.quantity`).
pub fn build_pieces(flats: &[Flat], s: &PieceSettings) -> Result<Vec<Piece>, PipelineError> {
    let mut out = Vec::with_capacity(flats.len());
    for f in flats {
        let Some(def) = f.def.as_ref().filter(|_| f.mirrored > 0) else {
            out.push(build_one(f, &f.name, s)?);
            continue;
        };
        let [drawn, mirrored] = def.pair_labels();
        out.push(build_one(f, &format!("{} {drawn}", f.name), s)?);
        out.push(build_one(&mirror(f), &format!("{} {mirrored}", f.name), s)?);
    }
    Ok(out)
}

fn build_one(f: &Flat, name: &str, s: &PieceSettings) -> Result<Piece, PipelineError> {
    let ctx = PieceContext {
        def: f.def.as_ref(),
        report: Some(&f.report),
        darts: &f.darts,
        seam_mm: s.seam_mm,
        size: String::new(),
        corner: s.corner,
        notches: &f.notches,
        grain_dir: f.grain_dir.or(f.grain.as_ref().map(|g| g.pattern_dir)),
    };
    pipeline::piece_from_flat(name, &f.mesh, &ctx, &s.options)
}

/// The mirror image of a flattened piece (x → −x in the plane), cut `mirrored` times: the other
/// side of a pair. Marks, lines, darts and the grain are carried through the mirrored map.
pub fn mirror(f: &Flat) -> Flat {
    let mut g = f.clone();
    if let Some(flat) = &mut g.mesh.flat {
        flat.iter_mut().for_each(|q| q.x = -q.x);
    }
    for d in &mut g.darts {
        d.drill_2d.x = -d.drill_2d.x;
    }
    if let Some(grain) = &mut g.grain {
        grain.pattern_dir.x = -grain.pattern_dir.x;
    }
    if let Some(d) = &mut g.grain_dir {
        d.x = -d.x;
    }
    if let Some(def) = &mut g.def {
        def.quantity = f.mirrored;
        def.mirrored = 0;
    }
    g.quantity = f.mirrored;
    g.mirrored = 0;
    g
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
