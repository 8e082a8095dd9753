//! A piece flattened: its mesh with the flat map, its notches, darts and grain — what the
//! flattening stage hands to the pattern, the report and the nest.

use flatcut_design::PieceDef;
use flatcut_flatten::FlattenInfo;
use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;

/// A notch of a piece: a boundary vertex of its mesh, exactly where the notch is, and its name
/// (a mating seam's notch `line n`, or the design's notch mark).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FlatNotch {
    /// The notch's name.
    pub name: String,
    /// Its boundary vertex in the piece's mesh.
    pub vertex: u32,
}

/// A piece of a design, cut along its seams and flattened: `mesh.flat` holds the 2D position of
/// every vertex (mm, true scale).
#[derive(Clone, Debug)]
pub struct FlatPiece {
    /// The piece as the design defines it.
    pub def: PieceDef,
    /// The 3D mesh with its flattening (`flat`, mm).
    pub mesh: TriMesh,
    /// How the flattening went: method, iterations, warnings.
    pub info: FlattenInfo,
    /// Its notches: the notches of its mating seams and its own notch marks.
    pub notches: Vec<FlatNotch>,
    /// The darts cut into the piece to meet its limits (`mesh` is then cut along them).
    pub darts: Vec<flatcut_darts::Dart>,
    /// Its material and grain, when it has a material ([`crate::material`]).
    pub grain: Option<crate::material::PieceGrain>,
    /// The grain's direction in the flat map of a piece without a material whose grain line
    /// cannot be drawn from the design (a part of a split piece).
    pub grain_dir: Option<DVec2>,
    /// What removing its surface's spikes changed, when asked for ([`crate::despiking`]); the
    /// parts of a split piece carry the whole surface's.
    pub despike: Option<crate::despiking::DespikeRecord>,
}
