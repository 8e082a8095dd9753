//! Interpolating C² cubic splines through points (Salomon ch. 5, digest A8; TV10–TV12), with
//! clamped, relaxed (natural) and closed (periodic) end conditions and uniform, chord-length,
//! centripetal or explicit parameters.
//!
//! The unknowns are the tangents `D_i = r'(u_i)` at the knots; with `h_i = u_{i+1} − u_i`, C²
//! continuity at an interior knot reads (Salomon (5.22))
//! `h_i D_{i−1} + 2(h_{i−1} + h_i) D_i + h_{i−1} D_{i+1} = 3[h_i/h_{i−1} (P_i − P_{i−1}) +
//! h_{i−1}/h_i (P_{i+1} − P_i)]`, a tridiagonal system (cyclic for closed curves, solved with
//! the Sherman–Morrison correction). Natural ends add `2D_0 + D_1 = 3(P_1 − P_0)/h_0` and
//! `D_{n−1} + 2D_n = 3(P_n − P_{n−1})/h_{n−1}`.

use glam::DVec3;

use super::bezier::{Bezier, check_finite};
use super::ext::{flatten_with_breaks, nearest_from_samples};
use crate::{ParamCurve, SurfaceError};

/// End conditions of [`CubicSpline::interpolate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplineEnds {
    /// Given end derivatives `r'(u_0)`, `r'(u_n)` (with respect to the spline parameter).
    Clamped(DVec3, DVec3),
    /// Natural ends: `r'' = 0` at both ends.
    Relaxed,
    /// A closed loop through the points, C² at every point including the first; a last point
    /// equal to the first is dropped.
    Closed,
}

/// Parametrisation of [`CubicSpline::interpolate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplineParam {
    /// `u_i = i`: each segment on a unit interval (Salomon's uniform spline).
    Uniform,
    /// `u_{i+1} − u_i = |P_{i+1} − P_i|`: the parameter approximates arc length in mm.
    ChordLength,
    /// `u_{i+1} − u_i = |P_{i+1} − P_i|^{1/2}`: avoids cusps and overshoot on uneven spacing.
    Centripetal,
}

/// Points closer than this fraction of the data's extent are the same point: a closing point
/// that repeats the first one up to rounding (e.g. computed as cos 2π, sin 2π) is dropped, and
/// parameter intervals shorter than this fraction of the total are rejected as coincident points.
const SAME_POINT_REL: f64 = 1e-12;

/// A C² piecewise cubic through points `P_i` at knots `u_i`, stored in Hermite form.
#[derive(Clone, Debug, PartialEq)]
pub struct CubicSpline {
    params: Vec<f64>,
    points: Vec<DVec3>,
    tangents: Vec<DVec3>,
    closed: bool,
}

impl CubicSpline {
    /// Interpolates `points` with the given end conditions and parametrisation.
    ///
    /// Needs ≥ 2 points (≥ 3 distinct for [`SplineEnds::Closed`]); consecutive points must differ
    /// for the chord-length and centripetal parametrisations.
    pub fn interpolate(
        points: &[DVec3],
        ends: SplineEnds,
        param: SplineParam,
    ) -> Result<Self, SurfaceError> {
        check_finite(points, "spline point")?;
        let pts = loop_points(points, ends)?;
        let mut params = Vec::with_capacity(pts.len());
        params.push(0.0);
        for (i, w) in pts.windows(2).enumerate() {
            let d = w[0].distance(w[1]);
            let h = match param {
                SplineParam::Uniform => 1.0,
                SplineParam::ChordLength => d,
                SplineParam::Centripetal => d.sqrt(),
            };
            if h.is_nan() || h <= 0.0 {
                return Err(SurfaceError::SplinePointsCoincide {
                    first: i,
                    second: i + 1,
                });
            }
            params.push(params[i] + h);
        }
        let total = params[params.len() - 1];
        if let Some(i) = params
            .windows(2)
            .position(|w| w[1] - w[0] <= SAME_POINT_REL * total)
        {
            return Err(SurfaceError::SplinePointsNear {
                first: i,
                second: i + 1,
                interval: params[i + 1] - params[i],
                total,
            });
        }
        Self::solve(pts, params, ends)
    }

    /// Interpolates `points[i]` at the explicit parameters `params[i]` (strictly increasing).
    /// For [`SplineEnds::Closed`], `params` has one more entry than the (de-duplicated) points:
    /// the parameter at which the loop returns to the first point.
    pub fn interpolate_at(
        points: &[DVec3],
        params: &[f64],
        ends: SplineEnds,
    ) -> Result<Self, SurfaceError> {
        check_finite(points, "spline point")?;
        let pts = loop_points(points, ends)?;
        if params.len() != pts.len() {
            return Err(SurfaceError::SplineParamCount {
                want: pts.len(),
                points: points.len(),
                ends: if matches!(ends, SplineEnds::Closed) {
                    "closed: one more for the return to the start"
                } else {
                    "open"
                },
                got: params.len(),
            });
        }
        for i in 0..params.len() {
            if !params[i].is_finite() {
                return Err(SurfaceError::NonFinite {
                    what: "spline parameter",
                    index: i,
                });
            }
            if i > 0 && params[i] <= params[i - 1] {
                return Err(SurfaceError::SplineParamOrder {
                    index: i,
                    value: params[i],
                    previous: i - 1,
                    previous_value: params[i - 1],
                });
            }
        }
        Self::solve(pts, params.to_vec(), ends)
    }

    fn solve(pts: Vec<DVec3>, params: Vec<f64>, ends: SplineEnds) -> Result<Self, SurfaceError> {
        let n = pts.len() - 1; // segments
        let h: Vec<f64> = params.windows(2).map(|w| w[1] - w[0]).collect();
        let slope = |i: usize| (pts[i + 1] - pts[i]) / h[i];
        let closed = matches!(ends, SplineEnds::Closed);
        let tangents = if closed {
            // Unknowns D_0..D_{n−1} (D_n = D_0); row i couples segments i−1 (cyclic) and i.
            let m = n;
            let mut sub = vec![0.0; m];
            let mut diag = vec![0.0; m];
            let mut sup = vec![0.0; m];
            let mut rhs = vec![DVec3::ZERO; m];
            for i in 0..m {
                let ip = (i + m - 1) % m;
                let (hp, hi) = (h[ip], h[i]);
                sub[i] = hi;
                diag[i] = 2.0 * (hp + hi);
                sup[i] = hp;
                rhs[i] = 3.0 * (hi * slope(ip) + hp * slope(i));
            }
            let mut d = solve_cyclic(&sub, &diag, &sup, &rhs);
            d.push(d[0]);
            d
        } else {
            let m = n + 1;
            let mut sub = vec![0.0; m];
            let mut diag = vec![0.0; m];
            let mut sup = vec![0.0; m];
            let mut rhs = vec![DVec3::ZERO; m];
            for i in 1..n {
                let (hp, hi) = (h[i - 1], h[i]);
                sub[i] = hi;
                diag[i] = 2.0 * (hp + hi);
                sup[i] = hp;
                rhs[i] = 3.0 * (hi * slope(i - 1) + hp * slope(i));
            }
            match ends {
                SplineEnds::Clamped(d0, d1) => {
                    check_finite(&[d0, d1], "clamped end derivative")?;
                    diag[0] = 1.0;
                    rhs[0] = d0;
                    diag[n] = 1.0;
                    rhs[n] = d1;
                }
                _ => {
                    diag[0] = 2.0;
                    sup[0] = 1.0;
                    rhs[0] = 3.0 * slope(0);
                    sub[n] = 1.0;
                    diag[n] = 2.0;
                    rhs[n] = 3.0 * slope(n - 1);
                }
            }
            solve_tridiagonal(&sub, &diag, &sup, &rhs)
        };
        check_finite(&tangents, "spline tangent")?;
        Ok(Self {
            params,
            points: pts,
            tangents,
            closed,
        })
    }

    /// The knots `u_0..u_n` (segment breakpoints).
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// The interpolated points at the knots (for closed splines the first point is repeated at
    /// the end).
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The tangents `r'(u_i)` at the knots.
    pub fn tangents(&self) -> &[DVec3] {
        &self.tangents
    }

    /// The same curve traversed backwards, on the parameter `u_0 + u_n − u`.
    pub fn reversed(&self) -> CubicSpline {
        let (a, b) = (self.params[0], self.params[self.params.len() - 1]);
        CubicSpline {
            params: self.params.iter().rev().map(|u| a + b - u).collect(),
            points: self.points.iter().rev().copied().collect(),
            tangents: self.tangents.iter().rev().map(|d| -*d).collect(),
            closed: self.closed,
        }
    }

    /// Whether the spline is a closed loop.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Number of cubic segments.
    pub fn segment_count(&self) -> usize {
        self.points.len() - 1
    }

    /// Power coefficients `[a0, a1, a2, a3]` of segment `i` in its local parameter
    /// `s = u − u_i ∈ [0, h_i]` (Salomon's segment form); `None` if `i` is out of range.
    pub fn segment_power(&self, i: usize) -> Option<[DVec3; 4]> {
        if i >= self.segment_count() {
            return None;
        }
        let h = self.params[i + 1] - self.params[i];
        let (p0, p1) = (self.points[i], self.points[i + 1]);
        let (d0, d1) = (self.tangents[i], self.tangents[i + 1]);
        let s = (p1 - p0) / h;
        Some([
            p0,
            d0,
            (3.0 * s - 2.0 * d0 - d1) / h,
            (d0 + d1 - 2.0 * s) / (h * h),
        ])
    }

    /// Segment `i` as a cubic Bézier on `[0, 1]` (for SVG and G-code output).
    pub fn segment_bezier(&self, i: usize) -> Option<Bezier> {
        if i >= self.segment_count() {
            return None;
        }
        let h = self.params[i + 1] - self.params[i];
        Some(Bezier::from_points_unchecked(vec![
            self.points[i],
            self.points[i] + self.tangents[i] * (h / 3.0),
            self.points[i + 1] - self.tangents[i + 1] * (h / 3.0),
            self.points[i + 1],
        ]))
    }

    /// The same curve as a cubic B-spline on the same parameter, interior knots of multiplicity
    /// 3 (the exact Bézier form of each segment; for the patch constructions that take B-spline
    /// boundaries).
    pub fn to_bspline(&self) -> Result<super::BSpline, SurfaceError> {
        let pieces: Vec<Bezier> = (0..self.segment_count())
            .filter_map(|i| self.segment_bezier(i))
            .collect();
        super::BSpline::from_beziers(&pieces, &self.params, 0.0)
    }

    /// Flattens within chordal tolerance `tol` (mm), starting from the knots.
    pub fn flatten(&self, tol: f64) -> Vec<(f64, DVec3)> {
        flatten_with_breaks(self, tol, &self.params)
    }

    /// Closest point `(u, distance)`, sampling every segment.
    pub fn nearest(&self, p: DVec3, accuracy: f64) -> (f64, f64) {
        nearest_from_samples(self, p, accuracy, &refine(&self.params, 8))
    }

    fn segment_of(&self, u: f64) -> usize {
        let n = self.segment_count();
        self.params[1..n].partition_point(|&k| k <= u)
    }
}

/// `k` samples per interval of sorted breakpoints, including all breakpoints.
pub(crate) fn refine(breaks: &[f64], k: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(breaks.len() * k);
    for w in breaks.windows(2) {
        for j in 0..k {
            out.push(w[0] + (w[1] - w[0]) * (j as f64 / k as f64));
        }
    }
    if let Some(&l) = breaks.last() {
        out.push(l);
    }
    out
}

/// The point list of an open or closed spline (closed: first point repeated at the end).
fn loop_points(points: &[DVec3], ends: SplineEnds) -> Result<Vec<DVec3>, SurfaceError> {
    let mut pts = points.to_vec();
    if matches!(ends, SplineEnds::Closed) {
        let extent = flatcut_geom::Aabb3::from_points(pts.iter().copied()).diagonal();
        if pts.len() >= 2 && pts[0].distance(pts[pts.len() - 1]) <= SAME_POINT_REL * extent {
            pts.pop();
        }
        if pts.len() < 3 {
            return Err(SurfaceError::ControlPointCount {
                expected: 3,
                got: pts.len(),
            });
        }
        pts.push(pts[0]);
    } else if pts.len() < 2 {
        return Err(SurfaceError::ControlPointCount {
            expected: 2,
            got: pts.len(),
        });
    }
    Ok(pts)
}

/// Thomas algorithm for a diagonally dominant tridiagonal system (no pivoting needed: every
/// row of the spline systems has `|diag| ≥ |sub| + |sup|`).
fn solve_tridiagonal(sub: &[f64], diag: &[f64], sup: &[f64], rhs: &[DVec3]) -> Vec<DVec3> {
    let m = diag.len();
    let mut c = vec![0.0; m];
    let mut d = vec![DVec3::ZERO; m];
    c[0] = sup[0] / diag[0];
    d[0] = rhs[0] / diag[0];
    for i in 1..m {
        let den = diag[i] - sub[i] * c[i - 1];
        c[i] = if i + 1 < m { sup[i] / den } else { 0.0 };
        d[i] = (rhs[i] - sub[i] * d[i - 1]) / den;
    }
    for i in (0..m - 1).rev() {
        d[i] = d[i] - c[i] * d[i + 1];
    }
    d
}

/// Cyclic tridiagonal solve: `sub[0]` couples row 0 to the last unknown and `sup[m−1]` the last
/// row to the first. Sherman–Morrison on top of [`solve_tridiagonal`].
fn solve_cyclic(sub: &[f64], diag: &[f64], sup: &[f64], rhs: &[DVec3]) -> Vec<DVec3> {
    let m = diag.len();
    let (alpha, beta) = (sup[m - 1], sub[0]);
    let gamma = -diag[0];
    let mut bb = diag.to_vec();
    bb[0] -= gamma;
    bb[m - 1] -= alpha * beta / gamma;
    let x = solve_tridiagonal(sub, &bb, sup, rhs);
    let mut u = vec![DVec3::ZERO; m];
    u[0] = DVec3::splat(gamma);
    u[m - 1] = DVec3::splat(alpha);
    let z = solve_tridiagonal(sub, &bb, sup, &u);
    // All three coordinates of z are equal (the same scalar system); use x.
    let fact_num = x[0] + x[m - 1] * (beta / gamma);
    let fact_den = 1.0 + z[0].x + z[m - 1].x * beta / gamma;
    let fact = fact_num / fact_den;
    x.iter().zip(&z).map(|(xi, zi)| *xi - fact * zi.x).collect()
}

impl ParamCurve for CubicSpline {
    fn domain(&self) -> (f64, f64) {
        (self.params[0], self.params[self.params.len() - 1])
    }

    fn eval(&self, u: f64) -> DVec3 {
        self.deriv(u, 0)
    }

    fn deriv(&self, u: f64, k: usize) -> DVec3 {
        let i = self.segment_of(u);
        let s = u - self.params[i];
        let h = self.params[i + 1] - self.params[i];
        let (p0, p1) = (self.points[i], self.points[i + 1]);
        let (d0, d1) = (self.tangents[i], self.tangents[i + 1]);
        let sl = (p1 - p0) / h;
        let a2 = (3.0 * sl - 2.0 * d0 - d1) / h;
        let a3 = (d0 + d1 - 2.0 * sl) / (h * h);
        match k {
            0 => ((a3 * s + a2) * s + d0) * s + p0,
            1 => (3.0 * a3 * s + 2.0 * a2) * s + d0,
            2 => 6.0 * a3 * s + 2.0 * a2,
            3 => 6.0 * a3,
            _ => DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CurveExt;
    use proptest::prelude::*;

    fn v2(x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, 0.0)
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).abs().max_element() <= tol
    }

    const SQUARE: [DVec3; 4] = [
        DVec3::new(0., 0., 0.),
        DVec3::new(1., 0., 0.),
        DVec3::new(1., 1., 0.),
        DVec3::new(0., 1., 0.),
    ];

    fn check_segments(s: &CubicSpline, want: &[[DVec3; 4]]) {
        for (i, w) in want.iter().enumerate() {
            let got = s.segment_power(i).unwrap();
            for j in 0..4 {
                assert!(
                    close(got[j], w[j], 1e-14),
                    "segment {i} coeff {j}: {} vs {}",
                    got[j],
                    w[j]
                );
            }
        }
    }

    #[test]
    fn tv10_clamped() {
        let s = CubicSpline::interpolate(
            &SQUARE,
            SplineEnds::Clamped(v2(1., -1.), v2(-1., -1.)),
            SplineParam::Uniform,
        )
        .unwrap();
        assert!(close(s.tangents()[1], v2(2. / 3., 4. / 5.), 1e-15));
        assert!(close(s.tangents()[2], v2(-2. / 3., 4. / 5.), 1e-15));
        check_segments(
            &s,
            &[
                [
                    v2(0., 0.),
                    v2(1., -1.),
                    v2(1. / 3., 6. / 5.),
                    v2(-1. / 3., -1. / 5.),
                ],
                [
                    v2(1., 0.),
                    v2(2. / 3., 4. / 5.),
                    v2(-2. / 3., 3. / 5.),
                    v2(0., -2. / 5.),
                ],
                [
                    v2(1., 1.),
                    v2(-2. / 3., 4. / 5.),
                    v2(-2. / 3., -3. / 5.),
                    v2(1. / 3., -1. / 5.),
                ],
            ],
        );
    }

    #[test]
    fn tv11_relaxed() {
        let s =
            CubicSpline::interpolate(&SQUARE, SplineEnds::Relaxed, SplineParam::Uniform).unwrap();
        let want_t = [
            v2(6. / 5., -1. / 3.),
            v2(3. / 5., 2. / 3.),
            v2(-3. / 5., 2. / 3.),
            v2(-6. / 5., -1. / 3.),
        ];
        for i in 0..4 {
            assert!(close(s.tangents()[i], want_t[i], 1e-15));
        }
        check_segments(
            &s,
            &[
                [
                    v2(0., 0.),
                    v2(6. / 5., -1. / 3.),
                    v2(0., 0.),
                    v2(-1. / 5., 1. / 3.),
                ],
                [
                    v2(1., 0.),
                    v2(3. / 5., 2. / 3.),
                    v2(-3. / 5., 1.),
                    v2(0., -2. / 3.),
                ],
                [
                    v2(1., 1.),
                    v2(-3. / 5., 2. / 3.),
                    v2(-3. / 5., -1.),
                    v2(1. / 5., 1. / 3.),
                ],
            ],
        );
        assert!(s.deriv(0.0, 2).length() < 1e-14 && s.deriv(3.0, 2).length() < 1e-14);
    }

    #[test]
    fn tv12_nonuniform_explicit_parameters() {
        let s = CubicSpline::interpolate_at(
            &SQUARE,
            &[0.0, 2.0, 4.0, 6.0],
            SplineEnds::Clamped(v2(1., -1.), v2(-1., -1.)),
        )
        .unwrap();
        assert!(close(s.tangents()[1], v2(1. / 6., 1. / 2.), 1e-15));
        assert!(close(s.tangents()[2], v2(-1. / 6., 1. / 2.), 1e-15));
        check_segments(
            &s,
            &[
                [
                    v2(0., 0.),
                    v2(1., -1.),
                    v2(-1. / 3., 3. / 4.),
                    v2(1. / 24., -1. / 8.),
                ],
                [
                    v2(1., 0.),
                    v2(1. / 6., 1. / 2.),
                    v2(-1. / 12., 0.),
                    v2(0., 0.),
                ],
                [
                    v2(1., 1.),
                    v2(-1. / 6., 1. / 2.),
                    v2(-1. / 12., 0.),
                    v2(-1. / 24., -1. / 8.),
                ],
            ],
        );
        assert_eq!(s.domain(), (0.0, 6.0));
        assert!(close(s.eval(6.0), v2(0., 1.), 1e-15));
    }

    #[test]
    fn c2_continuity_and_interpolation() {
        let pts: Vec<DVec3> = (0..9)
            .map(|i| {
                let t = i as f64 * 0.8;
                DVec3::new(10.0 * t.cos(), 7.0 * t.sin(), (i * i) as f64 * 0.3)
            })
            .collect();
        for ends in [
            SplineEnds::Relaxed,
            SplineEnds::Closed,
            SplineEnds::Clamped(DVec3::X, DVec3::Y),
        ] {
            for param in [
                SplineParam::Uniform,
                SplineParam::ChordLength,
                SplineParam::Centripetal,
            ] {
                let s = CubicSpline::interpolate(&pts, ends, param).unwrap();
                for (i, &u) in s.params().iter().enumerate() {
                    assert!(close(s.eval(u), s.points()[i], 1e-12));
                }
                let n = s.params().len() - 1;
                for &u in &s.params()[1..n] {
                    let e = 1e-9;
                    for k in 0..3 {
                        let jump = s.deriv(u - e, k) - s.deriv(u, k);
                        assert!(
                            jump.length() < 1e-6 * (1.0 + s.deriv(u, k).length()),
                            "{ends:?} {param:?} k={k} at {u}: {jump}"
                        );
                    }
                }
                if ends == SplineEnds::Closed {
                    let (a, b) = s.domain();
                    for k in 0..3 {
                        assert!(
                            close(
                                s.deriv(a, k),
                                s.deriv(b, k),
                                1e-9 * (1.0 + s.deriv(a, k).length())
                            ),
                            "closed seam k={k}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn closed_spline_through_a_regular_polygon_approximates_the_circle() {
        let m = 24;
        let r = 100.0;
        let pts: Vec<DVec3> = (0..=m)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / m as f64;
                DVec3::new(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect();
        let s =
            CubicSpline::interpolate(&pts, SplineEnds::Closed, SplineParam::ChordLength).unwrap();
        assert!(s.is_closed());
        assert_eq!(s.segment_count(), m);
        let mut worst: f64 = 0.0;
        for (_, p) in s.flatten(0.001) {
            worst = worst.max((p.length() - r).abs());
        }
        // Cubic interpolation error O(h⁴): about 1e-3 mm on a 100 mm radius with 24 points.
        assert!(worst < 5e-3, "radius error {worst}");
        let length = s.arclen(1e-9);
        assert!(
            (length - std::f64::consts::TAU * r).abs() < 0.05,
            "{length}"
        );
        let (u, d) = s.nearest(DVec3::new(0.0, 150.0, 0.0), 1e-10);
        assert!((d - 50.0).abs() < 5e-3);
        assert!((s.eval(u).x).abs() < 1e-6);
    }

    #[test]
    fn rejects_bad_input() {
        let dup = [v2(0., 0.), v2(1., 0.), v2(1., 0.), v2(2., 1.)];
        assert!(
            CubicSpline::interpolate(&dup, SplineEnds::Relaxed, SplineParam::ChordLength).is_err()
        );
        assert!(CubicSpline::interpolate(&dup, SplineEnds::Relaxed, SplineParam::Uniform).is_ok());
        assert!(
            CubicSpline::interpolate(&dup[..1], SplineEnds::Relaxed, SplineParam::Uniform).is_err()
        );
        assert!(
            CubicSpline::interpolate(
                &[v2(0., 0.), v2(1., 0.), v2(0., 0.)],
                SplineEnds::Closed,
                SplineParam::Uniform
            )
            .is_err()
        );
        assert!(
            CubicSpline::interpolate_at(&SQUARE, &[0., 1., 1., 2.], SplineEnds::Relaxed).is_err()
        );
        assert!(CubicSpline::interpolate_at(&SQUARE, &[0., 1., 2.], SplineEnds::Relaxed).is_err());
        assert!(
            CubicSpline::interpolate_at(&SQUARE, &[0., 1., 2., 3., 4.], SplineEnds::Closed).is_ok()
        );
        assert!(matches!(
            CubicSpline::interpolate(
                &[v2(0., 0.), DVec3::NAN],
                SplineEnds::Relaxed,
                SplineParam::Uniform
            ),
            Err(SurfaceError::NonFinite { index: 1, .. })
        ));
        // Two points, natural ends: the straight segment traversed uniformly.
        let s = CubicSpline::interpolate(
            &[v2(0., 0.), v2(3., 4.)],
            SplineEnds::Relaxed,
            SplineParam::ChordLength,
        )
        .unwrap();
        assert!(close(s.eval(2.5), v2(1.5, 2.0), 1e-15));
        assert!(close(s.deriv(1.0, 1), v2(0.6, 0.8), 1e-15));
    }

    #[test]
    fn bspline_form_is_the_same_curve() {
        let s = CubicSpline::interpolate(&SQUARE, SplineEnds::Closed, SplineParam::ChordLength)
            .unwrap();
        let b = s.to_bspline().unwrap();
        assert_eq!(b.domain(), s.domain());
        let (lo, hi) = s.domain();
        for i in 0..=50 {
            let t = lo + (hi - lo) * i as f64 / 50.0;
            assert!(close(b.eval(t), s.eval(t), 1e-13));
            assert!(close(b.deriv(t, 1), s.deriv(t, 1), 1e-12));
        }
    }

    proptest! {
        #[test]
        fn affine_invariance_and_bezier_segments(
            raw in proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0, -5.0f64..5.0), 3..10),
            u in 0.0f64..1.0,
        ) {
            let pts: Vec<DVec3> = raw.into_iter().map(|(x, y, z)| DVec3::new(x, y, z)).collect();
            prop_assume!(pts.windows(2).all(|w| w[0].distance(w[1]) > 1e-3));
            let s = CubicSpline::interpolate(&pts, SplineEnds::Relaxed, SplineParam::Uniform).unwrap();
            let m = glam::DMat3::from_rotation_x(0.7) * 2.0;
            let off = DVec3::new(1.0, 2.0, 3.0);
            let moved: Vec<DVec3> = pts.iter().map(|p| m * *p + off).collect();
            let sm = CubicSpline::interpolate(&moved, SplineEnds::Relaxed, SplineParam::Uniform).unwrap();
            let (a, b) = s.domain();
            let t = a + u * (b - a);
            prop_assert!(close(sm.eval(t), m * s.eval(t) + off, 1e-9));
            let i = s.segment_of(t);
            let (k0, k1) = (s.params()[i], s.params()[i + 1]);
            let bz = s.segment_bezier(i).unwrap();
            prop_assert!(close(bz.eval((t - k0) / (k1 - k0)), s.eval(t), 1e-9));
        }
    }
}
