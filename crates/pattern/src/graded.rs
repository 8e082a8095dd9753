//! The graded nest of a piece: every size's cut and sew lines stacked on one reference point, as
//! pattern makers check a grade (the lines should grow evenly from size to size, never cross).
//! The reference point of a piece is the start of its grain line (the same point of the design
//! in every size, and every size turned with its grain along +x), else the middle of its sew
//! line. A picture in true millimetres (1 user unit = 1 mm), each size in its own colour, with
//! a legend; not a cutting file.

use crate::drawing::Layer;
use crate::piece::Piece;
use flatcut_font as font;
use flatcut_geom::{Aabb2, DVec2};
use svg::node::element::{Group, Polygon, Polyline};

/// Colours of the sizes, in order (repeated beyond eight).
const COLOURS: [&str; 8] = [
    "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
];
/// Margin round the picture and cap height of the legend (mm).
const MARGIN_MM: f64 = 10.0;
const LEGEND_MM: f64 = 5.0;
/// Half-size of the reference point's cross (mm).
const CROSS_MM: f64 = 4.0;

/// A piece's reference point for grading: its grain line's start, else the area centroid of its
/// sew line.
pub fn reference_point(p: &Piece) -> DVec2 {
    p.grain.map(|(a, _)| a).unwrap_or_else(|| {
        flatcut_geom::polygon::area_centroid(&p.sew_polyline).unwrap_or(DVec2::ZERO)
    })
}

fn f(v: f64) -> String {
    let s = format!("{v:.3}");
    if s == "-0.000" { "0.000".into() } else { s }
}

/// The graded nest of `title`: each (size, piece) drawn with its reference point at the origin.
pub fn graded_svg(title: &str, sizes: &[(&str, &Piece)]) -> String {
    let shifted: Vec<(&str, Vec<DVec2>, Vec<DVec2>)> = sizes
        .iter()
        .map(|(size, p)| {
            let r = reference_point(p);
            (
                *size,
                p.cut.iter().map(|q| *q - r).collect(),
                p.sew_polyline.iter().map(|q| *q - r).collect(),
            )
        })
        .collect();
    let mut legend: Vec<(String, usize)> = vec![(title.to_string(), usize::MAX)];
    legend.extend(
        sizes
            .iter()
            .enumerate()
            .map(|(k, (size, _))| (format!("size {size}"), k)),
    );
    let body = Aabb2::from_points(shifted.iter().flat_map(|(_, c, _)| c.iter().copied()));
    let (lo, hi) = if body.min.is_finite() {
        (body.min, body.max)
    } else {
        (DVec2::ZERO, DVec2::ZERO)
    };
    let legend_h = legend.len() as f64 * LEGEND_MM * font::LINE_SPACING;
    let origin = lo - DVec2::splat(MARGIN_MM);
    let size = (hi - lo) + DVec2::new(2.0 * MARGIN_MM, 2.0 * MARGIN_MM + legend_h);
    let map = |p: DVec2| (f(p.x - origin.x), f(size.y - (p.y - origin.y)));
    let pts = |p: &[DVec2]| {
        p.iter()
            .map(|q| {
                let (x, y) = map(*q);
                format!("{x},{y}")
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut doc = svg::Document::new()
        .set("width", format!("{}mm", f(size.x)))
        .set("height", format!("{}mm", f(size.y)))
        .set("viewBox", format!("0 0 {} {}", f(size.x), f(size.y)));
    for (k, (name, cut, sew)) in shifted.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let g = Group::new()
            .set("id", format!("size-{}", crate::safe_name(name)))
            .set("fill", "none")
            .set("stroke", colour)
            .add(
                Polygon::new()
                    .set("points", pts(cut))
                    .set("stroke-width", f(0.3)),
            )
            .add(
                Polygon::new()
                    .set("points", pts(sew))
                    .set("stroke-width", f(0.15))
                    .set("stroke-dasharray", "2 1"),
            );
        doc = doc.add(g);
    }
    let ink = crate::svg::layer_colour(Layer::Engrave);
    let mut marks = Group::new()
        .set("id", "reference")
        .set("fill", "none")
        .set("stroke", ink)
        .set("stroke-width", f(0.2));
    for d in [DVec2::X, DVec2::Y] {
        marks = marks.add(Polyline::new().set("points", pts(&[-d * CROSS_MM, d * CROSS_MM])));
    }
    doc = doc.add(marks);
    let top = DVec2::new(lo.x, hi.y + MARGIN_MM + legend_h - LEGEND_MM);
    let mut text = Group::new()
        .set("id", "legend")
        .set("fill", "none")
        .set("stroke-width", f(0.3));
    for (row, (line, k)) in legend.iter().enumerate() {
        let colour = COLOURS.get(*k % COLOURS.len()).filter(|_| *k != usize::MAX);
        let at = top - DVec2::new(0.0, row as f64 * LEGEND_MM * font::LINE_SPACING);
        for s in font::text_strokes(line, at, LEGEND_MM, DVec2::X) {
            text = text.add(
                Polyline::new()
                    .set("points", pts(&s))
                    .set("stroke", colour.copied().unwrap_or(ink)),
            );
        }
    }
    doc = doc.add(text);
    let mut s = doc.to_string();
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{PieceInput, PieceOptions};

    fn square(side: f64) -> Piece {
        let mut input = PieceInput::new(
            "panel",
            vec![
                DVec2::ZERO,
                DVec2::new(side, 0.0),
                DVec2::new(side, side),
                DVec2::new(0.0, side),
            ],
        );
        input.grain = Some((DVec2::new(10.0, 10.0), DVec2::new(side - 10.0, 10.0)));
        Piece::build(&input, &PieceOptions::default()).unwrap()
    }

    #[test]
    fn sizes_stack_on_their_reference_points() {
        let (s, m) = (square(100.0), square(110.0));
        let svg = graded_svg("panel", &[("S", &s), ("M", &m)]);
        assert!(svg.contains("id=\"size-S\"") && svg.contains("id=\"size-M\""));
        assert_eq!(reference_point(&s), DVec2::new(10.0, 10.0));
        // both cut lines' lower-left corners sit at (−20, −20) from the shared reference point:
        // the first polygon of each size group has the same smallest x and largest y
        let corner = |id: &str| {
            let at = svg.find(&format!("id=\"{id}\"")).unwrap();
            let pts = &svg[at..];
            let pts = &pts[pts.find("points=\"").unwrap() + 8..];
            let pts = &pts[..pts.find('"').unwrap()];
            pts.split(' ')
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse::<f64>().unwrap(), y.parse::<f64>().unwrap())
                })
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (x, y)| {
                    (a.min(x), b.max(y))
                })
        };
        assert_eq!(corner("size-S"), corner("size-M"));
        assert_eq!(svg, graded_svg("panel", &[("S", &s), ("M", &m)]));
    }
}
