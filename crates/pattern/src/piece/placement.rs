//! A piece instance placed on a sheet: its drawing in sheet coordinates ([`Placement`] is the
//! rigid map).

use super::Piece;
use crate::drawing::Drawing;
use crate::placement::Placement;

/// A piece instance placed on a sheet.
#[derive(Clone, Copy, Debug)]
pub struct PlacedPiece<'a> {
    /// The piece.
    pub piece: &'a Piece,
    /// Which copy of the piece (0-based), carried into the strokes' piece ids.
    pub instance: u32,
    /// Where the copy lies on the sheet.
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
