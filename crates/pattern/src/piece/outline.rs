//! The input outline cleaned for fitting: repeated points welded, counter-clockwise, simple, with
//! the map from input indices to cleaned vertices that boundary marks are carried through.

use super::PatternError;
use crate::poly;
use flatcut_geom::DVec2;

/// Points closer than this (mm) are one point.
pub(super) const WELD: f64 = flatcut_geom::Tolerances::DEFAULT_WELD_MM;

/// A cleaned outline: distinct points, counter-clockwise, simple, at least three.
pub(super) struct Outline {
    pub points: Vec<DVec2>,
    /// The cleaned vertex of each input point.
    pub map: Vec<usize>,
}

impl Outline {
    /// Welds repeated points (keeping an index map for boundary marks), turns a clockwise outline
    /// round keeping vertex 0 first, and refuses a degenerate or self-intersecting one.
    pub fn clean(name: &str, raw: &[DVec2]) -> Result<Outline, PatternError> {
        let (mut points, mut map) = weld(raw);
        if points.len() < 3 {
            return Err(PatternError::DegenerateOutline {
                piece: name.into(),
                reason: format!("{} distinct points, need at least 3", points.len()),
            });
        }
        check_simple(name, &points)?;
        let area = poly::signed_area(&points);
        if area.abs() < WELD * WELD {
            return Err(PatternError::DegenerateOutline {
                piece: name.into(),
                reason: "zero area".into(),
            });
        }
        let n = points.len();
        if area < 0.0 {
            // accept clockwise input: reverse, keeping vertex 0 first
            points[1..].reverse();
            map.iter_mut().for_each(|m| {
                if *m != 0 {
                    *m = n - *m
                }
            });
        }
        check_simple(name, &points)?;
        Ok(Outline { points, map })
    }
}

/// The distinct points of `raw` (consecutive points within [`WELD`] merged, the closing point
/// dropped) and the index of each input point among them.
fn weld(raw: &[DVec2]) -> (Vec<DVec2>, Vec<usize>) {
    let mut points: Vec<DVec2> = Vec::with_capacity(raw.len());
    let mut map = vec![0usize; raw.len()];
    for (i, &q) in raw.iter().enumerate() {
        if points.last().is_none_or(|l: &DVec2| l.distance(q) > WELD) {
            points.push(q);
        }
        map[i] = points.len() - 1;
    }
    while points.len() > 1 && points[0].distance(points[points.len() - 1]) <= WELD {
        points.pop();
        let last = points.len();
        map.iter_mut().for_each(|m| {
            if *m >= last {
                *m = 0
            }
        });
    }
    (points, map)
}

/// Refuses a closed polyline whose edges cross, naming the edges and where.
pub(super) fn check_simple(name: &str, points: &[DVec2]) -> Result<(), PatternError> {
    match poly::first_self_intersection(points) {
        Some((a, b, x)) => Err(PatternError::SelfIntersecting {
            piece: name.into(),
            edge_a: a,
            edge_b: b,
            x: x.x,
            y: x.y,
        }),
        None => Ok(()),
    }
}
