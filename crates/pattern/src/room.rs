//! Where a box fits: the largest axis-aligned box of a given shape inside a polygon that crosses
//! none of a set of obstacle segments, found as a pole of inaccessibility in the box's own
//! metric. Labels go there, so they never cover the grain line or a mark.
//!
//! Written here rather than with the `polylabel` crate, which finds the largest circle in a
//! polygon with holes: a text block is a rectangle, and the grain line and internal lines are
//! open segments, not holes.
//!
//! Scaled by the box's half-size (x / hw, y / hh), a box of half-size s·(hw, hh) about q is the
//! L∞ ball of radius s about q, so the largest box about q has s = the L∞ distance from q to the
//! nearest edge or obstacle. That distance is 1-Lipschitz, so the search is polylabel's (Garcia-
//! Castellanos and Lombardo, 2007) branch and bound over square cells in that metric: a cell of
//! half-size r can hold nothing better than its centre's distance plus r.

use crate::poly;
use flatcut_geom::DVec2;
use std::collections::BinaryHeap;

/// How close to the best box the search stops, in multiples of the box's half-size: a label
/// scale within 0.1 % of the largest.
const PRECISION: f64 = 1e-3;
/// Cells examined at most: bounds the work on long outlines (the answer is then the best found).
const MAX_CELLS: usize = 20_000;

/// The centre `q` and scale `s` of the largest box of half-size `s·half` about `q` inside the
/// closed polygon `container` that no segment of `obstacles` (open polylines) enters; `None`
/// when nothing fits (a degenerate polygon or a zero half-size).
pub fn largest_box(
    container: &[DVec2],
    obstacles: &[Vec<DVec2>],
    half: DVec2,
) -> Option<(DVec2, f64)> {
    if container.len() < 3 || !(half.x > 0.0 && half.y > 0.0) {
        return None;
    }
    let scaled = |p: DVec2| p / half;
    let poly: Vec<DVec2> = container.iter().map(|p| scaled(*p)).collect();
    let mut segs: Vec<(DVec2, DVec2)> = (0..poly.len())
        .map(|i| (poly[i], poly[(i + 1) % poly.len()]))
        .collect();
    for l in obstacles {
        segs.extend(l.windows(2).map(|w| (scaled(w[0]), scaled(w[1]))));
    }
    let room = |q: DVec2| {
        let d = segs
            .iter()
            .map(|&(a, b)| linf_to_segment(q, a, b))
            .fold(f64::INFINITY, f64::min);
        if poly::contains(&poly, q) { d } else { -d }
    };
    let (best, s) = search(&poly, &room)?;
    (s > 0.0).then_some((best * half, s))
}

/// A square cell of the search: centre, half-size, room at the centre and the best room any
/// point of it can have; `order` breaks ties so the search is deterministic.
struct Cell {
    c: DVec2,
    r: f64,
    d: f64,
    bound: f64,
    order: usize,
}

impl PartialEq for Cell {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o).is_eq()
    }
}
impl Eq for Cell {}
impl PartialOrd for Cell {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Cell {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.bound
            .total_cmp(&o.bound)
            .then(o.order.cmp(&self.order))
    }
}

/// Branch and bound over square cells covering the polygon's bounding box: the point of most
/// room and that room.
fn search(poly: &[DVec2], room: &dyn Fn(DVec2) -> f64) -> Option<(DVec2, f64)> {
    let (lo, hi) = poly.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let size = (hi - lo).min_element();
    if !(size > 0.0 && size.is_finite()) {
        return None;
    }
    let mut order = 0;
    let mut cell = |c: DVec2, r: f64| {
        let d = room(c);
        order += 1;
        Cell {
            c,
            r,
            d,
            bound: d + r,
            order,
        }
    };
    let r = size * 0.5;
    let mut heap = BinaryHeap::new();
    let mut y = lo.y;
    while y < hi.y {
        let mut x = lo.x;
        while x < hi.x {
            heap.push(cell(DVec2::new(x + r, y + r), r));
            x += size;
        }
        y += size;
    }
    let start = cell((lo + hi) * 0.5, 0.0);
    let (mut best, mut best_d) = (start.c, start.d);
    let mut examined = 0;
    while let Some(c) = heap.pop() {
        if c.d > best_d {
            (best, best_d) = (c.c, c.d);
        }
        examined += 1;
        if c.bound - best_d <= PRECISION || examined >= MAX_CELLS {
            continue;
        }
        let h = c.r * 0.5;
        for (dx, dy) in [(-h, -h), (h, -h), (-h, h), (h, h)] {
            heap.push(cell(c.c + DVec2::new(dx, dy), h));
        }
    }
    Some((best, best_d))
}

/// The L∞ distance from `q` to the segment `a`–`b`: max(|x|, |y|) of `a + t(b − a) − q` is
/// convex and piecewise linear in t, so its minimum is at an end or where |x| = |y|.
pub fn linf_to_segment(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let (p, d) = (a - q, b - a);
    let at = |t: f64| (p + d * t).abs().max_element();
    let mut best = at(0.0).min(at(1.0));
    for (num, den) in [(p.y - p.x, d.x - d.y), (-(p.x + p.y), d.x + d.y)] {
        if den != 0.0 {
            let t = num / den;
            if (0.0..=1.0).contains(&t) {
                best = best.min(at(t));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: f64, h: f64) -> Vec<DVec2> {
        vec![
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, h),
            DVec2::new(0.0, h),
        ]
    }

    #[test]
    fn linf_distance_to_a_segment() {
        let q = DVec2::ZERO;
        // a horizontal segment 2 above: distance 2 whatever its x extent
        assert_eq!(
            linf_to_segment(q, DVec2::new(-5.0, 2.0), DVec2::new(5.0, 2.0)),
            2.0
        );
        // a diagonal x + y = 4 from (0, 4) to (4, 0): nearest in L∞ at (2, 2)
        assert!(
            (linf_to_segment(q, DVec2::new(0.0, 4.0), DVec2::new(4.0, 0.0)) - 2.0).abs() < 1e-12
        );
        // a segment ending at (3, 1): the end point, max(3, 1)
        assert_eq!(
            linf_to_segment(q, DVec2::new(3.0, 1.0), DVec2::new(9.0, 1.0)),
            3.0
        );
    }

    #[test]
    fn a_box_in_a_rectangle_is_centred_and_as_large_as_the_tighter_side() {
        // 200 × 100 container, box of half-size (10, 2): width-limited at s = 10, height at 25
        let (c, s) = largest_box(&rect(200.0, 100.0), &[], DVec2::new(10.0, 2.0)).unwrap();
        assert!((s - 10.0).abs() < 0.02, "{s}");
        assert!((c.x - 100.0).abs() < 0.5, "{c}");
    }

    #[test]
    fn the_box_keeps_off_the_obstacles() {
        // a line across the middle of a 200 × 100 rectangle: the box goes above or below it
        let grain = vec![vec![DVec2::new(20.0, 50.0), DVec2::new(180.0, 50.0)]];
        let half = DVec2::new(20.0, 4.0);
        let (c, s) = largest_box(&rect(200.0, 100.0), &grain, half).unwrap();
        let (lo, hi) = (c - half * s, c + half * s);
        assert!(hi.y <= 50.0 + 1e-9 || lo.y >= 50.0 - 1e-9, "{lo} {hi}");
        // the width allows s = 100 / 20 = 5, either half of the height 25 / 4: s = 5
        assert!((s - 5.0).abs() < 0.02, "{s}");
        assert!(lo.x >= -1e-9 && hi.x <= 200.0 + 1e-9 && lo.y >= -1e-9 && hi.y <= 100.0 + 1e-9);
    }

    #[test]
    fn nothing_fits_in_a_degenerate_polygon() {
        assert!(
            largest_box(
                &[DVec2::ZERO, DVec2::X, DVec2::new(2.0, 0.0)],
                &[],
                DVec2::ONE
            )
            .is_none()
        );
        assert!(largest_box(&rect(10.0, 10.0), &[], DVec2::ZERO).is_none());
    }
}
