//! The curves and surfaces a STEP model is made of, as flatcut-surface types: lines, circles and
//! ellipses ([`Line`], [`Ellipse`]), B-spline and NURBS curves, polylines, curves on surfaces;
//! the elementary and swept surfaces ([`Analytic`]) and B-spline/NURBS patches
//! ([`BSplinePatch`]). Lengths are in mm (converted when read).
//!
//! [`Surface::param_of`] finds the (u, v) of a point of the surface: in closed form for the
//! analytic kinds, by Newton iteration on the squared distance for patches (from a hint, or from
//! the best point of a sample grid), to [`PROJECT_ACCURACY`].

use std::sync::Arc;

use flatcut_geom::{DVec2, DVec3};
use flatcut_surface::curve::{BSpline, Ellipse, Line, Nurbs, Polyline};
use flatcut_surface::patch::{Analytic, BSplinePatch};
use flatcut_surface::{Domain2, ParamCurve, ParamSurface, SurfaceDerivs};

/// Parameter points projected onto a patch converge to within this distance of their closest
/// point (mm): far below any chordal tolerance, far above round-off for mm-sized models.
pub const PROJECT_ACCURACY: f64 = 1e-9;
/// Newton steps of the projection onto a patch.
const PROJECT_MAX_STEPS: usize = 60;
/// Samples per knot span (and at least this many per direction) for the global start of a
/// projection without a hint.
const PROJECT_SAMPLES: usize = 8;
/// At most this many samples per direction for that start.
const PROJECT_MAX_SAMPLES: usize = 96;

/// A curve of the model (3D, mm) or of a parameter space (z = 0, unscaled).
#[derive(Clone, Debug)]
pub enum Curve {
    Line(Line),
    /// A circle or an ellipse.
    Conic(Ellipse),
    BSpline(BSpline),
    Nurbs(Nurbs),
    Polyline(Polyline),
    /// A curve in the (u, v) space of a surface (its x, y), mapped onto the surface.
    OnSurface {
        uv: Arc<Curve>,
        surface: Arc<Surface>,
    },
}

impl Curve {
    /// Parameters where derivatives may jump (knots), within the domain, for flattening.
    pub fn breakpoints(&self) -> Vec<f64> {
        match self {
            Curve::BSpline(c) => c.breakpoints(),
            Curve::Nurbs(c) => c.breakpoints(),
            Curve::Polyline(c) => c.params().to_vec(),
            Curve::OnSurface { uv, .. } => uv.breakpoints(),
            Curve::Line(_) | Curve::Conic(_) => Vec::new(),
        }
    }

    /// True for the curves whose parameter is a periodic angle (circles, ellipses).
    pub fn is_periodic(&self) -> bool {
        matches!(self, Curve::Conic(_))
    }

    /// The curve's name in messages and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Curve::Line(_) => "line",
            Curve::Conic(e) if e.a == e.b => "circle",
            Curve::Conic(_) => "ellipse",
            Curve::BSpline(_) => "bspline",
            Curve::Nurbs(_) => "nurbs",
            Curve::Polyline(_) => "polyline",
            Curve::OnSurface { .. } => "curve on surface",
        }
    }
}

impl ParamCurve for Curve {
    fn domain(&self) -> (f64, f64) {
        match self {
            Curve::Line(c) => c.domain(),
            Curve::Conic(c) => c.domain(),
            Curve::BSpline(c) => c.domain(),
            Curve::Nurbs(c) => c.domain(),
            Curve::Polyline(c) => c.domain(),
            Curve::OnSurface { uv, .. } => uv.domain(),
        }
    }

    fn eval(&self, t: f64) -> DVec3 {
        match self {
            Curve::Line(c) => c.eval(t),
            Curve::Conic(c) => c.eval(t),
            Curve::BSpline(c) => c.eval(t),
            Curve::Nurbs(c) => c.eval(t),
            Curve::Polyline(c) => c.eval(t),
            Curve::OnSurface { uv, surface } => {
                let q = uv.eval(t);
                surface.eval(q.x, q.y)
            }
        }
    }

    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        match self {
            Curve::Line(c) => c.deriv(t, k),
            Curve::Conic(c) => c.deriv(t, k),
            Curve::BSpline(c) => c.deriv(t, k),
            Curve::Nurbs(c) => c.deriv(t, k),
            Curve::Polyline(c) => c.deriv(t, k),
            Curve::OnSurface { uv, surface } => {
                let q = uv.eval(t);
                match k {
                    0 => surface.eval(q.x, q.y),
                    1 => {
                        let d = uv.deriv(t, 1);
                        let (_, su, sv) = surface.deriv1(q.x, q.y);
                        su * d.x + sv * d.y
                    }
                    2 => {
                        let (d1, d2) = (uv.deriv(t, 1), uv.deriv(t, 2));
                        let s = surface.deriv2(q.x, q.y);
                        s.suu * (d1.x * d1.x)
                            + s.suv * (2.0 * d1.x * d1.y)
                            + s.svv * (d1.y * d1.y)
                            + s.su * d2.x
                            + s.sv * d2.y
                    }
                    // Third and higher derivatives are not needed by flattening or nearest.
                    _ => DVec3::ZERO,
                }
            }
        }
    }
}

/// A surface of the model.
#[derive(Clone, Debug)]
pub enum Surface {
    Analytic(Analytic),
    Spline(BSplinePatch),
}

impl Surface {
    /// `plane`, `cylinder`, `cone`, `sphere`, `torus`, `extrusion`, `revolution`, `bspline` or
    /// `nurbs`.
    pub fn name(&self) -> &'static str {
        match self {
            Surface::Analytic(a) => a.name(),
            Surface::Spline(s) if s.is_rational() => "nurbs",
            Surface::Spline(_) => "bspline",
        }
    }

    /// True for the kinds that are developable by construction (plane, cylinder, cone,
    /// extrusion): their lines u = const are straight and flat.
    pub fn is_ruled_developable(&self) -> bool {
        matches!(self, Surface::Analytic(a) if a.is_developable())
    }

    /// The (u, v) of the point of the surface nearest `p` (for a patch: the local minimum
    /// reached from `near`, or from the best sample when there is no hint). Angles of the
    /// analytic kinds are unwrapped to the period nearest `near`.
    pub fn param_of(&self, p: DVec3, near: Option<DVec2>) -> DVec2 {
        match self {
            Surface::Analytic(a) => a.param_of(p, near),
            Surface::Spline(s) => {
                let start = near.unwrap_or_else(|| sample_start(s, p));
                project(s, p, start)
            }
        }
    }
}

impl ParamSurface for Surface {
    fn domain(&self) -> Domain2 {
        match self {
            Surface::Analytic(a) => a.domain(),
            Surface::Spline(s) => s.domain(),
        }
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        match self {
            Surface::Analytic(a) => a.eval(u, v),
            Surface::Spline(s) => s.eval(u, v),
        }
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        match self {
            Surface::Analytic(a) => a.deriv1(u, v),
            Surface::Spline(s) => s.deriv1(u, v),
        }
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        match self {
            Surface::Analytic(a) => a.deriv2(u, v),
            Surface::Spline(s) => s.deriv2(u, v),
        }
    }
}

fn clamp_to(d: &Domain2, uv: DVec2) -> DVec2 {
    DVec2::new(uv.x.clamp(d.u.0, d.u.1), uv.y.clamp(d.v.0, d.v.1))
}

/// The best point of a sample grid over the patch's domain (more samples for more knot spans).
fn sample_start(s: &BSplinePatch, p: DVec3) -> DVec2 {
    let d = s.domain();
    let (ku, kv) = s.knots();
    let spans = |k: &[f64]| {
        let mut x: Vec<f64> = k.to_vec();
        x.dedup();
        x.len().saturating_sub(1).max(1)
    };
    let nu = (spans(ku) * PROJECT_SAMPLES).clamp(PROJECT_SAMPLES, PROJECT_MAX_SAMPLES);
    let nv = (spans(kv) * PROJECT_SAMPLES).clamp(PROJECT_SAMPLES, PROJECT_MAX_SAMPLES);
    let mut best = (f64::INFINITY, DVec2::new(d.u.0, d.v.0));
    for i in 0..=nu {
        for j in 0..=nv {
            let uv = DVec2::new(
                d.u.0 + (d.u.1 - d.u.0) * i as f64 / nu as f64,
                d.v.0 + (d.v.1 - d.v.0) * j as f64 / nv as f64,
            );
            let q = s.eval(uv.x, uv.y).distance_squared(p);
            if q < best.0 {
                best = (q, uv);
            }
        }
    }
    best.1
}

/// Newton iteration on |S(u, v) − p|² from `start`, kept in the domain, with step halving when a
/// step does not bring the point closer.
pub fn project(s: &dyn ParamSurface, p: DVec3, start: DVec2) -> DVec2 {
    let d = s.domain();
    let mut uv = clamp_to(&d, start);
    let mut dist = s.eval(uv.x, uv.y).distance(p);
    for _ in 0..PROJECT_MAX_STEPS {
        let (q, su, sv) = s.deriv1(uv.x, uv.y);
        let r = p - q;
        let (a, b, c) = (su.dot(su), su.dot(sv), sv.dot(sv));
        let (gu, gv) = (su.dot(r), sv.dot(r));
        let det = a * c - b * b;
        if !(det.is_finite() && det > 0.0) {
            break;
        }
        let step = DVec2::new((c * gu - b * gv) / det, (a * gv - b * gu) / det);
        let mut lambda = 1.0;
        let mut moved = false;
        for _ in 0..12 {
            let next = clamp_to(&d, uv + step * lambda);
            let nd = s.eval(next.x, next.y).distance(p);
            if nd <= dist {
                let len = (s.eval(next.x, next.y) - s.eval(uv.x, uv.y)).length();
                uv = next;
                dist = nd;
                moved = len > PROJECT_ACCURACY;
                break;
            }
            lambda *= 0.5;
        }
        if !moved {
            break;
        }
    }
    uv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_onto_a_patch_finds_the_parameters() {
        let mut pts = Vec::new();
        for i in 0..5 {
            for j in 0..4 {
                let (x, y) = (i as f64 * 20.0, j as f64 * 25.0);
                pts.push(DVec3::new(
                    x,
                    y,
                    0.002 * (x - 40.0).powi(2) + 3.0 * (y / 30.0).sin(),
                ));
            }
        }
        let k5 = vec![0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0];
        let k4 = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let s = Surface::Spline(BSplinePatch::new(3, 3, k5, k4, 5, 4, pts, None).unwrap());
        for &(u, v) in &[(0.1, 0.2), (0.77, 0.9), (0.5, 0.5), (0.0, 1.0)] {
            let p = s.eval(u, v);
            let uv = s.param_of(p, None);
            assert!(s.eval(uv.x, uv.y).distance(p) < 1e-8, "({u}, {v}) → {uv}");
            let uv = s.param_of(p, Some(DVec2::new(u + 0.05, v - 0.05)));
            assert!((uv - DVec2::new(u, v)).length() < 1e-8);
        }
    }
}
