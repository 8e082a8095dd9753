//! Conjugate gradients preconditioned by an approximate inverse: what turns a single-precision
//! Cholesky factor into double-precision solutions ([`crate::sparse::SpdSolver`] on large
//! systems).
//!
//! Written here rather than taken from a crate: the loop is twenty lines, and it must run on
//! faer's factor in the solver's own order, with fixed-order sums for bit-identical results.
//!
//! The preconditioner (a triangular solve in f32) is not exactly the same linear map from one
//! application to the next, so the step uses the Polak–Ribière form of β (flexible CG), which
//! keeps the convergence of CG where the plain form can stall on such a preconditioner.

/// Solves `A x = b` for a symmetric positive definite `A` given as the product `mul(v, out)`
/// (`out = A v`), with `precondition(r, out)` (`out ≈ A⁻¹ r`), starting from `x = 0`. Ends when
/// the residual is at most `tol·‖b‖`: `Some(iterations)`. `None` when `max_iter` iterations did
/// not get there, or the recurrence broke down (a non-positive or non-finite curvature); `x`
/// then holds the last iterate.
pub fn preconditioned_cg(
    b: &[f64],
    x: &mut [f64],
    mul: impl Fn(&[f64], &mut [f64]),
    precondition: impl Fn(&[f64], &mut [f64]),
    tol: f64,
    max_iter: usize,
) -> Option<usize> {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    let target = tol * norm(b);
    if target == 0.0 {
        return Some(0);
    }
    let mut r = b.to_vec();
    let mut z = vec![0.0; n];
    precondition(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut q = vec![0.0; n];
    for it in 1..=max_iter {
        mul(&p, &mut q);
        let pq = dot(&p, &q);
        if !(pq > 0.0 && rz.is_finite()) {
            return None;
        }
        let alpha = rz / pq;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        if norm(&r) <= target {
            return Some(it);
        }
        precondition(&r, &mut z);
        let rz_new = dot(&r, &z);
        // Polak–Ribière: z·(r − r_old) / rz, where r − r_old = −α q (no copy of r_old kept:
        // 8 MB at a million faces).
        let beta = (-alpha * dot(&z, &q) / rz).max(0.0);
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
        rz = rz_new;
    }
    None
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D Laplacian plus `shift` on the diagonal.
    fn laplacian(shift: f64) -> impl Fn(&[f64], &mut [f64]) {
        move |v: &[f64], out: &mut [f64]| {
            let n = v.len();
            for i in 0..n {
                let left = if i > 0 { v[i - 1] } else { 0.0 };
                let right = if i + 1 < n { v[i + 1] } else { 0.0 };
                out[i] = (2.0 + shift) * v[i] - left - right;
            }
        }
    }

    #[test]
    fn an_exact_preconditioner_solves_in_one_iteration() {
        // A = 3 I, M⁻¹ = A⁻¹.
        let b = vec![3.0, -6.0, 1.5];
        let mut x = vec![9.0; 3];
        let it = preconditioned_cg(
            &b,
            &mut x,
            |v, o| o.iter_mut().zip(v).for_each(|(o, v)| *o = 3.0 * v),
            |r, o| o.iter_mut().zip(r).for_each(|(o, r)| *o = r / 3.0),
            1e-14,
            5,
        );
        assert_eq!(it, Some(1));
        assert_eq!(x, vec![1.0, -2.0, 0.5]);
    }

    #[test]
    fn a_preconditioner_rounded_to_single_precision_reaches_double_precision() {
        // M⁻¹ = the Jacobi inverse rounded through f32 (a perturbed, slightly different map at
        // each application): CG still reaches a residual of 1e-13.
        let n = 200;
        let a = laplacian(0.01);
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let mut b = vec![0.0; n];
        a(&x_true, &mut b);
        let mut x = vec![0.0; n];
        let it = preconditioned_cg(
            &b,
            &mut x,
            &a,
            |r, o| {
                o.iter_mut()
                    .zip(r)
                    .for_each(|(o, r)| *o = f64::from((*r as f32) / 2.01f32))
            },
            1e-13,
            2000,
        )
        .expect("converges");
        assert!(it > 1);
        let mut res = vec![0.0; n];
        a(&x, &mut res);
        let r: f64 = res.iter().zip(&b).map(|(p, q)| (p - q).powi(2)).sum();
        assert!(r.sqrt() <= 1e-13 * norm(&b) * 1.01, "residual {}", r.sqrt());
        for (p, q) in x.iter().zip(&x_true) {
            assert!((p - q).abs() < 1e-8, "{p} vs {q}");
        }
    }

    #[test]
    fn too_few_iterations_and_a_zero_right_hand_side() {
        let n = 100;
        let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut x = vec![0.0; n];
        let none = |r: &[f64], o: &mut [f64]| o.copy_from_slice(r);
        assert_eq!(
            preconditioned_cg(&b, &mut x, laplacian(0.0), none, 1e-12, 3),
            None
        );
        let mut x = vec![1.0; n];
        assert_eq!(
            preconditioned_cg(&vec![0.0; n], &mut x, laplacian(0.0), none, 1e-12, 3),
            Some(0)
        );
        assert!(x.iter().all(|&v| v == 0.0));
    }
}
