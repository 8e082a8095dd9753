//! Flattened pieces with their distortion reports: what every later stage (pattern, nesting,
//! G-code, the report's pictures) starts from, whether the input was a design or an OBJ that
//! already carries its flat map.

use std::path::Path;

use flatcut_design::PieceDef;
use flatcut_flatten::{FlattenInfo, FlattenParams};
use flatcut_geom::Tolerances;
use flatcut_mesh::TriMesh;
use flatcut_report::Report;

use crate::pipeline::{self, FlatPiece, PipelineError};

/// A flattened piece ready for the pattern: its mesh (with `flat`), its design entry when it came
/// from a design, its distortion report and how the flattening went.
#[derive(Clone, Debug)]
pub struct Flat {
    pub name: String,
    pub def: Option<PieceDef>,
    pub mesh: TriMesh,
    pub report: Report,
    pub quantity: u32,
    /// Absent when the map was read from a file rather than computed.
    pub info: Option<FlattenInfo>,
}

/// Stretch and compression limits in percent, checked by the report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Limits {
    pub stretch_pct: Option<f64>,
    pub compress_pct: Option<f64>,
}

/// Reads a mesh file; when it already carries a flat map (`vt`), returns it as one reported piece
/// named after the file. `Ok(None)`: the file is a 3D mesh that still needs flattening.
pub fn read_flat_mesh(path: &Path, limits: Limits) -> Result<Option<Flat>, PipelineError> {
    let mesh = flatcut_mesh::read_mesh(path)?;
    if mesh.flat.is_none() {
        return Ok(None);
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "piece".into());
    let report =
        pipeline::report_piece(&name, &mesh, &[], limits.stretch_pct, limits.compress_pct)?;
    Ok(Some(Flat {
        name,
        def: None,
        mesh,
        report,
        quantity: 1,
        info: None,
    }))
}

/// Flattens every piece of a design (or 3D mesh) and reports each; `progress(piece, index,
/// count)` is called before each piece.
pub fn flatten_and_report(
    path: &Path,
    tol: &Tolerances,
    params: &FlattenParams,
    limits: Limits,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Vec<Flat>, PipelineError> {
    let (_, pieces) = pipeline::flatten_design(path, tol, params, progress)?;
    pieces
        .into_iter()
        .map(|FlatPiece { def, mesh, info }| {
            let boundary = pipeline::flat_boundary(&def.name, &mesh)
                .map(|b| b.1)
                .unwrap_or_default();
            let marks = pipeline::notch_vertices(&def, &mesh, &boundary);
            let report = pipeline::report_piece(
                &def.name,
                &mesh,
                &marks,
                limits.stretch_pct,
                limits.compress_pct,
            )?;
            Ok(Flat {
                name: def.name.clone(),
                quantity: def.quantity,
                def: Some(def),
                mesh,
                report,
                info: Some(info),
            })
        })
        .collect()
}

/// Loads a flattened OBJ (with `vt`) as it is, or flattens every piece of a design or 3D mesh.
pub fn load_flat(
    path: &Path,
    tol: &Tolerances,
    params: &FlattenParams,
    limits: Limits,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Vec<Flat>, PipelineError> {
    if flatcut_mesh::io::is_mesh_path(path) {
        if let Some(f) = read_flat_mesh(path, limits)? {
            return Ok(vec![f]);
        }
    }
    flatten_and_report(path, tol, params, limits, progress)
}
