//! Pieces split by seams where darts cannot bring them within their limits (`--split auto`).
//! Where the cuts go is [`flatcut_darts::split`]'s; here each part becomes a piece of the
//! pattern: named `<piece>-1`, `<piece>-2`, … (numbered as the cuts made them), with its share of
//! the piece's marks and notches, the piece's grain, and two balance notches on every new seam at
//! a third and two thirds of its length (one on a seam too short for two well apart), so the
//! sewer matches the parts point to point. A surface that is not a disk (closed, of any genus, or
//! with several boundary loops) is opened first ([`flatcut_darts::open`]); the design's
//! `seam_hidden` direction, `seam_hidden_regions` and `no_cut` regions say where its seams go
//! ([`flatcut_darts::seam_cost`]), and every seam's length and visibility-weighted length are
//! kept for the report.

use flatcut_darts::DartError;
use flatcut_darts::seam_cost::{SeamCost, Visibility};
use flatcut_darts::split::{SplitOptions, split};
use flatcut_design::{MarkDef, PieceDef};
use flatcut_flatten::{Budget, FlattenParams};
use flatcut_geom::DVec3;
use flatcut_mesh::TriMesh;
use flatcut_mesh::grain_strain::{central_face, centroid, pattern_direction_near};
use flatcut_mesh::mating::{MatingSeam, SeamNotch, arc_lengths};
use flatcut_mesh::symmetry::MirrorPlane;

use crate::darting;
use crate::error::PipelineError;
use crate::flat_piece::{FlatNotch, FlatPiece};

/// How pieces are split when asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitSettings {
    /// Most parts one piece may become.
    pub max_pieces: usize,
    /// CPU time of the process after which a piece's best split so far is taken, with a
    /// warning (`flatcut_darts::clock`).
    pub time_limit: Option<std::time::Duration>,
    /// The seam allowance (mm) of pieces whose design gives none: merged parts keep no neck
    /// narrower than twice the allowance.
    pub seam_allowance_mm: f64,
    /// Whether a closed surface is split as mirrored left and right pairs.
    pub symmetry: SymmetrySettings,
    /// Whether the spikes of a piece are removed before it is flattened and split, and the
    /// largest move of a vertex (mm) when they are ([`crate::despiking`]).
    pub despike_max_mm: Option<f64>,
}

/// Whether a closed surface's split looks for a mirror plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SymmetryMode {
    /// Split without symmetry (the default: a mirrored layout can take more pieces than the
    /// fewest, as a ball's tennis-ball halves are no mirror pair).
    Off,
    /// The best plane through the principal axes, taken when within the tolerance; a surface
    /// with none is split without symmetry, with a note.
    Auto,
    /// A plane normal to this axis (through the surface's middle, refined), taken when within
    /// the tolerance; an error otherwise.
    Axis(DVec3),
    /// This plane, as it is (a point and a normal: a plane off the coordinate planes or the
    /// surface's middle), taken when within the tolerance; an error otherwise.
    Plane(MirrorPlane),
}

impl SymmetryMode {
    /// The names of the modes a word selects (`--symmetry`, a project's `symmetry`).
    pub const NAMES: [&'static str; 5] = ["off", "auto", "x", "y", "z"];

    /// The mode named `name` (one of [`Self::NAMES`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "off" => Some(Self::Off),
            "auto" => Some(Self::Auto),
            "x" => Some(Self::Axis(DVec3::X)),
            "y" => Some(Self::Axis(DVec3::Y)),
            "z" => Some(Self::Axis(DVec3::Z)),
            _ => None,
        }
    }

    /// The plane through the point `[x, y, z]` (mm) normal to `[nx, ny, nz]` (of any length)
    /// (`--symmetry-plane`, a project's `symmetry_plane`), or why there is none: a number that
    /// is not finite or beyond the coordinates' range, or a normal of no length.
    pub fn plane(v: [f64; 6]) -> Result<Self, String> {
        if let Some(bad) = v.iter().find(|x| !flatcut_geom::limits::in_range(**x)) {
            return Err(flatcut_geom::limits::out_of_range_reason(*bad));
        }
        let [x, y, z, nx, ny, nz] = v;
        MirrorPlane::new(DVec3::new(x, y, z), DVec3::new(nx, ny, nz))
            .map(Self::Plane)
            .ok_or_else(|| format!("the normal ({nx}, {ny}, {nz}) has no direction"))
    }
}

/// How a split looks for symmetry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SymmetrySettings {
    /// Whether, and across which axis.
    pub mode: SymmetryMode,
    /// Largest deviation of the surface from its mirror image, as a share of its bounding box
    /// diagonal (`flatcut_mesh::symmetry::DEFAULT_TOLERANCE`).
    pub tolerance: f64,
}

impl Default for SymmetrySettings {
    fn default() -> Self {
        Self {
            mode: SymmetryMode::Off,
            tolerance: flatcut_mesh::symmetry::DEFAULT_TOLERANCE,
        }
    }
}

impl Default for SplitSettings {
    fn default() -> Self {
        Self {
            max_pieces: SplitOptions::DEFAULT_MAX_PIECES,
            time_limit: None,
            seam_allowance_mm: 0.0,
            symmetry: SymmetrySettings::default(),
            despike_max_mm: None,
        }
    }
}

/// Where the balance notches of a new seam sit, as fractions of its length.
const BALANCE_NOTCHES: [f64; 2] = [1.0 / 3.0, 2.0 / 3.0];

/// A piece split into parts and the seams between them (sides index `pieces`).
#[derive(Clone, Debug)]
pub struct SplitPieces {
    /// The parts, in the order the cuts made them (part `k` is named `<piece>-<k+1>`), each with
    /// its share of the marks and notches and the balance notches of its new seams; the piece
    /// itself, alone, when it needed no split.
    pub pieces: Vec<FlatPiece>,
    /// The new seams between parts, named `<piece> <seam>`; each side's `piece` is a 0-based
    /// index into `pieces`. Empty when the piece came back whole.
    pub seams: Vec<MatingSeam>,
    /// Total 3D length of the cuts (mm).
    pub cut_mm: f64,
}

/// Splits a flattened piece that is beyond the limits of `params` (a piece within them, or
/// already darted, comes back whole). Fails, as darts do, when no split into at most
/// `settings.max_pieces` parts brings every face within the limits.
pub fn split_piece(
    piece: FlatPiece,
    params: &FlattenParams,
    settings: &SplitSettings,
) -> Result<SplitPieces, PipelineError> {
    let whole = |piece| SplitPieces {
        pieces: vec![piece],
        seams: Vec::new(),
        cut_mm: 0.0,
    };
    let limited = params.max_stretch_pct.is_some() || params.max_compress_pct.is_some();
    let Some(uv) = piece.mesh.flat.clone() else {
        return Ok(whole(piece));
    };
    // A piece that overlaps itself flat is split like one beyond its limits, or refused.
    let crossing = darting::no_crossing(&piece.def.name, &piece.mesh);
    if !limited || !piece.darts.is_empty() {
        crossing?;
        return Ok(whole(piece));
    }
    if crossing.is_ok() && darting::within(&piece.mesh, &uv, params, None) {
        return Ok(whole(piece));
    }
    let opts = options(&piece, &piece.mesh, params, settings)?;
    // Every flattening of the split draws on one stage: the split's.
    let stage = params.split_budget(std::time::Instant::now());
    let inside = params.clone().with_within(Some(stage.clone()));
    let s = split(&piece.mesh, &uv, &inside, &opts).map_err(|source| PipelineError::Darts {
        piece: piece.def.name.clone(),
        source,
    })?;
    into_parts(piece, s, settings, &stage)
}

/// Splits a piece whose surface (`whole`) is not a disk — closed (a ball, a plush toy), of any
/// genus (a ring, a boot with eyelets) or with several boundary loops — into parts within the
/// limits of `params`: it is opened first ([`flatcut_darts::split::split_surface`]); `piece`
/// carries its design (its mesh is not used).
pub fn split_surface_piece(
    piece: FlatPiece,
    whole: &TriMesh,
    params: &FlattenParams,
    settings: &SplitSettings,
) -> Result<SplitPieces, PipelineError> {
    let opts = options(&piece, whole, params, settings)?;
    let stage = params.split_budget(std::time::Instant::now());
    let inside = params.clone().with_within(Some(stage.clone()));
    let s = flatcut_darts::split::split_surface(whole, &inside, &opts).map_err(|source| {
        PipelineError::Darts {
            piece: piece.def.name.clone(),
            source,
        }
    })?;
    into_parts(piece, s, settings, &stage)
}

/// True for a surface no flattening takes as it is but an opening can: one that is not a disk
/// because it is closed, has handles or several boundary loops, or several parts.
pub fn needs_opening(mesh: &TriMesh) -> bool {
    use flatcut_mesh::TopologyError as E;
    matches!(
        flatcut_mesh::check_disk(mesh),
        Err(E::NoBoundary
            | E::SeveralBoundaries { .. }
            | E::NotADisk { .. }
            | E::SeveralComponents { .. })
    )
}

/// Where seams should hide on `mesh`, from the piece's design: its `seam_hidden` direction and
/// `seam_hidden_regions` (no_cut regions are the keep-out's).
pub fn visibility(def: &PieceDef, mesh: &TriMesh) -> Result<Visibility, PipelineError> {
    let mut hidden = flatcut_darts::KeepOut::none(mesh);
    for (i, region) in def.seam_hidden_regions.iter().enumerate() {
        let pts: Vec<DVec3> = region.iter().map(|p| DVec3::from_array(*p)).collect();
        hidden
            .block_region(mesh, &pts, i)
            .map_err(|source| PipelineError::SeamHidden {
                piece: def.name.clone(),
                index: i,
                source,
            })?;
    }
    Ok(Visibility {
        hidden_dir: def
            .seam_hidden
            .and_then(|d| DVec3::from_array(d).try_normalize()),
        hidden: if def.seam_hidden_regions.is_empty() {
            Vec::new()
        } else {
            hidden.blocked
        },
        blocked: Vec::new(),
    })
}

/// What a split of `piece` (its surface `mesh`) is for: the limits of `params`, the most parts,
/// and the design's no_cut regions and marks kept out of the cuts.
pub(crate) fn options(
    piece: &FlatPiece,
    mesh: &TriMesh,
    params: &FlattenParams,
    settings: &SplitSettings,
) -> Result<SplitOptions, PipelineError> {
    Ok(SplitOptions {
        band: flatcut_darts::Band::from_pct(params.max_stretch_pct, params.max_compress_pct),
        max_pieces: settings.max_pieces,
        keep_out: Some(darting::keep_out(Some(&piece.def), mesh)?),
        visibility: visibility(&piece.def, mesh)?,
        time_limit: settings.time_limit,
        seam_allowance_mm: piece
            .def
            .seam_allowance_mm
            .unwrap_or(settings.seam_allowance_mm),
    })
}

/// What a split beyond the limits says of the surface's vertices beyond reach
/// ([`flatcut_darts::split::Split::beyond_reach`]): how many, and where the worst is, and the
/// remedy (or what `despiked`, the repair already made, moved and left); empty when the split
/// is within the limits or the surface has none.
fn spikes_note(
    s: &flatcut_darts::split::Split,
    despiked: Option<&crate::despiking::DespikeRecord>,
) -> String {
    let remedy = match despiked {
        None => "--despike (a project's despike = true) moves such spikes back into the surface before the split, within --despike-max-mm".to_string(),
        Some(d) => format!(
            "--despike moved {} vertices, at most {:.3} mm, and left {} beyond reach within --despike-max-mm; a larger one may move them",
            d.moved, d.max_mm, d.left
        ),
    };
    match s.beyond_reach.first() {
        Some(p) if !s.feasible => format!(
            "; {} vertices of the surface have more angle defect than the faces round them can absorb within the limits (a scan's spikes; the worst at ({:.1}, {:.1}, {:.1})): no part within the limits holds one inside, so only a seam through every one of them meets the limits; {remedy}",
            s.beyond_reach.len(),
            p.x,
            p.y,
            p.z
        ),
        _ => String::new(),
    }
}

/// The parts of a split as pieces of the pattern, or the error saying what was reached.
pub(crate) fn into_parts(
    piece: FlatPiece,
    s: flatcut_darts::split::Split,
    settings: &SplitSettings,
    stage: &Budget,
) -> Result<SplitPieces, PipelineError> {
    let name = piece.def.name.clone();
    let count = stage.count();
    // The stand-in's own warnings do not carry over to the parts.
    let mut timed_out_warning = None;
    let spikes = spikes_note(&s, piece.despike.as_ref());
    if s.seams_apart {
        // No joint solve of the parts finished in the time: their seams are not yet equal.
        timed_out_warning = Some(format!(
            "{name}: the split's time limit stopped the joint solve of its {} parts before their seams agreed; this is the best cut found, its seams not yet sewable (a longer --split-time solves them){spikes}",
            s.pieces.len()
        ));
    } else if s.timed_out && s.feasible {
        // Every part within the limits; the time ran out before all could be tried sewn back.
        timed_out_warning = Some(format!(
            "{name}: the split's time limit ended the merging of parts at {} parts, every one within the limits; fewer might do",
            s.pieces.len()
        ));
    } else if s.timed_out {
        // The best split found in the time: written, its excess left to the report's check.
        timed_out_warning = Some(format!(
            "{name}: the split's time limit ended the search at {} parts, {:.2} % beyond the limits near ({:.1}, {:.1}, {:.1}); this is the best split found{spikes}",
            s.pieces.len(),
            flatcut_darts::excess_pct(s.excess),
            s.worst_3d.x,
            s.worst_3d.y,
            s.worst_3d.z
        ));
    } else if !s.feasible {
        return Err(PipelineError::Darts {
            piece: name,
            source: DartError::Infeasible {
                darts: 0,
                excess: s.excess,
                at: s.worst_3d,
                reason: format!(
                    "{}{}{spikes}",
                    if s.pieces.len() < settings.max_pieces {
                        // Parts to spare: the worst part has no cut left that relieves it.
                        format!(
                            "split into {} parts, the worst has no cut left that brings it within them",
                            s.pieces.len()
                        )
                    } else {
                        format!(
                            "no split into at most {} parts brought every face within them",
                            settings.max_pieces
                        )
                    },
                    if count.stopped {
                        format!(
                            " before the split stopped at its cap ({count}; --max-iters, --flatten-time)"
                        )
                    } else {
                        String::new()
                    }
                ),
            },
        });
    }
    let cut_mm = s.total_cut_mm();
    let grain_3d = grain_direction(&piece);
    let mut parts: Vec<FlatPiece> = s
        .pieces
        .iter()
        .enumerate()
        .map(|(k, mesh)| part(&piece, k, mesh, &s.pieces, grain_3d))
        .collect();
    for p in &mut parts {
        p.info.iterations += count.iterations;
        p.info.stages.push(count.clone());
    }
    let mut seams = s.seams;
    for seam in &mut seams {
        seam.name = format!("{name} {}", seam.name);
        let pts = seam.points_3d(0, &s.pieces.iter().collect::<Vec<_>>());
        let cum = arc_lengths(&pts, |a, b| a.distance(*b));
        for (j, index) in balance_indices(&cum).into_iter().enumerate() {
            let notch = format!("{} {}", seam.name, j + 1);
            for side in &seam.sides {
                parts[side.piece].notches.push(FlatNotch {
                    name: notch.clone(),
                    vertex: side.vertices[index],
                });
            }
            seam.notches.push(SeamNotch { name: notch, index });
        }
    }
    if let (Some(w), Some(first)) = (timed_out_warning, parts.first_mut()) {
        first.info.warnings.push(w);
    }
    Ok(SplitPieces {
        pieces: parts,
        seams,
        cut_mm,
    })
}

/// The seam vertices (indices into `cum`, the arc length from the seam's start to each) that
/// carry its balance notches: the inner vertex nearest each of [`BALANCE_NOTCHES`], dropped
/// where it is a seam end or within a sixth of the seam's length of a notch already kept (a
/// short seam of few vertices gets one notch rather than two at one place).
fn balance_indices(cum: &[f64]) -> Vec<usize> {
    let total = cum.last().copied().unwrap_or(0.0);
    let mut out: Vec<usize> = Vec::new();
    for f in BALANCE_NOTCHES {
        let Some((index, _)) = cum
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - f * total).abs().total_cmp(&(b.1 - f * total).abs()))
        else {
            continue;
        };
        let inner = index > 0 && index + 1 < cum.len();
        if inner
            && out
                .iter()
                .all(|&k| (cum[k] - cum[index]).abs() >= total / 6.0)
        {
            out.push(index);
        }
    }
    out
}

/// What each seam costs as a seam (length, visibility-weighted length, turning): the pieces
/// welded by their coincident vertices into the surface they were cut from, its visibility
/// factors taken with the design of `def` (its hidden side and regions; curvature alone
/// without one).
pub fn seam_costs(
    meshes: &[&TriMesh],
    seams: &[MatingSeam],
    def: Option<&PieceDef>,
) -> Vec<SeamCost> {
    if seams.is_empty() {
        return Vec::new();
    }
    let mut all = TriMesh::default();
    for m in meshes {
        let base = all.positions.len() as u32;
        all.positions.extend_from_slice(&m.positions);
        all.triangles
            .extend(m.triangles.iter().map(|t| t.map(|v| v + base)));
    }
    let (positions, map) = flatcut_mesh::weld::weld_points(&all.positions, 0.0);
    let surface = TriMesh::new(
        positions,
        all.triangles
            .iter()
            .map(|t| t.map(|v| map[v as usize]))
            .collect(),
    );
    let vis = def
        .and_then(|d| visibility(d, &surface).ok())
        .unwrap_or_default();
    let factors = vis.vertex_factors(&surface);
    seams
        .iter()
        .map(|s| SeamCost::of_points(&surface, &factors, &s.points_3d(0, meshes)))
        .collect()
}

/// The 3D grain of a piece: its material's warp where the flattening chose or followed one, else
/// the direction of the design's grain line.
fn grain_direction(piece: &FlatPiece) -> Option<DVec3> {
    if let Some(g) = &piece.grain {
        let uv = piece.mesh.flat.as_deref()?;
        let t = central_face(&piece.mesh)?;
        return flatcut_mesh::grain_strain::warp_at(&piece.mesh, uv, g.pattern_dir, t);
    }
    let [a, b] = piece.def.grain.as_ref()?.line().copied()?;
    (DVec3::from_array(b) - DVec3::from_array(a)).try_normalize()
}

/// Part `k` of a split piece as a piece of its own.
fn part(
    piece: &FlatPiece,
    k: usize,
    mesh: &TriMesh,
    all: &[TriMesh],
    grain_3d: Option<DVec3>,
) -> FlatPiece {
    let mut def: PieceDef = piece.def.clone();
    def.name = format!("{}-{}", piece.def.name, k + 1);
    def.marks = piece
        .def
        .marks
        .iter()
        .flat_map(|m| marks_on(m, k, all))
        .collect();
    // The grain is a direction on a part: drawn through its middle (`grain_dir`), since the
    // piece's grain line may lie on another part.
    def.grain = None;
    let uv = mesh.flat.as_deref().unwrap_or_default();
    let grain_dir = grain_3d.and_then(|d| {
        let t = central_face(mesh)?;
        pattern_direction_near(mesh, uv, d, centroid(mesh, t), 0.0)
    });
    let notches = piece
        .notches
        .iter()
        .filter_map(|n| {
            let p = piece.mesh.positions[n.vertex as usize];
            let v = mesh.positions.iter().position(|q| *q == p)?;
            Some(FlatNotch {
                name: n.name.clone(),
                vertex: v as u32,
            })
        })
        .collect();
    let mut info = piece.info.clone();
    info.warnings.clear();
    FlatPiece {
        def,
        mesh: mesh.clone(),
        info,
        notches,
        darts: Vec::new(),
        grain: piece.grain.clone().map(|mut g| {
            g.pattern_dir = grain_dir.unwrap_or(g.pattern_dir);
            g
        }),
        grain_dir: grain_dir.filter(|_| piece.grain.is_none()),
        despike: piece.despike.clone(),
    }
}

/// The stretches of mark `m` that lie on part `k` (each point goes to the part whose surface is
/// nearest it; a line crossing a cut becomes one line per part it crosses).
fn marks_on(m: &MarkDef, k: usize, all: &[TriMesh]) -> Vec<MarkDef> {
    let owner = |p: &[f64; 3]| {
        let p = DVec3::from_array(*p);
        (0..all.len())
            .min_by(|&a, &b| nearest(&all[a], p).total_cmp(&nearest(&all[b], p)))
            .unwrap_or(0)
    };
    let mut out: Vec<MarkDef> = Vec::new();
    let mut run: Vec<[f64; 3]> = Vec::new();
    for p in &m.points {
        if owner(p) == k {
            run.push(*p);
        } else if !run.is_empty() {
            out.push(MarkDef {
                points: std::mem::take(&mut run),
                ..m.clone()
            });
        }
    }
    if !run.is_empty() {
        out.push(MarkDef {
            points: run,
            ..m.clone()
        });
    }
    out
}

/// Distance from `p` to the mesh's nearest vertex (a part's surface is fine against its
/// neighbour's: the cut between them is the only place both are near).
fn nearest(mesh: &TriMesh, p: DVec3) -> f64 {
    mesh.positions
        .iter()
        .map(|q| q.distance_squared(p))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balance_notches_sit_at_thirds_on_distinct_spaced_vertices() {
        // Evenly sampled: the vertices at a third and two thirds.
        let even: Vec<f64> = (0..=9).map(|i| 3.0 * i as f64).collect();
        assert_eq!(balance_indices(&even), vec![3, 6]);
        // A 28.7 mm seam of three vertices: a third (9.6) and two thirds (19.1) are both
        // nearest the middle vertex; one notch, not two at one place.
        assert_eq!(balance_indices(&[0.0, 10.0, 28.7]), vec![1]);
        // Two inner vertices 0.6 mm apart near the middle: one notch.
        assert_eq!(balance_indices(&[0.0, 14.0, 14.6, 28.7]), vec![1]);
        // A seam of one edge has no inner vertex.
        assert!(balance_indices(&[0.0, 28.7]).is_empty());
        assert!(balance_indices(&[]).is_empty());
    }
}
