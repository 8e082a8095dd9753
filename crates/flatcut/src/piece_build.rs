//! A flattened mesh to a 2D pattern piece: boundary → sew line, the design's 3D marks, darts
//! and grain → 2D.
//!
//! It is the glue from a flattened mesh boundary to a 2D piece, so `pattern` never learns about
//! meshes: notches come as boundary vertices named after their seam, a pair's mirrored side is
//! the mirror image of the flat map.

use flatcut_design::{MarkKind as DesignMark, PieceDef};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_pattern::{LabelInfo, Mark, MarkKind, Piece, PieceInput, PieceOptions};
use flatcut_report::Report;

use crate::error::PipelineError;
use crate::flat_piece::FlatNotch;
use flatcut_pattern::poly::signed_area;

/// The flattened boundary of a piece as a closed CCW polyline (first point not repeated) with the
/// mesh vertex of each polyline point.
pub fn flat_boundary(name: &str, mesh: &TriMesh) -> Result<(Vec<DVec2>, Vec<u32>), PipelineError> {
    let flat = mesh
        .flat
        .as_ref()
        .ok_or_else(|| PipelineError::NotFlattened { piece: name.into() })?;
    let topo = flatcut_mesh::Topology::build(mesh).map_err(|source| PipelineError::Topology {
        piece: name.into(),
        source,
    })?;
    let lp = match topo.boundary_loops.len() {
        1 => topo.boundary_loops[0].clone(),
        0 => {
            return Err(PipelineError::NoBoundary { piece: name.into() });
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

/// What a pattern piece is built with beyond the flattened mesh.
#[derive(Clone, Debug, Default)]
pub struct PieceContext<'a> {
    /// The piece as the design defines it (marks, grain, allowances); `None` for a mesh file.
    pub def: Option<&'a PieceDef>,
    /// The piece's distortion report, summarised on its label.
    pub report: Option<&'a Report>,
    /// The piece's darts: their mouths get notches, their points drill marks and a fold arrow
    /// says which way each is pressed.
    pub darts: &'a [flatcut_darts::Dart],
    /// Seam allowance (mm) when the design gives none.
    pub seam_mm: Option<f64>,
    /// The size the piece is cut in, for its label (empty when ungraded).
    pub size: String,
    /// How the allowance turns at corners.
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
        let k = ids.iter().position(|&v| v == n.vertex).ok_or_else(|| {
            PipelineError::NotchOffOutline {
                piece: name.into(),
                notch: n.name.clone(),
            }
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
        _ => Err(PipelineError::GrainCollapsed { piece: name.into() }),
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
                let line = line.ok_or_else(|| PipelineError::LineOffSurface {
                    piece: name.into(),
                    mark: mark.name.clone(),
                    max_offset_pct: flatcut_flatten::marks::MAX_OFFSET_REL * 100.0,
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
                    let q = q.ok_or_else(|| PipelineError::PointOffSurface {
                        piece: name.into(),
                        mark: mark.name.clone(),
                        point: *p,
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
