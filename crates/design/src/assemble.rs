//! The pieces of a design with their 3D meshes, and the mating seams between them: `[[piece]]`s
//! as they are (cut open along their own seams), each `[[part]]` split along its style lines into
//! the regions its `[[part.piece]]`s name, and the `[[join]]`s between piece edges.
//!
//! Every line between two regions is a mating seam named after the line (a line crossed by
//! another becomes several seams, `name-1`, `name-2`, … in the line's direction); its notches
//! are named `line 1`, `line 2`, … in the order given. A region that no piece names, or a piece
//! that names no region, is an error that says where. Pieces expanded from one STEP model are
//! sewn along every edge their faces share, each edge one seam ([`crate::step_seams`]).

use std::path::Path;

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::joins::boundary_vertex;
use flatcut_mesh::lines::{LineSpec, OFF_SURFACE_REL, embed_lines};
use flatcut_mesh::mating::{MatingSeam, SeamNotch, SeamSide};
use flatcut_mesh::nearest::Bvh;
use flatcut_mesh::regions::split_along_lines;
use flatcut_mesh::{TriMesh, check_disk};

use crate::edge::{EdgeKind, OutlineEdge};
use crate::{Design, DesignError, LineDef, PartDef, PieceDef};

/// A piece to cut, with the mesh its flattening starts from.
#[derive(Clone, Debug)]
pub struct AssembledPiece {
    /// The piece as the design defines it (name, quantity, marks, grain, material), lengths in mm.
    pub def: PieceDef,
    /// The part it was cut from (`None` for a `[[piece]]`).
    pub part: Option<String>,
    /// The 3D mesh the piece is flattened from (mm): the piece's own surface tessellated, or its
    /// region of the part's mesh.
    pub mesh: TriMesh,
    /// The piece's notch marks (`kind = "notch"`) as boundary vertices of `mesh`, inserted
    /// exactly where each mark's point falls on the boundary: (mark name, vertex).
    pub notch_marks: Vec<(String, u32)>,
}

/// Every piece of a design and the mating seams between them (sides index `pieces`).
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Every piece to cut, `[[piece]]`s first in file order, then the pieces of each part.
    pub pieces: Vec<AssembledPiece>,
    /// The mating seams between pieces; their sides index `pieces`.
    pub seams: Vec<MatingSeam>,
}

impl Design {
    /// Builds every piece's mesh and the mating seams (mesh files resolved against `base_dir`,
    /// surfaces tessellated to `tol`).
    pub fn assemble(&self, base_dir: &Path, tol: &Tolerances) -> Result<Assembly, DesignError> {
        let mut out = Assembly {
            pieces: Vec::new(),
            seams: Vec::new(),
        };
        for def in &self.pieces {
            let mut mesh = def.mesh(base_dir, tol)?;
            let mut def = def.clone();
            def.outline_edges =
                crate::edge::find(&mut mesh, &def.edges).map_err(|(edge, msg)| {
                    crate::error::Ctx::of(&def).err(format!("edge '{edge}': {msg}"))
                })?;
            out.pieces.push(AssembledPiece {
                def,
                part: None,
                mesh,
                notch_marks: Vec::new(),
            });
        }
        for part in &self.parts {
            split_part(part, base_dir, tol, &mut out)?;
        }
        for p in &mut out.pieces {
            place_notch_marks(p)?;
        }
        for (k, p) in out.pieces.iter().enumerate() {
            if let Some(j) = out.pieces[..k]
                .iter()
                .position(|q| q.def.name == p.def.name)
            {
                let whose = |q: &AssembledPiece| match &q.part {
                    Some(part) => format!("part '{part}'"),
                    None => "a [[piece]]".to_string(),
                };
                return Err(DesignError::Part {
                    file: self.source.clone(),
                    index: self.parts.len(),
                    part: p.part.clone().unwrap_or_default(),
                    msg: format!(
                        "two pieces are named '{}' ({} and {}): piece names must differ, they name the outputs",
                        p.def.name,
                        whose(&out.pieces[j]),
                        whose(p)
                    ),
                });
            }
        }
        for j in &self.joins {
            let seam = crate::join::join_seam(&self.source, j, &mut out.pieces)?;
            out.seams.push(seam);
        }
        out.seams
            .extend(crate::step_seams::shared_edge_seams(&out.pieces, tol)?);
        Ok(out)
    }
}

/// The message of an error about a part's surface, without the "piece i 'name': " context.
fn bare(e: DesignError) -> String {
    match e {
        DesignError::Piece { msg, .. } => msg,
        DesignError::Surface { source, .. } => source.to_string(),
        DesignError::Mesh { source, .. } => source.to_string(),
        DesignError::Tessellation { source, .. } => source.to_string(),
        other => other.to_string(),
    }
}

/// Names line `k` in a message of the mesh crate that says "line k".
fn named(msg: String, k: usize, part: &PartDef) -> String {
    let name = part.lines.get(k).map_or("", |l| l.name.as_str());
    msg.replacen(&format!("line {k}"), &format!("line {k} '{name}'"), 1)
}

/// A part's surface split along its style lines: the surface mesh with the lines embedded, its
/// regions and seams, and which `[[part.piece]]` names each region (`None`: no piece does yet).
/// What a design editor shows while lines are drawn; [`Design::assemble`] refuses a part with a
/// region no piece names.
#[derive(Clone, Debug)]
pub struct PartRegions {
    /// The part's surface with its lines as mesh edges.
    pub mesh: TriMesh,
    /// Per line, its vertex path in `mesh`.
    pub lines: Vec<Vec<u32>>,
    /// Per line, the vertices of its notches in `mesh`.
    pub notches: Vec<Vec<u32>>,
    /// The regions and the seams between them.
    pub split: flatcut_mesh::regions::Split,
    /// Per region, the `[[part.piece]]`s whose `at` falls in it (one in a design that
    /// assembles).
    pub pieces_of_region: Vec<Vec<usize>>,
    /// The part's `[[part.edge]]`s found on its outline (their ends are vertices of `mesh`).
    pub edges: Vec<OutlineEdge>,
}

impl PartRegions {
    /// A point of region `r` near the middle of its surface (for an `at` that names it).
    pub fn inner_point(&self, r: usize) -> DVec3 {
        inner_point(&self.split.regions[r].mesh)
    }

    /// The region of the surface point nearest to `p`, and its distance from the surface.
    pub fn region_at(&self, p: DVec3) -> Option<(usize, f64)> {
        let bvh = Bvh::new(&self.mesh.positions, &self.mesh.triangles);
        let (f, _, d) = bvh.nearest(&self.mesh.positions, &self.mesh.triangles, p)?;
        Some((self.split.region_of_face[f] as usize, d))
    }
}

impl PartDef {
    /// Tessellates the part's surface (mesh files resolved against `base_dir`), embeds its lines
    /// and splits it into regions, each with the piece that names it, if any. Errors name the
    /// part and the line; a region named by none or by several pieces is not an error here.
    pub fn regions(&self, base_dir: &Path, tol: &Tolerances) -> Result<PartRegions, DesignError> {
        let part = self;
        let surface = part
            .surface_piece()
            .mesh(base_dir, tol)
            .map_err(|e| part.err(bare(e)))?;
        let specs: Vec<LineSpec> = part
            .lines
            .iter()
            .enumerate()
            .map(|(k, l)| {
                let points = match l.edge {
                    Some(e) => crate::step::edge_points(&part.surface_piece(), base_dir, tol, e)
                        .map_err(|m| part.err(format!("line {k} '{}': {m}", l.name)))?,
                    None => l.points.iter().map(|p| DVec3::from_array(*p)).collect(),
                };
                Ok(LineSpec {
                    points,
                    notches: l.notches.iter().map(|p| DVec3::from_array(*p)).collect(),
                })
            })
            .collect::<Result<_, DesignError>>()?;
        let mut embedded = embed_lines(&surface, &specs).map_err(|e| {
            let k = match &e {
                flatcut_mesh::lines::LineError::TooShort { line }
                | flatcut_mesh::lines::LineError::OffSurface { line, .. }
                | flatcut_mesh::lines::LineError::NotchOffLine { line, .. }
                | flatcut_mesh::lines::LineError::LooseEnd { line, .. }
                | flatcut_mesh::lines::LineError::LeavesSurface { line, .. }
                | flatcut_mesh::lines::LineError::Lost { line, .. } => *line,
                _ => 0,
            };
            part.err(named(e.to_string(), k, part))
        })?;
        // The part's edges, their ends made vertices of its outline before it is split.
        let edges = crate::edge::find(&mut embedded.mesh, &part.edges)
            .map_err(|(edge, msg)| part.err(format!("edge '{edge}': {msg}")))?;
        let split = split_along_lines(&embedded.mesh, &embedded.lines).map_err(|e| {
            let k = match &e {
                flatcut_mesh::regions::RegionError::NotAnEdge { line, .. }
                | flatcut_mesh::regions::RegionError::AlongBoundary { line, .. } => *line,
                _ => 0,
            };
            part.err(named(e.to_string(), k, part))
        })?;
        // Which piece names which region.
        let mesh = &embedded.mesh;
        let bvh = Bvh::new(&mesh.positions, &mesh.triangles);
        let far = OFF_SURFACE_REL * mesh.bbox().diagonal();
        let mut pieces_of_region: Vec<Vec<usize>> = vec![Vec::new(); split.regions.len()];
        for (k, p) in part.pieces.iter().enumerate() {
            let at = DVec3::from_array(p.at);
            let (f, _, d) = bvh
                .nearest(&mesh.positions, &mesh.triangles, at)
                .ok_or_else(|| part.err("the surface has no triangles".into()))?;
            if d > far {
                return Err(part.err(format!(
                    "piece {k} '{}': `at` ({:.2}, {:.2}, {:.2}) is {d:.2} mm from the surface",
                    p.name, at.x, at.y, at.z
                )));
            }
            pieces_of_region[split.region_of_face[f] as usize].push(k);
        }
        Ok(PartRegions {
            mesh: embedded.mesh,
            lines: embedded.lines,
            notches: embedded.notches,
            split,
            pieces_of_region,
            edges,
        })
    }
}

/// Splits a part along its style lines into its pieces and seams.
fn split_part(
    part: &PartDef,
    base_dir: &Path,
    tol: &Tolerances,
    out: &mut Assembly,
) -> Result<(), DesignError> {
    let regions = part.regions(base_dir, tol)?;
    let split = &regions.split;
    for ks in &regions.pieces_of_region {
        if let [j, k, ..] = ks[..] {
            let at = part.pieces[k].at;
            return Err(part.err(format!(
                "pieces {j} '{}' and {k} '{}' name the same region (near ({:.1}, {:.1}, {:.1})): a style line between them is missing or does not close",
                part.pieces[j].name, part.pieces[k].name, at[0], at[1], at[2]
            )));
        }
    }
    let piece_of_region: Vec<Option<usize>> = regions
        .pieces_of_region
        .iter()
        .map(|ks| ks.first().copied())
        .collect();
    if let Some(r) = piece_of_region.iter().position(Option::is_none) {
        let reg = &split.regions[r];
        let c = inner_point(&reg.mesh);
        let mut around: Vec<&str> = split
            .seams
            .iter()
            .filter(|s| s.sides.iter().any(|x| x.piece == r))
            .map(|s| part.lines[s.line].name.as_str())
            .collect();
        around.dedup();
        return Err(part.err(format!(
            "the region near ({:.1}, {:.1}, {:.1}) ({:.0} mm², bounded by line(s) {}) is named by no [[part.piece]]: add one with `at` inside it",
            c.x,
            c.y,
            c.z,
            reg.mesh.area(),
            if around.is_empty() {
                "none".to_string()
            } else {
                around.join(", ")
            }
        )));
    }
    // The pieces, in the part's order.
    let first = out.pieces.len();
    let mut index_of_region = vec![0usize; split.regions.len()];
    let mut region_of_piece = vec![0usize; part.pieces.len()];
    for (r, k) in piece_of_region.iter().enumerate() {
        let k = k.expect("every region is named");
        region_of_piece[k] = r;
        index_of_region[r] = first + k;
    }
    for (k, &r) in region_of_piece.iter().enumerate() {
        let mut def = part.piece_def(k);
        def.resolve_pairs();
        let reg = &split.regions[r];
        check_disk(&reg.mesh).map_err(|e| {
            part.err(format!(
                "piece {k} '{}': its region is not a disk ({e}); add a style line that cuts it open",
                def.name
            ))
        })?;
        def.outline_edges = regions.edges.clone();
        out.pieces.push(AssembledPiece {
            def,
            part: Some(part.name.clone()),
            mesh: reg.mesh.clone(),
            notch_marks: Vec::new(),
        });
    }
    // The seams: one per stretch of a line between two regions.
    for (k, line) in part.lines.iter().enumerate() {
        let runs: Vec<_> = split.seams.iter().filter(|s| s.line == k).collect();
        for (i, run) in runs.iter().enumerate() {
            let name = if runs.len() == 1 {
                line.name.clone()
            } else {
                format!("{}-{}", line.name, i + 1)
            };
            let path = &regions.lines[k];
            let mut notches = Vec::new();
            for (j, &nv) in regions.notches[k].iter().enumerate() {
                if let Some(at) = run.path_index.iter().position(|&p| path[p] == nv) {
                    notches.push(SeamNotch {
                        name: format!("{} {}", line.name, j + 1),
                        index: at,
                    });
                }
            }
            let seam = MatingSeam {
                name,
                sides: run.sides.clone().map(|s| SeamSide {
                    piece: index_of_region[s.piece],
                    vertices: s.vertices,
                }),
                notches,
            };
            line_edges(part, line, &seam, &mut out.pieces)?;
            out.seams.push(seam);
        }
    }
    Ok(())
}

/// The allowance a style line gives the pieces on its two sides along one of its seams: its
/// `allowance_mm`, or for a lapped seam 0 on the piece on top (cut raw) and the underlay on the
/// other. Every seam side becomes an edge of its piece named after the seam (the pieces' own
/// allowance where the line gives none), so each stretch of a pattern's outline is named.
fn line_edges(
    part: &PartDef,
    line: &LineDef,
    seam: &MatingSeam,
    pieces: &mut [AssembledPiece],
) -> Result<(), DesignError> {
    let names = seam
        .sides
        .each_ref()
        .map(|s| pieces[s.piece].def.name.clone());
    if let Some(lap) = &line.lap {
        let what = format!("line '{}'", line.name);
        if names[0] == names[1] {
            return Err(part.err(format!(
                "{what}: lap = \"{lap}\": the line has '{}' on both sides, so nothing laps",
                names[0]
            )));
        }
        if !names.contains(lap) {
            return Err(part.err(format!(
                "{what}: lap = \"{lap}\" is not beside the line (seam '{}' lies between '{}' and '{}')",
                seam.name, names[0], names[1]
            )));
        }
    }
    for (side, name) in seam.sides.iter().zip(&names) {
        let (kind, allowance_mm) = match &line.lap {
            Some(top) if top == name => (EdgeKind::Raw, Some(0.0)),
            Some(_) => (
                EdgeKind::Seam,
                Some(line.underlay_mm.unwrap_or(LineDef::UNDERLAY_MM)),
            ),
            None => (EdgeKind::Seam, line.allowance_mm),
        };
        let piece = &mut pieces[side.piece];
        let points = side
            .vertices
            .iter()
            .map(|&v| piece.mesh.positions[v as usize])
            .collect();
        piece.def.outline_edges.push(OutlineEdge {
            name: seam.name.clone(),
            kind,
            allowance_mm,
            points,
            closed: false,
        });
    }
    Ok(())
}

/// Inserts the piece's notch marks as boundary vertices, each exactly where its point falls.
fn place_notch_marks(p: &mut AssembledPiece) -> Result<(), DesignError> {
    let tol = OFF_SURFACE_REL * p.mesh.bbox().diagonal();
    for m in p
        .def
        .marks
        .iter()
        .filter(|m| m.kind == crate::MarkKind::Notch)
    {
        for q in &m.points {
            let what = format!("notch mark '{}'", m.name);
            let v =
                boundary_vertex(&mut p.mesh, DVec3::from_array(*q), tol, &what).map_err(|e| {
                    DesignError::Piece {
                        file: p.def.file.clone(),
                        index: p.def.index,
                        piece: p.def.name.clone(),
                        msg: e.to_string(),
                    }
                })?;
            p.notch_marks.push((m.name.clone(), v));
        }
    }
    Ok(())
}

/// A point of the mesh near the middle of its surface: the vertex nearest to the area-weighted
/// centroid (the centroid itself may lie off a curved or non-convex region).
fn inner_point(m: &TriMesh) -> DVec3 {
    let mut c = DVec3::ZERO;
    let mut area = 0.0;
    for t in 0..m.triangles.len() {
        let a = m.triangle_area(t);
        let [p, q, r] = m.corners(t);
        c += (p + q + r) / 3.0 * a;
        area += a;
    }
    let c = if area > 0.0 { c / area } else { c };
    m.positions
        .iter()
        .copied()
        .min_by(|a, b| a.distance(c).total_cmp(&b.distance(c)))
        .unwrap_or(c)
}
