//! Flattening a design: load it (or a mesh or STEP model), build its pieces and seams, and
//! flatten them with their material, darts and splits, measured by the report.
//!
//! Every size of a graded design is flattened, its pieces named `<piece> <size>`, into
//! [`crate::flat_piece::FlatPiece`]s.

use std::path::Path;
use std::time::{Duration, Instant};

use flatcut_design::material::MaterialSpec;
use flatcut_design::{Design, PieceDef};
use flatcut_flatten::FlattenParams;
use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::MatingSeam;
use flatcut_report::Report;

use crate::darting::{self, DartLimits, DartSettings};
use crate::error::PipelineError;
use crate::flat_piece::{FlatNotch, FlatPiece};

/// Refuses a design whose piece names collide, exactly or once made safe for ids and file
/// names (`a/b` and `a_b` both become `a_b`): their SVG ids, DXF blocks and per-piece files
/// would overwrite each other. Renaming silently would put a name on the cut piece that is in
/// no design, so the design must say which is which.
pub fn check_unique_names(design: &Design) -> Result<(), PipelineError> {
    let mut seen: std::collections::BTreeMap<String, &str> = Default::default();
    let names = design.pieces.iter().map(|p| p.name.as_str()).chain(
        design
            .parts
            .iter()
            .flat_map(|p| p.pieces.iter().map(|q| q.name.as_str())),
    );
    for name in names {
        let safe = flatcut_pattern::safe_name(name);
        if let Some(first) = seen.insert(safe.clone(), name) {
            return Err(PipelineError::NameClash {
                file: design.source.clone(),
                first: first.to_string(),
                second: name.to_string(),
                safe,
            });
        }
    }
    Ok(())
}

/// A design flattened: every piece (a `[[piece]]` or a region of a `[[part]]`) and the mating
/// seams between them (sides index `pieces`).
#[derive(Clone, Debug)]
pub struct FlatDesign {
    /// The design, lengths in mm.
    pub design: Design,
    /// The flattened pieces, in the design's piece order.
    pub pieces: Vec<FlatPiece>,
    /// The mating seams between pieces; their sides index `pieces`.
    pub seams: Vec<MatingSeam>,
    /// Time spent reading the surfaces and building the pieces and seams (every size's), before
    /// any flattening.
    pub read: Duration,
}

/// Loads a design (or a mesh file), builds its pieces and seams, and flattens them, the pieces
/// joined by seams together ([`flatcut_flatten::assembly`]); `progress(piece, index, count)` is
/// called for each piece before the solve. A graded design is flattened in every size, each
/// with its own lines, notches, seams and limits: its pieces are named `<piece> <size>` (their
/// `def.size` says which) and its seams `<seam> <size>`, size after size in the grading's order.
pub fn flatten_design(
    path: &Path,
    tol: &Tolerances,
    params: &FlattenParams,
    darts: Option<&DartSettings>,
    split: Option<&crate::splitting::SplitSettings>,
    material: Option<&MaterialSpec>,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<FlatDesign, PipelineError> {
    let design = Design::load(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    flatten_loaded(design, base, tol, params, darts, split, material, progress)
}

/// [`flatten_design`] of a design already loaded (an editor's design in memory); mesh and STEP
/// files it names are resolved against `base`, the design file's directory.
#[allow(clippy::too_many_arguments)]
pub fn flatten_loaded(
    design: Design,
    base: &Path,
    tol: &Tolerances,
    params: &FlattenParams,
    darts: Option<&DartSettings>,
    split: Option<&crate::splitting::SplitSettings>,
    material: Option<&MaterialSpec>,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<FlatDesign, PipelineError> {
    check_unique_names(&design)?;
    let sizes = design.sizes(base)?;
    let count = sizes.len();
    let mut out = FlatDesign {
        design: design.clone(),
        pieces: Vec::new(),
        seams: Vec::new(),
        read: Duration::ZERO,
    };
    for sized in sizes {
        let first = out.pieces.len();
        let (mut pieces, mut seams, read) = match &sized.size {
            None => flatten_one(
                &sized.design,
                &sized.dir,
                tol,
                params,
                darts,
                split,
                material,
                progress,
            )?,
            Some(size) => flatten_one(
                &sized.design,
                &sized.dir,
                tol,
                params,
                darts,
                split,
                material,
                &mut |name, k, n| progress(&format!("{name} {size}"), first + k, n * count),
            )?,
        };
        if let Some(size) = &sized.size {
            for p in &mut pieces {
                p.def.size = Some(flatcut_design::PieceSize {
                    size: size.clone(),
                    piece: p.def.name.clone(),
                });
                p.def.name = format!("{} {size}", p.def.name);
            }
            for s in &mut seams {
                s.name = format!("{} {size}", s.name);
            }
        }
        for s in &mut seams {
            s.sides.iter_mut().for_each(|side| side.piece += first);
        }
        out.pieces.extend(pieces);
        out.seams.extend(seams);
        out.read += read;
    }
    let mut seen = std::collections::BTreeMap::new();
    for p in &out.pieces {
        let safe = flatcut_pattern::safe_name(&p.def.name);
        if let Some(first) = seen.insert(safe.clone(), p.def.name.clone()) {
            return Err(PipelineError::NameClash {
                file: design.source.clone(),
                first,
                second: p.def.name.clone(),
                safe,
            });
        }
    }
    Ok(out)
}

/// The pieces and seams of one design (one size), flattened, and the time spent reading and
/// building them.
#[allow(clippy::too_many_arguments)]
fn flatten_one(
    design: &Design,
    base: &Path,
    tol: &Tolerances,
    params: &FlattenParams,
    darts: Option<&DartSettings>,
    split: Option<&crate::splitting::SplitSettings>,
    material: Option<&MaterialSpec>,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<(Vec<FlatPiece>, Vec<MatingSeam>, Duration), PipelineError> {
    let reading = Instant::now();
    let mut asm = design.assemble(base, tol)?;
    let read = reading.elapsed();
    // A scan's spikes removed first, when asked for: the opening, the flattening and the split
    // all see the repaired surface.
    let despiked = despike_pieces(&mut asm, base, params, split, material)?;
    // Nothing flattens a surface that is not a disk (closed, of any genus, with several
    // boundary loops): one that may be split is flattened opened here as a stand-in and split
    // from the whole afterwards ([`crate::splitting::split_surface_piece`]).
    let mut closed: std::collections::BTreeMap<usize, TriMesh> = Default::default();
    if split.is_some() {
        for (k, p) in asm.pieces.iter_mut().enumerate() {
            if crate::splitting::needs_opening(&p.mesh) {
                let opened = flatcut_darts::open::open_surface(&p.mesh, &Default::default())
                    .map_err(|source| PipelineError::Darts {
                        piece: p.def.name.clone(),
                        source,
                    })?;
                let stand_in = opened.pieces.into_iter().next().unwrap_or_default();
                closed.insert(k, std::mem::replace(&mut p.mesh, stand_in));
            }
        }
    }
    for (k, p) in asm.pieces.iter().enumerate() {
        progress(&p.def.name, k, asm.pieces.len());
    }
    let joined: Vec<bool> = (0..asm.pieces.len())
        .map(|k| {
            asm.seams
                .iter()
                .any(|s| s.sides.iter().any(|d| d.piece == k))
        })
        .collect();
    let materials = asm
        .pieces
        .iter()
        .map(|p| crate::material::of_piece(&p.def, base, material))
        .collect::<Result<Vec<_>, PipelineError>>()?;
    // A free piece with a material is flattened by its material's energy alone (below); every
    // other piece by the isotropic one, with the pieces its seams join.
    let isotropic: Vec<bool> = (0..asm.pieces.len())
        .map(|k| joined[k] || closed.contains_key(&k) || materials[k].is_none())
        .collect();
    // A closed piece's stand-in is split from the whole, never used as it is: it is flattened
    // without the limits (one solve, where holding them on a surface that is no disk's shape
    // took minutes on a 90k-face scan for a map the split throws away).
    let stand_ins: Vec<bool> = (0..asm.pieces.len())
        .map(|k| closed.contains_key(&k) && !joined[k])
        .collect();
    let others: Vec<bool> = (0..asm.pieces.len())
        .map(|k| isotropic[k] && !stand_ins[k])
        .collect();
    let mut solved = flatten_isotropic(design, &asm, &others, params)?.into_iter();
    let free = params
        .clone()
        .with_max_stretch_pct(None)
        .with_max_compress_pct(None);
    let mut freed = flatten_isotropic(design, &asm, &stand_ins, &free)?.into_iter();
    let mut flats = (0..asm.pieces.len())
        .filter(|&k| isotropic[k])
        .map(|k| {
            let f = if stand_ins[k] {
                freed.next()
            } else {
                solved.next()
            };
            f.ok_or_else(|| unsolved(&asm.pieces[k].def.name))
        })
        .collect::<Result<Vec<_>, _>>()?
        .into_iter();
    let mut notches: Vec<Vec<FlatNotch>> = asm
        .pieces
        .iter()
        .map(|p| {
            p.notch_marks
                .iter()
                .map(|(name, vertex)| FlatNotch {
                    name: name.clone(),
                    vertex: *vertex,
                })
                .collect()
        })
        .collect();
    for s in &asm.seams {
        for side in &s.sides {
            for n in &s.notches {
                notches[side.piece].push(FlatNotch {
                    name: n.name.clone(),
                    vertex: side.vertices[n.index],
                });
            }
        }
    }
    let joined_copy = joined.clone();
    let mut pieces = asm
        .pieces
        .into_iter()
        .zip(materials)
        .zip(notches)
        .zip(joined)
        .enumerate()
        .map(|(k, (((p, piece_material), notches), joined))| {
            // Solved above exactly when the piece is flattened by the isotropic energy.
            let f = if isotropic[k] { flats.next() } else { None };
            match f {
                Some(f) if closed.contains_key(&k) => {
                // A stand-in until the split pass splits the whole.
                let mut mesh = p.mesh;
                mesh.flat = Some(f.uv);
                Ok(FlatPiece {
                    def: p.def,
                    mesh,
                    info: f.info,
                    notches,
                    darts: Vec::new(),
                    grain: None,
                    grain_dir: None,
                    despike: None,
                })
                }
                Some(f) if joined => {
                let mut info = f.info;
                if piece_material.is_some() {
                    info.warnings.push(format!(
                        "{}: a piece joined to others by seams is flattened with them by the isotropic energy; its material's limits are not checked per direction",
                        p.def.name
                    ));
                }
                if darting::wanted(Some(&p.def), darts) {
                    info.warnings.push(format!(
                        "{}: no darts are cut into a piece joined to others by seams (a dart would move its seams); split it by a style line instead",
                        p.def.name
                    ));
                }
                let mut mesh = p.mesh;
                mesh.flat = Some(f.uv);
                Ok(FlatPiece {
                    def: p.def,
                    mesh,
                    info,
                    notches,
                    darts: Vec::new(),
                    grain: None,
                    grain_dir: None,
                    despike: None,
                })
                }
                f => {
                let (f, grain, limits) = match &piece_material {
                    Some(m) => {
                        let (f, g) = crate::material::flatten(
                            &p.def.name,
                            &p.mesh,
                            params,
                            m,
                            p.def.grain.as_ref(),
                        )?;
                        let limits = crate::material::dart_limits(
                            params,
                            m,
                            &g,
                            p.def.grain.as_ref(),
                            &p.mesh,
                        );
                        (f, Some(g), limits)
                    }
                    None => (
                        f.ok_or_else(|| unsolved(&p.def.name))?,
                        None,
                        DartLimits::of(params),
                    ),
                };
                // Darts first; where they cannot help and splitting is asked for, the piece
                // goes on whole to be split.
                let whole = split.is_some().then(|| {
                    let mut mesh = p.mesh.clone();
                    mesh.flat = Some(f.uv.clone());
                    FlatPiece {
                        def: p.def.clone(),
                        mesh,
                        info: f.info.clone(),
                        notches: notches.clone(),
                        darts: Vec::new(),
                        grain: grain.clone(),
                        grain_dir: None,
                        despike: None,
                    }
                });
                match dart_if_wanted(p.def, p.mesh, f, notches, &limits, darts, grain) {
                    Err(e) if darting::is_out_of_limits(&e) => whole.ok_or(e),
                    r => r,
                }
                }
            }
        })
        .collect::<Result<Vec<FlatPiece>, PipelineError>>()?;
    for (p, d) in pieces.iter_mut().zip(despiked) {
        p.despike = d;
    }
    let (pieces, seams) = match split {
        Some(s) => {
            split_where_wanted(pieces, asm.seams, &joined_copy, &closed, params, s, |def| {
                crate::material::of_piece(def, base, material)
            })?
        }
        None => (pieces, asm.seams),
    };
    Ok((pieces, seams, read))
}

/// Removes the spikes of every piece's surface when the split settings ask for it
/// ([`crate::despiking`]), each with the limits its split holds; what each repair changed, in
/// the order of the pieces (`None` throughout when not asked for).
fn despike_pieces(
    asm: &mut flatcut_design::Assembly,
    base: &Path,
    params: &FlattenParams,
    split: Option<&crate::splitting::SplitSettings>,
    material: Option<&MaterialSpec>,
) -> Result<Vec<Option<crate::despiking::DespikeRecord>>, PipelineError> {
    let Some(max_mm) = split.and_then(|s| s.despike_max_mm) else {
        return Ok(vec![None; asm.pieces.len()]);
    };
    asm.pieces
        .iter_mut()
        .map(|p| {
            let m = crate::material::of_piece(&p.def, base, material)?;
            crate::despiking::despike_piece(&p.def.name, &mut p.mesh, params, m.as_ref(), max_mm)
        })
        .collect()
}

/// The isotropic flattening of every piece `wanted` marks (the others are left out of the
/// solve), pieces joined by seams flattened together; in the order of the pieces.
fn flatten_isotropic(
    design: &Design,
    asm: &flatcut_design::Assembly,
    wanted: &[bool],
    params: &FlattenParams,
) -> Result<Vec<flatcut_flatten::Flattening>, PipelineError> {
    let index: Vec<usize> = (0..asm.pieces.len()).filter(|&k| wanted[k]).collect();
    let meshes: Vec<&TriMesh> = index.iter().map(|&k| &asm.pieces[k].mesh).collect();
    // The seams between pieces solved here, their sides renumbered among those (a joined piece
    // is solved with every piece it is joined to, so no seam has one side here and one not).
    let seams: Vec<MatingSeam> = asm
        .seams
        .iter()
        .filter(|s| {
            s.sides
                .iter()
                .all(|side| wanted.get(side.piece) == Some(&true))
        })
        .map(|s| {
            let mut s = s.clone();
            for side in &mut s.sides {
                side.piece = index.partition_point(|&k| k < side.piece);
            }
            s
        })
        .collect();
    flatcut_flatten::assembly::flatten_assembly(&meshes, &seams, params).map_err(|e| match e {
        flatcut_flatten::assembly::AssemblyError::Piece { piece, source } => {
            PipelineError::Flatten {
                piece: asm.pieces[index[piece]].def.name.clone(),
                source,
            }
        }
        source => PipelineError::Assembly {
            file: design.source.clone(),
            source,
        },
    })
}

/// The error of a piece that should have been flattened and was not: a bug.
fn unsolved(piece: &str) -> PipelineError {
    PipelineError::Internal {
        piece: piece.to_string(),
        what: "the piece was left out of the flattening",
    }
}

/// Splits every piece no seam joins that is beyond its limits ([`crate::splitting`]); the parts
/// take the piece's place in the order, and the seams' piece indices follow.
fn split_where_wanted(
    pieces: Vec<FlatPiece>,
    mut seams: Vec<MatingSeam>,
    joined: &[bool],
    closed: &std::collections::BTreeMap<usize, TriMesh>,
    params: &FlattenParams,
    settings: &crate::splitting::SplitSettings,
    material_of: impl Fn(&PieceDef) -> Result<Option<MaterialSpec>, PipelineError>,
) -> Result<(Vec<FlatPiece>, Vec<MatingSeam>), PipelineError> {
    let mut out: Vec<FlatPiece> = Vec::with_capacity(pieces.len());
    let mut index = Vec::with_capacity(pieces.len());
    let mut new_seams = Vec::new();
    for (k, (mut piece, &joined)) in pieces.into_iter().zip(joined).enumerate() {
        index.push(out.len());
        if joined {
            let over = piece
                .mesh
                .flat
                .as_deref()
                .is_some_and(|uv| !darting::within(&piece.mesh, uv, params, None));
            if over {
                piece.info.warnings.push(format!(
                    "{}: a piece joined to others by seams is not split (a cut would move its seams); split it by a style line instead",
                    piece.def.name
                ));
            }
            out.push(piece);
            continue;
        }
        let limits = match material_of(&piece.def)? {
            Some(m) => crate::material::dart_params(params, &m),
            None => params.clone(),
        };
        let parts = match closed.get(&k) {
            Some(whole) => crate::mirrored::split_closed(piece, whole, &limits, settings)?,
            None => crate::splitting::split_piece(piece, &limits, settings)?,
        };
        let base = out.len();
        new_seams.extend(parts.seams.into_iter().map(|mut s| {
            s.sides.iter_mut().for_each(|side| side.piece += base);
            s
        }));
        out.extend(parts.pieces);
    }
    for s in &mut seams {
        s.sides
            .iter_mut()
            .for_each(|side| side.piece = index[side.piece]);
    }
    seams.extend(new_seams);
    let mut names = std::collections::BTreeSet::new();
    for p in &out {
        if !names.insert(p.def.name.as_str()) {
            return Err(PipelineError::SplitNameClash {
                piece: p.def.name.clone(),
            });
        }
    }
    Ok((out, seams))
}

/// A piece no seam joins, flattened: where it exceeds its limits and darts are wanted
/// ([`darting::wanted`]), darted and flattened again with the limits held; its notches are found
/// again in the darted mesh by their 3D position (the cut adds and splits vertices).
fn dart_if_wanted(
    def: PieceDef,
    mesh: TriMesh,
    f: flatcut_flatten::Flattening,
    notches: Vec<FlatNotch>,
    limits: &DartLimits,
    darts: Option<&DartSettings>,
    grain: Option<crate::material::PieceGrain>,
) -> Result<FlatPiece, PipelineError> {
    let before = grain.as_ref().map(|_| (mesh.clone(), f.uv.clone()));
    let settings = darting::wanted(Some(&def), darts).then(|| darts.copied().unwrap_or_default());
    let at: Vec<DVec3> = notches
        .iter()
        .map(|n| mesh.positions[n.vertex as usize])
        .collect();
    let darting::Finished {
        mesh,
        info,
        darts,
        grain_kept,
    } = darting::finish(
        &def.name,
        Some(&def),
        mesh,
        f.uv,
        f.info,
        limits,
        settings.as_ref(),
    )?;
    let notches = if darts.is_empty() {
        notches
    } else {
        notches
            .into_iter()
            .zip(at)
            .filter_map(|(n, p)| {
                let v = mesh.positions.iter().position(|q| q.distance(p) < 1e-9)?;
                Some(FlatNotch {
                    name: n.name,
                    vertex: v as u32,
                })
            })
            .collect()
    };
    let grain = match (grain, before) {
        (Some(g), Some((m0, uv0))) if !grain_kept => {
            let uv = mesh.flat.as_deref().unwrap_or_default();
            Some(crate::material::carry_over(&g, (&m0, &uv0), (&mesh, uv)))
        }
        (g, _) => g,
    };
    Ok(FlatPiece {
        def,
        mesh,
        info,
        notches,
        darts,
        grain,
        grain_dir: None,
        despike: None,
    })
}

/// The distortion report of a flattened piece, with its notch marks splitting the boundary into
/// seam segments.
pub fn report_piece(
    name: &str,
    mesh: &TriMesh,
    marks: &[u32],
    limit_stretch: Option<f64>,
    limit_compress: Option<f64>,
) -> Result<Report, PipelineError> {
    let opts = flatcut_report::ReportOptions::default()
        .with_boundary_marks(marks.to_vec())
        .with_limit_stretch_pct(limit_stretch)
        .with_limit_compress_pct(limit_compress);
    Report::compute(name, mesh, &opts).map_err(|source| PipelineError::Report {
        piece: name.to_string(),
        source,
    })
}
