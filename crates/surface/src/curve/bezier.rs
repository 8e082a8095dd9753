//! Bézier curves of any degree: de Casteljau evaluation, derivatives and hodograph, subdivision,
//! degree elevation, blossoms, power-basis conversion and interpolation (digest A1–A7).
//!
//! Written here rather than taken from kurbo because kurbo's curves are planar and fixed-degree
//! (quadratic/cubic); flatcut needs 3D curves of arbitrary degree as boundaries of patches.

use glam::DVec3;

use crate::{ParamCurve, SurfaceError};

/// Control-point count up to which evaluation works in a stack buffer (degree ≤ 15); higher
/// degrees copy to the heap.
const STACK_POINTS: usize = 16;
/// Control points of a cubic: the common case gets the smallest buffer (less to initialise).
const CUBIC_POINTS: usize = 4;

/// Runs `f` on a mutable copy of `pts`, on the stack when it is small enough.
#[inline]
pub(crate) fn with_scratch<R>(pts: &[DVec3], f: impl FnOnce(&mut [DVec3]) -> R) -> R {
    if pts.len() <= CUBIC_POINTS {
        let mut a = [DVec3::ZERO; CUBIC_POINTS];
        a[..pts.len()].copy_from_slice(pts);
        f(&mut a[..pts.len()])
    } else if pts.len() <= STACK_POINTS {
        let mut a = [DVec3::ZERO; STACK_POINTS];
        a[..pts.len()].copy_from_slice(pts);
        f(&mut a[..pts.len()])
    } else {
        let mut v = pts.to_vec();
        f(&mut v)
    }
}

/// de Casteljau in place: on return `b[0]` is the point at `t`.
#[inline]
fn casteljau_in_place(b: &mut [DVec3], t: f64) {
    let s = 1.0 - t;
    let n = b.len();
    for l in 1..n {
        for i in 0..n - l {
            b[i] = s * b[i] + t * b[i + 1];
        }
    }
}

/// Binomial coefficient as f64 (exact up to n ≈ 50, far beyond useful Bézier degrees).
pub(crate) fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let k = k.min(n - k);
    let mut c = 1.0;
    for i in 0..k {
        c = c * (n - i) as f64 / (i + 1) as f64;
    }
    c.round()
}

/// Checks that every point is finite; `what` names the element in the error.
pub(crate) fn check_finite(points: &[DVec3], what: &'static str) -> Result<(), SurfaceError> {
    match points.iter().position(|p| !flatcut_geom::finite3(*p)) {
        Some(index) => Err(SurfaceError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// A polynomial Bézier curve `r(t) = Σ b_i B_i^n(t)`, `t ∈ [0, 1]`, of degree `n = points − 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Bezier {
    points: Vec<DVec3>,
}

impl Bezier {
    /// Builds a Bézier curve from its control points (at least one, all finite).
    pub fn new(points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        if points.is_empty() {
            return Err(SurfaceError::ControlPointCount {
                expected: 1,
                got: 0,
            });
        }
        check_finite(&points, "control point")?;
        Ok(Self { points })
    }

    /// Wraps control points already known to be finite and non-empty.
    pub(crate) fn from_points_unchecked(points: Vec<DVec3>) -> Self {
        debug_assert!(!points.is_empty());
        Self { points }
    }

    /// The control points `b_0..b_n`.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The polynomial degree `n`.
    pub fn degree(&self) -> usize {
        self.points.len() - 1
    }

    /// The hodograph: the derivative curve, of degree `n − 1` with control points `n Δb_i`
    /// (a single zero point for a degree-0 curve).
    pub fn hodograph(&self) -> Bezier {
        let n = self.degree();
        if n == 0 {
            return Bezier {
                points: vec![DVec3::ZERO],
            };
        }
        let points = self
            .points
            .windows(2)
            .map(|w| n as f64 * (w[1] - w[0]))
            .collect();
        Bezier { points }
    }

    /// Splits at `t` into the curves on `[0, t]` and `[t, 1]`, each reparametrised to `[0, 1]`
    /// (the outer edges of the de Casteljau triangle).
    pub fn subdivide(&self, t: f64) -> (Bezier, Bezier) {
        let n = self.points.len();
        let mut left = Vec::with_capacity(n);
        let mut right = vec![DVec3::ZERO; n];
        let mut b = self.points.clone();
        let s = 1.0 - t;
        left.push(b[0]);
        right[n - 1] = b[n - 1];
        for l in 1..n {
            for i in 0..n - l {
                b[i] = s * b[i] + t * b[i + 1];
            }
            left.push(b[0]);
            right[n - 1 - l] = b[n - 1 - l];
        }
        (Bezier { points: left }, Bezier { points: right })
    }

    /// The same curve restricted to `[a, b]` and reparametrised to `[0, 1]`:
    /// control points `f(a^{n−k}, b^k)` of the blossom (digest A4).
    pub fn subsegment(&self, a: f64, b: f64) -> Bezier {
        let n = self.degree();
        let mut args = vec![a; n];
        let points = (0..=n)
            .map(|k| {
                if k > 0 {
                    args[n - k] = b;
                }
                self.blossom_unchecked(&args)
            })
            .collect();
        Bezier { points }
    }

    /// Degree elevation: the same curve with one more control point (digest A5).
    pub fn elevate(&self) -> Bezier {
        let n = self.degree();
        let m = (n + 1) as f64;
        let mut points = Vec::with_capacity(n + 2);
        points.push(self.points[0]);
        for k in 1..=n {
            let a = k as f64 / m;
            points.push(a * self.points[k - 1] + (1.0 - a) * self.points[k]);
        }
        points.push(self.points[n]);
        Bezier { points }
    }

    /// The same curve traversed backwards (`t ↦ 1 − t`).
    pub fn reversed(&self) -> Bezier {
        let mut points = self.points.clone();
        points.reverse();
        Bezier { points }
    }

    /// The blossom (polar form) `f(t_1, …, t_n)`: symmetric, multi-affine, equal to the curve on
    /// the diagonal; `f(0^{n−k}, 1^k) = b_k` (digest A6). `args` must hold exactly `n` values.
    pub fn blossom(&self, args: &[f64]) -> Result<DVec3, SurfaceError> {
        if args.len() != self.degree() {
            return Err(SurfaceError::BlossomArity {
                degree: self.degree(),
                got: args.len(),
            });
        }
        if let Some(i) = args.iter().position(|a| !a.is_finite()) {
            return Err(SurfaceError::NonFinite {
                what: "blossom argument",
                index: i,
            });
        }
        Ok(self.blossom_unchecked(args))
    }

    fn blossom_unchecked(&self, args: &[f64]) -> DVec3 {
        with_scratch(&self.points, |b| {
            let n = b.len();
            for l in 1..n {
                let t = args[l - 1];
                let s = 1.0 - t;
                for i in 0..n - l {
                    b[i] = s * b[i] + t * b[i + 1];
                }
            }
            b[0]
        })
    }

    /// Power-basis coefficients `a_j` with `r(t) = Σ a_j t^j`: `a_j = C(n, j) Δ^j b_0`.
    pub fn to_power(&self) -> Vec<DVec3> {
        let n = self.degree();
        let mut diff = self.points.clone();
        let mut out = Vec::with_capacity(n + 1);
        for j in 0..=n {
            out.push(binomial(n, j) * diff[0]);
            for i in 0..n - j {
                diff[i] = diff[i + 1] - diff[i];
            }
        }
        out
    }

    /// The Bézier form of the polynomial `Σ a_j t^j`:
    /// `b_i = Σ_{j ≤ i} C(i, j) / C(n, j) a_j` (digest A1 monomial ↔ Bernstein).
    pub fn from_power(coeffs: &[DVec3]) -> Result<Bezier, SurfaceError> {
        if coeffs.is_empty() {
            return Err(SurfaceError::ControlPointCount {
                expected: 1,
                got: 0,
            });
        }
        check_finite(coeffs, "power coefficient")?;
        Ok(Self::from_power_unchecked(coeffs))
    }

    /// [`Bezier::from_power`] for non-empty coefficients already known to be finite.
    pub(crate) fn from_power_unchecked(coeffs: &[DVec3]) -> Bezier {
        let n = coeffs.len() - 1;
        let points = (0..=n)
            .map(|i| {
                (0..=i).fold(DVec3::ZERO, |acc, j| {
                    acc + (binomial(i, j) / binomial(n, j)) * coeffs[j]
                })
            })
            .collect();
        Bezier { points }
    }

    /// The Bézier curve of degree `points.len() − 1` that passes through `points[i]` at parameter
    /// `params[i]` (Bernstein–Vandermonde system, solved by LU with partial pivoting).
    /// Parameters must be distinct; `[0, 1]` is the natural range.
    pub fn interpolate(points: &[DVec3], params: &[f64]) -> Result<Bezier, SurfaceError> {
        if points.is_empty() {
            return Err(SurfaceError::ControlPointCount {
                expected: 1,
                got: 0,
            });
        }
        if params.len() != points.len() {
            return Err(SurfaceError::BezierParamCount {
                points: points.len(),
                params: params.len(),
            });
        }
        check_finite(points, "interpolated point")?;
        if let Some(i) = params.iter().position(|a| !a.is_finite()) {
            return Err(SurfaceError::NonFinite {
                what: "interpolation parameter",
                index: i,
            });
        }
        let m = points.len();
        let n = m - 1;
        let a = nalgebra::DMatrix::from_fn(m, m, |r, c| {
            let t = params[r];
            binomial(n, c) * t.powi(c as i32) * (1.0 - t).powi((n - c) as i32)
        });
        let rhs = nalgebra::DMatrix::from_fn(m, 3, |r, c| points[r][c]);
        let lu = a.lu();
        let sol = lu
            .solve(&rhs)
            .ok_or(SurfaceError::BezierInterpolationSingular)?;
        let out: Vec<DVec3> = (0..m)
            .map(|r| DVec3::new(sol[(r, 0)], sol[(r, 1)], sol[(r, 2)]))
            .collect();
        check_finite(&out, "interpolating control point")?;
        Ok(Bezier { points: out })
    }

    /// Gravesen's arc-length estimate `(2ℓ_c + (n − 1)ℓ_p)/(n + 1)` from the chord `ℓ_c` and the
    /// control-polygon length `ℓ_p` (digest A18; exact for straight lines, error O(h⁴) under
    /// subdivision). For a cheap bound; [`crate::curve::CurveExt::arclen`] is accurate.
    pub fn arclen_estimate(&self) -> f64 {
        let n = self.degree() as f64;
        let lc = self.points[0].distance(self.points[self.points.len() - 1]);
        (2.0 * lc + (n - 1.0) * self.polygon_length()) / (n + 1.0)
    }

    /// Length of the control polygon (an upper bound of the arc length).
    pub fn polygon_length(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

impl ParamCurve for Bezier {
    fn domain(&self) -> (f64, f64) {
        (0.0, 1.0)
    }

    fn eval(&self, t: f64) -> DVec3 {
        let s = 1.0 - t;
        match *self.points.as_slice() {
            // Unrolled de Casteljau for the common low degrees (same operations, same rounding).
            [a] => a,
            [a, b] => s * a + t * b,
            [a, b, c] => {
                let (ab, bc) = (s * a + t * b, s * b + t * c);
                s * ab + t * bc
            }
            [a, b, c, d] => {
                let (ab, bc, cd) = (s * a + t * b, s * b + t * c, s * c + t * d);
                let (abc, bcd) = (s * ab + t * bc, s * bc + t * cd);
                s * abc + t * bcd
            }
            _ => with_scratch(&self.points, |b| {
                casteljau_in_place(b, t);
                b[0]
            }),
        }
    }

    /// `r^{(k)}(t) = n!/(n−k)! Σ Δ^k b_i B_i^{n−k}(t)` (digest A3).
    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        let n = self.degree();
        if k > n {
            return DVec3::ZERO;
        }
        if let [a, b, c, d] = *self.points.as_slice() {
            let s = 1.0 - t;
            match k {
                1 => {
                    let (d0, d1, d2) = (b - a, c - b, d - c);
                    let (e0, e1) = (s * d0 + t * d1, s * d1 + t * d2);
                    return 3.0 * (s * e0 + t * e1);
                }
                2 => {
                    let (d0, d1) = (c - 2.0 * b + a, d - 2.0 * c + b);
                    return 6.0 * (s * d0 + t * d1);
                }
                3 => return 6.0 * (d - 3.0 * c + 3.0 * b - a),
                _ => {}
            }
        }
        with_scratch(&self.points, |b| {
            let mut scale = 1.0;
            for l in 0..k {
                scale *= (n - l) as f64;
                for i in 0..n - l {
                    b[i] = b[i + 1] - b[i];
                }
            }
            let m = n - k + 1;
            casteljau_in_place(&mut b[..m], t);
            scale * b[0]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v2(x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, 0.0)
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).abs().max_element() <= tol
    }

    fn tv1() -> Bezier {
        Bezier::new(vec![v2(0., 0.), v2(1., 2.), v2(4., 2.), v2(6., 0.)]).unwrap()
    }

    #[test]
    fn tv1_values_derivatives_power_form() {
        let c = tv1();
        assert!(close(c.eval(0.25), v2(1.078125, 1.125), 1e-15));
        assert!(close(c.eval(0.5), v2(2.625, 1.5), 1e-15));
        assert!(close(c.deriv(0.5, 1), v2(6.75, 0.0), 1e-14));
        assert!(close(c.deriv(0.5, 2), v2(3.0, -12.0), 1e-14));
        assert!(close(c.deriv(0.0, 2), v2(12.0, -12.0), 1e-14));
        // Hermite data (errata E14: r'(1) = (6, −6)).
        assert!(close(c.deriv(0.0, 1), v2(3.0, 6.0), 1e-14));
        assert!(close(c.deriv(1.0, 1), v2(6.0, -6.0), 1e-14));
        assert!(close(c.eval(1.0), v2(6.0, 0.0), 0.0));
        let pw = c.to_power();
        let want = [v2(0., 0.), v2(3., 6.), v2(6., -6.), v2(-3., 0.)];
        for (a, b) in pw.iter().zip(want) {
            assert!(close(*a, b, 1e-14));
        }
        let back = Bezier::from_power(&pw).unwrap();
        for (a, b) in back.points().iter().zip(c.points()) {
            assert!(close(*a, *b, 1e-14));
        }
        assert_eq!(c.deriv(0.3, 4), DVec3::ZERO);
        assert!(close(c.deriv(0.3, 3), 6.0 * v2(-3.0, 0.0), 1e-13));
    }

    #[test]
    fn tv1_split_and_elevate() {
        let (l, r) = tv1().subdivide(0.5);
        let wl = [v2(0., 0.), v2(0.5, 1.), v2(1.5, 1.5), v2(2.625, 1.5)];
        let wr = [v2(2.625, 1.5), v2(3.75, 1.5), v2(5., 1.), v2(6., 0.)];
        for i in 0..4 {
            assert!(close(l.points()[i], wl[i], 1e-15));
            assert!(close(r.points()[i], wr[i], 1e-15));
        }
        let e = tv1().elevate();
        let we = [
            v2(0., 0.),
            v2(0.75, 1.5),
            v2(2.5, 2.),
            v2(4.5, 1.5),
            v2(6., 0.),
        ];
        for i in 0..5 {
            assert!(close(e.points()[i], we[i], 1e-15));
        }
        // G's control-polygon length (ℓp of TV1) and arc-length estimate.
        assert!((tv1().polygon_length() - 8.064495102).abs() < 1e-9);
        assert!((tv1().arclen_estimate() - 7.032247551).abs() < 1e-9);
        let (l, r) = tv1().subdivide(0.5);
        let (ll, lr) = l.subdivide(0.5);
        let (rl, rr) = r.subdivide(0.5);
        let refined: f64 = [ll, lr, rl, rr].iter().map(Bezier::arclen_estimate).sum();
        assert!((refined - 6.979054670).abs() < 2e-3, "{refined}");
    }

    #[test]
    fn tv2_elevation() {
        let c = Bezier::new(vec![v2(0., 0.), v2(1., 2.), v2(3., 2.), v2(2., 0.)]).unwrap();
        let e = c.elevate();
        let want = [
            v2(0., 0.),
            v2(0.75, 1.5),
            v2(2., 2.),
            v2(2.75, 1.5),
            v2(2., 0.),
        ];
        for i in 0..5 {
            assert!(close(e.points()[i], want[i], 1e-15));
        }
        let pw = e.to_power();
        assert!(close(pw[1], v2(3., 6.), 1e-14));
        assert!(close(pw[2], v2(3., -6.), 1e-14));
        assert!(close(pw[3], v2(-4., 0.), 1e-14));
        assert!(close(pw[4], DVec3::ZERO, 1e-14));
    }

    fn tv3() -> Bezier {
        Bezier::new(vec![
            DVec3::new(0., 1., 1.),
            DVec3::new(1., 1., 0.),
            DVec3::new(4., 2., 0.),
            DVec3::new(6., 1., 1.),
        ])
        .unwrap()
    }

    #[test]
    fn tv3_split_at_one_third() {
        let (l, r) = tv3().subdivide(1.0 / 3.0);
        let n9 = |x: f64, y: f64, z: f64| DVec3::new(x / 9.0, y / 9.0, z / 9.0);
        assert!(close(
            l.points()[1],
            DVec3::new(1. / 3., 1., 2. / 3.),
            1e-15
        ));
        assert!(close(l.points()[2], n9(8., 10., 4.), 1e-15));
        assert!(close(l.points()[3], n9(14., 11., 3.), 1e-15));
        assert!(close(r.points()[1], n9(26., 13., 1.), 1e-15));
        assert!(close(
            r.points()[2],
            DVec3::new(14. / 3., 5. / 3., 1. / 3.),
            1e-15
        ));
    }

    #[test]
    fn tv4_blossom() {
        let c = tv3();
        let f = |u: f64, v: f64, w: f64| c.blossom(&[u, v, w]).unwrap();
        assert!(close(f(0., 0., 0.), DVec3::new(0., 1., 1.), 0.0));
        assert!(close(f(0., 0., 1.), DVec3::new(1., 1., 0.), 1e-15));
        assert!(close(f(0., 1., 1.), DVec3::new(4., 2., 0.), 1e-15));
        assert!(close(f(1., 1., 1.), DVec3::new(6., 1., 1.), 1e-15));
        let want = DVec3::new(2.79, 1.46, 0.13);
        for (u, v, w) in [(0.2, 0.5, 0.9), (0.9, 0.2, 0.5), (0.5, 0.9, 0.2)] {
            assert!(close(f(u, v, w), want, 1e-14));
        }
        // Closed-form blossom f_x = −3uvw + 2(uv+uw+vw) + (u+v+w).
        let (u, v, w) = (0.3, -0.4, 1.7);
        let fx = -3.0 * u * v * w + 2.0 * (u * v + u * w + v * w) + (u + v + w);
        assert!((f(u, v, w).x - fx).abs() < 1e-14);
        assert!(c.blossom(&[0.1, 0.2]).is_err());
        // Power form of TV4.
        let pw = c.to_power();
        assert!(close(pw[3], DVec3::new(-3., -3., 0.), 1e-14));
        assert!(close(pw[2], DVec3::new(6., 3., 3.), 1e-14));
        assert!(close(pw[1], DVec3::new(3., 0., -3.), 1e-14));
    }

    #[test]
    fn tv8_interpolation_and_tv9_parabola() {
        let q = [v2(0., 0.), v2(1., 1.), v2(2., 1.), v2(3., 0.)];
        let c = Bezier::interpolate(&q, &[0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]).unwrap();
        assert!(close(c.points()[1], v2(1.0, 1.5), 1e-14));
        assert!(close(c.points()[2], v2(2.0, 1.5), 1e-14));
        assert!(Bezier::interpolate(&q, &[0.0, 0.5, 0.5, 1.0]).is_err());
        // γ(t) = (t, t²): power coefficients (0,0), (1,0), (0,1).
        let p = Bezier::from_power(&[v2(0., 0.), v2(1., 0.), v2(0., 1.)]).unwrap();
        assert!(close(p.points()[1], v2(0.5, 0.0), 1e-15));
        assert!(close(p.points()[2], v2(1.0, 1.0), 1e-15));
    }

    #[test]
    fn tv5_space_cubic_derivatives() {
        let c = Bezier::new(vec![
            DVec3::ZERO,
            DVec3::new(1., 0., 0.),
            DVec3::new(2., 1., 0.),
            DVec3::new(3., 0., 1.),
        ])
        .unwrap();
        for t in [0.0, 0.3, 0.5, 1.0] {
            let want = DVec3::new(3.0 * t, 3.0 * t * t * (1.0 - t), t * t * t);
            assert!(close(c.eval(t), want, 1e-15));
            let d1 = DVec3::new(3.0, 3.0 * t * (2.0 - 3.0 * t), 3.0 * t * t);
            assert!(close(c.deriv(t, 1), d1, 1e-14));
            let d2 = DVec3::new(0.0, 6.0 - 18.0 * t, 6.0 * t);
            assert!(close(c.deriv(t, 2), d2, 1e-13));
        }
    }

    #[test]
    fn tv20_quarter_circles() {
        // Cubic: handle k = 4(√2 − 1)/3, max radius 1.00027253 at t = (3 − √3)/6.
        let k = 4.0 * (2f64.sqrt() - 1.0) / 3.0;
        let c = Bezier::new(vec![v2(1., 0.), v2(1., k), v2(k, 1.), v2(0., 1.)]).unwrap();
        let pw = c.to_power();
        assert!(close(pw[3], v2(0.3431457505, -0.3431457505), 1e-10));
        assert!(close(pw[2], v2(-1.3431457505, -0.3137084990), 1e-10));
        assert!(close(pw[1], v2(0.0, 1.6568542495), 1e-10));
        let t = (3.0 - 3f64.sqrt()) / 6.0;
        assert!((c.eval(t).length() - 1.00027253).abs() < 1e-8);
        assert!((c.eval(1.0 - t).length() - 1.00027253).abs() < 1e-8);
        // Quadratic, k = (2√2 − 1)/2: errata E21 — the worst point is the minimum radius
        // 0.9892185757 at t = (2 − √2)/4, not 0.995685.
        let k = (2.0 * 2f64.sqrt() - 1.0) / 2.0;
        let q = Bezier::new(vec![v2(1., 0.), v2(k, k), v2(0., 1.)]).unwrap();
        let (tmin, rmin) = (0..=100_000)
            .map(|i| i as f64 / 100_000.0)
            .map(|t| (t, q.eval(t).length()))
            .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        assert!((rmin - 0.9892185757).abs() < 1e-9, "{rmin}");
        assert!((tmin - (2.0 - 2f64.sqrt()) / 4.0).abs() < 1e-4, "{tmin}");
        assert!((q.eval((2.0 - 2f64.sqrt()) / 4.0).length() - 0.9892185757).abs() < 1e-10);
        assert!((q.eval(0.5).length() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn tv5_osculating_planes() {
        // Binormal ∝ (t², −t, 1 − 3t): z = 0 at t = 0, 0.25x − 0.5y − 0.5z = 0.125 at ½,
        // x − y − 2z = 1 at 1.
        use crate::curve::CurveExt;
        let c = Bezier::new(vec![
            DVec3::ZERO,
            DVec3::new(1., 0., 0.),
            DVec3::new(2., 1., 0.),
            DVec3::new(3., 0., 1.),
        ])
        .unwrap();
        for (t, n, d) in [
            (0.0, DVec3::new(0., 0., 1.), 0.0),
            (0.5, DVec3::new(0.25, -0.5, -0.5), 0.125),
            (1.0, DVec3::new(1., -1., -2.), 1.0),
        ] {
            let b = c.frenet(t).unwrap().b;
            assert!((b.cross(n.normalize())).length() < 1e-14, "t={t}");
            assert!((n.dot(c.eval(t)) - d).abs() < 1e-14);
        }
    }

    #[test]
    fn rejects_bad_input() {
        assert!(matches!(
            Bezier::new(vec![]),
            Err(SurfaceError::ControlPointCount { .. })
        ));
        assert!(matches!(
            Bezier::new(vec![DVec3::ZERO, DVec3::new(f64::NAN, 0., 0.)]),
            Err(SurfaceError::NonFinite { index: 1, .. })
        ));
    }

    #[test]
    fn high_degree_uses_heap_path_consistently() {
        let pts: Vec<DVec3> = (0..20)
            .map(|i| DVec3::new(i as f64, ((i * 7) % 5) as f64, (i % 3) as f64))
            .collect();
        let c = Bezier::new(pts).unwrap();
        let (l, _) = c.subdivide(0.4);
        assert!(close(l.eval(1.0), c.eval(0.4), 1e-12));
        let h = 1e-6;
        let fd = (c.eval(0.3 + h) - c.eval(0.3 - h)) / (2.0 * h);
        assert!(close(c.deriv(0.3, 1), fd, 1e-5 * fd.length().max(1.0)));
        assert!(close(c.hodograph().eval(0.3), c.deriv(0.3, 1), 1e-9));
    }

    fn arb_curve() -> impl Strategy<Value = Bezier> {
        proptest::collection::vec((-10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0), 1..9).prop_map(
            |v| Bezier::new(v.into_iter().map(|(x, y, z)| DVec3::new(x, y, z)).collect()).unwrap(),
        )
    }

    proptest! {
        #[test]
        fn subdivision_leaves_curve_unchanged(c in arb_curve(), s in 0.01f64..0.99, t in 0.0f64..1.0) {
            let (l, r) = c.subdivide(s);
            let p = c.eval(t);
            let q = if t <= s { l.eval(t / s) } else { r.eval((t - s) / (1.0 - s)) };
            prop_assert!(close(p, q, 1e-11));
            let seg = c.subsegment(0.2, 0.7);
            prop_assert!(close(seg.eval(t), c.eval(0.2 + 0.5 * t), 1e-11));
        }

        #[test]
        fn elevation_leaves_curve_unchanged(c in arb_curve(), t in 0.0f64..1.0) {
            let e = c.elevate().elevate();
            prop_assert!(close(c.eval(t), e.eval(t), 1e-11));
            prop_assert!(close(c.deriv(t, 1), e.deriv(t, 1), 1e-9));
        }

        #[test]
        fn affine_invariance(c in arb_curve(), t in 0.0f64..1.0, ang in 0.0f64..6.0) {
            let m = glam::DMat3::from_rotation_z(ang) * glam::DMat3::from_diagonal(DVec3::new(2.0, 0.5, 1.5));
            let off = DVec3::new(3.0, -1.0, 7.0);
            let mapped = Bezier::new(c.points().iter().map(|p| m * *p + off).collect()).unwrap();
            prop_assert!(close(mapped.eval(t), m * c.eval(t) + off, 1e-10));
        }

        #[test]
        fn derivatives_match_finite_differences(c in arb_curve(), t in 0.05f64..0.95) {
            let h = 1e-5;
            for k in 1..3 {
                let fd = (c.deriv(t + h, k - 1) - c.deriv(t - h, k - 1)) / (2.0 * h);
                let d = c.deriv(t, k);
                prop_assert!(close(d, fd, 1e-5 * (1.0 + d.length())), "k={} {:?} {:?}", k, d, fd);
            }
        }

        #[test]
        fn power_roundtrip(c in arb_curve(), t in 0.0f64..1.0) {
            let pw = c.to_power();
            let horner = pw.iter().rev().fold(DVec3::ZERO, |acc, a| acc * t + *a);
            prop_assert!(close(horner, c.eval(t), 1e-9));
            let back = Bezier::from_power(&pw).unwrap();
            prop_assert!(close(back.eval(t), c.eval(t), 1e-9));
        }
    }
}
