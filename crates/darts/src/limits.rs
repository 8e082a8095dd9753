//! Material limits held as hard constraints of a flattening: every face's principal stretches
//! within `[C, S]` (C = 1 − compress/100, S = 1 + stretch/100), or the proof that the solve could
//! not get there and by how much it missed.
//!
//! The measure is the face's *limit excess* in log strain,
//! e = max(ln σ1 − ln S, ln C − ln σ2): negative inside the limits, 0 on them. Two phases, both
//! flip-free projected Newton on isotropic energies of the singular values (the flattener's own
//! kernel and solver, [`flatcut_flatten::nonlinear`]):
//!
//! 1. **Reaching the limits** (the method of centres): with a wall w above the largest excess,
//!    minimise Σ A·(−ln(w − e₁(σ)) − ln(w − e₂(σ))) (+ a small δ2 term that keeps faces far from
//!    the wall well-conditioned); then lower the wall towards the new largest excess and repeat.
//!    The barrier is infinite at the wall, so the largest excess never rises; the walls converge
//!    to the smallest largest excess the cut can reach (a min-max), which is either below the
//!    target (the map is within the limits) or the figure reported when it is not.
//! 2. **Least distortion within the limits** (an interior point): Duncan's δ2 plus a vanishing
//!    barrier at the limits themselves, from the feasible map of phase 1, so the result is the
//!    least-distorted map of the cut within the limits rather than any map that meets them.
//!
//! Why not a penalty: a penalty of finite stiffness settles beyond the bound it penalises, so a
//! penalised map is never proof that the limits can be met; the barrier is.

use flatcut_flatten::Budget;
use flatcut_flatten::nonlinear::kernel::{
    IsoDerivs, IsoEnergy, Projection, RestTri, SymDirichlet, TriEnergy, TriEval, flip_from,
    rest_frames, singular_values, twist_from,
};
use flatcut_geom::{DMat2, DVec2};
use flatcut_mesh::TriMesh;

use crate::sewn::{Closing, EdgePairs};
use crate::solve;
use crate::threads::{ThreadBarrier, ThreadPower, Threads};

pub use crate::band::Band;

/// The limits a piece is held to: on the principal stretches (a [`Band`]: an isotropic material,
/// or the tightest of a material's directions), or per thread of a woven or knitted material
/// ([`Threads`], with the grain where it lies in the plane of the solve).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limits {
    /// Bounds on both principal stretches, whatever their direction.
    Band(Band),
    /// Bounds per thread direction (warp, weft, both biases).
    Threads(Threads),
}

impl Limits {
    /// The largest excess (log strain; negative inside the limits) of a face mapped by `f`;
    /// +∞ for a degenerate or inverted face.
    pub fn excess(&self, f: DMat2) -> f64 {
        match self {
            Limits::Band(b) => {
                if f.determinant() > 0.0 {
                    let (s1, s2) = singular_values(f);
                    b.excess(s1, s2)
                } else {
                    f64::INFINITY
                }
            }
            Limits::Threads(t) => t.excess(f),
        }
    }

    /// The principal-stretch band the darts' demand and reach are estimated with: the band
    /// itself, or the tightest of the threads' limits (the loosest thread, a woven fabric's
    /// bias, would see no demand where the warp and the weft are far beyond theirs). The count
    /// is first estimated with [`Limits::count_band`].
    pub fn estimate_band(&self) -> Band {
        match self {
            Limits::Band(b) => *b,
            Limits::Threads(t) => t.tightest(),
        }
    }

    /// The principal-stretch band the darts' count is first estimated with: the band itself, or
    /// the loosest of the threads' limits. A dome in a woven fabric takes its curvature on the
    /// bias, so its count is near the loosest band's, far below the tightest's: the search then
    /// goes up from the first estimate until a count holds, in few attempts.
    pub fn count_band(&self) -> Band {
        match self {
            Limits::Band(b) => *b,
            Limits::Threads(t) => t.loosest(),
        }
    }

    /// True when nothing is limited.
    pub fn is_open(&self) -> bool {
        match self {
            Limits::Band(b) => b.is_open(),
            Limits::Threads(t) => t.tightest().is_open(),
        }
    }

    /// A length scale in log strain for relative tolerances: the band's, or the tightest
    /// thread's.
    fn scale(&self) -> f64 {
        match self {
            Limits::Band(b) => b.scale(),
            Limits::Threads(t) => t.tightest().scale(),
        }
    }

    /// The p-norm stand-in for the largest excess.
    fn power(&self, p: f64, reg: f64) -> LimitEnergy {
        match *self {
            Limits::Band(band) => LimitEnergy::BandPower(BandPower { band, p, reg }),
            Limits::Threads(threads) => LimitEnergy::ThreadPower(ThreadPower { threads, p, reg }),
        }
    }

    /// Log barriers at walls `wall` beyond the limits.
    fn barrier(&self, wall: f64, mu: f64, reg: f64) -> LimitEnergy {
        match *self {
            Limits::Band(band) => LimitEnergy::BandBarrier(BandBarrier {
                band,
                wall,
                mu,
                reg,
            }),
            Limits::Threads(threads) => LimitEnergy::ThreadBarrier(ThreadBarrier {
                threads,
                wall,
                mu,
                reg,
            }),
        }
    }
}

/// The energies of the limit solves, for either kind of [`Limits`].
#[derive(Clone, Copy, Debug)]
enum LimitEnergy {
    BandPower(BandPower),
    BandBarrier(BandBarrier),
    ThreadPower(ThreadPower),
    ThreadBarrier(ThreadBarrier),
}

impl TriEnergy for LimitEnergy {
    fn tri_energy(&self, r: &RestTri, x: &[DVec2]) -> f64 {
        match self {
            LimitEnergy::BandPower(e) => e.tri_energy(r, x),
            LimitEnergy::BandBarrier(e) => e.tri_energy(r, x),
            LimitEnergy::ThreadPower(e) => e.tri_energy(r, x),
            LimitEnergy::ThreadBarrier(e) => e.tri_energy(r, x),
        }
    }
    fn tri_eval(&self, r: &RestTri, x: &[DVec2], proj: Option<Projection>) -> TriEval {
        match self {
            LimitEnergy::BandPower(e) => e.tri_eval(r, x, proj),
            LimitEnergy::BandBarrier(e) => e.tri_eval(r, x, proj),
            LimitEnergy::ThreadPower(e) => e.tri_eval(r, x, proj),
            LimitEnergy::ThreadBarrier(e) => e.tri_eval(r, x, proj),
        }
    }
}

/// Target of phase 1 (log strain): the map counts as within the limits when every face's
/// excess is at most minus this, so that phase 2's wall (half of it) is strictly satisfied.
pub const FEASIBLE_MARGIN: f64 = 2e-5;
/// Phase 2's wall: the final map is at least this far inside the limits (log strain, 0.001 % of
/// stretch), so an independent check of the singular values sees it within them.
const INTERIOR_MARGIN: f64 = 1e-5;
/// Weight of δ2 in phase 1: enough to keep faces far from the wall from drifting, small against
/// the barrier's pull where it matters.
const CENTRE_REG: f64 = 1e-3;
/// Fraction of the gap between the wall and the largest excess kept when the wall is lowered.
const WALL_KEEP: f64 = 0.1;
/// First wall above the largest excess, as a fraction of the band's scale.
const FIRST_GAP: f64 = 0.05;
/// Phase 1 gives up when the largest excess improved by less than this fraction of the band's
/// scale over [`STALL_STAGES`] stages.
const STALL_REL: f64 = 2e-3;
const STALL_STAGES: usize = 3;
/// Stages of phase 1 before it stops in any case.
const MAX_STAGES: usize = 60;
/// The continuation's exponent p (in units of 1/(band scale)): POWER_RANGE·scale/(excess +
/// scale/2), so that p·excess stays about POWER_RANGE while the excess is large and grows as it
/// falls, between Q_MIN and Q_MAX; a stage whose p grew by less than Q_STEP_MIN ends it.
const POWER_RANGE: f64 = 20.0;
const Q_MIN: f64 = 2.0;
const Q_MAX: f64 = 256.0;
const Q_STEP_MIN: f64 = 0.1;
/// Most continuation stages.
const MAX_POWER_STAGES: usize = 12;
/// Newton iterations per power.
const POWER_ITERS: usize = 20;
/// Newton iterations per stage of phase 1 (each stage only needs to centre approximately).
const STAGE_ITERS: usize = 12;
/// Barrier weights of phase 2 (relative to δ2), decreasing: the last one leaves the map within
/// a fraction of a percent of the least-δ2 map under the limits.
const INTERIOR_MU: [f64; 2] = [1e-2, 1e-3];
/// Newton iterations of each phase-2 solve.
const INTERIOR_ITERS: usize = 40;

/// An isotropic energy: reg·δ2 + mu·Σ over both singular values of the log barriers of the
/// stretch and the compression wall, the walls `wall` (log strain) beyond the limits.
#[derive(Clone, Copy, Debug)]
pub struct BandBarrier {
    /// The limits.
    pub band: Band,
    /// How far beyond the limits the barriers' walls stand (log strain).
    pub wall: f64,
    /// The barriers' weight (smaller: a map closer to the walls).
    pub mu: f64,
    /// The weight of δ2.
    pub reg: f64,
}

impl BandBarrier {
    /// (value, first, second derivative) of the barrier terms of one singular value.
    #[inline]
    fn terms(&self, s: f64) -> (f64, f64, f64) {
        let (mut v, mut d1, mut d2) = (0.0, 0.0, 0.0);
        let l = s.ln();
        if self.band.ln_s.is_finite() {
            let y = self.wall + self.band.ln_s - l;
            if y.is_nan() || y <= 0.0 {
                return (f64::INFINITY, 0.0, 0.0);
            }
            v -= y.ln();
            d1 += 1.0 / (s * y);
            d2 += (1.0 - y) / (s * s * y * y);
        }
        if self.band.ln_c.is_finite() {
            let y = self.wall - self.band.ln_c + l;
            if y.is_nan() || y <= 0.0 {
                return (f64::INFINITY, 0.0, 0.0);
            }
            v -= y.ln();
            d1 -= 1.0 / (s * y);
            d2 += (1.0 + y) / (s * s * y * y);
        }
        (self.mu * v, self.mu * d1, self.mu * d2)
    }
}

/// The energy of a map whose per-face density is reg·δ2 plus a term of each singular value
/// alone (`self.terms(σ)` = value, first and second derivative), infinite on an inverted face:
/// the form both limit energies share, written once.
macro_rules! separable_iso_energy {
    ($t:ty) => {
        impl IsoEnergy for $t {
            fn psi(&self, s1: f64, s2: f64) -> f64 {
                if s2.is_nan() || s2 <= 0.0 {
                    return f64::INFINITY;
                }
                self.reg * SymDirichlet.psi(s1, s2) + self.terms(s1).0 + self.terms(s2).0
            }
            fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
                let g = SymDirichlet.grad(s1, s2);
                [
                    self.reg * g[0] + self.terms(s1).1,
                    self.reg * g[1] + self.terms(s2).1,
                ]
            }
            fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
                let h = SymDirichlet.hess(s1, s2);
                [
                    [self.reg * h[0][0] + self.terms(s1).2, 0.0],
                    [0.0, self.reg * h[1][1] + self.terms(s2).2],
                ]
            }
            fn derivs(&self, s1: f64, s2: f64) -> IsoDerivs {
                let (t1, t2) = (self.terms(s1), self.terms(s2));
                let psi = if s2.is_nan() || s2 <= 0.0 {
                    f64::INFINITY
                } else {
                    self.reg * SymDirichlet.psi(s1, s2) + t1.0 + t2.0
                };
                let g = SymDirichlet.grad(s1, s2);
                let grad = [self.reg * g[0] + t1.1, self.reg * g[1] + t2.1];
                let h = SymDirichlet.hess(s1, s2);
                let hess = [
                    [self.reg * h[0][0] + t1.2, 0.0],
                    [0.0, self.reg * h[1][1] + t2.2],
                ];
                IsoDerivs {
                    psi,
                    grad,
                    hess,
                    twist: twist_from(s1, s2, || grad, || hess),
                    flip: flip_from(s1, s2, grad),
                }
            }
            fn is_barrier(&self) -> bool {
                true
            }
        }
    };
}

separable_iso_energy!(BandBarrier);

/// A smooth stand-in for the largest excess: reg·δ2 + Σ over both singular values of
/// (σ/S)^p + (C/σ)^p, whose minimiser approaches the min-max of the excess as p grows (the sum of
/// p-th powers is dominated by the faces nearest the largest excess).
#[derive(Clone, Copy, Debug)]
pub struct BandPower {
    /// The limits.
    pub band: Band,
    /// The exponent (larger: closer to the min-max).
    pub p: f64,
    /// The weight of δ2.
    pub reg: f64,
}

/// Exponents above this make a power overflow (e^700 is near f64's largest value): such a map
/// counts as infinitely far from the limits.
const EXP_CAP: f64 = 700.0;

impl BandPower {
    #[inline]
    fn terms(&self, s: f64) -> (f64, f64, f64) {
        let (mut v, mut d1, mut d2) = (0.0, 0.0, 0.0);
        let l = s.ln();
        let p = self.p;
        if self.band.ln_s.is_finite() {
            let a = p * (l - self.band.ln_s);
            if a > EXP_CAP {
                return (f64::INFINITY, 0.0, 0.0);
            }
            let f = a.exp();
            v += f;
            d1 += p * f / s;
            d2 += p * (p - 1.0) * f / (s * s);
        }
        if self.band.ln_c.is_finite() {
            let a = p * (self.band.ln_c - l);
            if a > EXP_CAP {
                return (f64::INFINITY, 0.0, 0.0);
            }
            let f = a.exp();
            v += f;
            d1 -= p * f / s;
            d2 += p * (p + 1.0) * f / (s * s);
        }
        (v, d1, d2)
    }
}

separable_iso_energy!(BandPower);

/// The largest limit excess over the faces of a map, and the face where it is.
pub fn max_excess(rest: &[RestTri], x: &[DVec2], limits: &Limits) -> (f64, usize) {
    let mut best = (f64::NEG_INFINITY, 0usize);
    for (t, r) in rest.iter().enumerate() {
        let e = limits.excess(r.jacobian(x));
        if e > best.0 || e.is_nan() {
            best = (if e.is_nan() { f64::INFINITY } else { e }, t);
        }
    }
    best
}

/// Per-face limit excess (log strain) of a map.
pub fn face_excess(rest: &[RestTri], x: &[DVec2], limits: &Limits) -> Vec<f64> {
    rest.iter().map(|r| limits.excess(r.jacobian(x))).collect()
}

/// What the limit solve reached.
#[derive(Clone, Debug)]
pub struct Held {
    /// The map (flip-free): within the limits when `feasible`, else the best reached.
    pub x: Vec<DVec2>,
    /// The largest excess over the faces (log strain; negative when within the limits).
    pub excess: f64,
    /// The face with the largest excess.
    pub worst_face: usize,
    /// True when every face is within the limits (`excess` ≤ 0).
    pub feasible: bool,
    /// Newton iterations spent.
    pub iterations: usize,
}

/// Why a limit solve could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LimitError {
    /// A triangle (0-based index) has zero area on the surface.
    #[error("triangle {0} is degenerate")]
    Degenerate(usize),
    /// A triangle (0-based index) is flipped in the start map, which must be flip-free.
    #[error("the start map has an inverted triangle ({0})")]
    Inverted(usize),
    /// The Newton solve failed; the message says why.
    #[error("the solver failed: {0}")]
    Solver(String),
}

/// Brings a flip-free map `x0` of `mesh` within the limits if the solver can (phases 0–1), then
/// to the least-δ2 map within them with the paired edges of `pairs` at equal 2D lengths (phase
/// 2). When the limits cannot be reached, the best map found is returned with `feasible ==
/// false` and the excess it reached.
pub fn hold(
    mesh: &TriMesh,
    x0: &[DVec2],
    limits: &Limits,
    pairs: &EdgePairs,
    budget: &Budget,
) -> Result<Held, LimitError> {
    let held = reach(mesh, x0, limits, Effort::Full, budget)?;
    if held.feasible {
        settle(mesh, &held.x, limits, pairs, Closing::default(), budget)
    } else {
        Ok(held)
    }
}

/// How hard [`reach`] works.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effort {
    /// From any flip-free map: the whole continuation, then the method of centres.
    Full,
    /// From the map of a previous solve of a less cut piece: the sharpest stages of the
    /// continuation only, and the method of centres only when the limits are near.
    Warm,
}

/// Excess (relative to the band's scale) beyond which the method of centres is not tried: the
/// limits are clearly out of reach of this cut, and the continuation's figure is close enough
/// to the min-max to say so and where.
const CLEARLY_OUT: f64 = 0.5;

/// Phases 0 and 1: the map nearest the limits the solver finds (min-max of the excess).
pub fn reach(
    mesh: &TriMesh,
    x0: &[DVec2],
    limits: &Limits,
    effort: Effort,
    budget: &Budget,
) -> Result<Held, LimitError> {
    let rest = rest_frames(mesh).map_err(LimitError::Degenerate)?;
    let mut solves = solves(mesh, &rest, limits, budget);
    let mut x = x0.to_vec();
    let mut iterations = 0;
    let (mut e, mut worst) = max_excess(&rest, &x, limits);
    if !e.is_finite() {
        return Err(LimitError::Inverted(worst));
    }
    let scale = limits.scale();
    if limits.is_open() {
        return Ok(Held {
            x,
            excess: f64::NEG_INFINITY,
            worst_face: 0,
            feasible: true,
            iterations,
        });
    }
    // Phase 0: the p-norm continuation brings the map near the min-max quickly. Newton on
    // e^(p·excess) gains about one unit of p·excess per step far from the optimum, so p follows
    // the excess: large enough to single out the worst faces, small enough that each stage is
    // a few steps.
    let _ = effort;
    let mut last_q = 0.0;
    for _ in 0..MAX_POWER_STAGES {
        if e <= -FEASIBLE_MARGIN || budget.spent() {
            break;
        }
        let q = (POWER_RANGE * scale / (e + 0.5 * scale)).clamp(Q_MIN, Q_MAX);
        if q <= last_q * (1.0 + Q_STEP_MIN) {
            break;
        }
        last_q = q;
        let p = q / scale;
        let energy = limits.power(p, CENTRE_REG);
        let run = solves
            .newton(energy, &x, POWER_ITERS, None, SEARCH_TOLERANCE)
            .map_err(LimitError::Solver)?;
        iterations += run.iterations;
        let (e_run, w_run) = max_excess(&rest, &run.x, limits);
        if e_run <= e {
            x = run.x;
            (e, worst) = (e_run, w_run);
        }
        tracing::debug!(p, e, iterations = run.iterations, "limits: power stage");
    }
    // Phase 1: lower the wall until the largest excess is below the target or stops falling.
    let skip = e > CLEARLY_OUT * scale;
    let mut wall = e + FIRST_GAP * scale;
    let mut history: Vec<f64> = vec![e];
    for _ in 0..if skip { 0 } else { MAX_STAGES } {
        if e <= -FEASIBLE_MARGIN || budget.spent() {
            break;
        }
        let energy = limits.barrier(wall, 1.0, CENTRE_REG);
        let run = solves
            .newton(energy, &x, STAGE_ITERS, None, SEARCH_TOLERANCE)
            .map_err(LimitError::Solver)?;
        iterations += run.iterations;
        let (e_run, w_run) = max_excess(&rest, &run.x, limits);
        if e_run <= e {
            x = run.x;
            (e, worst) = (e_run, w_run);
        }
        history.push(e);
        tracing::debug!(
            wall,
            e,
            iterations = run.iterations,
            "limits: centring stage"
        );
        let k = history.len();
        if k > STALL_STAGES && history[k - 1 - STALL_STAGES] - e < STALL_REL * scale {
            break;
        }
        if out_of_reach(&history, MAX_STAGES + 1 - k) {
            break;
        }
        wall = e + WALL_KEEP * (wall - e).max(0.0) + f64::EPSILON * scale;
    }
    Ok(Held {
        x,
        excess: e,
        worst_face: worst,
        feasible: e <= -FEASIBLE_MARGIN,
        iterations,
    })
}

/// True when the largest excess (`history`, one entry per stage) cannot fall below the target
/// in the `left` stages the method of centres has left: the stages' gains shrink as the walls
/// close in, so at most the best of the last [`STALL_STAGES`] gains is still to come per stage.
/// Such a cut ends above the limits whatever the remaining stages do, and its excess is only a
/// measure for the search, which does not need it to more digits.
fn out_of_reach(history: &[f64], left: usize) -> bool {
    let k = history.len();
    if k <= STALL_STAGES {
        return false;
    }
    let e = history[k - 1];
    let pace = history[k - 1 - STALL_STAGES..]
        .windows(2)
        .map(|w| w[0] - w[1])
        .fold(0.0, f64::max);
    e - pace * left as f64 > -FEASIBLE_MARGIN
}

/// Phase 2: from a map within the limits, the least-δ2 map within them (drawn shut by
/// `closing` for a tight fit, [`crate::fit`]), with the paired edges at equal 2D lengths.
pub fn settle(
    mesh: &TriMesh,
    x0: &[DVec2],
    limits: &Limits,
    pairs: &EdgePairs,
    closing: Closing,
    budget: &Budget,
) -> Result<Held, LimitError> {
    let rest = rest_frames(mesh).map_err(LimitError::Degenerate)?;
    let mut solves = solves(mesh, &rest, limits, budget).with_closing(closing);
    let mut x = x0.to_vec();
    let mut iterations = 0;
    for (i, mu) in INTERIOR_MU.iter().enumerate() {
        let energy = limits.barrier(-INTERIOR_MARGIN, *mu, 1.0);
        // The legs are paired in the last solve only: the first brings the map near.
        let pairs = (i + 1 == INTERIOR_MU.len()).then_some(pairs);
        let run = solves
            .newton(energy, &x, INTERIOR_ITERS, pairs, FINAL_TOLERANCE)
            .map_err(LimitError::Solver)?;
        iterations += run.iterations;
        x = run.x;
    }
    let (e, worst) = max_excess(&rest, &x, limits);
    Ok(Held {
        x,
        excess: e,
        worst_face: worst,
        feasible: e <= 0.0,
        iterations,
    })
}

/// The solves of a limit solve on `mesh`: with a grain line held where the limits are a
/// material's threads anchored on the surface.
fn solves<'a>(
    mesh: &TriMesh,
    rest: &'a [RestTri],
    limits: &Limits,
    budget: &Budget,
) -> solve::Solves<'a> {
    let s = solve::Solves::new(rest, mesh.positions.len(), budget);
    match limits {
        Limits::Threads(t) => s.with_align(t.anchor_terms(mesh, rest)),
        Limits::Band(_) => s,
    }
}

/// Relative energy decrease at which the search's solves stop: the excess is resolved to far
/// better than the growth steps need.
const SEARCH_TOLERANCE: f64 = 1e-6;
/// Relative energy decrease at which the final map's solve stops (the flattener's own).
const FINAL_TOLERANCE: f64 = 1e-9;

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_check(e: &BandBarrier, s1: f64, s2: f64) {
        let h = 1e-6;
        let g = e.grad(s1, s2);
        let fd1 = (e.psi(s1 + h, s2) - e.psi(s1 - h, s2)) / (2.0 * h);
        let fd2 = (e.psi(s1, s2 + h) - e.psi(s1, s2 - h)) / (2.0 * h);
        assert!((g[0] - fd1).abs() < 1e-5 * (1.0 + fd1.abs()), "{g:?} {fd1}");
        assert!((g[1] - fd2).abs() < 1e-5 * (1.0 + fd2.abs()), "{g:?} {fd2}");
        let hs = e.hess(s1, s2);
        let fdh = (e.grad(s1 + h, s2)[0] - e.grad(s1 - h, s2)[0]) / (2.0 * h);
        assert!(
            (hs[0][0] - fdh).abs() < 1e-4 * (1.0 + fdh.abs()),
            "{hs:?} {fdh}"
        );
    }

    #[test]
    fn barrier_derivatives_match_finite_differences() {
        let band = Band::from_pct(Some(3.0), Some(3.0));
        for wall in [0.0, 0.05] {
            let e = BandBarrier {
                band,
                wall,
                mu: 0.7,
                reg: 0.3,
            };
            fd_check(&e, 1.02, 0.985);
            fd_check(&e, 1.0, 0.99);
        }
        let one_sided = BandBarrier {
            band: Band::from_pct(None, Some(0.0)),
            wall: 0.02,
            mu: 1.0,
            reg: 1.0,
        };
        fd_check(&one_sided, 1.3, 0.995);
    }

    #[test]
    fn the_centres_stop_only_where_the_best_recent_pace_cannot_reach_the_target() {
        // Too few stages to judge a pace.
        assert!(!out_of_reach(&[0.02, 0.019, 0.018], 10));
        // 1.5 % left at a best pace of 0.05 % per stage: 20 stages cannot do it, 40 can.
        let slowing = [0.0165, 0.0160, 0.0156, 0.0153, 0.0150];
        assert!(out_of_reach(&slowing, 20));
        assert!(!out_of_reach(&slowing, 40));
        // Already within the limits: never out of reach.
        assert!(!out_of_reach(&[0.001, 0.0, -0.001, -0.002], 1));
        // A stalled history (no gain at all) is out of reach as long as it is above the target.
        assert!(out_of_reach(&[0.01, 0.01, 0.01, 0.01], 1000));
    }

    #[test]
    fn the_combined_derivatives_are_the_separate_methods_bit_for_bit() {
        let band = Band::from_pct(Some(3.0), Some(3.0));
        let barrier = BandBarrier {
            band,
            wall: 0.01,
            mu: 0.7,
            reg: 0.3,
        };
        let power = BandPower {
            band,
            p: 150.0,
            reg: 1e-3,
        };
        // Inside, near the walls, at σ1 = σ2 (the twist's limit), beyond the wall, reflected.
        for (s1, s2) in [
            (1.02, 0.985),
            (1.039, 0.962),
            (1.0, 1.0),
            (1.05, 0.99),
            (1.0, -0.5),
        ] {
            for e in [&barrier as &dyn IsoEnergy, &power] {
                let d = e.derivs(s1, s2);
                let want = IsoDerivs {
                    psi: e.psi(s1, s2),
                    grad: e.grad(s1, s2),
                    hess: e.hess(s1, s2),
                    twist: e.twist(s1, s2),
                    flip: e.flip(s1, s2),
                };
                assert_eq!(format!("{d:?}"), format!("{want:?}"), "σ = ({s1}, {s2})");
            }
        }
    }

    #[test]
    fn barrier_is_infinite_beyond_its_wall() {
        let band = Band::from_pct(Some(3.0), Some(3.0));
        let e = BandBarrier {
            band,
            wall: 0.0,
            mu: 1.0,
            reg: 0.0,
        };
        assert!(e.psi(1.031, 1.0).is_infinite());
        assert!(e.psi(1.0, 0.969).is_infinite());
        assert!(e.psi(1.029, 0.971).is_finite());
        assert!((band.excess(1.03, 1.0)).abs() < 1e-15);
    }
}
