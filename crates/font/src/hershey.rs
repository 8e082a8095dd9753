//! The Hershey glyphs: the three fonts in James Hurt's format (`data/*.jhf`), decoded once, and
//! which glyph draws which character.
//!
//! Decoded here rather than with the `hershey` crate: that parser reads a glyph's spacing pair
//! as a point (so its bounds mix the advance into the outline), drops the advance, and indexes
//! below its first character with an unchecked subtraction; the format is two characters per
//! point and takes a few lines.

use flatcut_geom::DVec2;
use std::sync::OnceLock;

/// Cap height in font units (Roman simplex: capitals from y = −12 to the baseline at 9).
pub const CAP_HEIGHT: f64 = 21.0;
/// Top of the lowercase letters above the baseline, in font units.
pub const X_HEIGHT: f64 = 11.0;
/// The baseline in the files' y-down units.
const BASELINE: i32 = 9;

/// A glyph in font units: x from the pen position (the left side bearing included), y up from
/// the baseline.
#[derive(Clone, Debug, Default)]
pub struct Glyph {
    pub advance: f64,
    pub strokes: Vec<Vec<DVec2>>,
}

/// The fonts that are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Face {
    Roman,
    Math,
    Greek,
}

const SOURCES: [&str; 3] = [
    include_str!("../data/futural.jhf"),
    include_str!("../data/mathlow.jhf"),
    include_str!("../data/greek.jhf"),
];

/// The glyphs of a face, indexed by their ASCII slot (the files hold slots 32 to 127 in order).
fn face(f: Face) -> &'static [Glyph] {
    static FACES: OnceLock<[Vec<Glyph>; 3]> = OnceLock::new();
    let faces = FACES.get_or_init(|| SOURCES.map(decode_file));
    &faces[f as usize]
}

/// The glyph in `slot` (an ASCII character) of a face.
pub fn glyph(f: Face, slot: char) -> Option<&'static Glyph> {
    (slot as usize)
        .checked_sub(' ' as usize)
        .and_then(|i| face(f).get(i))
}

/// Every glyph of a file, one per line; a line that does not decode is an empty glyph (the
/// tests check that none is).
fn decode_file(src: &str) -> Vec<Glyph> {
    src.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| decode(l).unwrap_or_default())
        .collect()
}

/// One glyph line: a five-character number, a three-character count of pairs, then the pairs,
/// each two characters offset from `R`: first the left and right side bearings, then points,
/// with ` R` lifting the pen.
pub fn decode(line: &str) -> Option<Glyph> {
    let count: usize = line.get(5..8)?.trim().parse().ok()?;
    let body = line.get(8..)?.as_bytes();
    if body.len() != 2 * count || count == 0 {
        return None;
    }
    let v = |b: u8| b as i32 - b'R' as i32;
    let (left, right) = (v(body[0]), v(body[1]));
    let mut strokes: Vec<Vec<DVec2>> = vec![Vec::new()];
    for pair in body[2..].chunks_exact(2) {
        if pair == b" R" {
            strokes.push(Vec::new());
            continue;
        }
        let p = DVec2::new((v(pair[0]) - left) as f64, (BASELINE - v(pair[1])) as f64);
        strokes.last_mut()?.push(p);
    }
    strokes.retain(|s| !s.is_empty());
    Some(Glyph {
        advance: (right - left) as f64,
        strokes,
    })
}

/// The face and slot of the Hershey glyph that draws `c`, if one does.
pub fn slot_of(c: char) -> Option<(Face, char)> {
    if (' '..='~').contains(&c) {
        return Some((Face::Roman, c));
    }
    if let Some(&(_, s)) = MATH.iter().find(|(m, _)| *m == c) {
        return Some((Face::Math, s));
    }
    GREEK
        .iter()
        .find(|(g, _)| *g == c)
        .map(|&(_, s)| (Face::Greek, s))
}

/// Mathematical and typographic symbols in the math face.
const MATH: [(char, char); 22] = [
    ('±', '!'),
    ('∓', '"'),
    ('×', '#'),
    ('·', '$'),
    ('•', '$'),
    ('≤', '&'),
    ('≥', '\''),
    ('−', '-'),
    ('∏', ':'),
    ('∑', ';'),
    ('≠', '?'),
    ('≡', '@'),
    ('∝', '^'),
    ('∞', '_'),
    ('°', '`'),
    ('√', 'b'),
    ('→', 'i'),
    ('↑', 'j'),
    ('←', 'k'),
    ('↓', 'l'),
    ('∂', 'm'),
    ('÷', 'x'),
];

/// Greek letters in the Greek face (whose slots follow the classic Symbol-font layout).
const GREEK: [(char, char); 51] = [
    ('Α', 'A'),
    ('Β', 'B'),
    ('Γ', 'G'),
    ('Δ', 'D'),
    ('Ε', 'E'),
    ('Ζ', 'Z'),
    ('Η', 'H'),
    ('Θ', 'Q'),
    ('Ι', 'I'),
    ('Κ', 'K'),
    ('Λ', 'L'),
    ('Μ', 'M'),
    ('Ν', 'N'),
    ('Ξ', 'X'),
    ('Ο', 'O'),
    ('Π', 'P'),
    ('Ρ', 'R'),
    ('Σ', 'S'),
    ('Τ', 'T'),
    ('Υ', 'U'),
    ('Φ', 'F'),
    ('Χ', 'C'),
    ('Ψ', 'Y'),
    ('Ω', 'W'),
    ('α', 'a'),
    ('β', 'b'),
    ('γ', 'g'),
    ('δ', 'd'),
    ('ε', 'e'),
    ('ζ', 'z'),
    ('η', 'h'),
    ('θ', 'q'),
    ('ϑ', 'q'),
    ('ι', 'i'),
    ('κ', 'k'),
    ('λ', 'l'),
    ('μ', 'm'),
    ('µ', 'm'),
    ('ν', 'n'),
    ('ξ', 'x'),
    ('ο', 'o'),
    ('π', 'p'),
    ('ρ', 'r'),
    ('σ', 's'),
    ('ς', 's'),
    ('τ', 't'),
    ('υ', 'u'),
    ('φ', 'f'),
    ('χ', 'c'),
    ('ψ', 'y'),
    ('ω', 'w'),
];
