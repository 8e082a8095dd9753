//! The label of a piece: its text lines, and where and how large they are written.

use super::Piece;
use crate::poly;
use flatcut_font as font;
use flatcut_geom::{Aabb2, DVec2};

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

    /// Places the label at the most interior point of the sew polygon, along the grain line
    /// when there is one, shrinking the text until the block fits the inscribed circle.
    pub(super) fn layout_label(&self, max_height: f64) -> Vec<Vec<DVec2>> {
        let lines = self.label_lines();
        let Some((best, best_d)) = pole(&self.sew_polyline) else {
            return Vec::new();
        };
        let dir = self
            .grain
            .map(|(a, b)| (b - a).normalize())
            .unwrap_or(DVec2::X);
        // block of width W = max chars, height H = lines × spacing at cap height h
        let widest = lines
            .iter()
            .map(|l| font::text_width(l, 1.0))
            .fold(0.0, f64::max);
        let rows = lines.len() as f64;
        let block = |h: f64| DVec2::new(widest * h, (rows - 1.0) * font::LINE_SPACING * h + h);
        let unit = block(1.0);
        let h = max_height.min(2.0 * best_d / unit.length());
        let size = block(h);
        let up = DVec2::new(-dir.y, dir.x);
        let mut out = Vec::new();
        for (k, line) in lines.iter().enumerate() {
            let w = font::text_width(line, h);
            let y = size.y * 0.5 - h - k as f64 * font::LINE_SPACING * h;
            let origin = best + dir * (-w * 0.5) + up * y;
            out.extend(font::text_strokes(line, origin, h, dir));
        }
        out
    }
}

/// The pole of inaccessibility of a polygon (the inside point farthest from its edges) and that
/// distance, by a grid search refined twice; `None` when no grid point is inside.
fn pole(poly: &[DVec2]) -> Option<(DVec2, f64)> {
    let bb = Aabb2::from_points(poly.iter().copied());
    let mut best = (bb.min + bb.max) * 0.5;
    let mut best_d = -1.0;
    let mut span = bb.max - bb.min;
    let mut center = best;
    const GRID: usize = 24;
    for _ in 0..3 {
        for i in 0..=GRID {
            for j in 0..=GRID {
                let q = center - span * 0.5
                    + DVec2::new(
                        span.x * i as f64 / GRID as f64,
                        span.y * j as f64 / GRID as f64,
                    );
                if !poly::contains(poly, q) {
                    continue;
                }
                let d = poly::dist_to_closed(poly, q);
                if d > best_d {
                    best_d = d;
                    best = q;
                }
            }
        }
        center = best;
        span *= 2.0 / GRID as f64 * 2.0;
    }
    (best_d > 0.0).then_some((best, best_d))
}
