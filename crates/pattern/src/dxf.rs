//! DXF export (R12, `AC1009`, ASCII) for industrial cutters, and a small reader for the subset
//! we write (round trips and re-import of our own files).
//!
//! Entities are `POLYLINE`/`VERTEX`/`SEQEND` (arcs as vertex bulges, group code 42), which every
//! R12 reader and every cutter front end accepts. Units are mm (`$INSUNITS` 4, `$MEASUREMENT` 1).
//! Layers follow one of two conventions:
//! * [`DxfLayers::Aama`] (default): the AAMA/ASTM D6673 pattern layer numbers — `1` boundary
//!   (cut line), `4` notches, `8` internal lines (grain line, marks), `13` drill holes,
//!   `14` sew lines, `15` annotation text (label strokes). Layer 11 (internal cut-outs) is
//!   used for other closed inner cut contours.
//! * [`DxfLayers::Named`]: `CUT`, `DRAW`, `NOTCH`, `DRILL`, `TEXT` for laser/knife software.
//!
//! Numbers are written with 4 decimals (0.1 µm), so output is byte-identical for identical input.

use crate::PatternError;
use crate::drawing::{Drawing, Layer, Stroke};
use crate::fit::PathSeg;
use crate::piece::PlacedPiece;
use flatcut_geom::DVec2;
use std::fmt::Write;

/// Layer naming convention.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DxfLayers {
    /// AAMA/ASTM D6673 numeric layers.
    #[default]
    Aama,
    /// Descriptive names.
    Named,
}

/// What a stroke is, for layer selection.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Boundary,
    InnerCut,
    Notch,
    Drill,
    Sew,
    Internal,
    Text,
}

impl DxfLayers {
    fn name(self, role: Role) -> &'static str {
        match (self, role) {
            (DxfLayers::Aama, Role::Boundary) => "1",
            (DxfLayers::Aama, Role::Notch) => "4",
            (DxfLayers::Aama, Role::Internal) => "8",
            (DxfLayers::Aama, Role::InnerCut) => "11",
            (DxfLayers::Aama, Role::Drill) => "13",
            (DxfLayers::Aama, Role::Sew) => "14",
            (DxfLayers::Aama, Role::Text) => "15",
            (DxfLayers::Named, Role::Boundary | Role::InnerCut) => "CUT",
            (DxfLayers::Named, Role::Notch) => "NOTCH",
            (DxfLayers::Named, Role::Drill) => "DRILL",
            (DxfLayers::Named, Role::Sew | Role::Internal) => "DRAW",
            (DxfLayers::Named, Role::Text) => "TEXT",
        }
    }
    /// Layers in table order with their ACI colour.
    fn table(self) -> Vec<(&'static str, u8)> {
        let roles = [
            (Role::Boundary, 1),
            (Role::Notch, 3),
            (Role::Internal, 5),
            (Role::InnerCut, 1),
            (Role::Drill, 6),
            (Role::Sew, 5),
            (Role::Text, 7),
        ];
        let mut v: Vec<(&'static str, u8)> = Vec::new();
        for (r, c) in roles {
            let n = self.name(r);
            if !v.iter().any(|(m, _)| *m == n) {
                v.push((n, c));
            }
        }
        v
    }
}

fn role_of(s: &Stroke) -> Role {
    match s.layer {
        Layer::Cut if s.outer => Role::Boundary,
        Layer::Cut if s.id.contains("-notch-") => Role::Notch,
        Layer::Cut if s.id.contains("-drill-") => Role::Drill,
        Layer::Cut => Role::InnerCut,
        Layer::Draw if s.id.ends_with("-sew") => Role::Sew,
        Layer::Draw => Role::Internal,
        Layer::Engrave => Role::Text,
    }
}

fn num(v: f64) -> String {
    let s = format!("{v:.4}");
    if s == "-0.0000" { "0.0000".into() } else { s }
}

struct Writer {
    out: String,
}

impl Writer {
    fn pair(&mut self, code: i32, value: &str) {
        let _ = write!(self.out, "{code:>3}\n{value}\n");
    }
    fn polyline(&mut self, layer: &str, pts: &[DVec2], bulges: Option<&[f64]>, closed: bool) {
        self.pair(0, "POLYLINE");
        self.pair(8, layer);
        self.pair(66, "1");
        self.pair(10, "0.0");
        self.pair(20, "0.0");
        self.pair(30, "0.0");
        self.pair(70, if closed { "1" } else { "0" });
        for (i, p) in pts.iter().enumerate() {
            self.pair(0, "VERTEX");
            self.pair(8, layer);
            self.pair(10, &num(p.x));
            self.pair(20, &num(p.y));
            self.pair(30, "0.0");
            if let Some(b) = bulges.and_then(|b| b.get(i)).filter(|b| **b != 0.0) {
                self.pair(42, &num(*b));
            }
        }
        self.pair(0, "SEQEND");
        self.pair(8, layer);
    }
}

fn header(layers: DxfLayers, extents: (DVec2, DVec2)) -> Writer {
    let mut w = Writer { out: String::new() };
    w.pair(0, "SECTION");
    w.pair(2, "HEADER");
    w.pair(9, "$ACADVER");
    w.pair(1, "AC1009");
    w.pair(9, "$INSUNITS");
    w.pair(70, "4");
    w.pair(9, "$MEASUREMENT");
    w.pair(70, "1");
    w.pair(9, "$EXTMIN");
    w.pair(10, &num(extents.0.x));
    w.pair(20, &num(extents.0.y));
    w.pair(9, "$EXTMAX");
    w.pair(10, &num(extents.1.x));
    w.pair(20, &num(extents.1.y));
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
    w.pair(0, "SECTION");
    w.pair(2, "ENTITIES");
    w
}

fn footer(mut w: Writer) -> String {
    w.pair(0, "ENDSEC");
    w.pair(0, "EOF");
    w.out
}

fn extents(d: &Drawing) -> (DVec2, DVec2) {
    let b = d.bbox();
    if b.min.is_finite() {
        (b.min, b.max)
    } else {
        (DVec2::ZERO, DVec2::ZERO)
    }
}

/// Writes a drawing (all strokes as polylines).
pub fn write_drawing(d: &Drawing, layers: DxfLayers) -> String {
    let mut w = header(layers, extents(d));
    for s in d.strokes.iter().filter(|s| s.points.len() >= 2) {
        w.polyline(layers.name(role_of(s)), &s.points, None, s.closed);
    }
    footer(w)
}

/// Writes placed pieces; the sew line keeps its fitted lines and arcs as bulge polylines
/// (cubics are flattened within the piece's chord tolerance).
pub fn write_pieces(placed: &[PlacedPiece], layers: DxfLayers, chord_tol: f64) -> String {
    let drawings: Vec<Drawing> = placed.iter().map(|p| p.to_drawing()).collect();
    let all = Drawing {
        strokes: drawings
            .iter()
            .flat_map(|d| d.strokes.iter().cloned())
            .collect(),
    };
    let mut w = header(layers, extents(&all));
    for (pp, d) in placed.iter().zip(&drawings) {
        let sew_id = format!("{}-sew", pp.piece.instance_id(pp.instance));
        for s in d.strokes.iter().filter(|s| s.points.len() >= 2) {
            if s.id == sew_id && !pp.piece.sew.is_empty() {
                let (pts, bulges) = bulge_polyline(&pp.piece.sew, chord_tol);
                let pl = pp.placement;
                let pts: Vec<DVec2> = pts.iter().map(|q| pl.apply(*q)).collect();
                let bulges: Vec<f64> = bulges
                    .iter()
                    .map(|b| if pl.mirror { -b } else { *b })
                    .collect();
                w.polyline(layers.name(Role::Sew), &pts, Some(&bulges), true);
            } else {
                w.polyline(layers.name(role_of(s)), &s.points, None, s.closed);
            }
        }
    }
    footer(w)
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

/// A polyline read back from a DXF.
#[derive(Clone, Debug, PartialEq)]
pub struct DxfPolyline {
    pub layer: String,
    pub points: Vec<DVec2>,
    pub bulges: Vec<f64>,
    pub closed: bool,
}

/// Reads the `POLYLINE`/`VERTEX` and `LWPOLYLINE` entities of an ASCII DXF.
pub fn read_polylines(text: &str) -> Result<Vec<DxfPolyline>, PatternError> {
    let lines: Vec<&str> = text.lines().collect();
    if !lines.len().is_multiple_of(2) {
        return Err(PatternError::Dxf {
            line: lines.len(),
            reason: "odd number of lines (code/value pairs)".into(),
        });
    }
    let mut pairs = Vec::with_capacity(lines.len() / 2);
    for k in (0..lines.len()).step_by(2) {
        let code: i32 = lines[k].trim().parse().map_err(|_| PatternError::Dxf {
            line: k + 1,
            reason: format!("group code expected, found `{}`", lines[k].trim()),
        })?;
        pairs.push((code, lines[k + 1].trim(), k + 2));
    }
    let parse = |v: &str, line: usize| -> Result<f64, PatternError> {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| PatternError::Dxf {
                line,
                reason: format!("number expected, found `{v}`"),
            })
    };
    let mut out = Vec::new();
    let mut i = 0;
    let mut in_entities = false;
    while i < pairs.len() {
        let (code, val, _) = pairs[i];
        if code == 2 && val == "ENTITIES" {
            in_entities = true;
        }
        if !(in_entities && code == 0 && (val == "POLYLINE" || val == "LWPOLYLINE")) {
            i += 1;
            continue;
        }
        let lw = val == "LWPOLYLINE";
        let mut pl = DxfPolyline {
            layer: String::new(),
            points: Vec::new(),
            bulges: Vec::new(),
            closed: false,
        };
        i += 1;
        // entity header
        while i < pairs.len() && pairs[i].0 != 0 {
            let (c, v, ln) = pairs[i];
            match c {
                8 => pl.layer = v.to_string(),
                70 => pl.closed = (parse(v, ln)? as i64) & 1 == 1,
                10 if lw => {
                    pl.points.push(DVec2::new(parse(v, ln)?, 0.0));
                    pl.bulges.push(0.0);
                }
                20 if lw => {
                    if let Some(p) = pl.points.last_mut() {
                        p.y = parse(v, ln)?;
                    }
                }
                42 if lw => {
                    if let Some(b) = pl.bulges.last_mut() {
                        *b = parse(v, ln)?;
                    }
                }
                _ => {}
            }
            i += 1;
        }
        if !lw {
            while i < pairs.len() && pairs[i].0 == 0 && pairs[i].1 == "VERTEX" {
                i += 1;
                let (mut p, mut b) = (DVec2::ZERO, 0.0);
                while i < pairs.len() && pairs[i].0 != 0 {
                    let (c, v, ln) = pairs[i];
                    match c {
                        10 => p.x = parse(v, ln)?,
                        20 => p.y = parse(v, ln)?,
                        42 => b = parse(v, ln)?,
                        _ => {}
                    }
                    i += 1;
                }
                pl.points.push(p);
                pl.bulges.push(b);
            }
            if i < pairs.len() && pairs[i].1 == "SEQEND" {
                i += 1;
            } else {
                let ln = pairs.get(i).map(|p| p.2).unwrap_or(lines.len());
                return Err(PatternError::Dxf {
                    line: ln,
                    reason: "POLYLINE without SEQEND".into(),
                });
            }
        }
        out.push(pl);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::piece::{Mark, MarkKind, Piece, PieceInput, PieceOptions, Placement};

    fn piece() -> Piece {
        // half-disc: a straight edge and an arc
        let pts: Vec<DVec2> = (0..=32)
            .map(|i| 50.0 * DVec2::from_angle(i as f64 / 32.0 * std::f64::consts::PI))
            .collect();
        let mut input = PieceInput::new("cap", pts);
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
        Piece::build(&input, &PieceOptions::default()).unwrap()
    }

    #[test]
    fn round_trip_of_coordinates_and_layers() {
        let p = piece();
        let pl = Placement {
            rotation: 0.0,
            mirror: false,
            translation: DVec2::new(100., 100.),
        };
        let text = write_pieces(
            &[PlacedPiece {
                piece: &p,
                instance: 1,
                placement: pl,
            }],
            DxfLayers::Aama,
            0.01,
        );
        assert!(text.contains("AC1009"));
        let pls = read_polylines(&text).unwrap();
        let cut = pls.iter().find(|l| l.layer == "1").unwrap();
        assert!(cut.closed);
        assert_eq!(cut.points.len(), p.cut.len());
        for (a, b) in cut.points.iter().zip(&p.cut) {
            assert!(a.distance(pl.apply(*b)) <= 0.5e-4 * 1.5, "{a} vs {b}");
        }
        assert!(pls.iter().any(|l| l.layer == "4"), "notch layer");
        assert!(pls.iter().any(|l| l.layer == "13"), "drill layer");
        let sew = pls.iter().find(|l| l.layer == "14").unwrap();
        // the half-disc's curved side is two quarter arcs (split at the notch): bulge tan(π/8)
        let q = (std::f64::consts::PI / 8.0).tan();
        assert_eq!(
            sew.bulges.iter().filter(|b| (**b - q).abs() < 1e-3).count(),
            2,
            "{:?}",
            sew.bulges
        );
        assert_eq!(
            text,
            write_pieces(
                &[PlacedPiece {
                    piece: &p,
                    instance: 1,
                    placement: pl
                }],
                DxfLayers::Aama,
                0.01
            )
        );
    }

    #[test]
    fn named_layers_from_a_drawing() {
        let p = piece();
        let text = write_drawing(&p.to_drawing(1), DxfLayers::Named);
        let pls = read_polylines(&text).unwrap();
        for l in ["CUT", "DRAW", "NOTCH", "DRILL", "TEXT"] {
            assert!(pls.iter().any(|p| p.layer == l), "layer {l}");
        }
    }

    #[test]
    fn malformed_dxf_reports_the_line() {
        let e = read_polylines("  0\nSECTION\nxx\nENTITIES\n").unwrap_err();
        assert!(e.to_string().contains("line 3"), "{e}");
    }
}
