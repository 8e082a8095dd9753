//! DXF export (R12, `AC1009`, ASCII) in the AAMA/ASTM D6673 structure that pattern CAD and
//! cutter front ends import, or with descriptive layer names for laser/knife software.
//!
//! * [`DxfLayers::Aama`] (default): one `BLOCK` per piece cut (each copy, side of a pair and
//!   size its own), placed by an `INSERT` in `ENTITIES`. Inside a block, by AAMA layer number:
//!   `1` boundary (the cut line) and the piece's `TEXT` (`Piece Name:`, `Size:`, `Quantity:`,
//!   `Material:`), `2` turn points and `3` curve points of the boundary (`POINT`s), `4`
//!   notches, `6` mirror (fold) lines, `7` the grain line (one `LINE`), `8` internal lines, `11`
//!   internal cut-outs, `13` drill holes (`POINT` at the centre), `14` the sew line (arcs kept
//!   as vertex bulges), `15` annotation (the label's stroke text, and a `TEXT` per run of one
//!   allowance at its middle on the sew line: `featherline: lasting 16.0 mm`). R12 has no
//!   header variable for the drawing unit, so the unit is stated as AAMA files state it, in a
//!   `TEXT` on layer 1 outside the blocks: `Units: METRIC`.
//! * [`DxfLayers::Named`]: the flat style laser and knife software reads — every stroke a
//!   `POLYLINE` in `ENTITIES` on `CUT`, `DRAW`, `NOTCH`, `DRILL` or `TEXT`.
//!
//! The layer of a stroke comes from its [`StrokeKind`], never from its id.
//!
//! A fixed writer of our own rather than the `dxf` crate: the output must be byte-identical for
//! identical input and exactly R12 (no handles, no R13+ header variables, a fixed table order),
//! which a general writer that fills in its own defaults and handles does not promise across
//! versions. Numbers are written with 6 decimals (1 nm), so a round trip through another
//! program keeps the geometry to 1e-6 mm.

use crate::drawing::{Drawing, Layer, PieceInfo, Stroke, StrokeKind};
use crate::fit::{self, PathSeg};
use crate::piece::{LabelInfo, PieceEdge, PlacedPiece};
use flatcut_geom::{Aabb2, DVec2};
use std::fmt::Write;

/// Layer naming convention.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DxfLayers {
    /// AAMA/ASTM D6673 numeric layers, one block per piece.
    #[default]
    Aama,
    /// Descriptive names, every stroke in `ENTITIES`.
    Named,
}

/// AAMA layer of the turn points (corners) of a boundary.
pub const AAMA_TURN_POINTS: &str = "2";
/// AAMA layer of the curve points of a boundary.
pub const AAMA_CURVE_POINTS: &str = "3";
/// Cap height of the piece `TEXT` entities (mm).
pub const TEXT_HEIGHT_MM: f64 = 2.5;
/// A boundary vertex turning more than this (degrees) is a turn point, else a curve point: the
/// outline fitter's corner angle.
pub const TURN_POINT_DEG: f64 = fit::DEFAULT_CORNER_DEG;
/// Decimals of every coordinate.
const DECIMALS: usize = 6;

impl DxfLayers {
    /// The layer of a stroke kind.
    pub fn layer(self, kind: StrokeKind) -> &'static str {
        match (self, kind) {
            (DxfLayers::Aama, StrokeKind::Boundary) => "1",
            (DxfLayers::Aama, StrokeKind::Notch) => "4",
            (DxfLayers::Aama, StrokeKind::Mirror) => "6",
            (DxfLayers::Aama, StrokeKind::Grain) => "7",
            (DxfLayers::Aama, StrokeKind::Internal) => "8",
            (DxfLayers::Aama, StrokeKind::InnerCut) => "11",
            (DxfLayers::Aama, StrokeKind::Drill) => "13",
            (DxfLayers::Aama, StrokeKind::Sew) => "14",
            (DxfLayers::Aama, StrokeKind::Text) => "15",
            (DxfLayers::Named, StrokeKind::Boundary | StrokeKind::InnerCut) => "CUT",
            (DxfLayers::Named, StrokeKind::Notch) => "NOTCH",
            (DxfLayers::Named, StrokeKind::Drill) => "DRILL",
            (
                DxfLayers::Named,
                StrokeKind::Sew | StrokeKind::Internal | StrokeKind::Grain | StrokeKind::Mirror,
            ) => "DRAW",
            (DxfLayers::Named, StrokeKind::Text) => "TEXT",
        }
    }

    /// Layers in table order with their ACI colour.
    fn table(self) -> Vec<(&'static str, u8)> {
        match self {
            DxfLayers::Aama => vec![
                ("1", 1),
                (AAMA_TURN_POINTS, 2),
                (AAMA_CURVE_POINTS, 3),
                ("4", 3),
                ("6", 4),
                ("7", 5),
                ("8", 5),
                ("11", 1),
                ("13", 6),
                ("14", 5),
                ("15", 7),
            ],
            DxfLayers::Named => vec![
                ("CUT", 1),
                ("NOTCH", 3),
                ("DRAW", 5),
                ("DRILL", 6),
                ("TEXT", 7),
            ],
        }
    }
}

fn num(v: f64) -> String {
    let s = format!("{v:.DECIMALS$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        format!("{:.DECIMALS$}", 0.0)
    } else {
        s
    }
}

/// DXF text values are one line; group-code 1 strings cannot hold a newline.
fn text_value(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

struct Writer {
    out: String,
}

impl Writer {
    fn pair(&mut self, code: i32, value: &str) {
        let _ = write!(self.out, "{code:>3}\n{value}\n");
    }
    fn xy(&mut self, base: i32, p: DVec2) {
        self.pair(base, &num(p.x));
        self.pair(base + 10, &num(p.y));
        self.pair(base + 20, &num(0.0));
    }
    fn polyline(&mut self, layer: &str, pts: &[DVec2], bulges: Option<&[f64]>, closed: bool) {
        self.pair(0, "POLYLINE");
        self.pair(8, layer);
        self.pair(66, "1");
        self.xy(10, DVec2::ZERO);
        self.pair(70, if closed { "1" } else { "0" });
        for (i, p) in pts.iter().enumerate() {
            self.pair(0, "VERTEX");
            self.pair(8, layer);
            self.xy(10, *p);
            if let Some(b) = bulges.and_then(|b| b.get(i)).filter(|b| **b != 0.0) {
                self.pair(42, &num(*b));
            }
        }
        self.pair(0, "SEQEND");
        self.pair(8, layer);
    }
    fn line(&mut self, layer: &str, a: DVec2, b: DVec2) {
        self.pair(0, "LINE");
        self.pair(8, layer);
        self.xy(10, a);
        self.xy(11, b);
    }
    fn point(&mut self, layer: &str, p: DVec2) {
        self.pair(0, "POINT");
        self.pair(8, layer);
        self.xy(10, p);
    }
    fn text(&mut self, layer: &str, at: DVec2, height: f64, value: &str) {
        self.pair(0, "TEXT");
        self.pair(8, layer);
        self.xy(10, at);
        self.pair(40, &num(height));
        self.pair(1, &text_value(value));
    }
}

fn header(w: &mut Writer, layers: DxfLayers, extents: Aabb2) {
    let (lo, hi) = if extents.min.is_finite() && extents.max.is_finite() {
        (extents.min, extents.max)
    } else {
        (DVec2::ZERO, DVec2::ZERO)
    };
    w.pair(0, "SECTION");
    w.pair(2, "HEADER");
    w.pair(9, "$ACADVER");
    w.pair(1, "AC1009");
    w.pair(9, "$INSBASE");
    w.xy(10, DVec2::ZERO);
    w.pair(9, "$EXTMIN");
    w.xy(10, lo);
    w.pair(9, "$EXTMAX");
    w.xy(10, hi);
    // Decimal units with the writer's precision (R12's only unit-related header variables).
    w.pair(9, "$LUNITS");
    w.pair(70, "2");
    w.pair(9, "$LUPREC");
    w.pair(70, &DECIMALS.to_string());
    w.pair(0, "ENDSEC");
    w.pair(0, "SECTION");
    w.pair(2, "TABLES");
    w.pair(0, "TABLE");
    w.pair(2, "LTYPE");
    w.pair(70, "1");
    w.pair(0, "LTYPE");
    w.pair(2, "CONTINUOUS");
    w.pair(70, "0");
    w.pair(3, "Solid line");
    w.pair(72, "65");
    w.pair(73, "0");
    w.pair(40, "0.0");
    w.pair(0, "ENDTAB");
    let table = layers.table();
    w.pair(0, "TABLE");
    w.pair(2, "LAYER");
    w.pair(70, &table.len().to_string());
    for (name, colour) in table {
        w.pair(0, "LAYER");
        w.pair(2, name);
        w.pair(70, "0");
        w.pair(62, &colour.to_string());
        w.pair(6, "CONTINUOUS");
    }
    w.pair(0, "ENDTAB");
    w.pair(0, "ENDSEC");
}

fn footer(mut w: Writer) -> String {
    w.pair(0, "ENDSEC");
    w.pair(0, "EOF");
    w.out
}

/// A stroke to write, with the sew line's exact bulges where known.
struct Item<'a> {
    stroke: &'a Stroke,
    bulges: Option<Vec<f64>>,
    points: Option<Vec<DVec2>>,
}

/// One piece (a block in the AAMA style).
struct Block<'a> {
    name: String,
    info: Option<&'a PieceInfo>,
    items: Vec<Item<'a>>,
    /// Annotation `TEXT`s on layer 15 (where, what): each edge's allowance.
    notes: Vec<(DVec2, String)>,
}

/// Writes a drawing; in the AAMA style every piece of the drawing is a block.
pub fn write_drawing(d: &Drawing, layers: DxfLayers) -> String {
    let blocks = unique_names(blocks_of_drawing(d));
    write_blocks(&blocks, d.bbox(), layers)
}

/// Writes placed pieces, each its own block (AAMA: one block per piece cut, with its own piece
/// text, whatever instance numbers the placements carry); the sew line keeps its fitted lines
/// and arcs as bulge polylines (cubics are flattened within the piece's chord tolerance), and
/// every run of one allowance is annotated on layer 15 with its name, kind and width.
pub fn write_pieces(placed: &[PlacedPiece], layers: DxfLayers, chord_tol: f64) -> String {
    let drawings: Vec<Drawing> = placed.iter().map(|p| p.to_drawing()).collect();
    let mut bbox_pts = Vec::new();
    let mut blocks = Vec::with_capacity(placed.len());
    for (pp, d) in placed.iter().zip(&drawings) {
        let b = d.bbox();
        bbox_pts.extend([b.min, b.max].into_iter().filter(|p| p.is_finite()));
        let pl = pp.placement;
        let sew = (!pp.piece.sew.is_empty()).then(|| {
            let (pts, bulges) = bulge_polyline(&pp.piece.sew, chord_tol);
            (
                pts.iter().map(|q| pl.apply(*q)).collect::<Vec<_>>(),
                bulges
                    .iter()
                    .map(|b| if pl.mirror { -b } else { *b })
                    .collect::<Vec<_>>(),
            )
        });
        let items = d
            .strokes
            .iter()
            .filter(|s| s.points.len() >= 2)
            .map(|s| {
                // The piece's sew line (closed) is written as fitted; inner sew lines (dart
                // legs, open) as drawn.
                let fitted = (s.kind == StrokeKind::Sew && s.closed)
                    .then_some(sew.as_ref())
                    .flatten();
                Item {
                    stroke: s,
                    points: fitted.map(|f| f.0.clone()),
                    bulges: fitted.map(|f| f.1.clone()),
                }
            })
            .collect();
        let notes = pp
            .piece
            .edges
            .iter()
            .filter_map(|e| Some((pl.apply(midpoint(&e.sew)?), edge_note(e))))
            .collect();
        blocks.push(Block {
            name: block_name(&pp.piece.label_with_name().name, pp.instance),
            info: d.pieces.first(),
            items,
            notes,
        });
    }
    write_blocks(&unique_names(blocks), Aabb2::from_points(bbox_pts), layers)
}

/// The annotation of a run of one allowance: `featherline: lasting 16.0 mm` (a run no edge
/// names: `seam 8.0 mm`).
pub fn edge_note(e: &PieceEdge) -> String {
    let what = format!("{} {:.1} mm", e.kind.name(), e.width);
    if e.name.is_empty() {
        what
    } else {
        format!("{}: {what}", e.name)
    }
}

/// The point halfway along an open polyline.
fn midpoint(line: &[DVec2]) -> Option<DVec2> {
    let total: f64 = line.windows(2).map(|w| w[0].distance(w[1])).sum();
    let mut left = 0.5 * total;
    for w in line.windows(2) {
        let l = w[0].distance(w[1]);
        if left <= l && l > 0.0 {
            return Some(w[0].lerp(w[1], left / l));
        }
        left -= l;
    }
    line.last().copied()
}

/// Groups the strokes by piece, in order of first appearance; strokes of no piece form a block
/// without a name (written straight into `ENTITIES`).
fn blocks_of_drawing(d: &Drawing) -> Vec<Block<'_>> {
    let mut blocks: Vec<(Option<u32>, Block<'_>)> = Vec::new();
    for s in d.strokes.iter().filter(|s| s.points.len() >= 2) {
        let at = match blocks.iter().position(|(p, _)| *p == s.piece) {
            Some(i) => i,
            None => {
                let info = s.piece.and_then(|p| d.piece_info(p));
                let name = match (s.piece, info) {
                    (Some(p), Some(i)) => block_name(&i.label.name, p),
                    (Some(p), None) => format!("PIECE_{p}"),
                    (None, _) => String::new(),
                };
                blocks.push((
                    s.piece,
                    Block {
                        name,
                        info,
                        items: Vec::new(),
                        notes: Vec::new(),
                    },
                ));
                blocks.len() - 1
            }
        };
        blocks[at].1.items.push(Item {
            stroke: s,
            bulges: None,
            points: None,
        });
    }
    blocks.into_iter().map(|(_, b)| b).collect()
}

/// Block names made unique (two pieces may share a name after sanitising): `_2`, `_3`, … added.
fn unique_names(blocks: Vec<Block<'_>>) -> Vec<Block<'_>> {
    let mut out: Vec<Block<'_>> = Vec::with_capacity(blocks.len());
    for mut b in blocks {
        if !b.name.is_empty() {
            let base = b.name.clone();
            let mut k = 2;
            while out.iter().any(|o| o.name == b.name) {
                b.name = format!("{base}_{k}");
                k += 1;
            }
        }
        out.push(b);
    }
    out
}

/// A block name R12 accepts: letters, digits, `-`, `_`, `$`, upper case.
fn block_name(name: &str, instance: u32) -> String {
    let clean: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '$' {
                c.to_ascii_uppercase()
            } else {
                '_'
            }
        })
        .collect();
    let clean = if clean.is_empty() {
        "PIECE".into()
    } else {
        clean
    };
    format!("{clean}-{instance}")
}

fn write_blocks(blocks: &[Block<'_>], extents: Aabb2, layers: DxfLayers) -> String {
    let mut w = Writer { out: String::new() };
    header(&mut w, layers, extents);
    if layers == DxfLayers::Aama {
        w.pair(0, "SECTION");
        w.pair(2, "BLOCKS");
        for b in blocks.iter().filter(|b| !b.name.is_empty()) {
            w.pair(0, "BLOCK");
            w.pair(8, "0");
            w.pair(2, &b.name);
            w.pair(70, "0");
            w.xy(10, DVec2::ZERO);
            w.pair(3, &b.name);
            write_aama_piece(&mut w, b);
            w.pair(0, "ENDBLK");
            w.pair(8, "0");
        }
        w.pair(0, "ENDSEC");
    }
    w.pair(0, "SECTION");
    w.pair(2, "ENTITIES");
    match layers {
        DxfLayers::Aama => {
            let at = if extents.min.is_finite() {
                extents.min
            } else {
                DVec2::ZERO
            };
            w.text(
                "1",
                at - DVec2::new(0.0, 2.0 * TEXT_HEIGHT_MM),
                TEXT_HEIGHT_MM,
                "Units: METRIC",
            );
            for b in blocks {
                if b.name.is_empty() {
                    write_aama_items(&mut w, &b.items);
                } else {
                    w.pair(0, "INSERT");
                    w.pair(8, "0");
                    w.pair(2, &b.name);
                    w.xy(10, DVec2::ZERO);
                }
            }
        }
        DxfLayers::Named => {
            for b in blocks {
                for it in &b.items {
                    let s = it.stroke;
                    let pts = it.points.as_deref().unwrap_or(&s.points);
                    w.polyline(layers.layer(s.kind), pts, it.bulges.as_deref(), s.closed);
                }
            }
        }
    }
    footer(w)
}

/// The entities of one AAMA piece block: geometry by kind, turn and curve points of the
/// boundary, and the piece's text.
fn write_aama_piece(w: &mut Writer, b: &Block<'_>) {
    write_aama_items(w, &b.items);
    for (at, note) in &b.notes {
        w.text("15", *at, TEXT_HEIGHT_MM, note);
    }
    if let Some(boundary) = b
        .items
        .iter()
        .find(|i| i.stroke.kind == StrokeKind::Boundary)
    {
        let p = &boundary.stroke.points;
        let n = p.len();
        for k in 0..n {
            let (a, c, d) = (p[(k + n - 1) % n], p[k], p[(k + 1) % n]);
            let turn = (c - a).angle_to(d - c).abs().to_degrees();
            let layer = if turn > TURN_POINT_DEG {
                AAMA_TURN_POINTS
            } else {
                AAMA_CURVE_POINTS
            };
            w.point(layer, c);
        }
    }
    let label = b
        .info
        .map(|i| i.label.clone())
        .unwrap_or_else(|| LabelInfo {
            name: b.name.clone(),
            quantity: 1,
            ..LabelInfo::default()
        });
    let bbox = Aabb2::from_points(
        b.items
            .iter()
            .filter(|i| i.stroke.kind == StrokeKind::Boundary)
            .flat_map(|i| i.stroke.points.iter().copied()),
    );
    let origin = if bbox.min.is_finite() {
        DVec2::new(bbox.min.x, bbox.max.y) + DVec2::new(0.0, TEXT_HEIGHT_MM)
    } else {
        DVec2::ZERO
    };
    for (k, text) in [
        format!("Piece Name: {}", label.name),
        format!("Size: {}", label.size),
        format!("Quantity: {}", label.quantity),
        format!("Material: {}", label.material),
    ]
    .iter()
    .enumerate()
    {
        let at = origin + DVec2::new(0.0, (3 - k) as f64 * 1.5 * TEXT_HEIGHT_MM);
        w.text("1", at, TEXT_HEIGHT_MM, text);
    }
}

fn write_aama_items(w: &mut Writer, items: &[Item<'_>]) {
    let layers = DxfLayers::Aama;
    for it in items {
        let s = it.stroke;
        let layer = layers.layer(s.kind);
        let pts = it.points.as_deref().unwrap_or(&s.points);
        match s.kind {
            StrokeKind::Drill => w.point(layer, centroid(pts)),
            // The grain line itself; its arrow heads are drawing decoration an importer draws.
            StrokeKind::Grain if pts.len() == 2 => w.line(layer, pts[0], pts[1]),
            StrokeKind::Grain => {}
            StrokeKind::Notch | StrokeKind::Mirror if pts.len() == 2 && !s.closed => {
                w.line(layer, pts[0], pts[1])
            }
            _ => w.polyline(layer, pts, it.bulges.as_deref(), s.closed),
        }
    }
}

/// Centre of a drill hole's polygon (its vertices are evenly spaced on the circle).
fn centroid(p: &[DVec2]) -> DVec2 {
    p.iter().copied().sum::<DVec2>() / p.len().max(1) as f64
}

/// Vertices and bulges (bulge `i` belongs to the segment leaving vertex `i`) of a closed path.
fn bulge_polyline(segs: &[PathSeg], chord_tol: f64) -> (Vec<DVec2>, Vec<f64>) {
    let mut pts = Vec::new();
    let mut bulges = Vec::new();
    for s in segs {
        match *s {
            PathSeg::Line { p0, .. } => {
                pts.push(p0);
                bulges.push(0.0);
            }
            PathSeg::Arc { p0, bulge, .. } => {
                pts.push(p0);
                bulges.push(bulge);
            }
            PathSeg::Cubic { .. } => {
                let mut tmp = Vec::new();
                s.flatten(chord_tol, &mut tmp);
                tmp.pop();
                bulges.extend(std::iter::repeat_n(0.0, tmp.len()));
                pts.extend(tmp);
            }
        }
    }
    (pts, bulges)
}

/// Kept for the tool layer of a stroke read back without a kind (the named style).
pub(crate) fn named_layer_kind(name: &str) -> Option<(Layer, StrokeKind)> {
    Some(match name {
        "CUT" => (Layer::Cut, StrokeKind::InnerCut),
        "NOTCH" => (Layer::Cut, StrokeKind::Notch),
        "DRILL" => (Layer::Cut, StrokeKind::Drill),
        "DRAW" => (Layer::Draw, StrokeKind::Internal),
        "TEXT" => (Layer::Engrave, StrokeKind::Text),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dxf_read::read_dxf;
    use crate::piece::{Mark, MarkKind, Piece, PieceInput, PieceOptions, Placement};

    fn piece(name: &str) -> Piece {
        // half-disc: a straight edge and an arc
        let pts: Vec<DVec2> = (0..=32)
            .map(|i| 50.0 * DVec2::from_angle(i as f64 / 32.0 * std::f64::consts::PI))
            .collect();
        let mut input = PieceInput::new(name, pts);
        input.marks.push(Mark {
            kind: MarkKind::Notch,
            pos: DVec2::new(0., 50.),
            boundary_index: None,
        });
        input.marks.push(Mark {
            kind: MarkKind::Drill,
            pos: DVec2::new(0., 20.),
            boundary_index: None,
        });
        input.grain = Some((DVec2::new(-30., 10.), DVec2::new(30., 10.)));
        input.label.size = "38".into();
        input.label.material = "felt 3mm".into();
        input.label.quantity = 2;
        Piece::build(&input, &PieceOptions::default()).unwrap()
    }

    const PL: Placement = Placement {
        rotation: 0.3,
        mirror: true,
        translation: DVec2::new(100., 100.),
    };

    fn placed(p: &Piece) -> [PlacedPiece<'_>; 1] {
        [PlacedPiece {
            piece: p,
            instance: 1,
            placement: PL,
        }]
    }

    #[test]
    fn aama_blocks_text_and_layers_read_back_exactly() {
        let p = piece("cap");
        let text = write_pieces(&placed(&p), DxfLayers::Aama, 0.01);
        assert!(text.contains("AC1009") && !text.contains("$INSUNITS"));
        assert!(text.contains("\n  0\nBLOCK\n") && text.contains("\n  0\nINSERT\n"));
        for t in [
            "Piece Name: cap",
            "Size: 38",
            "Quantity: 2",
            "Material: felt 3mm",
            "Units: METRIC",
        ] {
            assert!(text.contains(t), "missing TEXT {t}");
        }
        let d = read_dxf(&text, 0.01).unwrap();
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        let d = d.drawing;
        let cut = d.strokes.iter().find(|s| s.is_outer()).unwrap();
        assert!(cut.closed && cut.layer == Layer::Cut);
        let expect: Vec<DVec2> = p.cut.iter().map(|q| PL.apply(*q)).collect();
        assert_eq!(cut.points.len(), expect.len());
        // Mirrored placement: the drawing reverses closed strokes to keep them CCW.
        for q in &cut.points {
            let best = expect
                .iter()
                .map(|e| e.distance(*q))
                .fold(f64::INFINITY, f64::min);
            assert!(best <= 1e-6, "{q} is {best} mm from the cut line");
        }
        let notches: Vec<_> = d
            .strokes
            .iter()
            .filter(|s| s.kind == StrokeKind::Notch)
            .collect();
        assert_eq!(notches.len(), 1);
        let drills: Vec<_> = d
            .strokes
            .iter()
            .filter(|s| s.kind == StrokeKind::Drill)
            .collect();
        assert_eq!(drills.len(), 1);
        assert!(centroid(&drills[0].points).distance(PL.apply(DVec2::new(0., 20.))) < 1e-6);
        let info = &d.pieces[0];
        assert_eq!(info.label.name, "cap");
        assert_eq!(info.label.size, "38");
        assert_eq!(info.label.quantity, 2);
        assert_eq!(info.label.material, "felt 3mm");
        let (a, b) = info.grain.unwrap();
        assert!(a.distance(PL.apply(DVec2::new(-30., 10.))) < 1e-6);
        assert!(b.distance(PL.apply(DVec2::new(30., 10.))) < 1e-6);
        // the sew line keeps its arcs: flattened back it lies on the sew polyline
        let sew = d
            .strokes
            .iter()
            .find(|s| s.kind == StrokeKind::Sew)
            .unwrap();
        let sew_exp: Vec<DVec2> = p.sew_polyline.iter().map(|q| PL.apply(*q)).collect();
        for q in &sew.points {
            assert!(crate::poly::dist_to_closed(&sew_exp, *q) < 0.03, "{q}");
        }
        assert!(d.strokes.iter().any(|s| s.kind == StrokeKind::Text));
        assert!(d.strokes.iter().all(|s| s.piece == Some(0)));
        assert_eq!(text, write_pieces(&placed(&p), DxfLayers::Aama, 0.01));
    }

    #[test]
    fn every_placed_piece_is_its_own_block_with_its_own_text() {
        // three pieces, all instance 1 (a pattern sheet shows one of each): three blocks
        let pieces = [piece("toe cap L"), piece("toe cap R"), piece("vamp L")];
        let placed: Vec<PlacedPiece<'_>> = pieces
            .iter()
            .enumerate()
            .map(|(k, p)| PlacedPiece {
                piece: p,
                instance: 1,
                placement: Placement {
                    translation: DVec2::new(150.0 * k as f64, 0.0),
                    ..Placement::IDENTITY
                },
            })
            .collect();
        let text = write_pieces(&placed, DxfLayers::Aama, 0.01);
        assert_eq!(text.matches("\n  0\nBLOCK\n").count(), 3);
        assert_eq!(text.matches("\n  0\nINSERT\n").count(), 3);
        for b in ["TOE_CAP_L-1", "TOE_CAP_R-1", "VAMP_L-1"] {
            assert!(text.contains(&format!("  2\n{b}\n")), "block {b}");
        }
        let d = read_dxf(&text, 0.01).unwrap().drawing;
        let names: Vec<&str> = d.pieces.iter().map(|i| i.label.name.as_str()).collect();
        assert_eq!(names, ["toe cap L", "toe cap R", "vamp L"]);
        assert_eq!(d.strokes.iter().filter(|s| s.is_outer()).count(), 3);
        // each run of one allowance is annotated: here the default seam all round
        assert_eq!(text.matches("seam 10.0 mm").count(), 3);
    }

    #[test]
    fn layers_come_from_kinds_not_from_names() {
        // A piece whose name looks like a stroke id of another kind.
        let p = piece("a-notch-b-drill-1-sew");
        let text = write_drawing(&p.to_drawing(1), DxfLayers::Aama);
        let d = read_dxf(&text, 0.01).unwrap().drawing;
        let count = |k| d.strokes.iter().filter(|s| s.kind == k).count();
        assert_eq!(count(StrokeKind::Drill), 1);
        assert_eq!(count(StrokeKind::Notch), 1);
        assert_eq!(count(StrokeKind::Sew), 1);
        assert_eq!(count(StrokeKind::Boundary), 1);
        assert_eq!(count(StrokeKind::Grain), 1);
    }

    #[test]
    fn named_layers_from_a_drawing() {
        let p = piece("cap");
        let text = write_drawing(&p.to_drawing(1), DxfLayers::Named);
        assert!(!text.contains("BLOCK"));
        for l in ["CUT", "DRAW", "NOTCH", "DRILL", "TEXT"] {
            assert!(text.contains(&format!("  8\n{l}\n")), "layer {l}");
        }
        let d = read_dxf(&text, 0.01).unwrap().drawing;
        assert_eq!(d.strokes.iter().filter(|s| s.is_outer()).count(), 1);
        assert!(d.strokes.iter().any(|s| s.kind == StrokeKind::Notch));
    }

    #[test]
    fn malformed_dxf_reports_the_line() {
        let e = read_dxf("  0\nSECTION\nxx\nENTITIES\n", 0.01).unwrap_err();
        assert!(e.to_string().contains("line 3"), "{e}");
    }
}
