//! Bernstein basis values with first and second derivatives (shared by the Bézier patches).
//!
//! The values come from the triangular recurrence `B_i^r = (1−t) B_i^{r−1} + t B_{i−1}^{r−1}`,
//! which is the de Casteljau scheme applied to the basis and is unconditionally stable on
//! `[0, 1]`; derivatives use the degree-lowered bases
//! `B_i^n' = n (B_{i−1}^{n−1} − B_i^{n−1})`.

/// Fills `b[0..=n]` with the Bernstein polynomials of degree `n` at `t`.
pub(crate) fn basis(n: usize, t: f64, b: &mut [f64]) {
    let s = 1.0 - t;
    b[0] = 1.0;
    for r in 1..=n {
        let mut saved = 0.0;
        for i in 0..r {
            let tmp = b[i];
            b[i] = saved + s * tmp;
            saved = t * tmp;
        }
        b[r] = saved;
    }
}

/// Values, first and second derivatives of the degree-`n` Bernstein basis at `t`.
/// Each output vector has `n + 1` entries.
pub(crate) fn basis_d2(n: usize, t: f64) -> [Vec<f64>; 3] {
    let mut b0 = vec![0.0; n + 1];
    let mut b1 = vec![0.0; n + 1];
    let mut b2 = vec![0.0; n + 1];
    basis(n, t, &mut b0);
    if n >= 1 {
        let mut low = vec![0.0; n];
        basis(n - 1, t, &mut low);
        let nf = n as f64;
        for i in 0..=n {
            let a = if i >= 1 { low[i - 1] } else { 0.0 };
            let c = if i < n { low[i] } else { 0.0 };
            b1[i] = nf * (a - c);
        }
    }
    if n >= 2 {
        let mut low = vec![0.0; n - 1];
        basis(n - 2, t, &mut low);
        let k = (n * (n - 1)) as f64;
        for i in 0..=n {
            let get = |j: isize| -> f64 {
                if j >= 0 && (j as usize) < n - 1 {
                    low[j as usize]
                } else {
                    0.0
                }
            };
            let i = i as isize;
            b2[i as usize] = k * (get(i - 2) - 2.0 * get(i - 1) + get(i));
        }
    }
    [b0, b1, b2]
}

/// The cubic Bernstein basis at `t` with first and second derivatives, without allocation.
#[inline(always)]
pub(crate) fn cubic_d1(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    let b = [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t];
    let d = [
        -3.0 * s * s,
        3.0 * s * (s - 2.0 * t),
        3.0 * t * (2.0 * s - t),
        3.0 * t * t,
    ];
    (b, d)
}

/// Second derivatives of the cubic Bernstein basis at `t`.
#[inline(always)]
pub(crate) fn cubic_d2(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [6.0 * s, 6.0 * (t - 2.0 * s), 6.0 * (s - 2.0 * t), 6.0 * t]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_fast_path_matches_general_recurrence() {
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let [b, d, dd] = basis_d2(3, t);
            let (cb, cd) = cubic_d1(t);
            let cdd = cubic_d2(t);
            for i in 0..4 {
                assert!((b[i] - cb[i]).abs() < 1e-15);
                assert!((d[i] - cd[i]).abs() < 1e-13);
                assert!((dd[i] - cdd[i]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-6;
        for n in 1..=7 {
            let t = 0.37;
            let [_, d, dd] = basis_d2(n, t);
            let [bp, dp, _] = basis_d2(n, t + h);
            let [bm, dm, _] = basis_d2(n, t - h);
            for i in 0..=n {
                assert!(
                    (d[i] - (bp[i] - bm[i]) / (2.0 * h)).abs() < 1e-7,
                    "n={n} i={i}"
                );
                assert!(
                    (dd[i] - (dp[i] - dm[i]) / (2.0 * h)).abs() < 1e-6,
                    "n={n} i={i}"
                );
            }
            let sum: f64 = basis_d2(n, t)[0].iter().sum();
            assert!((sum - 1.0).abs() < 1e-15);
        }
    }
}
