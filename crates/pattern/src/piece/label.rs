//! The label of a piece: its text lines, and where and how large they are written: upright, in
//! the largest free room inside the sew line, clear of the grain line and every mark, never
//! below a cutter's readable cap height while a shorter label or the piece's short code fits.

use super::{MIN_LABEL_HEIGHT, Piece};
use crate::drawing::StrokeKind;
use crate::room;
use flatcut_font as font;
use flatcut_geom::DVec2;

/// Clear space kept round the label's text, in cap heights.
const MARGIN: f64 = 0.5;

impl Piece {
    /// Text lines of the label.
    pub fn label_lines(&self) -> Vec<String> {
        let l = &self.label;
        let mut v = vec![if l.name.is_empty() {
            self.name.clone()
        } else {
            l.name.clone()
        }];
        if !self.name_says_size() {
            v.push(format!("SIZE {}", l.size));
        }
        if !l.material.is_empty() {
            v.push(l.material.clone());
        }
        if l.quantity > 0 {
            v.push(format!("CUT {}", l.quantity));
        }
        if let Some(d) = &l.distortion {
            v.push(d.clone());
        }
        v
    }

    /// Lays the label out ([`Piece::label_strokes`], [`Piece::label_text`],
    /// [`Piece::label_height`]): the whole label where the piece holds it at
    /// [`MIN_LABEL_HEIGHT`] or more, else its first lines (the name, which carries the size and
    /// the side of a pair, comes first), else the piece's short code ([`Piece::label_code`]);
    /// where even the code does not fit at that height it is written as large as the piece
    /// allows. A cutter reads a label from 3 mm.
    pub(super) fn lay_out_label(&mut self, max_height: f64) {
        let lines = self.label_lines();
        let keep = self.label_lines_kept();
        let mut tries: Vec<Vec<String>> = (keep..=lines.len())
            .rev()
            .map(|k| lines[..k].to_vec())
            .collect();
        tries.push(vec![self.label_code()]);
        let obstacles = self.label_obstacles();
        let mut best: Option<(Vec<Vec<DVec2>>, Vec<String>, f64)> = None;
        for t in tries {
            let Some((strokes, h)) = self.layout_lines(&t, &obstacles, max_height) else {
                continue;
            };
            if h >= MIN_LABEL_HEIGHT.min(max_height) - 1e-9 {
                best = Some((strokes, t, h));
                break;
            }
            if best.as_ref().is_none_or(|b| h > b.2) {
                best = Some((strokes, t, h));
            }
        }
        if let Some((strokes, text, h)) = best {
            self.label_strokes = strokes;
            self.label_text = text;
            self.label_height = h;
        }
    }

    /// How many of the label's first lines name the piece: its name, and its size when the
    /// name does not say it.
    fn label_lines_kept(&self) -> usize {
        if self.name_says_size() { 1 } else { 2 }
    }

    /// Whether the label's first line already says the piece's size (a graded piece's name
    /// `toe cap 42 L`), or it has none.
    fn name_says_size(&self) -> bool {
        let l = &self.label;
        let name = if l.name.is_empty() {
            &self.name
        } else {
            &l.name
        };
        l.size.is_empty() || name.split_whitespace().any(|w| w == l.size)
    }

    /// The piece's short code: the label's own, else the initials of its name's words with
    /// numbers and one-letter words (a size, L or R) kept whole (`toe cap 42 L` → `TC42L`).
    pub fn label_code(&self) -> String {
        if let Some(c) = self.label.code.as_ref().filter(|c| !c.is_empty()) {
            return c.clone();
        }
        short_code(if self.label.name.is_empty() {
            &self.name
        } else {
            &self.label.name
        })
    }

    /// The strokes of `lines` written upright (along +x), centred in the largest room inside
    /// the sew line that the grain line, notches, drill holes, points and internal lines leave,
    /// at the given cap height or smaller where the room is smaller; and that cap height.
    fn layout_lines(
        &self,
        lines: &[String],
        obstacles: &[Vec<DVec2>],
        max_height: f64,
    ) -> Option<(Vec<Vec<DVec2>>, f64)> {
        let block = text_block(lines);
        let (lo, hi) = extent(&block)?;
        let half = (hi - lo) * 0.5 + DVec2::splat(MARGIN);
        let (at, room) = room::largest_box(&self.sew_polyline, obstacles, half)?;
        let h = max_height.min(room);
        let centre = (lo + hi) * 0.5;
        Some((
            block
                .into_iter()
                .map(|s| s.into_iter().map(|p| at + (p - centre) * h).collect())
                .collect(),
            h,
        ))
    }

    /// What a label must not cover: every drawn or cut stroke but the cut line, the closed sew
    /// line (the room's wall) and the label itself; a dart's legs (open sew lines) are covered.
    fn label_obstacles(&self) -> Vec<Vec<DVec2>> {
        self.to_drawing(0)
            .strokes
            .into_iter()
            .filter(|s| {
                !(matches!(s.kind, StrokeKind::Boundary | StrokeKind::Text)
                    || (s.kind == StrokeKind::Sew && s.closed))
            })
            .map(|s| {
                let mut p = s.points;
                if s.closed && !p.is_empty() {
                    p.push(p[0]);
                }
                p
            })
            .collect()
    }
}

/// A short code for a piece name: the initials of its words, upper case, with numbers and
/// one-letter words kept whole.
pub fn short_code(name: &str) -> String {
    name.split_whitespace()
        .map(|w| {
            if w.chars().count() == 1 || w.chars().all(|c| c.is_ascii_digit() || c == '.') {
                w.to_uppercase()
            } else {
                w.chars()
                    .next()
                    .map(|c| c.to_uppercase().to_string())
                    .unwrap_or_default()
            }
        })
        .collect()
}

/// The label's lines at cap height 1, each centred on x = 0, baselines `LINE_SPACING` apart
/// going down from y = 0.
fn text_block(lines: &[String]) -> Vec<Vec<DVec2>> {
    let mut out = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let w = font::text_width(line, 1.0);
        let origin = DVec2::new(-0.5 * w, -(k as f64) * font::LINE_SPACING);
        out.extend(font::text_strokes(line, origin, 1.0, DVec2::X));
    }
    out
}

/// The bounding box of strokes, if they have any point.
fn extent(strokes: &[Vec<DVec2>]) -> Option<(DVec2, DVec2)> {
    let mut pts = strokes.iter().flatten();
    let first = *pts.next()?;
    Some(pts.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
}
