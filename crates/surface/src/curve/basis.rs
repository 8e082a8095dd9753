//! B-spline basis functions: knot-span search, Cox–de Boor values and their derivatives.
//!
//! These are the kernels of every B-spline and NURBS evaluator in flatcut (curves here, tensor
//! product surfaces in `crate::patch`). They follow the triangular schemes of Piegl & Tiller
//! (*The NURBS Book*, algorithms A2.1–A2.3) with the closed-interval convention at the right end
//! of the domain (digest A12). They write into caller-provided slices so that the hot paths
//! (degree ≤ 3) never allocate.
//!
//! Conventions: degree `p`, control points `0..n` (n of them), knots `U[0..n+p+1]`, curve domain
//! `[U[p], U[n]]`.

/// Largest degree whose scratch space lives on the stack in [`ders_basis_funs`] and the curve
/// evaluators; higher degrees fall back to a heap buffer (rare in design data).
pub const MAX_STACK_DEGREE: usize = 7;

/// Scratch length needed by [`ders_basis_funs`] for degree `p`.
pub const fn ders_scratch_len(p: usize) -> usize {
    (p + 1) * (p + 1) + 2 * (p + 1)
}

/// Returns the knot span index `i` with `U[i] ≤ t < U[i+1]` and `p ≤ i < n`, for `n` control
/// points. Parameters outside the domain are clamped to it; at the right end the last non-empty
/// span is returned (closed-interval convention).
///
/// The knot vector must be valid (non-decreasing, `n + p + 1` knots, `U[p] < U[n]`); the curve
/// constructors check that.
pub fn find_span(n: usize, p: usize, t: f64, knots: &[f64]) -> usize {
    debug_assert!(knots.len() == n + p + 1);
    if t >= knots[n] {
        // Last non-empty span: the largest i < n with U[i] < U[n].
        let mut i = n - 1;
        while i > p && knots[i] >= knots[n] {
            i -= 1;
        }
        return i;
    }
    if t <= knots[p] {
        // First non-empty span at the left end.
        let mut i = p;
        while i + 1 < n && knots[i + 1] <= knots[p] {
            i += 1;
        }
        return i;
    }
    // Binary search in [p, n): invariant U[lo] ≤ t < U[hi].
    let (mut lo, mut hi) = (p, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if t < knots[mid] {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

/// Computes the `p + 1` non-vanishing basis functions `N[span-p..=span]` of degree `p` at `t`
/// into `out[0..=p]` (Cox–de Boor triangle, without temporaries).
///
/// `out.len()` must be at least `p + 1`.
pub fn basis_funs(span: usize, t: f64, p: usize, knots: &[f64], out: &mut [f64]) {
    out[0] = 1.0;
    for j in 1..=p {
        let mut saved = 0.0;
        for r in 0..j {
            let right = knots[span + r + 1] - t;
            let left = t - knots[span + 1 + r - j];
            let denom = right + left;
            // 0/0 := 0 for repeated knots (the corresponding lower-degree function is zero).
            let temp = if denom != 0.0 { out[r] / denom } else { 0.0 };
            out[r] = saved + right * temp;
            saved = left * temp;
        }
        out[j] = saved;
    }
}

/// Computes the non-vanishing basis functions and their derivatives up to order `nd` at `t`
/// (Piegl & Tiller A2.3). On return `out[k * (p + 1) + j]` holds the `k`-th derivative of
/// `N[span - p + j]`, for `k = 0..=nd` and `j = 0..=p`; derivatives of order above `p` are zero.
///
/// `out.len() ≥ (nd + 1)(p + 1)`; `scratch.len() ≥` [`ders_scratch_len`]`(p)`.
pub fn ders_basis_funs(
    span: usize,
    t: f64,
    p: usize,
    nd: usize,
    knots: &[f64],
    out: &mut [f64],
    scratch: &mut [f64],
) {
    let w = p + 1;
    for v in out[..(nd + 1) * w].iter_mut() {
        *v = 0.0;
    }
    let (ndu, rest) = scratch.split_at_mut(w * w);
    let (a0, a1) = rest.split_at_mut(w);
    // ndu[j*w + r]: upper triangle (r ≥ j... stored as ndu[r][j] in the book) — we keep the
    // book's layout ndu[row][col] = ndu[row * w + col].
    ndu[0] = 1.0;
    for j in 1..=p {
        let mut saved = 0.0;
        for r in 0..j {
            let right = knots[span + r + 1] - t;
            let left = t - knots[span + 1 + r - j];
            // Lower triangle: knot differences.
            ndu[j * w + r] = right + left;
            let temp = if ndu[j * w + r] != 0.0 {
                ndu[r * w + (j - 1)] / ndu[j * w + r]
            } else {
                0.0
            };
            // Upper triangle: basis functions.
            ndu[r * w + j] = saved + right * temp;
            saved = left * temp;
        }
        ndu[j * w + j] = saved;
    }
    for j in 0..=p {
        out[j] = ndu[j * w + p];
    }
    let nd_eff = nd.min(p);
    for r in 0..=p {
        let (mut s1, mut s2) = (&mut *a0, &mut *a1);
        s1[0] = 1.0;
        for k in 1..=nd_eff {
            let mut d = 0.0;
            let rk = r as isize - k as isize;
            let pk = p - k;
            if r >= k {
                let rku = rk as usize;
                let den = ndu[(pk + 1) * w + rku];
                s2[0] = if den != 0.0 { s1[0] / den } else { 0.0 };
                d = s2[0] * ndu[rku * w + pk];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if (r as isize - 1) <= pk as isize {
                k - 1
            } else {
                p - r
            };
            for j in j1..=j2 {
                let idx = (rk + j as isize) as usize;
                let den = ndu[(pk + 1) * w + idx];
                s2[j] = if den != 0.0 {
                    (s1[j] - s1[j - 1]) / den
                } else {
                    0.0
                };
                d += s2[j] * ndu[idx * w + pk];
            }
            if r <= pk {
                let den = ndu[(pk + 1) * w + r];
                s2[k] = if den != 0.0 { -s1[k - 1] / den } else { 0.0 };
                d += s2[k] * ndu[r * w + pk];
            }
            out[k * w + r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    // Multiply by p!/(p-k)!.
    let mut f = p as f64;
    for k in 1..=nd_eff {
        for j in 0..=p {
            out[k * w + j] *= f;
        }
        f *= (p - k) as f64;
    }
}

/// Nonzero basis functions and their derivatives up to order `nd ≤ 2` at `t` in span `span`
/// (Piegl–Tiller A2.3). `N` is the array size and must exceed the degree.
///
/// The fixed-size twin of [`ders_basis_funs`] for the patch evaluators' hot loop: no heap, no
/// slices, so the compiler unrolls it for the small degrees of real patches.
#[inline(always)]
pub fn ders_basis_funs_fixed<const N: usize>(
    knots: &[f64],
    span: usize,
    p: usize,
    t: f64,
    nd: usize,
    ders: &mut [[f64; N]; 3],
) {
    let mut ndu = [[0.0f64; N]; N];
    let mut left = [0.0f64; N];
    let mut right = [0.0f64; N];
    ndu[0][0] = 1.0;
    for j in 1..=p {
        left[j] = t - knots[span + 1 - j];
        right[j] = knots[span + j] - t;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for j in 0..=p {
        ders[0][j] = ndu[j][p];
    }
    if nd == 0 {
        return;
    }
    let mut a = [[0.0f64; N]; 2];
    for r in 0..=p {
        let (mut s1, mut s2) = (0usize, 1usize);
        a[0][0] = 1.0;
        for k in 1..=nd.min(p) {
            let mut d = 0.0;
            let rk = r as isize - k as isize;
            let pk = p - k;
            if r >= k {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk as usize];
                d = a[s2][0] * ndu[rk as usize][pk];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if r <= pk + 1 { k - 1 } else { p - r };
            for j in j1..=j2 {
                let idx = (rk + j as isize) as usize;
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                d += a[s2][j] * ndu[idx][pk];
            }
            if r <= pk {
                a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
        for k in (p + 1)..=nd {
            ders[k][r] = 0.0;
        }
    }
    let mut f = p as f64;
    for k in 1..=nd.min(p) {
        for j in 0..=p {
            ders[k][j] *= f;
        }
        f *= (p - k) as f64;
    }
}

/// Validates a knot vector for `n` control points of degree `p`: length `n + p + 1`, finite,
/// non-decreasing, no knot of multiplicity above `p + 1`, and a non-empty domain `U[p] < U[n]`.
pub fn check_knots(n: usize, p: usize, knots: &[f64]) -> Result<(), crate::SurfaceError> {
    use crate::SurfaceError;
    if n < p + 1 {
        return Err(SurfaceError::ControlPointCount {
            expected: p + 1,
            got: n,
        });
    }
    if knots.len() != n + p + 1 {
        return Err(SurfaceError::KnotCount {
            expected: n + p + 1,
            got: knots.len(),
        });
    }
    if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
        return Err(SurfaceError::NonFinite {
            what: "knot",
            index: i,
        });
    }
    let mut mult = 1;
    for i in 1..knots.len() {
        if knots[i] < knots[i - 1] {
            return Err(SurfaceError::DecreasingKnots {
                index: i,
                prev: knots[i - 1],
                next: knots[i],
            });
        }
        mult = if knots[i] == knots[i - 1] {
            mult + 1
        } else {
            1
        };
        if mult > p + 1 {
            return Err(SurfaceError::KnotMultiplicity {
                index: i,
                knot: knots[i],
                multiplicity: mult,
                max: p + 1,
            });
        }
    }
    if knots[p] >= knots[n] {
        return Err(SurfaceError::EmptyKnotDomain {
            first: p,
            first_knot: knots[p],
            last: n,
            last_knot: knots[n],
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// TV13 knots: (0,0,0,1,2,3,3,3), degree 2, five control points.
    const TV13: [f64; 8] = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0];

    fn all_basis(t: f64, p: usize, knots: &[f64]) -> Vec<f64> {
        let n = knots.len() - p - 1;
        let span = find_span(n, p, t, knots);
        let mut out = vec![0.0; p + 1];
        basis_funs(span, t, p, knots, &mut out);
        let mut full = vec![0.0; n];
        for j in 0..=p {
            full[span - p + j] = out[j];
        }
        full
    }

    #[test]
    fn tv13_values() {
        let cases: [(f64, [f64; 5]); 5] = [
            (0.5, [0.25, 0.625, 0.125, 0.0, 0.0]),
            (1.0, [0.0, 0.5, 0.5, 0.0, 0.0]),
            (1.5, [0.0, 0.125, 0.75, 0.125, 0.0]),
            (2.5, [0.0, 0.0, 0.125, 0.625, 0.25]),
            (3.0, [0.0, 0.0, 0.0, 0.0, 1.0]),
        ];
        for (t, want) in cases {
            let got = all_basis(t, 2, &TV13);
            for i in 0..5 {
                assert!((got[i] - want[i]).abs() < 1e-15, "t={t} i={i}: {got:?}");
            }
        }
    }

    #[test]
    fn tv13_piecewise_formulas() {
        // N13 = ½(−3t²+4t) on [0,1), ½(2−t)² on [1,2); N23 = ½(−2t²+6t−3) on [1,2).
        for t in [0.1, 0.4, 0.9] {
            let b = all_basis(t, 2, &TV13);
            assert!((b[0] - (1.0 - t) * (1.0 - t)).abs() < 1e-15);
            assert!((b[1] - 0.5 * (-3.0 * t * t + 4.0 * t)).abs() < 1e-15);
            assert!((b[2] - 0.5 * t * t).abs() < 1e-15);
        }
        for t in [1.1, 1.7] {
            let b = all_basis(t, 2, &TV13);
            assert!((b[1] - 0.5 * (2.0 - t) * (2.0 - t)).abs() < 1e-15);
            assert!((b[2] - 0.5 * (-2.0 * t * t + 6.0 * t - 3.0)).abs() < 1e-14);
            assert!((b[3] - 0.5 * (t - 1.0) * (t - 1.0)).abs() < 1e-15);
        }
        for t in [2.2, 2.9] {
            let b = all_basis(t, 2, &TV13);
            assert!((b[3] - 0.5 * (-3.0 * t * t + 14.0 * t - 15.0)).abs() < 1e-14);
            assert!((b[4] - (t - 2.0) * (t - 2.0)).abs() < 1e-15);
        }
    }

    #[test]
    fn tv14_bernstein() {
        let knots = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let b = all_basis(0.3, 4, &knots);
        let want = [0.2401, 0.4116, 0.2646, 0.0756, 0.0081];
        for i in 0..5 {
            assert!((b[i] - want[i]).abs() < 1e-15, "{b:?}");
        }
    }

    #[test]
    fn find_span_handles_ends_and_repeats() {
        assert_eq!(find_span(5, 2, 0.0, &TV13), 2);
        assert_eq!(find_span(5, 2, 0.999, &TV13), 2);
        assert_eq!(find_span(5, 2, 1.0, &TV13), 3);
        assert_eq!(find_span(5, 2, 3.0, &TV13), 4);
        assert_eq!(find_span(5, 2, 7.0, &TV13), 4);
        assert_eq!(find_span(5, 2, -1.0, &TV13), 2);
        // Double interior knot: (0,0,0,1,1,2,2,2)
        let k = [0.0, 0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 2.0];
        assert_eq!(find_span(5, 2, 1.0, &k), 4);
        assert_eq!(find_span(5, 2, 0.5, &k), 2);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let knots = [0.0, 0.0, 0.0, 0.0, 0.7, 1.5, 2.0, 2.0, 3.0, 3.0, 3.0, 3.0];
        let p = 3;
        let n = knots.len() - p - 1;
        let h = 1e-5;
        for &t in &[0.2, 0.9, 1.7, 2.5] {
            let span = find_span(n, p, t, &knots);
            let mut out = vec![0.0; 4 * (p + 1)];
            let mut scratch = vec![0.0; ders_scratch_len(p)];
            ders_basis_funs(span, t, p, 3, &knots, &mut out, &mut scratch);
            let f = |x: f64| {
                let mut o = vec![0.0; p + 1];
                basis_funs(span, x, p, &knots, &mut o);
                o
            };
            let (fp, fm, f0) = (f(t + h), f(t - h), f(t));
            for j in 0..=p {
                assert!((out[j] - f0[j]).abs() < 1e-15);
                let d1 = (fp[j] - fm[j]) / (2.0 * h);
                assert!((out[(p + 1) + j] - d1).abs() < 1e-8, "d1 t={t} j={j}");
                let d2 = (fp[j] - 2.0 * f0[j] + fm[j]) / (h * h);
                assert!((out[2 * (p + 1) + j] - d2).abs() < 1e-4, "d2 t={t} j={j}");
            }
            // Derivatives of the partition of unity vanish.
            for k in 1..=3 {
                let s: f64 = out[k * (p + 1)..(k + 1) * (p + 1)].iter().sum();
                assert!(s.abs() < 1e-10, "sum of order-{k} derivatives is {s}");
            }
        }
    }

    #[test]
    fn knot_validation_names_the_problem() {
        use crate::SurfaceError;
        assert!(matches!(
            check_knots(5, 2, &[0.0, 0.0, 0.0, 1.0, 0.5, 3.0, 3.0, 3.0]),
            Err(SurfaceError::DecreasingKnots { index: 4, .. })
        ));
        assert!(matches!(
            check_knots(5, 2, &[0.0, 0.0, 1.0, 3.0, 3.0, 3.0]),
            Err(SurfaceError::KnotCount {
                expected: 8,
                got: 6
            })
        ));
        assert!(matches!(
            check_knots(5, 2, &[0.0, 0.0, 0.0, f64::NAN, 2.0, 3.0, 3.0, 3.0]),
            Err(SurfaceError::NonFinite { index: 3, .. })
        ));
        assert!(check_knots(5, 2, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 3.0]).is_err());
        assert!(check_knots(2, 2, &[0.0; 5]).is_err());
        assert!(check_knots(5, 2, &TV13).is_ok());
    }

    proptest! {
        #[test]
        fn partition_of_unity(
            p in 1usize..6,
            gaps in proptest::collection::vec(0.0f64..2.0, 1..8),
            s in 0.0f64..1.0,
        ) {
            // Clamped knot vector with the given interior gaps (zero gaps = repeated knots).
            let mut knots = vec![0.0; p + 1];
            let mut acc = 0.0;
            for g in &gaps[..gaps.len() - 1] {
                acc += g;
                knots.push(acc);
            }
            acc += gaps[gaps.len() - 1] + 0.5;
            knots.extend(std::iter::repeat_n(acc, p + 1));
            let n = knots.len() - p - 1;
            prop_assume!(check_knots(n, p, &knots).is_ok());
            let t = s * acc;
            let b = all_basis(t, p, &knots);
            let sum: f64 = b.iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-13, "sum {}", sum);
            prop_assert!(b.iter().all(|&v| v >= -1e-15));
        }
    }

    #[test]
    fn fixed_size_derivatives_equal_the_general_ones() {
        // Cubic and quadratic on a non-uniform clamped vector with a double interior knot.
        let knots = [0.0, 0.0, 0.0, 0.0, 0.2, 0.5, 0.5, 0.9, 1.0, 1.0, 1.0, 1.0];
        for p in [2usize, 3] {
            let k = &knots[3 - p..knots.len() - (3 - p)];
            let n = k.len() - p - 1;
            for i in 0..=50 {
                let t = i as f64 / 50.0;
                let span = find_span(n, p, t, k);
                let mut general = vec![0.0; 3 * (p + 1)];
                let mut scratch = vec![0.0; ders_scratch_len(p)];
                ders_basis_funs(span, t, p, 2, k, &mut general, &mut scratch);
                let mut fixed = [[0.0; 4]; 3];
                ders_basis_funs_fixed::<4>(k, span, p, t, 2, &mut fixed);
                for d in 0..3 {
                    for j in 0..=p {
                        let (a, b) = (general[d * (p + 1) + j], fixed[d][j]);
                        assert!(
                            (a - b).abs() <= 1e-12 * (1.0 + a.abs()),
                            "p {p} t {t} d {d} j {j}: {a} vs {b}"
                        );
                    }
                }
            }
        }
    }
}
