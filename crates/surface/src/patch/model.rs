//! Multi-patch models and their shared-edge adjacency.
//!
//! A [`Model`] holds patches as `Arc<dyn ParamSurface>` and finds which patch sides coincide
//! geometrically within a weld tolerance: end points must match (in the same or the reversed
//! direction) and every sample of each side must lie within the tolerance of the other side.
//! The tessellator uses the resulting [`SharedEdge`] list to place identical vertices on both
//! sides of a seam, which makes meshes crack-free. Sides that collapse to a point (sphere
//! poles, cone apices) are never shared.

use crate::{DomainKind, ParamSurface, SurfaceError};
use flatcut_geom::Aabb3;
use flatcut_geom::num::{GoldenStop, golden_section_min};
use glam::{DVec2, DVec3};
use std::sync::Arc;

/// Samples per side used to compare boundary curves (the ends plus 15 interior points: enough
/// to tell apart any two distinct cubic-ish edges that share end points).
const SIDE_SAMPLES: usize = 17;
/// Dense samples of the opposite side for the closest-point search, before refinement.
const NEAREST_SAMPLES: usize = 64;
/// Golden-section refinement iterations of the closest-point search (interval shrinks 0.618ⁿ).
const NEAREST_REFINE: usize = 40;

/// One side of a patch's parameter domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Side {
    /// `u = u0`, v increasing.
    U0,
    /// `u = u1`, v increasing.
    U1,
    /// `v = v0`, u increasing.
    V0,
    /// `v = v1`, u increasing.
    V1,
    /// The hypotenuse `u + v = 1` of a triangular domain, from `(1, 0)` to `(0, 1)`.
    W0,
}

impl Side {
    /// The sides of a domain kind (triangles: `V0`, `U0` and `W0`).
    pub fn all(kind: DomainKind) -> &'static [Side] {
        match kind {
            DomainKind::Triangle => &[Side::V0, Side::U0, Side::W0],
            _ => &[Side::U0, Side::U1, Side::V0, Side::V1],
        }
    }

    /// The domain point at fraction `s ∈ [0, 1]` along this side of `patch`.
    pub fn param(self, patch: &dyn ParamSurface, s: f64) -> DVec2 {
        let d = patch.domain();
        let lerp = |a: (f64, f64), t: f64| a.0 + (a.1 - a.0) * t;
        match self {
            Side::U0 => DVec2::new(d.u.0, lerp(d.v, s)),
            Side::U1 => DVec2::new(d.u.1, lerp(d.v, s)),
            Side::V0 => DVec2::new(lerp(d.u, s), d.v.0),
            Side::V1 => DVec2::new(lerp(d.u, s), d.v.1),
            Side::W0 => DVec2::new(1.0 - s, s),
        }
    }

    /// The 3D point at fraction `s` along this side of `patch`.
    pub fn eval(self, patch: &dyn ParamSurface, s: f64) -> DVec3 {
        let p = self.param(patch, s);
        patch.eval(p.x, p.y)
    }
}

/// Two patch sides that coincide: side `side_a` of patch `a` and side `side_b` of patch `b`
/// (`a < b`, or `a == b` for a seam of a closed patch). `reversed` is true when they run in
/// opposite directions. `same_parameterization` is true when equal fractions along the two
/// sides give the same point (within the weld tolerance), so matching samples need no search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SharedEdge {
    /// 0-based index of the first patch.
    pub a: usize,
    /// The first patch's side.
    pub side_a: Side,
    /// 0-based index of the second patch (`a <= b`).
    pub b: usize,
    /// The second patch's side.
    pub side_b: Side,
    /// True when the two sides run in opposite directions.
    pub reversed: bool,
    /// True when equal fractions along the sides give the same point.
    pub same_parameterization: bool,
}

/// A set of patches with the adjacency of their sides.
#[derive(Clone, Debug)]
pub struct Model {
    patches: Vec<Arc<dyn ParamSurface>>,
    edges: Vec<SharedEdge>,
    weld_mm: f64,
}

struct SideInfo {
    patch: usize,
    side: Side,
    samples: Vec<DVec3>,
    bbox: Aabb3,
    degenerate: bool,
}

fn nearest_dist(patch: &dyn ParamSurface, side: Side, q: DVec3) -> f64 {
    let mut best = (f64::INFINITY, 0usize);
    for k in 0..=NEAREST_SAMPLES {
        let d = side
            .eval(patch, k as f64 / NEAREST_SAMPLES as f64)
            .distance_squared(q);
        if d < best.0 {
            best = (d, k);
        }
    }
    let h = 1.0 / NEAREST_SAMPLES as f64;
    let (mut lo, mut hi) = (((best.1 as f64) - 1.0) * h, ((best.1 as f64) + 1.0) * h);
    lo = lo.max(0.0);
    hi = hi.min(1.0);
    let f = |s: f64| side.eval(patch, s).distance_squared(q);
    let m = golden_section_min(f, lo, hi, GoldenStop::Iterations(NEAREST_REFINE));
    best.0.min(m.fx).sqrt()
}

/// Every side of every patch sampled, its box, and whether it collapses to a point within
/// `weld_mm`; a side that evaluates to a non-finite point is an error naming it.
fn sample_sides(
    patches: &[Arc<dyn ParamSurface>],
    weld_mm: f64,
) -> Result<Vec<SideInfo>, SurfaceError> {
    let mut sides = Vec::new();
    for (pi, p) in patches.iter().enumerate() {
        for &side in Side::all(p.domain_kind()) {
            let samples: Vec<DVec3> = (0..SIDE_SAMPLES)
                .map(|k| side.eval(p.as_ref(), k as f64 / (SIDE_SAMPLES - 1) as f64))
                .collect();
            if let Some(k) = samples.iter().position(|q| !flatcut_geom::finite3(*q)) {
                return Err(SurfaceError::NonFiniteSide {
                    patch: pi,
                    side: format!("{side:?}"),
                    sample: k,
                });
            }
            let bbox = Aabb3::from_points(samples.iter().copied());
            let degenerate = samples.iter().all(|q| q.distance(samples[0]) <= weld_mm);
            sides.push(SideInfo {
                patch: pi,
                side,
                samples,
                bbox,
                degenerate,
            });
        }
    }
    Ok(sides)
}

impl Model {
    /// Builds the model and detects shared sides within `weld_mm` (finite, > 0).
    pub fn new(patches: Vec<Arc<dyn ParamSurface>>, weld_mm: f64) -> Result<Self, SurfaceError> {
        if !(weld_mm.is_finite() && weld_mm > 0.0) {
            return Err(SurfaceError::NotPositive {
                what: "model weld tolerance".into(),
                value: weld_mm,
            });
        }
        let sides = sample_sides(&patches, weld_mm)?;
        let mut edges = Vec::new();
        for i in 0..sides.len() {
            for j in i + 1..sides.len() {
                let (a, b) = (&sides[i], &sides[j]);
                if a.degenerate || b.degenerate {
                    continue;
                }
                let grow = |bb: &Aabb3| Aabb3 {
                    min: bb.min - DVec3::splat(weld_mm),
                    max: bb.max + DVec3::splat(weld_mm),
                };
                let (ga, gb) = (grow(&a.bbox), grow(&b.bbox));
                if ga.min.cmpgt(gb.max).any() || gb.min.cmpgt(ga.max).any() {
                    continue;
                }
                let n = SIDE_SAMPLES - 1;
                let fwd = a.samples[0].distance(b.samples[0]) <= weld_mm
                    && a.samples[n].distance(b.samples[n]) <= weld_mm;
                let rev = a.samples[0].distance(b.samples[n]) <= weld_mm
                    && a.samples[n].distance(b.samples[0]) <= weld_mm;
                if !(fwd || rev) {
                    continue;
                }
                let pa = patches[a.patch].as_ref();
                let pb = patches[b.patch].as_ref();
                let on_b = a
                    .samples
                    .iter()
                    .all(|q| nearest_dist(pb, b.side, *q) <= weld_mm);
                let on_a = on_b
                    && b.samples
                        .iter()
                        .all(|q| nearest_dist(pa, a.side, *q) <= weld_mm);
                if !on_a {
                    continue;
                }
                // A closed side pair (both ends equal) may be shared either way; prefer the
                // direction in which the interior samples also correspond.
                let same_fwd = a
                    .samples
                    .iter()
                    .zip(&b.samples)
                    .all(|(p, q)| p.distance(*q) <= weld_mm);
                let same_rev = a
                    .samples
                    .iter()
                    .zip(b.samples.iter().rev())
                    .all(|(p, q)| p.distance(*q) <= weld_mm);
                let reversed = if same_fwd {
                    false
                } else if same_rev {
                    true
                } else {
                    !fwd
                };
                edges.push(SharedEdge {
                    a: a.patch,
                    side_a: a.side,
                    b: b.patch,
                    side_b: b.side,
                    reversed,
                    same_parameterization: same_fwd || same_rev,
                });
            }
        }
        Ok(Self {
            patches,
            edges,
            weld_mm,
        })
    }

    /// The patches, in the order given.
    pub fn patches(&self) -> &[Arc<dyn ParamSurface>] {
        &self.patches
    }

    /// The shared sides found, ordered by (a, side_a, b, side_b).
    pub fn edges(&self) -> &[SharedEdge] {
        &self.edges
    }

    /// The weld tolerance used (mm).
    pub fn weld_mm(&self) -> f64 {
        self.weld_mm
    }

    /// Sides that are not shared with any other side and not degenerate: the model's boundary.
    pub fn free_sides(&self) -> Vec<(usize, Side)> {
        let mut out = Vec::new();
        for (pi, p) in self.patches.iter().enumerate() {
            for &side in Side::all(p.domain_kind()) {
                let used = self
                    .edges
                    .iter()
                    .any(|e| (e.a == pi && e.side_a == side) || (e.b == pi && e.side_b == side));
                let first = side.eval(p.as_ref(), 0.0);
                let degenerate = (0..SIDE_SAMPLES).all(|k| {
                    side.eval(p.as_ref(), k as f64 / (SIDE_SAMPLES - 1) as f64)
                        .distance(first)
                        <= self.weld_mm
                });
                if !used && !degenerate {
                    out.push((pi, side));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::{BSplinePatch, BezierPatch, TriBezierPatch};

    fn quad(p: [DVec3; 4]) -> Arc<dyn ParamSurface> {
        // Bilinear patch with corners P(0,0), P(0,1), P(1,0), P(1,1).
        Arc::new(BezierPatch::new(1, 1, p.to_vec()).unwrap())
    }

    #[test]
    fn grid_of_four_quads_has_four_shared_edges() {
        let p = |x: f64, y: f64| DVec3::new(x, y, 0.1 * x * y);
        let a = quad([p(0., 0.), p(0., 1.), p(1., 0.), p(1., 1.)]);
        let b = quad([p(1., 0.), p(1., 1.), p(2., 0.), p(2., 1.)]);
        // c is flipped in v, so its shared side with a runs the other way.
        let c = quad([p(0., 2.), p(0., 1.), p(1., 2.), p(1., 1.)]);
        let d = quad([p(1., 1.), p(1., 2.), p(2., 1.), p(2., 2.)]);
        let m = Model::new(vec![a, b, c, d], 1e-6).unwrap();
        let e = m.edges();
        assert_eq!(e.len(), 4, "{e:?}");
        assert!(e.contains(&SharedEdge {
            a: 0,
            side_a: Side::U1,
            b: 1,
            side_b: Side::U0,
            reversed: false,
            same_parameterization: true
        }));
        assert!(e.contains(&SharedEdge {
            a: 0,
            side_a: Side::V1,
            b: 2,
            side_b: Side::V1,
            reversed: false,
            same_parameterization: true
        }));
        assert!(e.contains(&SharedEdge {
            a: 2,
            side_a: Side::U1,
            b: 3,
            side_b: Side::U0,
            reversed: true,
            same_parameterization: true
        }));
        assert_eq!(m.free_sides().len(), 8);
    }

    #[test]
    fn closed_sphere_has_its_seam_and_degenerate_poles() {
        let s: Arc<dyn ParamSurface> = Arc::new(BSplinePatch::sphere(DVec3::ZERO, 10.0).unwrap());
        let m = Model::new(vec![s], 1e-6).unwrap();
        assert_eq!(
            m.edges(),
            &[SharedEdge {
                a: 0,
                side_a: Side::V0,
                b: 0,
                side_b: Side::V1,
                reversed: false,
                same_parameterization: true
            }]
        );
        assert!(m.free_sides().is_empty());
    }

    #[test]
    fn triangle_next_to_quad_and_near_misses() {
        let a = quad([DVec3::ZERO, DVec3::Y, DVec3::X, DVec3::new(1.0, 1.0, 0.0)]);
        // Triangle with vertices w = (−1, ½), u = (0, 0), v = (0, 1): its W0 side (u-vertex to
        // v-vertex) is the quad's U0 side, in the same direction.
        let t: Arc<dyn ParamSurface> = Arc::new(
            TriBezierPatch::new(1, vec![DVec3::new(-1.0, 0.5, 0.0), DVec3::ZERO, DVec3::Y])
                .unwrap(),
        );
        let m = Model::new(vec![a.clone(), t], 1e-9).unwrap();
        assert_eq!(m.edges().len(), 1, "{:?}", m.edges());
        let e = m.edges()[0];
        assert_eq!(
            (e.a, e.side_a, e.b, e.side_b, e.reversed),
            (0, Side::U0, 1, Side::W0, false)
        );
        // A bulging neighbour with the same corners is not welded.
        let bulge: Arc<dyn ParamSurface> = Arc::new(
            BezierPatch::new(
                1,
                2,
                vec![
                    DVec3::X,
                    DVec3::new(1.0, 0.5, 0.01),
                    DVec3::new(1.0, 1.0, 0.0),
                    DVec3::new(2.0, 0.0, 0.0),
                    DVec3::new(2.0, 0.5, 0.0),
                    DVec3::new(2.0, 1.0, 0.0),
                ],
            )
            .unwrap(),
        );
        let m = Model::new(vec![a, bulge], 1e-4).unwrap();
        assert!(m.edges().is_empty());
        assert!(Model::new(vec![], 0.0).is_err());
    }
}
