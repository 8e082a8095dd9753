//! The darts of a piece as the report states them: where each starts and ends on the surface, how
//! long it is and how long its two legs are in the flat piece (they are sewn together, so they
//! must match), how wide its mouth opens and where its drill mark is.

use serde::Serialize;

/// One dart of a piece (mm).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DartReport {
    /// Its mouth on the outline (3D).
    pub start_3d: [f64; 3],
    /// Its point (3D).
    pub apex_3d: [f64; 3],
    /// Length along the surface.
    pub length_3d_mm: f64,
    /// 2D length of each leg.
    pub leg_2d_mm: [f64; 2],
    /// Width of the mouth in the flat piece.
    pub opening_mm: f64,
    /// The drill mark short of the point, on the surface.
    pub drill_3d: [f64; 3],
    /// The same drill mark in the flat piece.
    pub drill_2d: [f64; 2],
}

impl DartReport {
    /// |leg a − leg b| in the flat piece (mm).
    pub fn leg_mismatch_mm(&self) -> f64 {
        (self.leg_2d_mm[0] - self.leg_2d_mm[1]).abs()
    }
}
