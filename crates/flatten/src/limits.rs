//! Material limits that hold: the largest stretch σ1 ≤ 1 + P/100 and the largest compression
//! σ2 ≥ 1 − Q/100 of every triangle are constraints of the solve, not a cost traded against
//! distortion.
//!
//! Method (an interior-point scheme on top of the flip-free Newton solves):
//! 1. The unconstrained optimum (Duncan's δ2). If every triangle is within the limits, done.
//! 2. **Feasibility**: a quadratic penalty on the stretches beyond limits drawn a little inside
//!    the real ones ([`Limits::aim`]), its stiffness raised tenfold per stage
//!    ([`PENALTY_STIFFNESS`]), then, at the highest stiffness, the margin shrunk fivefold per
//!    stage ([`MARGIN_SHRINK`]) for thin feasible sets, until every triangle is strictly within
//!    the real limits. At that stiffness the penalty all but minimises the squared violation, so
//!    a map that still breaks a limit is the closest one found: the piece is reported as beyond
//!    its limits, with where and by how much ([`violations`]), for the caller to refuse.
//! 3. **Optimality within the limits**: from that strictly feasible map, δ2 plus a logarithmic
//!    barrier on each principal stretch ([`Barrier`]), whose weight falls by a hundred per stage
//!    ([`BARRIER_WEIGHTS`]). The barrier is infinite on the limits, so the flip-free line search
//!    never steps across one: every iterate, and the result, is within them.

use crate::internal::InternalError;
use flatcut_geom::DVec2;
use flatcut_mesh::{TriMesh, face_distortion};

use crate::nonlinear::kernel::{IsoEnergy, RestTri, SymDirichlet, WithLimits, singular_values};
use crate::{FlattenError, FlattenParams};

/// Stiffness stages of the feasibility penalty (relative to the δ2 density).
pub const PENALTY_STIFFNESS: [f64; 5] = [10.0, 1e2, 1e3, 1e4, 1e5];
/// Weights of the barrier stages (relative to the δ2 density): the result sits about weight /
/// (δ2's pull) inside an active limit, 1e-7 relative at the last stage.
pub const BARRIER_WEIGHTS: [f64; 3] = [1e-3, 1e-5, 1e-7];
/// Margin factors of the stages after the stiffness schedule: a feasible set thinner than the
/// first margin is still entered (the penalty overshoots its aim by ~1e-5 at the last stiffness).
pub const MARGIN_SHRINK: [f64; 4] = [0.2, 0.04, 0.008, 0.0016];
/// The feasibility penalty aims this fraction of the admissible band (at most of a 20 % band)
/// inside each limit, so that it ends strictly within the real ones.
const AIM_FRACTION: f64 = 0.05;
/// Widest band (stretch factor) the aim margin is taken from.
const AIM_BAND_CAP: f64 = 0.2;
/// Slack on a material limit below which a violation is round-off, not reported (as stretch
/// factor: 0.0005 %).
const REPORT_SLACK: f64 = 5e-6;

/// Material limits as bounds on the principal stretch factors: lo < σ2 ≤ σ1 < hi.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Largest stretch factor (∞ for none).
    pub hi: f64,
    /// Smallest stretch factor (0 for none).
    pub lo: f64,
}

impl Limits {
    /// The limits asked for in `params`, if any.
    pub fn of(params: &FlattenParams) -> Result<Option<Limits>, FlattenError> {
        if params.max_stretch_pct.is_none() && params.max_compress_pct.is_none() {
            return Ok(None);
        }
        let hi = params
            .max_stretch_pct
            .map_or(f64::INFINITY, |p| 1.0 + p / 100.0);
        let lo = params.max_compress_pct.map_or(0.0, |p| 1.0 - p / 100.0);
        if !(hi >= 1.0 && (0.0..=1.0).contains(&lo)) {
            return Err(FlattenError::Internal(
                InternalError::LimitsExcludeIdentity { hi, lo },
            ));
        }
        Ok(Some(Limits { hi, lo }))
    }

    /// True when every triangle's principal stretches lie strictly between the limits.
    pub fn hold(&self, rest: &[RestTri], x: &[DVec2]) -> bool {
        rest.iter().all(|r| {
            let (s1, s2) = singular_values(r.jacobian(x));
            s1 < self.hi && s2 > self.lo
        })
    }

    /// The limits the feasibility penalty aims at: drawn inside by `factor` × `AIM_FRACTION`
    /// of the band.
    pub fn aim(&self, factor: f64) -> Limits {
        let band = (self.hi - self.lo).min(AIM_BAND_CAP);
        let m = AIM_FRACTION * band * factor;
        Limits {
            hi: self.hi - m,
            lo: if self.lo > 0.0 { self.lo + m } else { 0.0 },
        }
    }
}

/// Duncan's δ2 (or another inner energy) plus a logarithmic barrier on each principal stretch:
/// μ·(−ln((hi − σ)/w) − ln((σ − lo)/w)), w = hi − lo; +∞ on and beyond a limit. A side without
/// a limit (hi = ∞, lo = 0) has no term.
#[derive(Clone, Copy, Debug)]
pub struct Barrier<E> {
    /// The energy the barrier is added to (δ2 by default).
    pub inner: E,
    /// The stretch limits the barrier keeps each principal stretch inside.
    pub limits: Limits,
    /// Barrier weight μ (relative to the inner density).
    pub mu: f64,
}

impl<E> Barrier<E> {
    fn width(&self) -> f64 {
        let Limits { hi, lo } = self.limits;
        if hi.is_finite() { hi - lo } else { 1.0 }
    }
    fn b(&self, s: f64) -> f64 {
        let Limits { hi, lo } = self.limits;
        if !(s < hi && s > lo) {
            return f64::INFINITY;
        }
        let w = self.width();
        let mut v = 0.0;
        if hi.is_finite() {
            v -= ((hi - s) / w).ln();
        }
        if lo > 0.0 {
            v -= ((s - lo) / w).ln();
        }
        self.mu * v
    }
    fn db(&self, s: f64) -> f64 {
        let Limits { hi, lo } = self.limits;
        let mut v = 0.0;
        if hi.is_finite() {
            v += 1.0 / (hi - s);
        }
        if lo > 0.0 {
            v -= 1.0 / (s - lo);
        }
        self.mu * v
    }
    fn d2b(&self, s: f64) -> f64 {
        let Limits { hi, lo } = self.limits;
        let mut v = 0.0;
        if hi.is_finite() {
            v += 1.0 / ((hi - s) * (hi - s));
        }
        if lo > 0.0 {
            v += 1.0 / ((s - lo) * (s - lo));
        }
        self.mu * v
    }
}

impl<E: IsoEnergy> IsoEnergy for Barrier<E> {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        self.inner.psi(s1, s2) + self.b(s1) + self.b(s2)
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        let g = self.inner.grad(s1, s2);
        [g[0] + self.db(s1), g[1] + self.db(s2)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        let mut h = self.inner.hess(s1, s2);
        h[0][0] += self.d2b(s1);
        h[1][1] += self.d2b(s2);
        h
    }
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        let extra = if (s1 - s2).abs() <= 1e-7 * (s1.abs() + s2.abs()) {
            self.d2b(s1)
        } else {
            (self.db(s1) - self.db(s2)) / (s1 - s2)
        };
        self.inner.twist(s1, s2) + extra
    }
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        self.inner.flip(s1, s2) + (self.db(s1) + self.db(s2)) / (s1 + s2)
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// Minimises a triangle energy from a start map (one piece, or several pieces with their seam
/// terms): the Newton solve the limit stages run.
pub(crate) trait EnergySolve {
    /// The minimiser of `energy` from `x` and the Newton iterations it took.
    fn solve<E: IsoEnergy + Copy>(
        &mut self,
        energy: E,
        x: &[DVec2],
    ) -> Result<(Vec<DVec2>, usize), FlattenError>;
    /// True once a solve stopped early (the caller's time limit) or the stage's iterations are
    /// spent: no further stage runs.
    fn stopped(&self) -> bool {
        false
    }
}

/// The result of [`enforce`]: the map (within the limits unless [`violations`] finds it beyond)
/// and the Newton iterations spent.
pub(crate) struct Enforced {
    pub x: Vec<DVec2>,
    pub iterations: usize,
}

/// Brings the δ2-optimal map `x` within the limits and optimises it there (see the module
/// documentation).
pub(crate) fn enforce<S: EnergySolve>(
    solver: &mut S,
    rest: &[RestTri],
    mut x: Vec<DVec2>,
    limits: Limits,
) -> Result<Enforced, FlattenError> {
    let mut iterations = 0;
    if limits.hold(rest, &x) {
        return Ok(Enforced { x, iterations });
    }
    let last = PENALTY_STIFFNESS[PENALTY_STIFFNESS.len() - 1];
    let stages = PENALTY_STIFFNESS
        .iter()
        .map(|&k| (k, 1.0))
        .chain(MARGIN_SHRINK.iter().map(|&f| (last, f)));
    for (k, factor) in stages {
        if solver.stopped() {
            break;
        }
        let aim = limits.aim(factor);
        let e = WithLimits {
            inner: SymDirichlet,
            s_max: aim.hi,
            s_min: aim.lo,
            k,
        };
        let (y, it) = solver.solve(e, &x)?;
        iterations += it;
        x = y;
        if limits.hold(rest, &x) {
            break;
        }
    }
    if !limits.hold(rest, &x) {
        return Ok(Enforced { x, iterations });
    }
    for mu in BARRIER_WEIGHTS {
        if solver.stopped() {
            break;
        }
        let e = Barrier {
            inner: SymDirichlet,
            limits,
            mu,
        };
        let (y, it) = solver.solve(e, &x)?;
        iterations += it;
        // The barrier keeps every accepted step within the limits; a solve that gained nothing
        // returns its start, which was within them too.
        if limits.hold(rest, &y) {
            x = y;
        }
    }
    Ok(Enforced { x, iterations })
}

/// Where the limits are not met: the count, the worst triangle of each kind, where it is on the
/// 3D surface and by how much (the same kernel as the report, `face_distortion`).
pub fn violations(mesh: &TriMesh, x: &[DVec2], limits: Limits) -> Vec<String> {
    let mut worst_stretch: Option<(usize, f64)> = None;
    let mut worst_compress: Option<(usize, f64)> = None;
    let (mut n_stretch, mut n_compress) = (0usize, 0usize);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let c3 = mesh.corners(t);
        let c2 = tri.map(|v| x[v as usize]);
        let Some(d) = face_distortion(c3, c2) else {
            continue;
        };
        if d.sigma1 > limits.hi + REPORT_SLACK {
            n_stretch += 1;
            if worst_stretch.is_none_or(|(_, s)| d.sigma1 > s) {
                worst_stretch = Some((t, d.sigma1));
            }
        }
        if d.sigma2 < limits.lo - REPORT_SLACK {
            n_compress += 1;
            if worst_compress.is_none_or(|(_, s)| d.sigma2 < s) {
                worst_compress = Some((t, d.sigma2));
            }
        }
    }
    let at = |t: usize| {
        let c = mesh.corners(t);
        (c[0] + c[1] + c[2]) / 3.0
    };
    let mut w = Vec::new();
    if let Some((t, s)) = worst_stretch {
        let p = at(t);
        w.push(format!(
            "max stretch {:.2}% cannot be met without a cut: {n_stretch} triangles beyond it; worst near ({:.2}, {:.2}, {:.2}) stretches {:.2}%",
            (limits.hi - 1.0) * 100.0,
            p.x,
            p.y,
            p.z,
            (s - 1.0) * 100.0
        ));
    }
    if let Some((t, s)) = worst_compress {
        let p = at(t);
        w.push(format!(
            "max compression {:.2}% cannot be met without a cut: {n_compress} triangles beyond it; worst near ({:.2}, {:.2}, {:.2}) compresses {:.2}%",
            (1.0 - limits.lo) * 100.0,
            p.x,
            p.y,
            p.z,
            (1.0 - s) * 100.0
        ));
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barrier_derivatives_match_finite_differences() {
        let e = Barrier {
            inner: SymDirichlet,
            limits: Limits { hi: 1.3, lo: 0.8 },
            mu: 0.1,
        };
        let h = 1e-6;
        for (s1, s2) in [(1.2, 0.9), (1.05, 0.85), (1.1, 1.0)] {
            let g = e.grad(s1, s2);
            let fd1 = (e.psi(s1 + h, s2) - e.psi(s1 - h, s2)) / (2.0 * h);
            let fd2 = (e.psi(s1, s2 + h) - e.psi(s1, s2 - h)) / (2.0 * h);
            assert!((g[0] - fd1).abs() < 1e-6 * (1.0 + fd1.abs()), "{g:?} {fd1}");
            assert!((g[1] - fd2).abs() < 1e-6 * (1.0 + fd2.abs()), "{g:?} {fd2}");
            let hs = e.hess(s1, s2);
            let fdh = (e.grad(s1 + h, s2)[0] - e.grad(s1 - h, s2)[0]) / (2.0 * h);
            assert!((hs[0][0] - fdh).abs() < 1e-5 * (1.0 + fdh.abs()));
        }
        assert!(e.psi(1.3, 1.0).is_infinite());
        assert!(e.psi(1.0, 0.8).is_infinite());
        assert!(e.psi(1.4, 1.0).is_infinite());
    }

    #[test]
    fn the_aim_lies_strictly_inside() {
        let l = Limits { hi: 1.12, lo: 0.98 };
        let a = l.aim(1.0);
        assert!(a.hi < l.hi && a.lo > l.lo && a.hi > 1.0 && a.lo < 1.0);
        let one_sided = Limits { hi: 1.05, lo: 0.0 }.aim(1.0);
        assert!(one_sided.lo == 0.0 && one_sided.hi < 1.05 && one_sided.hi > 1.0);
    }
}
