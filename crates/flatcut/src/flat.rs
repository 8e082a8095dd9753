//! Flattened pieces with their distortion reports: what every later stage (pattern, nesting,
//! G-code, the report's pictures) starts from, whether the input was a design or an OBJ that
//! already carries its flat map.

use std::path::Path;
use std::time::{Duration, Instant};

use flatcut_design::PieceDef;
use flatcut_flatten::{FlattenInfo, FlattenParams};
use flatcut_geom::Tolerances;
use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::MatingSeam;
use flatcut_report::{MatingSeamReport, Report};

use crate::darting::{self, DartSettings};
use crate::pipeline::{self, FlatDesign, FlatNotch, FlatPiece, PipelineError};
use flatcut_design::material::MaterialSpec;

/// A flattened piece ready for the pattern: its mesh (with `flat`), its design entry when it came
/// from a design, its distortion report (with the mating seams it takes part in) and how the
/// flattening went.
#[derive(Clone, Debug)]
pub struct Flat {
    /// The piece's name.
    pub name: String,
    /// The piece as the design defines it; `None` for a piece read from a mesh file.
    pub def: Option<PieceDef>,
    /// The 3D mesh with its flattening (`flat`, mm).
    pub mesh: TriMesh,
    /// The piece's distortion report.
    pub report: Report,
    /// How many to cut as drawn.
    pub quantity: u32,
    /// How many mirror images to cut besides (`pairs`).
    pub mirrored: u32,
    /// Its notches as boundary vertices of `mesh`.
    pub notches: Vec<FlatNotch>,
    /// Absent when the map was read from a file rather than computed.
    pub info: Option<FlattenInfo>,
    /// The darts cut into the piece to meet its limits.
    pub darts: Vec<flatcut_darts::Dart>,
    /// Its material and the warp's direction in its map, when it was flattened for a material.
    pub grain: Option<crate::material::PieceGrain>,
    /// The grain's direction in the map of a piece without a material whose grain line cannot
    /// be drawn from the design (a part of a split piece).
    pub grain_dir: Option<flatcut_geom::DVec2>,
    /// Where the time went besides the solve (whose parts are in `info`).
    pub times: PieceTimes,
    /// What removing its surface's spikes changed, when asked for ([`crate::despiking`]).
    pub despike: Option<crate::despiking::DespikeRecord>,
}

/// Where a piece's time went besides the flattening's solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PieceTimes {
    /// Reading the input and building its pieces and seams: the whole design's, the same for
    /// each of its pieces.
    pub read: Duration,
    /// Computing the piece's distortion report.
    pub report: Duration,
}

impl Flat {
    /// The piece's flat OBJ, as `flatten` and `run` write it: its name (`o`), the 3D vertices
    /// (`v`), one UV per vertex in mm (`vt`), the faces, then each dart's sew line
    /// ([`crate::dart_lines`]) and each notch ([`crate::notch_points`]) for a later `pattern`,
    /// `report` or `run` to read back.
    pub fn obj(&self) -> String {
        crate::notch_points::write_name(&self.name)
            + &flatcut_mesh::io::obj_string(&self.mesh)
            + &crate::dart_lines::write(&self.darts)
            + &crate::notch_points::write(&self.notches)
    }
}

/// A piece's report as `flatten --report` writes it: the distortion report, and after its keys
/// what removing the surface's spikes changed (`despike`; absent without `--despike`, so the
/// file is as it was).
#[derive(serde::Serialize)]
pub struct WrittenReport<'a> {
    #[serde(flatten)]
    report: &'a Report,
    #[serde(skip_serializing_if = "Option::is_none")]
    despike: Option<&'a crate::despiking::DespikeRecord>,
}

impl Flat {
    /// The piece's report as written ([`WrittenReport`]).
    pub fn written_report(&self) -> WrittenReport<'_> {
        WrittenReport {
            report: &self.report,
            despike: self.despike.as_ref(),
        }
    }
}

/// The heat map's columns: each piece under its name in capitals.
pub fn columns(flats: &[Flat]) -> Vec<flatcut_report::Column<'_>> {
    flats
        .iter()
        .map(|f| flatcut_report::Column {
            title: f.name.to_uppercase(),
            mesh: &f.mesh,
            report: &f.report,
        })
        .collect()
}

/// Stretch and compression limits in percent, checked by the report, and whether darts may be
/// cut to meet the flattening's limits (`None`: only where the design's piece asks for them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Limits {
    /// The largest stretch allowed (percent); `None`: no limit.
    pub stretch_pct: Option<f64>,
    /// The largest compression allowed (percent); `None`: no limit.
    pub compress_pct: Option<f64>,
    /// How darts are cut; `None`: only where the design's piece asks for them.
    pub darts: Option<DartSettings>,
    /// Whether pieces that darts cannot bring within the limits are split into parts sewn
    /// together ([`crate::splitting`]).
    pub split: Option<crate::splitting::SplitSettings>,
    /// The material of every piece that names none itself: its limits per direction and its
    /// stiffness drive the orthotropic flattening ([`crate::material`]).
    pub material: Option<MaterialSpec>,
}

/// Reads a mesh file; when it already carries a flat map (`vt`), returns it as one reported piece
/// named by the OBJ's object statement (`o`, which `flatten` and `run` write) or else after the
/// file, with the darts and notches the OBJ carries. `Ok(None)`: the file is a 3D mesh that
/// still needs flattening.
pub fn read_flat_mesh(path: &Path, limits: &Limits) -> Result<Option<Flat>, PipelineError> {
    let reading = Instant::now();
    let mesh = flatcut_mesh::read_mesh(path)?;
    let Some(x) = &mesh.flat else {
        return Ok(None);
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "piece".into());
    // The name, darts and notches `flatten` wrote with the map (only an OBJ carries them).
    let is_obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    let text = if is_obj {
        std::fs::read_to_string(path).map_err(|source| PipelineError::Read {
            piece: stem.clone(),
            path: path.to_path_buf(),
            source,
        })?
    } else {
        String::new()
    };
    let name = crate::notch_points::read_name(&text).unwrap_or(stem);
    let notches =
        crate::notch_points::read(&text, &mesh).map_err(|reason| PipelineError::NotchPoints {
            piece: name.clone(),
            path: path.to_path_buf(),
            reason,
        })?;
    let darts = if is_obj {
        let drill = limits
            .darts
            .as_ref()
            .map_or(flatcut_darts::DartOptions::DEFAULT_DRILL_OFFSET_MM, |d| {
                d.drill_offset_mm
            });
        crate::dart_lines::read(&text, &mesh, x, drill).map_err(|reason| {
            PipelineError::DartLines {
                piece: name.clone(),
                path: path.to_path_buf(),
                reason,
            }
        })?
    } else {
        Vec::new()
    };
    let read = reading.elapsed();
    let reporting = Instant::now();
    let marks: Vec<u32> = notches.iter().map(|n| n.vertex).collect();
    let report = pipeline::report_piece(
        &name,
        &mesh,
        &marks,
        limits.stretch_pct,
        limits.compress_pct,
    )?;
    let times = PieceTimes {
        read,
        report: reporting.elapsed(),
    };
    Ok(Some(Flat {
        name,
        def: None,
        mesh,
        report,
        quantity: 1,
        mirrored: 0,
        notches,
        info: None,
        darts,
        grain: None,
        grain_dir: None,
        times,
        despike: None,
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
    let design = flatcut_design::Design::load(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    flatten_and_report_loaded(design, base, tol, params, limits, progress)
}

/// [`flatten_and_report`] of a design already loaded (an editor's design in memory); mesh and
/// STEP files it names are resolved against `base`, the design file's directory.
pub fn flatten_and_report_loaded(
    design: flatcut_design::Design,
    base: &Path,
    tol: &Tolerances,
    params: &FlattenParams,
    limits: Limits,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Vec<Flat>, PipelineError> {
    let flat = pipeline::flatten_loaded(
        design,
        base,
        tol,
        params,
        limits.darts.as_ref(),
        limits.split.as_ref(),
        limits.material.as_ref(),
        progress,
    )?;
    report_flat_design(flat, &limits)
}

/// Reports every flattened piece of a design and measures its mating seams into the reports.
fn report_flat_design(flat: FlatDesign, limits: &Limits) -> Result<Vec<Flat>, PipelineError> {
    let FlatDesign {
        pieces,
        seams,
        read,
        ..
    } = flat;
    let mut flats = pieces
        .into_iter()
        .map(
            |FlatPiece {
                 def,
                 mesh,
                 info,
                 notches,
                 darts,
                 grain,
                 grain_dir,
                 despike,
             }| {
                let marks: Vec<u32> = notches.iter().map(|n| n.vertex).collect();
                let reporting = Instant::now();
                let mut report = pipeline::report_piece(
                    &def.name,
                    &mesh,
                    &marks,
                    limits.stretch_pct,
                    limits.compress_pct,
                )?;
                report.darts = darting::dart_reports(&darts);
                report.set_grain(
                    grain
                        .as_ref()
                        .and_then(|g| crate::material::report(g, &mesh)),
                );
                let times = PieceTimes {
                    read,
                    report: reporting.elapsed(),
                };
                Ok(Flat {
                    name: def.name.clone(),
                    quantity: def.quantity,
                    mirrored: def.mirrored,
                    def: Some(def),
                    mesh,
                    report,
                    notches,
                    info: Some(info),
                    darts,
                    grain,
                    grain_dir,
                    times,
                    despike,
                })
            },
        )
        .collect::<Result<Vec<Flat>, PipelineError>>()?;
    attach_seams(&mut flats, &seams);
    Ok(flats)
}

/// Measures every mating seam and lists it in the reports of the pieces on its sides.
pub fn attach_seams(flats: &mut [Flat], seams: &[MatingSeam]) {
    let all: Vec<usize> = (0..flats.len()).collect();
    attach_seams_among(flats, &all, seams);
}

/// [`attach_seams`] for seams whose sides index `idx` (piece k of a seam is `flats[idx[k]]`).
fn attach_seams_among(flats: &mut [Flat], idx: &[usize], seams: &[MatingSeam]) {
    let reports: Vec<(usize, usize, MatingSeamReport)> = {
        let meshes: Vec<&TriMesh> = idx.iter().map(|&k| &flats[k].mesh).collect();
        let names: Vec<&str> = idx.iter().map(|&k| flats[k].name.as_str()).collect();
        let def = idx.iter().find_map(|&k| flats[k].def.as_ref());
        let costs = crate::splitting::seam_costs(&meshes, seams, def);
        seams
            .iter()
            .zip(costs)
            .filter_map(|(s, c)| {
                let mut r = flatcut_report::measure_seam(s, &meshes, &names)?;
                r.visibility_cost_mm = Some(c.visible_mm);
                r.turning_deg = Some(c.turning_rad.to_degrees());
                Some((idx[s.sides[0].piece], idx[s.sides[1].piece], r))
            })
            .collect()
    };
    for (a, b, r) in reports {
        if a != b {
            flats[b].report.mating_seams.push(r.clone());
        }
        flats[a].report.mating_seams.push(r);
    }
}

/// Gives pieces of the same name from different inputs (`sources[k]` is where `flats[k]` came
/// from) names apart by adding their input's path: `"vamp (a/vamp.obj)"`. A name no other piece
/// has is kept as it is, so seams read from files are named by their pieces.
pub fn tell_apart(flats: &mut [Flat], sources: &[&Path]) {
    let clash: Vec<bool> = (0..flats.len())
        .map(|k| {
            (0..flats.len())
                .any(|j| j != k && flats[j].name == flats[k].name && sources[j] != sources[k])
        })
        .collect();
    for ((f, source), clash) in flats.iter_mut().zip(sources).zip(clash) {
        if clash {
            f.name = format!("{} ({})", f.name, source.display());
        }
    }
}

/// Pairs flattened meshes read from files (no design) by their coincident boundary vertices (the
/// `OUT-<piece>.obj` files of one split surface carry a seam's vertices at identical
/// coordinates on both sides) and lists each such seam in both pieces' reports, with the notches
/// the files carry on its vertices.
pub fn pair_coincident(flats: &mut [Flat]) {
    let idx: Vec<usize> = (0..flats.len())
        .filter(|&k| flats[k].def.is_none())
        .collect();
    let mut seams = {
        let meshes: Vec<&TriMesh> = idx.iter().map(|&k| &flats[k].mesh).collect();
        let names: Vec<&str> = idx.iter().map(|&k| flats[k].name.as_str()).collect();
        flatcut_mesh::mating::coincident_seams(&meshes, &names)
    };
    for s in &mut seams {
        s.notches = seam_notches(s, |k| &flats[idx[k]].notches);
    }
    attach_seams_among(flats, &idx, &seams);
}

/// The notches on a seam found between files: each seam vertex where either side's piece has a
/// notch (the first side's name when both do), in order along the seam.
fn seam_notches<'a>(
    seam: &MatingSeam,
    notches_of: impl Fn(usize) -> &'a [FlatNotch],
) -> Vec<flatcut_mesh::mating::SeamNotch> {
    let n = seam.sides[0]
        .vertices
        .len()
        .min(seam.sides[1].vertices.len());
    (0..n)
        .filter_map(|index| {
            seam.sides.iter().find_map(|side| {
                let v = side.vertices[index];
                notches_of(side.piece)
                    .iter()
                    .find(|m| m.vertex == v)
                    .map(|m| flatcut_mesh::mating::SeamNotch {
                        name: m.name.clone(),
                        index,
                    })
            })
        })
        .collect()
}

/// The mating seams of the pieces (each once, in the order of the pieces that list them).
pub fn mating_seams(flats: &[Flat]) -> Vec<MatingSeamReport> {
    let mut out: Vec<MatingSeamReport> = Vec::new();
    for f in flats {
        for s in &f.report.mating_seams {
            if !out.iter().any(|o| o.name == s.name && o.pieces == s.pieces) {
                out.push(s.clone());
            }
        }
    }
    out
}

/// One line per piece whose strain along, across or on the bias of its grain breaks its
/// material's limits (a piece flattened with a material file).
pub fn materials_over(flats: &[Flat]) -> Vec<String> {
    flats
        .iter()
        .filter_map(|f| {
            f.report
                .grain
                .as_ref()
                .filter(|g| !g.within())
                .map(|g| (f, g))
        })
        .map(|(f, g)| {
            format!(
                "{}: {} faces over {}'s limits, by up to {:.2} points (stretch/compression % along \
                 {:.2}/{:.2} of {:.1}/{:.1}, across {:.2}/{:.2} of {:.1}/{:.1}, bias {:.2}/{:.2} \
                 of {:.1}/{:.1})",
                f.name,
                g.faces_over_material_limits,
                g.material,
                g.material_excess_pct,
                g.stretch_max_pct_along,
                g.compress_max_pct_along,
                g.limit_stretch_pct_along,
                g.limit_compress_pct_along,
                g.stretch_max_pct_across,
                g.compress_max_pct_across,
                g.limit_stretch_pct_across,
                g.limit_compress_pct_across,
                g.stretch_max_pct_bias,
                g.compress_max_pct_bias,
                g.limit_stretch_pct_bias,
                g.limit_compress_pct_bias,
            )
        })
        .collect()
}

/// One line per mating seam whose sides (or a notch's offsets) differ by more than
/// `tolerance_mm` in the plane.
pub fn seams_over(flats: &[Flat], tolerance_mm: f64) -> Vec<String> {
    mating_seams(flats)
        .iter()
        .filter(|s| s.worst_mm() > tolerance_mm)
        .map(|s| {
            format!(
                "mating seam '{}' ({} / {}): the sides differ by {:.3} mm in length ({:.2} / {:.2} mm), notches by up to {:.3} mm (tolerance {tolerance_mm} mm)",
                s.name,
                s.pieces[0],
                s.pieces[1],
                s.mismatch_mm,
                s.length_2d_mm[0],
                s.length_2d_mm[1],
                s.notches
                    .iter()
                    .map(|n| (n.offset_mm[0] - n.offset_mm[1]).abs())
                    .fold(0.0, f64::max)
            )
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
    if flatcut_mesh::io::is_mesh_path(path)
        && let Some(f) = read_flat_mesh(path, &limits)?
    {
        return Ok(vec![f]);
    }
    flatten_and_report(path, tol, params, limits, progress)
}
