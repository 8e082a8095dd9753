//! Parts and joins: one surface cut into pieces by style lines (`[[part]]`), and mating seams
//! declared between edges of separate pieces (`[[join]]`). The schema, its checks and its unit
//! scaling; building the pieces and seams is [`crate::assemble`].
//!
//! ```toml
//! [[part]]
//! name = "upper"
//! [part.surface]                 # any surface type
//! type = "patches"
//! ...
//! [[part.line]]                  # a style line: points projected onto the surface, joined along it
//! name = "vamp-quarter"
//! points = [[x, y, z], ...]      # ends on the surface boundary or on another line
//! notches = [[x, y, z], ...]     # optional: notches on this line, shared by both sides
//! allowance_mm = 6               # optional: the allowance on both pieces along the line, or
//! # lap = "vamp"                 # a lapped seam: the vamp on top, cut raw; the other piece
//! # underlay_mm = 10             # gets the underlay (default 10 mm)
//! [[part.edge]]                  # a stretch of the part's outline (see `crate::edge`)
//! name = "featherline"
//! from = [x, y, z]
//! to = [x, y, z]
//! allowance_mm = 16
//! kind = "lasting"
//! [[part.piece]]
//! name = "vamp"
//! at = [x, y, z]                 # a point inside the region: names it
//! pairs = 1                      # or quantity = 2
//! seam_allowance_mm = 8          # and material, grain, marks as in [[piece]]
//!
//! [[join]]                       # a mating seam between edges of separate pieces
//! name = "back"
//! a = { piece = "quarter", from = [x, y, z], to = [x, y, z] }
//! b = { piece = "counter", from = [x, y, z], to = [x, y, z] }
//! notches = [[x, y, z]]
//! ```

use flatcut_geom::limits;
use serde::Deserialize;

use crate::check::check_piece;
use crate::edge::{EdgeDef, check_allowance};
use crate::units::{Axes, map_piece, map_point};
use crate::{DesignError, GrainDef, MarkDef, P3, PieceDef, SurfaceDef};

/// One surface cut into pieces by style lines.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartDef {
    /// The part's name, used in messages.
    pub name: String,
    /// The one surface the part's pieces are cut from.
    pub surface: SurfaceDef,
    #[serde(default, rename = "line")]
    /// The style lines that divide the surface into pieces (`[[part.line]]`).
    pub lines: Vec<LineDef>,
    /// Named stretches of the part's outline with their own allowance.
    #[serde(default, rename = "edge")]
    pub edges: Vec<EdgeDef>,
    #[serde(rename = "piece")]
    /// The pieces of the part, one per region between the style lines and the outline
    /// (`[[part.piece]]`).
    pub pieces: Vec<PartPieceDef>,
    /// Position among the parts (0-based), set at load time.
    #[serde(skip)]
    pub index: usize,
    /// The file the part came from, for error messages.
    #[serde(skip)]
    pub file: String,
    /// The map from a mesh file's coordinates to mm (units, and a size's scale).
    #[serde(skip, default = "crate::schema::no_map")]
    pub mesh_map: Axes,
}

/// A style line on a part's surface.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineDef {
    /// The line's name: seams along it are named after it.
    pub name: String,
    /// Points on (or near) the surface, in order; joined along the surface.
    #[serde(default)]
    pub points: Vec<P3>,
    /// Instead of points: the STEP entity number of an `EDGE_CURVE` of the part's `step`
    /// surface (as `flatcut inspect model.step` lists it); the line is that edge.
    #[serde(default)]
    pub edge: Option<u64>,
    /// Notch positions on the line, shared by the pieces on both sides.
    #[serde(default)]
    pub notches: Vec<P3>,
    /// The allowance (mm) of both pieces along the line, in place of their own.
    #[serde(default)]
    pub allowance_mm: Option<f64>,
    /// A lapped seam: the piece named lies on top, its edge cut raw; the other gets
    /// `underlay_mm`.
    #[serde(default)]
    pub lap: Option<String>,
    /// The under piece's allowance along a lapped seam (mm; default [`LineDef::UNDERLAY_MM`]).
    #[serde(default)]
    pub underlay_mm: Option<f64>,
}

impl LineDef {
    /// A lapped seam's underlay when the line gives none (mm): 8–10 mm is the trade's range.
    pub const UNDERLAY_MM: f64 = 10.0;
}

/// A piece of a part: the region around `at`, with the keys of a `[[piece]]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartPieceDef {
    /// The piece's name, unique in the design.
    pub name: String,
    /// A point inside the region (on or near the surface).
    pub at: P3,
    #[serde(default = "crate::schema::one")]
    /// How many to cut as drawn (default 1; set from `pairs` when given).
    pub quantity: u32,
    #[serde(default)]
    /// `pairs = N`: N as drawn and N mirrored (left and right).
    pub pairs: Option<u32>,
    #[serde(default)]
    /// What the labels of a pair say: as drawn, then mirrored (default "L", "R").
    pub pair_labels: Option<[String; 2]>,
    #[serde(default)]
    /// Notches, stitch lines and points on the piece's region of the surface.
    pub marks: Vec<MarkDef>,
    #[serde(default)]
    /// Grain direction: two points on (or near) the region, or `"auto"`.
    pub grain: Option<GrainDef>,
    #[serde(default)]
    /// Seam allowance in mm whatever the file's units (default: the project's).
    pub seam_allowance_mm: Option<f64>,
    #[serde(default)]
    /// The material's name as printed on the pattern piece (a label only).
    pub material: Option<String>,
    #[serde(default)]
    /// A bundled material or a material file relative to the design: its limits and stiffness drive
    /// the flattening.
    pub material_properties: Option<String>,
}

/// A mating seam between two boundary stretches of pieces (of any part or `[[piece]]`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JoinDef {
    /// The seam's name, used in the report and on notches.
    pub name: String,
    /// The first piece's edge.
    pub a: JoinEdgeDef,
    /// The second piece's edge, sewn to `a`.
    pub b: JoinEdgeDef,
    /// Notches on the seam: each is placed on both edges at its nearest point.
    #[serde(default)]
    pub notches: Vec<P3>,
    /// Position among the joins (0-based), set at load time.
    #[serde(skip)]
    pub index: usize,
}

/// One edge of a join: the stretch of a piece's boundary from `from` to `to` (the shorter way
/// round, or the way through `via`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JoinEdgeDef {
    /// The name of the piece (a `[[piece]]` or a part's piece) whose boundary the edge lies on.
    pub piece: String,
    /// Where the edge starts: a point on (or near) the piece's boundary.
    pub from: P3,
    /// Where the edge ends: a point on (or near) the piece's boundary.
    pub to: P3,
    #[serde(default)]
    /// A point the edge passes nearest, to choose between the two ways round (default: the
    /// shorter).
    pub via: Option<P3>,
}

impl PartDef {
    /// An error about this part.
    pub(crate) fn err(&self, msg: String) -> DesignError {
        DesignError::Part {
            file: self.file.clone(),
            index: self.index,
            part: self.name.clone(),
            msg,
        }
    }

    /// The part's surface as a piece of its own (for building and tessellating it).
    pub(crate) fn surface_piece(&self) -> PieceDef {
        PieceDef {
            index: self.index,
            mesh_map: self.mesh_map,
            ..PieceDef::of_surface(self.name.clone(), self.surface.clone(), self.file.clone())
        }
    }

    /// The piece definition of piece `k` (its surface is the part's; its mesh is its region).
    pub fn piece_def(&self, k: usize) -> PieceDef {
        let p = &self.pieces[k];
        PieceDef {
            quantity: p.quantity,
            pairs: p.pairs,
            pair_labels: p.pair_labels.clone(),
            marks: p.marks.clone(),
            grain: p.grain,
            seam_allowance_mm: p.seam_allowance_mm,
            material: p.material.clone(),
            material_properties: p.material_properties.clone(),
            index: k,
            mesh_map: self.mesh_map,
            ..PieceDef::of_surface(p.name.clone(), self.surface.clone(), self.file.clone())
        }
    }
}

/// Checks a parsed part (design units, `s` mm per unit): its surface, lines and pieces.
pub(crate) fn check_part(p: &PartDef, s: f64) -> Result<(), DesignError> {
    if p.pieces.is_empty() {
        return Err(p.err("it has no [[part.piece]]".into()));
    }
    for (k, l) in p.lines.iter().enumerate() {
        let what = format!("line {k} '{}'", l.name);
        if let Some(i) = out_of_range(&l.points, s) {
            return Err(p.err(format!(
                "{what}: point {i} has a coordinate that is not finite or beyond ±{:e} mm",
                limits::MAX_COORD_MM
            )));
        }
        if let Some(i) = out_of_range(&l.notches, s) {
            return Err(p.err(format!(
                "{what}: notch {i} has a coordinate that is not finite or beyond ±{:e} mm",
                limits::MAX_COORD_MM
            )));
        }
        match (l.edge, l.points.len()) {
            (Some(_), 0) if matches!(p.surface, SurfaceDef::Step { .. }) => {}
            (Some(_), 0) => {
                return Err(p.err(format!(
                    "{what}: `edge` names an edge of a STEP model; the part's surface is not `type = \"step\"`"
                )));
            }
            (Some(_), _) => {
                return Err(p.err(format!("{what}: give either `points` or `edge`, not both")));
            }
            (None, n) if n < 2 => {
                return Err(p.err(format!(
                    "{what}: a line needs at least two points (or `edge = N`, an edge of a STEP surface)"
                )));
            }
            (None, _) => {}
        }
        if let Some(j) = p.lines[..k].iter().position(|o| o.name == l.name) {
            return Err(p.err(format!("{what}: line {j} has the same name")));
        }
        check_allowance(&what, l.allowance_mm).map_err(|m| p.err(m))?;
        check_allowance(&format!("{what}: underlay_mm"), l.underlay_mm).map_err(|m| p.err(m))?;
        match (&l.lap, l.allowance_mm, l.underlay_mm) {
            (Some(_), Some(_), _) => {
                return Err(p.err(format!(
                    "{what}: give `allowance_mm` or `lap`, not both (a lapped seam's pieces get 0 and `underlay_mm`)"
                )));
            }
            (None, _, Some(_)) => {
                return Err(p.err(format!("{what}: `underlay_mm` needs `lap`")));
            }
            (Some(l), _, _) if !p.pieces.iter().any(|q| &q.name == l) => {
                return Err(p.err(format!("{what}: lap = \"{l}\" names no piece of the part")));
            }
            _ => {}
        }
    }
    for (k, e) in p.edges.iter().enumerate() {
        e.check(s).map_err(|m| p.err(m))?;
        if let Some(j) = p.edges[..k].iter().position(|o| o.name == e.name) {
            return Err(p.err(format!("edge '{}': edge {j} has the same name", e.name)));
        }
    }
    for k in 0..p.pieces.len() {
        let def = p.piece_def(k);
        check_piece(&def, s)
            .map_err(|e| p.err(format!("piece {k} '{}': {}", def.name, strip_context(&e))))?;
        if out_of_range(&[p.pieces[k].at], s).is_some() {
            return Err(p.err(format!(
                "piece {k} '{}': `at` has a coordinate that is not finite or beyond ±{:e} mm",
                def.name,
                limits::MAX_COORD_MM
            )));
        }
        if let Some(j) = p.pieces[..k].iter().position(|o| o.name == def.name) {
            return Err(p.err(format!(
                "piece {k} '{}': piece {j} has the same name",
                def.name
            )));
        }
    }
    Ok(())
}

/// The index of the first point with a coordinate not finite or out of range in mm (`s` mm per
/// design unit).
fn out_of_range(pts: &[P3], s: f64) -> Option<usize> {
    pts.iter()
        .position(|p| !p.iter().all(|x| limits::in_range(x * s)))
}

/// The message of a piece error without its "file: piece i 'name': " prefix.
fn strip_context(e: &DesignError) -> String {
    match e {
        DesignError::Piece { msg, .. } => msg.clone(),
        other => other.to_string(),
    }
}

/// Checks a parsed join (design units, `s` mm per unit).
pub(crate) fn check_join(file: &str, j: &JoinDef, s: f64) -> Result<(), DesignError> {
    let err = |msg: String| DesignError::Join {
        file: file.to_string(),
        index: j.index,
        join: j.name.clone(),
        msg,
    };
    for (side, e) in [("a", &j.a), ("b", &j.b)] {
        let mut pts = vec![e.from, e.to];
        pts.extend(e.via);
        if out_of_range(&pts, s).is_some() {
            return Err(err(format!(
                "{side}: a point has a coordinate that is not finite or beyond ±{:e} mm",
                limits::MAX_COORD_MM
            )));
        }
        if e.from == e.to {
            return Err(err(format!("{side}: `from` and `to` coincide")));
        }
    }
    if out_of_range(&j.notches, s).is_some() {
        return Err(err(format!(
            "a notch has a coordinate that is not finite or beyond ±{:e} mm",
            limits::MAX_COORD_MM
        )));
    }
    Ok(())
}

/// Maps a part's lengths (design units → mm when `units`, or a size of a grading).
pub(crate) fn map_part(p: &mut PartDef, m: &Axes, units: bool) -> Result<(), String> {
    let mut surf = p.surface_piece();
    map_piece(&mut surf, m, units)?;
    p.surface = surf.surface;
    p.mesh_map = surf.mesh_map;
    for l in &mut p.lines {
        l.points
            .iter_mut()
            .chain(l.notches.iter_mut())
            .for_each(|q| map_point(q, m));
    }
    for e in &mut p.edges {
        e.map(m);
    }
    for k in &mut p.pieces {
        map_point(&mut k.at, m);
        for mk in &mut k.marks {
            mk.points.iter_mut().for_each(|q| map_point(q, m));
        }
        if let Some(g) = k.grain.as_mut().and_then(GrainDef::line_mut) {
            g.iter_mut().for_each(|q| map_point(q, m));
        }
    }
    Ok(())
}

/// Maps a join's points.
pub(crate) fn map_join(j: &mut JoinDef, m: &Axes) {
    for e in [&mut j.a, &mut j.b] {
        map_point(&mut e.from, m);
        map_point(&mut e.to, m);
        if let Some(v) = &mut e.via {
            map_point(v, m);
        }
    }
    j.notches.iter_mut().for_each(|q| map_point(q, m));
}
