//! Allowed turns of a piece kind: a list of angles, any angle, or bands around the grain
//! direction (grain with a tolerance). On a hide with a direction field the turns are relative
//! to the local grain direction where the piece lies.

use std::f32::consts::{PI, TAU};

/// Allowed rotation angles (radians), relative to the material's grain direction.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Turns {
    /// Exactly these angles.
    Discrete(Vec<f32>),
    /// Any angle.
    Continuous,
    /// Within `half` of one of `centers`.
    Bands { centers: Vec<f32>, half: f32 },
}

/// Wraps an angle to (−π, π].
pub(crate) fn wrap(a: f32) -> f32 {
    let r = (a + PI).rem_euclid(TAU) - PI;
    if r <= -PI { r + TAU } else { r }
}

impl Turns {
    /// Angles to sample from when searching (`steps` of them for free rotation).
    pub(crate) fn sample_angles(&self, steps: usize) -> Vec<f32> {
        match self {
            Turns::Discrete(v) => v.clone(),
            Turns::Continuous => {
                let s = steps.max(1);
                (0..s).map(|i| i as f32 * TAU / s as f32).collect()
            }
            Turns::Bands { centers, .. } => centers.clone(),
        }
    }

    /// Whether the refinement may turn a piece continuously.
    pub(crate) fn can_wiggle(&self) -> bool {
        match self {
            Turns::Discrete(_) => false,
            Turns::Continuous => true,
            Turns::Bands { half, .. } => *half > 0.0,
        }
    }

    /// The allowed angle closest to `a`.
    pub(crate) fn project(&self, a: f32) -> f32 {
        match self {
            Turns::Continuous => a,
            Turns::Discrete(v) => nearest(v, a),
            Turns::Bands { centers, half } => {
                let c = nearest(centers, a);
                let d = wrap(a - c).clamp(-half, *half);
                c + d
            }
        }
    }

    /// Whether `a` is allowed, to `tol` radians.
    #[cfg(test)]
    pub(crate) fn allows(&self, a: f32, tol: f32) -> bool {
        wrap(self.project(a) - a).abs() <= tol
    }
}

fn nearest(v: &[f32], a: f32) -> f32 {
    v.iter()
        .copied()
        .min_by(|x, y| wrap(a - x).abs().total_cmp(&wrap(a - y).abs()))
        .unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_clamp_to_the_nearest_band() {
        let t = Turns::Bands {
            centers: vec![0.0, PI],
            half: 0.1,
        };
        assert!((t.project(0.05) - 0.05).abs() < 1e-6);
        assert!((t.project(0.3) - 0.1).abs() < 1e-6);
        assert!((wrap(t.project(3.0) - (PI - 0.1))).abs() < 1e-5);
        assert!((wrap(t.project(-3.0) - (PI + 0.1))).abs() < 1e-5);
        assert!(t.allows(PI + 0.05, 1e-6));
        assert!(!t.allows(1.0, 1e-3));
    }

    #[test]
    fn discrete_snaps_across_the_wrap() {
        let t = Turns::Discrete(vec![0.0, PI / 2.0]);
        assert_eq!(t.project(-0.2), 0.0);
        assert_eq!(t.project(TAU - 0.2), 0.0);
        assert_eq!(t.project(1.4), PI / 2.0);
    }
}
