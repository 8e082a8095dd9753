//! Placing a piece instance on a sheet: a rigid map (mirror, rotation, translation).

use flatcut_geom::DVec2;

/// A rigid placement of a piece instance: optional mirror (x → −x), then rotation, then
/// translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Rotation in radians, counter-clockwise, after the mirror.
    pub rotation: f64,
    /// True when x is negated first (the piece turned over).
    pub mirror: bool,
    /// Translation (mm), applied last.
    pub translation: DVec2,
}

impl Placement {
    /// The placement that leaves the piece where it is.
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
