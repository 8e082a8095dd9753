//! Polyline curves with chord-length parameter: boundary and seam curves read from files.
//!
//! The parameter is arc length in mm, so `|r'| = 1` on every segment; at a vertex the derivative
//! is taken from the segment that starts there (from the last segment at the end).

use glam::DVec3;

use super::bezier::check_finite;
use crate::{ParamCurve, SurfaceError};

/// A piecewise-linear curve through its vertices, parametrised by arc length from 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    points: Vec<DVec3>,
    /// Cumulative arc length at each vertex (`s[0] = 0`).
    s: Vec<f64>,
}

impl Polyline {
    /// Builds a polyline from at least two distinct finite points. Consecutive duplicate points
    /// (zero-length segments, common in exported outlines) are dropped.
    pub fn new(points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        check_finite(&points, "polyline point")?;
        let mut pts: Vec<DVec3> = Vec::with_capacity(points.len());
        for p in points {
            if pts.last() != Some(&p) {
                pts.push(p);
            }
        }
        if pts.len() < 2 {
            return Err(SurfaceError::ControlPointCount {
                expected: 2,
                got: pts.len(),
            });
        }
        let mut s = Vec::with_capacity(pts.len());
        s.push(0.0);
        for w in pts.windows(2) {
            s.push(s[s.len() - 1] + w[0].distance(w[1]));
        }
        Ok(Self { points: pts, s })
    }

    /// A closed polyline: the first point is appended at the end unless it is already there.
    pub fn closed(mut points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        if let (Some(&f), Some(&l)) = (points.first(), points.last())
            && f != l
        {
            points.push(f);
        }
        Self::new(points)
    }

    /// The vertices.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The arc-length parameter of each vertex.
    pub fn params(&self) -> &[f64] {
        &self.s
    }

    /// Total length in mm (exact).
    pub fn length(&self) -> f64 {
        self.s[self.s.len() - 1]
    }

    /// Whether the last vertex equals the first.
    pub fn is_closed(&self) -> bool {
        self.points.first() == self.points.last()
    }

    /// The vertices with their parameters: the polyline is its own exact flattening, whatever
    /// the tolerance.
    pub fn flatten(&self, _tol: f64) -> Vec<(f64, DVec3)> {
        self.s
            .iter()
            .copied()
            .zip(self.points.iter().copied())
            .collect()
    }

    /// Exact closest point `(s, distance)`: the best projection onto any segment.
    pub fn nearest(&self, p: DVec3, _accuracy: f64) -> (f64, f64) {
        let mut best = (0.0, f64::INFINITY);
        for i in 0..self.points.len() - 1 {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let ab = b - a;
            let f = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            let d = p.distance(a + f * ab);
            if d < best.1 {
                best = (self.s[i] + f * (self.s[i + 1] - self.s[i]), d);
            }
        }
        best
    }

    /// The same polyline traversed backwards (vertices reversed, parameter from 0 again).
    pub fn reversed(&self) -> Polyline {
        let total = self.length();
        let mut points = self.points.clone();
        points.reverse();
        let s = self.s.iter().rev().map(|x| total - x).collect();
        Polyline { points, s }
    }

    fn segment_of(&self, t: f64) -> usize {
        let n = self.points.len() - 1;
        self.s[1..n].partition_point(|&k| k <= t)
    }
}

impl ParamCurve for Polyline {
    fn domain(&self) -> (f64, f64) {
        (0.0, self.length())
    }

    fn eval(&self, t: f64) -> DVec3 {
        let i = self.segment_of(t);
        let f = (t - self.s[i]) / (self.s[i + 1] - self.s[i]);
        self.points[i].lerp(self.points[i + 1], f)
    }

    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        match k {
            0 => self.eval(t),
            1 => {
                let i = self.segment_of(t);
                (self.points[i + 1] - self.points[i]) / (self.s[i + 1] - self.s[i])
            }
            _ => DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CurveExt;

    #[test]
    fn chord_length_parameter_and_queries() {
        let pl = Polyline::new(vec![
            DVec3::ZERO,
            DVec3::new(3.0, 4.0, 0.0),
            DVec3::new(3.0, 4.0, 0.0),
            DVec3::new(3.0, 4.0, 12.0),
        ])
        .unwrap();
        assert_eq!(pl.points().len(), 3, "duplicate vertex dropped");
        assert_eq!(pl.domain(), (0.0, 17.0));
        assert_eq!(pl.eval(2.5), DVec3::new(1.5, 2.0, 0.0));
        assert_eq!(pl.eval(11.0), DVec3::new(3.0, 4.0, 6.0));
        assert_eq!(pl.deriv(5.0, 1), DVec3::Z);
        assert!((pl.deriv(1.0, 1).length() - 1.0).abs() < 1e-15);
        assert_eq!(pl.deriv(1.0, 2), DVec3::ZERO);
        assert!((pl.arclen(1e-9) - 17.0).abs() < 1e-9);
        let (s, d) = pl.nearest(DVec3::new(3.0, 4.0 + 1.0, 6.0), 1e-9);
        assert!((s - 11.0).abs() < 1e-14 && (d - 1.0).abs() < 1e-14);
        assert_eq!(pl.flatten(0.1).len(), 3);
        assert!(Polyline::new(vec![DVec3::X, DVec3::X]).is_err());
        assert!(Polyline::new(vec![DVec3::X, DVec3::NAN]).is_err());
        let sq = Polyline::closed(vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::ONE.with_z(0.0),
            DVec3::Y,
        ])
        .unwrap();
        assert!(sq.is_closed());
        assert_eq!(sq.length(), 4.0);
        let rev = pl.reversed();
        assert_eq!(rev.domain(), (0.0, 17.0));
        assert!((rev.eval(17.0 - 2.5) - pl.eval(2.5)).length() < 1e-14);
    }
}
