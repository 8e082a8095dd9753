//! Nesting drawings: pattern pieces as rigid groups placed on sheets, a roll or hides, each
//! placed copy a drawing of its own. A copy's strokes are named `<id>#<n>` (the n-th placed);
//! the two sides of a mirrored pair `<id>#<n>L` (as drawn) and `<id>#<n>R` (its mirror image),
//! n counting each side's copies, and the piece's name says its side.

use flatcut_geom::DVec2;
use flatcut_nest::{
    GrainDirections, Hide, NestItem, NestOptions, NestProgress, NestResult, Rotations, Stock,
};
use flatcut_pattern::{Drawing, Piece, Placement};

use crate::error::PipelineError;
use flatcut_pattern::poly::signed_area;

/// A rigid group of strokes nested as one item: a pattern piece's drawing in its own frame.
#[derive(Clone, Debug)]
pub struct NestGroup {
    /// The group's name, as the layout names its copies.
    pub name: String,
    /// The strokes in the group's own frame (mm).
    pub drawing: Drawing,
    /// The outline that must not overlap (the cut line), CCW.
    pub outline: Vec<DVec2>,
    /// How many copies to place.
    pub quantity: usize,
    /// True when `quantity` mirror images are placed besides (left and right pieces).
    pub mirrored_pair: bool,
    /// The grain line's direction in the group's frame (radians from +x); `None`: no grain line.
    pub grain_angle: Option<f64>,
    /// The material's grain rule for a piece with a grain line, and its tolerance (degrees).
    pub grain_directions: GrainDirections,
    /// How far a placed copy's grain may turn from the material's (degrees).
    pub grain_tolerance_deg: f64,
    /// The worst hide grade the piece accepts (`None` = any).
    pub quality: Option<u32>,
}

impl NestGroup {
    /// The group of a built piece.
    pub fn from_piece(piece: &Piece, quantity: usize, mirrored_pair: bool) -> Self {
        let item = NestItem::from_piece(piece, quantity, mirrored_pair);
        Self {
            name: piece.name.clone(),
            drawing: piece.to_drawing(1),
            outline: item.outline,
            quantity,
            mirrored_pair,
            grain_angle: item.grain_angle,
            grain_directions: item.grain_directions,
            grain_tolerance_deg: item.grain_tolerance_deg,
            quality: item.quality,
        }
    }

    /// The pieces of a drawing read from an SVG or a DXF: one group per outer cut contour with
    /// the strokes that belong to it, its quantity and grain from the drawing's piece
    /// information where the file carried them.
    pub fn from_drawing(name: &str, d: &Drawing) -> Vec<Self> {
        let mut groups: Vec<Self> = Vec::new();
        let mut by_piece: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (i, s) in d.strokes.iter().enumerate() {
            by_piece
                .entry(s.piece.unwrap_or(u32::MAX))
                .or_default()
                .push(i);
        }
        for (p, idx) in by_piece {
            let Some(outer) = idx
                .iter()
                .map(|&i| &d.strokes[i])
                .find(|s| s.is_outer() && s.closed)
            else {
                continue;
            };
            let mut outline = outer.points.clone();
            if signed_area(&outline) < 0.0 {
                outline.reverse();
            }
            let info = d.piece_info(p);
            let label_name = info.map(|i| i.label.name.clone()).unwrap_or_default();
            let gname = if !label_name.is_empty() {
                label_name
            } else {
                outer
                    .id
                    .strip_suffix("-cut")
                    .unwrap_or(&outer.id)
                    .to_string()
            };
            let gname = if gname.is_empty() {
                format!("{name}-{p}")
            } else {
                gname
            };
            let mut pieces: Vec<_> = info.cloned().into_iter().collect();
            pieces.iter_mut().for_each(|i| i.piece = p);
            groups.push(Self {
                name: gname,
                drawing: Drawing {
                    strokes: idx.iter().map(|&i| d.strokes[i].clone()).collect(),
                    pieces,
                },
                outline,
                quantity: info.map_or(1, |i| i.label.quantity.max(1) as usize),
                mirrored_pair: false,
                grain_angle: info
                    .and_then(|i| i.grain)
                    .map(|(a, b)| (b - a).y.atan2((b - a).x)),
                grain_directions: GrainDirections::default(),
                grain_tolerance_deg: 0.0,
                quality: None,
            });
        }
        groups
    }
}

/// A nested layout: one drawing per sheet or hide (its coordinates, mm) and the nesting figures.
pub struct Layout {
    /// One drawing per sheet or hide, in sheet coordinates (mm).
    pub sheets: Vec<Drawing>,
    /// The nesting's figures: placements, utilisation, copies left unplaced.
    pub result: NestResult,
    /// The roll or sheets (`None` on hides).
    pub stock: Option<Stock>,
}

/// The nesting items of the groups: a piece with a grain line keeps it by the group's rule
/// (which may be `any`), others turn in quarter turns.
fn nest_items(groups: &[NestGroup]) -> Vec<NestItem> {
    groups
        .iter()
        .map(|g| {
            let mut it = NestItem::new(g.name.clone(), g.outline.clone(), g.quantity);
            it.mirrored_pair = g.mirrored_pair;
            it.grain_angle = g.grain_angle;
            it.grain_directions = g.grain_directions;
            it.grain_tolerance_deg = g.grain_tolerance_deg;
            it.quality = g.quality;
            it.rotations = Rotations::Quarter;
            it
        })
        .collect()
}

/// The groups' drawings at their placements, one drawing per sheet or hide.
fn place_groups(groups: &[NestGroup], result: NestResult, stock: Option<Stock>) -> Layout {
    let mut sheets = vec![Drawing::default(); result.sheets.max(1)];
    let mut counters = vec![0u32; groups.len()];
    for p in &result.placed {
        counters[p.item] += 1;
        let g = &groups[p.item];
        let copy = match g.mirrored_pair {
            true => CopyName::Side {
                n: p.copy + 1,
                side: PairSide::of(p.placement.mirror),
            },
            false => CopyName::Plain,
        };
        let d = place(
            &g.drawing,
            &p.placement,
            counters[p.item],
            p.item as u32,
            copy,
        );
        if let Some(sheet) = sheets.get_mut(p.sheet) {
            sheet.strokes.extend(d.strokes);
            sheet.pieces.extend(d.pieces);
        }
    }
    Layout {
        sheets,
        result,
        stock,
    }
}

/// Nests the groups on the stock and places their drawings.
pub fn nest_groups(
    groups: &[NestGroup],
    stock: Stock,
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<Layout, PipelineError> {
    let result = flatcut_nest::nest(&nest_items(groups), stock, opts, progress)?;
    Ok(place_groups(groups, result, Some(stock)))
}

/// Nests the groups on leather hides (in order) and places their drawings, one per hide used.
pub fn nest_groups_on_hides(
    groups: &[NestGroup],
    hides: &[Hide],
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<Layout, PipelineError> {
    let result = flatcut_nest::nest_hides(&nest_items(groups), hides, opts, progress)?;
    Ok(place_groups(groups, result, None))
}

/// The side of a mirrored pair a placed copy is: as drawn (left) or its mirror image (right).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairSide {
    /// As drawn.
    L,
    /// Mirrored.
    R,
}

impl PairSide {
    /// The side of a copy placed mirrored (`true`) or as drawn.
    pub fn of(mirrored: bool) -> Self {
        if mirrored { PairSide::R } else { PairSide::L }
    }

    /// `"L"` or `"R"`.
    pub fn letter(self) -> &'static str {
        match self {
            PairSide::L => "L",
            PairSide::R => "R",
        }
    }
}

/// How a placed copy is named: by its place in the order of placement, or as the n-th copy of
/// its side of a mirrored pair.
#[derive(Clone, Copy, Debug)]
enum CopyName {
    Plain,
    Side { n: usize, side: PairSide },
}

fn place(d: &Drawing, pl: &Placement, instance: u32, item: u32, copy: CopyName) -> Drawing {
    let mut out = d.clone();
    out.apply_placement(pl);
    let suffix = match copy {
        CopyName::Plain => instance.to_string(),
        CopyName::Side { n, side } => format!("{n}{}", side.letter()),
    };
    for s in &mut out.strokes {
        // Unique piece numbers per placed instance so the G-code writer keeps holes before their
        // outer contour per instance.
        s.piece = Some(item * 10_000 + instance);
        s.id = format!("{}#{suffix}", s.id);
    }
    out.pieces.truncate(1);
    for info in &mut out.pieces {
        info.piece = item * 10_000 + instance;
        // each placed copy is one piece cut (its drawn label still says how many a set takes)
        info.label.quantity = 1;
        if let CopyName::Side { side, .. } = copy {
            info.label.name = format!("{} {}", info.label.name, side.letter());
        }
    }
    out
}
