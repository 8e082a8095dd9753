//! Closed surfaces split as left and right pairs (`--symmetry`): where the surface is its own
//! mirror image across a plane within the tolerance ([`flatcut_mesh::symmetry`]), it is cut
//! along the plane ([`flatcut_mesh::halve`]), its first half split as any closed surface's is
//! ([`flatcut_darts::split::split_surface`]), and the other half's pieces made as the mirror
//! images of the first's ([`flatcut_darts::mirror`]). The parts are named `<piece>-<k>L` and
//! `<piece>-<k>R` (a pair: `R` is `L` reversed), their seams `<piece> <k> L/<j> R`, with balance
//! notches as every new seam's. A surface with no such plane is split without symmetry, with a
//! note saying how far it is from one; a plane the user named (an axis, or a point and a normal,
//! taken as given) that is none is an error saying how far the surface is from its mirror image
//! across it and the tolerance.

use flatcut_darts::mirror::{SIDES, mirror_split};
use flatcut_flatten::FlattenParams;
use flatcut_geom::DVec3;
use flatcut_mesh::TriMesh;
use flatcut_mesh::halve::half_of;
use flatcut_mesh::symmetry::{Symmetry, SymmetryOptions, find_mirror, mirror_across};

use crate::error::PipelineError;
use crate::flat_piece::FlatPiece;
use crate::splitting::{
    SplitPieces, SplitSettings, SymmetryMode, into_parts, options, split_surface_piece,
};

/// Splits a closed surface (`whole`) as [`split_surface_piece`] does, as mirrored pairs when
/// `settings.symmetry` asks for them and the surface has a mirror plane; a surface with none is
/// split without symmetry, with a note on its first part.
pub fn split_closed(
    piece: FlatPiece,
    whole: &TriMesh,
    params: &FlattenParams,
    settings: &SplitSettings,
) -> Result<SplitPieces, PipelineError> {
    let note = match split_mirrored(&piece, whole, params, settings)? {
        Ok(pairs) => return Ok(pairs),
        Err(note) => note,
    };
    let mut parts = split_surface_piece(piece, whole, params, settings)?;
    if let (Some(n), Some(first)) = (note, parts.pieces.first_mut()) {
        first.info.warnings.push(n);
    }
    Ok(parts)
}

/// The split of a closed surface (`whole`) as mirrored pairs, or `Ok(None)` with the note to
/// give when the settings ask for none or the surface has no mirror plane within the tolerance
/// (the caller splits it without symmetry). An axis or a plane the user named that is no mirror
/// plane is an error.
pub fn split_mirrored(
    piece: &FlatPiece,
    whole: &TriMesh,
    params: &FlattenParams,
    settings: &SplitSettings,
) -> Result<Result<SplitPieces, Option<String>>, PipelineError> {
    let name = &piece.def.name;
    let (normal, given) = match settings.symmetry.mode {
        SymmetryMode::Off => return Ok(Err(None)),
        SymmetryMode::Auto => (None, None),
        SymmetryMode::Axis(n) => (Some(n), None),
        SymmetryMode::Plane(p) => (None, Some(p)),
    };
    let opts = SymmetryOptions {
        tolerance: settings.symmetry.tolerance,
        normal,
    };
    let best = match given {
        Some(p) => mirror_across(whole, p, opts.tolerance),
        None => find_mirror(whole, &opts),
    };
    let half = best
        .filter(|s| s.accepted)
        .map(|s| (s, half_of(whole, &s.plane)));
    let (sym, half) = match half {
        Some((s, Ok(h))) => (s, h),
        other => {
            let why = match other {
                Some((_, Err(e))) => format!("it cannot be cut along its mirror plane: {e}"),
                _ => no_plane(best, &opts, given.is_some()),
            };
            if normal.is_some() || given.is_some() {
                return Err(PipelineError::Symmetry {
                    piece: name.clone(),
                    reason: why,
                });
            }
            return Ok(Err(Some(format!("{name}: split without symmetry: {why}"))));
        }
    };
    let opts = options(piece, &half.mesh, params, settings)?;
    let stage = params.split_budget(std::time::Instant::now());
    let inside = params.clone().with_within(Some(stage.clone()));
    let darts_err = |source| PipelineError::Darts {
        piece: name.clone(),
        source,
    };
    let first =
        flatcut_darts::split::split_surface(&half.mesh, &inside, &opts).map_err(darts_err)?;
    let on_plane: Vec<DVec3> = half
        .mesh
        .positions
        .iter()
        .zip(&half.on_plane)
        .filter(|(_, on)| **on)
        .map(|(p, _)| *p)
        .collect();
    let n = first.pieces.len();
    let closed = flatcut_mesh::Topology::build(whole).is_ok_and(|t| t.boundary_loops.is_empty());
    let both = mirror_split(first, &sym.plane, &on_plane, closed).map_err(darts_err)?;
    let mut parts = into_parts(piece.clone(), both, settings, &stage)?;
    for (k, p) in parts.pieces.iter_mut().enumerate() {
        p.def.name = format!("{name}-{}{}", k % n + 1, SIDES[k / n]);
    }
    if let Some(first) = parts.pieces.first_mut() {
        first
            .info
            .warnings
            .push(found_note(name, &sym, half.snapped_mm));
    }
    Ok(Ok(parts))
}

/// What the user is told of the plane a mirrored split used.
fn found_note(name: &str, s: &Symmetry, snapped_mm: f64) -> String {
    let (p, n) = (s.plane.point, s.plane.normal);
    format!(
        "{name}: cut as mirrored pairs across the plane through ({:.2}, {:.2}, {:.2}) normal to ({:.4}, {:.4}, {:.4}); the surface is within {:.3} mm of its mirror image (RMS {:.3} mm; the pattern is of its first half and that half's mirror image), and its vertices within {:.3} mm of the plane were moved onto it",
        p.x, p.y, p.z, n.x, n.y, n.z, s.max_mm, s.rms_mm, snapped_mm
    )
}

/// Why no plane was taken: the best one's (or the `given` one's) deviation against the
/// tolerance.
fn no_plane(best: Option<Symmetry>, opts: &SymmetryOptions, given: bool) -> String {
    match best {
        Some(s) => format!(
            "{} leaves it {:.2} mm from its mirror image, beyond the tolerance of {:.2} mm ({} % of its {:.1} mm size; --symmetry-tolerance)",
            if given {
                let (p, n) = (s.plane.point, s.plane.normal);
                format!(
                    "the mirror plane given (through ({:.2}, {:.2}, {:.2}) normal to ({:.4}, {:.4}, {:.4}))",
                    p.x, p.y, p.z, n.x, n.y, n.z
                )
            } else {
                let n = s.plane.normal;
                format!(
                    "its best mirror plane (normal ({:.4}, {:.4}, {:.4}))",
                    n.x, n.y, n.z
                )
            },
            s.max_mm,
            opts.tolerance * s.size_mm,
            opts.tolerance * 100.0,
            s.size_mm
        ),
        None => "it has no area to find a mirror plane of".into(),
    }
}
