//! Collision quantification (Gardeyn & Vanden Berghe 2025, §4): how much two placed shapes
//! overlap, measured on their inscribed poles so it is cheap, smooth and positive whenever the
//! exact shapes collide; and how far a shape sticks out of its container.

use jagua_rs::geometry::fail_fast::SPSurrogate;
use jagua_rs::geometry::primitives::{Circle, Rect, SPolygon};
use std::f32::consts::PI;

/// The decay length of the overlap proxy, as a fraction of the larger shape's diameter: pole
/// pairs closer than this to touching still count a little, so the measure has no flat zero
/// region between a barely-touching and a barely-separated pair.
const EPS_DIAM_RATIO: f32 = 0.01;

/// Lanes of the pole arrays: the pairwise loop runs on fixed-size chunks the compiler maps to
/// vector registers (floating-point sums are only vectorised when written lane-wise).
const LANES: usize = 8;

/// The poles of one transformed shape in structure-of-arrays form, padded to whole chunks with
/// zero-radius poles (which contribute nothing), so the pairwise loop over another shape's
/// poles runs on packed lanes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Poles {
    x: Vec<[f32; LANES]>,
    y: Vec<[f32; LANES]>,
    r: Vec<[f32; LANES]>,
}

impl Poles {
    pub(crate) fn load(&mut self, s: &SPSurrogate) {
        let chunks = s.poles.len().div_ceil(LANES);
        self.x.clear();
        self.y.clear();
        self.r.clear();
        self.x.resize(chunks, [0.0; LANES]);
        self.y.resize(chunks, [0.0; LANES]);
        self.r.resize(chunks, [0.0; LANES]);
        for (k, c) in s.poles.iter().enumerate() {
            let (i, l) = (k / LANES, k % LANES);
            self.x[i][l] = c.center.0;
            self.y[i][l] = c.center.1;
            self.r[i][l] = c.radius;
        }
    }

    pub(crate) fn of(s: &SPolygon) -> Self {
        let mut p = Self::default();
        p.load(s.surrogate());
        p
    }
}

/// Overlap-area proxy of two pole sets: Σ over pole pairs of the penetration depth (decayed to
/// a small positive value when the poles are apart) times the smaller radius, times π.
fn overlap_proxy(a: &Poles, b: &[Circle], eps: f32) -> f32 {
    let eps2 = eps * eps;
    let mut acc = [0.0f32; LANES];
    for c in b {
        let (cx, cy, cr) = (c.center.0, c.center.1, c.radius);
        for ((xs, ys), rs) in a.x.iter().zip(&a.y).zip(&a.r) {
            for l in 0..LANES {
                let dx = xs[l] - cx;
                let dy = ys[l] - cy;
                let pd = (rs[l] + cr) - (dx * dx + dy * dy).sqrt();
                let far = eps2 / (2.0 * eps - pd);
                let decayed = if pd >= eps { pd } else { far };
                acc[l] += decayed * rs[l].min(cr);
            }
        }
    }
    acc.iter().sum::<f32>() * PI
}

/// The shape factor of a pair: the geometric mean of the square roots of their convex-hull
/// areas, so large pieces weigh more than slivers at equal overlap.
fn shape_factor(a: &SPolygon, b: &SPolygon) -> f32 {
    (a.surrogate().convex_hull_area.sqrt() * b.surrogate().convex_hull_area.sqrt()).sqrt()
}

/// Loss of the collision of shape `a` (whose poles are `ap`) with shape `b` (a placed piece, a
/// defect or a quality zone): positive for any collision.
pub(crate) fn pair_loss(a: &SPolygon, ap: &Poles, b: &SPolygon) -> f32 {
    let eps = a.diameter().max(b.diameter()) * EPS_DIAM_RATIO;
    let proxy = overlap_proxy(ap, &b.surrogate().poles, eps) + eps * eps;
    proxy.sqrt() * shape_factor(a, b)
}

/// Loss of shape `s` sticking out of a rectangular container `c`: the area of its bounding box
/// outside `c` (plus a sliver so it is never zero), or, when the box misses `c` entirely, its
/// area and distance to `c`.
pub(crate) fn rect_exterior_loss(s: &SPolygon, c: Rect) -> f32 {
    let b = s.bbox();
    let outside = match Rect::intersection(b, c) {
        Some(r) => (b.area() - r.area()) + 1e-4 * b.area(),
        None => {
            let (bc, cc) = (b.centroid(), c.centroid());
            b.area() + ((bc.0 - cc.0).powi(2) + (bc.1 - cc.1).powi(2)).sqrt()
        }
    };
    2.0 * outside.max(f32::MIN_POSITIVE).sqrt() * shape_factor(s, s)
}

/// Loss of shape `s` sticking out of an irregular container whose signed distance (positive
/// inside) is `sd`: its poles' penetration through the boundary plus its hull vertices' distance
/// outside.
pub(crate) fn field_exterior_loss(s: &SPolygon, sd: &impl Fn(f32, f32) -> f32) -> f32 {
    let eps = s.diameter() * EPS_DIAM_RATIO;
    let eps2 = eps * eps;
    let mut proxy = 0.0f32;
    for c in &s.surrogate().poles {
        let pd = c.radius - sd(c.center.0, c.center.1);
        let decayed = if pd >= eps {
            pd
        } else {
            eps2 / (2.0 * eps - pd)
        };
        proxy += PI * decayed * c.radius;
    }
    for &i in &s.surrogate().convex_hull_indices {
        let v = s.vertex(i);
        let out = (-sd(v.0, v.1)).max(0.0);
        proxy += out * out;
    }
    2.0 * (proxy + eps2).sqrt() * shape_factor(s, s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use jagua_rs::geometry::Transformation;
    use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
    use jagua_rs::geometry::geo_traits::Transformable;
    use jagua_rs::geometry::primitives::Point;

    fn square(s: f32) -> SPolygon {
        let mut p = SPolygon::new(vec![
            Point(0.0, 0.0),
            Point(s, 0.0),
            Point(s, s),
            Point(0.0, s),
        ])
        .unwrap();
        p.generate_surrogate(SPSurrogateConfig {
            n_pole_limits: [(32, 0.0), (16, 0.8), (8, 0.9)],
            ff_pole_area_ratio: 0.5,
            n_ff_piers: 0,
        })
        .unwrap();
        p
    }

    /// The loss grows as two squares overlap more, and is symmetric.
    #[test]
    fn pair_loss_is_monotone_in_overlap_and_symmetric() {
        let a = square(10.0);
        let ap = Poles::of(&a);
        let mut last = 0.0;
        for k in (0..10).rev() {
            let b = a.transform_clone(&Transformation::from_translation((k as f32, 0.0)));
            let l = pair_loss(&a, &ap, &b);
            assert!(l > last, "shift {k}: {l} <= {last}");
            let back = pair_loss(&b, &Poles::of(&b), &a);
            assert!((back - l).abs() <= 1e-3 * l);
            last = l;
        }
    }

    #[test]
    fn exterior_loss_grows_with_the_part_outside() {
        let c = Rect::try_new(0.0, 0.0, 100.0, 100.0).unwrap();
        let a = square(10.0);
        let l1 = rect_exterior_loss(
            &a.transform_clone(&Transformation::from_translation((95.0, 0.0))),
            c,
        );
        let l2 = rect_exterior_loss(
            &a.transform_clone(&Transformation::from_translation((98.0, 0.0))),
            c,
        );
        assert!(l2 > l1 && l1 > 0.0);
        let sd = |x: f32, _y: f32| 100.0 - x;
        let f1 = field_exterior_loss(
            &a.transform_clone(&Transformation::from_translation((95.0, 0.0))),
            &sd,
        );
        let f2 = field_exterior_loss(
            &a.transform_clone(&Transformation::from_translation((98.0, 0.0))),
            &sd,
        );
        assert!(f2 > f1 && f1 > 0.0);
    }
}
