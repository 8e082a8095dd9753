//! Kernels of closed plane polygons (f64 mm, no repeated end point) used by more than one crate:
//! containment, the area centroid and where a ray leaves. A few lines each, exact in their
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
