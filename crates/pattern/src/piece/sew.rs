//! The sew line: the cleaned outline fitted with lines, arcs and cubics between its corners, and
//! flattened within the chord tolerance with the seam width of every edge.

use super::outline::{self, Outline, WELD};
use super::seams::SeamSegments;
use super::{PatternError, PieceOptions};
use crate::fit::{self, PathSeg};
use crate::poly;
use flatcut_geom::DVec2;

/// The fitted sew line.
pub(super) struct SewLine {
    /// Lines, arcs and cubics, closed.
    pub segs: Vec<PathSeg>,
    /// The segments flattened (CCW, no repeated points).
    pub polyline: Vec<DVec2>,
    /// The seam width of each polyline edge (edge i runs from point i to i + 1).
    pub edge_widths: Vec<f64>,
}

impl SewLine {
    /// Fits the outline between its corners (the marks on it are corners) and flattens the fit,
    /// refusing a sew line that crosses itself.
    pub fn fit(
        name: &str,
        outline: &Outline,
        segments: &SeamSegments,
        opts: &PieceOptions,
    ) -> Result<SewLine, PatternError> {
        let corners =
            fit::find_corners(&outline.points, &segments.forced_corners(), opts.corner_deg);
        let spans = fit::fit_closed_spans(&outline.points, &corners, opts.fit_tol);
        let mut polyline: Vec<DVec2> = Vec::new();
        let mut edge_widths: Vec<f64> = Vec::new();
        let mut segs: Vec<PathSeg> = Vec::new();
        for (start, span) in &spans {
            let w = segments.width_at(*start);
            let mut pts = Vec::new();
            for s in span {
                s.flatten(opts.chord_tol, &mut pts);
            }
            pts.pop(); // the next span starts there
            edge_widths.extend(std::iter::repeat_n(w, pts.len()));
            polyline.extend(pts);
            segs.extend(span.iter().copied());
        }
        let (polyline, edge_widths) = dedup_with_widths(polyline, edge_widths);
        outline::check_simple(name, &polyline)?;
        Ok(SewLine {
            segs,
            polyline,
            edge_widths,
        })
    }
}

/// Drops repeated points of the flattened sew line, keeping each remaining edge's width (taken
/// from the nearest original edge).
fn dedup_with_widths(poly_in: Vec<DVec2>, widths: Vec<f64>) -> (Vec<DVec2>, Vec<f64>) {
    let clean = poly::dedup_closed(&poly_in, WELD);
    if clean.len() == poly_in.len() {
        return (clean, widths);
    }
    let w2 = clean
        .iter()
        .map(|q| widths[poly::nearest_on_closed(&poly_in, *q).0])
        .collect();
    (clean, w2)
}
