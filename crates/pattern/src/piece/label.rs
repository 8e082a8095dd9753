//! The label of a piece: its text lines, and where and how large they are written: upright, in
//! the largest free room inside the sew line, clear of the grain line and every mark.

use super::Piece;
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
        if !l.size.is_empty() {
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

    /// The label's strokes: the text block written upright (along +x), centred in the largest
    /// room inside the sew line that the grain line, notches, drill holes, points and internal
    /// lines leave, at the given cap height or smaller where the room is smaller.
    pub(super) fn layout_label(&self, max_height: f64) -> Vec<Vec<DVec2>> {
        let block = text_block(&self.label_lines());
        let Some((lo, hi)) = extent(&block) else {
            return Vec::new();
        };
        let half = (hi - lo) * 0.5 + DVec2::splat(MARGIN);
        let Some((at, room)) = room::largest_box(&self.sew_polyline, &self.label_obstacles(), half)
        else {
            return Vec::new();
        };
        let h = max_height.min(room);
        let centre = (lo + hi) * 0.5;
        block
            .into_iter()
            .map(|s| s.into_iter().map(|p| at + (p - centre) * h).collect())
            .collect()
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
