//! Where darts are needed and how much they must open, from the piece flattened as if it could
//! be darted everywhere.
//!
//! A dart removes 2D length across itself; in the limit of many thin darts the material may be
//! as long as it likes in one direction, at no cost beyond the limit. The flattening energy of
//! that limit is Duncan's δ2, except that the largest stretch continues above the stretch limit S
//! as a straight line (constant force, like a material that yields in one direction), so the map
//! stretches freely across where darts will go; the other direction cannot be darted at the same
//! place (darts do not cross), and compression below C cannot be darted at all and stays
//! penalised. The map's stretch beyond S is
//! the darts' opening, spread out: its direction (the largest stretch) is across the darts, its
//! extent inward from the outline is where the darts reach, and its sum along the outline is the
//! total opening the darts must provide at their mouths.

use flatcut_flatten::nonlinear::kernel::{IsoEnergy, RestTri, singular_values};
use flatcut_geom::DVec2;

use crate::band::Band;

/// Curvature kept beyond the yield point, relative to δ2's there: keeps Newton's system regular
/// where the material yields.
const YIELD_STIFFNESS: f64 = 0.01;
/// Weight of the compression penalty below C, relative to δ2's density.
const COMPRESS_PENALTY: f64 = 100.0;

/// The yielding energy of the dart limit (see the module doc).
#[derive(Clone, Copy, Debug)]
pub struct Yield {
    /// S, the largest stretch factor before the material yields (1 + stretch %/100).
    pub s_max: f64,
    /// C, the smallest stretch factor (1 − compression %/100); below it compression is
    /// penalised.
    pub s_min: f64,
}

impl Yield {
    /// The yielding energy of the limits `band`.
    pub fn new(band: Band) -> Self {
        Self {
            s_max: band.s_max(),
            s_min: band.s_min(),
        }
    }

    /// δ2's part for one singular value, ½(σ² + σ⁻² − 2), and its first two derivatives.
    fn d2(s: f64) -> (f64, f64, f64) {
        (
            0.5 * (s * s + 1.0 / (s * s) - 2.0),
            s - 1.0 / (s * s * s),
            1.0 + 3.0 / (s * s * s * s),
        )
    }

    /// The largest singular value's part: δ2's below S, yielding above.
    fn g(&self, s: f64) -> (f64, f64, f64) {
        if s > self.s_max {
            let (f0, f1, f2) = Self::d2(self.s_max);
            let u = s - self.s_max;
            return (
                f0 + f1 * u + 0.5 * YIELD_STIFFNESS * f2 * u * u,
                f1 + YIELD_STIFFNESS * f2 * u,
                YIELD_STIFFNESS * f2,
            );
        }
        self.f(s)
    }

    /// The smallest singular value's part: δ2's, with the compression penalty below C.
    fn f(&self, s: f64) -> (f64, f64, f64) {
        let (mut v, mut d1, mut d2) = Self::d2(s);
        if s < self.s_min {
            let u = self.s_min - s;
            v += COMPRESS_PENALTY * u * u;
            d1 -= 2.0 * COMPRESS_PENALTY * u;
            d2 += 2.0 * COMPRESS_PENALTY;
        }
        (v, d1, d2)
    }
}

impl IsoEnergy for Yield {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        if s2.is_nan() || s2 <= 0.0 {
            return f64::INFINITY;
        }
        self.g(s1).0 + self.f(s2).0
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        [self.g(s1).1, self.f(s2).1]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        [[self.g(s1).2, 0.0], [0.0, self.f(s2).2]]
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// The opening a dart field must provide, per face: the relative stretch beyond S, (σ1/S − 1)₊.
pub fn face_opening(rest: &[RestTri], x: &[DVec2], s_max: f64) -> Vec<f64> {
    rest.iter()
        .map(|r| {
            let (s1, _) = singular_values(r.jacobian(x));
            (s1 / s_max - 1.0).max(0.0)
        })
        .collect()
}

/// The opening demanded along a boundary loop: per boundary edge (from `lp[i]` to `lp[i+1]`),
/// how much longer it is in 2D than the stretch limit allows (mm).
pub fn rim_demand(
    positions: &[flatcut_geom::DVec3],
    x: &[DVec2],
    lp: &[u32],
    s_max: f64,
) -> Vec<f64> {
    let n = lp.len();
    (0..n)
        .map(|i| {
            let (a, b) = (lp[i] as usize, lp[(i + 1) % n] as usize);
            (x[a].distance(x[b]) - s_max * positions[a].distance(positions[b])).max(0.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yield_energy_is_c1_and_its_derivatives_agree() {
        let y = Yield::new(Band::from_pct(Some(3.0), Some(3.0)));
        let h = 1e-6;
        for s in [0.9, 0.98, 1.0, 1.029, 1.031, 1.2] {
            let (_, d1, d2) = y.g(s);
            let fd1 = (y.g(s + h).0 - y.g(s - h).0) / (2.0 * h);
            let fd2 = (y.g(s + h).1 - y.g(s - h).1) / (2.0 * h);
            assert!((d1 - fd1).abs() < 1e-6, "{s}: {d1} {fd1}");
            assert!(
                (d2 - fd2).abs() < 1e-4 * (1.0 + d2.abs()),
                "{s}: {d2} {fd2}"
            );
        }
        // Continuous first derivative at the yield point.
        let s = y.s_max;
        assert!((y.g(s - 1e-9).1 - y.g(s + 1e-9).1).abs() < 1e-6);
    }
}
