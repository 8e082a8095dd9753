//! The single-stroke font that labels and heat maps are written in, so pen plotters, knives with
//! a pen tool and lasers write every label as vector strokes, with no font file and no outline
//! text. It is one fact in one place: the pattern crate's labels and the report's heat maps both
//! draw with it.
//!
//! The glyphs are Dr. A. V. Hershey's (Roman simplex for ASCII, Greek simplex, the mathematical
//! symbols: `data/README.md` gives their source and use terms). Accented Latin letters are their
//! canonical decomposition (a base letter and combining marks) with the marks drawn over or under
//! the base (`marks`); ß, æ, œ, ø, ł, đ and the typographic quotes and dashes have stand-ins. A
//! character with no glyph is drawn as an empty box, never as another character.
//!
//! Coordinates are millimetres in the caller's frame: text runs along a unit direction from an
//! origin on its baseline, with a given cap height. No IO.
#![warn(missing_docs)]

mod compose;
mod hershey;
mod marks;

use flatcut_geom::DVec2;

/// Line spacing (baseline to baseline) as a multiple of the cap height.
pub const LINE_SPACING: f64 = 1.6;

/// Strokes (open polylines, mm) writing `text` with its baseline starting at `origin`, cap
/// height `height` mm, along the unit direction `dir` (up is `dir` turned left).
pub fn text_strokes(text: &str, origin: DVec2, height: f64, dir: DVec2) -> Vec<Vec<DVec2>> {
    let s = height / hershey::CAP_HEIGHT;
    let up = DVec2::new(-dir.y, dir.x);
    let mut out = Vec::new();
    let mut pen = 0.0;
    for shape in compose::shapes(text) {
        for stroke in &shape.strokes {
            out.push(
                stroke
                    .iter()
                    .map(|p| origin + dir * ((pen + p.x) * s) + up * (p.y * s))
                    .collect(),
            );
        }
        pen += shape.advance;
    }
    out
}

/// Advance width in mm of `text` written at cap height `height` (the glyphs' side bearings
/// included).
pub fn text_width(text: &str, height: f64) -> f64 {
    let units: f64 = compose::shapes(text).iter().map(|s| s.advance).sum();
    units * height / hershey::CAP_HEIGHT
}

/// Whether `c` is drawn by a glyph of its own (or a composition or stand-in), not by the
/// missing-glyph box.
pub fn has_glyph(c: char) -> bool {
    compose::shapes(&c.to_string()).iter().all(|s| !s.missing)
}

#[cfg(test)]
mod tests;
