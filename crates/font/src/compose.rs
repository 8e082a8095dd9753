//! Text to shapes: each character decomposed canonically (an accented letter is a base letter
//! and combining marks), stand-ins for the letters and signs Hershey did not draw, and the
//! missing-glyph box for the rest.

use crate::hershey::{self, CAP_HEIGHT, Glyph};
use crate::marks;
use flatcut_geom::DVec2;
use unicode_normalization::char::{decompose_canonical, is_combining_mark};

/// One written character in font units: x from the pen position, y up from the baseline.
#[derive(Clone, Debug)]
pub struct Shape {
    pub advance: f64,
    pub strokes: Vec<Vec<DVec2>>,
    /// Drawn (wholly or partly) as the missing-glyph box.
    pub missing: bool,
}

/// The shapes writing `text`, one per base character with its marks.
pub fn shapes(text: &str) -> Vec<Shape> {
    let mut out = Vec::new();
    let mut cluster: Option<(char, Vec<char>)> = None;
    for c in expand(text) {
        if is_combining_mark(c) {
            // a mark with nothing before it sits on a space
            cluster.get_or_insert((' ', Vec::new())).1.push(c);
            continue;
        }
        if let Some((base, m)) = cluster.replace((c, Vec::new())) {
            out.push(shape(base, &m));
        }
    }
    if let Some((base, m)) = cluster {
        out.push(shape(base, &m));
    }
    out
}

/// The characters of `text` with stand-ins substituted and every character without a glyph of
/// its own decomposed canonically (≠ has one, though it decomposes to = and a stroke).
fn expand(text: &str) -> Vec<char> {
    let mut out = Vec::with_capacity(text.len());
    for c in text.chars() {
        if hershey::slot_of(c).is_some() {
            out.push(c);
        } else if let Some(s) = stand_in(c) {
            out.extend(s.chars());
        } else {
            decompose_canonical(c, |d| out.push(d));
        }
    }
    out
}

/// Letters and signs written as other text: ligatures and ß as their letters, typographic
/// quotes, dashes, ellipses and spaces as their ASCII forms.
fn stand_in(c: char) -> Option<&'static str> {
    Some(match c {
        'ß' => "ss",
        'ẞ' => "SS",
        'æ' => "ae",
        'Æ' => "AE",
        'œ' => "oe",
        'Œ' => "OE",
        '\u{2018}' | '\u{2019}' | '\u{201a}' | '\u{201b}' | '\u{2032}' => "'",
        '\u{201c}' | '\u{201d}' | '\u{201e}' | '\u{2033}' => "\"",
        '\u{2039}' => "<",
        '\u{203a}' => ">",
        '«' => "<<",
        '»' => ">>",
        '\u{2010}'..='\u{2015}' => "-",
        '\u{2026}' => "...",
        '\u{a0}' | '\u{2000}'..='\u{200a}' | '\u{202f}' | '\t' => " ",
        '©' => "(C)",
        '®' => "(R)",
        '™' => "TM",
        _ => return None,
    })
}

/// Superscript digits: drawn as digits at this fraction of the size, raised.
const SUPERSCRIPT_SCALE: f64 = 0.6;
/// How far a superscript's baseline is raised, in cap heights.
const SUPERSCRIPT_RISE: f64 = 0.45;

/// The shape of one base character with its combining marks.
fn shape(base: char, mark_chars: &[char]) -> Shape {
    let (mut g, mut missing) = base_glyph(base);
    let known = marks::place(mark_chars, base, &mut g);
    missing |= !known;
    Shape {
        advance: g.advance,
        strokes: g.strokes,
        missing,
    }
}

/// The glyph of a base character (a Hershey glyph, a letter with a bar or stroke through it, a
/// superscript digit) and whether it is the missing-glyph box instead.
fn base_glyph(c: char) -> (Glyph, bool) {
    if let Some(g) = hershey_glyph(c) {
        return (g.clone(), false);
    }
    if let Some(g) = marks::barred(c) {
        return (g, false);
    }
    if let Some(g) = superscript(c).and_then(hershey_glyph) {
        return (raised(g), false);
    }
    (missing_box(), true)
}

/// The Hershey glyph that draws `c`, if one does.
fn hershey_glyph(c: char) -> Option<&'static Glyph> {
    hershey::slot_of(c).and_then(|(face, slot)| hershey::glyph(face, slot))
}

/// The digit a superscript digit stands for.
fn superscript(c: char) -> Option<char> {
    match c {
        '¹' => Some('1'),
        '²' => Some('2'),
        '³' => Some('3'),
        '⁰' => Some('0'),
        '\u{2074}'..='\u{2079}' => char::from_digit(c as u32 - 0x2070, 10),
        _ => None,
    }
}

/// A glyph at superscript size and height.
fn raised(g: &Glyph) -> Glyph {
    let rise = SUPERSCRIPT_RISE * CAP_HEIGHT;
    Glyph {
        advance: g.advance * SUPERSCRIPT_SCALE,
        strokes: g
            .strokes
            .iter()
            .map(|s| {
                s.iter()
                    .map(|p| DVec2::new(p.x, p.y) * SUPERSCRIPT_SCALE + DVec2::Y * rise)
                    .collect()
            })
            .collect(),
    }
}

/// The missing-glyph box: an empty rectangle of cap height, as wide as a capital.
fn missing_box() -> Glyph {
    let (x0, x1, top) = (3.0, 15.0, CAP_HEIGHT);
    Glyph {
        advance: 18.0,
        strokes: vec![vec![
            DVec2::new(x0, 0.0),
            DVec2::new(x1, 0.0),
            DVec2::new(x1, top),
            DVec2::new(x0, top),
            DVec2::new(x0, 0.0),
        ]],
    }
}
