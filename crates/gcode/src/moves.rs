//! The motions of a working tool, lines and circular arcs in machine coordinates: what the
//! planner, the knife's compensation and the arc fitting pass to one another.

use flatcut_geom::DVec2;

/// One motion while the tool works, in machine coordinates (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// A straight line to the point.
    Line(DVec2),
    /// A circular arc to `to` around `center`, counter-clockwise (`G3`) or clockwise (`G2`).
    Arc {
        /// Where the arc ends.
        to: DVec2,
        /// The arc's centre.
        center: DVec2,
        /// Counter-clockwise (`G3`), or clockwise (`G2`).
        ccw: bool,
    },
}

impl Move {
    /// Where the move ends.
    pub fn end(&self) -> DVec2 {
        match *self {
            Move::Line(p) => p,
            Move::Arc { to, .. } => to,
        }
    }
}
