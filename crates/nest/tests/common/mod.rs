//! Independent layout checks shared by the tests (no jagua-rs involved).

use flatcut_geom::DVec2;
use flatcut_nest::{NestItem, NestResult};

fn seg_seg_dist(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> f64 {
    let r = a1 - a0;
    let s = b1 - b0;
    let den = r.perp_dot(s);
    if den.abs() > 1e-300 {
        let t = (b0 - a0).perp_dot(s) / den;
        let u = (b0 - a0).perp_dot(r) / den;
        if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
            return 0.0;
        }
    }
    let pd = |p: DVec2, a: DVec2, b: DVec2| {
        let d = b - a;
        let t = if d.length_squared() > 0.0 {
            ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + d * t).distance(p)
    };
    pd(a0, b0, b1)
        .min(pd(a1, b0, b1))
        .min(pd(b0, a0, a1))
        .min(pd(b1, a0, a1))
}

fn contains(poly: &[DVec2], q: DVec2) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Placed outlines in stock coordinates, with their sheet.
pub fn placed_polygons(items: &[NestItem], r: &NestResult) -> Vec<(usize, Vec<DVec2>)> {
    r.placed
        .iter()
        .map(|p| {
            (
                p.sheet,
                items[p.item]
                    .outline
                    .iter()
                    .map(|q| p.placement.apply(*q))
                    .collect(),
            )
        })
        .collect()
}

/// Minimum distance between any two placed pieces on the same sheet (0 when they overlap).
pub fn min_gap(polys: &[(usize, Vec<DVec2>)]) -> f64 {
    let mut best = f64::INFINITY;
    let bbs: Vec<(DVec2, DVec2)> = polys
        .iter()
        .map(|(_, p)| {
            (
                p.iter().copied().fold(DVec2::INFINITY, DVec2::min),
                p.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max),
            )
        })
        .collect();
    for i in 0..polys.len() {
        for j in i + 1..polys.len() {
            if polys[i].0 != polys[j].0 {
                continue;
            }
            let (a, b) = (&polys[i].1, &polys[j].1);
            // boxes farther apart than the current best cannot lower it
            let gap = (bbs[j].0 - bbs[i].1).max(bbs[i].0 - bbs[j].1).max_element();
            if gap > best {
                continue;
            }
            if contains(b, a[0]) || contains(a, b[0]) {
                return 0.0;
            }
            for k in 0..a.len() {
                for l in 0..b.len() {
                    let d = seg_seg_dist(a[k], a[(k + 1) % a.len()], b[l], b[(l + 1) % b.len()]);
                    best = best.min(d);
                }
            }
        }
    }
    best
}
