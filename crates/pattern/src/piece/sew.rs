//! The sew line: the cleaned outline fitted with lines, arcs and cubics between its corners, and
//! flattened within the chord tolerance with the width, kind and stretch of every edge.

use super::edges::{EdgeKind, OutlineEdges};
use super::outline::{self, Outline, WELD};
use super::{PatternError, PieceOptions};
use crate::fit::{self, PathSeg};
use crate::poly;
use flatcut_geom::DVec2;

/// How one edge of the flattened sew line is finished.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct EdgeFinish {
    /// Allowance (mm).
    pub width: f64,
    pub kind: EdgeKind,
    /// The named stretch of the input it belongs to (`None`: the default seam).
    pub stretch: Option<usize>,
}

/// The fitted sew line.
pub(super) struct SewLine {
    /// Lines, arcs and cubics, closed.
    pub segs: Vec<PathSeg>,
    /// The segments flattened (CCW, no repeated points).
    pub polyline: Vec<DVec2>,
    /// How each polyline edge is finished (edge i runs from point i to i + 1).
    pub finish: Vec<EdgeFinish>,
    /// Whether each polyline vertex is a corner of the fit (a span's start), not a point inside
    /// a fitted curve.
    pub corner: Vec<bool>,
}

impl SewLine {
    /// Fits the outline between its corners (the marks on it and the ends of its named
    /// stretches are corners) and flattens the fit; where the fit would cross itself, the
    /// outline's own points joined by lines.
    pub fn fit(
        name: &str,
        outline: &Outline,
        edges: &OutlineEdges,
        opts: &PieceOptions,
    ) -> Result<SewLine, PatternError> {
        let corners = fit::find_corners(&outline.points, edges.forced_corners(), opts.corner_deg);
        let fitted = Self::fit_at(&outline.points, &corners, edges, opts);
        if outline::check_simple(name, &fitted.polyline).is_ok() {
            return Ok(fitted);
        }
        // Curves fitted within the tolerance across a slot narrower than it (where seams meet
        // on a split piece) can cross the other side; the outline itself is simple (checked
        // when cleaned), so its own points joined by lines are the sew line.
        let every: Vec<usize> = (0..outline.points.len()).collect();
        let lines = Self::fit_at(&outline.points, &every, edges, opts);
        outline::check_simple(name, &lines.polyline)?;
        Ok(lines)
    }

    /// The outline's points fitted between `corners` and flattened (see [`SewLine::fit`]).
    fn fit_at(
        points: &[DVec2],
        corners: &[usize],
        edges: &OutlineEdges,
        opts: &PieceOptions,
    ) -> SewLine {
        let spans = fit::fit_closed_spans(points, corners, opts.fit_tol);
        let mut polyline: Vec<DVec2> = Vec::new();
        let mut finish: Vec<EdgeFinish> = Vec::new();
        let mut corner: Vec<bool> = Vec::new();
        let mut segs: Vec<PathSeg> = Vec::new();
        for (start, span) in &spans {
            let (width, kind) = edges.finish_at(*start);
            let f = EdgeFinish {
                width,
                kind,
                stretch: edges.stretch_at(*start),
            };
            let mut pts = Vec::new();
            for s in span {
                s.flatten(opts.chord_tol, &mut pts);
            }
            pts.pop(); // the next span starts there
            corner.push(!corners.is_empty());
            corner.extend(std::iter::repeat_n(false, pts.len().saturating_sub(1)));
            finish.extend(std::iter::repeat_n(f, pts.len()));
            polyline.extend(pts);
            segs.extend(span.iter().copied());
        }
        let (polyline, finish, corner) = dedup(polyline, finish, corner);
        SewLine {
            segs,
            polyline,
            finish,
            corner,
        }
    }

    /// The allowance of each polyline edge (mm).
    pub fn widths(&self) -> Vec<f64> {
        self.finish.iter().map(|f| f.width).collect()
    }
}

/// Drops repeated points of the flattened sew line, keeping each remaining edge's finish (taken
/// from the nearest original edge) and each remaining vertex's corner flag.
fn dedup(
    poly_in: Vec<DVec2>,
    finish: Vec<EdgeFinish>,
    corner: Vec<bool>,
) -> (Vec<DVec2>, Vec<EdgeFinish>, Vec<bool>) {
    let clean = poly::dedup_closed(&poly_in, WELD);
    if clean.len() == poly_in.len() {
        return (clean, finish, corner);
    }
    let at: Vec<usize> = clean
        .iter()
        .map(|q| poly::nearest_on_closed(&poly_in, *q).0)
        .collect();
    let f2 = at.iter().map(|&i| finish[i]).collect();
    let c2 = clean
        .iter()
        .map(|q| {
            poly_in
                .iter()
                .zip(&corner)
                .any(|(p, c)| *c && p.distance(*q) <= WELD)
        })
        .collect();
    (clean, f2, c2)
}
