//! Small numeric kernels shared by the geometry crates: Gauss–Legendre quadrature (fixed and
//! adaptive) and a safeguarded 1D root finder.

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
}
