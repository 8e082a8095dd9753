//! Darts in the pipeline: when a flattened piece exceeds its limits and darts are asked for
//! (`--darts auto`, or `darts = "auto"` in the project or the piece), the piece is cut by
//! [`flatcut_darts::place()`] and flattened again with the limits held; where no dart can bring it
//! within them the pipeline fails with what was reached.
//!
//! What the design says about the piece keeps darts away: its `no_cut` regions, its marks
//! (notches, drill and reference points, stitch and placement lines); its seams are already part
//! of the outline.
//!
//! Pieces joined to others by mating seams are not darted (a dart would move their seams): the
//! flattening warns and leaves them whole.

pub use flatcut_darts::DartFit;
use flatcut_darts::{Dart, DartError, DartOptions, Darted, KeepOut, Threads};
use flatcut_design::{DartsDef, MarkKind, PieceDef};
use flatcut_flatten::{Budget, FlattenInfo, FlattenParams};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_report::DartReport;

use crate::error::PipelineError;

/// How darts are placed when they are asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DartSettings {
    /// Most darts in one piece.
    pub max_darts: usize,
    /// Least distance between two darts (mm).
    pub min_spacing_mm: f64,
    /// How far short of its point a dart's drill mark sits (mm).
    pub drill_offset_mm: f64,
    /// How the final map uses the material's give.
    pub fit: DartFit,
}

impl Default for DartSettings {
    fn default() -> Self {
        Self {
            max_darts: DartOptions::DEFAULT_MAX_DARTS,
            min_spacing_mm: DartOptions::DEFAULT_MIN_SPACING_MM,
            drill_offset_mm: DartOptions::DEFAULT_DRILL_OFFSET_MM,
            fit: DartFit::LeastStrain,
        }
    }
}

/// The limits a piece is darted for: `params`' stretch and compression on the principal
/// stretches, or, when given, `threads`' per thread of the material.
#[derive(Clone, Debug)]
pub struct DartLimits {
    /// The flattening's parameters: its stretch and compression limits on the principal stretches.
    pub params: FlattenParams,
    /// The material's limits per thread; when given, they replace the principal-stretch limits.
    pub threads: Option<Threads>,
}

impl DartLimits {
    /// The limits of `params` alone.
    pub fn of(params: &FlattenParams) -> Self {
        Self {
            params: params.clone(),
            threads: None,
        }
    }
}

/// Radius (mm) around a point mark that darts keep clear of.
const MARK_CLEARANCE_MM: f64 = 3.0;

/// True when darts are to be tried for this piece: the piece says so, or the run does and the
/// piece does not refuse.
pub fn wanted(def: Option<&PieceDef>, run: Option<&DartSettings>) -> bool {
    match def.and_then(|d| d.darts) {
        Some(DartsDef::Auto) => true,
        Some(DartsDef::Off) => false,
        None => run.is_some(),
    }
}

/// True when every face of the map is within the limits of `params`, or within `threads`'
/// limits when given.
pub fn within(
    mesh: &TriMesh,
    uv: &[DVec2],
    params: &FlattenParams,
    threads: Option<&Threads>,
) -> bool {
    let band = flatcut_darts::Band::from_pct(params.max_stretch_pct, params.max_compress_pct);
    (0..mesh.triangles.len()).all(|t| {
        let c3 = mesh.corners(t);
        let c2 = mesh.triangles[t].map(|v| uv[v as usize]);
        match threads {
            Some(th) => flatcut_mesh::grain_strain::triangle_jacobian(c3, c2)
                .is_some_and(|j| th.excess(j) <= 0.0),
            None => flatcut_mesh::face_distortion(c3, c2)
                .is_some_and(|d| !d.flipped() && band.excess(d.sigma1, d.sigma2) <= 0.0),
        }
    })
}

/// The vertices no dart may use, from the piece's design.
pub fn keep_out(def: Option<&PieceDef>, mesh: &TriMesh) -> Result<KeepOut, PipelineError> {
    let mut k = KeepOut::none(mesh);
    let Some(def) = def else {
        return Ok(k);
    };
    for (i, region) in def.no_cut.iter().enumerate() {
        let pts: Vec<DVec3> = region.iter().map(|p| DVec3::from_array(*p)).collect();
        k.block_region(mesh, &pts, i)
            .map_err(|source| PipelineError::NoCut {
                piece: def.name.clone(),
                source,
            })?;
    }
    for m in &def.marks {
        let pts: Vec<DVec3> = m.points.iter().map(|p| DVec3::from_array(*p)).collect();
        match m.kind {
            MarkKind::Line if pts.len() >= 2 => {
                k.block_line(mesh, &pts)
                    .map_err(|reason| PipelineError::MarkKeepOut {
                        piece: def.name.clone(),
                        mark: m.name.clone(),
                        reason,
                    })?
            }
            _ => k.block_points(mesh, &pts, MARK_CLEARANCE_MM),
        }
    }
    Ok(k)
}

/// Darts for a flattened piece (`mesh` with `uv`) that exceeds the limits of `params` (or of
/// `threads`, per thread, when given); `None` when it is within them already. Fails when no
/// darts bring it within them. The flag says whether the darts held the threads' limits: where
/// no darts do (their final map closing past a mouth, say), the piece is darted for the tightest
/// band of `params` instead, as it would have been without them, and the flag is false.
pub fn dart_piece(
    name: &str,
    def: Option<&PieceDef>,
    mesh: &TriMesh,
    uv: &[DVec2],
    limits: &DartLimits,
    settings: &DartSettings,
    stage: &Budget,
) -> Result<Option<(Darted, bool)>, PipelineError> {
    let (params, threads) = (&limits.params, limits.threads.as_ref());
    if params.max_stretch_pct.is_none() && params.max_compress_pct.is_none() {
        return Ok(None);
    }
    if within(mesh, uv, params, threads) {
        return Ok(None);
    }
    let band = DartOptions::new(params.max_stretch_pct, params.max_compress_pct)
        .with_max_darts(settings.max_darts)
        .with_min_spacing_mm(settings.min_spacing_mm)
        .with_drill_offset_mm(settings.drill_offset_mm)
        .with_fit(settings.fit)
        .with_keep_out(keep_out(def, mesh)?)
        .with_budget(stage.clone());
    if let Some(t) = threads
        && let Ok(d) = flatcut_darts::place(mesh, uv, &band.clone().with_threads(*t))
    {
        return Ok(Some((d, true)));
    }
    flatcut_darts::place(mesh, uv, &band)
        .map(|d| Some((d, false)))
        .map_err(|source| {
            let count = stage.count();
            if count.stopped {
                PipelineError::DartsStopped {
                    piece: name.to_string(),
                    source,
                    count: Box::new(count),
                }
            } else {
                PipelineError::Darts {
                    piece: name.to_string(),
                    source,
                }
            }
        })
}

/// A piece after [`finish`].
pub struct Finished {
    /// The mesh, cut along the darts when there are any, with `flat` set.
    pub mesh: TriMesh,
    /// The flattening's info (its limit warnings dropped when darts brought the piece within
    /// them).
    pub info: FlattenInfo,
    /// The darts cut, in the order they were found.
    pub darts: Vec<Dart>,
    /// True when the map keeps the grain where it lay in the flattening's map: no darts, or
    /// darts that held the threads' limits along it. False: the grain is to be found again.
    pub grain_kept: bool,
}

/// A flattened piece (`mesh` with its map `uv`) with darts when `settings` asks for them and the
/// piece needs them ([`dart_piece`]).
pub fn finish(
    name: &str,
    def: Option<&PieceDef>,
    mut mesh: TriMesh,
    uv: Vec<DVec2>,
    mut info: FlattenInfo,
    limits: &DartLimits,
    settings: Option<&DartSettings>,
) -> Result<Finished, PipelineError> {
    let stage = limits
        .params
        .stage_budget("darts", std::time::Instant::now());
    if let Some(settings) = settings
        && let Some((d, per_thread)) = dart_piece(name, def, &mesh, &uv, limits, settings, &stage)?
    {
        info.warnings.clear();
        info.iterations += stage.used();
        info.stages.push(stage.count());
        if limits.threads.is_some() && !per_thread {
            info.warnings.push(format!(
                "{name}: no darts held the material's limits thread by thread, so the darts hold the tightest of them on every direction (more darts than the threads would need)"
            ));
        }
        if settings.fit == DartFit::Tight && d.fit != DartFit::Tight {
            info.warnings.push(format!(
                "{name}: drawn tight, a dart would close past its mouth (its legs cross or part), so the darts keep the least-strained map"
            ));
        }
        no_crossing(name, &d.mesh)?;
        return Ok(Finished {
            mesh: d.mesh,
            info,
            darts: d.darts,
            grain_kept: per_thread,
        });
    }
    mesh.flat = Some(uv);
    no_crossing(name, &mesh)?;
    Ok(Finished {
        mesh,
        info,
        darts: Vec::new(),
        grain_kept: true,
    })
}

/// Refuses a flat piece (`mesh` with its map) whose outline crosses itself: within its limits
/// face by face, it still overlaps itself flat, and no pattern can be cut from it (as a split's
/// parts are checked, [`flatcut_darts::crossing`]).
pub fn no_crossing(name: &str, mesh: &TriMesh) -> Result<(), PipelineError> {
    let Some(uv) = mesh.flat.as_deref() else {
        return Ok(());
    };
    let darts = |source| PipelineError::Darts {
        piece: name.to_string(),
        source,
    };
    match flatcut_darts::crossing::outline_crossing(mesh, uv).map_err(darts)? {
        Some(v) => Err(darts(DartError::OutlineCrossing {
            at: mesh.positions[v as usize],
        })),
        None => Ok(()),
    }
}

/// The report's view of a piece's darts.
pub fn dart_reports(darts: &[Dart]) -> Vec<DartReport> {
    darts
        .iter()
        .map(|t| DartReport {
            start_3d: t.start_3d.to_array(),
            apex_3d: t.apex_3d.to_array(),
            length_3d_mm: t.length_3d_mm,
            leg_2d_mm: t.leg_2d_mm,
            opening_mm: t.opening_mm,
            drill_3d: t.drill_3d.to_array(),
            drill_2d: t.drill_2d.to_array(),
        })
        .collect()
}

/// True when the error says the limits cannot be met with darts (the limit exit code's case).
pub fn is_out_of_limits(e: &PipelineError) -> bool {
    matches!(
        e,
        PipelineError::Darts {
            source: DartError::Infeasible { .. }
                | DartError::Overlap { .. }
                | DartError::LegsApart { .. }
                | DartError::SplitOverlap { .. }
                | DartError::OutlineCrossing { .. },
            ..
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_flatten::anisotropy::{ByDirection, DirectionalLimits};
    use flatcut_flatten::testmesh::spherical_cap;

    #[test]
    fn darts_fall_back_to_the_band_where_no_darts_hold_the_threads() {
        // Thread limits of 0 % no darts can meet, with a band of 5 % / 2 % they can: the band's
        // darts are the answer, the grain is to be found again, and the run says why.
        let mesh = spherical_cap(100.0, 0.8, 12);
        let params = FlattenParams::new(flatcut_flatten::Method::Isometric)
            .with_max_stretch_pct(Some(5.0))
            .with_max_compress_pct(Some(2.0));
        let f = flatcut_flatten::flatten(&mesh, &params).unwrap();
        let none = ByDirection {
            along: 0.0,
            across: 0.0,
            bias: 0.0,
        };
        let zero = DirectionalLimits {
            stretch_pct: none,
            compress_pct: none,
        };
        let limits = DartLimits {
            params: params.clone(),
            threads: Some(Threads::new(&zero, DVec2::X)),
        };
        let settings = DartSettings {
            max_darts: 4,
            ..Default::default()
        };
        let done = finish("cap", None, mesh, f.uv, f.info, &limits, Some(&settings)).unwrap();
        assert!(!done.darts.is_empty());
        assert!(!done.grain_kept);
        assert!(
            done.info.warnings.iter().any(|w| w.contains("tightest")),
            "{:?}",
            done.info.warnings
        );
        let uv = done.mesh.flat.as_deref().unwrap();
        assert!(within(&done.mesh, uv, &params, None));
    }
}
