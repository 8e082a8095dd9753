//! Kernels of closed plane polygons (f64 mm, no repeated end point) used by more than one crate:
//! containment, the area centroid, where a ray leaves, segment crossings and the first
//! self-crossing (the pattern's outlines and seam offsets, the darts' flat outlines). A few lines each, exact in their
//! arithmetic, so written here rather than taken from a polygon library.

use glam::DVec2;

/// Even-odd point-in-polygon test.
pub fn contains(poly: &[DVec2], q: DVec2) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The area centroid; `None` for a polygon of zero area.
pub fn area_centroid(p: &[DVec2]) -> Option<DVec2> {
    let n = p.len();
    let (mut c, mut twice_area) = (DVec2::ZERO, 0.0);
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        let w = a.perp_dot(b);
        twice_area += w;
        c += (a + b) * w;
    }
    (twice_area != 0.0).then(|| c / (3.0 * twice_area))
}

/// Where the ray `o + t·dir` (t > 0) first crosses the polygon's boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The ray's parameter (a distance when `dir` is a unit vector).
    pub t: f64,
    /// The crossed edge, from vertex `edge` to vertex `edge + 1` (cyclically).
    pub edge: usize,
    /// Where along that edge, 0 at its first vertex and 1 at its second.
    pub u: f64,
}

/// The first crossing of the ray `o + t·dir` (t > 0) with the polygon's boundary.
pub fn ray_hit(poly: &[DVec2], o: DVec2, dir: DVec2) -> Option<RayHit> {
    let n = poly.len();
    let mut best: Option<RayHit> = None;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let s = b - a;
        let den = dir.perp_dot(s);
        if den.abs() < 1e-15 {
            continue;
        }
        let qp = a - o;
        let t = qp.perp_dot(s) / den;
        let u = qp.perp_dot(dir) / den;
        if t > 0.0 && (0.0..=1.0).contains(&u) && best.is_none_or(|h| t < h.t) {
            best = Some(RayHit { t, edge: i, u });
        }
    }
    best
}

/// Proper or touching intersection point of segments `a0a1` and `b0b1`, if any.
pub fn seg_intersection(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> Option<DVec2> {
    let r = a1 - a0;
    let s = b1 - b0;
    let den = r.perp_dot(s);
    let qp = b0 - a0;
    if den.abs() <= f64::EPSILON * r.length() * s.length() {
        // Parallel: report an overlap of collinear segments as an intersection.
        if qp.perp_dot(r).abs() > 1e-12 * (1.0 + r.length_squared()) {
            return None;
        }
        let rr = r.length_squared();
        if rr == 0.0 {
            return None;
        }
        let t0 = qp.dot(r) / rr;
        let t1 = (b1 - a0).dot(r) / rr;
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        if hi < 0.0 || lo > 1.0 {
            return None;
        }
        return Some(a0 + r * lo.max(0.0));
    }
    let t = qp.perp_dot(s) / den;
    let u = qp.perp_dot(r) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then(|| a0 + r * t)
}

/// First pair of non-adjacent crossing edges of a closed polygon (edge i runs from vertex i to
/// i+1), found with a sweep over x-sorted edge boxes: O(n log n + k).
pub fn first_self_intersection(p: &[DVec2]) -> Option<(usize, usize, DVec2)> {
    let n = p.len();
    if n < 4 {
        return None;
    }
    let mut order: Vec<usize> = (0..n).collect();
    let lo = |i: usize| p[i].x.min(p[(i + 1) % n].x);
    let hi = |i: usize| p[i].x.max(p[(i + 1) % n].x);
    order.sort_by(|&a, &b| lo(a).total_cmp(&lo(b)).then(a.cmp(&b)));
    let mut active: Vec<usize> = Vec::new();
    let mut found: Option<(usize, usize, DVec2)> = None;
    for &i in &order {
        let x = lo(i);
        active.retain(|&j| hi(j) >= x);
        for &j in &active {
            let adjacent = (i + 1) % n == j || (j + 1) % n == i;
            if adjacent {
                continue;
            }
            let (ylo_i, yhi_i) = (p[i].y.min(p[(i + 1) % n].y), p[i].y.max(p[(i + 1) % n].y));
            let (ylo_j, yhi_j) = (p[j].y.min(p[(j + 1) % n].y), p[j].y.max(p[(j + 1) % n].y));
            if yhi_i < ylo_j || yhi_j < ylo_i {
                continue;
            }
            if let Some(x) = seg_intersection(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]) {
                let (a, b) = (i.min(j), i.max(j));
                if found.is_none_or(|(fa, fb, _)| (a, b) < (fa, fb)) {
                    found = Some((a, b, x));
                }
            }
        }
        active.push(i);
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn a_squares_centroid_containment_and_exit() {
        let sq = [v(0., 0.), v(2., 0.), v(2., 2.), v(0., 2.)];
        assert_eq!(area_centroid(&sq), Some(v(1., 1.)));
        assert!(contains(&sq, v(1., 1.)) && !contains(&sq, v(3., 1.)));
        let h = ray_hit(&sq, v(1., 1.), v(1., 0.)).unwrap();
        assert_eq!((h.t, h.edge, h.u), (1.0, 1, 0.5));
        assert!(ray_hit(&sq, v(3., 1.), v(1., 0.)).is_none());
        assert_eq!(area_centroid(&[v(0., 0.), v(1., 1.), v(2., 2.)]), None);
    }
}
