//! A compact built-in single-stroke font (Hershey-like, on a 4×6 grid) so pen plotters, knives
//! with a pen tool and lasers can write labels as vector strokes, with no font file and no
//! outline text. Covers A–Z (lowercase maps to capitals), 0–9 and common punctuation.

use flatcut_geom::DVec2;

/// Cap height of the grid, in grid units.
const GRID_H: f64 = 6.0;
/// Advance per character in grid units (4 wide + 2 gap).
const ADVANCE: f64 = 6.0;
/// Line spacing as a multiple of the text height.
pub const LINE_SPACING: f64 = 1.6;

/// Strokes of a glyph: groups separated by `;`, points as two digits `xy` on the grid.
fn glyph(c: char) -> &'static str {
    match c.to_ascii_uppercase() {
        'A' => "00 04 26 44 40;03 43",
        'B' => "00 06 36 45 44 33 03;33 42 41 30 00",
        'C' => "45 36 16 05 01 10 30 41",
        'D' => "00 06 26 44 42 20 00",
        'E' => "40 00 06 46;03 33",
        'F' => "00 06 46;03 33",
        'G' => "45 36 16 05 01 10 30 41 43 23",
        'H' => "00 06;40 46;03 43",
        'I' => "10 30;20 26;16 36",
        'J' => "46 41 30 10 01",
        'K' => "00 06;46 02;13 40",
        'L' => "06 00 40",
        'M' => "00 06 23 46 40",
        'N' => "00 06 40 46",
        'O' => "10 01 05 16 36 45 41 30 10",
        'P' => "00 06 36 45 44 33 03",
        'Q' => "10 01 05 16 36 45 41 30 10;22 40",
        'R' => "00 06 36 45 44 33 03;23 40",
        'S' => "45 36 16 05 04 13 33 42 41 30 10 01",
        'T' => "06 46;26 20",
        'U' => "06 01 10 30 41 46",
        'V' => "06 20 46",
        'W' => "06 10 23 30 46",
        'X' => "00 46;06 40",
        'Y' => "06 23 46;23 20",
        'Z' => "06 46 00 40",
        '0' => "10 01 05 16 36 45 41 30 10;41 05",
        '1' => "14 26 20;10 30",
        '2' => "05 16 36 45 44 00 40",
        '3' => "05 16 36 45 44 33 13;33 42 41 30 10 01",
        '4' => "36 02 42;34 30",
        '5' => "46 06 04 34 43 41 30 10 01",
        '6' => "45 36 16 05 01 10 30 41 42 33 13 02",
        '7' => "06 46 20",
        '8' => "13 04 05 16 36 45 44 33 13 02 01 10 30 41 42 33",
        '9' => "01 10 30 41 45 36 16 05 04 13 33 44",
        '-' => "03 43",
        '_' => "00 40",
        '.' => "20 21",
        ',' => "21 10",
        ':' => "21 20;24 25",
        ';' => "24 25;21 10",
        '/' => "00 46",
        '(' => "36 24 22 30",
        ')' => "16 24 22 10",
        '+' => "03 43;21 25",
        '=' => "02 42;04 44",
        '%' => "00 46;06 15;31 40",
        '\'' => "26 24",
        '"' => "16 14;36 34",
        '!' => "26 22;21 20",
        '*' => "13 35;15 33;03 43",
        '#' => "10 16;30 36;02 42;04 44",
        '<' => "45 03 41",
        '>' => "05 43 01",
        '°' => "25 26 36 35 25",
        ' ' => "",
        _ => "05 16 36 45 44 23 22;21 20",
    }
}

/// Strokes (open polylines, mm) writing `text` with its baseline starting at `origin`, cap
/// height `height` mm, along the unit direction `dir` (up is `dir` turned left).
pub fn text_strokes(text: &str, origin: DVec2, height: f64, dir: DVec2) -> Vec<Vec<DVec2>> {
    let s = height / GRID_H;
    let up = DVec2::new(-dir.y, dir.x);
    let mut out = Vec::new();
    for (k, c) in text.chars().enumerate() {
        let x0 = k as f64 * ADVANCE;
        for stroke in glyph(c).split(';').filter(|g| !g.is_empty()) {
            let pts: Vec<DVec2> = stroke
                .split(' ')
                .filter_map(|xy| {
                    let mut ch = xy.chars();
                    let x = ch.next()?.to_digit(10)? as f64;
                    let y = ch.next()?.to_digit(10)? as f64;
                    Some(origin + dir * ((x0 + x) * s) + up * (y * s))
                })
                .collect();
            if pts.len() >= 2 {
                out.push(pts);
            }
        }
    }
    out
}

/// Width in mm of `text` written at cap height `height` (without the trailing gap).
pub fn text_width(text: &str, height: f64) -> f64 {
    let n = text.chars().count() as f64;
    if n == 0.0 {
        0.0
    } else {
        (n * ADVANCE - 2.0) * height / GRID_H
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_parses_and_stays_in_its_cell() {
        let all = "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.,:;/()+=%'\"!*#<>°?";
        for c in all.chars() {
            let st = text_strokes(&c.to_string(), DVec2::ZERO, 6.0, DVec2::X);
            assert!(!st.is_empty(), "glyph {c} has no strokes");
            for p in st.iter().flatten() {
                assert!(
                    (0.0..=4.0).contains(&p.x) && (0.0..=6.0).contains(&p.y),
                    "{c}: {p}"
                );
            }
        }
    }

    #[test]
    fn width_and_direction() {
        assert!((text_width("AB", 6.0) - 10.0).abs() < 1e-12);
        let st = text_strokes("I", DVec2::new(10., 0.), 6.0, DVec2::Y);
        // written upward: x decreases with the glyph's height
        assert!(
            st.iter()
                .flatten()
                .all(|p| p.x <= 10.0 + 1e-12 && p.y >= 0.0)
        );
    }
}
