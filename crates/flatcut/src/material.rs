//! Materials in the pipeline: a piece with a material (`--material`, `[material] properties` in
//! a project, `material_properties` in a piece) is flattened with the orthotropic energy along
//! its grain (`flatcut_flatten::Method::Orthotropic`), its report checks the material's limits
//! along, across and on the bias ([`flatcut_report::GrainReport`]), and darts, when asked for,
//! hold each of those limits on its own thread ([`dart_limits`], [`flatcut_darts::Threads`]):
//! a woven fabric takes a dome's curvature on its bias and needs darts only for what is beyond
//! that. The darted piece is flattened again by the darts' solve, and its threads run along the
//! pattern direction the darts were solved with; a design's grain line is held on the surface.
//! Where the run gives its own limits too (`--max-stretch`/`--max-compress`, on the principal
//! stretches), darts hold the tightest of the limits as one band on the principal stretches
//! ([`dart_params`]): a direction's stretch lies between the principal stretches, so a piece
//! within that band is within every direction's.

use flatcut_design::material::MaterialSpec;
use flatcut_design::{GrainDef, PieceDef};
use flatcut_flatten::anisotropy::{Anisotropy, ByDirection, DirectionalLimits, Grain, Stiffness};
use flatcut_flatten::{FlattenParams, Flattening, Method};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_mesh::grain_strain::{central_face, centroid, pattern_direction_near, warp_at};
use flatcut_report::GrainReport;

use crate::error::PipelineError;

/// A piece's material and where its grain runs in the piece's flat map.
#[derive(Clone, Debug, PartialEq)]
pub struct PieceGrain {
    /// The material: its limits per direction and stiffness.
    pub material: MaterialSpec,
    /// True when the flattening chose the grain.
    pub auto: bool,
    /// The warp's direction in the piece's flat map (unit).
    pub pattern_dir: DVec2,
}

/// The material of a piece: its own `material_properties` (relative to the design's folder),
/// else the run's.
pub fn of_piece(
    def: &PieceDef,
    base: &std::path::Path,
    run: Option<&MaterialSpec>,
) -> Result<Option<MaterialSpec>, PipelineError> {
    match &def.material_properties {
        Some(spec) => MaterialSpec::load(spec, Some(base))
            .map(Some)
            .map_err(|source| PipelineError::Material {
                piece: def.name.clone(),
                source,
            }),
        None => Ok(run.cloned()),
    }
}

/// The material's limits per direction.
pub fn limits(m: &MaterialSpec) -> DirectionalLimits {
    let d = |x: flatcut_design::material::Directions| ByDirection {
        along: x.along,
        across: x.across,
        bias: x.bias,
    };
    DirectionalLimits {
        stretch_pct: d(m.stretch_max_pct),
        compress_pct: d(m.compress_max_pct),
    }
}

/// The orthotropic flattening's material for a piece whose grain is `grain` (none or `"auto"`:
/// chosen by the flattening).
pub fn anisotropy(m: &MaterialSpec, grain: Option<&GrainDef>) -> Anisotropy {
    let s = m.stiffness_or_isotropic();
    Anisotropy {
        stiffness: Stiffness {
            along: s.along,
            across: s.across,
            shear: s.shear,
        },
        limits: Some(limits(m)),
        grain: match grain.and_then(GrainDef::line) {
            Some([a, b]) => Grain::Line([DVec3::from_array(*a), DVec3::from_array(*b)]),
            None => Grain::Auto,
        },
    }
}

/// Flattens `mesh` with the orthotropic energy of `m` (the warp along +x of the result).
pub fn flatten(
    name: &str,
    mesh: &TriMesh,
    params: &FlattenParams,
    m: &MaterialSpec,
    grain: Option<&GrainDef>,
) -> Result<(Flattening, PieceGrain), PipelineError> {
    let mut p = params
        .clone()
        .with_anisotropy(Some(anisotropy(m, grain)))
        .with_max_stretch_pct(None)
        .with_max_compress_pct(None);
    p.method = Method::Orthotropic;
    let f = flatcut_flatten::flatten(mesh, &p).map_err(|source| PipelineError::Flatten {
        piece: name.to_string(),
        source,
    })?;
    let auto = grain.and_then(GrainDef::line).is_none();
    Ok((
        f,
        PieceGrain {
            material: m.clone(),
            auto,
            pattern_dir: DVec2::X,
        },
    ))
}

/// The limits darts hold for a piece `mesh` of material `m` whose grain lies along
/// `g.pattern_dir` in its map and is drawn as `grain` by the design: [`dart_params`]' band, and
/// the per-thread limits where they apply (`dart_threads`).
pub fn dart_limits(
    params: &FlattenParams,
    m: &MaterialSpec,
    g: &PieceGrain,
    grain: Option<&GrainDef>,
    mesh: &TriMesh,
) -> crate::darting::DartLimits {
    crate::darting::DartLimits {
        params: dart_params(params, m),
        threads: dart_threads(params, m, g, grain, mesh),
    }
}

/// The per-thread limits darts hold for a piece `mesh` of material `m` whose grain lies along
/// `g.pattern_dir` in its map; `None` (darts hold [`dart_params`]' band) where the run gives
/// limits of its own. The thread limits turn with the map, so where the design fixes the grain
/// line (`grain`), the darts' solve holds the warp along the line's direction at the piece's
/// central face (where the orthotropic flattening put the grain and a split finds it again); a
/// chosen grain goes where the solve puts it.
fn dart_threads(
    params: &FlattenParams,
    m: &MaterialSpec,
    g: &PieceGrain,
    grain: Option<&GrainDef>,
    mesh: &TriMesh,
) -> Option<flatcut_darts::Threads> {
    if params.max_stretch_pct.is_some() || params.max_compress_pct.is_some() {
        return None;
    }
    let threads = flatcut_darts::Threads::new(&limits(m), g.pattern_dir);
    let line = grain.and_then(GrainDef::line);
    Some(match (line, central_face(mesh)) {
        (Some([a, b]), Some(t)) => threads.with_anchor(
            centroid(mesh, t),
            DVec3::from_array(*b) - DVec3::from_array(*a),
        ),
        _ => threads,
    })
}

/// The parameters darts are placed with for a piece of material `m`: the tightest of its limits
/// (and of the run's own limits, where given) as the isotropic band; with no limits of the run's
/// own, the per-thread limits of [`dart_limits`] replace the band in the solve, and the band
/// only says that darts are asked for limits.
pub fn dart_params(params: &FlattenParams, m: &MaterialSpec) -> FlattenParams {
    let (s, c) = m.tightest_pct();
    let tight = |run: Option<f64>, mat: f64| Some(run.map_or(mat, |r| r.min(mat)));
    params
        .clone()
        .with_max_stretch_pct(tight(params.max_stretch_pct, s))
        .with_max_compress_pct(tight(params.max_compress_pct, c))
}

/// The grain after the piece was cut and flattened again (`before`: the map the grain was chosen
/// in, `after`: the new one of the cut mesh).
pub fn carry_over(
    g: &PieceGrain,
    before: (&TriMesh, &[DVec2]),
    after: (&TriMesh, &[DVec2]),
) -> PieceGrain {
    // The warp where the old piece's centre was, found again in the new map there.
    let dir = central_face(before.0)
        .and_then(|t| {
            Some((
                warp_at(before.0, before.1, g.pattern_dir, t)?,
                centroid(before.0, t),
            ))
        })
        .and_then(|(d, at)| pattern_direction_near(after.0, after.1, d, at, 0.0))
        .unwrap_or(g.pattern_dir);
    PieceGrain {
        pattern_dir: dir,
        ..g.clone()
    }
}

/// The grain section of the report of a flattened piece (`mesh.flat` set).
pub fn report(g: &PieceGrain, mesh: &TriMesh) -> Option<GrainReport> {
    let uv = mesh.flat.as_ref()?;
    GrainReport::compute(
        &g.material.name,
        g.auto,
        mesh,
        uv,
        g.pattern_dir,
        &limits(&g.material),
    )
}
