//! [`Curve`]: one enum over every curve type, for collections of mixed curves (design files,
//! boundaries, seams) that must keep piecewise structure visible.
//!
//! Through `dyn ParamCurve` the blanket [`super::CurveExt`] methods only see a black box and
//! sample its domain uniformly; a [`Curve`] knows its breakpoints, so flattening keeps polyline
//! corners and spline knots exactly and the closest-point search samples every span.

use glam::DVec3;

use super::ext::{flatten_with_breaks, nearest_from_samples};
use super::spline::refine;
use super::{
    BSpline, Bezier, CubicSpline, Hermite, HermiteSpline, Nurbs, Polyline, RationalBezier,
};
use crate::ParamCurve;

/// Samples per span for [`Curve::nearest`], and the least total, so that every span of a
/// piecewise curve is searched and a single-span curve gets the density of
/// [`super::CurveExt::nearest`].
const NEAREST_PER_SPAN: usize = 8;
const NEAREST_MIN_SAMPLES: usize = 128;

/// Any curve of this module.
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// A polynomial Bézier curve.
    Bezier(Bezier),
    /// A rational Bézier curve.
    Rational(RationalBezier),
    /// A B-spline curve.
    BSpline(BSpline),
    /// A NURBS curve (also exact arcs and conics).
    Nurbs(Nurbs),
    /// A single cubic Hermite segment.
    Hermite(Hermite),
    /// A G¹ chain of Hermite cubics.
    HermiteSpline(HermiteSpline),
    /// An interpolating C² cubic spline.
    Spline(CubicSpline),
    /// A polyline with chord-length parameter.
    Polyline(Polyline),
}

macro_rules! each {
    ($self:expr, $c:ident => $e:expr) => {
        match $self {
            Curve::Bezier($c) => $e,
            Curve::Rational($c) => $e,
            Curve::BSpline($c) => $e,
            Curve::Nurbs($c) => $e,
            Curve::Hermite($c) => $e,
            Curve::HermiteSpline($c) => $e,
            Curve::Spline($c) => $e,
            Curve::Polyline($c) => $e,
        }
    };
}

impl Curve {
    /// The parameters where the curve's pieces meet (derivatives may jump there), including both
    /// ends of the domain.
    pub fn breakpoints(&self) -> Vec<f64> {
        match self {
            Curve::BSpline(c) => c.breakpoints(),
            Curve::Nurbs(c) => c.breakpoints(),
            Curve::Spline(c) => c.params().to_vec(),
            Curve::Polyline(c) => c.params().to_vec(),
            Curve::HermiteSpline(c) => (0..=c.segments().len()).map(|i| i as f64).collect(),
            Curve::Bezier(_) | Curve::Rational(_) | Curve::Hermite(_) => vec![0.0, 1.0],
        }
    }

    /// The same curve traversed backwards (the parameter `t ↦ t0 + t1 − t` on the same domain,
    /// or on the new chord-length parameter for a polyline): orientation fixing of outlines.
    pub fn reversed(&self) -> Curve {
        match self {
            Curve::Bezier(c) => Curve::Bezier(c.reversed()),
            Curve::Rational(c) => Curve::Rational(c.reversed()),
            Curve::BSpline(c) => Curve::BSpline(c.reversed()),
            Curve::Nurbs(c) => Curve::Nurbs(c.reversed()),
            Curve::Hermite(c) => Curve::Hermite(c.reversed()),
            Curve::HermiteSpline(c) => Curve::HermiteSpline(c.reversed()),
            Curve::Spline(c) => Curve::Spline(c.reversed()),
            Curve::Polyline(c) => Curve::Polyline(c.reversed()),
        }
    }

    /// Flattens to `(parameter, point)` pairs within chordal tolerance `tol` (mm); every
    /// breakpoint is a vertex (a polyline returns exactly its vertices).
    pub fn flatten(&self, tol: f64) -> Vec<(f64, DVec3)> {
        match self {
            Curve::Polyline(c) => c.flatten(tol),
            _ => flatten_with_breaks(self, tol, &refine(&self.breakpoints(), 2)),
        }
    }

    /// Closest point `(t, distance)`, sampling every span (exact for polylines).
    pub fn nearest(&self, p: DVec3, accuracy: f64) -> (f64, f64) {
        match self {
            Curve::Polyline(c) => c.nearest(p, accuracy),
            _ => {
                let br = self.breakpoints();
                let spans = br.len().saturating_sub(1).max(1);
                let per = NEAREST_PER_SPAN.max(NEAREST_MIN_SAMPLES.div_ceil(spans));
                nearest_from_samples(self, p, accuracy, &refine(&br, per))
            }
        }
    }
}

impl ParamCurve for Curve {
    fn domain(&self) -> (f64, f64) {
        each!(self, c => c.domain())
    }

    fn eval(&self, t: f64) -> DVec3 {
        each!(self, c => c.eval(t))
    }

    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        each!(self, c => c.deriv(t, k))
    }
}

macro_rules! from {
    ($($v:ident($t:ty)),*) => {
        $(impl From<$t> for Curve {
            fn from(c: $t) -> Self {
                Curve::$v(c)
            }
        })*
    };
}
from!(
    Bezier(Bezier),
    Rational(RationalBezier),
    BSpline(BSpline),
    Nurbs(Nurbs),
    Hermite(Hermite),
    HermiteSpline(HermiteSpline),
    Spline(CubicSpline),
    Polyline(Polyline)
);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CurveExt;

    #[test]
    fn reversal_of_every_type() {
        let pts = [
            DVec3::ZERO,
            DVec3::new(10., 5., 0.),
            DVec3::new(20., -3., 2.),
            DVec3::new(30., 4., 0.),
        ];
        let curves: Vec<Curve> = vec![
            Bezier::new(pts.to_vec()).unwrap().into(),
            RationalBezier::new(&pts, &[1., 2., 0.5, 1.])
                .unwrap()
                .into(),
            BSpline::clamped_uniform(2, pts.to_vec()).unwrap().into(),
            Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 3., 0.5, 5.)
                .unwrap()
                .into(),
            Hermite::new(pts[0], pts[1], pts[2], pts[3]).unwrap().into(),
            HermiteSpline::through(&pts, false, crate::curve::SpeedRule::Manning)
                .unwrap()
                .into(),
            CubicSpline::interpolate(
                &pts,
                crate::curve::SplineEnds::Relaxed,
                crate::curve::SplineParam::ChordLength,
            )
            .unwrap()
            .into(),
            Polyline::new(pts.to_vec()).unwrap().into(),
        ];
        for c in curves {
            let r = c.reversed();
            let (a, b) = c.domain();
            let (ra, rb) = r.domain();
            assert!((rb - ra - (b - a)).abs() < 1e-12, "{c:?}");
            for i in 0..=10 {
                let s = i as f64 / 10.0;
                let p = c.eval(a + s * (b - a));
                let q = r.eval(rb - s * (rb - ra));
                assert!((p - q).length() < 1e-12, "{c:?} at {s}");
                if i > 0 && i < 10 {
                    let (d, e) = (c.deriv(a + s * (b - a), 1), r.deriv(rb - s * (rb - ra), 1));
                    assert!((d + e).length() < 1e-9 * (1.0 + d.length()), "{c:?} at {s}");
                }
            }
        }
    }

    #[test]
    fn every_curve_type_is_thread_safe_and_cloneable() {
        fn check<T: ParamCurve + Send + Sync + Clone + std::fmt::Debug + 'static>() {}
        check::<Bezier>();
        check::<RationalBezier>();
        check::<BSpline>();
        check::<Nurbs>();
        check::<Hermite>();
        check::<HermiteSpline>();
        check::<CubicSpline>();
        check::<Polyline>();
        check::<Curve>();
    }

    #[test]
    fn keeps_corners_and_searches_every_span() {
        // A zig-zag polyline with 200 vertices: uniform sampling through dyn would cut corners.
        let pts: Vec<DVec3> = (0..200)
            .map(|i| DVec3::new(i as f64, if i % 2 == 0 { 0.0 } else { 10.0 }, 0.0))
            .collect();
        let pl = Polyline::new(pts.clone()).unwrap();
        let c = Curve::from(pl.clone());
        let flat = c.flatten(0.01);
        assert_eq!(flat.len(), 200);
        for (f, p) in flat.iter().zip(&pts) {
            assert_eq!(f.1, *p);
        }
        let q = DVec3::new(150.5, 5.0, 0.0);
        let (_, d) = c.nearest(q, 1e-12);
        let (_, d_exact) = pl.nearest(q, 1e-12);
        assert_eq!(d, d_exact);
        // A B-spline with 100 spans: every span is sampled.
        let cps: Vec<DVec3> = (0..103)
            .map(|i| DVec3::new(i as f64, ((i * 37) % 11) as f64, 0.0))
            .collect();
        let b = Curve::from(BSpline::clamped_uniform(3, cps).unwrap());
        assert_eq!(b.breakpoints().len(), 101);
        let (lo, hi) = b.domain();
        for k in 0..20 {
            let t = lo + (hi - lo) * (k as f64 + 0.37) / 20.0;
            let p = b.eval(t) + 1e-3 * DVec3::Z;
            let (tt, d) = b.nearest(p, 1e-13);
            assert!((d - 1e-3).abs() < 1e-9, "t={t}: found {tt} at {d}");
        }
        // Delegation agrees with the wrapped curve.
        let arc = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 5.0, 0.0, 3.0).unwrap();
        let ca = Curve::from(arc.clone());
        assert_eq!(ca.domain(), arc.domain());
        assert_eq!(ca.deriv(0.3, 2), arc.deriv(0.3, 2));
        assert!((ca.arclen(1e-10) - 15.0).abs() < 1e-9);
        let flat = ca.flatten(0.01);
        assert!(flat.iter().all(|(_, p)| (p.length() - 5.0).abs() < 1e-12));
    }
}
