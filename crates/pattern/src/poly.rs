//! Small exact polygon kernels in f64 mm: signed area, containment, segment crossing, simplicity
//! and distances. Written here because they are a few lines each and the validation of the seam
//! offset must be independent of the library that computed it.

use flatcut_geom::DVec2;

/// Signed area (positive for counter-clockwise) of a closed polygon without repeated end point.
pub fn signed_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>() * 0.5
}

pub use flatcut_geom::polygon::contains;

/// Distance from `q` to the segment `a`–`b` and the parameter of the nearest point.
pub fn seg_nearest(a: DVec2, b: DVec2, q: DVec2) -> (f64, f64) {
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((q - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((a + d * t).distance(q), t)
}

/// Distance from `q` to a closed polyline.
pub fn dist_to_closed(poly: &[DVec2], q: DVec2) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| seg_nearest(poly[i], poly[(i + 1) % n], q).0)
        .fold(f64::INFINITY, f64::min)
}

pub use flatcut_geom::polygon::{first_self_intersection, seg_intersection};

/// Removes consecutive duplicates (closer than `eps`) including a repeated closing point.
pub fn dedup_closed(p: &[DVec2], eps: f64) -> Vec<DVec2> {
    let mut out: Vec<DVec2> = Vec::with_capacity(p.len());
    for &q in p {
        if out.last().is_none_or(|l| l.distance(q) > eps) {
            out.push(q);
        }
    }
    while out.len() > 1 && out[0].distance(out[out.len() - 1]) <= eps {
        out.pop();
    }
    out
}

/// Arc length of a closed polyline up to each vertex (len n+1, last = perimeter).
pub fn cumulative_length(p: &[DVec2]) -> Vec<f64> {
    let n = p.len();
    let mut s = Vec::with_capacity(n + 1);
    s.push(0.0);
    for i in 0..n {
        let l = s[i] + p[i].distance(p[(i + 1) % n]);
        s.push(l);
    }
    s
}

/// Nearest point on a closed polyline: (edge index, parameter on the edge, point, distance).
pub fn nearest_on_closed(p: &[DVec2], q: DVec2) -> (usize, f64, DVec2, f64) {
    let n = p.len();
    let mut best = (0, 0.0, p[0], f64::INFINITY);
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        let (d, t) = seg_nearest(a, b, q);
        if d < best.3 {
            best = (i, t, a.lerp(b, t), d);
        }
    }
    best
}

/// First crossing of the ray `o + s·dir` (s > 0) with a closed polyline: the smallest s.
pub fn ray_hit(poly: &[DVec2], o: DVec2, dir: DVec2) -> Option<f64> {
    flatcut_geom::polygon::ray_hit(poly, o, dir).map(|h| h.t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn area_and_containment_of_unit_square() {
        let sq = [v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        assert_eq!(signed_area(&sq), 1.0);
        assert!(contains(&sq, v(0.5, 0.5)));
        assert!(!contains(&sq, v(1.5, 0.5)));
        assert!(first_self_intersection(&sq).is_none());
    }

    #[test]
    fn bow_tie_is_self_intersecting() {
        let bow = [v(0., 0.), v(2., 2.), v(2., 0.), v(0., 2.)];
        let (a, b, x) = first_self_intersection(&bow).unwrap();
        assert_eq!((a, b), (0, 2));
        assert!(x.distance(v(1., 1.)) < 1e-12);
    }

    #[test]
    fn ray_hits_nearest_edge() {
        let sq = [v(0., 0.), v(4., 0.), v(4., 4.), v(0., 4.)];
        assert!((ray_hit(&sq, v(1., 1.), v(1., 0.)).unwrap() - 3.0).abs() < 1e-12);
    }
}
