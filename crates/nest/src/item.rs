//! What is nested: a piece type with its outline, copies, allowed turns, grain rule, mirror
//! images and the worst hide grade it accepts.

use flatcut_geom::DVec2;

/// Allowed rotations of an item that has no grain constraint.
#[derive(Clone, Debug, PartialEq)]
pub enum Rotations {
    /// As drawn only.
    None,
    /// 0° and 180°.
    Half,
    /// Multiples of 90°.
    Quarter,
    /// Any angle.
    Free,
    /// An explicit list (radians).
    List(Vec<f64>),
}

/// Which ways a piece's grain line may run against the material's grain (the roll's length,
/// the sheet's x axis, or a hide's local backbone direction).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GrainDirections {
    /// Along the material's grain, one way only (a napped or printed material).
    Fixed,
    /// Along the material's grain either way (`"0,180"`, most woven materials).
    #[default]
    Reversible,
    /// Any direction: the material has no grain to keep (the item's [`Rotations`] apply).
    Any,
}

impl GrainDirections {
    /// Parses `"fixed"`, `"0,180"` (or `"reversible"`) and `"any"`.
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().replace(' ', "").as_str() {
            "fixed" | "0" => Some(Self::Fixed),
            "0,180" | "reversible" => Some(Self::Reversible),
            "any" => Some(Self::Any),
            _ => None,
        }
    }
}

/// One piece type to nest.
#[derive(Clone, Debug, PartialEq)]
pub struct NestItem {
    /// Name used in reports and errors.
    pub name: String,
    /// Outline (cut line), closed, without repeated end point (mm). Either orientation.
    pub outline: Vec<DVec2>,
    /// Copies to place (for a mirrored pair: copies of each side).
    pub quantity: usize,
    /// Allowed rotations when the grain does not decide them.
    pub rotations: Rotations,
    /// Angle of the grain line in the piece frame (radians). When set and
    /// [`grain_directions`](Self::grain_directions) is not [`GrainDirections::Any`], the piece is
    /// only turned so its grain runs along the material's grain, within
    /// [`grain_tolerance_deg`](Self::grain_tolerance_deg).
    pub grain_angle: Option<f64>,
    /// The material's rule for the grain.
    pub grain_directions: GrainDirections,
    /// How far the grain may deviate from the material's grain, degrees (0 = exactly along).
    pub grain_tolerance_deg: f64,
    /// Also place `quantity` mirror images (left/right shoe parts): a mirrored copy is the mirror
    /// image of the outline, so it takes a different place than a turned copy would.
    pub mirrored_pair: bool,
    /// The worst hide grade the piece accepts (1 = first quality only; `None` = any grade).
    /// Defects are never accepted. Only hides have grades; sheets and rolls are first quality.
    pub quality: Option<u32>,
}

impl NestItem {
    /// An item with `quantity` copies, rotations 0/180°, no grain, no mirror, any quality.
    pub fn new(name: impl Into<String>, outline: Vec<DVec2>, quantity: usize) -> Self {
        Self {
            name: name.into(),
            outline,
            quantity,
            rotations: Rotations::Half,
            grain_angle: None,
            grain_directions: GrainDirections::Reversible,
            grain_tolerance_deg: 0.0,
            mirrored_pair: false,
            quality: None,
        }
    }

    /// A nesting item from a built pattern piece: its cut line, its grain line (when it has one,
    /// the grain runs along the material's either way), `quantity` copies per side.
    pub fn from_piece(
        piece: &flatcut_pattern::Piece,
        quantity: usize,
        mirrored_pair: bool,
    ) -> Self {
        Self {
            grain_angle: piece.grain.map(|(a, b)| (b - a).y.atan2((b - a).x)),
            mirrored_pair,
            ..Self::new(piece.name.clone(), piece.cut.clone(), quantity)
        }
    }

    /// The grain rule that applies: `Some(angle)` when the grain constrains the turns.
    pub(crate) fn effective_grain(&self) -> Option<f64> {
        self.grain_angle
            .filter(|_| self.grain_directions != GrainDirections::Any)
    }
}
