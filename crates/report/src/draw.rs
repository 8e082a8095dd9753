//! Pictures of a report: the flattened piece coloured by a measure (SVG, true millimetres, one
//! cell per input, in rows), a histogram, a PNG rendered from the same SVG by resvg, and a
//! self-contained HTML page.
//!
//! Legend and titles are drawn with the single-stroke font (flatcut-font) as paths, so the SVG,
//! the PNG and the browser show identical text without any font file.

use flatcut_font as font;
use flatcut_geom::{Aabb2, DVec2};
use flatcut_mesh::TriMesh;
use std::collections::BTreeMap;

use svg::Document;
use svg::node::element::{Group, Path, Rectangle};

use crate::{Measure, Report, ReportError};

/// One input of a (side-by-side) picture.
pub struct Column<'a> {
    /// The caption drawn above the column.
    pub title: String,
    /// The flattened piece drawn (its `flat` positions, mm); `report` must have been computed
    /// from it.
    pub mesh: &'a TriMesh,
    /// The piece's report: its per-face measures colour the faces.
    pub report: &'a Report,
}

/// Margin around each column (mm).
const MARGIN: f64 = 10.0;
/// Height of titles and legend text (mm).
const TEXT_H: f64 = 4.0;
/// Minimum column width so titles and legends fit (mm).
const MIN_COL_W: f64 = 120.0;
/// Height of the legend block (mm).
const LEGEND_H: f64 = 36.0;
/// Colour given to flipped faces.
const FLIPPED: &str = "#ff00ff";
/// Colour of a face with nothing to show in the measure (no material to measure against).
const NO_VALUE: &str = "#d0d0d0";
/// Drawing width (mm) up to which titles and legend keep their nominal size. A wider drawing is
/// shown shrunk to the page (the HTML report fits it to the page width), so its annotations grow
/// in proportion: two 400 mm pieces side by side keep the legend as readable as one shoe piece.
const ANNOTATION_REF_W: f64 = 320.0;
/// Length of the legend's colour bar at nominal size (mm).
const LEGEND_BAR_W: f64 = 160.0;
/// Height of the legend's colour bar at nominal size (mm).
const LEGEND_BAR_H: f64 = 5.0;

fn n(v: f64) -> String {
    let s = format!("{v:.3}");
    if s == "-0.000" { "0.000".into() } else { s }
}

/// A perceptually ordered sequential map (viridis, 9 stops), t in [0, 1].
fn sequential(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 9] = [
        [68.0, 1.0, 84.0],
        [72.0, 40.0, 120.0],
        [62.0, 74.0, 137.0],
        [49.0, 104.0, 142.0],
        [38.0, 130.0, 142.0],
        [31.0, 158.0, 137.0],
        [53.0, 183.0, 121.0],
        [109.0, 205.0, 89.0],
        [253.0, 231.0, 37.0],
    ];
    interp(&STOPS, t)
}

/// The diverging map's colours, evenly spaced from −1 (blue: compression) through 0 (white) to
/// +1 (red: stretch); the workbench's page draws its heat maps with them too.
pub const DIVERGING_STOPS: [[f64; 3]; 5] = [
    [33.0, 102.0, 172.0],
    [146.0, 197.0, 222.0],
    [247.0, 247.0, 247.0],
    [244.0, 165.0, 130.0],
    [178.0, 24.0, 43.0],
];

/// A diverging map: blue (negative) – white (0) – red (positive), t in [−1, 1].
fn diverging(t: f64) -> [u8; 3] {
    interp(&DIVERGING_STOPS, 0.5 * (t + 1.0))
}

fn interp(stops: &[[f64; 3]], t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = t * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    std::array::from_fn(|k| (stops[i][k] * (1.0 - f) + stops[i + 1][k] * f).round() as u8)
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// The colour scale of one column (each piece has its own, so one spike in one piece does not
/// wash out the others): (lo, hi). A piece with nothing above the noise floor gets a scale of
/// ± the floor, on which it shows as zero.
fn scale(c: &Column<'_>, m: Measure) -> (f64, f64) {
    let hi = if m.signed() {
        c.report
            .per_face
            .iter()
            .map(|f| m.drawn(f).abs())
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    } else {
        let s = c.report.stats(m);
        s.p99.max(s.mean)
    };
    let hi = if hi.is_finite() && hi >= m.floor() {
        hi
    } else {
        m.floor()
    };
    if m.signed() { (-hi, hi) } else { (0.0, hi) }
}

/// A legend tick: enough decimals to tell the ticks of a scale reaching `hi` apart.
fn tick(m: Measure, v: f64, hi: f64) -> String {
    let d = (1.0 - hi.log10()).ceil().clamp(1.0, 6.0) as usize;
    let d = if m.signed() { d } else { d.max(3) };
    let v = if v.abs() < 0.5 * 10f64.powi(-(d as i32)) {
        0.0
    } else {
        v
    };
    if m.signed() {
        if v == 0.0 {
            "0".to_string()
        } else {
            format!("{v:+.d$}")
        }
    } else {
        format!("{v:.d$}")
    }
}

fn colour(m: Measure, v: f64, (lo, hi): (f64, f64)) -> String {
    if m.signed() {
        hex(diverging(v / hi))
    } else {
        hex(sequential((v - lo) / (hi - lo)))
    }
}

fn text_path(text: &str, origin: DVec2, h: f64, colour: &str) -> Path {
    let mut d = String::new();
    for stroke in font::text_strokes(text, origin, h, DVec2::X) {
        for (k, p) in stroke.iter().enumerate() {
            d.push_str(&format!(
                "{}{} {} ",
                if k == 0 { "M" } else { "L" },
                n(p.x),
                n(-p.y)
            ));
        }
    }
    Path::new()
        .set("d", d.trim_end().to_string())
        .set("fill", "none")
        .set("stroke", colour)
        .set("stroke-width", h * 0.08)
        .set("stroke-linecap", "round")
        .set("stroke-linejoin", "round")
}

/// The heat map of one or more flattened pieces at true scale in mm, each with its own legend in
/// real units, laid out in rows, as many to a row as brings the drawing nearest a landscape page.
/// `glyphs` adds short ticks along the principal stretch direction.
pub fn heatmap_svg(cols: &[Column<'_>], m: Measure, glyphs: bool) -> String {
    let boxes: Vec<Aabb2> = cols
        .iter()
        .map(|c| {
            c.mesh.flat_bbox().unwrap_or(Aabb2 {
                min: DVec2::ZERO,
                max: DVec2::ZERO,
            })
        })
        .collect();
    let grid = Grid::of(&boxes);
    let (u, width, height) = (grid.u, grid.width, grid.height);
    let (margin, text_h) = (MARGIN * u, TEXT_H * u);
    let title_h = 2.5 * text_h;
    let mut doc = Document::new()
        .set("xmlns", "http://www.w3.org/2000/svg")
        .set("width", format!("{}mm", n(width)))
        .set("height", format!("{}mm", n(height)))
        .set("viewBox", format!("0 0 {} {}", n(width), n(height)));
    doc = doc.add(
        Rectangle::new()
            .set("x", 0)
            .set("y", 0)
            .set("width", n(width))
            .set("height", n(height))
            .set("fill", "#ffffff"),
    );
    for (k, c) in cols.iter().enumerate() {
        let (b, cell) = (boxes[k], grid.cells[k]);
        let (x0, col_w) = (cell.x, cell.w);
        let ox = x0 + margin + (col_w - 2.0 * margin - b.width()) / 2.0 - b.min.x;
        let top = cell.y + title_h + margin;
        // Plane y up → SVG y down: y_svg = top + (b.max.y − y).
        let map = |p: DVec2| DVec2::new(ox + p.x, top + (b.max.y - p.y));
        let range = scale(c, m);
        let mut g = Group::new().set("id", format!("piece-{k}"));
        let flat = c.mesh.flat.as_ref();
        if let Some(flat) = flat {
            let fill_of = |t: usize| {
                let f = &c.report.per_face[t];
                let v = m.drawn(f);
                if f.flipped {
                    FLIPPED.to_string()
                } else if v.is_nan() {
                    NO_VALUE.to_string()
                } else {
                    colour(m, v, range)
                }
            };
            let tri_d = |tri: &[u32; 3]| {
                let q: Vec<DVec2> = tri.iter().map(|&v| map(flat[v as usize])).collect();
                format!(
                    "M{} {} L{} {} L{} {} Z",
                    n(q[0].x),
                    n(q[0].y),
                    n(q[1].x),
                    n(q[1].y),
                    n(q[2].x),
                    n(q[2].y)
                )
            };
            if c.mesh.triangles.len() <= MAX_FACE_ELEMENTS {
                for (t, tri) in c.mesh.triangles.iter().enumerate() {
                    let fill = fill_of(t);
                    g = g.add(face_path(tri_d(tri), fill));
                }
            } else {
                // One path per colour: a renderer's element limit is not reached by a mesh of
                // millions of faces, and the picture is the same.
                let mut by_fill: BTreeMap<String, String> = BTreeMap::new();
                for (t, tri) in c.mesh.triangles.iter().enumerate() {
                    let d = by_fill.entry(fill_of(t)).or_default();
                    if !d.is_empty() {
                        d.push(' ');
                    }
                    d.push_str(&tri_d(tri));
                }
                for (fill, d) in by_fill {
                    g = g.add(face_path(d, fill));
                }
            }
        }
        if glyphs && let Some(flat) = flat {
            let spacing = (b.width().max(b.height()) / 30.0).max(1.0);
            let mut last: Vec<DVec2> = Vec::new();
            let mut d = String::new();
            for (t, tri) in c.mesh.triangles.iter().enumerate() {
                let cen =
                    (flat[tri[0] as usize] + flat[tri[1] as usize] + flat[tri[2] as usize]) / 3.0;
                if last.iter().any(|p| p.distance(cen) < spacing) {
                    continue;
                }
                last.push(cen);
                let f = &c.report.per_face[t];
                let len = spacing * 0.4 * (1.0 + (f.stretch_pct / 10.0).min(1.0));
                let (a, e) = (map(cen - f.dir_max_2d * len), map(cen + f.dir_max_2d * len));
                d.push_str(&format!("M{} {} L{} {} ", n(a.x), n(a.y), n(e.x), n(e.y)));
            }
            g = g.add(
                Path::new()
                    .set("id", format!("glyphs-{k}"))
                    .set("d", d.trim_end().to_string())
                    .set("stroke", "#000000")
                    .set("stroke-width", 0.3 * u)
                    .set("fill", "none"),
            );
        }
        doc = doc.add(g);
        let title = format!(
            "{}  MEAN D2 {:.4}  MAX STRETCH {:.1}%",
            c.title, c.report.delta2_mean, c.report.stretch_max_pct
        );
        // Shrunk to its column when long (file names), so it never runs into its neighbour.
        let room = col_w - 2.0 * margin;
        let th = text_h * 0.8;
        let th = th * (room / font::text_width(&title, th)).min(1.0);
        doc = doc.add(text_path(
            &title,
            DVec2::new(x0 + margin, -(cell.y + 1.5 * text_h)),
            th,
            "#000000",
        ));
        // Legend: this piece's colour bar with five ticks.
        let ly = cell.y + title_h + cell.piece_h + 2.0 * margin;
        let bar_w = (col_w - 2.0 * margin).min(LEGEND_BAR_W * u);
        doc = legend(doc, m, range, DVec2::new(x0 + margin, ly), bar_w, u);
    }
    doc.to_string()
}

/// The shape (width over height) a heat map of many pieces is laid out toward: a landscape page
/// or screen, between A4 landscape (1.41) and 16:10 (1.6). Twelve graded shoe pieces in one row
/// made a 4096 × 217 px strip with each piece a few dozen pixels high.
const PAGE_ASPECT: f64 = 1.5;

/// Where the pieces of a heat map sit: in rows, left to right in their given order (a graded
/// set reads size by size), each with its title above and its legend below.
struct Grid {
    /// Annotation scale: 1 for a widest row of up to [`ANNOTATION_REF_W`], in proportion beyond.
    u: f64,
    /// One cell per piece.
    cells: Vec<Cell>,
    /// The drawing's width and height (mm).
    width: f64,
    height: f64,
}

/// A piece's place in a [`Grid`] (mm, SVG frame).
#[derive(Clone, Copy)]
struct Cell {
    /// The cell's top-left corner.
    x: f64,
    y: f64,
    /// The cell's width.
    w: f64,
    /// The height of the tallest piece in the cell's row.
    piece_h: f64,
}

impl Grid {
    /// The layout of pieces of these flat bounding boxes whose shape comes nearest
    /// [`PAGE_ASPECT`]; among equally near ones, the one of fewest rows.
    fn of(boxes: &[Aabb2]) -> Self {
        let misfit = |g: &Grid| (g.width / g.height / PAGE_ASPECT).ln().abs();
        (1..=boxes.len().max(1))
            .rev()
            .map(|per_row| Self::rows_of(boxes, per_row))
            .reduce(|best, g| if misfit(&g) < misfit(&best) { g } else { best })
            .expect("at least one layout is tried")
    }

    /// The layout of `per_row` pieces to a row.
    fn rows_of(boxes: &[Aabb2], per_row: usize) -> Self {
        let nominal = |b: &Aabb2| b.width().max(MIN_COL_W) + 2.0 * MARGIN;
        let widest = boxes
            .chunks(per_row)
            .map(|row| row.iter().map(nominal).sum::<f64>())
            .fold(0.0, f64::max);
        let u = (widest / ANNOTATION_REF_W).max(1.0);
        let (margin, title_h) = (MARGIN * u, 2.5 * TEXT_H * u);
        let (mut cells, mut width, mut y) = (Vec::with_capacity(boxes.len()), 0.0_f64, 0.0);
        for row in boxes.chunks(per_row) {
            let piece_h = row.iter().map(|b| b.height()).fold(0.0, f64::max);
            let mut x = 0.0;
            for b in row {
                let w = b.width().max(MIN_COL_W * u) + 2.0 * margin;
                cells.push(Cell { x, y, w, piece_h });
                x += w;
            }
            width = width.max(x);
            y += title_h + piece_h + 2.0 * margin + LEGEND_H * u;
        }
        Grid {
            u,
            cells,
            width,
            height: y,
        }
    }
}

/// Faces drawn as one element each up to this many per piece; beyond, one element per colour.
pub const MAX_FACE_ELEMENTS: usize = 100_000;

/// A filled face (or faces) of one colour, stroked in the same colour so no hairline shows
/// between neighbours.
fn face_path(d: String, fill: String) -> Path {
    Path::new()
        .set("d", d)
        .set("fill", fill.clone())
        .set("stroke", fill)
        .set("stroke-width", 0.05)
}

/// A colour bar at `at` (SVG frame, mm), `bar_w` long, with five ticks, the measure's title and
/// what the scale is.
fn legend(
    mut doc: Document,
    m: Measure,
    range: (f64, f64),
    at: DVec2,
    bar_w: f64,
    u: f64,
) -> Document {
    let (bar_h, text_h) = (LEGEND_BAR_H * u, TEXT_H * u);
    let steps = 64;
    for s in 0..steps {
        let t = s as f64 / (steps - 1) as f64;
        let v = range.0 + t * (range.1 - range.0);
        doc = doc.add(
            Rectangle::new()
                .set("x", n(at.x + t * bar_w * (steps - 1) as f64 / steps as f64))
                .set("y", n(at.y))
                .set("width", n(bar_w / steps as f64 + 0.05 * u))
                .set("height", n(bar_h))
                .set("fill", colour(m, v, range)),
        );
    }
    for i in 0..=4 {
        let t = i as f64 / 4.0;
        let label = tick(m, range.0 + t * (range.1 - range.0), range.1);
        let x = at.x + t * bar_w - font::text_width(&label, text_h * 0.7) / 2.0;
        doc = doc.add(text_path(
            &label,
            DVec2::new(x, -(at.y + bar_h + 1.5 * text_h)),
            text_h * 0.7,
            "#000000",
        ));
    }
    for (row, line) in [
        m.title().to_string(),
        format!("SCALE OF THIS PIECE; BELOW {} SHOWN AS 0", m.floor()),
    ]
    .iter()
    .enumerate()
    {
        doc = doc.add(text_path(
            line,
            DVec2::new(at.x, -(at.y + bar_h + (3.5 + 1.6 * row as f64) * text_h)),
            // The note shrinks to the bar; the measure's name keeps its size.
            if row == 0 {
                text_h * 0.7
            } else {
                text_h * 0.7 * (bar_w / font::text_width(line, text_h * 0.7)).min(1.0)
            },
            "#000000",
        ));
    }
    doc
}

/// A histogram of the measure over surface area (fraction of the area per bin), as SVG.
pub fn histogram_svg(report: &Report, m: Measure, bins: usize) -> String {
    let bins = bins.max(2);
    let vals: Vec<(f64, f64)> = report
        .per_face
        .iter()
        .map(|f| (m.of(f), f.area_3d))
        .filter(|v| v.0.is_finite())
        .collect();
    let (lo, hi) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v.0), b.max(v.0))
        });
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (0.0, 1.0)
    };
    let total: f64 = vals.iter().map(|v| v.1).sum::<f64>().max(f64::MIN_POSITIVE);
    let mut h = vec![0.0; bins];
    for (v, w) in &vals {
        let i = (((v - lo) / (hi - lo)) * bins as f64)
            .floor()
            .clamp(0.0, (bins - 1) as f64) as usize;
        h[i] += w / total;
    }
    let (w, ht) = (160.0, 60.0);
    let top = h.iter().copied().fold(0.0, f64::max).max(1e-12);
    let mut doc = Document::new()
        .set("xmlns", "http://www.w3.org/2000/svg")
        .set("width", format!("{w}mm"))
        .set("height", format!("{}mm", ht + 12.0))
        .set("viewBox", format!("0 0 {} {}", w, ht + 12.0));
    for (i, f) in h.iter().enumerate() {
        let bh = f / top * (ht - 2.0);
        doc = doc.add(
            Rectangle::new()
                .set("x", n(i as f64 * w / bins as f64))
                .set("y", n(ht - bh))
                .set("width", n(w / bins as f64 * 0.9))
                .set("height", n(bh))
                .set("fill", "#3b6ea5"),
        );
    }
    let lo_l = format!("{lo:.3}");
    let hi_l = format!("{hi:.3}");
    doc = doc.add(text_path(
        &lo_l,
        DVec2::new(0.0, -(ht + 8.0)),
        3.0,
        "#000000",
    ));
    doc = doc.add(text_path(
        &hi_l,
        DVec2::new(w - font::text_width(&hi_l, 3.0), -(ht + 8.0)),
        3.0,
        "#000000",
    ));
    doc.to_string()
}

/// Pixels per millimetre of the PNG when no width is asked for (≈ 254 dpi).
pub const DEFAULT_PX_PER_MM: f64 = 10.0;
/// Largest PNG rendered (pixels): 16 megapixels, 64 MB of RGBA.
pub const MAX_PNG_PIXELS: f64 = 16.0e6;

/// Longest side of a PNG rendered by default (pixels): a 2.5 m sail panel at the default
/// resolution would need 25,000 pixels a side (gigabytes); larger drawings get fewer pixels per
/// mm instead.
pub const MAX_DEFAULT_SIDE_PX: f64 = 4096.0;

/// Renders an SVG (ours) to PNG bytes with resvg, `width_px` wide (height in proportion).
pub fn render_png(svg: &str, width_px: Option<u32>) -> Result<Vec<u8>, ReportError> {
    use resvg::{tiny_skia, usvg};
    let tree = usvg::Tree::from_str(svg, &usvg::Options::default())
        .map_err(|e| ReportError::Render(e.to_string()))?;
    let size = tree.size();
    let longest = size.width().max(size.height()) as f64;
    let w = width_px.map_or(
        size.width() as f64
            * (DEFAULT_PX_PER_MM / (96.0 / 25.4)).min(MAX_DEFAULT_SIDE_PX / longest),
        |w| w as f64,
    );
    // A drawing metres long at the default density would need gigabytes of pixels: the image is
    // scaled down to stay within MAX_PNG_PIXELS.
    let area = size.width() as f64 * size.height() as f64;
    let s = (w / size.width() as f64).min((MAX_PNG_PIXELS / area).sqrt());
    let (pw, ph) = (
        (size.width() as f64 * s).ceil() as u32,
        (size.height() as f64 * s).ceil() as u32,
    );
    let mut pix = tiny_skia::Pixmap::new(pw.max(1), ph.max(1))
        .ok_or_else(|| ReportError::Render(format!("cannot allocate {pw}×{ph} pixels")))?;
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(s as f32, s as f32),
        &mut pix.as_mut(),
    );
    pix.encode_png()
        .map_err(|e| ReportError::Render(e.to_string()))
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A self-contained HTML report: the heat map, one histogram and one table per input, and the
/// worst regions with their location. No external assets.
pub fn html_report(cols: &[Column<'_>], m: Measure, glyphs: bool) -> String {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>flatcut distortion report</title>\n");
    h.push_str("<style>body{font-family:sans-serif;margin:2em;color:#222}table{border-collapse:collapse}td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:right}th{text-align:left}.cols{display:flex;gap:2em;flex-wrap:wrap}.col{flex:1;min-width:20em}.pic svg{width:100%;height:auto;border:1px solid #ccc}.hist svg{width:100%;height:auto}</style></head><body>\n");
    h.push_str(&format!("<h1>Distortion report</h1>\n<p>Measure shown: <b>{}</b>. Faces coloured by value; magenta = flipped.</p>\n", esc(m.title())));
    h.push_str(&format!(
        "<div class=\"pic\" id=\"heatmap\">{}</div>\n<div class=\"cols\">\n",
        heatmap_svg(cols, m, glyphs)
    ));
    for c in cols {
        let r = c.report;
        h.push_str(&format!(
            "<div class=\"col\"><h2>{}</h2>\n<div class=\"hist\">{}</div>\n<table>\n",
            esc(&c.title),
            histogram_svg(r, m, 40)
        ));
        let rows: Vec<(&str, String)> = vec![
            ("faces", r.faces.to_string()),
            ("flipped faces", r.flipped.to_string()),
            ("area 3D (mm²)", format!("{:.1}", r.area_3d_mm2)),
            ("area 2D (mm²)", format!("{:.1}", r.area_2d_mm2)),
            ("δ0 global", format!("{:.5}", r.delta0)),
            (
                "δ1 mean / p90 / max",
                format!(
                    "{:.5} / {:.5} / {:.5}",
                    r.delta1_mean, r.delta1_p90, r.delta1_max
                ),
            ),
            (
                "δ2 mean / p90 / max",
                format!(
                    "{:.5} / {:.5} / {:.5}",
                    r.delta2_mean, r.delta2_p90, r.delta2_max
                ),
            ),
            (
                "stretch max / p90 (%)",
                format!("{:.2} / {:.2}", r.stretch_max_pct, r.stretch_p90_pct),
            ),
            (
                "compression max / p90 (%)",
                format!("{:.2} / {:.2}", r.compress_max_pct, r.compress_p90_pct),
            ),
            ("area ratio mean", format!("{:.5}", r.area_mean)),
            (
                "boundary length error",
                format!("{:+.4}%", r.boundary_length_error * 100.0),
            ),
        ];
        for (k, v) in rows {
            h.push_str(&format!(
                "<tr><th>{}</th><td>{}</td></tr>\n",
                esc(k),
                esc(&v)
            ));
        }
        h.push_str("</table>\n");
        if !r.boundary_segments.is_empty() {
            h.push_str("<h3>Seams</h3><table><tr><th>from</th><th>to</th><th>3D mm</th><th>2D mm</th><th>error</th></tr>\n");
            for s in &r.boundary_segments {
                h.push_str(&format!(
                    "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td>{:.2}</td><td>{:+.3}%</td></tr>\n",
                    s.from_vertex,
                    s.to_vertex,
                    s.length_3d_mm,
                    s.length_2d_mm,
                    s.relative_error * 100.0
                ));
            }
            h.push_str("</table>\n");
        }
        if !r.mating_seams.is_empty() {
            h.push_str("<h3>Mating seams</h3><table><tr><th>seam</th><th>pieces</th><th>3D mm</th><th>2D mm</th><th>mismatch mm</th></tr>\n");
            for s in &r.mating_seams {
                h.push_str(&format!(
                    "<tr><td>{}</td><td>{} / {}</td><td>{:.2}</td><td>{:.3} / {:.3}</td><td>{:.4}</td></tr>\n",
                    esc(&s.name),
                    esc(&s.pieces[0]),
                    esc(&s.pieces[1]),
                    s.length_3d_mm,
                    s.length_2d_mm[0],
                    s.length_2d_mm[1],
                    s.mismatch_mm
                ));
                for n in &s.notches {
                    h.push_str(&format!(
                        "<tr><td>notch {}</td><td></td><td></td><td>{:.3} / {:.3}</td><td>{:.4}</td></tr>\n",
                        esc(&n.name),
                        n.offset_mm[0],
                        n.offset_mm[1],
                        (n.offset_mm[0] - n.offset_mm[1]).abs()
                    ));
                }
            }
            h.push_str("</table>\n");
        }
        if !r.darts.is_empty() {
            h.push_str("<h3>Darts</h3><table><tr><th>mouth 3D (mm)</th><th>point 3D (mm)</th><th>length mm</th><th>legs 2D mm</th><th>opening mm</th></tr>\n");
            for d in &r.darts {
                h.push_str(&format!(
                    "<tr><td>({:.1}, {:.1}, {:.1})</td><td>({:.1}, {:.1}, {:.1})</td><td>{:.1}</td><td>{:.2} / {:.2}</td><td>{:.1}</td></tr>\n",
                    d.start_3d[0], d.start_3d[1], d.start_3d[2], d.apex_3d[0], d.apex_3d[1], d.apex_3d[2],
                    d.length_3d_mm, d.leg_2d_mm[0], d.leg_2d_mm[1], d.opening_mm
                ));
            }
            h.push_str("</table>\n");
        }
        let over = !c.report.regions.is_empty();
        h.push_str(if over {
            "<h3>Regions beyond the limits</h3>\n"
        } else {
            "<h3>Worst regions (1 % of the area most stretched or compressed)</h3>\n"
        });
        let worst = worst_regions(c, 5);
        if worst.is_empty() {
            h.push_str("<p>No measurable distortion anywhere.</p>\n");
        } else {
            h.push_str("<table><tr><th>kind</th><th>worst %</th><th>area mm²</th><th>worst at 3D (mm)</th><th>worst at 2D (mm)</th></tr>\n");
            for r in worst {
                h.push_str(&format!(
                    "<tr><td>{}</td><td>{:.2}</td><td>{:.1}</td><td>({:.1}, {:.1}, {:.1})</td><td>({:.1}, {:.1})</td></tr>\n",
                    r.kind, r.worst_pct, r.area_mm2, r.worst_at_3d[0], r.worst_at_3d[1], r.worst_at_3d[2], r.worst_at_2d[0], r.worst_at_2d[1]
                ));
            }
            h.push_str("</table>\n");
        }
        h.push_str("</div>\n");
    }
    h.push_str("</div>\n<p><small>Duncan's measures (1976): μ1, μ2 are the extreme values of ds̄²/ds²; δ1 = log(μ1/μ2); δ2 = (μ1 + 1/μ1 + μ2 + 1/μ2 − 4)/2; δ0 = log(s2/s1) over pairs of points (geodesic vs plane distance).</small></p>\n</body></html>\n");
    h
}

/// The regions beyond the limits, or, when there are none, the hot spots: the regions of the
/// 1 % most stretched or compressed surface.
fn worst_regions(c: &Column<'_>, k: usize) -> Vec<crate::Region> {
    let mut v = if c.report.regions.is_empty() {
        c.report.hot_spots.clone()
    } else {
        c.report.regions.clone()
    };
    v.truncate(k);
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ReportOptions;
    use flatcut_geom::DVec3;

    /// A flat square piece of side `s` mm mapped to itself.
    fn square(s: f64) -> TriMesh {
        let p = [(0.0, 0.0), (s, 0.0), (s, s), (0.0, s), (0.5 * s, 0.5 * s)]
            .map(|(x, y)| DVec3::new(x, y, 0.0))
            .to_vec();
        let mut m = TriMesh::new(p, vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]);
        m.flat = Some(m.positions.iter().map(|p| p.truncate()).collect());
        m
    }

    /// The text paths of the SVG (stroke font: round caps), each as its list of points, and the
    /// viewBox width.
    fn text_paths(svg: &str) -> (Vec<Vec<DVec2>>, f64) {
        let w: f64 = svg
            .split("viewBox=\"0 0 ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let paths = svg
            .split("<path ")
            .skip(1)
            .filter(|p| p.contains("stroke-linecap"))
            .map(|p| {
                let d = p.split("d=\"").nth(1).unwrap().split('"').next().unwrap();
                let v: Vec<f64> = d
                    .split_whitespace()
                    .map(|t| t.trim_start_matches(['M', 'L']).parse().unwrap())
                    .collect();
                v.chunks(2).map(|c| DVec2::new(c[0], c[1])).collect()
            })
            .collect();
        (paths, w)
    }

    fn text_height(p: &[DVec2]) -> f64 {
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
                (a.min(q.y), b.max(q.y))
            });
        hi - lo
    }

    #[test]
    fn annotations_grow_with_a_wide_drawing_and_titles_stay_in_their_column() {
        let (small, big) = (square(100.0), square(800.0));
        let opts = ReportOptions::default();
        let (rs, rb) = (
            Report::compute("s", &small, &opts).unwrap(),
            Report::compute("b", &big, &opts).unwrap(),
        );
        let col = |title: &str, mesh, report| Column {
            title: title.into(),
            mesh,
            report,
        };
        let narrow = heatmap_svg(&[col("S", &small, &rs)], Measure::Stretch, false);
        let long = "A VERY LONG TITLE NAMING /SOME/DEEP/DIRECTORY/PIECE_WITH_DARTS.OBJ";
        let wide = heatmap_svg(
            &[col(long, &big, &rb), col(long, &big, &rb)],
            Measure::Stretch,
            false,
        );
        let (pn, wn) = text_paths(&narrow);
        let (pw, ww) = text_paths(&wide);
        // Per column: title, then its legend (five ticks, the measure's name drawn at
        // 0.7 × TEXT_H × scale, the scale note).
        let hn = text_height(&pn[pn.len() - 2]);
        let hw = text_height(&pw[pw.len() - 2]);
        assert!(
            wn < ANNOTATION_REF_W && ww > 4.0 * ANNOTATION_REF_W,
            "{wn} {ww}"
        );
        // The measure's name at its nominal cap height (0.7 × TEXT_H): as tall as the font
        // writes it there, parentheses included.
        let name = Measure::Stretch.title();
        let nominal =
            text_height(&font::text_strokes(name, DVec2::ZERO, 0.7 * TEXT_H, DVec2::X).concat());
        assert!(nominal > 0.7 * TEXT_H, "{nominal}");
        assert!(
            (hn - nominal).abs() < 0.01,
            "nominal legend text {hn} vs {nominal}"
        );
        // The wide drawing's annotations grow by its nominal width over the reference width, so
        // shrunk to the same page they read about as large (within the grown margins).
        let u = 2.0 * (800.0 + 2.0 * MARGIN) / ANNOTATION_REF_W;
        assert!(
            (hw / hn - u).abs() < 1e-3 * u,
            "legend text {hw} mm vs {hn} mm"
        );
        assert!(
            hw / ww >= 0.9 * hn / ANNOTATION_REF_W,
            "legend text {hw} mm on {ww} mm"
        );
        // The two titles each stay inside their own column (half the width, minus the margin).
        let xmax = |p: &[DVec2]| p.iter().map(|q| q.x).fold(f64::NEG_INFINITY, f64::max);
        let xmin = |p: &[DVec2]| p.iter().map(|q| q.x).fold(f64::INFINITY, f64::min);
        assert!(
            xmax(&pw[0]) <= 0.5 * ww + 1e-6,
            "title 0 ends at {}",
            xmax(&pw[0])
        );
        assert!(xmin(&pw[8]) >= 0.5 * ww - 1e-6 && xmax(&pw[8]) <= ww + 1e-6);
        // Each column's legend stays in its column too.
        for p in &pw[1..8] {
            assert!(xmax(p) <= 0.5 * ww + 1e-6);
        }
    }

    #[test]
    fn a_piece_of_more_faces_than_elements_is_drawn_one_path_per_colour_and_renders() {
        // 240 × 240 quads: 115,200 faces, stretched along x by 0 % at the bottom to 10 % at the top.
        let k = 240;
        let mut m =
            flatcut_mesh::test_grid::grid_mesh(k, k, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        m.flat = Some(
            m.positions
                .iter()
                .map(|q| DVec2::new(q.x * (1.0 + 0.1 * q.y / k as f64), q.y))
                .collect(),
        );
        assert!(m.triangles.len() > MAX_FACE_ELEMENTS);
        let r = Report::compute("big", &m, &ReportOptions::default()).unwrap();
        let cols = [Column {
            title: "BIG".into(),
            mesh: &m,
            report: &r,
        }];
        let svg = heatmap_svg(&cols, Measure::Stretch, false);
        let piece = svg.split("id=\"piece-0\"").nth(1).unwrap();
        let piece = piece.split("</g>").next().unwrap();
        let elements = piece.matches("<path").count();
        let fills: std::collections::BTreeSet<&str> =
            piece.split("fill=\"").skip(1).map(|s| &s[..7]).collect();
        // Several colours (the stretch varies), one element each, every face drawn.
        assert!(
            fills.len() > 5 && elements == fills.len(),
            "{elements} elements, {} fills",
            fills.len()
        );
        assert_eq!(piece.matches('Z').count(), m.triangles.len());
        let png = render_png(&svg, Some(600)).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
    }

    /// The bounding box of a piece's faces in the SVG (mm), read from its group's paths.
    fn piece_box(svg: &str, k: usize) -> Aabb2 {
        let g = svg.split(&format!("id=\"piece-{k}\"")).nth(1).unwrap();
        let g = g.split("</g>").next().unwrap();
        let v: Vec<f64> = g
            .split("d=\"")
            .skip(1)
            .flat_map(|p| p.split('"').next().unwrap().split_whitespace())
            .filter_map(|t| {
                t.trim_start_matches(['M', 'L'])
                    .trim_end_matches('Z')
                    .parse()
                    .ok()
            })
            .collect();
        let pts: Vec<DVec2> = v.chunks(2).map(|c| DVec2::new(c[0], c[1])).collect();
        Aabb2::from_points(pts)
    }

    #[test]
    fn a_graded_set_is_laid_out_in_rows_near_a_page_in_its_given_order() {
        // Twelve 250 × 90 mm pieces (four pieces in three sizes): one row was a 45:1 strip.
        let piece = |w: f64| {
            let mut m = square(1.0);
            if let Some(f) = &mut m.flat {
                f.iter_mut()
                    .for_each(|q| *q = DVec2::new(q.x * w, q.y * 90.0));
            }
            m.positions = m
                .flat
                .as_ref()
                .unwrap()
                .iter()
                .map(|q| q.extend(0.0))
                .collect();
            m
        };
        let meshes: Vec<TriMesh> = (0..12).map(|k| piece(240.0 + k as f64)).collect();
        let reports: Vec<Report> = meshes
            .iter()
            .map(|m| Report::compute("p", m, &ReportOptions::default()).unwrap())
            .collect();
        let cols: Vec<Column<'_>> = meshes
            .iter()
            .zip(&reports)
            .enumerate()
            .map(|(k, (mesh, report))| Column {
                title: format!("P{k}"),
                mesh,
                report,
            })
            .collect();
        let svg = heatmap_svg(&cols, Measure::Stretch, false);
        let (_, w) = text_paths(&svg);
        let h: f64 = svg
            .split("viewBox=\"0 0 ")
            .nth(1)
            .unwrap()
            .split(['"', ' '])
            .nth(1)
            .unwrap()
            .parse()
            .unwrap();
        assert!((1.0..=2.25).contains(&(w / h)), "{w} × {h} mm");
        let boxes: Vec<Aabb2> = (0..12).map(|k| piece_box(&svg, k)).collect();
        // Every piece drawn at true size, inside the drawing, overlapping no other.
        for (k, b) in boxes.iter().enumerate() {
            assert!((b.width() - (240.0 + k as f64)).abs() < 1e-6, "{k}: {b:?}");
            assert!((b.height() - 90.0).abs() < 1e-6, "{k}: {b:?}");
            assert!(b.min.x >= 0.0 && b.min.y >= 0.0 && b.max.x <= w && b.max.y <= h);
            for c in &boxes[..k] {
                assert!(
                    b.min.x >= c.max.x
                        || c.min.x >= b.max.x
                        || b.min.y >= c.max.y
                        || c.min.y >= b.max.y,
                    "{b:?} overlaps {c:?}"
                );
            }
        }
        // Several rows, read in the given order: left to right, then down.
        let rows = 1 + boxes.windows(2).filter(|p| p[1].min.y > p[0].max.y).count();
        assert!((2..=6).contains(&rows), "{rows} rows");
        for p in boxes.windows(2) {
            assert!(p[1].min.x > p[0].max.x || p[1].min.y > p[0].max.y);
        }
        // As a PNG of the default size, a piece is hundreds of pixels wide, not dozens.
        let png = render_png(&svg, None).unwrap();
        let png_w = u32::from_be_bytes(png[16..20].try_into().unwrap()) as f64;
        assert!(png_w / w * 240.0 > 500.0, "{png_w} px over {w} mm");
    }

    #[test]
    fn each_piece_has_its_own_scale_and_noise_below_the_floor_is_zero() {
        let opts = ReportOptions::default();
        // floating-point noise: 1e-13 relative
        let mut noisy = square(100.0);
        if let Some(f) = &mut noisy.flat {
            f[0] *= 1.0 + 1e-13;
        }
        let rn = Report::compute("noisy", &noisy, &opts).unwrap();
        let mut stretched = square(100.0);
        if let Some(f) = &mut stretched.flat {
            f.iter_mut().for_each(|q| q.x *= 1.2);
        }
        let rs = Report::compute("stretched", &stretched, &opts).unwrap();
        let cols = [
            Column {
                title: "NOISY".into(),
                mesh: &noisy,
                report: &rn,
            },
            Column {
                title: "STRETCHED".into(),
                mesh: &stretched,
                report: &rs,
            },
        ];
        let svg = heatmap_svg(&cols, Measure::Stretch, false);
        // the noisy piece is white (zero on the diverging map), not saturated
        let piece0 = svg.split("id=\"piece-0\"").nth(1).unwrap();
        let piece0 = piece0.split("</g>").next().unwrap();
        assert!(
            piece0.contains("fill=\"#f7f7f7\"") && !piece0.contains("#b2182b"),
            "{piece0}"
        );
        // the stretched piece is saturated on its own scale (+20 %)
        let piece1 = svg.split("id=\"piece-1\"").nth(1).unwrap();
        let piece1 = piece1.split("</g>").next().unwrap();
        assert!(piece1.contains("fill=\"#b2182b\""), "{piece1}");
        // legend ticks are drawn as strokes; their text comes from `tick`
        assert_eq!(tick(Measure::Stretch, 20.0, 20.0), "+20.0");
        assert_eq!(tick(Measure::Stretch, -0.005, 0.01), "-0.005");
        assert_eq!(tick(Measure::Stretch, 1e-17, 0.01), "0");
    }
}
