//! Placing a piece instance on a sheet: a rigid map (mirror, rotation, translation) and the
//! instance's drawing in sheet coordinates.

use super::Piece;
use crate::drawing::Drawing;
use flatcut_geom::DVec2;

/// A rigid placement of a piece instance: optional mirror (x → −x), then rotation, then
/// translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub rotation: f64,
    pub mirror: bool,
    pub translation: DVec2,
}

impl Placement {
    pub const IDENTITY: Self = Self {
        rotation: 0.0,
        mirror: false,
        translation: DVec2::ZERO,
    };

    /// Maps a point of the piece frame to the sheet.
    pub fn apply(&self, p: DVec2) -> DVec2 {
        let q = if self.mirror {
            DVec2::new(-p.x, p.y)
        } else {
            p
        };
        self.translation + DVec2::from_angle(self.rotation).rotate(q)
    }
}

/// A piece instance placed on a sheet.
#[derive(Clone, Copy, Debug)]
pub struct PlacedPiece<'a> {
    pub piece: &'a Piece,
    pub instance: u32,
    pub placement: Placement,
}

impl PlacedPiece<'_> {
    /// The instance's drawing in sheet coordinates (closed strokes stay CCW and the label reads
    /// rightly under mirroring).
    pub fn to_drawing(&self) -> Drawing {
        let mut d = self.piece.to_drawing(self.instance);
        d.apply_placement(&self.placement);
        d
    }
}
