//! A hide's grain direction field: direction lines (the backbone and lines fanning out from it)
//! sampled on a grid; the local direction is the inverse-square-distance-weighted mean of the
//! nearby lines' directions, as drawn.

use flatcut_geom::DVec2;

/// Grid cells per side: fine enough that the direction varies little across a cell on a hide.
const CELLS: usize = 96;

/// The local grain direction over a hide.
#[derive(Clone, Debug)]
pub(crate) struct DirectionField {
    min: DVec2,
    cell: DVec2,
    /// Angle (radians) per cell, row-major.
    angle: Vec<f32>,
}

impl DirectionField {
    /// The field of `lines` over the box `min..max`; `None` without a usable segment.
    pub(crate) fn new(lines: &[Vec<DVec2>], min: DVec2, max: DVec2) -> Option<Self> {
        let segs: Vec<(DVec2, DVec2)> = lines
            .iter()
            .flat_map(|l| l.windows(2).map(|w| (w[0], w[1])))
            .filter(|(a, b)| (*b - *a).length() > 0.0)
            .collect();
        if segs.is_empty() {
            return None;
        }
        let size = (max - min).max(DVec2::splat(1e-9));
        let cell = size / CELLS as f64;
        // softening: a fraction of a cell, so a cell on a line takes that line's direction
        let soft2 = (0.25 * cell.length()).powi(2);
        let mut angle = Vec::with_capacity(CELLS * CELLS);
        for j in 0..CELLS {
            for i in 0..CELLS {
                let p = min + DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * cell;
                let mut acc = DVec2::ZERO;
                for (a, b) in &segs {
                    let d = *b - *a;
                    let t = ((p - *a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                    let dist2 = (*a + d * t).distance_squared(p);
                    acc += d.normalize() / (dist2 + soft2);
                }
                angle.push(acc.y.atan2(acc.x) as f32);
            }
        }
        Some(Self { min, cell, angle })
    }

    /// The local grain direction at `p` (radians).
    pub(crate) fn at(&self, p: (f32, f32)) -> f32 {
        let i = (((p.0 as f64 - self.min.x) / self.cell.x).floor() as isize)
            .clamp(0, CELLS as isize - 1) as usize;
        let j = (((p.1 as f64 - self.min.y) / self.cell.y).floor() as isize)
            .clamp(0, CELLS as isize - 1) as usize;
        self.angle[j * CELLS + i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_the_nearest_line() {
        let lines = vec![
            vec![DVec2::new(0., 10.), DVec2::new(100., 10.)],
            vec![DVec2::new(50., 60.), DVec2::new(50., 100.)],
        ];
        let f = DirectionField::new(&lines, DVec2::ZERO, DVec2::splat(100.)).unwrap();
        assert!(f.at((20.0, 12.0)).abs() < 0.05);
        assert!((f.at((52.0, 90.0)) - std::f32::consts::FRAC_PI_2).abs() < 0.05);
    }
}
