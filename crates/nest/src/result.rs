//! The layout found: placements, what did not fit, utilization and the use of each sheet or hide.

use flatcut_pattern::Placement;

/// One placed piece instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedInstance {
    /// Index into the input items.
    pub item: usize,
    /// Copy number (0-based) among the item's copies of this side.
    pub copy: usize,
    /// Sheet or hide index (always 0 on a roll).
    pub sheet: usize,
    /// Piece frame → stock frame (the mirror flag marks the mirrored side of a pair).
    pub placement: Placement,
}

/// An instance that could not be placed.
#[derive(Clone, Debug, PartialEq)]
pub struct Unplaced {
    /// Index of its item in the input.
    pub item: usize,
    /// The item's name.
    pub name: String,
    /// Copy number (0-based) among the item's copies of this side.
    pub copy: usize,
    /// True for the mirrored side of a pair.
    pub mirrored: bool,
    /// Why it could not be placed.
    pub reason: String,
}

/// How much of one sheet or hide the layout uses.
#[derive(Clone, Debug, PartialEq)]
pub struct SheetUse {
    /// The hide's name, or `sheet N`.
    pub name: String,
    /// Pieces placed on it.
    pub pieces: usize,
    /// Area of the pieces placed on it, mm².
    pub piece_area: f64,
    /// Area that can be cut: the outline minus its defects, mm².
    pub usable_area: f64,
    /// piece area / usable area, percent.
    pub yield_pct: f64,
}

/// The layout found.
#[derive(Clone, Debug, PartialEq)]
pub struct NestResult {
    /// Every instance placed, with where.
    pub placed: Vec<PlacedInstance>,
    /// Every instance that could not be placed, with why.
    pub unplaced: Vec<Unplaced>,
    /// Placed piece area / used stock area, in percent: on a roll the used length × width, on
    /// sheets the sheets used, on hides the usable area of the hides used.
    pub utilization: f64,
    /// Used roll length: where the pieces end (max x of their outlines); on sheets the extent on
    /// the last sheet.
    pub length: f64,
    /// Sheets or hides used.
    pub sheets: usize,
    /// Per sheet or hide used (empty on a roll).
    pub sheet_use: Vec<SheetUse>,
    /// Utilization of the first feasible layout the search started from (percent).
    pub baseline_utilization: f64,
    /// Used length of the first feasible layout (mm), as [`NestResult::length`].
    pub baseline_length: f64,
    /// Separation iterations run.
    pub iterations: usize,
    /// True when the cancel hook stopped the search before its budget ran out.
    pub cancelled: bool,
}
