//! A piece instance placed on a sheet: its drawing in sheet coordinates ([`Placement`] is the
//! rigid map).

use super::Piece;
use crate::drawing::Drawing;
use crate::placement::Placement;

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
