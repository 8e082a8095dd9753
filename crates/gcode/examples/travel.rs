//! Pen-up travel of our ordering on a plotter drawing, for comparison with `vpype linesort`.
//!
//! Usage: `cargo run --release -p flatcut-gcode --example travel -- drawing.svg`
//! Reads the simple elements the bench generator writes (`polyline`, `polygon`, `rect`, `circle`,
//! `line`) in mm, and prints the pen-up length between consecutive paths in file order and after
//! ordering (the same measure as `vpype stat`: gaps between paths, no leg from the origin).

use flatcut_gcode::order::{OrderItem, Visit, order, visit_points};
use flatcut_geom::DVec2;

fn attr(tag: &str, name: &str) -> Option<f64> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    tag[i..j].parse().ok()
}

fn points(tag: &str) -> Vec<DVec2> {
    let i = tag.find("points=\"").map(|i| i + 8).unwrap_or(0);
    let j = tag[i..].find('"').map(|j| j + i).unwrap_or(i);
    tag[i..j]
        .split_whitespace()
        .filter_map(|pair| {
            let mut it = pair.split(',').map(|v| v.parse::<f64>());
            Some(DVec2::new(it.next()?.ok()?, it.next()?.ok()?))
        })
        .collect()
}

fn main() {
    let path = std::env::args().nth(1).expect("usage: travel drawing.svg");
    let text = std::fs::read_to_string(&path).expect("readable SVG");
    let mut paths: Vec<(Vec<DVec2>, bool)> = Vec::new();
    for tag in text.split('<').skip(1) {
        let name = tag.split_whitespace().next().unwrap_or("");
        match name {
            "polyline" => paths.push((points(tag), false)),
            "polygon" => paths.push((points(tag), true)),
            "line" => paths.push((
                vec![
                    DVec2::new(attr(tag, "x1").unwrap(), attr(tag, "y1").unwrap()),
                    DVec2::new(attr(tag, "x2").unwrap(), attr(tag, "y2").unwrap()),
                ],
                false,
            )),
            "rect" => {
                let (x, y, w, h) = (
                    attr(tag, "x").unwrap(),
                    attr(tag, "y").unwrap(),
                    attr(tag, "width").unwrap(),
                    attr(tag, "height").unwrap(),
                );
                paths.push((
                    vec![
                        DVec2::new(x, y),
                        DVec2::new(x + w, y),
                        DVec2::new(x + w, y + h),
                        DVec2::new(x, y + h),
                    ],
                    true,
                ));
            }
            "circle" => {
                let (cx, cy, r) = (
                    attr(tag, "cx").unwrap(),
                    attr(tag, "cy").unwrap(),
                    attr(tag, "r").unwrap(),
                );
                let n = 64;
                paths.push((
                    (0..n)
                        .map(|k| {
                            DVec2::new(cx, cy)
                                + DVec2::from_angle(k as f64 * std::f64::consts::TAU / n as f64) * r
                        })
                        .collect(),
                    true,
                ));
            }
            "path" => {
                // The generator writes single cubics: "M x y C x1 y1 x2 y2 x y".
                let d = tag
                    .split("d=\"")
                    .nth(1)
                    .and_then(|r| r.split('"').next())
                    .unwrap_or("");
                let v: Vec<f64> = d
                    .split_whitespace()
                    .filter_map(|t| t.parse().ok())
                    .collect();
                if v.len() == 8 {
                    let p: Vec<DVec2> = v.chunks(2).map(|c| DVec2::new(c[0], c[1])).collect();
                    let bez = |t: f64| {
                        let u = 1.0 - t;
                        p[0] * (u * u * u)
                            + p[1] * (3.0 * u * u * t)
                            + p[2] * (3.0 * u * t * t)
                            + p[3] * (t * t * t)
                    };
                    paths.push(((0..=32).map(|k| bez(k as f64 / 32.0)).collect(), false));
                }
            }
            _ => {}
        }
    }
    let items: Vec<OrderItem<'_>> = paths
        .iter()
        .map(|(p, c)| OrderItem {
            points: p,
            closed: *c,
        })
        .collect();
    let gaps = |tour: &[Visit]| -> f64 {
        let seq: Vec<Vec<DVec2>> = tour
            .iter()
            .map(|v| visit_points(&items[v.item], v))
            .collect();
        seq.windows(2)
            .map(|w| w[0].last().unwrap().distance(*w[1].first().unwrap()))
            .sum()
    };
    let file: Vec<Visit> = (0..items.len())
        .map(|i| Visit {
            item: i,
            reversed: false,
            start: 0,
        })
        .collect();
    let t0 = std::time::Instant::now();
    // Start where the file's first path starts, as vpype does (no leg from the origin is counted).
    let tour = order(&items, items[0].points[0]);
    let dt = t0.elapsed();
    println!("paths: {}", items.len());
    println!("flatcut file order: {:.0} mm", gaps(&file));
    println!(
        "flatcut ordered:    {:.0} mm ({:.1} ms)",
        gaps(&tour),
        dt.as_secs_f64() * 1e3
    );
}
