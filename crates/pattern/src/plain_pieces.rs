//! The pieces of a plain drawing (an SVG or DXF that flatcut did not write, so no stroke names
//! its piece): every closed cut contour inside no larger one is a piece's outline, and every
//! other stroke belongs to the piece whose outline holds its first point. SVG and DXF import
//! share this one rule.

use crate::drawing::{Layer, Stroke, StrokeKind};
use crate::poly;
use flatcut_geom::DVec2;

/// Marks the outer contours of a plain drawing as piece boundaries (numbered in drawing order),
/// the other closed cut contours as inner cuts, and gives every stroke the piece that holds it.
/// A contour counts as inside another only when it is smaller: of two coincident contours (a
/// cut drawn twice) each is a piece, where "all points inside" alone would make neither one.
pub fn find_pieces(strokes: &mut [Stroke]) {
    let closed_cut: Vec<usize> = (0..strokes.len())
        .filter(|&i| {
            strokes[i].closed
                && strokes[i].layer == Layer::Cut
                && matches!(strokes[i].kind, StrokeKind::Boundary | StrokeKind::InnerCut)
        })
        .collect();
    let inside = |a: usize, b: usize| {
        area(&strokes[a].points) < area(&strokes[b].points)
            && strokes[a]
                .points
                .iter()
                .all(|q| poly::contains(&strokes[b].points, *q))
    };
    let outers: Vec<usize> = closed_cut
        .iter()
        .copied()
        .filter(|&i| !closed_cut.iter().any(|&j| j != i && inside(i, j)))
        .collect();
    for (k, &i) in outers.iter().enumerate() {
        strokes[i].kind = StrokeKind::Boundary;
        strokes[i].piece = Some(k as u32);
    }
    for s in strokes
        .iter_mut()
        .filter(|s| s.kind == StrokeKind::Boundary && s.piece.is_none())
    {
        s.kind = StrokeKind::InnerCut;
    }
    assign_by_containment(strokes);
}

/// Gives strokes without a piece the piece whose boundary holds their first point.
pub fn assign_by_containment(strokes: &mut [Stroke]) {
    let outers: Vec<(u32, Vec<DVec2>)> = strokes
        .iter()
        .filter(|s| s.kind == StrokeKind::Boundary)
        .filter_map(|s| s.piece.map(|p| (p, s.points.clone())))
        .collect();
    for s in strokes.iter_mut().filter(|s| s.piece.is_none()) {
        let Some(&q) = s.points.first() else {
            continue;
        };
        if let Some((p, _)) = outers.iter().find(|(_, o)| poly::contains(o, q)) {
            s.piece = Some(*p);
        }
    }
}

/// The area a closed polyline encloses, whichever way it runs.
fn area(p: &[DVec2]) -> f64 {
    poly::signed_area(p).abs()
}
