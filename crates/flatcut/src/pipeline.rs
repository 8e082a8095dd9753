//! The pipeline stages that need more than one crate: flatten the pieces of a design, turn a
//! flattened mesh into a 2D pattern piece (boundary → sew line, 3D marks and grain → 2D), and
//! nest drawings on sheets or a roll.

use std::path::Path;

use flatcut_design::material::MaterialSpec;
use flatcut_design::{Design, DesignError, MarkKind as DesignMark, PieceDef};
use flatcut_flatten::{FlattenError, FlattenInfo, FlattenParams};
use flatcut_geom::{DVec2, DVec3, Tolerances};
use flatcut_mesh::TriMesh;
use flatcut_mesh::mating::MatingSeam;
use flatcut_nest::{
    GrainDirections, Hide, NestError, NestItem, NestOptions, NestProgress, NestResult, Rotations,
    Stock,
};
use flatcut_pattern::{
    Drawing, LabelInfo, Mark, MarkKind, PatternError, Piece, PieceInput, PieceOptions, Placement,
};
use flatcut_report::{Report, ReportError};

use crate::darting::{self, DartLimits, DartSettings};

/// Why a pipeline stage failed; every variant names the piece or file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    #[error(transparent)]
    Design(#[from] DesignError),
    #[error("piece '{piece}': {source}")]
    Flatten { piece: String, source: FlattenError },
    #[error("piece '{piece}': {source}")]
    Report { piece: String, source: ReportError },
    #[error(transparent)]
    Pattern(#[from] PatternError),
    #[error(transparent)]
    Nest(#[from] NestError),
    #[error(transparent)]
    Gcode(#[from] flatcut_gcode::GcodeError),
    #[error(transparent)]
    Mesh(#[from] flatcut_mesh::MeshIoError),
    #[error("piece '{piece}': {reason}")]
    Piece { piece: String, reason: String },
    #[error("piece '{piece}': {source}")]
    Darts {
        piece: String,
        source: flatcut_darts::DartError,
    },
    #[error(
        "{file}: pieces '{first}' and '{second}' would share the name '{safe}' in ids and file names; rename one of them"
    )]
    NameClash {
        file: String,
        first: String,
        second: String,
        safe: String,
    },
}

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

/// A notch of a piece: a boundary vertex of its mesh, exactly where the notch is, and its name
/// (a mating seam's notch `line n`, or the design's notch mark).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FlatNotch {
    pub name: String,
    pub vertex: u32,
}

/// A piece of a design, cut along its seams and flattened: `mesh.flat` holds the 2D position of
/// every vertex (mm, true scale).
#[derive(Clone, Debug)]
pub struct FlatPiece {
    pub def: PieceDef,
    pub mesh: TriMesh,
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
}

/// A design flattened: every piece (a `[[piece]]` or a region of a `[[part]]`) and the mating
/// seams between them (sides index `pieces`).
#[derive(Clone, Debug)]
pub struct FlatDesign {
    pub design: Design,
    pub pieces: Vec<FlatPiece>,
    pub seams: Vec<MatingSeam>,
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
    };
    for sized in sizes {
        let first = out.pieces.len();
        let (mut pieces, mut seams) = match &sized.size {
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

/// The pieces and seams of one design (one size), flattened.
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
) -> Result<(Vec<FlatPiece>, Vec<MatingSeam>), PipelineError> {
    let mut asm = design.assemble(base, tol)?;
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
    let meshes: Vec<&TriMesh> = asm.pieces.iter().map(|p| &p.mesh).collect();
    let flats =
        flatcut_flatten::assembly::flatten_assembly(&meshes, &asm.seams, params).map_err(|e| {
            match e {
                flatcut_flatten::assembly::AssemblyError::Piece { piece, source } => {
                    PipelineError::Flatten {
                        piece: asm.pieces[piece].def.name.clone(),
                        source,
                    }
                }
                other => PipelineError::Piece {
                    piece: design.source.clone(),
                    reason: other.to_string(),
                },
            }
        })?;
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
    let joined: Vec<bool> = (0..asm.pieces.len())
        .map(|k| {
            asm.seams
                .iter()
                .any(|s| s.sides.iter().any(|d| d.piece == k))
        })
        .collect();
    let joined_copy = joined.clone();
    let pieces = asm
        .pieces
        .into_iter()
        .zip(flats)
        .zip(notches)
        .zip(joined)
        .enumerate()
        .map(|(k, (((p, f), notches), joined))| {
            let piece_material = crate::material::of_piece(&p.def, base, material)?;
            if closed.contains_key(&k) {
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
                })
            } else if joined {
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
                })
            } else {
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
                    None => (f, None, DartLimits::of(params)),
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
                    }
                });
                match dart_if_wanted(p.def, p.mesh, f, notches, &limits, darts, grain) {
                    Err(e) if darting::is_out_of_limits(&e) => whole.ok_or(e),
                    r => r,
                }
            }
        })
        .collect::<Result<Vec<_>, PipelineError>>()?;
    match split {
        Some(s) => split_where_wanted(pieces, asm.seams, &joined_copy, &closed, params, s, |def| {
            crate::material::of_piece(def, base, material)
        }),
        None => Ok((pieces, asm.seams)),
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
            Some(whole) => crate::splitting::split_surface_piece(piece, whole, &limits, settings)?,
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
            return Err(PipelineError::Piece {
                piece: p.def.name.clone(),
                reason:
                    "a part of a split piece takes the name of another piece; rename that piece"
                        .into(),
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

/// The flattened boundary of a piece as a closed CCW polyline (first point not repeated) with the
/// mesh vertex of each polyline point.
pub fn flat_boundary(name: &str, mesh: &TriMesh) -> Result<(Vec<DVec2>, Vec<u32>), PipelineError> {
    let flat = mesh.flat.as_ref().ok_or_else(|| PipelineError::Piece {
        piece: name.into(),
        reason: "the mesh has no flattening".into(),
    })?;
    let topo = flatcut_mesh::Topology::build(mesh).map_err(|e| PipelineError::Piece {
        piece: name.into(),
        reason: e.to_string(),
    })?;
    let lp = match topo.boundary_loops.len() {
        1 => topo.boundary_loops[0].clone(),
        0 => {
            return Err(PipelineError::Piece {
                piece: name.into(),
                reason: "the flattened mesh has no boundary".into(),
            });
        }
        n => {
            // The outer loop is the one with the largest enclosed area in the plane; holes are
            // not carried into the pattern as cut-outs here.
            let area = |lp: &Vec<u32>| {
                signed_area(&lp.iter().map(|&v| flat[v as usize]).collect::<Vec<_>>()).abs()
            };
            let best = topo
                .boundary_loops
                .iter()
                .max_by(|a, b| area(a).total_cmp(&area(b)))
                .cloned()
                .unwrap_or_default();
            let _ = n;
            best
        }
    };
    let mut pts: Vec<DVec2> = lp.iter().map(|&v| flat[v as usize]).collect();
    let mut ids = lp;
    if signed_area(&pts) < 0.0 {
        pts.reverse();
        ids.reverse();
    }
    Ok((pts, ids))
}

fn signed_area(p: &[DVec2]) -> f64 {
    (0..p.len())
        .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
        .sum::<f64>()
        * 0.5
}

/// What a pattern piece is built with beyond the flattened mesh.
#[derive(Clone, Debug, Default)]
pub struct PieceContext<'a> {
    pub def: Option<&'a PieceDef>,
    pub report: Option<&'a Report>,
    /// The piece's darts: their mouths get notches, their points drill marks and a fold arrow
    /// says which way each is pressed.
    pub darts: &'a [flatcut_darts::Dart],
    /// Seam allowance (mm) when the design gives none.
    pub seam_mm: Option<f64>,
    pub size: String,
    pub corner: flatcut_pattern::CornerStyle,
    /// The piece's notches as boundary vertices (exact positions; named on mating seams).
    pub notches: &'a [FlatNotch],
    /// The warp's direction in the flat map of a piece flattened for its material: drawn as
    /// the grain line (through the piece's middle) when the design draws none, as for a grain
    /// the flattening chose (`grain = "auto"`).
    pub grain_dir: Option<DVec2>,
    /// The short code the label writes where the piece has no room for a readable one (`None`:
    /// the initials of its name).
    pub code: Option<String>,
}

/// Longest step (mm) between samples of a stitch or placement line carried into the plane:
/// fine enough that the drawn line follows the map's bending within a pen width.
const LINE_STEP_MM: f64 = 1.0;

/// Builds the pattern piece of a flattened mesh: the flattened boundary is the sew line, its
/// stretches given the allowances of the design's edges and style lines they lie on
/// ([`crate::outline_edges`]), notches sit on their boundary vertices (inserted where they are,
/// never snapped), darts are drawn as a pattern maker draws them ([`crate::dart_drawing`]),
/// drill/reference points, stitch lines and the grain line are carried through the map, the
/// label carries the distortion summary, and the piece is turned with its grain along +x
/// (without one, its minimum-area bounding box square to the axes, the longer side along x).
pub fn piece_from_flat(
    name: &str,
    mesh: &TriMesh,
    ctx: &PieceContext<'_>,
    opts: &PieceOptions,
) -> Result<Piece, PipelineError> {
    let (outline, ids) = flat_boundary(name, mesh)?;
    let flat = mesh.flat.as_deref().unwrap_or_default();
    let edges: &[flatcut_design::OutlineEdge] = ctx.def.map_or(&[], |d| &d.outline_edges);
    let classes = crate::outline_edges::classify(&ids, mesh, edges);
    let grain = match ctx.def {
        Some(def) => design_grain(name, def, mesh, flat)?,
        None => None,
    };
    let drawn = draw_darts(ctx, mesh, flat, &outline, grain, opts.chord_tol);
    let pressed: Vec<(&flatcut_darts::Dart, usize)> = ctx
        .darts
        .iter()
        .zip(&drawn)
        .map(|(d, w)| (d, w.pressed))
        .collect();
    let (outline, ids, classes) =
        crate::dart_drawing::true_mouths(outline, ids, classes, &pressed, flat);
    let mut input = PieceInput::new(name, outline);
    input.edges = crate::outline_edges::stretches(&classes, edges);
    input.corner_style = ctx.corner;
    input.grain = grain;
    let mut opts = *opts;
    for n in ctx.notches {
        let k = ids
            .iter()
            .position(|&v| v == n.vertex)
            .ok_or_else(|| PipelineError::Piece {
                piece: name.into(),
                reason: format!("notch '{}' is not on the piece's outline", n.name),
            })?;
        input.mark_names.resize(input.marks.len(), String::new());
        input.mark_names.push(n.name.clone());
        input.marks.push(Mark {
            kind: MarkKind::Notch,
            pos: input.outline[k],
            boundary_index: Some(k),
        });
    }
    if let Some(def) = ctx.def {
        design_marks(name, def, mesh, flat, &mut input)?;
        if let Some(w) = def.seam_allowance_mm {
            opts = opts.with_default_seam(w);
        }
        input.label = LabelInfo {
            name: name.into(),
            size: def
                .size
                .as_ref()
                .map_or_else(|| ctx.size.clone(), |s| s.size.clone()),
            material: def.material.clone().unwrap_or_default(),
            quantity: def.quantity,
            distortion: None,
            code: None,
        };
    }
    if input.grain.is_none()
        && let Some(d) = ctx.grain_dir
    {
        input.grain = flatcut_pattern::piece::grain_line_along(&input.outline, d);
    }
    for (d, w) in ctx.darts.iter().zip(&drawn) {
        crate::dart_drawing::dart_marks(&mut input, d, w, &ids);
    }
    if ctx.def.and_then(|d| d.seam_allowance_mm).is_none()
        && let Some(w) = ctx.seam_mm
    {
        opts = opts.with_default_seam(w);
    }
    if let Some(r) = ctx.report {
        input.label.distortion = Some(format!(
            "STRETCH {:.1}% COMPRESS {:.1}% D2 {:.4}",
            r.stretch_max_pct, r.compress_max_pct, r.delta2_mean
        ));
    }
    if let Some(code) = &ctx.code {
        input.label.code = Some(code.clone());
    }
    // The flattening leaves the piece at the solver's rotation: turn it square (grain along +x,
    // else its smallest bounding box) before it is built.
    input.orient();
    Ok(Piece::build(&input, &opts)?)
}

/// The design's grain line carried into the plane. A grain line is a direction drawn near the
/// surface: points off the surface are carried by their nearest vertex rather than refused.
fn design_grain(
    name: &str,
    def: &PieceDef,
    mesh: &TriMesh,
    flat: &[DVec2],
) -> Result<Option<(DVec2, DVec2)>, PipelineError> {
    let Some([a, b]) = def.grain.as_ref().and_then(|g| g.line()).copied() else {
        return Ok(None);
    };
    let (a, b) = (DVec3::from_array(a), DVec3::from_array(b));
    let q = flatcut_flatten::marks::to_plane(mesh, flat, &[a, b]);
    match (
        q[0].or_else(|| near_flat(mesh, flat, a)),
        q[1].or_else(|| near_flat(mesh, flat, b)),
    ) {
        (Some(a), Some(b)) if a.distance(b) > 0.0 => Ok(Some((a, b))),
        _ => Err(PipelineError::Piece {
            piece: name.into(),
            reason: "the grain line's two points map to the same place".into(),
        }),
    }
}

/// The flat position of the mesh vertex nearest `p`.
fn near_flat(mesh: &TriMesh, flat: &[DVec2], p: DVec3) -> Option<DVec2> {
    (0..mesh.positions.len().min(flat.len()))
        .min_by(|&x, &y| {
            mesh.positions[x]
                .distance(p)
                .total_cmp(&mesh.positions[y].distance(p))
        })
        .map(|v| flat[v])
}

/// The piece's darts as the pattern draws them: legs smoothed, and the side each intake is
/// pressed toward (the design's `dart_press` point, or the piece's centre line).
fn draw_darts(
    ctx: &PieceContext<'_>,
    mesh: &TriMesh,
    flat: &[DVec2],
    outline: &[DVec2],
    grain: Option<(DVec2, DVec2)>,
    chord_tol: f64,
) -> Vec<crate::dart_drawing::DrawnDart> {
    use crate::dart_drawing::{DrawnDart, pressed_leg, smooth_leg, toward_centre_line};
    let toward = match ctx.def.and_then(|d| d.dart_press) {
        Some(flatcut_design::DartPress::Toward(p)) => {
            let p = DVec3::from_array(p);
            flatcut_flatten::marks::to_plane(mesh, flat, &[p])[0]
                .or_else(|| near_flat(mesh, flat, p))
        }
        _ => None,
    };
    let (centre, dir) =
        crate::outline_edges::centre_line(outline, grain.map(|(a, b)| b - a).or(ctx.grain_dir));
    ctx.darts
        .iter()
        .map(|d| {
            let legs = d.leg_polylines(flat).map(|l| smooth_leg(&l, chord_tol));
            let target = toward.unwrap_or_else(|| toward_centre_line(&legs, centre, dir));
            let pressed = pressed_leg(&legs, target);
            DrawnDart { legs, pressed }
        })
        .collect()
}

/// The design's marks of a piece carried into the plane: stitch and placement lines (following
/// the surface), drill holes and reference points.
fn design_marks(
    name: &str,
    def: &PieceDef,
    mesh: &TriMesh,
    flat: &[DVec2],
    input: &mut PieceInput,
) -> Result<(), PipelineError> {
    for mark in &def.marks {
        let pts: Vec<DVec3> = mark.points.iter().map(|p| DVec3::from_array(*p)).collect();
        match mark.kind {
            // Notch marks are boundary vertices of the mesh already (`ctx.notches`).
            DesignMark::Notch => {}
            DesignMark::Line if pts.len() >= 2 => {
                // Stitch and placement lines follow the surface: each 3D segment is subdivided
                // and every sample carried by its nearest surface point, so the flat line bends
                // as the map does.
                let q = flatcut_flatten::marks::polyline_to_plane(mesh, flat, &pts, LINE_STEP_MM);
                let line: Option<Vec<DVec2>> = q.into_iter().collect();
                let line = line.ok_or_else(|| PipelineError::Piece {
                    piece: name.into(),
                    reason: format!(
                        "mark '{}': the line leaves the surface (a point is farther than {:.0} % of the part size from it)",
                        mark.name,
                        flatcut_flatten::marks::MAX_OFFSET_REL * 100.0
                    ),
                })?;
                input.lines.push(line);
            }
            DesignMark::Point | DesignMark::Line => {
                // a one-point "line" is a reference point
                let kind = if mark.kind == DesignMark::Point {
                    MarkKind::Drill
                } else {
                    MarkKind::Point
                };
                for (q, p) in flatcut_flatten::marks::to_plane(mesh, flat, &pts)
                    .into_iter()
                    .zip(&pts)
                {
                    let q = q.ok_or_else(|| PipelineError::Piece {
                        piece: name.into(),
                        reason: format!(
                            "mark '{}': point ({:.2}, {:.2}, {:.2}) is not on the surface",
                            mark.name, p.x, p.y, p.z
                        ),
                    })?;
                    input.marks.push(Mark {
                        kind,
                        pos: q,
                        boundary_index: None,
                    });
                }
            }
        }
    }
    Ok(())
}

/// A rigid group of strokes nested as one item: a pattern piece's drawing in its own frame.
#[derive(Clone, Debug)]
pub struct NestGroup {
    pub name: String,
    pub drawing: Drawing,
    /// The outline that must not overlap (the cut line), CCW.
    pub outline: Vec<DVec2>,
    pub quantity: usize,
    pub mirrored_pair: bool,
    pub grain_angle: Option<f64>,
    /// The material's grain rule for a piece with a grain line, and its tolerance (degrees).
    pub grain_directions: GrainDirections,
    pub grain_tolerance_deg: f64,
    /// The worst hide grade the piece accepts (`None` = any).
    pub quality: Option<u32>,
}

impl NestGroup {
    /// The group of a built piece.
    pub fn from_piece(piece: &Piece, quantity: usize, mirrored_pair: bool) -> Self {
        let item = NestItem::from_piece(piece, quantity, mirrored_pair);
        Self {
            name: piece.name.clone(),
            drawing: piece.to_drawing(1),
            outline: item.outline,
            quantity,
            mirrored_pair,
            grain_angle: item.grain_angle,
            grain_directions: item.grain_directions,
            grain_tolerance_deg: item.grain_tolerance_deg,
            quality: item.quality,
        }
    }

    /// The pieces of a drawing read from an SVG or a DXF: one group per outer cut contour with
    /// the strokes that belong to it, its quantity and grain from the drawing's piece
    /// information where the file carried them.
    pub fn from_drawing(name: &str, d: &Drawing) -> Vec<Self> {
        let mut groups: Vec<Self> = Vec::new();
        let mut by_piece: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (i, s) in d.strokes.iter().enumerate() {
            by_piece
                .entry(s.piece.unwrap_or(u32::MAX))
                .or_default()
                .push(i);
        }
        for (p, idx) in by_piece {
            let Some(outer) = idx
                .iter()
                .map(|&i| &d.strokes[i])
                .find(|s| s.is_outer() && s.closed)
            else {
                continue;
            };
            let mut outline = outer.points.clone();
            if signed_area(&outline) < 0.0 {
                outline.reverse();
            }
            let info = d.piece_info(p);
            let label_name = info.map(|i| i.label.name.clone()).unwrap_or_default();
            let gname = if !label_name.is_empty() {
                label_name
            } else {
                outer
                    .id
                    .strip_suffix("-cut")
                    .unwrap_or(&outer.id)
                    .to_string()
            };
            let gname = if gname.is_empty() {
                format!("{name}-{p}")
            } else {
                gname
            };
            let mut pieces: Vec<_> = info.cloned().into_iter().collect();
            pieces.iter_mut().for_each(|i| i.piece = p);
            groups.push(Self {
                name: gname,
                drawing: Drawing {
                    strokes: idx.iter().map(|&i| d.strokes[i].clone()).collect(),
                    pieces,
                },
                outline,
                quantity: info.map_or(1, |i| i.label.quantity.max(1) as usize),
                mirrored_pair: false,
                grain_angle: info
                    .and_then(|i| i.grain)
                    .map(|(a, b)| (b - a).y.atan2((b - a).x)),
                grain_directions: GrainDirections::default(),
                grain_tolerance_deg: 0.0,
                quality: None,
            });
        }
        groups
    }
}

/// A nested layout: one drawing per sheet or hide (its coordinates, mm) and the nesting figures.
pub struct Layout {
    pub sheets: Vec<Drawing>,
    pub result: NestResult,
    /// The roll or sheets (`None` on hides).
    pub stock: Option<Stock>,
}

/// The nesting items of the groups: a piece with a grain line keeps it by the group's rule
/// (which may be `any`), others turn in quarter turns.
fn nest_items(groups: &[NestGroup]) -> Vec<NestItem> {
    groups
        .iter()
        .map(|g| {
            let mut it = NestItem::new(g.name.clone(), g.outline.clone(), g.quantity);
            it.mirrored_pair = g.mirrored_pair;
            it.grain_angle = g.grain_angle;
            it.grain_directions = g.grain_directions;
            it.grain_tolerance_deg = g.grain_tolerance_deg;
            it.quality = g.quality;
            it.rotations = Rotations::Quarter;
            it
        })
        .collect()
}

/// The groups' drawings at their placements, one drawing per sheet or hide.
fn place_groups(groups: &[NestGroup], result: NestResult, stock: Option<Stock>) -> Layout {
    let mut sheets = vec![Drawing::default(); result.sheets.max(1)];
    let mut counters = vec![0u32; groups.len()];
    for p in &result.placed {
        counters[p.item] += 1;
        let g = &groups[p.item];
        let d = place(&g.drawing, &p.placement, counters[p.item], p.item as u32);
        if let Some(sheet) = sheets.get_mut(p.sheet) {
            sheet.strokes.extend(d.strokes);
            sheet.pieces.extend(d.pieces);
        }
    }
    Layout {
        sheets,
        result,
        stock,
    }
}

/// Nests the groups on the stock and places their drawings.
pub fn nest_groups(
    groups: &[NestGroup],
    stock: Stock,
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<Layout, PipelineError> {
    let result = flatcut_nest::nest(&nest_items(groups), stock, opts, progress)?;
    Ok(place_groups(groups, result, Some(stock)))
}

/// Nests the groups on leather hides (in order) and places their drawings, one per hide used.
pub fn nest_groups_on_hides(
    groups: &[NestGroup],
    hides: &[Hide],
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<Layout, PipelineError> {
    let result = flatcut_nest::nest_hides(&nest_items(groups), hides, opts, progress)?;
    Ok(place_groups(groups, result, None))
}

fn place(d: &Drawing, pl: &Placement, instance: u32, item: u32) -> Drawing {
    let mut out = d.clone();
    out.apply_placement(pl);
    for s in &mut out.strokes {
        // Unique piece numbers per placed instance so the G-code writer keeps holes before their
        // outer contour per instance.
        s.piece = Some(item * 10_000 + instance);
        s.id = format!("{}#{}", s.id, instance);
    }
    out.pieces.truncate(1);
    for info in &mut out.pieces {
        info.piece = item * 10_000 + instance;
        // each placed copy is one piece cut (its drawn label still says how many a set takes)
        info.label.quantity = 1;
    }
    out
}
