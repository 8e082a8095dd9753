//! Pattern pieces from flattened pieces, and the plain row in which a pattern sheet shows them.
//!
//! Short label codes are unique in a set; a graded design's pieces make one row per size, and
//! the graded sets.

use flatcut_geom::DVec2;
use flatcut_pattern::{CornerStyle, Piece, PieceOptions, PlacedPiece, Placement};

use crate::flat::Flat;
use crate::pipeline::{self, PieceContext, PipelineError};

/// How pattern pieces are built beyond what the design says.
#[derive(Clone, Copy, Debug)]
pub struct PieceSettings {
    /// The options every piece is built with (tolerances, notch style, label height).
    pub options: PieceOptions,
    /// Seam allowance (mm) where the design gives none.
    pub seam_mm: Option<f64>,
    /// How the allowance turns at corners.
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
/// (`label.quantity`) and, where the piece is too small for a readable label, its short code,
/// unique in the set ([`codes`]).
pub fn build_pieces(flats: &[Flat], s: &PieceSettings) -> Result<Vec<Piece>, PipelineError> {
    let mut jobs: Vec<(Flat, String)> = Vec::with_capacity(flats.len());
    for f in flats {
        match f.def.as_ref().filter(|_| f.mirrored > 0) {
            Some(def) => {
                let [drawn, mirrored] = def.pair_labels();
                jobs.push((f.clone(), format!("{} {drawn}", f.name)));
                jobs.push((mirror(f), format!("{} {mirrored}", f.name)));
            }
            None => jobs.push((f.clone(), f.name.clone())),
        }
    }
    let names: Vec<&str> = jobs.iter().map(|(_, n)| n.as_str()).collect();
    let codes = codes(&names);
    jobs.iter()
        .zip(codes)
        .map(|((f, name), code)| build_one(f, name, code, s))
        .collect()
}

/// Short codes for the pieces' labels: the initials of each name (numbers and one-letter words
/// kept whole: `toe cap 42 L` → `TC42L`), a number added (`-2`, `-3`, …) where two would be
/// the same.
pub fn codes(names: &[&str]) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for n in names {
        let base = flatcut_pattern::piece::short_code(n);
        let mut code = base.clone();
        let mut k = 2;
        while out.contains(&code) {
            code = format!("{base}-{k}");
            k += 1;
        }
        out.push(code);
    }
    out
}

fn build_one(
    f: &Flat,
    name: &str,
    code: String,
    s: &PieceSettings,
) -> Result<Piece, PipelineError> {
    let ctx = PieceContext {
        def: f.def.as_ref(),
        report: Some(&f.report),
        darts: &f.darts,
        seam_mm: s.seam_mm,
        size: String::new(),
        corner: s.corner,
        notches: &f.notches,
        grain_dir: f.grain_dir.or(f.grain.as_ref().map(|g| g.pattern_dir)),
        code: Some(code),
    };
    pipeline::piece_from_flat(name, &f.mesh, &ctx, &s.options)
}

/// The graded sets of [`build_pieces`]'s pieces (built from `flats`): for every piece of a
/// graded design, its name in the design and its as-drawn pattern piece in each size, in the
/// grading's order (the mirrored side of a pair is its mirror image). Empty for a design
/// without grading.
pub fn graded_sets<'a>(
    flats: &[Flat],
    pieces: &'a [Piece],
) -> Vec<(String, Vec<(String, &'a Piece)>)> {
    let mut sets: Vec<(String, Vec<(String, &'a Piece)>)> = Vec::new();
    let mut at = 0;
    for f in flats {
        let drawn = pieces.get(at);
        at += if f.mirrored > 0 && f.def.is_some() {
            2
        } else {
            1
        };
        let (Some(size), Some(p)) = (f.def.as_ref().and_then(|d| d.size.as_ref()), drawn) else {
            continue;
        };
        match sets.iter_mut().find(|(name, _)| *name == size.piece) {
            Some((_, v)) => v.push((size.size.clone(), p)),
            None => sets.push((size.piece.clone(), vec![(size.size.clone(), p)])),
        }
    }
    sets
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

/// Gap between pieces laid out in a row, and between rows (mm).
pub const ROW_GAP_MM: f64 = 10.0;

/// Places pieces left to right with their lowest points on y = 0, one instance each; the sizes
/// of a graded set each get their own row, the first size's on top.
pub fn row_layout(pieces: &[Piece]) -> Vec<PlacedPiece<'_>> {
    let mut sizes: Vec<&str> = Vec::new();
    for p in pieces {
        if !sizes.contains(&p.label.size.as_str()) {
            sizes.push(&p.label.size);
        }
    }
    let mut rows: Vec<Vec<PlacedPiece<'_>>> = Vec::with_capacity(sizes.len());
    let mut heights = Vec::with_capacity(sizes.len());
    for size in &sizes {
        let mut x = 0.0;
        let mut height = 0.0f64;
        let row = pieces
            .iter()
            .filter(|p| p.label.size == *size)
            .map(|p| {
                let b = p.bbox();
                let pl = Placement {
                    rotation: 0.0,
                    mirror: false,
                    translation: DVec2::new(x - b.min.x, -b.min.y),
                };
                x += b.width() + ROW_GAP_MM;
                height = height.max(b.height());
                PlacedPiece {
                    piece: p,
                    instance: 1,
                    placement: pl,
                }
            })
            .collect();
        rows.push(row);
        heights.push(height);
    }
    // stacked downwards: the first row at y = 0, each next one below it
    let mut y = 0.0;
    let mut out = Vec::with_capacity(pieces.len());
    for (k, row) in rows.into_iter().enumerate() {
        if k > 0 {
            y -= heights[k] + ROW_GAP_MM;
        }
        out.extend(row.into_iter().map(|mut pp| {
            pp.placement.translation.y += y;
            pp
        }));
    }
    out
}
