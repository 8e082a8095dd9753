//! A flat drawing in millimetres: polylines on layers, grouped by piece.
//!
//! This is the hand-over format from patterns (and imported SVGs and DXFs) to the G-code and
//! HP-GL writers and the nester: every curve is already flattened to a polyline within the
//! chordal tolerance (arcs are re-fitted by the G-code writer). Coordinates: x to the right,
//! y up, origin at the sheet's lower-left corner.
//!
//! Each stroke carries its tool [`Layer`] (what the machine does: cut, draw, engrave) and its
//! [`StrokeKind`] (what the line is on the pattern: boundary, notch, drill hole, grain line, …),
//! so writers choose DXF layers and cut order from types, never from the stroke's id text.

use crate::label_info::LabelInfo;
use crate::placement::Placement;
use flatcut_geom::{Aabb2, DVec2};
use serde::{Deserialize, Serialize};

/// What a stroke is for; decides tool, power and order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Layer {
    /// Engraved text and labels (laser raster/vector engraving, pen writing).
    Engrave,
    /// Drawn lines: sew lines, marks, grain lines (pen, or laser at marking power).
    Draw,
    /// Cut lines: the outline with seam allowance, holes, notches cut through.
    Cut,
}

impl Layer {
    /// Every layer: engrave, draw, cut.
    pub const ALL: [Layer; 3] = [Layer::Engrave, Layer::Draw, Layer::Cut];

    /// The layer's name as files carry it: `engrave`, `draw` or `cut`.
    pub fn name(self) -> &'static str {
        match self {
            Layer::Engrave => "engrave",
            Layer::Draw => "draw",
            Layer::Cut => "cut",
        }
    }
}

/// One polyline of the drawing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stroke {
    /// What the tool does along the stroke.
    pub layer: Layer,
    /// Points in mm. A closed stroke does not repeat its first point at the end.
    pub points: Vec<DVec2>,
    /// True when the stroke returns from its last point to its first.
    pub closed: bool,
    /// Which piece (instance) the stroke belongs to, if any: inner cuts of a piece are cut before
    /// the outer contour that holds them.
    pub piece: Option<u32>,
    /// What the stroke is on the pattern.
    pub kind: StrokeKind,
    /// A human-readable id (`"vamp-1-cut"`, `"vamp-1-notch-3"`), carried into comments; never
    /// parsed for meaning (that is [`Stroke::kind`]).
    pub id: String,
}

/// What a stroke is on the pattern; decides its DXF layer and its place in the cut order.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum StrokeKind {
    /// The outer cut contour of a piece (its cut line, seam allowance included).
    Boundary,
    /// A closed cut inside a piece that is not a drill hole (a cut-out).
    InnerCut,
    /// A notch cut into the seam allowance.
    Notch,
    /// A drill hole.
    Drill,
    /// The sew line (seam line).
    Sew,
    /// The grain line with its arrow heads.
    Grain,
    /// A fold (mirror) line: the piece is cut on the fold along it.
    Mirror,
    /// Any other drawn internal line: stitch and placement lines, reference-point crosses.
    #[default]
    Internal,
    /// Label text strokes.
    Text,
}

impl StrokeKind {
    /// True for the outer cut contour of a piece.
    pub fn is_outer(self) -> bool {
        self == StrokeKind::Boundary
    }
}

/// What a drawing knows about one of its pieces beyond the strokes: the label fields a cutting
/// room reads (name, size, quantity, material) and the grain line, so that a pattern read back
/// from a DXF or SVG nests with its grain and cut count.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PieceInfo {
    /// The value of [`Stroke::piece`] of the strokes this describes.
    pub piece: u32,
    /// The piece's label fields: name, size, material, quantity.
    pub label: LabelInfo,
    /// Grain line end points in the drawing's frame (mm).
    pub grain: Option<(DVec2, DVec2)>,
}

/// A set of strokes in mm.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Drawing {
    /// The polylines, in drawing order.
    pub strokes: Vec<Stroke>,
    /// Label and grain of the pieces the strokes belong to, where known (by [`PieceInfo::piece`]).
    #[serde(default)]
    pub pieces: Vec<PieceInfo>,
}

impl Drawing {
    /// A drawing of strokes with no piece information.
    pub fn from_strokes(strokes: Vec<Stroke>) -> Self {
        Self {
            strokes,
            pieces: Vec::new(),
        }
    }

    /// What is known about piece `piece`.
    pub fn piece_info(&self, piece: u32) -> Option<&PieceInfo> {
        self.pieces.iter().find(|p| p.piece == piece)
    }

    /// The bounding box of every stroke's points (mm); empty for a drawing without points.
    pub fn bbox(&self) -> Aabb2 {
        Aabb2::from_points(self.strokes.iter().flat_map(|s| s.points.iter().copied()))
    }

    /// Moves the drawing by a rigid placement: every point and grain line mapped, closed strokes
    /// kept counter-clockwise under a mirror, and, under a mirror, each piece's text reflected in
    /// place first so it reads rightly on the sheet rather than mirror-written.
    pub fn apply_placement(&mut self, pl: &Placement) {
        if pl.mirror {
            self.reflect_text_in_place();
        }
        for s in &mut self.strokes {
            for p in &mut s.points {
                *p = pl.apply(*p);
            }
            if pl.mirror && s.closed && s.points.len() > 1 {
                s.points[1..].reverse();
            }
        }
        for info in &mut self.pieces {
            info.grain = info.grain.map(|(a, b)| (pl.apply(a), pl.apply(b)));
        }
    }

    /// Reflects each piece's text strokes about the vertical line through their middle
    /// (x → 2c − x). A label is written upright in its piece's frame, so after this a mirrored
    /// placement (x → −x) leaves it readable, in the same room.
    fn reflect_text_in_place(&mut self) {
        let mut pieces: Vec<Option<u32>> = Vec::new();
        for s in self.strokes.iter().filter(|s| s.kind == StrokeKind::Text) {
            if !pieces.contains(&s.piece) {
                pieces.push(s.piece);
            }
        }
        for piece in pieces {
            let text = |s: &&mut Stroke| s.kind == StrokeKind::Text && s.piece == piece;
            let (lo, hi) = self
                .strokes
                .iter_mut()
                .filter(text)
                .flat_map(|s| s.points.iter())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p.x), hi.max(p.x))
                });
            let c2 = lo + hi;
            for s in self.strokes.iter_mut().filter(text) {
                s.points.iter_mut().for_each(|p| p.x = c2 - p.x);
            }
        }
    }

    /// Total length of the strokes on `layer`, in mm (closed strokes include their closing segment).
    pub fn length(&self, layer: Layer) -> f64 {
        self.strokes
            .iter()
            .filter(|s| s.layer == layer)
            .map(Stroke::length)
            .sum()
    }
}

impl Stroke {
    /// True for the outer cut contour of a piece.
    pub fn is_outer(&self) -> bool {
        self.kind.is_outer()
    }

    /// Length in mm, including the closing segment of a closed stroke.
    pub fn length(&self) -> f64 {
        let open: f64 = self.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        match (self.closed, self.points.first(), self.points.last()) {
            (true, Some(a), Some(b)) if self.points.len() > 2 => open + a.distance(*b),
            _ => open,
        }
    }
}
