//! SVG export at true size and SVG import.
//!
//! Export: `width`/`height` in mm and `viewBox="0 0 W H"`, so 1 user unit = 1 mm and nothing
//! scales; y is flipped by writing `H − y` (our frame is y-up), never by a transform. Three
//! groups with the stroke colours laser software keys on: `id="cut"` (#ff0000, cut lines,
//! notches, drill holes), `id="draw"` (#0000ff, sew line, marks, grain line) and
//! `id="engrave"` (#000000, labels); fill none, stroke width 0.1 mm. Element ids say what
//! each element is (`vamp-1-cut`, `vamp-1-sew`, `vamp-1-notch-2`). Numbers are written with
//! 3 decimals, so the output is byte-identical for identical input.
//!
//! Each piece's cut line carries what nesting needs to know again when the SVG is read back:
//! `data-flatcut-quantity` (copies to cut) and `data-flatcut-grain-deg` (the grain direction,
//! degrees counter-clockwise from +x, y up) when the piece has a grain line.
//!
//! Import: `usvg` resolves units, transforms, basic shapes and arcs into paths; curves are
//! flattened here within a chordal tolerance. Layers come from the enclosing group id (`cut`,
//! `draw`, `engrave`: flatcut's own SVGs), then from the element id, then from the stroke colour
//! through a [`ColourTable`] (LightBurn's palette; see `crate::colours`). Everything dropped or
//! assumed is a warning of the import: text, images, fills, colours the table maps to nothing,
//! a document without width and height (read as CSS px). A width or height in percent has no
//! physical size and is refused, as is any coordinate beyond the sane range.

use crate::colours::ColourTable;
use crate::drawing::{Drawing, Layer, PieceInfo, Stroke, StrokeKind};
use crate::fit::PathSeg;
use crate::piece::PlacedPiece;
use crate::{PatternError, poly};
use flatcut_geom::{Aabb2, DVec2, limits};
use svg::node::element::{Group, Path, Polygon, Polyline};

/// Stroke width of every exported element (mm): thin enough for hairline-cut detection.
pub const STROKE_WIDTH_MM: f64 = 0.1;
/// Margin around the drawing when no sheet size is given (mm).
pub const DEFAULT_MARGIN_MM: f64 = 5.0;
/// CSS pixels per millimetre (96 dpi), the unit usvg resolves lengths to.
const PX_PER_MM: f64 = 96.0 / 25.4;

/// Colour of a layer's group.
pub fn layer_colour(layer: Layer) -> &'static str {
    match layer {
        Layer::Cut => "#ff0000",
        Layer::Draw => "#0000ff",
        Layer::Engrave => "#000000",
    }
}

/// Fixed 3-decimal formatting without negative zero.
fn f(v: f64) -> String {
    let s = format!("{v:.3}");
    if s == "-0.000" { "0.000".into() } else { s }
}

struct Frame {
    origin: DVec2,
    size: DVec2,
}

impl Frame {
    fn new(bbox: Aabb2, sheet: Option<DVec2>) -> Frame {
        match sheet {
            Some(s) => Frame {
                origin: DVec2::ZERO,
                size: s,
            },
            None if bbox.min.is_finite() && bbox.max.is_finite() => {
                let m = DVec2::splat(DEFAULT_MARGIN_MM);
                Frame {
                    origin: bbox.min - m,
                    size: bbox.max - bbox.min + 2.0 * m,
                }
            }
            None => Frame {
                origin: DVec2::ZERO,
                size: DVec2::splat(1.0),
            },
        }
    }
    fn map(&self, p: DVec2) -> (String, String) {
        (
            f(p.x - self.origin.x),
            f(self.size.y - (p.y - self.origin.y)),
        )
    }
    fn pts(&self, p: &[DVec2]) -> String {
        p.iter()
            .map(|q| {
                let (x, y) = self.map(*q);
                format!("{x},{y}")
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
}

enum Item {
    Stroke(Stroke),
    /// A curved path (id, layer, d attribute).
    Path(Layer, String, String),
}

/// Extra attributes of an element, by element id (the piece metadata on cut lines).
type Attrs = std::collections::BTreeMap<String, Vec<(&'static str, String)>>;

fn document(items: Vec<Item>, frame: &Frame, attrs: &Attrs) -> String {
    let mut doc = svg::Document::new()
        .set("width", format!("{}mm", f(frame.size.x)))
        .set("height", format!("{}mm", f(frame.size.y)))
        .set(
            "viewBox",
            format!("0 0 {} {}", f(frame.size.x), f(frame.size.y)),
        );
    for layer in [Layer::Cut, Layer::Draw, Layer::Engrave] {
        let mut g = Group::new()
            .set("id", layer.name())
            .set("fill", "none")
            .set("stroke", layer_colour(layer))
            .set("stroke-width", f(STROKE_WIDTH_MM));
        for it in &items {
            match it {
                Item::Stroke(s) if s.layer == layer && s.points.len() >= 2 => {
                    let pts = frame.pts(&s.points);
                    if s.closed {
                        let mut e = Polygon::new().set("id", s.id.clone()).set("points", pts);
                        for (k, v) in attrs.get(&s.id).into_iter().flatten() {
                            e = e.set(*k, v.clone());
                        }
                        g = g.add(e);
                    } else {
                        g = g.add(Polyline::new().set("id", s.id.clone()).set("points", pts));
                    }
                }
                Item::Path(l, id, d) if *l == layer => {
                    g = g.add(Path::new().set("id", id.clone()).set("d", d.clone()));
                }
                _ => {}
            }
        }
        doc = doc.add(g);
    }
    let mut s = doc.to_string();
    s.push('\n');
    s
}

/// Writes a drawing; `sheet` = (width, height) in mm with the origin at the lower-left corner,
/// or `None` for the drawing's bounding box plus a margin.
pub fn write_drawing(d: &Drawing, sheet: Option<DVec2>) -> String {
    let frame = Frame::new(d.bbox(), sheet);
    document(
        d.strokes.iter().cloned().map(Item::Stroke).collect(),
        &frame,
        &Attrs::new(),
    )
}

/// SVG path data of a fitted closed path under a placement (lines, arcs, cubics kept exact).
fn path_d(segs: &[PathSeg], map: impl Fn(DVec2) -> DVec2, mirror: bool, frame: &Frame) -> String {
    let mut d = String::new();
    if let Some(first) = segs.first() {
        let (x, y) = frame.map(map(first.start()));
        d.push_str(&format!("M{x},{y}"));
    }
    for s in segs {
        match *s {
            PathSeg::Line { p1, .. } => {
                let (x, y) = frame.map(map(p1));
                d.push_str(&format!(" L{x},{y}"));
            }
            PathSeg::Arc { p0, p1, bulge } => {
                let (_, r, _, sweep) = crate::fit::arc_geometry(p0, p1, bulge);
                let ccw = (sweep > 0.0) != mirror;
                let large = u8::from(sweep.abs() > std::f64::consts::PI);
                // y is flipped in SVG: a counter-clockwise arc has sweep-flag 0 there
                let sflag = u8::from(!ccw);
                let (x, y) = frame.map(map(p1));
                d.push_str(&format!(" A{},{} 0 {large} {sflag} {x},{y}", f(r), f(r)));
            }
            PathSeg::Cubic { c1, c2, p1, .. } => {
                let (ax, ay) = frame.map(map(c1));
                let (bx, by) = frame.map(map(c2));
                let (x, y) = frame.map(map(p1));
                d.push_str(&format!(" C{ax},{ay} {bx},{by} {x},{y}"));
            }
        }
    }
    d.push_str(" Z");
    d
}

/// Writes placed pieces on a sheet (`None`: fit the drawing). The sew line keeps its fitted
/// lines, arcs and cubics as a `<path>`; everything else is polylines.
pub fn write_pieces(placed: &[PlacedPiece], sheet: Option<DVec2>) -> String {
    let mut items = Vec::new();
    let mut bbox = Aabb2::from_points(std::iter::empty());
    let drawings: Vec<Drawing> = placed.iter().map(|p| p.to_drawing()).collect();
    for d in &drawings {
        let b = d.bbox();
        bbox = Aabb2::from_points(
            [bbox.min, bbox.max, b.min, b.max]
                .into_iter()
                .filter(|p| p.is_finite()),
        );
    }
    let frame = Frame::new(bbox, sheet);
    let mut attrs = Attrs::new();
    for (pp, d) in placed.iter().zip(drawings) {
        let sew_id = format!("{}-sew", pp.piece.instance_id(pp.instance));
        let mut meta = vec![(
            "data-flatcut-quantity",
            pp.piece.label.quantity.max(1).to_string(),
        )];
        if let Some((a, b)) = pp.piece.grain {
            let d = pp.placement.apply(b) - pp.placement.apply(a);
            meta.push(("data-flatcut-grain-deg", f(d.y.atan2(d.x).to_degrees())));
        }
        attrs.insert(format!("{}-cut", pp.piece.instance_id(pp.instance)), meta);
        for s in d.strokes {
            if s.id == sew_id && !pp.piece.sew.is_empty() {
                let pl = pp.placement;
                items.push(Item::Path(
                    Layer::Draw,
                    s.id,
                    path_d(&pp.piece.sew, |q| pl.apply(q), pl.mirror, &frame),
                ));
            } else {
                items.push(Item::Stroke(s));
            }
        }
    }
    document(items, &frame, &attrs)
}

fn layer_from_id(id: &str) -> Option<Layer> {
    match id {
        "cut" => return Some(Layer::Cut),
        "draw" => return Some(Layer::Draw),
        "engrave" => return Some(Layer::Engrave),
        _ => {}
    }
    let parts: Vec<&str> = id.rsplitn(3, '-').collect();
    let what = |w: &str| parts.contains(&w);
    if id.ends_with("-cut") || what("notch") || what("drill") {
        Some(Layer::Cut)
    } else if id.ends_with("-sew")
        || id.contains("-grain")
        || what("point")
        || id.contains("-point-")
    {
        Some(Layer::Draw)
    } else if id.contains("-label-") {
        Some(Layer::Engrave)
    } else {
        None
    }
}

/// The kind of one of our elements, read back from the id the writer gave it (an SVG has no
/// other place for it); other SVGs' strokes are internal lines or inner cuts until the piece
/// search below finds their outer contours.
fn kind_from_id(id: &str, layer: Layer) -> StrokeKind {
    let parts: Vec<&str> = id.rsplitn(3, '-').collect();
    let what = |w: &str| parts.contains(&w);
    match layer {
        Layer::Cut if id.ends_with("-cut") => StrokeKind::Boundary,
        Layer::Cut if what("notch") => StrokeKind::Notch,
        Layer::Cut if what("drill") => StrokeKind::Drill,
        Layer::Cut => StrokeKind::InnerCut,
        Layer::Draw if id.ends_with("-sew") => StrokeKind::Sew,
        Layer::Draw if id.contains("-grain") => StrokeKind::Grain,
        Layer::Draw => StrokeKind::Internal,
        Layer::Engrave => StrokeKind::Text,
    }
}

/// Piece prefix of one of our element ids (`vamp-1-notch-2` → `vamp-1`).
fn piece_prefix(id: &str) -> Option<&str> {
    for key in [
        "-cut", "-sew", "-notch-", "-drill-", "-point-", "-grain", "-label-",
    ] {
        if let Some(i) = id.rfind(key)
            && (key.ends_with('-')
                || i + key.len() == id.len()
                || id[i + key.len()..].starts_with('-'))
        {
            return Some(&id[..i]);
        }
    }
    None
}

fn flatten_usvg_path(
    path: &usvg::Path,
    tol_mm: f64,
    height_mm: f64,
) -> Result<Vec<(Vec<DVec2>, bool)>, String> {
    use tiny_skia_path::PathSegment as S;
    let ts = path.abs_transform();
    let to_mm = |p: tiny_skia_path::Point| {
        let mut q = p;
        ts.map_point(&mut q);
        DVec2::new(q.x as f64 / PX_PER_MM, height_mm - q.y as f64 / PX_PER_MM)
    };
    let mut out: Vec<(Vec<DVec2>, bool)> = Vec::new();
    let mut cur: Vec<DVec2> = Vec::new();
    let finish = |cur: &mut Vec<DVec2>, closed: bool, out: &mut Vec<(Vec<DVec2>, bool)>| {
        let mut pts = std::mem::take(cur);
        if closed {
            pts = poly::dedup_closed(&pts, 1e-9);
        }
        if pts.len() >= 2 {
            out.push((pts, closed));
        }
    };
    for seg in path.data().segments() {
        // Checked before flattening: a curve spanning 1e30 mm would flatten to billions of points.
        let ends: Vec<tiny_skia_path::Point> = match seg {
            S::MoveTo(p) | S::LineTo(p) => vec![p],
            S::QuadTo(a, b) => vec![a, b],
            S::CubicTo(a, b, c) => vec![a, b, c],
            S::Close => Vec::new(),
        };
        if let Some(q) = ends
            .iter()
            .map(|p| to_mm(*p))
            .find(|q| !limits::in_range2(*q))
        {
            let x = if limits::in_range(q.x) { q.y } else { q.x };
            return Err(format!("coordinate {}", limits::out_of_range_reason(x)));
        }
        match seg {
            S::MoveTo(p) => {
                finish(&mut cur, false, &mut out);
                cur.push(to_mm(p));
            }
            S::LineTo(p) => cur.push(to_mm(p)),
            S::QuadTo(c, p) => {
                let p0 = *cur.last().unwrap_or(&to_mm(c));
                let (c, p1) = (to_mm(c), to_mm(p));
                let seg = PathSeg::Cubic {
                    p0,
                    c1: p0 + (c - p0) * (2.0 / 3.0),
                    c2: p1 + (c - p1) * (2.0 / 3.0),
                    p1,
                };
                seg.flatten(tol_mm, &mut cur);
            }
            S::CubicTo(a, b, p) => {
                let p0 = *cur.last().unwrap_or(&to_mm(a));
                PathSeg::Cubic {
                    p0,
                    c1: to_mm(a),
                    c2: to_mm(b),
                    p1: to_mm(p),
                }
                .flatten(tol_mm, &mut cur);
            }
            S::Close => {
                let start = cur.first().copied();
                finish(&mut cur, true, &mut out);
                if let Some(s) = start {
                    cur.push(s); // a following LineTo continues from the subpath start
                }
            }
        }
    }
    finish(&mut cur, false, &mut out);
    out.retain(|(p, _)| p.len() >= 2);
    Ok(out)
}

/// What an import left out or assumed, counted while walking the tree.
#[derive(Default)]
struct Dropped {
    /// Palette layer → (colour as written, count) of strokes whose colour maps to nothing.
    colours: std::collections::BTreeMap<&'static str, (String, usize)>,
    fills_only: usize,
    fills_ignored: usize,
    paints: usize,
    images: usize,
}

impl Dropped {
    fn warnings(&self, texts: usize) -> Vec<String> {
        let mut w = Vec::new();
        for (layer, (colour, n)) in &self.colours {
            w.push(format!(
                "{n} stroke(s) in colour {colour} (LightBurn layer {layer}) dropped: the colour table maps layer {layer} to no layer (map it in the machine profile's [svg_colours])"
            ));
        }
        let mut say = |n: usize, what: &str| {
            if n > 0 {
                w.push(format!("{n} {what}"));
            }
        };
        say(
            texts,
            "<text> element(s) dropped: text is neither cut nor drawn; convert text to paths",
        );
        say(
            self.images,
            "image(s) dropped: raster images are neither cut nor drawn",
        );
        say(
            self.fills_only,
            "filled shape(s) without a stroke dropped: fills are neither cut nor drawn",
        );
        say(
            self.fills_ignored,
            "shape(s) have a fill as well as a stroke: the fill is ignored, the stroke is used",
        );
        say(
            self.paints,
            "stroke(s) painted with a gradient or pattern dropped: no colour to choose a layer by",
        );
        w
    }
}

/// The tree walk of an import: strokes with their piece prefix, and what was dropped.
struct Walk<'a> {
    /// Paths seen, to name those without an id (`svg-path-3`) in later messages.
    paths: usize,
    tol: f64,
    h: f64,
    table: &'a ColourTable,
    out: Vec<(Stroke, Option<String>)>,
    dropped: Dropped,
}

impl Walk<'_> {
    fn group(&mut self, g: &usvg::Group, layer: Option<Layer>) -> Result<(), String> {
        for node in g.children() {
            match node {
                usvg::Node::Group(sub) => {
                    let l = layer_from_id(sub.id())
                        .filter(|_| matches!(sub.id(), "cut" | "draw" | "engrave"))
                        .or(layer);
                    self.group(sub, l)?;
                }
                usvg::Node::Path(p) => self.path(p, layer)?,
                usvg::Node::Image(_) => self.dropped.images += 1,
                _ => {}
            }
        }
        Ok(())
    }

    /// The layer of a path: its group's, its id's, or its stroke colour's (`None`: dropped).
    fn layer(&mut self, p: &usvg::Path, named: Option<Layer>) -> Option<Layer> {
        match (named, p.stroke().map(|s| s.paint())) {
            (Some(l), _) => Some(l),
            (None, Some(usvg::Paint::Color(c))) => {
                if p.fill().is_some() {
                    self.dropped.fills_ignored += 1;
                }
                let (name, layer) = self.table.layer_of([c.red, c.green, c.blue]);
                if layer.is_none() {
                    let e = self.dropped.colours.entry(name).or_insert_with(|| {
                        (format!("#{:02x}{:02x}{:02x}", c.red, c.green, c.blue), 0)
                    });
                    e.1 += 1;
                }
                layer
            }
            (None, Some(_)) => {
                self.dropped.paints += 1;
                None
            }
            (None, None) => {
                if p.fill().is_some() {
                    self.dropped.fills_only += 1;
                }
                None
            }
        }
    }

    fn path(&mut self, p: &usvg::Path, layer: Option<Layer>) -> Result<(), String> {
        if !p.is_visible() {
            return Ok(());
        }
        self.paths += 1;
        let id = if p.id().is_empty() {
            format!("svg-path-{}", self.paths)
        } else {
            p.id().to_string()
        };
        let Some(lay) = self.layer(p, layer.or_else(|| layer_from_id(&id))) else {
            return Ok(());
        };
        let prefix = piece_prefix(&id).map(str::to_string);
        let parts =
            flatten_usvg_path(p, self.tol, self.h).map_err(|e| format!("element '{id}': {e}"))?;
        for (k, (pts, closed)) in parts.into_iter().enumerate() {
            let sid = if k == 0 {
                id.clone()
            } else {
                format!("{id}-{k}")
            };
            let kind = kind_from_id(&id, lay);
            self.out.push((
                Stroke {
                    layer: lay,
                    points: pts,
                    closed,
                    piece: None,
                    kind,
                    id: sid,
                },
                prefix.clone(),
            ));
        }
        Ok(())
    }
}

/// What flatcut wrote on a piece's cut line: copies to cut, and the grain direction in the
/// drawing's frame (radians counter-clockwise from +x, y up).
struct PieceMeta {
    quantity: u32,
    grain_angle: Option<f64>,
}

/// An imported SVG: the drawing (with the quantity and grain of flatcut's pieces in
/// [`Drawing::pieces`]) and what was dropped or assumed, one sentence each.
#[derive(Clone, Debug, Default)]
pub struct SvgImport {
    /// The paths read, pieces told apart by their outer boundaries.
    pub drawing: Drawing,
    /// What was dropped or assumed, one sentence each.
    pub warnings: Vec<String>,
}

/// The metadata flatcut wrote on a cut line (`None` for any other element).
fn piece_meta(n: usvg::roxmltree::Node) -> Result<Option<(String, PieceMeta)>, String> {
    let (Some(id), Some(q)) = (n.attribute("id"), n.attribute("data-flatcut-quantity")) else {
        return Ok(None);
    };
    let Some(prefix) = id.strip_suffix("-cut") else {
        return Ok(None);
    };
    let quantity = q
        .trim()
        .parse::<u32>()
        .ok()
        .filter(|q| (1..=limits::MAX_QUANTITY).contains(q))
        .ok_or_else(|| {
            format!(
                "element '{id}': data-flatcut-quantity=\"{q}\" is not a count from 1 to {}",
                limits::MAX_QUANTITY
            )
        })?;
    let grain_angle = match n.attribute("data-flatcut-grain-deg") {
        None => None,
        Some(g) => Some(
            g.trim()
                .parse::<f64>()
                .ok()
                .filter(|g| g.is_finite())
                .ok_or_else(|| {
                    format!("element '{id}': data-flatcut-grain-deg=\"{g}\" is not an angle")
                })?
                .to_radians(),
        ),
    };
    Ok(Some((
        prefix.to_string(),
        PieceMeta {
            quantity,
            grain_angle,
        },
    )))
}

/// What the raw document says before usvg resolves it: refusals (percent sizes), warnings
/// (px assumed), the number of `<text>` elements and flatcut's piece metadata.
fn scan_document(
    text: &str,
    import: &mut SvgImport,
    metas: &mut std::collections::BTreeMap<String, PieceMeta>,
) -> Result<usize, String> {
    let doc = usvg::roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
    let root = doc.root_element();
    let mut missing = Vec::new();
    for attr in ["width", "height"] {
        match root.attribute(attr) {
            Some(v) if v.trim().ends_with('%') => {
                return Err(format!(
                    "{attr}=\"{v}\" on <svg> is a percentage, which has no physical size; give the {attr} in mm (e.g. {attr}=\"600mm\")"
                ));
            }
            Some(_) => {}
            None => missing.push(attr),
        }
    }
    if !missing.is_empty() {
        import.warnings.push(format!(
            "the <svg> element has no {}: its user units are read as CSS px (96 per inch, {:.4} mm each); give width and height in mm",
            missing.join(" and "),
            1.0 / PX_PER_MM
        ));
    }
    let mut texts = 0;
    for n in doc.descendants().filter(|n| n.is_element()) {
        if n.tag_name().name() == "text" {
            texts += 1;
        }
        if let Some((prefix, meta)) = piece_meta(n)? {
            metas.insert(prefix, meta);
        }
    }
    Ok(texts)
}

/// Parses an SVG (ours or any SVG with real units) into a drawing in mm, y up, origin at the
/// lower-left corner of the document; curves are flattened within `chord_tol` mm; stroke
/// colours choose layers through `table`.
///
/// Pieces: strokes with our ids are grouped by their id prefix; in other SVGs every closed
/// cut contour not inside another one is a piece (`outer`), and strokes inside it belong to it.
pub fn read_svg(
    text: &str,
    source_name: &str,
    chord_tol: f64,
    table: &ColourTable,
) -> Result<SvgImport, PatternError> {
    let err = |reason: String| PatternError::Svg {
        source_name: source_name.to_string(),
        reason,
    };
    if !(chord_tol.is_finite() && chord_tol > 0.0) {
        return Err(err(format!(
            "chord tolerance must be positive, got {chord_tol}"
        )));
    }
    let mut import = SvgImport::default();
    let mut metas = std::collections::BTreeMap::new();
    let texts = scan_document(text, &mut import, &mut metas).map_err(err)?;
    let tree =
        usvg::Tree::from_str(text, &usvg::Options::default()).map_err(|e| err(e.to_string()))?;
    let h_mm = tree.size().height() as f64 / PX_PER_MM;
    let mut walk = Walk {
        paths: 0,
        tol: chord_tol,
        h: h_mm,
        table,
        out: Vec::new(),
        dropped: Dropped::default(),
    };
    walk.group(tree.root(), None).map_err(err)?;
    import.warnings.extend(walk.dropped.warnings(texts));
    let raw = walk.out;
    // piece numbering
    let mut prefixes: Vec<String> = Vec::new();
    let mut strokes: Vec<Stroke> = Vec::with_capacity(raw.len());
    let ours = raw.iter().any(|(_, p)| p.is_some());
    for (mut s, prefix) in raw {
        if let Some(p) = prefix {
            let idx = prefixes.iter().position(|q| *q == p).unwrap_or_else(|| {
                prefixes.push(p.clone());
                prefixes.len() - 1
            });
            s.piece = Some(idx as u32);
        }
        strokes.push(s);
    }
    if !ours {
        crate::plain_pieces::find_pieces(&mut strokes);
    }
    // The quantity and grain flatcut wrote, for each of its pieces found.
    let pieces = prefixes
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            let m = metas.get(p)?;
            Some(PieceInfo {
                piece: k as u32,
                label: crate::LabelInfo {
                    quantity: m.quantity,
                    ..Default::default()
                },
                grain: m.grain_angle.map(|a| (DVec2::ZERO, DVec2::from_angle(a))),
            })
        })
        .collect();
    import.drawing = Drawing { strokes, pieces };
    Ok(import)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::piece::{Mark, MarkKind, Piece, PieceInput, PieceOptions, PlacedPiece, Placement};

    fn sample_piece() -> Piece {
        // a rounded-corner rectangle: straight sides and quarter circles
        let mut pts = Vec::new();
        let (w, h, r) = (120.0, 60.0, 15.0);
        let centers = [
            DVec2::new(w - r, r),
            DVec2::new(w - r, h - r),
            DVec2::new(r, h - r),
            DVec2::new(r, r),
        ];
        for (k, c) in centers.iter().enumerate() {
            let a0 = -std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..=12 {
                pts.push(
                    *c + r * DVec2::from_angle(a0 + j as f64 / 12.0 * std::f64::consts::FRAC_PI_2),
                );
            }
        }
        let mut input = PieceInput::new("vamp", pts);
        input.marks.push(Mark {
            kind: MarkKind::Notch,
            pos: DVec2::new(60., 0.),
            boundary_index: None,
        });
        input.grain = Some((DVec2::new(20., 30.), DVec2::new(100., 30.)));
        Piece::build(&input, &PieceOptions::default()).unwrap()
    }

    #[test]
    fn true_size_header_and_groups() {
        let p = sample_piece();
        let s = write_pieces(
            &[PlacedPiece {
                piece: &p,
                instance: 1,
                placement: Placement::IDENTITY,
            }],
            Some(DVec2::new(600., 400.)),
        );
        assert!(
            s.contains(r#"width="600.000mm""#) && s.contains(r#"height="400.000mm""#),
            "{s}"
        );
        assert!(s.contains(r#"viewBox="0 0 600.000 400.000""#));
        for (id, c) in [
            ("cut", "#ff0000"),
            ("draw", "#0000ff"),
            ("engrave", "#000000"),
        ] {
            assert!(s.contains(&format!(r#"id="{id}""#)) && s.contains(c));
        }
        assert!(
            s.contains(r#"id="vamp-1-cut""#)
                && s.contains(r#"id="vamp-1-sew""#)
                && s.contains(r#"id="vamp-1-notch-1""#)
        );
        assert!(!s.contains("transform"));
        assert!(s.contains(" A"), "arcs kept in the sew path");
    }

    #[test]
    fn parse_back_gives_same_cut_line_and_sew_curve() {
        let p = sample_piece();
        let pl = Placement {
            rotation: 0.4,
            mirror: true,
            translation: DVec2::new(200., 150.),
        };
        let s = write_pieces(
            &[PlacedPiece {
                piece: &p,
                instance: 2,
                placement: pl,
            }],
            Some(DVec2::new(600., 400.)),
        );
        let d = read_svg(&s, "test", 0.01, &ColourTable::default())
            .unwrap()
            .drawing;
        let cut = d.strokes.iter().find(|s| s.id == "vamp-2-cut").unwrap();
        assert!(cut.is_outer() && cut.layer == Layer::Cut && cut.piece == Some(0));
        let expect: Vec<DVec2> = p.cut.iter().map(|q| pl.apply(*q)).collect();
        let l0: f64 = (0..expect.len())
            .map(|i| expect[i].distance(expect[(i + 1) % expect.len()]))
            .sum();
        assert!(
            (cut.length() - l0).abs() < 0.01 * expect.len() as f64 * 1e-3 + 1e-2,
            "{} vs {l0}",
            cut.length()
        );
        for q in &cut.points {
            assert!(poly::dist_to_closed(&expect, *q) < 2e-3);
        }
        // the curved sew path flattens back onto the sew polyline
        let sew = d.strokes.iter().find(|s| s.id == "vamp-2-sew").unwrap();
        let sew_exp: Vec<DVec2> = p.sew_polyline.iter().map(|q| pl.apply(*q)).collect();
        for q in &sew.points {
            assert!(poly::dist_to_closed(&sew_exp, *q) < 0.05, "{q}");
        }
        assert!(d.strokes.iter().any(|s| s.layer == Layer::Engrave));
    }

    #[test]
    fn general_svg_in_inches_with_transform() {
        let s = r##"<svg xmlns="http://www.w3.org/2000/svg" width="4in" height="2in" viewBox="0 0 400 200">
            <g transform="translate(100,50)"><rect x="0" y="0" width="100" height="50" stroke="red" fill="none"/>
            <circle cx="50" cy="25" r="10" stroke="#f00" fill="none"/></g></svg>"##;
        let d = read_svg(s, "in.svg", 0.01, &ColourTable::default())
            .unwrap()
            .drawing;
        assert_eq!(d.strokes.len(), 2);
        let outer = d.strokes.iter().find(|s| s.is_outer()).unwrap();
        // 100 user units = 1 in = 25.4 mm
        assert!(
            (outer.length() - 2.0 * (25.4 + 12.7)).abs() < 1e-3,
            "{}",
            outer.length()
        );
        let bb = Aabb2::from_points(outer.points.iter().copied());
        assert!(
            (bb.min.x - 25.4).abs() < 1e-3 && (bb.max.y - (50.8 - 12.7)).abs() < 1e-3,
            "{bb:?}"
        );
        let hole = d.strokes.iter().find(|s| !s.is_outer()).unwrap();
        assert_eq!(hole.piece, Some(0));
        // a polygon inscribed within 0.01 mm chordal error is at most ~2·0.01/r shorter
        let c = 2.0 * std::f64::consts::PI * 2.54;
        assert!(
            hole.length() <= c && hole.length() > c * (1.0 - 2.0 * 0.01 / 2.54),
            "{}",
            hole.length()
        );
    }

    /// DXF and SVG import share one rule for plain files: a contour is a hole of another only
    /// when it is smaller and inside it. A square whose corners lie in a thin U's base and arms
    /// is larger than the U and crosses it: no cutout of the U (the SVG copy without the area
    /// test made it one), both are outlines; the circle inside the U's base is the U's hole.
    #[test]
    fn a_larger_contour_with_its_corners_inside_another_is_no_hole_of_it() {
        let s = r##"<svg xmlns="http://www.w3.org/2000/svg" width="40mm" height="40mm" viewBox="0 0 40 40">
            <polygon points="0,0 30,0 30,30 27,30 27,3 3,3 3,30 0,30" stroke="red" fill="none"/>
            <polygon points="1,1 29,1 29,29 1,29" stroke="red" fill="none"/>
            <circle cx="15" cy="1.5" r="1" stroke="red" fill="none"/></svg>"##;
        let d = read_svg(s, "u.svg", 0.01, &ColourTable::default())
            .unwrap()
            .drawing;
        let outers: Vec<&Stroke> = d.strokes.iter().filter(|s| s.is_outer()).collect();
        assert_eq!(outers.len(), 2, "{:?}", d.strokes);
        let holes: Vec<&Stroke> = d.strokes.iter().filter(|s| !s.is_outer()).collect();
        assert_eq!(holes.len(), 1);
        assert_eq!(holes[0].kind, StrokeKind::InnerCut);
        assert!(holes[0].piece.is_some());
    }

    #[test]
    fn deterministic_output() {
        let p = sample_piece();
        let pp = [PlacedPiece {
            piece: &p,
            instance: 1,
            placement: Placement::IDENTITY,
        }];
        assert_eq!(write_pieces(&pp, None), write_pieces(&pp, None));
    }

    #[test]
    fn garbage_is_an_error_naming_the_source() {
        let e = read_svg("<svg", "broken.svg", 0.01, &ColourTable::default()).unwrap_err();
        assert!(e.to_string().contains("broken.svg"));
    }

    fn import(s: &str) -> Result<SvgImport, PatternError> {
        read_svg(s, "x.svg", 0.01, &ColourTable::default())
    }

    #[test]
    fn colours_go_to_layers_by_the_table_and_dropped_ones_are_named() {
        let s = r##"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">
            <path d="M0 0 L10 0" stroke="black"/><path d="M0 5 L10 5" stroke="#0000ff"/>
            <path d="M0 9 L10 9" stroke="#ff0000"/><path d="M0 20 L10 20" stroke="#00e000"/>
            <path d="M0 30 L10 30" stroke="#00ff00"/>
            <rect x="50" y="50" width="10" height="10" fill="black"/>
            <rect x="70" y="50" width="10" height="10" fill="yellow" stroke="red"/>
            <text x="5" y="90">SIZE 42</text></svg>"##;
        let r = import(s).unwrap();
        let layers: Vec<Layer> = r.drawing.strokes.iter().map(|s| s.layer).collect();
        assert_eq!(
            layers,
            [Layer::Engrave, Layer::Draw, Layer::Cut, Layer::Cut],
            "{:?}",
            r.drawing.strokes
        );
        let w = r.warnings.join("\n");
        assert!(
            w.contains("2 stroke(s) in colour #00e000 (LightBurn layer 03) dropped"),
            "{w}"
        );
        assert!(w.contains("1 <text> element(s) dropped"), "{w}");
        assert!(
            w.contains("1 filled shape(s) without a stroke dropped"),
            "{w}"
        );
        assert!(w.contains("the fill is ignored"), "{w}");
        assert!(!w.contains("px"), "{w}");
        // a profile may send layer 03 to the cut
        let t = ColourTable::with_overrides(
            &[("03".to_string(), crate::ColourJob::Cut)]
                .into_iter()
                .collect(),
        )
        .unwrap();
        let r = read_svg(s, "x.svg", 0.01, &t).unwrap();
        assert_eq!(
            r.drawing
                .strokes
                .iter()
                .filter(|s| s.layer == Layer::Cut)
                .count(),
            4
        );
    }

    #[test]
    fn percentage_size_is_refused_and_a_missing_size_is_a_warning() {
        let e = import(r##"<svg xmlns="http://www.w3.org/2000/svg" width="100%" height="100%" viewBox="0 0 10 10"><path d="M0 0 L5 5" stroke="red"/></svg>"##)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x.svg") && e.contains("width=\"100%\"") && e.contains("percentage"),
            "{e}"
        );
        let r = import(r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 96 96"><path d="M0 0 L96 0" stroke="red"/></svg>"##)
            .unwrap();
        assert!(r.warnings[0].contains("no width and height") && r.warnings[0].contains("px"));
        // 96 px = 1 in
        assert!((r.drawing.strokes[0].length() - 25.4).abs() < 1e-9);
    }

    #[test]
    fn coordinates_beyond_the_sane_range_are_refused_naming_the_element() {
        let e = import(r##"<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" viewBox="0 0 10 10"><path id="far" d="M0 0 L1e12 5" stroke="red"/></svg>"##)
            .unwrap_err()
            .to_string();
        assert!(e.contains("element 'far'") && e.contains("beyond"), "{e}");
        // a path without id is named by its place in the document
        let e = import(r##"<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" viewBox="0 0 10 10"><path d="M0 0 L1 1" stroke="red"/><path d="M0 0 L1e12 5" stroke="red"/></svg>"##)
            .unwrap_err()
            .to_string();
        assert!(e.contains("element 'svg-path-2'"), "{e}");
    }

    #[test]
    fn quantity_and_grain_come_back_from_the_metadata_we_write() {
        let mut p = sample_piece();
        p.label.quantity = 2;
        let pl = Placement {
            rotation: std::f64::consts::FRAC_PI_2,
            mirror: false,
            translation: DVec2::new(200., 150.),
        };
        let s = write_pieces(
            &[PlacedPiece {
                piece: &p,
                instance: 1,
                placement: pl,
            }],
            None,
        );
        let r = import(&s).unwrap();
        let m = r.drawing.piece_info(0).unwrap();
        assert_eq!(m.label.quantity, 2);
        // the sample's grain runs along +x; placed a quarter turn, it runs along +y
        let (a, b) = m.grain.unwrap();
        assert!(((b - a).y.atan2((b - a).x) - std::f64::consts::FRAC_PI_2).abs() < 1e-4);
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    }
}
