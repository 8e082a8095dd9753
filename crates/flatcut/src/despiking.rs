//! A piece's spikes removed before it is flattened and split (`--despike`, a project's
//! `despike`): [`flatcut_mesh::despike`] with the bound the piece's own limits set
//! ([`flatcut_darts::cone::corner_reach`] of the band its split holds), and what it moved kept
//! for the report, since the pattern is then cut from a surface that differs from the scan there.

use flatcut_darts::Band;
use flatcut_design::material::MaterialSpec;
use flatcut_flatten::FlattenParams;
use flatcut_mesh::TriMesh;

use crate::error::PipelineError;

/// The largest move of a vertex when none is given (mm): a scan's spike is a fan of a few faces
/// raised a millimetre or so out of its surface (the Nefertiti bust's, 0.6–1.5 rad of defect over
/// edges of about 1 mm), and a move of more than 2 mm changes the shape rather than its noise.
pub const DEFAULT_MAX_MM: f64 = 2.0;

/// What the repair of one piece changed, as the report records it (`"despike"`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DespikeRecord {
    /// The piece as the design names it (its parts carry this same record).
    #[serde(skip)]
    pub piece: String,
    /// How many vertices moved.
    pub moved: usize,
    /// The largest distance a vertex moved (mm).
    pub max_mm: f64,
    /// Where the vertex that moved farthest was (mm); `None` when none moved.
    pub at: Option<[f64; 3]>,
    /// How many inside vertices are still beyond what the limits let their corners absorb.
    pub left: usize,
}

/// Removes the spikes of `mesh` (piece `piece`) that the limits of `params` (or the tightest of
/// `material`'s and the run's, as darts and splits hold them) leave no part able to hold inside,
/// moving no vertex farther than `max_mm`; `None` when `params` sets no limit.
pub fn despike_piece(
    piece: &str,
    mesh: &mut TriMesh,
    params: &FlattenParams,
    material: Option<&MaterialSpec>,
    max_mm: f64,
) -> Result<Option<DespikeRecord>, PipelineError> {
    let limits = match material {
        Some(m) => crate::material::dart_params(params, m),
        None => params.clone(),
    };
    if limits.max_stretch_pct.is_none() && limits.max_compress_pct.is_none() {
        return Ok(None);
    }
    let band = Band::from_pct(limits.max_stretch_pct, limits.max_compress_pct);
    let reach = flatcut_darts::cone::corner_reach(band);
    let r = flatcut_mesh::despike::despike(mesh, reach, max_mm).map_err(|source| {
        PipelineError::Topology {
            piece: piece.to_string(),
            source,
        }
    })?;
    Ok(Some(DespikeRecord {
        piece: piece.to_string(),
        moved: r.moved.len(),
        max_mm: r.max_mm,
        at: r.max_at.map(|(_, p)| p.to_array()),
        left: r.left.len(),
    }))
}

impl DespikeRecord {
    /// The line that tells the user what was changed: "despiked N vertices of 'piece', moved at
    /// most X mm at (x, y, z)", and how many are left beyond reach.
    pub fn line(&self) -> String {
        let at = self
            .at
            .map(|p| format!(" at ({:.2}, {:.2}, {:.2})", p[0], p[1], p[2]))
            .unwrap_or_default();
        let left = if self.left > 0 {
            format!(
                "; {} vertices left beyond what the limits let their corners absorb (a larger --despike-max-mm may move them)",
                self.left
            )
        } else {
            String::new()
        };
        format!(
            "despiked {} vertices of '{}', moved at most {:.3} mm{at}{left}",
            self.moved, self.piece, self.max_mm
        )
    }
}
