//! Signed distance to a container's outline on a grid (positive inside), bilinearly
//! interpolated: how the search measures a piece sticking out of an irregular hide.

use flatcut_geom::DVec2;
use flatcut_pattern::poly;

/// Grid nodes per side.
const NODES: usize = 160;

/// Signed distance to a closed outline, sampled on a grid over its box (plus a margin).
#[derive(Clone, Debug)]
pub(crate) struct DistanceGrid {
    min: DVec2,
    step: DVec2,
    d: Vec<f32>,
}

impl DistanceGrid {
    pub(crate) fn new(outline: &[DVec2]) -> Self {
        let lo = outline.iter().copied().fold(DVec2::INFINITY, DVec2::min);
        let hi = outline
            .iter()
            .copied()
            .fold(DVec2::NEG_INFINITY, DVec2::max);
        let margin = 0.05 * (hi - lo).max_element();
        let (min, max) = (lo - DVec2::splat(margin), hi + DVec2::splat(margin));
        let step = (max - min) / (NODES - 1) as f64;
        let mut d = Vec::with_capacity(NODES * NODES);
        for j in 0..NODES {
            for i in 0..NODES {
                let q = min + DVec2::new(i as f64, j as f64) * step;
                let e = poly::dist_to_closed(outline, q);
                d.push(if poly::contains(outline, q) { e } else { -e } as f32);
            }
        }
        Self { min, step, d }
    }

    /// Signed distance at `(x, y)`: bilinear inside the grid; beyond it, the border value minus
    /// the distance to the grid.
    pub(crate) fn at(&self, x: f32, y: f32) -> f32 {
        let fx = (x as f64 - self.min.x) / self.step.x;
        let fy = (y as f64 - self.min.y) / self.step.y;
        let last = (NODES - 1) as f64;
        let (cx, cy) = (fx.clamp(0.0, last), fy.clamp(0.0, last));
        let beyond = ((fx - cx) * self.step.x).hypot((fy - cy) * self.step.y) as f32;
        let (i, j) = (
            (cx.floor() as usize).min(NODES - 2),
            (cy.floor() as usize).min(NODES - 2),
        );
        let (tx, ty) = ((cx - i as f64) as f32, (cy - j as f64) as f32);
        let v = |a: usize, b: usize| self.d[b * NODES + a];
        let bottom = v(i, j) * (1.0 - tx) + v(i + 1, j) * tx;
        let top = v(i, j + 1) * (1.0 - tx) + v(i + 1, j + 1) * tx;
        bottom * (1.0 - ty) + top * ty - beyond
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_distances() {
        let sq = vec![
            DVec2::ZERO,
            DVec2::new(100., 0.),
            DVec2::new(100., 100.),
            DVec2::new(0., 100.),
        ];
        let g = DistanceGrid::new(&sq);
        assert!((g.at(50.0, 50.0) - 50.0).abs() < 1.0);
        assert!((g.at(10.0, 50.0) - 10.0).abs() < 1.0);
        assert!((g.at(-3.0, 50.0) + 3.0).abs() < 1.0);
        assert!(g.at(500.0, 50.0) < -350.0);
    }
}
