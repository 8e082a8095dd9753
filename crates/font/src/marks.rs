//! Diacritical marks drawn over or under a base glyph (the combining marks of a canonical
//! decomposition: é is e and U+0301), and the letters written as a base glyph with a bar or a
//! stroke through it (ø, ł, đ). The strokes are the project's own, in Hershey font units (cap
//! height 21), sized to the Roman simplex.

use crate::hershey::{self, CAP_HEIGHT, Face, Glyph, X_HEIGHT};
use flatcut_geom::DVec2;

/// Gap between a glyph's top and the first mark above it, and between stacked marks.
const GAP: f64 = 2.0;
/// Radius of a dot (as the Roman simplex's full stop).
const DOT: f64 = 1.0;

/// Draws `marks` on the glyph `g` of `base`: marks above stack upward from the glyph's top, marks
/// below hang from its baseline. Returns false when a mark has no drawing (it is drawn as a small
/// box above, so the loss is visible).
pub fn place(marks: &[char], base: char, g: &mut Glyph) -> bool {
    if marks.is_empty() {
        return true;
    }
    if matches!(base, 'i' | 'j') && marks.iter().any(|m| above(*m).is_some()) {
        // the dot gives way to the accent (í, not i with a dot and an accent)
        g.strokes
            .retain(|s| s.iter().any(|p| p.y <= X_HEIGHT + 0.5));
    }
    let b = Bounds::of(g);
    let mut y = b.top + GAP;
    let mut known = true;
    for &m in marks {
        let (strokes, at) = if let Some((s, h)) = above(m) {
            let at = DVec2::new(b.centre, y);
            y += h + GAP;
            (s, at)
        } else if let Some(s) = below(m) {
            let x = if m == '\u{328}' {
                b.right - 2.0
            } else {
                b.centre
            };
            (s, DVec2::new(x, 0.0))
        } else {
            known = false;
            let at = DVec2::new(b.centre, y);
            y += 4.0 + GAP;
            (vec![square(DVec2::new(0.0, 2.0), 2.0)], at)
        };
        g.strokes.extend(
            strokes
                .into_iter()
                .map(|s| s.into_iter().map(|p| p + at).collect()),
        );
    }
    known
}

/// Where a glyph's strokes lie, in font units.
struct Bounds {
    centre: f64,
    right: f64,
    top: f64,
}

impl Bounds {
    fn of(g: &Glyph) -> Bounds {
        let pts = || g.strokes.iter().flatten();
        if pts().next().is_none() {
            return Bounds {
                centre: g.advance * 0.5,
                right: g.advance * 0.75,
                top: X_HEIGHT,
            };
        }
        let lo = pts().map(|p| p.x).fold(f64::INFINITY, f64::min);
        let hi = pts().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
        let top = pts().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
        Bounds {
            centre: 0.5 * (lo + hi),
            right: hi,
            top,
        }
    }
}

fn pts(v: &[(f64, f64)]) -> Vec<DVec2> {
    v.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
}

/// A dot (a small diamond, as Hershey draws them) centred at `c`.
fn dot(c: DVec2) -> Vec<DVec2> {
    [
        (0.0, -DOT),
        (-DOT, 0.0),
        (0.0, DOT),
        (DOT, 0.0),
        (0.0, -DOT),
    ]
    .iter()
    .map(|&(x, y)| c + DVec2::new(x, y))
    .collect()
}

/// A closed square of half-size `r` about `c`.
fn square(c: DVec2, r: f64) -> Vec<DVec2> {
    [(-r, -r), (r, -r), (r, r), (-r, r), (-r, -r)]
        .iter()
        .map(|&(x, y)| c + DVec2::new(x, y))
        .collect()
}

/// Points of `f(t)` for t in [0, 1], `n` + 1 of them.
fn curve(n: usize, f: impl Fn(f64) -> (f64, f64)) -> Vec<DVec2> {
    (0..=n)
        .map(|k| {
            let (x, y) = f(k as f64 / n as f64);
            DVec2::new(x, y)
        })
        .collect()
}

/// A mark above the letter: its strokes (x about 0, y from 0 up) and its height.
fn above(m: char) -> Option<(Vec<Vec<DVec2>>, f64)> {
    use std::f64::consts::PI;
    Some(match m {
        '\u{300}' => (vec![pts(&[(1.5, 0.0), (-1.5, 4.0)])], 4.0), // grave
        '\u{301}' => (vec![pts(&[(-1.5, 0.0), (1.5, 4.0)])], 4.0), // acute
        '\u{302}' => (vec![pts(&[(-3.0, 0.0), (0.0, 3.0), (3.0, 0.0)])], 3.0), // circumflex
        '\u{303}' => (
            // tilde: one period of a sine, rising at the left
            vec![curve(12, |t| {
                let x = -4.0 + 8.0 * t;
                (x, 1.25 - 1.25 * (PI * x / 4.0).sin())
            })],
            2.5,
        ),
        '\u{304}' => (vec![pts(&[(-4.0, 0.5), (4.0, 0.5)])], 1.0), // macron
        '\u{306}' => (
            // breve: the lower half of an ellipse
            vec![curve(8, |t| {
                let a = PI + PI * t;
                (3.0 * a.cos(), 2.5 + 2.5 * a.sin())
            })],
            2.5,
        ),
        '\u{307}' => (vec![dot(DVec2::new(0.0, DOT))], 2.0 * DOT), // dot above
        '\u{308}' => (
            // diaeresis
            vec![dot(DVec2::new(-2.5, DOT)), dot(DVec2::new(2.5, DOT))],
            2.0 * DOT,
        ),
        '\u{30a}' => (
            // ring
            vec![curve(12, |t| {
                let a = 2.0 * PI * t;
                (1.8 * a.sin(), 1.8 - 1.8 * a.cos())
            })],
            3.6,
        ),
        '\u{30b}' => (
            // double acute
            vec![
                pts(&[(-3.0, 0.0), (-1.0, 4.0)]),
                pts(&[(1.0, 0.0), (3.0, 4.0)]),
            ],
            4.0,
        ),
        '\u{30c}' => (vec![pts(&[(-3.0, 3.0), (0.0, 0.0), (3.0, 3.0)])], 3.0), // caron
        _ => return None,
    })
}

/// A mark below the letter: its strokes about (anchor, baseline), y down from 0.
fn below(m: char) -> Option<Vec<Vec<DVec2>>> {
    Some(match m {
        '\u{327}' => vec![pts(&[
            // cedilla
            (0.0, 0.0),
            (0.0, -2.0),
            (1.5, -2.5),
            (1.5, -4.0),
            (0.0, -4.5),
            (-1.5, -4.2),
        ])],
        '\u{328}' => vec![pts(&[(0.0, 0.0), (-2.0, -2.0), (-1.5, -4.0), (0.5, -4.5)])], // ogonek
        '\u{323}' => vec![dot(DVec2::new(0.0, -3.0))],                                  // dot below
        '\u{326}' => vec![pts(&[(0.3, -2.0), (0.0, -3.5), (-1.0, -5.0)])], // comma below
        '\u{331}' => vec![pts(&[(-4.0, -3.0), (4.0, -3.0)])],              // macron below
        _ => return None,
    })
}

/// Letters drawn as a Roman glyph with a stroke through it: ø, Ø and the diameter sign ⌀ (an o
/// struck through), ł and Ł (a slanted bar across the stem), đ and Đ (a bar across the stem),
/// dotless ı and ȷ.
pub fn barred(c: char) -> Option<Glyph> {
    let (base, bar): (char, fn(&Bounds, f64) -> Vec<DVec2>) = match c {
        'ø' | '⌀' => ('o', |b, _| slash(b, X_HEIGHT)),
        'Ø' => ('O', |b, _| slash(b, CAP_HEIGHT)),
        'ł' | 'Ł' => (if c == 'ł' { 'l' } else { 'L' }, |_, stem| {
            pts(&[(stem - 3.5, 7.0), (stem + 3.5, 12.0)])
        }),
        'đ' => ('d', |b, _| {
            pts(&[(b.right - 5.0, 17.0), (b.right + 2.0, 17.0)])
        }),
        'Đ' => ('D', |_, stem| {
            pts(&[(stem - 2.5, 10.5), (stem + 5.0, 10.5)])
        }),
        'ı' | 'ȷ' => {
            let mut g = hershey::glyph(Face::Roman, if c == 'ı' { 'i' } else { 'j' })?.clone();
            g.strokes
                .retain(|s| s.iter().any(|p| p.y <= X_HEIGHT + 0.5));
            return Some(g);
        }
        _ => return None,
    };
    let mut g = hershey::glyph(Face::Roman, base)?.clone();
    let b = Bounds::of(&g);
    let stem = g
        .strokes
        .iter()
        .flatten()
        .map(|p| p.x)
        .fold(f64::INFINITY, f64::min);
    g.strokes.push(bar(&b, stem));
    Some(g)
}

/// A stroke from below the glyph's left to above its right, through a letter `height` tall.
fn slash(b: &Bounds, height: f64) -> Vec<DVec2> {
    let half = b.right - b.centre;
    pts(&[(b.centre - half - 1.0, -1.0), (b.right + 1.0, height + 1.0)])
}
