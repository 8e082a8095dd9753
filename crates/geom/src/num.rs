//! Small numeric kernels shared by the geometry crates: Gauss–Legendre quadrature (fixed and
//! adaptive), a safeguarded 1D root finder and golden-section minimisation.

/// Nodes and weights of the 16-point Gauss–Legendre rule on [-1, 1] (positive half; the rule is symmetric).
const GL16_X: [f64; 8] = [
    0.0950125098376374401853193,
    0.2816035507792589132304605,
    0.4580167776572273863424194,
    0.6178762444026437484466718,
    0.7554044083550030338951012,
    0.8656312023878317438804679,
    0.9445750230732325760779884,
    0.9894009349916499325961542,
];
const GL16_W: [f64; 8] = [
    0.1894506104550684962853967,
    0.1826034150449235888667637,
    0.1691565193950025381893121,
    0.1495959888165767320814835,
    0.1246289712555338720524763,
    0.0951585116824927848099251,
    0.0622535239386478928628438,
    0.0271524594117540948517806,
];

/// Integrates `f` over `[a, b]` with the 16-point Gauss–Legendre rule (exact for polynomials of degree ≤ 31).
pub fn gauss16<F: FnMut(f64) -> f64>(mut f: F, a: f64, b: f64) -> f64 {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let mut s = 0.0;
    for i in 0..8 {
        let dx = h * GL16_X[i];
        s += GL16_W[i] * (f(c - dx) + f(c + dx));
    }
    s * h
}

/// Maximum recursion depth of [`integrate`]: 2^30 subintervals is far beyond any useful accuracy.
const MAX_DEPTH: u32 = 30;

/// Adaptive Gauss–Legendre quadrature: subdivides until the 16-point rule on each interval
/// agrees within `accuracy` (absolute, distributed over subintervals) with the same rule on its
/// two halves, and returns the halves' sum.
///
/// The halving comparison replaced an 8- against 16-point comparison on the same interval: on
/// integrands with a sharp dip (the speed of a wiggly curve at a tight turn) the two rules could
/// agree by coincidence while both missed the dip, off by 2.7 × the accuracy asked for.
///
/// Cost grows roughly as `accuracy^(-1/16)` for smooth integrands.
pub fn integrate<F: FnMut(f64) -> f64>(mut f: F, a: f64, b: f64, accuracy: f64) -> f64 {
    fn rec<F: FnMut(f64) -> f64>(
        f: &mut F,
        a: f64,
        b: f64,
        whole: f64,
        acc: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let left = gauss16(&mut *f, a, m);
        let right = gauss16(&mut *f, m, b);
        let halves = left + right;
        if (halves - whole).abs() <= acc || depth >= MAX_DEPTH {
            return halves;
        }
        rec(f, a, m, left, 0.5 * acc, depth + 1) + rec(f, m, b, right, 0.5 * acc, depth + 1)
    }
    if a == b {
        return 0.0;
    }
    let whole = gauss16(&mut f, a, b);
    rec(&mut f, a, b, whole, accuracy.max(f64::EPSILON), 0)
}

/// Finds a root of `f` in `[a, b]` where `f(a)` and `f(b)` have opposite signs (or one is zero),
/// by bisection safeguarded secant steps (Illinois variant of regula falsi).
/// Returns `None` when the signs do not bracket a root.
pub fn bracket_root<F: FnMut(f64) -> f64>(
    mut f: F,
    mut a: f64,
    mut b: f64,
    x_tol: f64,
) -> Option<f64> {
    let mut fa = f(a);
    let mut fb = f(b);
    if fa == 0.0 {
        return Some(a);
    }
    if fb == 0.0 {
        return Some(b);
    }
    if fa.signum() == fb.signum() || !fa.is_finite() || !fb.is_finite() {
        return None;
    }
    let mut side = 0i8;
    for _ in 0..200 {
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !c.is_finite() || c <= a.min(b) || c >= a.max(b) {
            c = 0.5 * (a + b);
        }
        let fc = f(c);
        if fc == 0.0 || (b - a).abs() < x_tol {
            return Some(c);
        }
        if fc.signum() == fb.signum() {
            b = c;
            fb = fc;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            a = c;
            fa = fc;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
    }
    Some(0.5 * (a + b))
}

/// When a golden-section search stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GoldenStop {
    /// After this many shrinks of the bracket (each by 0.618).
    Iterations(usize),
    /// Once the bracket is no wider than this (at most [`GOLDEN_MAX_ITERS`] shrinks).
    Width(f64),
}

/// Cap on the shrinks of a [`GoldenStop::Width`] search: 0.618^200 ≈ 1e-42 of the start bracket,
/// below any f64 width, so the cap only guards a zero or NaN width.
pub const GOLDEN_MAX_ITERS: usize = 200;

/// Result of [`golden_section_min`]: the better of the two interior points and the final bracket.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GoldenMin {
    /// The better of the two interior points.
    pub x: f64,
    /// The function's value at `x`.
    pub fx: f64,
    /// The final bracket's lower end.
    pub lo: f64,
    /// The final bracket's upper end.
    pub hi: f64,
}

/// Minimises a function unimodal on `[lo, hi]` by golden-section search (on ties the left point
/// is kept). Cost: one evaluation per shrink of the bracket by 0.618.
pub fn golden_section_min<F: FnMut(f64) -> f64>(
    mut f: F,
    mut lo: f64,
    mut hi: f64,
    stop: GoldenStop,
) -> GoldenMin {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (iters, width) = match stop {
        GoldenStop::Iterations(n) => (n, 0.0),
        GoldenStop::Width(w) => (GOLDEN_MAX_ITERS, w),
    };
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iters {
        if matches!(stop, GoldenStop::Width(_)) && hi - lo <= width {
            break;
        }
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    let (x, fx) = if f1 <= f2 { (x1, f1) } else { (x2, f2) };
    GoldenMin { x, fx, lo, hi }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss16_is_exact_for_degree_31() {
        let v = gauss16(|x| x.powi(31) + x.powi(30), 0.0, 1.0);
        assert!((v - (1.0 / 32.0 + 1.0 / 31.0)).abs() < 1e-15);
    }

    #[test]
    fn adaptive_arclength_of_parabola_matches_closed_form() {
        // TV38: length of (t, t²) on [0, 1] = (2√5 + asinh 2)/4.
        let exact = (2.0 * 5f64.sqrt() + 2f64.asinh()) / 4.0;
        for acc in [1e-3, 1e-6, 1e-9, 1e-12] {
            let v = integrate(|t| (1.0 + 4.0 * t * t).sqrt(), 0.0, 1.0, acc);
            assert!((v - exact).abs() <= acc, "acc {acc}: {v} vs {exact}");
        }
    }

    #[test]
    fn root_of_cubic() {
        let r = bracket_root(|x| x * x * x - 2.0, 0.0, 2.0, 1e-14).unwrap();
        assert!((r - 2f64.cbrt()).abs() < 1e-12);
        assert!(bracket_root(|x| x * x + 1.0, -1.0, 1.0, 1e-12).is_none());
    }

    #[test]
    fn golden_section_finds_the_minimum_of_a_parabola_to_the_bracket_width() {
        let m = golden_section_min(|x| (x - 0.3).powi(2), -2.0, 5.0, GoldenStop::Width(1e-10));
        assert!(m.hi - m.lo <= 1e-10, "bracket {}..{}", m.lo, m.hi);
        assert!((m.x - 0.3).abs() < 1e-10 && m.lo <= 0.3 && 0.3 <= m.hi);
        // 40 shrinks leave 0.618^40 ≈ 4.4e-9 of the 7-wide bracket.
        let m = golden_section_min(|x| (x - 0.3).powi(2), -2.0, 5.0, GoldenStop::Iterations(40));
        let w = 7.0 * (0.5 * (5f64.sqrt() - 1.0)).powi(40);
        assert!(((m.hi - m.lo) - w).abs() < 1e-12 && (m.x - 0.3).abs() < w);
        // A minimum at the end of the bracket is approached, not missed.
        let m = golden_section_min(|x| x, 0.0, 1.0, GoldenStop::Width(1e-12));
        assert!(m.x < 1e-11 && m.fx == m.x);
        // A NaN width stops at the iteration cap rather than looping.
        let m = golden_section_min(|x| x * x, -1.0, 1.0, GoldenStop::Width(f64::NAN));
        assert!(m.hi - m.lo < 1e-30);
    }
}
