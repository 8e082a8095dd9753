//! A flat drawing in millimetres: polylines on layers, grouped by piece.
//!
//! This is the hand-over format from patterns (and imported SVGs) to the G-code writer and the
//! nester: every curve is already flattened to a polyline within the chordal tolerance (arcs are
//! re-fitted by the G-code writer). Coordinates: x to the right, y up, origin at the sheet's
//! lower-left corner.

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
    pub const ALL: [Layer; 3] = [Layer::Engrave, Layer::Draw, Layer::Cut];

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
    pub layer: Layer,
    /// Points in mm. A closed stroke does not repeat its first point at the end.
    pub points: Vec<DVec2>,
    pub closed: bool,
    /// Which piece (instance) the stroke belongs to, if any: inner cuts of a piece are cut before
    /// the outer contour that holds them.
    pub piece: Option<u32>,
    /// True for the outer cut contour of a piece (its cut line).
    pub outer: bool,
    /// A human-readable id (`"vamp-1/cut"`, `"vamp-1/notch-3"`), carried into comments.
    pub id: String,
}

/// A set of strokes in mm.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Drawing {
    pub strokes: Vec<Stroke>,
}

impl Drawing {
    pub fn bbox(&self) -> Aabb2 {
        Aabb2::from_points(self.strokes.iter().flat_map(|s| s.points.iter().copied()))
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
    /// Length in mm, including the closing segment of a closed stroke.
    pub fn length(&self) -> f64 {
        let open: f64 = self.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        match (self.closed, self.points.first(), self.points.last()) {
            (true, Some(a), Some(b)) if self.points.len() > 2 => open + a.distance(*b),
            _ => open,
        }
    }
}
