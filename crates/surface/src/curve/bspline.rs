//! B-spline and NURBS curves: de Boor evaluation, derivatives of any order (rational ones by the
//! quotient rule), Boehm knot insertion, Bézier extraction, exact circular arcs and conics
//! (digest A12–A14).
//!
//! Hand-written on top of [`super::basis`] rather than taken from `curvo`: curvo pins its own
//! nalgebra point types and churns quickly, while flatcut needs glam vectors, typed errors that
//! name the bad knot or weight, and allocation-free evaluation for degree ≤ 3.

use std::ops::{Add, Mul, Sub};

use glam::{DVec3, DVec4};

use super::basis::{
    MAX_STACK_DEGREE, basis_funs, check_knots, ders_basis_funs, ders_scratch_len, find_span,
};
use super::bezier::{Bezier, binomial, check_finite};
use super::ext::{flatten_with_breaks, nearest_from_samples};
use super::rational::RationalBezier;
use super::spline::refine;
use crate::{ParamCurve, SurfaceError};

/// Vector types the B-spline kernels work on: points (`DVec3`) and homogeneous points (`DVec4`).
pub(crate) trait Lin:
    Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self>
{
}
impl<T: Copy + Default + Add<Output = T> + Sub<Output = T> + Mul<f64, Output = T>> Lin for T {}

/// Runs `f` on a zeroed buffer of `len` elements: a `[T; S]` stack array when `len ≤ S` (sized
/// for cubics, so the hot path initialises little memory), a `[T; N]` one when `len ≤ N`, the
/// heap beyond.
#[inline]
pub(crate) fn with_buf<T: Copy + Default, const S: usize, const N: usize, R>(
    len: usize,
    f: impl FnOnce(&mut [T]) -> R,
) -> R {
    if len <= S {
        let mut a = [T::default(); S];
        f(&mut a[..len])
    } else if len <= N {
        let mut a = [T::default(); N];
        f(&mut a[..len])
    } else {
        let mut v = vec![T::default(); len];
        f(&mut v)
    }
}

/// Stack sizes for degree ≤ [`MAX_STACK_DEGREE`]: basis values, derivative table, scratch.
const STACK_BASIS: usize = MAX_STACK_DEGREE + 1;
const STACK_DERS: usize = STACK_BASIS * STACK_BASIS;
const STACK_SCRATCH: usize = ders_scratch_len(MAX_STACK_DEGREE);
/// Derivative orders computed on the stack (k < 8).
const STACK_ORDERS: usize = 8;
/// The same sizes for degree ≤ 3 and derivative order ≤ 3, the hot path.
const CUBIC_BASIS: usize = 4;
const CUBIC_DERS: usize = 16;
const CUBIC_SCRATCH: usize = ders_scratch_len(3);
const CUBIC_ORDERS: usize = 4;

/// `Σ N_j P_{span−p+j}` at `t`.
#[inline]
fn point_at<V: Lin>(p: usize, knots: &[f64], pts: &[V], t: f64) -> V {
    let n = pts.len();
    let span = find_span(n, p, t, knots);
    with_buf::<f64, CUBIC_BASIS, STACK_BASIS, _>(p + 1, |nb| {
        basis_funs(span, t, p, knots, nb);
        let mut acc = V::default();
        for j in 0..=p {
            acc = acc + pts[span - p + j] * nb[j];
        }
        acc
    })
}

/// Derivatives of orders `0..out.len()` at `t` (zero above the degree).
fn ders_at<V: Lin>(p: usize, knots: &[f64], pts: &[V], t: f64, out: &mut [V]) {
    let n = pts.len();
    let span = find_span(n, p, t, knots);
    let kmax = out.len() - 1;
    let nd = kmax.min(p);
    with_buf::<f64, CUBIC_DERS, STACK_DERS, _>((nd + 1) * (p + 1), |nders| {
        with_buf::<f64, CUBIC_SCRATCH, STACK_SCRATCH, _>(ders_scratch_len(p), |scr| {
            ders_basis_funs(span, t, p, nd, knots, nders, scr);
            for (k, o) in out.iter_mut().enumerate() {
                *o = V::default();
                if k <= nd {
                    for j in 0..=p {
                        *o = *o + pts[span - p + j] * nders[k * (p + 1) + j];
                    }
                }
            }
        })
    });
}

/// The `k`-th derivative at `t` for `k ≤ p` by differencing the `p + 1` active control points
/// `k` times (`Q^l_i = (p−l+1)(Q^{l−1}_i − Q^{l−1}_{i−1}) / (U_{i+p−l+1} − U_i)`, Piegl & Tiller
/// §3.3) and evaluating them against the degree `p − k` basis of the same span. Cheaper than the
/// full derivative table of [`ders_basis_funs`] when one order is wanted.
fn deriv_at<V: Lin>(p: usize, knots: &[f64], pts: &[V], t: f64, k: usize) -> V {
    debug_assert!(k <= p);
    let n = pts.len();
    let span = find_span(n, p, t, knots);
    let first = span - p;
    with_buf::<V, CUBIC_BASIS, STACK_BASIS, _>(p + 1, |q| {
        q.copy_from_slice(&pts[first..=span]);
        for l in 1..=k {
            let f = (p - l + 1) as f64;
            for j in (l..=p).rev() {
                let i = first + j;
                let den = knots[i + p - l + 1] - knots[i];
                // 0/0 := 0: a zero-length support means the basis function vanishes.
                q[j] = if den != 0.0 {
                    (q[j] - q[j - 1]) * (f / den)
                } else {
                    V::default()
                };
            }
        }
        with_buf::<f64, CUBIC_BASIS, STACK_BASIS, _>(p - k + 1, |nb| {
            basis_funs(span, t, p - k, knots, nb);
            let mut acc = V::default();
            for m in 0..=(p - k) {
                acc = acc + q[k + m] * nb[m];
            }
            acc
        })
    })
}

/// The knot vector of the reversed curve: `t ↦ U_0 + U_last − t`.
fn reversed_knots(knots: &[f64]) -> Vec<f64> {
    let (a, b) = (knots[0], knots[knots.len() - 1]);
    knots.iter().rev().map(|k| a + b - k).collect()
}

/// Bézier control points of each polynomial span on `[0, 1]`, from the Taylor coefficients at
/// the span start (right derivatives scaled by `h^j/j!`) converted by
/// `b_i = Σ_{j ≤ i} C(i, j)/C(p, j) a_j`.
fn span_beziers<V: Lin>(p: usize, knots: &[f64], pts: &[V]) -> Vec<Vec<V>> {
    let br = breakpoints(p, knots, pts.len());
    br.windows(2)
        .map(|w| {
            let h = w[1] - w[0];
            let mut d = vec![V::default(); p + 1];
            ders_at(p, knots, pts, w[0], &mut d);
            let mut fact = 1.0;
            let mut hp = 1.0;
            for (j, dj) in d.iter_mut().enumerate() {
                if j > 0 {
                    fact *= j as f64;
                    hp *= h;
                }
                *dj = *dj * (hp / fact);
            }
            (0..=p)
                .map(|i| {
                    (0..=i).fold(V::default(), |acc, j| {
                        acc + d[j] * (binomial(i, j) / binomial(p, j))
                    })
                })
                .collect()
        })
        .collect()
}

/// Boehm/Piegl–Tiller knot insertion (A5.1) of `t` `r` times; returns the new knots and points.
fn insert<V: Lin>(
    p: usize,
    knots: &[f64],
    pts: &[V],
    t: f64,
    r: usize,
) -> Result<(Vec<f64>, Vec<V>), SurfaceError> {
    let n = pts.len();
    if !(t > knots[p] && t < knots[n]) {
        return Err(SurfaceError::InsertOutside {
            knot: t,
            lo: knots[p],
            hi: knots[n],
        });
    }
    let k = find_span(n, p, t, knots);
    let s = knots.iter().filter(|&&u| u == t).count();
    if r + s > p {
        return Err(SurfaceError::InsertTooOften {
            knot: t,
            times: r,
            multiplicity: s,
            degree: p,
        });
    }
    if r == 0 {
        return Ok((knots.to_vec(), pts.to_vec()));
    }
    let np = n - 1;
    let mut uq = Vec::with_capacity(knots.len() + r);
    uq.extend_from_slice(&knots[..=k]);
    uq.extend(std::iter::repeat_n(t, r));
    uq.extend_from_slice(&knots[k + 1..]);
    let mut q = vec![V::default(); n + r];
    q[..=(k - p)].copy_from_slice(&pts[..=(k - p)]);
    q[(k - s + r)..=(np + r)].copy_from_slice(&pts[(k - s)..=np]);
    let mut rw: Vec<V> = (0..=(p - s)).map(|i| pts[k - p + i]).collect();
    let mut l = 0;
    for j in 1..=r {
        l = k - p + j;
        for i in 0..=(p - j - s) {
            let alpha = (t - knots[l + i]) / (knots[i + k + 1] - knots[l + i]);
            rw[i] = rw[i + 1] * alpha + rw[i] * (1.0 - alpha);
        }
        q[l] = rw[0];
        q[k + r - j - s] = rw[p - j - s];
    }
    if l + 1 < k - s {
        q[(l + 1)..(k - s)].copy_from_slice(&rw[1..(k - s - l)]);
    }
    Ok((uq, q))
}

/// A non-rational B-spline curve of degree `p` with `n` control points and `n + p + 1` knots,
/// defined on `[U[p], U[n]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct BSpline {
    degree: usize,
    knots: Vec<f64>,
    points: Vec<DVec3>,
}

impl BSpline {
    /// Builds a B-spline, validating the knot vector (count `n + degree + 1`, finite,
    /// non-decreasing, non-empty domain) and the control points (finite).
    pub fn new(degree: usize, knots: Vec<f64>, points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        check_knots(points.len(), degree, &knots)?;
        check_finite(&points, "control point")?;
        Ok(Self {
            degree,
            knots,
            points,
        })
    }

    /// A clamped B-spline with uniform interior knots (the "open uniform" knot vector of
    /// digest A12): it interpolates the first and last control point.
    pub fn clamped_uniform(degree: usize, points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        let n = points.len();
        if n < degree + 1 {
            return Err(SurfaceError::ControlPointCount {
                expected: degree + 1,
                got: n,
            });
        }
        let segs = (n - degree) as f64;
        let mut knots = vec![0.0; degree + 1];
        knots.extend((1..n - degree).map(|i| i as f64 / segs));
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Self::new(degree, knots, points)
    }

    /// A closed (periodic) uniform B-spline through the control polygon `points` taken as a loop:
    /// the first `degree` points are repeated at the end, knots are the integers, and the domain
    /// is `[0, points.len()]`. The curve is C^{degree−1} everywhere including the seam.
    pub fn periodic(degree: usize, points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        let m = points.len();
        if degree == 0 || m < degree + 1 {
            return Err(SurfaceError::ControlPointCount {
                expected: degree + 1,
                got: m,
            });
        }
        let mut pts = points.clone();
        pts.extend_from_slice(&points[..degree]);
        let nk = pts.len() + degree + 1;
        let knots = (0..nk).map(|i| i as f64 - degree as f64).collect();
        Self::new(degree, knots, pts)
    }

    /// Joins Bézier pieces of one degree into a B-spline: piece `i` covers `[breaks[i],
    /// breaks[i+1]]`, interior knots get multiplicity `p` (C⁰ in general, exact whatever the
    /// joins), and consecutive pieces must share their end point (within `join_tol` mm; the
    /// shared control point is their midpoint).
    pub fn from_beziers(
        pieces: &[Bezier],
        breaks: &[f64],
        join_tol: f64,
    ) -> Result<BSpline, SurfaceError> {
        let Some(first) = pieces.first() else {
            return Err(SurfaceError::ControlPointCount {
                expected: 1,
                got: 0,
            });
        };
        let p = first.degree();
        if p == 0 {
            return Err(SurfaceError::BadDegree {
                degree: 0,
                reason: "Bézier pieces of degree 0 cannot be joined",
            });
        }
        if breaks.len() != pieces.len() + 1 {
            return Err(SurfaceError::BreakpointCount {
                pieces: pieces.len(),
                want: pieces.len() + 1,
                got: breaks.len(),
            });
        }
        let mut points = first.points().to_vec();
        let mut knots = vec![breaks[0]; p + 1];
        for (i, pc) in pieces.iter().enumerate().skip(1) {
            if pc.degree() != p {
                return Err(SurfaceError::PieceDegree {
                    piece: i,
                    degree: pc.degree(),
                    first: p,
                });
            }
            let (end, start) = (points[points.len() - 1], pc.points()[0]);
            if end.distance(start) > join_tol {
                return Err(SurfaceError::PieceGap {
                    piece: i,
                    gap: end.distance(start),
                    previous: i - 1,
                });
            }
            let last = points.len() - 1;
            points[last] = 0.5 * (end + start);
            points.extend_from_slice(&pc.points()[1..]);
            knots.extend(std::iter::repeat_n(breaks[i], p));
        }
        knots.extend(std::iter::repeat_n(breaks[pieces.len()], p + 1));
        Self::new(p, knots, points)
    }

    /// The degree `p`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knot vector.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The control points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Derivatives of orders `0..=k` at `t` into a vector (orders above the degree are zero).
    pub fn ders(&self, t: f64, k: usize) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; k + 1];
        ders_at(self.degree, &self.knots, &self.points, t, &mut out);
        out
    }

    /// Inserts the knot `t` `times` times (Boehm); the curve is unchanged. `t` must lie inside the
    /// domain and its multiplicity must stay ≤ the degree.
    pub fn insert_knot(&self, t: f64, times: usize) -> Result<BSpline, SurfaceError> {
        let (knots, points) = insert(self.degree, &self.knots, &self.points, t, times)?;
        Ok(BSpline {
            degree: self.degree,
            knots,
            points,
        })
    }

    /// The distinct knot values inside the domain, including both ends (segment breakpoints).
    pub fn breakpoints(&self) -> Vec<f64> {
        breakpoints(self.degree, &self.knots, self.points.len())
    }

    /// Flattens within chordal tolerance `tol` (mm), starting from the knots so that no span is
    /// skipped and kinks at multiple knots become vertices.
    pub fn flatten(&self, tol: f64) -> Vec<(f64, DVec3)> {
        flatten_with_breaks(self, tol, &refine(&self.breakpoints(), 2))
    }

    /// Closest point `(t, distance)`, sampling every knot span.
    pub fn nearest(&self, p: DVec3, accuracy: f64) -> (f64, f64) {
        nearest_from_samples(
            self,
            p,
            accuracy,
            &refine(&self.breakpoints(), 4 * self.degree.max(2)),
        )
    }

    /// Splits the curve into its polynomial pieces as Bézier curves, one per non-empty knot span,
    /// each on `[0, 1]` (for SVG/G-code output and Bézier algorithms).
    pub fn to_beziers(&self) -> Vec<Bezier> {
        span_beziers(self.degree, &self.knots, &self.points)
            .into_iter()
            .map(Bezier::from_points_unchecked)
            .collect()
    }

    /// The same curve traversed backwards, on the reflected knot vector `U_0 + U_last − t`.
    pub fn reversed(&self) -> BSpline {
        let mut points = self.points.clone();
        points.reverse();
        BSpline {
            degree: self.degree,
            knots: reversed_knots(&self.knots),
            points,
        }
    }
}

fn breakpoints(p: usize, knots: &[f64], n: usize) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for &k in &knots[p..=n] {
        if out.last() != Some(&k) {
            out.push(k);
        }
    }
    out
}

impl ParamCurve for BSpline {
    fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    fn eval(&self, t: f64) -> DVec3 {
        point_at(self.degree, &self.knots, &self.points, t)
    }

    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        if k > self.degree {
            return DVec3::ZERO;
        }
        deriv_at(self.degree, &self.knots, &self.points, t, k)
    }
}

/// A NURBS curve: `r(t) = Σ w_i N_i(t) P_i / Σ w_i N_i(t)`, evaluated on homogeneous points
/// `(w_i P_i, w_i)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Nurbs {
    degree: usize,
    knots: Vec<f64>,
    points: Vec<DVec3>,
    weights: Vec<f64>,
    hom: Vec<DVec4>,
}

/// Smallest accepted NURBS weight relative to the largest: below this the homogeneous
/// denominator loses all significant digits and derivatives blow up.
const MIN_WEIGHT_RATIO: f64 = 1e-12;

impl Nurbs {
    /// Builds a NURBS curve, validating the knot vector, the control points (finite) and the
    /// weights (finite and strictly positive; one weight per control point).
    pub fn new(
        degree: usize,
        knots: Vec<f64>,
        points: Vec<DVec3>,
        weights: Vec<f64>,
    ) -> Result<Self, SurfaceError> {
        check_knots(points.len(), degree, &knots)?;
        check_finite(&points, "control point")?;
        if weights.len() != points.len() {
            return Err(SurfaceError::WeightCount {
                what: "NURBS",
                points: points.len(),
                weights: weights.len(),
            });
        }
        let wmax = weights.iter().fold(0.0f64, |a, &w| a.max(w));
        if let Some(index) = weights
            .iter()
            .position(|&w| !w.is_finite() || w <= 0.0 || w < MIN_WEIGHT_RATIO * wmax)
        {
            return Err(SurfaceError::BadWeight {
                index,
                value: weights[index],
            });
        }
        let hom = points
            .iter()
            .zip(&weights)
            .map(|(p, &w)| (*p * w).extend(w))
            .collect();
        Ok(Self {
            degree,
            knots,
            points,
            weights,
            hom,
        })
    }

    /// The conic arc from `p0` to `p2` with control point `p1` and middle weight `w` (end weights
    /// 1): an ellipse for `w < 1`, a parabola for `w = 1`, a hyperbola for `w > 1`
    /// (digest A14). For an isosceles control triangle with base angle θ and `w = cos θ` it is an
    /// exact circular arc spanning 2θ.
    pub fn conic(p0: DVec3, p1: DVec3, p2: DVec3, w: f64) -> Result<Self, SurfaceError> {
        Self::new(
            2,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![p0, p1, p2],
            vec![1.0, w, 1.0],
        )
    }

    /// An exact circular arc of `radius` around `center` in the plane of `x_axis`, `y_axis`, from
    /// angle `a0` to `a1` (radians, measured from `x_axis` towards `y_axis`; `0 < a1 − a0 ≤ 2π`,
    /// so a full circle is allowed). The arc is split into ≤ 4 quadratic pieces of at most 90°
    /// (Piegl & Tiller A7.1); the domain is `[0, 1]`.
    ///
    /// `x_axis` is normalised and `y_axis` is made orthogonal to it (Gram–Schmidt).
    pub fn circle_arc(
        center: DVec3,
        x_axis: DVec3,
        y_axis: DVec3,
        radius: f64,
        a0: f64,
        a1: f64,
    ) -> Result<Self, SurfaceError> {
        /// Slack on the 2π limit for angles computed by callers (e.g. `a0 + TAU`).
        const FULL_TURN_SLACK: f64 = 1e-12;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(SurfaceError::ArcRadius { radius });
        }
        if !(a0.is_finite() && a1.is_finite())
            || a1 <= a0
            || a1 - a0 > std::f64::consts::TAU * (1.0 + FULL_TURN_SLACK)
        {
            return Err(SurfaceError::ArcAngles { a0, a1 });
        }
        if !flatcut_geom::finite3(center) {
            return Err(SurfaceError::NonFinite {
                what: "circle centre",
                index: 0,
            });
        }
        /// Axes closer to parallel than this (sine of their angle) do not span a plane.
        const MIN_AXIS_SINE: f64 = 1e-9;
        let x = x_axis.normalize_or_zero();
        let y_perp = y_axis - y_axis.dot(x) * x;
        let y = y_perp.normalize_or_zero();
        if x == DVec3::ZERO
            || y == DVec3::ZERO
            || !flatcut_geom::finite3(x + y)
            || y_perp.length() <= MIN_AXIS_SINE * y_axis.length()
        {
            return Err(SurfaceError::ArcAxes);
        }
        let theta = (a1 - a0).min(std::f64::consts::TAU);
        let narcs = (theta / std::f64::consts::FRAC_PI_2 - 1e-12)
            .ceil()
            .max(1.0) as usize;
        let dtheta = theta / narcs as f64;
        let w1 = (0.5 * dtheta).cos();
        let on = |a: f64| center + radius * (a.cos() * x + a.sin() * y);
        let mut points = vec![on(a0)];
        let mut weights = vec![1.0];
        for i in 0..narcs {
            let mid = a0 + (i as f64 + 0.5) * dtheta;
            // The tangents at both ends of the piece meet on the bisector at distance r / cos(Δθ/2).
            points.push(center + (radius / w1) * (mid.cos() * x + mid.sin() * y));
            weights.push(w1);
            points.push(if i + 1 == narcs {
                on(a1)
            } else {
                on(a0 + (i + 1) as f64 * dtheta)
            });
            weights.push(1.0);
        }
        let mut knots = vec![0.0; 3];
        for i in 1..narcs {
            let u = i as f64 / narcs as f64;
            knots.push(u);
            knots.push(u);
        }
        knots.extend([1.0; 3]);
        Self::new(2, knots, points, weights)
    }

    /// The same curve as a NURBS with unit weights.
    pub fn from_bspline(b: &BSpline) -> Self {
        Self::new(
            b.degree,
            b.knots.clone(),
            b.points.clone(),
            vec![1.0; b.points.len()],
        )
        .expect("a valid B-spline is a valid NURBS with unit weights")
    }

    /// The degree `p`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knot vector.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The control points (Cartesian).
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The distinct knot values inside the domain, including both ends.
    pub fn breakpoints(&self) -> Vec<f64> {
        breakpoints(self.degree, &self.knots, self.points.len())
    }

    /// Flattens within chordal tolerance `tol` (mm), starting from the knots.
    pub fn flatten(&self, tol: f64) -> Vec<(f64, DVec3)> {
        flatten_with_breaks(self, tol, &refine(&self.breakpoints(), 2))
    }

    /// Closest point `(t, distance)`, sampling every knot span.
    pub fn nearest(&self, p: DVec3, accuracy: f64) -> (f64, f64) {
        nearest_from_samples(
            self,
            p,
            accuracy,
            &refine(&self.breakpoints(), 4 * self.degree.max(2)),
        )
    }

    /// Splits the curve into rational Bézier pieces, one per non-empty knot span, each on
    /// `[0, 1]`.
    pub fn to_rational_beziers(&self) -> Result<Vec<RationalBezier>, SurfaceError> {
        span_beziers(self.degree, &self.knots, &self.hom)
            .into_iter()
            .map(RationalBezier::from_homogeneous)
            .collect()
    }

    /// The same curve traversed backwards, on the reflected knot vector `U_0 + U_last − t`.
    pub fn reversed(&self) -> Nurbs {
        Nurbs {
            degree: self.degree,
            knots: reversed_knots(&self.knots),
            points: self.points.iter().rev().copied().collect(),
            weights: self.weights.iter().rev().copied().collect(),
            hom: self.hom.iter().rev().copied().collect(),
        }
    }

    /// Inserts the knot `t` `times` times on the homogeneous points; the curve is unchanged.
    pub fn insert_knot(&self, t: f64, times: usize) -> Result<Nurbs, SurfaceError> {
        let (knots, hom) = insert(self.degree, &self.knots, &self.hom, t, times)?;
        let points = hom.iter().map(|h| h.truncate() / h.w).collect();
        let weights = hom.iter().map(|h| h.w).collect();
        Ok(Nurbs {
            degree: self.degree,
            knots,
            points,
            weights,
            hom,
        })
    }

    /// Derivatives of orders `0..out.len()` by the quotient rule (Piegl & Tiller A4.2):
    /// `C^(k) = (A^(k) − Σ_{i=1..k} C(k,i) w^(i) C^(k−i)) / w`.
    fn ders_into(&self, t: f64, out: &mut [DVec3]) {
        with_buf::<DVec4, CUBIC_ORDERS, STACK_ORDERS, _>(out.len(), |h| {
            for (kk, hk) in h.iter_mut().enumerate() {
                *hk = if kk <= self.degree {
                    deriv_at(self.degree, &self.knots, &self.hom, t, kk)
                } else {
                    DVec4::ZERO
                };
            }
            let w0 = h[0].w;
            for k in 0..out.len() {
                let mut v = h[k].truncate();
                for i in 1..=k {
                    v -= binomial(k, i) * h[i].w * out[k - i];
                }
                out[k] = v / w0;
            }
        });
    }

    /// Derivatives of orders `0..=k` at `t`.
    pub fn ders(&self, t: f64, k: usize) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; k + 1];
        self.ders_into(t, &mut out);
        out
    }
}

impl ParamCurve for Nurbs {
    fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    fn eval(&self, t: f64) -> DVec3 {
        let h = point_at(self.degree, &self.knots, &self.hom, t);
        h.truncate() / h.w
    }

    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        with_buf::<DVec3, CUBIC_ORDERS, STACK_ORDERS, _>(k + 1, |out| {
            self.ders_into(t, out);
            out[k]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, PI, SQRT_2, TAU};

    fn v2(x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, 0.0)
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).abs().max_element() <= tol
    }

    const TV13_KNOTS: [f64; 8] = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0];

    fn tv13() -> BSpline {
        BSpline::new(
            2,
            TV13_KNOTS.to_vec(),
            vec![v2(0., 0.), v2(1., 1.), v2(1., 2.), v2(2., 2.), v2(3., 1.)],
        )
        .unwrap()
    }

    #[test]
    fn tv13_curve_points_and_knot_insertion() {
        let c = tv13();
        assert!(close(c.eval(0.5), v2(0.75, 0.875), 1e-15));
        assert!(close(c.eval(1.5), v2(1.125, 1.875), 1e-15));
        assert!(close(c.eval(2.5), v2(2.125, 1.75), 1e-15));
        // Segment joints are midpoints of control legs.
        assert!(close(c.eval(1.0), v2(1.0, 1.5), 1e-15));
        assert!(close(c.eval(2.0), v2(1.5, 2.0), 1e-15));
        assert_eq!(c.domain(), (0.0, 3.0));
        let d = c.insert_knot(1.5, 1).unwrap();
        assert_eq!(d.knots(), &[0., 0., 0., 1., 1.5, 2., 3., 3., 3.]);
        let want = [
            v2(0., 0.),
            v2(1., 1.),
            v2(1., 1.75),
            v2(1.25, 2.),
            v2(2., 2.),
            v2(3., 1.),
        ];
        for (a, b) in d.points().iter().zip(want) {
            assert!(close(*a, b, 1e-15), "{a} vs {b}");
        }
        for t in [0.3, 1.2, 1.7, 2.9] {
            assert!(close(c.eval(t), d.eval(t), 1e-15));
        }
        assert!(c.insert_knot(1.0, 2).is_err());
        assert!(c.insert_knot(3.0, 1).is_err());
        assert!(c.insert_knot(1.0, 1).is_ok());
    }

    #[test]
    fn tv15_weights() {
        let pts = vec![v2(0., 0.), v2(1., 1.), v2(1., 2.), v2(2., 2.), v2(3., 1.)];
        let unit = Nurbs::new(2, TV13_KNOTS.to_vec(), pts.clone(), vec![1.0; 5]).unwrap();
        for t in [0.0, 0.5, 1.3, 2.5, 3.0] {
            assert!(close(unit.eval(t), tv13().eval(t), 1e-15));
        }
        // w2 → 0: segment 2 becomes ((2−t)² P1 + (t−1)² P3)/(5 − 6t + 2t²).
        let tiny = Nurbs::new(
            2,
            TV13_KNOTS.to_vec(),
            pts.clone(),
            vec![1., 1., 1e-11, 1., 1.],
        )
        .unwrap();
        for t in [1.2f64, 1.5, 1.9] {
            let den = 5.0 - 6.0 * t + 2.0 * t * t;
            let want = ((2.0 - t).powi(2) * pts[1] + (t - 1.0).powi(2) * pts[3]) / den;
            assert!(close(tiny.eval(t), want, 1e-9));
        }
        assert!(matches!(
            Nurbs::new(
                2,
                TV13_KNOTS.to_vec(),
                pts.clone(),
                vec![1., 1., 0., 1., 1.]
            ),
            Err(SurfaceError::BadWeight { index: 2, .. })
        ));
        assert!(matches!(
            Nurbs::new(2, TV13_KNOTS.to_vec(), pts, vec![1., f64::NAN, 1., 1., 1.]),
            Err(SurfaceError::BadWeight { index: 1, .. })
        ));
    }

    #[test]
    fn tv16_uniform_cubic_at_a_knot() {
        let p = vec![
            DVec3::new(1., 2., 0.),
            DVec3::new(3., 3., 1.),
            DVec3::new(4., 1., 3.),
            DVec3::new(6., 0., 2.),
        ];
        let c = BSpline::new(3, (0..8).map(f64::from).collect(), p).unwrap();
        let (t0, _) = c.domain();
        assert_eq!(t0, 3.0);
        let d = c.ders(t0, 3);
        assert!(close(d[0], DVec3::new(17. / 6., 2.5, 7. / 6.), 1e-14));
        assert!(close(d[1], DVec3::new(1.5, -0.5, 1.5), 1e-14));
        assert!(close(d[2], DVec3::new(-1., -3., 1.), 1e-14));
        assert!(close(d[3], DVec3::new(2., 4., -4.), 1e-13));
        let kappa = d[1].cross(d[2]).length() / d[1].length().powi(3);
        assert!((kappa - 0.6830375627).abs() < 1e-10);
        let tau = d[1].cross(d[2]).dot(d[3]) / d[1].cross(d[2]).length_squared();
        assert!((tau - 0.32).abs() < 1e-14, "tau {tau}");
    }

    #[test]
    fn tv17_rational_circle_quadrant() {
        let c = Nurbs::new(
            2,
            vec![0., 0., 0., 1., 1., 1.],
            vec![v2(0., -1.), v2(1., -1.), v2(1., 0.)],
            vec![1., 1., 2.],
        )
        .unwrap();
        assert!(close(c.eval(0.5), v2(0.8, -0.6), 1e-15));
        assert!(close(c.eval(0.25), v2(8. / 17., -15. / 17.), 1e-15));
        for i in 0..=20 {
            assert!((c.eval(i as f64 / 20.0).length() - 1.0).abs() < 1e-15);
        }
        let s = Nurbs::conic(v2(0., -1.), v2(1., -1.), v2(1., 0.), SQRT_2 / 2.0).unwrap();
        assert!(close(s.eval(0.5), v2(SQRT_2 / 2.0, -SQRT_2 / 2.0), 1e-15));
    }

    #[test]
    fn tv19_conic_circle_arcs() {
        let r3 = 3f64.sqrt();
        let c = Nurbs::conic(v2(0., -1.), v2(-r3, -1.), v2(-r3 / 2.0, 0.5), 0.5).unwrap();
        assert!(close(c.eval(0.25), v2(-0.46632, -0.88462), 5e-6));
        assert!(close(c.eval(0.5), v2(-r3 / 2.0, -0.5), 1e-15));
        assert!(close(c.eval(0.75), v2(-0.99926, 0.03846), 5e-6));
        for i in 0..=16 {
            assert!((c.eval(i as f64 / 16.0).length() - 1.0).abs() < 1e-15);
        }
        // Errata E20: the 90° arc needs P1 = (1, 1).
        let q = Nurbs::conic(v2(1., 0.), v2(1., 1.), v2(0., 1.), SQRT_2 / 2.0).unwrap();
        assert!(close(q.eval(0.5), v2(SQRT_2 / 2.0, SQRT_2 / 2.0), 1e-15));
    }

    #[test]
    fn circle_arcs_are_exact_up_to_full_circle() {
        let center = DVec3::new(1.0, -2.0, 3.0);
        let x = DVec3::new(1.0, 1.0, 0.0);
        let y = DVec3::new(-1.0, 1.0, 1.0);
        let xn = x.normalize();
        let yn = (y - y.dot(xn) * xn).normalize();
        for (a0, a1) in [(0.0, 0.3), (0.2, FRAC_PI_2), (-1.0, 2.0), (0.5, 0.5 + TAU)] {
            let c = Nurbs::circle_arc(center, x, y, 2.5, a0, a1).unwrap();
            assert!(close(
                c.eval(0.0),
                center + 2.5 * (a0.cos() * xn + a0.sin() * yn),
                1e-14
            ));
            assert!(close(
                c.eval(1.0),
                center + 2.5 * (a1.cos() * xn + a1.sin() * yn),
                1e-14
            ));
            for i in 0..=200 {
                let p = c.eval(i as f64 / 200.0) - center;
                assert!((p.length() - 2.5).abs() < 1e-14);
                assert!(p.dot(xn.cross(yn)).abs() < 1e-14);
            }
            // Curvature of an exact circle is 1/r everywhere.
            for t in [0.1, 0.37, 0.8] {
                let d = c.ders(t, 2);
                let k = d[1].cross(d[2]).length() / d[1].length().powi(3);
                assert!((k - 0.4).abs() < 1e-12);
            }
        }
        assert!(Nurbs::circle_arc(center, x, y, 1.0, 0.0, 7.0).is_err());
        assert!(Nurbs::circle_arc(center, x, 2.0 * x, 1.0, 0.0, 1.0).is_err());
        assert!(Nurbs::circle_arc(center, x, y, 0.0, 0.0, 1.0).is_err());
        assert!(Nurbs::circle_arc(center, x, y, 1.0, 1.0, 1.0).is_err());
        let full = Nurbs::circle_arc(center, x, y, 1.0, 0.0, TAU).unwrap();
        assert_eq!(full.points().len(), 9);
        assert!(close(full.eval(0.0), full.eval(1.0), 1e-15));
        let half = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 1.0, 0.0, PI).unwrap();
        assert!(close(half.eval(0.5), v2(0.0, 1.0), 1e-15));
    }

    #[test]
    fn rational_derivatives_match_finite_differences() {
        let c = Nurbs::new(
            3,
            vec![0., 0., 0., 0., 0.4, 1.0, 1.0, 1.0, 1.0],
            vec![
                DVec3::new(0., 0., 0.),
                DVec3::new(1., 2., 0.5),
                DVec3::new(2., -1., 1.),
                DVec3::new(4., 1., 0.),
                DVec3::new(5., 0., 2.),
            ],
            vec![1.0, 2.5, 0.5, 1.5, 1.0],
        )
        .unwrap();
        let h = 1e-5;
        for t in [0.1, 0.3, 0.55, 0.9] {
            for k in 1..=3 {
                let fd = (c.deriv(t + h, k - 1) - c.deriv(t - h, k - 1)) / (2.0 * h);
                let d = c.deriv(t, k);
                assert!(
                    close(d, fd, 2e-5 * (1.0 + d.length())),
                    "t={t} k={k} {d} {fd}"
                );
            }
        }
        // Above the degree the rational curve still has non-zero derivatives.
        assert!(c.deriv(0.3, 4).length() > 0.0);
    }

    #[test]
    fn bezier_extraction_reproduces_spans() {
        let c = BSpline::new(
            3,
            vec![0., 0., 0., 0., 0.5, 1.2, 2., 2., 2., 2.],
            vec![
                DVec3::new(0., 0., 0.),
                DVec3::new(1., 2., 0.5),
                DVec3::new(2., -1., 1.),
                DVec3::new(4., 1., 0.),
                DVec3::new(5., 0., 2.),
                DVec3::new(6., 1., 1.),
            ],
        )
        .unwrap();
        let br = c.breakpoints();
        assert_eq!(br, vec![0.0, 0.5, 1.2, 2.0]);
        let bz = c.to_beziers();
        assert_eq!(bz.len(), 3);
        for (i, b) in bz.iter().enumerate() {
            for s in [0.0, 0.3, 1.0] {
                let t = br[i] + s * (br[i + 1] - br[i]);
                assert!(close(b.eval(s), c.eval(t), 1e-12));
            }
        }
        // Clamped ends: the first Bézier starts at the first control point.
        assert!(close(bz[0].points()[0], c.points()[0], 1e-15));
    }

    #[test]
    fn reversal_and_rational_extraction() {
        let c = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 2.0, 0.3, 4.0).unwrap();
        let r = c.reversed();
        let (a, b) = c.domain();
        assert_eq!(r.domain(), (a, b));
        for t in [0.0, 0.2, 0.5, 0.9, 1.0] {
            assert!(close(r.eval(a + b - t), c.eval(t), 1e-14));
        }
        let pieces = c.to_rational_beziers().unwrap();
        let br = c.breakpoints();
        assert_eq!(pieces.len(), br.len() - 1);
        for (i, pc) in pieces.iter().enumerate() {
            for s in [0.0, 0.4, 1.0] {
                let t = br[i] + s * (br[i + 1] - br[i]);
                assert!(close(pc.eval(s), c.eval(t), 1e-14));
            }
        }
        let bs = tv13();
        let rb = bs.reversed();
        for t in [0.0, 0.7, 2.2, 3.0] {
            assert!(close(rb.eval(3.0 - t), bs.eval(t), 1e-15));
        }
    }

    #[test]
    fn periodic_spline_closes_smoothly() {
        let pts: Vec<DVec3> = (0..6)
            .map(|i| {
                let a = i as f64 * TAU / 6.0;
                DVec3::new(a.cos(), a.sin(), 0.1 * i as f64)
            })
            .collect();
        let c = BSpline::periodic(3, pts).unwrap();
        let (a, b) = c.domain();
        assert_eq!((a, b), (0.0, 6.0));
        for k in 0..3 {
            assert!(close(c.deriv(a, k), c.deriv(b, k), 1e-13), "order {k}");
        }
    }

    #[test]
    fn tv20_uniform_bspline_circles() {
        // m = 4: R = 3/2, the segment from (0, 1) to (−1, 0) is ¼(2t³ − 6t, 2t³ − 6t² + 4).
        let r = 1.5;
        let p = vec![v2(r, 0.), v2(0., r), v2(-r, 0.), v2(0., -r)];
        let c = BSpline::periodic(3, p).unwrap();
        for t in [0.0, 0.25, 0.5, 1.0] {
            let want = 0.25
                * v2(
                    2.0 * t * t * t - 6.0 * t,
                    2.0 * t * t * t - 6.0 * t * t + 4.0,
                );
            assert!(close(c.eval(t), want, 1e-15), "t={t}");
        }
        assert!(close(c.eval(0.5), v2(-0.6875, 0.6875), 1e-15));
        for (m, dev) in [(4, 0.0277282), (5, 0.0094067), (6, 0.0040708)] {
            let a = TAU / m as f64;
            let big_r = 3.0 / (2.0 + a.cos());
            let pts = (0..m)
                .map(|i| big_r * v2((i as f64 * a).cos(), (i as f64 * a).sin()))
                .collect();
            let c = BSpline::periodic(3, pts).unwrap();
            let (lo, hi) = (0..=4000)
                .map(|i| c.eval(m as f64 * i as f64 / 4000.0).length())
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
                    (lo.min(r), hi.max(r))
                });
            assert!(
                (hi - 1.0).abs() < 1e-14,
                "m={m}: knots lie on the unit circle"
            );
            assert!(
                (1.0 - lo - dev).abs() < 1e-7,
                "m={m}: deviation {}",
                1.0 - lo
            );
        }
    }

    fn arb_bspline() -> impl Strategy<Value = BSpline> {
        (1usize..5, proptest::collection::vec(0.05f64..1.0, 1..6)).prop_flat_map(|(p, gaps)| {
            let n = gaps.len() + p;
            proptest::collection::vec((-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0), n).prop_map(
                move |pts| {
                    let mut knots = vec![0.0; p + 1];
                    let mut acc = 0.0;
                    for g in &gaps[..gaps.len() - 1] {
                        acc += g;
                        knots.push(acc);
                    }
                    acc += gaps[gaps.len() - 1];
                    knots.extend(std::iter::repeat_n(acc, p + 1));
                    let pts = pts
                        .into_iter()
                        .map(|(x, y, z)| DVec3::new(x, y, z))
                        .collect();
                    BSpline::new(p, knots, pts).unwrap()
                },
            )
        })
    }

    proptest! {
        #[test]
        fn knot_insertion_leaves_curve_unchanged(c in arb_bspline(), s in 0.01f64..0.99, u in 0.0f64..1.0, times in 1usize..3) {
            let (a, b) = c.domain();
            let t = a + s * (b - a);
            let times = times.min(c.degree());
            if let Ok(d) = c.insert_knot(t, times) {
                let x = a + u * (b - a);
                prop_assert!(close(c.eval(x), d.eval(x), 1e-12));
                prop_assert!(close(c.deriv(x, 1), d.deriv(x, 1), 1e-9));
            }
            let w: Vec<f64> = (0..c.points().len()).map(|i| 0.5 + (i % 3) as f64).collect();
            let r = Nurbs::new(c.degree(), c.knots().to_vec(), c.points().to_vec(), w).unwrap();
            if let Ok(rd) = r.insert_knot(t, times) {
                let x = a + u * (b - a);
                prop_assert!(close(r.eval(x), rd.eval(x), 1e-12));
            }
        }

        #[test]
        fn bspline_derivatives_match_finite_differences(c in arb_bspline(), u in 0.02f64..0.98) {
            let (a, b) = c.domain();
            let t = a + u * (b - a);
            // Stay clear of knots where higher derivatives jump.
            prop_assume!(c.knots().iter().all(|k| (k - t).abs() > 1e-3));
            let h = 1e-6;
            let fd = (c.eval(t + h) - c.eval(t - h)) / (2.0 * h);
            let d = c.deriv(t, 1);
            prop_assert!(close(d, fd, 1e-5 * (1.0 + d.length())));
            let bz = c.to_beziers();
            prop_assert_eq!(bz.len(), c.breakpoints().len() - 1);
        }

        #[test]
        fn nurbs_affine_invariance(c in arb_bspline(), u in 0.0f64..1.0, ang in 0.0f64..6.0) {
            let w: Vec<f64> = (0..c.points().len()).map(|i| 0.3 + (i % 4) as f64).collect();
            let m = glam::DMat3::from_rotation_y(ang) * glam::DMat3::from_diagonal(DVec3::new(1.5, 0.7, 2.0));
            let off = DVec3::new(-2.0, 4.0, 1.0);
            let r = Nurbs::new(c.degree(), c.knots().to_vec(), c.points().to_vec(), w.clone()).unwrap();
            let rm = Nurbs::new(c.degree(), c.knots().to_vec(), c.points().iter().map(|p| m * *p + off).collect(), w).unwrap();
            let (a, b) = c.domain();
            let t = a + u * (b - a);
            prop_assert!(close(rm.eval(t), m * r.eval(t) + off, 1e-11));
        }
    }
}
