//! Mating seams as a pattern maker checks them: the length of each side in the plane against the
//! other side and against 3D, and each notch's distance from the seam's start on both sides.

use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::{MatingSeam, arc_lengths};
use serde::Serialize;

/// Default largest difference between the two flat sides of a mating seam (mm): below what a
/// stitcher can take up, well above the flattener's own agreement (1e-9 of an edge).
pub const DEFAULT_SEAM_TOLERANCE_MM: f64 = 0.1;

/// A notch on a mating seam: its distance from the seam's start along each side (flat, mm).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NotchOffset {
    /// The notch's name.
    pub name: String,
    /// Arc length in the flat piece from the seam's start to the notch, on side 0 and side 1
    /// (mm); equal on a seam that sews true.
    pub offset_mm: [f64; 2],
}

/// The figures of one mating seam. Field names are the JSON contract.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MatingSeamReport {
    /// The seam's name.
    pub name: String,
    /// The pieces of its two sides (the same piece twice for a dart or a tube's seam).
    pub pieces: [String; 2],
    /// Its length on the surface (the mean of the two sides' when they differ, for a join of
    /// separately modelled pieces).
    pub length_3d_mm: f64,
    /// The length of each side in the plane.
    pub length_2d_mm: [f64; 2],
    /// |side a − side b| in the plane.
    pub mismatch_mm: f64,
    /// The seam's notches, in the seam's order.
    pub notches: Vec<NotchOffset>,
    /// Its length weighted by how visible it is (mm; less than `length_3d_mm` where it hides in
    /// a crease or on the hidden side), when measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visibility_cost_mm: Option<f64>,
    /// How much it turns on the surface (degrees; 0 for a straight seam), when measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turning_deg: Option<f64>,
}

impl MatingSeamReport {
    /// The largest difference between the two sides: the lengths and every notch's offsets.
    pub fn worst_mm(&self) -> f64 {
        self.notches
            .iter()
            .map(|n| (n.offset_mm[0] - n.offset_mm[1]).abs())
            .fold(self.mismatch_mm, f64::max)
    }
}

/// Measures a seam on flattened meshes (`meshes[i].flat` set); `names[i]` names piece i.
/// `None` when a side's mesh has no flattening.
pub fn measure_seam(
    seam: &MatingSeam,
    meshes: &[&TriMesh],
    names: &[&str],
) -> Option<MatingSeamReport> {
    let flat = [seam.points_2d(0, meshes)?, seam.points_2d(1, meshes)?];
    let s2 = flat.map(|p| arc_lengths(&p, |a, b| a.distance(*b)));
    let l3 = [0, 1].map(|k| {
        let p = seam.points_3d(k, meshes);
        arc_lengths(&p, |a, b| a.distance(*b))
            .last()
            .copied()
            .unwrap_or(0.0)
    });
    let end = |s: &Vec<f64>| s.last().copied().unwrap_or(0.0);
    let l2 = [end(&s2[0]), end(&s2[1])];
    Some(MatingSeamReport {
        name: seam.name.clone(),
        pieces: [0, 1].map(|k| names[seam.sides[k].piece].to_string()),
        length_3d_mm: 0.5 * (l3[0] + l3[1]),
        length_2d_mm: l2,
        mismatch_mm: (l2[0] - l2[1]).abs(),
        notches: seam
            .notches
            .iter()
            .map(|n| NotchOffset {
                name: n.name.clone(),
                offset_mm: [s2[0][n.index], s2[1][n.index]],
            })
            .collect(),
        visibility_cost_mm: None,
        turning_deg: None,
    })
}
