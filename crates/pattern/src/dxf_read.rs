//! DXF import: AAMA/ASTM D6673 pattern files (one block per piece, layers by number, piece
//! text), flat files with AAMA numbers or our named layers, and plain DXF from any CAD program
//! (closed chains of `LWPOLYLINE`, `POLYLINE`, `LINE`, `ARC`, `CIRCLE`, `ELLIPSE` and `SPLINE`)
//! into a [`Drawing`] in millimetres with stroke kinds and piece labels.
//!
//! Units: `$INSUNITS` where present (R13+), else the AAMA `Units:` text (`METRIC` = mm,
//! `ENGLISH` = inches), else millimetres with a warning. Curves are flattened within the chordal
//! tolerance. Pieces: in AAMA files each inserted block is a piece; elsewhere every closed cut
//! contour not inside another is a piece, and the strokes inside it belong to it.
//!
//! The group-code layer is small and written here (the same fixed subset the writer emits plus
//! the entities CAD programs write); the work is in chaining and AAMA semantics.

use crate::PatternError;
use crate::drawing::{Drawing, Layer, PieceInfo, Stroke, StrokeKind};
use crate::dxf::named_layer_kind;
use crate::piece::{LabelInfo, PieceOptions};
use crate::poly;
use flatcut_geom::DVec2;
use std::collections::BTreeMap;

/// Endpoints closer than this (mm) are joined when chaining lines and arcs into contours.
pub const CHAIN_TOL_MM: f64 = 1e-3;
/// Coordinates beyond this (mm, after unit scaling) are an error: no cutting table is a
/// kilometre wide, and larger values only come from broken files.
pub const MAX_COORD_MM: f64 = 1e6;
/// Most entities (after block expansion) a file may produce.
pub const MAX_ENTITIES: usize = 1_000_000;
/// Most points one flattened curve may produce.
const MAX_CURVE_POINTS: usize = 100_000;
/// Deepest nesting of block inserts followed.
const MAX_INSERT_DEPTH: usize = 8;
/// Largest spline degree accepted.
const MAX_SPLINE_DEGREE: usize = 11;

/// A DXF read into a drawing, with what was skipped or assumed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DxfImport {
    /// The contours read, pieces told apart by their outer boundaries.
    pub drawing: Drawing,
    /// Entities skipped and assumptions made (unit, open contours), one line each.
    pub warnings: Vec<String>,
}

fn err(line: usize, reason: impl Into<String>) -> PatternError {
    PatternError::Dxf {
        line,
        reason: reason.into(),
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Geo {
    Path { pts: Vec<DVec2>, closed: bool },
    Point(DVec2),
    Text { at: DVec2, value: String },
    Insert(Insert),
}

#[derive(Clone, Debug, PartialEq)]
struct Insert {
    name: String,
    at: DVec2,
    scale: DVec2,
    rotation_deg: f64,
}

#[derive(Clone, Debug, PartialEq)]
struct Entity {
    layer: String,
    geo: Geo,
    line: usize,
}

#[derive(Clone, Debug, Default)]
struct BlockDef {
    base: DVec2,
    entities: Vec<Entity>,
}

/// One group: code, value, 1-based line number of the code.
type Pair<'a> = (i32, &'a str, usize);

fn pairs(text: &str) -> Result<Vec<Pair<'_>>, PatternError> {
    if text.starts_with("AutoCAD Binary DXF") {
        return Err(err(
            1,
            "binary DXF is not supported; save the file as ASCII DXF",
        ));
    }
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::with_capacity(lines.len() / 2);
    let mut k = 0;
    while k + 1 < lines.len() {
        let code: i32 = lines[k].trim().parse().map_err(|_| {
            err(
                k + 1,
                format!("group code expected, found `{}`", lines[k].trim()),
            )
        })?;
        out.push((code, lines[k + 1].trim(), k + 1));
        k += 2;
    }
    if k < lines.len() && !lines[k].trim().is_empty() {
        return Err(err(k + 1, "odd number of lines (code/value pairs)"));
    }
    Ok(out)
}

fn number(v: &str, line: usize) -> Result<f64, PatternError> {
    v.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && x.abs() <= MAX_COORD_MM * 1e3)
        .ok_or_else(|| err(line + 1, format!("number expected, found `{v}`")))
}

/// Reads a DXF into a drawing in mm; curves are flattened within `chord_tol` mm.
pub fn read_dxf(text: &str, chord_tol: f64) -> Result<DxfImport, PatternError> {
    let (top, n_insert, warnings) = read_entities(text, chord_tol)?;
    Ok(classify(top, n_insert, warnings))
}

/// A contour of a DXF with the name of its layer (lines and arcs chained into contours).
#[derive(Clone, Debug, PartialEq)]
pub struct LayerPath {
    /// The DXF layer the contour was drawn on.
    pub layer: String,
    /// Points in mm; a closed contour does not repeat its first point.
    pub points: Vec<DVec2>,
    /// True when the contour closes on itself.
    pub closed: bool,
}

/// Reads a DXF's contours by layer name, for files whose layers say what a contour is (a hide's
/// outline, defects and zones), with the same entities, units and chaining as [`read_dxf`].
pub fn read_dxf_layers(
    text: &str,
    chord_tol: f64,
) -> Result<(Vec<LayerPath>, Vec<String>), PatternError> {
    let (top, _, warnings) = read_entities(text, chord_tol)?;
    let mut groups: BTreeMap<String, Vec<(Vec<DVec2>, bool)>> = BTreeMap::new();
    for (_, e) in top {
        if let Geo::Path { pts, closed } = e.geo
            && pts.len() >= 2
        {
            groups.entry(e.layer).or_default().push((pts, closed));
        }
    }
    let mut out = Vec::new();
    for (layer, paths) in groups {
        for (points, closed) in chain(paths) {
            out.push(LayerPath {
                layer: layer.clone(),
                points,
                closed,
            });
        }
    }
    Ok((out, warnings))
}

/// The entities of a DXF with inserts expanded and units applied: (top-level insert index,
/// entity), the number of inserts, and warnings.
fn read_entities(
    text: &str,
    chord_tol: f64,
) -> Result<(Vec<(Option<usize>, Entity)>, usize, Vec<String>), PatternError> {
    if !(chord_tol.is_finite() && chord_tol > 0.0) {
        return Err(err(
            0,
            format!("chord tolerance must be positive, got {chord_tol}"),
        ));
    }
    let pairs = pairs(text)?;
    let mut warnings = Vec::new();
    let sections = read_sections(&pairs, chord_tol)?;
    if !sections.seen_eof && pairs.last().is_some_and(|p| p.1 != "EOF") {
        warnings.push("no EOF marker: the file may be truncated".into());
    }
    for (name, n) in &sections.skipped {
        warnings.push(format!(
            "{n} {name} entit{} skipped (not a cut or drawn line)",
            if *n == 1 { "y" } else { "ies" }
        ));
    }
    let (mut top, n_insert) = expand_inserts(sections.entities, &sections.blocks)?;
    let scale = unit_scale(sections.insunits, &top, &mut warnings);
    for (_, e) in &mut top {
        scale_geo(&mut e.geo, scale);
        check_range(e)?;
    }
    Ok((top, n_insert, warnings))
}

/// What the sections of a DXF hold, as read.
#[derive(Default)]
struct Sections {
    /// `$INSUNITS` of the header, if given.
    insunits: Option<i64>,
    /// The block definitions, by name.
    blocks: BTreeMap<String, BlockDef>,
    /// The entities of the `ENTITIES` section, in order.
    entities: Vec<Entity>,
    /// Entities skipped, counted by kind.
    skipped: BTreeMap<String, usize>,
    /// Whether an `EOF` marker ended the file.
    seen_eof: bool,
}

/// Reads the header's unit, the blocks and the entities of the group pairs, curves flattened
/// within `chord_tol`.
fn read_sections(pairs: &[Pair<'_>], chord_tol: f64) -> Result<Sections, PatternError> {
    let mut s = Sections::default();
    let mut i = 0;
    let mut section = String::new();
    while i < pairs.len() {
        let (code, val, line) = pairs[i];
        match (code, val) {
            (0, "SECTION") => {
                section = pairs
                    .get(i + 1)
                    .filter(|p| p.0 == 2)
                    .map(|p| p.1.to_string())
                    .unwrap_or_default();
                i += 2;
            }
            (0, "ENDSEC") => {
                section.clear();
                i += 1;
            }
            (0, "EOF") => {
                s.seen_eof = true;
                break;
            }
            (9, "$INSUNITS") if section == "HEADER" => {
                if let Some(&(70, v, l)) = pairs.get(i + 1) {
                    s.insunits = Some(number(v, l)? as i64);
                }
                i += 2;
            }
            (0, "BLOCK") if section == "BLOCKS" => {
                let (name, def) = block(pairs, &mut i, chord_tol, &mut s.skipped)?;
                s.blocks.insert(name, def);
            }
            (0, _) if section == "ENTITIES" => {
                if let Some(e) = entity(pairs, &mut i, chord_tol, &mut s.skipped)? {
                    s.entities.push(e);
                }
                if s.entities.len() > MAX_ENTITIES {
                    return Err(err(line, format!("more than {MAX_ENTITIES} entities")));
                }
            }
            _ => i += 1,
        }
    }
    Ok(s)
}

/// Reads the block definition starting at `pairs[*i]` (its `BLOCK` pair) up to its `ENDBLK`;
/// advances past it.
fn block(
    pairs: &[Pair<'_>],
    i: &mut usize,
    chord_tol: f64,
    skipped: &mut BTreeMap<String, usize>,
) -> Result<(String, BlockDef), PatternError> {
    *i += 1;
    let mut def = BlockDef::default();
    let mut name = String::new();
    while *i < pairs.len() && pairs[*i].0 != 0 {
        let (c, v, l) = pairs[*i];
        match c {
            2 => name = v.to_string(),
            10 => def.base.x = number(v, l)?,
            20 => def.base.y = number(v, l)?,
            _ => {}
        }
        *i += 1;
    }
    while *i < pairs.len() && !(pairs[*i].0 == 0 && pairs[*i].1 == "ENDBLK") {
        if pairs[*i].1 == "EOF" || pairs[*i].1 == "ENDSEC" {
            return Err(err(pairs[*i].2, format!("block `{name}` without ENDBLK")));
        }
        if let Some(e) = entity(pairs, i, chord_tol, skipped)? {
            def.entities.push(e);
        }
    }
    *i += 1;
    Ok((name, def))
}

/// The entities with every insert replaced by its block's entities: every top-level insert is
/// a piece candidate, so each entity carries the index of the insert it came from. Also returns
/// the number of inserts.
fn expand_inserts(
    entities: Vec<Entity>,
    blocks: &BTreeMap<String, BlockDef>,
) -> Result<(Vec<(Option<usize>, Entity)>, usize), PatternError> {
    let mut top: Vec<(Option<usize>, Entity)> = Vec::new();
    let mut n_insert = 0;
    let mut count = 0usize;
    for e in entities {
        match &e.geo {
            Geo::Insert(ins) => {
                let mut out = Vec::new();
                expand(ins, blocks, 0, e.line, &mut out, &mut count)?;
                top.extend(out.into_iter().map(|x| (Some(n_insert), x)));
                n_insert += 1;
            }
            _ => top.push((None, e)),
        }
    }
    Ok((top, n_insert))
}

/// Millimetres per drawing unit: `$INSUNITS` where it names a length unit, else the AAMA
/// `Units:` text, else 1 (with a warning).
fn unit_scale(
    insunits: Option<i64>,
    top: &[(Option<usize>, Entity)],
    warnings: &mut Vec<String>,
) -> f64 {
    let aama_units = top.iter().find_map(|(_, e)| match &e.geo {
        Geo::Text { value, .. } => aama_field(value, "Units"),
        _ => None,
    });
    match (insunits, aama_units.as_deref()) {
        (Some(1), _) => 25.4,
        (Some(2), _) => 304.8,
        (Some(4), _) => 1.0,
        (Some(5), _) => 10.0,
        (Some(6), _) => 1000.0,
        (_, Some(u)) if u.eq_ignore_ascii_case("ENGLISH") => 25.4,
        (_, Some(u)) if u.eq_ignore_ascii_case("METRIC") => 1.0,
        (Some(u), _) if u != 0 => {
            warnings.push(format!(
                "$INSUNITS {u} is not a length unit flatcut reads: read as mm"
            ));
            1.0
        }
        _ => {
            warnings
                .push("the file states no unit ($INSUNITS or AAMA `Units:`): read as mm".into());
            1.0
        }
    }
}

/// Reads one entity starting at `pairs[*i]` (a code-0 pair); advances past it.
fn entity(
    pairs: &[Pair<'_>],
    i: &mut usize,
    tol: f64,
    skipped: &mut BTreeMap<String, usize>,
) -> Result<Option<Entity>, PatternError> {
    let (_, kind, line) = pairs[*i];
    *i += 1;
    let start = *i;
    while *i < pairs.len() && pairs[*i].0 != 0 {
        *i += 1;
    }
    let body = Body::new(kind, line, &pairs[start..*i])?;
    let geo = match kind {
        "LINE" => line_geo(&body)?,
        "POINT" => Geo::Point(body.point(10, 20)?),
        "CIRCLE" | "ARC" => circle_or_arc(&body, tol)?,
        "ELLIPSE" => ellipse(&body, tol)?,
        "LWPOLYLINE" => lwpolyline(&body, tol)?,
        "POLYLINE" => match polyline(&body, pairs, i, tol)? {
            Some(geo) => geo,
            None => {
                *skipped.entry("POLYLINE mesh".into()).or_default() += 1;
                return Ok(None);
            }
        },
        "SPLINE" => spline(body.pairs, line, tol)?,
        "TEXT" | "MTEXT" => text(&body)?,
        "INSERT" => insert(&body)?,
        other => {
            *skipped.entry(other.to_string()).or_default() += 1;
            return Ok(None);
        }
    };
    Ok(Some(Entity {
        layer: body.layer(),
        geo,
        line,
    }))
}

/// The groups of one entity after its code-0 pair, with the entity's name, line and
/// orientation.
struct Body<'p, 'a> {
    kind: &'a str,
    line: usize,
    pairs: &'p [Pair<'a>],
    /// OCS with extrusion (0, 0, -1): x is mirrored (arcs drawn from below).
    flip: bool,
}

impl<'p, 'a> Body<'p, 'a> {
    fn new(kind: &'a str, line: usize, pairs: &'p [Pair<'a>]) -> Result<Self, PatternError> {
        let mut body = Body {
            kind,
            line,
            pairs,
            flip: false,
        };
        body.flip = body.get_or(230, 1.0)? < 0.0;
        Ok(body)
    }

    /// The layer name (code 8), `0` when none is given.
    fn layer(&self) -> String {
        self.pairs
            .iter()
            .find(|p| p.0 == 8)
            .map(|p| p.1.to_string())
            .unwrap_or_else(|| "0".into())
    }

    /// The number of the first group with code `c`, `d` when there is none.
    fn get_or(&self, c: i32, d: f64) -> Result<f64, PatternError> {
        match self.pairs.iter().find(|p| p.0 == c) {
            Some(&(_, v, l)) => number(v, l),
            None => Ok(d),
        }
    }

    /// The number of the first group with code `c`, 0 when there is none.
    fn get(&self, c: i32) -> Result<f64, PatternError> {
        self.get_or(c, 0.0)
    }

    /// The point of codes `cx`, `cy` as written, in the entity's own coordinates.
    fn xy(&self, cx: i32, cy: i32) -> Result<DVec2, PatternError> {
        Ok(DVec2::new(self.get(cx)?, self.get(cy)?))
    }

    /// A point of the entity's own coordinates in the drawing's.
    fn ocs(&self, p: DVec2) -> DVec2 {
        if self.flip { DVec2::new(-p.x, p.y) } else { p }
    }

    /// The point of codes `cx`, `cy` in the drawing's coordinates.
    fn point(&self, cx: i32, cy: i32) -> Result<DVec2, PatternError> {
        Ok(self.ocs(self.xy(cx, cy)?))
    }

    /// Bit 1 of the flags (code 70): a closed polyline.
    fn closed_flag(&self) -> Result<bool, PatternError> {
        Ok((self.get(70)? as i64) & 1 == 1)
    }
}

/// A `LINE`: its two endpoints.
fn line_geo(body: &Body<'_, '_>) -> Result<Geo, PatternError> {
    Ok(Geo::Path {
        pts: vec![body.point(10, 20)?, body.point(11, 21)?],
        closed: false,
    })
}

/// A `CIRCLE` or `ARC`, flattened within `tol`.
fn circle_or_arc(body: &Body<'_, '_>, tol: f64) -> Result<Geo, PatternError> {
    let c = body.xy(10, 20)?;
    let r = body.get(40)?;
    if r.is_nan() || r <= 0.0 {
        return Err(err(body.line, format!("{} with radius {r}", body.kind)));
    }
    let (a0, a1, closed) = if body.kind == "CIRCLE" {
        (0.0, 360.0, true)
    } else {
        let (a0, mut a1) = (body.get(50)?, body.get(51)?);
        while a1 <= a0 {
            a1 += 360.0;
        }
        (a0, a1, false)
    };
    let mut pts = arc_points(c, r, a0.to_radians(), a1.to_radians(), tol);
    if closed {
        pts.pop();
    }
    Ok(Geo::Path {
        pts: pts.into_iter().map(|p| body.ocs(p)).collect(),
        closed,
    })
}

/// An `ELLIPSE` (or an arc of one), flattened within `tol`.
fn ellipse(body: &Body<'_, '_>, tol: f64) -> Result<Geo, PatternError> {
    let c = body.xy(10, 20)?;
    let major = body.xy(11, 21)?;
    let ratio = body.get_or(40, 1.0)?;
    let (t0, mut t1) = (
        body.get_or(41, 0.0)?,
        body.get_or(42, std::f64::consts::TAU)?,
    );
    while t1 <= t0 {
        t1 += std::f64::consts::TAU;
    }
    let minor = DVec2::new(-major.y, major.x) * ratio;
    let a = major.length();
    if !(a > 0.0 && ratio > 0.0) {
        return Err(err(body.line, "ELLIPSE with a zero axis"));
    }
    let step = 2.0 * (1.0 - (tol / a).min(1.0)).acos().max(1e-4);
    let n = (((t1 - t0) / step).ceil() as usize).clamp(4, MAX_CURVE_POINTS);
    let closed = (t1 - t0 - std::f64::consts::TAU).abs() < 1e-9;
    let m = if closed { n } else { n + 1 };
    let pts = (0..m)
        .map(|k| {
            let t = t0 + (t1 - t0) * k as f64 / n as f64;
            body.ocs(c + major * t.cos() + minor * t.sin())
        })
        .collect();
    Ok(Geo::Path { pts, closed })
}

/// An `LWPOLYLINE`: its vertices (codes 10, 20) and bulges (42), arcs flattened within `tol`.
fn lwpolyline(body: &Body<'_, '_>, tol: f64) -> Result<Geo, PatternError> {
    let closed = body.closed_flag()?;
    let mut verts: Vec<(DVec2, f64)> = Vec::new();
    for &(c, v, l) in body.pairs {
        match c {
            10 => verts.push((DVec2::new(number(v, l)?, 0.0), 0.0)),
            20 => {
                if let Some(p) = verts.last_mut() {
                    p.0.y = number(v, l)?;
                }
            }
            42 => {
                if let Some(p) = verts.last_mut() {
                    p.1 = number(v, l)?;
                }
            }
            _ => {}
        }
    }
    Ok(bulge_path(&verts, closed, tol, |p| body.ocs(p)))
}

/// A `POLYLINE` with the `VERTEX` entities and the `SEQEND` after it (`*i` is advanced past
/// them), arcs flattened within `tol`; `None` for a polygon or polyface mesh.
fn polyline(
    body: &Body<'_, '_>,
    pairs: &[Pair<'_>],
    i: &mut usize,
    tol: f64,
) -> Result<Option<Geo>, PatternError> {
    let flags = body.get(70)? as i64;
    let closed = flags & 1 == 1;
    let verts = polyline_vertices(pairs, i)?;
    skip_seqend(pairs, i, body.line)?;
    if flags & (16 | 64) != 0 {
        return Ok(None);
    }
    Ok(Some(bulge_path(&verts, closed, tol, |p| body.ocs(p))))
}

/// The `VERTEX` entities from `pairs[*i]` on: each one's point and bulge; advances past them.
fn polyline_vertices(pairs: &[Pair<'_>], i: &mut usize) -> Result<Vec<(DVec2, f64)>, PatternError> {
    let mut verts = Vec::new();
    while *i < pairs.len() && pairs[*i].0 == 0 && pairs[*i].1 == "VERTEX" {
        *i += 1;
        let (mut p, mut b) = (DVec2::ZERO, 0.0);
        while *i < pairs.len() && pairs[*i].0 != 0 {
            let (c, v, l) = pairs[*i];
            match c {
                10 => p.x = number(v, l)?,
                20 => p.y = number(v, l)?,
                42 => b = number(v, l)?,
                _ => {}
            }
            *i += 1;
        }
        verts.push((p, b));
    }
    Ok(verts)
}

/// Advances past the `SEQEND` at `pairs[*i]` that ends the `POLYLINE` of line `line`; an error
/// when there is none.
fn skip_seqend(pairs: &[Pair<'_>], i: &mut usize, line: usize) -> Result<(), PatternError> {
    if *i < pairs.len() && pairs[*i].1 == "SEQEND" {
        *i += 1;
        while *i < pairs.len() && pairs[*i].0 != 0 {
            *i += 1;
        }
        Ok(())
    } else {
        let ln = pairs.get(*i).map_or(line, |p| p.2);
        Err(err(ln, "POLYLINE without SEQEND"))
    }
}

/// A `TEXT` or `MTEXT`: its insertion point and its text (codes 3 and 1, in order).
fn text(body: &Body<'_, '_>) -> Result<Geo, PatternError> {
    let mut value = String::new();
    for &(c, v, _) in body.pairs {
        if c == 3 || c == 1 {
            value.push_str(v);
        }
    }
    Ok(Geo::Text {
        at: body.point(10, 20)?,
        value,
    })
}

/// An `INSERT` of a block; arrays of inserts are refused.
fn insert(body: &Body<'_, '_>) -> Result<Geo, PatternError> {
    let name = body
        .pairs
        .iter()
        .find(|p| p.0 == 2)
        .map(|p| p.1.to_string())
        .unwrap_or_default();
    let cols = body.get_or(70, 1.0)?;
    let rows = body.get_or(71, 1.0)?;
    if cols > 1.0 || rows > 1.0 {
        return Err(err(
            body.line,
            format!("INSERT of `{name}` as a {cols}×{rows} array is not supported"),
        ));
    }
    let mirror = if body.flip { -1.0 } else { 1.0 };
    Ok(Geo::Insert(Insert {
        name,
        at: body.point(10, 20)?,
        scale: DVec2::new(body.get_or(41, 1.0)? * mirror, body.get_or(42, 1.0)?),
        rotation_deg: body.get(50)? * mirror,
    }))
}

/// Points of an arc from angle `a0` to `a1` (radians, counter-clockwise), within `tol`.
fn arc_points(c: DVec2, r: f64, a0: f64, a1: f64, tol: f64) -> Vec<DVec2> {
    let step = 2.0 * (1.0 - (tol / r).min(1.0)).acos().max(1e-4);
    let n = (((a1 - a0).abs() / step).ceil() as usize).clamp(1, MAX_CURVE_POINTS);
    (0..=n)
        .map(|k| c + r * DVec2::from_angle(a0 + (a1 - a0) * k as f64 / n as f64))
        .collect()
}

/// A polyline with bulges (bulge `k` on the segment leaving vertex `k`) flattened.
fn bulge_path(verts: &[(DVec2, f64)], closed: bool, tol: f64, ocs: impl Fn(DVec2) -> DVec2) -> Geo {
    let mut pts = Vec::new();
    let n = verts.len();
    let segs = if closed { n } else { n.saturating_sub(1) };
    for k in 0..segs {
        let (p0, b) = verts[k];
        let p1 = verts[(k + 1) % n].0;
        if b == 0.0 || p0.distance(p1) == 0.0 {
            pts.push(p0);
            continue;
        }
        let (c, r, a0, sweep) = crate::fit::arc_geometry(p0, p1, b);
        let mut arc = arc_points(c, r, a0, a0 + sweep, tol);
        arc.pop();
        arc[0] = p0;
        pts.extend(arc);
    }
    if !closed && let Some(last) = verts.last() {
        pts.push(last.0);
    }
    Geo::Path {
        pts: pts.into_iter().map(ocs).collect(),
        closed,
    }
}

/// A `SPLINE` (NURBS by control points, or a polyline through its fit points) flattened.
fn spline(body: &[Pair<'_>], line: usize, tol: f64) -> Result<Geo, PatternError> {
    let mut degree = 3usize;
    let mut flags = 0i64;
    let (mut knots, mut weights, mut ctrl, mut fit) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &(c, v, l) in body {
        match c {
            70 => flags = number(v, l)? as i64,
            71 => degree = number(v, l)? as usize,
            40 => knots.push(number(v, l)?),
            41 => weights.push(number(v, l)?),
            10 => ctrl.push(DVec2::new(number(v, l)?, 0.0)),
            20 => {
                if let Some(p) = ctrl.last_mut() {
                    p.y = number(v, l)?;
                }
            }
            11 => fit.push(DVec2::new(number(v, l)?, 0.0)),
            21 => {
                if let Some(p) = fit.last_mut() {
                    p.y = number(v, l)?;
                }
            }
            _ => {}
        }
    }
    let closed = flags & 1 == 1;
    if ctrl.is_empty() {
        if fit.len() < 2 {
            return Err(err(line, "SPLINE without control or fit points"));
        }
        return Ok(Geo::Path { pts: fit, closed });
    }
    if degree == 0 || degree > MAX_SPLINE_DEGREE {
        return Err(err(
            line,
            format!("SPLINE of degree {degree} (1..={MAX_SPLINE_DEGREE} supported)"),
        ));
    }
    let n = ctrl.len();
    if knots.len() != n + degree + 1 || n <= degree {
        return Err(err(
            line,
            format!(
                "SPLINE with {} knots for {n} control points of degree {degree} (needs {})",
                knots.len(),
                n + degree + 1
            ),
        ));
    }
    if knots.windows(2).any(|w| w[1] < w[0]) {
        return Err(err(line, "SPLINE knots decrease"));
    }
    if weights.len() != n {
        weights = vec![1.0; n];
    }
    if weights.iter().any(|w| w.is_nan() || *w <= 0.0) {
        return Err(err(line, "SPLINE weight not positive"));
    }
    let eval = |t: f64| nurbs_point(degree, &knots, &ctrl, &weights, t);
    let (t0, t1) = (knots[degree], knots[n]);
    // Sample each knot span, then refine where the chord deviates more than `tol`.
    let mut params: Vec<f64> = Vec::new();
    for k in degree..n {
        let (a, b) = (knots[k], knots[k + 1]);
        if b > a {
            for j in 0..4 {
                params.push(a + (b - a) * j as f64 / 4.0);
            }
        }
    }
    params.push(t1);
    let mut pts = vec![eval(t0)];
    let mut stack: Vec<(f64, f64, DVec2, DVec2, u32)> = Vec::new();
    for w in params.windows(2).rev() {
        stack.push((w[0], w[1], eval(w[0]), eval(w[1]), 0));
    }
    while let Some((a, b, pa, pb, depth)) = stack.pop() {
        let m = 0.5 * (a + b);
        let pm = eval(m);
        let (d, _) = poly::seg_nearest(pa, pb, pm);
        if d > tol && depth < 20 && pts.len() + stack.len() < MAX_CURVE_POINTS {
            stack.push((m, b, pm, pb, depth + 1));
            stack.push((a, m, pa, pm, depth + 1));
        } else {
            pts.push(pb);
        }
    }
    if closed && pts.len() > 2 && pts[0].distance(pts[pts.len() - 1]) < CHAIN_TOL_MM {
        pts.pop();
    }
    Ok(Geo::Path { pts, closed })
}

/// A point of a NURBS curve by de Boor's algorithm in homogeneous coordinates.
fn nurbs_point(p: usize, u: &[f64], ctrl: &[DVec2], w: &[f64], t: f64) -> DVec2 {
    let n = ctrl.len();
    let mut k = p;
    while k + 1 < n && u[k + 1] <= t {
        k += 1;
    }
    let mut d: Vec<(DVec2, f64)> = (0..=p)
        .map(|j| (ctrl[j + k - p] * w[j + k - p], w[j + k - p]))
        .collect();
    for r in 1..=p {
        for j in (r..=p).rev() {
            let i = j + k - p;
            let den = u[i + p + 1 - r] - u[i];
            let a = if den > 0.0 { (t - u[i]) / den } else { 0.0 };
            d[j] = (
                d[j - 1].0 * (1.0 - a) + d[j].0 * a,
                d[j - 1].1 * (1.0 - a) + d[j].1 * a,
            );
        }
    }
    d[p].0 / d[p].1
}

fn expand(
    ins: &Insert,
    blocks: &BTreeMap<String, BlockDef>,
    depth: usize,
    line: usize,
    out: &mut Vec<Entity>,
    count: &mut usize,
) -> Result<(), PatternError> {
    if depth >= MAX_INSERT_DEPTH {
        return Err(err(
            line,
            format!(
                "blocks nested deeper than {MAX_INSERT_DEPTH} (at `{}`)",
                ins.name
            ),
        ));
    }
    let def = blocks
        .get(&ins.name)
        .ok_or_else(|| err(line, format!("INSERT of undefined block `{}`", ins.name)))?;
    let rot = DVec2::from_angle(ins.rotation_deg.to_radians());
    let map = |p: DVec2| ins.at + rot.rotate((p - def.base) * ins.scale);
    for e in &def.entities {
        *count += 1;
        if *count > MAX_ENTITIES {
            return Err(err(
                line,
                format!("more than {MAX_ENTITIES} entities after expanding blocks"),
            ));
        }
        match &e.geo {
            Geo::Insert(inner) => {
                let mut sub = Vec::new();
                expand(inner, blocks, depth + 1, e.line, &mut sub, count)?;
                for mut s in sub {
                    map_geo(&mut s.geo, &map);
                    out.push(s);
                }
            }
            g => {
                let mut g = g.clone();
                map_geo(&mut g, &map);
                out.push(Entity {
                    layer: e.layer.clone(),
                    geo: g,
                    line: e.line,
                });
            }
        }
    }
    Ok(())
}

fn map_geo(g: &mut Geo, map: &impl Fn(DVec2) -> DVec2) {
    match g {
        Geo::Path { pts, .. } => pts.iter_mut().for_each(|p| *p = map(*p)),
        Geo::Point(p) | Geo::Text { at: p, .. } => *p = map(*p),
        Geo::Insert(i) => i.at = map(i.at),
    }
}

fn scale_geo(g: &mut Geo, s: f64) {
    if s != 1.0 {
        map_geo(g, &|p| p * s);
    }
}

fn check_range(e: &Entity) -> Result<(), PatternError> {
    let bad = |p: &DVec2| !(p.x.abs() <= MAX_COORD_MM && p.y.abs() <= MAX_COORD_MM);
    let hit = match &e.geo {
        Geo::Path { pts, .. } => pts.iter().any(bad),
        Geo::Point(p) | Geo::Text { at: p, .. } => bad(p),
        Geo::Insert(_) => false,
    };
    if hit {
        return Err(err(
            e.line,
            format!("coordinate beyond {MAX_COORD_MM} mm on layer `{}`", e.layer),
        ));
    }
    Ok(())
}

/// `Field: value` of an AAMA text (case-insensitive field name).
fn aama_field(text: &str, field: &str) -> Option<String> {
    let (k, v) = text.split_once(':')?;
    k.trim()
        .eq_ignore_ascii_case(field)
        .then(|| v.trim().to_string())
}

/// Tool layer and kind of an AAMA layer number.
fn aama_layer_kind(name: &str) -> Option<(Layer, StrokeKind)> {
    Some(match name {
        "1" => (Layer::Cut, StrokeKind::Boundary),
        "4" => (Layer::Cut, StrokeKind::Notch),
        "6" => (Layer::Draw, StrokeKind::Mirror),
        "7" => (Layer::Draw, StrokeKind::Grain),
        "8" => (Layer::Draw, StrokeKind::Internal),
        "11" => (Layer::Cut, StrokeKind::InnerCut),
        "13" => (Layer::Cut, StrokeKind::Drill),
        "14" => (Layer::Draw, StrokeKind::Sew),
        "15" => (Layer::Engrave, StrokeKind::Text),
        _ => return None,
    })
}

/// Turns the expanded entities into strokes with kinds, pieces and labels.
fn classify(
    top: Vec<(Option<usize>, Entity)>,
    n_insert: usize,
    mut warnings: Vec<String>,
) -> DxfImport {
    // An AAMA file: some inserted block holds a boundary on layer 1.
    let aama_blocks = top
        .iter()
        .any(|(b, e)| b.is_some() && e.layer == "1" && matches!(e.geo, Geo::Path { .. }));
    let gathered = gather(top, aama_blocks, &mut warnings);
    let _ = n_insert;
    let mut strokes = group_strokes(gathered.groups, &mut warnings);
    let pieces = if aama_blocks {
        block_pieces(
            &mut strokes,
            gathered.labels,
            &gathered.grains,
            &mut warnings,
        )
    } else {
        contour_pieces(&mut strokes)
    };
    assign_ids(&mut strokes, &pieces);
    DxfImport {
        drawing: Drawing { strokes, pieces },
        warnings,
    }
}

/// What the top-level entities say, sorted by what classification does with it.
#[derive(Default)]
struct Gathered {
    /// (insert index or None, layer name) → paths to chain.
    groups: BTreeMap<(Option<usize>, String), Vec<(Vec<DVec2>, bool)>>,
    /// Per AAMA block: its piece label (layer 1 text).
    labels: BTreeMap<usize, LabelInfo>,
    /// Per AAMA block: its grain line (the first two-point line on layer 7).
    grains: BTreeMap<usize, (DVec2, DVec2)>,
}

/// Sorts the entities into paths per block and layer, labels and grain lines; blocks count only
/// in an AAMA file (`aama_blocks`).
fn gather(
    top: Vec<(Option<usize>, Entity)>,
    aama_blocks: bool,
    warnings: &mut Vec<String>,
) -> Gathered {
    let mut g = Gathered::default();
    for (b, e) in top {
        let block = if aama_blocks { b } else { None };
        match e.geo {
            Geo::Path { pts, closed } if pts.len() >= 2 => {
                if let (Some(k), "7") = (block, e.layer.as_str())
                    && pts.len() == 2
                {
                    g.grains.entry(k).or_insert((pts[0], pts[1]));
                }
                g.groups
                    .entry((block, e.layer.clone()))
                    .or_default()
                    .push((pts, closed));
            }
            Geo::Path { .. } => {}
            Geo::Point(p) if e.layer == "13" => {
                g.groups
                    .entry((block, e.layer.clone()))
                    .or_default()
                    .push((drill_hole(p), true));
            }
            Geo::Point(_) => {}
            Geo::Text { value, .. } => {
                if let (Some(k), "1") = (block, e.layer.as_str()) {
                    let label = g.labels.entry(k).or_insert_with(unlabelled);
                    read_label_text(label, &value, k, warnings);
                }
            }
            Geo::Insert(_) => {}
        }
    }
    g
}

/// A drill hole at `p` (AAMA layer 13) as a closed 24-gon of the default drill diameter.
fn drill_hole(p: DVec2) -> Vec<DVec2> {
    let drill_r = 0.5 * PieceOptions::DEFAULT_DRILL_DIAMETER;
    let n = 24;
    (0..n)
        .map(|k| p + drill_r * DVec2::from_angle(k as f64 * std::f64::consts::TAU / n as f64))
        .collect()
}

/// The label of a piece nothing names: quantity 1, no name, size or material.
fn unlabelled() -> LabelInfo {
    LabelInfo {
        quantity: 1,
        ..LabelInfo::default()
    }
}

/// Reads one AAMA piece text of block `k` (`Piece Name:`, `Size:`, `Material:` or `Quantity:`)
/// into its label.
fn read_label_text(label: &mut LabelInfo, value: &str, k: usize, warnings: &mut Vec<String>) {
    if let Some(v) = aama_field(value, "Piece Name") {
        label.name = v;
    } else if let Some(v) = aama_field(value, "Size") {
        label.size = v;
    } else if let Some(v) = aama_field(value, "Material") {
        label.material = v;
    } else if let Some(v) = aama_field(value, "Quantity") {
        match v.parse::<u32>() {
            Ok(q) if q > 0 => label.quantity = q,
            _ => warnings.push(format!(
                "piece {}: `Quantity: {v}` is not a positive count; 1 used",
                k + 1
            )),
        }
    }
}

/// The strokes of the grouped paths: each layer's kind, cuts and seams chained into contours,
/// open cut contours kept as lines (with a warning).
fn group_strokes(
    groups: BTreeMap<(Option<usize>, String), Vec<(Vec<DVec2>, bool)>>,
    warnings: &mut Vec<String>,
) -> Vec<Stroke> {
    let mut strokes: Vec<Stroke> = Vec::new();
    for ((block, layer), paths) in groups {
        let (tool, kind) = aama_layer_kind(&layer)
            .or_else(|| named_layer_kind(&layer))
            .unwrap_or((Layer::Cut, StrokeKind::InnerCut));
        let chain_it = matches!(
            kind,
            StrokeKind::Boundary | StrokeKind::InnerCut | StrokeKind::Sew
        );
        let paths = if chain_it { chain(paths) } else { paths };
        for (pts, closed) in paths {
            let kind = match kind {
                StrokeKind::Boundary | StrokeKind::InnerCut if !closed => {
                    warnings.push(open_contour_warning(&layer, &pts));
                    StrokeKind::Internal
                }
                k => k,
            };
            strokes.push(Stroke {
                layer: tool,
                points: pts,
                closed,
                piece: block.map(|k| k as u32),
                kind,
                id: String::new(),
            });
        }
    }
    strokes
}

/// The warning for an open contour on a cut layer.
fn open_contour_warning(layer: &str, pts: &[DVec2]) -> String {
    format!(
        "an open contour on layer `{layer}` ({} points from ({:.3}, {:.3})) is kept as a line, not a piece",
        pts.len(),
        pts[0].x,
        pts[0].y
    )
}

/// The pieces of an AAMA file, one per block, with the labels and grain lines read; loose
/// strokes join the piece that holds them.
fn block_pieces(
    strokes: &mut [Stroke],
    mut labels: BTreeMap<usize, LabelInfo>,
    grains: &BTreeMap<usize, (DVec2, DVec2)>,
    warnings: &mut Vec<String>,
) -> Vec<PieceInfo> {
    let mut pieces = Vec::new();
    let blocks: Vec<u32> = {
        let mut v: Vec<u32> = strokes.iter().filter_map(|s| s.piece).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    for b in blocks {
        if keep_largest_boundary(strokes, b).is_none() {
            warnings.push(format!(
                "block {} has no closed boundary on layer 1: not a piece",
                b + 1
            ));
        }
        let label = labels.remove(&(b as usize)).unwrap_or_else(unlabelled);
        pieces.push(PieceInfo {
            piece: b,
            label,
            grain: grains.get(&(b as usize)).copied(),
        });
    }
    // Loose strokes outside the blocks join the piece that holds them.
    crate::plain_pieces::assign_by_containment(strokes);
    pieces
}

/// In block `b`, the largest closed boundary is the piece and other closed boundaries become
/// cut-outs; returns the piece's stroke index, if the block has a boundary.
fn keep_largest_boundary(strokes: &mut [Stroke], b: u32) -> Option<usize> {
    let best = strokes
        .iter()
        .enumerate()
        .filter(|(_, s)| s.piece == Some(b) && s.kind == StrokeKind::Boundary)
        .max_by(|x, y| area(&x.1.points).total_cmp(&area(&y.1.points)))
        .map(|(i, _)| i);
    for (i, s) in strokes.iter_mut().enumerate() {
        if s.piece == Some(b) && s.kind == StrokeKind::Boundary && Some(i) != best {
            s.kind = StrokeKind::InnerCut;
        }
    }
    best
}

/// The pieces of a file without AAMA blocks: every outer closed cut contour, with the strokes
/// inside it and its grain line.
fn contour_pieces(strokes: &mut [Stroke]) -> Vec<PieceInfo> {
    crate::plain_pieces::find_pieces(strokes);
    let n = strokes
        .iter()
        .filter_map(|s| s.piece)
        .max()
        .map_or(0, |m| m + 1);
    (0..n)
        .map(|k| {
            let grain = strokes
                .iter()
                .find(|s| s.piece == Some(k) && s.kind == StrokeKind::Grain && s.points.len() == 2)
                .map(|s| (s.points[0], s.points[1]));
            PieceInfo {
                piece: k,
                label: unlabelled(),
                grain,
            }
        })
        .collect()
}

/// Ids for comments and messages: piece name (or number), kind and a count.
fn assign_ids(strokes: &mut [Stroke], pieces: &[PieceInfo]) {
    let mut counters: BTreeMap<(Option<u32>, StrokeKind), usize> = BTreeMap::new();
    for s in strokes {
        let c = counters.entry((s.piece, s.kind)).or_default();
        *c += 1;
        let owner = match s.piece {
            Some(p) => pieces
                .iter()
                .find(|i| i.piece == p)
                .map(|i| i.label.name.clone())
                .filter(|n| !n.is_empty())
                .unwrap_or_else(|| format!("piece{}", p + 1)),
            None => "loose".into(),
        };
        s.id = format!("{owner}-{}-{c}", kind_name(s.kind));
    }
}

fn kind_name(k: StrokeKind) -> &'static str {
    match k {
        StrokeKind::Boundary => "cut",
        StrokeKind::InnerCut => "cutout",
        StrokeKind::Notch => "notch",
        StrokeKind::Drill => "drill",
        StrokeKind::Sew => "sew",
        StrokeKind::Grain => "grain",
        StrokeKind::Mirror => "mirror",
        StrokeKind::Internal => "line",
        StrokeKind::Text => "label",
    }
}

fn area(p: &[DVec2]) -> f64 {
    poly::signed_area(p).abs()
}

/// Joins open paths whose ends meet (within [`CHAIN_TOL_MM`]) into longer paths; a chain whose
/// ends meet is closed. Closed inputs pass through.
fn chain(paths: Vec<(Vec<DVec2>, bool)>) -> Vec<(Vec<DVec2>, bool)> {
    let cell = |p: DVec2| {
        (
            (p.x / CHAIN_TOL_MM).floor() as i64,
            (p.y / CHAIN_TOL_MM).floor() as i64,
        )
    };
    let mut out = Vec::new();
    let mut open: Vec<Option<Vec<DVec2>>> = Vec::new();
    for (p, closed) in paths {
        if closed {
            out.push((p, true));
        } else {
            open.push(Some(p));
        }
    }
    // Endpoint index: cell → (path, at end?).
    let mut index: BTreeMap<(i64, i64), Vec<(usize, bool)>> = BTreeMap::new();
    for (k, p) in open.iter().enumerate() {
        let p = p.as_ref().expect("all present");
        index.entry(cell(p[0])).or_default().push((k, false));
        index
            .entry(cell(p[p.len() - 1]))
            .or_default()
            .push((k, true));
    }
    let find = |open: &[Option<Vec<DVec2>>], q: DVec2, not: usize| -> Option<(usize, bool)> {
        let (cx, cy) = cell(q);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for &(k, at_end) in index.get(&(cx + dx, cy + dy)).map_or(&[][..], |v| &v[..]) {
                    if k == not {
                        continue;
                    }
                    if let Some(p) = &open[k] {
                        let e = if at_end { p[p.len() - 1] } else { p[0] };
                        if e.distance(q) <= CHAIN_TOL_MM {
                            return Some((k, at_end));
                        }
                    }
                }
            }
        }
        None
    };
    for start in 0..open.len() {
        let Some(mut cur) = open[start].take() else {
            continue;
        };
        // Extend forwards, then backwards.
        for _ in 0..2 {
            while let Some((k, at_end)) = find(&open, cur[cur.len() - 1], start) {
                if cur[0].distance(cur[cur.len() - 1]) <= CHAIN_TOL_MM && cur.len() > 2 {
                    break;
                }
                let mut next = open[k].take().expect("found present");
                if at_end {
                    next.reverse();
                }
                cur.extend(next.into_iter().skip(1));
            }
            cur.reverse();
        }
        let closed = cur.len() > 3 && cur[0].distance(cur[cur.len() - 1]) <= CHAIN_TOL_MM;
        if closed {
            cur.pop();
        }
        out.push((cur, closed));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dxf(entities: &str, header: &str, blocks: &str) -> String {
        format!(
            "  0\nSECTION\n  2\nHEADER\n{header}  0\nENDSEC\n  0\nSECTION\n  2\nBLOCKS\n{blocks}  0\nENDSEC\n  0\nSECTION\n  2\nENTITIES\n{entities}  0\nENDSEC\n  0\nEOF\n"
        )
    }

    fn line(a: (f64, f64), b: (f64, f64)) -> String {
        format!(
            "  0\nLINE\n  8\n0\n 10\n{}\n 20\n{}\n 11\n{}\n 21\n{}\n",
            a.0, a.1, b.0, b.1
        )
    }

    #[test]
    fn lines_and_an_arc_chain_into_a_piece_with_a_hole() {
        // A 100 × 50 slot: two lines and two half circles (arcs in any order and direction),
        // and a circle inside it.
        let mut e = String::new();
        e += &line((0., 0.), (100., 0.));
        e += &line((0., 50.), (100., 50.)); // reversed relative to the walk
        e += "  0\nARC\n  8\n0\n 10\n100\n 20\n25\n 40\n25\n 50\n270\n 51\n90\n";
        e += "  0\nARC\n  8\n0\n 10\n0\n 20\n25\n 40\n25\n 50\n90\n 51\n270\n";
        e += "  0\nCIRCLE\n  8\n0\n 10\n50\n 20\n25\n 40\n5\n";
        let r = read_dxf(&dxf(&e, "  9\n$INSUNITS\n 70\n4\n", ""), 0.001).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        let d = r.drawing;
        assert_eq!(d.strokes.len(), 2);
        let outer = d.strokes.iter().find(|s| s.is_outer()).unwrap();
        let area_true = 100.0 * 50.0 + std::f64::consts::PI * 25.0 * 25.0;
        assert!((area(&outer.points) - area_true).abs() < area_true * 1e-4);
        let hole = d.strokes.iter().find(|s| !s.is_outer()).unwrap();
        assert_eq!(hole.kind, StrokeKind::InnerCut);
        assert_eq!(hole.piece, outer.piece);
    }

    #[test]
    fn spline_inserts_and_inches() {
        // A closed quadratic B-spline square-ish loop in a block inserted twice, in inches.
        let ctrl = [(0., 0.), (2., 0.), (2., 2.), (0., 2.), (0., 0.)];
        let mut s = String::from("  0\nSPLINE\n  8\n0\n 70\n0\n 71\n1\n");
        for k in [0., 0., 1., 2., 3., 4., 4.] {
            s += &format!(" 40\n{k}\n");
        }
        for (x, y) in ctrl {
            s += &format!(" 10\n{x}\n 20\n{y}\n 30\n0\n");
        }
        let blocks = format!("  0\nBLOCK\n  2\nSQ\n 10\n0\n 20\n0\n{s}  0\nENDBLK\n");
        let ins = |x: f64, rot: f64| {
            format!("  0\nINSERT\n  8\n0\n  2\nSQ\n 10\n{x}\n 20\n0\n 50\n{rot}\n")
        };
        let e = ins(0.0, 0.0) + &ins(10.0, 90.0);
        let r = read_dxf(&dxf(&e, "  9\n$INSUNITS\n 70\n1\n", &blocks), 0.01).unwrap();
        let outers: Vec<_> = r.drawing.strokes.iter().filter(|s| s.is_outer()).collect();
        assert_eq!(outers.len(), 2);
        for o in &outers {
            assert!(
                (area(&o.points) - 4.0 * 25.4 * 25.4).abs() < 1e-6,
                "{}",
                area(&o.points)
            );
        }
        // the rotated copy spans x in [10 - 2, 10] inches
        let xs: Vec<f64> = outers[1].points.iter().map(|p| p.x).collect();
        let min = xs.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((min - 8.0 * 25.4).abs() < 1e-6, "{min}");
    }

    #[test]
    fn bad_input_names_the_line() {
        let e = read_dxf(
            &dxf("  0\nCIRCLE\n  8\n0\n 10\n1\n 20\n1\n 40\n-2\n", "", ""),
            0.01,
        )
        .unwrap_err();
        assert!(e.to_string().contains("radius"), "{e}");
        let e = read_dxf(&dxf("  0\nLINE\n 10\n1e300\n", "", ""), 0.01).unwrap_err();
        assert!(e.to_string().contains("number expected"), "{e}");
        let e = read_dxf(&dxf("  0\nINSERT\n  2\nNOPE\n", "", ""), 0.01).unwrap_err();
        assert!(e.to_string().contains("undefined block `NOPE`"), "{e}");
        let r = read_dxf(&dxf(&line((0., 0.), (1., 0.)), "", ""), 0.01).unwrap();
        assert!(
            r.warnings.iter().any(|w| w.contains("read as mm")),
            "{:?}",
            r.warnings
        );
    }
}
