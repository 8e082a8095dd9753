//! The curves and surfaces a STEP model is made of, as flatcut-surface types: lines, circles and
//! ellipses ([`Line`], [`Ellipse`]), B-spline and NURBS curves, polylines, curves on surfaces;
//! the elementary and swept surfaces ([`Analytic`]) and B-spline/NURBS patches
//! ([`BSplinePatch`]). Lengths are in mm (converted when read).
//!
//! [`Surface::param_of`] finds the (u, v) of a point of the surface: in closed form for the
//! analytic kinds (both branches of a cone's two nappes and of a spindle torus tried), by Newton
//! iteration on the squared distance for patches (from a hint, or from the best point of a sample
//! grid), to [`PROJECT_ACCURACY`].
//!
//! The shape of a surface's parameter space, which trimming needs: the periods of its periodic
//! directions ([`Surface::periods`]: the angles of the elementary and swept surfaces, and a patch
//! whose opposite sides meet, evaluated modulo its domain — [`Spline`]), and its poles
//! ([`Surface::free_direction`]: points where one parameter does not move the point, a sphere's
//! poles or a cone's apex).

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use flatcut_geom::{DVec2, DVec3};
use flatcut_surface::curve::{BSpline, Ellipse, Line, Nurbs, Polyline};
use flatcut_surface::patch::analytic::unwrap_angle;
use flatcut_surface::patch::{Analytic, AnalyticKind, BSplinePatch};
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
/// A patch whose opposite sides lie within this fraction of its size of each other, point for
/// point, is closed in that direction.
const CLOSED_REL: f64 = 1e-7;
/// Points compared along a side to decide that a patch is closed, or a side collapsed.
const SIDE_SAMPLES: usize = 12;

/// A curve of the model (3D, mm) or of a parameter space (z = 0, unscaled).
#[derive(Clone, Debug)]
pub enum Curve {
    /// A straight line.
    Line(Line),
    /// A circle or an ellipse.
    Conic(Ellipse),
    /// A polynomial B-spline curve.
    BSpline(BSpline),
    /// A rational B-spline (NURBS) curve.
    Nurbs(Nurbs),
    /// Straight segments through points.
    Polyline(Polyline),
    /// A curve in the (u, v) space of a surface (its x, y), mapped onto the surface.
    OnSurface {
        /// The curve in (u, v) (its x, y; z = 0).
        uv: Arc<Curve>,
        /// The surface it lies on.
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
    /// A plane, cylinder, cone, sphere, torus, extrusion or revolution in its STEP parametrisation.
    Analytic(Analytic),
    /// A B-spline or NURBS patch.
    Spline(Spline),
}

/// A B-spline or NURBS patch, and the directions in which its opposite sides meet (a tube, a
/// ring): those are periodic with the domain's width as period, evaluated modulo the domain.
#[derive(Clone, Debug)]
pub struct Spline {
    /// The patch in model space (mm).
    pub patch: BSplinePatch,
    /// The period of u and of v, when the patch closes on itself in that direction.
    pub period: [Option<f64>; 2],
    /// The file's u domain `[a, b]` when the file's patch closes in v only: it is held turned
    /// ([`BSplinePatch::turned`]), so that its closed direction is u as the trimming expects,
    /// and the file's (u, v) (its p-curves) map to `(v, a + b − u)`.
    pub turned: Option<(f64, f64)>,
}

impl Spline {
    /// The patch, with its closed directions found by comparing its opposite sides; a patch
    /// closed in v only is turned so that it closes in u.
    pub fn new(patch: BSplinePatch) -> Self {
        let s = Self::as_given(patch);
        if let [None, Some(_)] = s.period
            && let Ok(t) = s.patch.turned()
        {
            let d = s.patch.domain();
            let mut out = Self::as_given(t);
            if let [Some(_), None] = out.period {
                out.turned = Some(d.u);
                return out;
            }
        }
        s
    }

    /// The (u, v) of this surface for a (u, v) of the file's patch (a p-curve's point).
    pub fn from_file(&self, q: DVec2) -> DVec2 {
        match self.turned {
            Some((a, b)) => DVec2::new(q.y, a + b - q.x),
            None => q,
        }
    }

    /// The patch as given, with its closed directions found by comparing its opposite sides.
    fn as_given(patch: BSplinePatch) -> Self {
        let d = patch.domain();
        let size = flatcut_geom::Aabb3::from_points(patch.points().iter().copied()).diagonal();
        let tol = (CLOSED_REL * size).max(1e-12);
        let side = |t: f64, along_u: bool, at_start: bool| -> DVec3 {
            let (u, v) = if along_u {
                (
                    d.u.0 + (d.u.1 - d.u.0) * t,
                    if at_start { d.v.0 } else { d.v.1 },
                )
            } else {
                (
                    if at_start { d.u.0 } else { d.u.1 },
                    d.v.0 + (d.v.1 - d.v.0) * t,
                )
            };
            patch.eval(u, v)
        };
        let ts: Vec<f64> = (0..=SIDE_SAMPLES)
            .map(|k| k as f64 / SIDE_SAMPLES as f64)
            .collect();
        // Closed in u: the sides u = u0 and u = u1 (which run along v) coincide and are not points.
        let closed = |along_u: bool| {
            let a: Vec<DVec3> = ts.iter().map(|&t| side(t, along_u, true)).collect();
            let b: Vec<DVec3> = ts.iter().map(|&t| side(t, along_u, false)).collect();
            let len: f64 = a.windows(2).map(|w| w[0].distance(w[1])).sum();
            len > 100.0 * tol && a.iter().zip(&b).all(|(p, q)| p.distance(*q) <= tol)
        };
        let period = [
            closed(false).then_some(d.u.1 - d.u.0),
            closed(true).then_some(d.v.1 - d.v.0),
        ];
        Self {
            patch,
            period,
            turned: None,
        }
    }

    /// (u, v) brought into the domain in the closed directions.
    fn wrap(&self, u: f64, v: f64) -> (f64, f64) {
        let d = self.patch.domain();
        let w = |x: f64, lo: f64, p: Option<f64>| match p {
            Some(p) if x < lo || x > lo + p => lo + (x - lo).rem_euclid(p),
            _ => x,
        };
        (w(u, d.u.0, self.period[0]), w(v, d.v.0, self.period[1]))
    }
}

impl ParamSurface for Spline {
    fn domain(&self) -> Domain2 {
        self.patch.domain()
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        let (u, v) = self.wrap(u, v);
        self.patch.eval(u, v)
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let (u, v) = self.wrap(u, v);
        self.patch.deriv1(u, v)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        let (u, v) = self.wrap(u, v);
        self.patch.deriv2(u, v)
    }
}

impl Surface {
    /// `plane`, `cylinder`, `cone`, `sphere`, `torus`, `extrusion`, `revolution`, `bspline` or
    /// `nurbs`.
    pub fn name(&self) -> &'static str {
        match self {
            Surface::Analytic(a) => a.name(),
            Surface::Spline(s) if s.patch.is_rational() => "nurbs",
            Surface::Spline(_) => "bspline",
        }
    }

    /// True for the kinds that are developable by construction (plane, cylinder, cone,
    /// extrusion): their lines u = const are straight and flat.
    pub fn is_ruled_developable(&self) -> bool {
        matches!(self, Surface::Analytic(a) if a.is_developable())
    }

    /// This surface's (u, v) for a (u, v) of the file's surface entity (a p-curve's point).
    pub fn from_file(&self, q: DVec2) -> DVec2 {
        match self {
            Surface::Spline(s) => s.from_file(q),
            Surface::Analytic(_) => q,
        }
    }

    /// The (u, v) of the point of the surface nearest `p` (for a patch: the local minimum
    /// reached from `near`, or from the best sample when there is no hint). Angles of the
    /// analytic kinds are unwrapped to the period nearest `near`.
    pub fn param_of(&self, p: DVec3, near: Option<DVec2>) -> DVec2 {
        match self {
            Surface::Analytic(a) => analytic_param_of(a, p, near),
            Surface::Spline(s) => {
                let start = near.unwrap_or_else(|| sample_start(&s.patch, p));
                let uv = project(s, p, start);
                match near {
                    // Periodic directions continue from the hint.
                    Some(n) => DVec2::new(
                        s.period[0].map_or(uv.x, |pd| uv.x + pd * ((n.x - uv.x) / pd).round()),
                        s.period[1].map_or(uv.y, |pd| uv.y + pd * ((n.y - uv.y) / pd).round()),
                    ),
                    None => uv,
                }
            }
        }
    }

    /// The periods of u and v (`None` for a direction that is not periodic).
    pub fn periods(&self) -> [Option<f64>; 2] {
        match self {
            Surface::Analytic(a) => {
                let (pu, pv) = a.periodic();
                [pu.then_some(TAU), pv.then_some(TAU)]
            }
            Surface::Spline(s) => s.period,
        }
    }

    /// The direction (0 = u, 1 = v) in which the parameter does not move the point at `uv` —
    /// a pole of a sphere, a cone's apex, a collapsed side of a patch — when a whole period (or
    /// the domain's width) of it covers less than `tol` mm.
    pub fn free_direction(&self, uv: DVec2, tol: f64) -> Option<usize> {
        let (_, su, sv) = self.deriv1(uv.x, uv.y);
        let d = self.domain();
        let [pu, pv] = self.periods();
        let span = [pu.unwrap_or(d.u.1 - d.u.0), pv.unwrap_or(d.v.1 - d.v.0)];
        let moves = [su.length() * span[0], sv.length() * span[1]];
        match (moves[0] <= tol, moves[1] <= tol) {
            (true, false) => Some(0),
            (false, true) => Some(1),
            _ => None,
        }
    }

    /// The value of v beyond `v` (towards larger v when `up`) where the surface closes in a
    /// pole (a sphere's pole, a cone's apex, the end of a meridian on the axis of a surface of
    /// revolution, a collapsed side of a patch), if it has one: the side a loop winding once
    /// around u bounds, with the pole as the rest of the boundary.
    pub fn pole_beyond(&self, v: f64, up: bool, tol: f64) -> Option<f64> {
        let candidate = match self {
            Surface::Analytic(a) => match &a.kind {
                AnalyticKind::Sphere { .. } => Some(if up { 0.5 * PI } else { -0.5 * PI }),
                AnalyticKind::Cone { radius, semi_angle } => Some(-radius / semi_angle.tan()),
                AnalyticKind::Revolution { curve } => {
                    let (t0, t1) = curve.domain();
                    Some(if up { t1 } else { t0 })
                }
                _ => None,
            },
            Surface::Spline(s) => {
                let d = s.patch.domain();
                Some(if up { d.v.1 } else { d.v.0 })
            }
        }?;
        if (candidate > v) != up {
            return None;
        }
        // A pole: the whole circle of u at that v is one point.
        let d = self.domain();
        let span = self.periods()[0].unwrap_or(d.u.1 - d.u.0);
        let a = self.eval(d.u.0, candidate);
        let closes = (1..=SIDE_SAMPLES).all(|k| {
            self.eval(d.u.0 + span * k as f64 / SIDE_SAMPLES as f64, candidate)
                .distance(a)
                <= tol
        });
        closes.then_some(candidate)
    }
}

/// The (u, v) of `p` on an analytic surface: the closed form, and for a cone (both nappes) and
/// a torus (a spindle torus, whose tube crosses its axis, reaches a point from both half-planes)
/// the other branch too, whichever lies nearer.
fn analytic_param_of(a: &Analytic, p: DVec3, near: Option<DVec2>) -> DVec2 {
    let uv = a.param_of(p, near);
    let other = match &a.kind {
        AnalyticKind::Cone { .. } => DVec2::new(uv.x + PI, uv.y),
        AnalyticKind::Torus { major, .. } => {
            let q = a.frame.local(p);
            let v = q.z.atan2(-q.x.hypot(q.y) - major);
            DVec2::new(uv.x + PI, v)
        }
        _ => return uv,
    };
    let other = match near {
        Some(n) => DVec2::new(
            unwrap_angle(other.x, n.x),
            if a.periodic().1 {
                unwrap_angle(other.y, n.y)
            } else {
                other.y
            },
        ),
        None => DVec2::new(unwrap_angle(other.x, 0.0), other.y),
    };
    let gap = |w: DVec2| a.eval(w.x, w.y).distance(p);
    if gap(other) < gap(uv) { other } else { uv }
}

impl ParamSurface for Surface {
    fn domain(&self) -> Domain2 {
        match self {
            Surface::Analytic(a) => a.domain(),
            Surface::Spline(s) => s.patch.domain(),
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

/// `uv` kept in the domain `d`, except in the periodic directions (`period` set).
fn clamp_to(d: &Domain2, period: [Option<f64>; 2], uv: DVec2) -> DVec2 {
    DVec2::new(
        if period[0].is_some() {
            uv.x
        } else {
            uv.x.clamp(d.u.0, d.u.1)
        },
        if period[1].is_some() {
            uv.y
        } else {
            uv.y.clamp(d.v.0, d.v.1)
        },
    )
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

/// Newton iteration on |S(u, v) − p|² from `start`, kept in the domain (but for the patch's
/// periodic directions), with step halving when a step does not bring the point closer.
pub fn project(s: &Spline, p: DVec3, start: DVec2) -> DVec2 {
    let d = s.domain();
    let mut uv = clamp_to(&d, s.period, start);
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
            let next = clamp_to(&d, s.period, uv + step * lambda);
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
    fn a_patch_closed_in_v_only_is_turned_to_close_in_u() {
        // The exact NURBS cylinder: u along the axis, v around it (closed in v only).
        let file = BSplinePatch::cylinder(DVec3::new(1.0, 2.0, 3.0), 40.0, 90.0).unwrap();
        let s = Spline::new(file.clone());
        assert!(s.turned.is_some());
        assert!(
            s.period[0].is_some() && s.period[1].is_none(),
            "{:?}",
            s.period
        );
        let surface = Surface::Spline(s);
        for (u, v) in [(0.1, 0.2), (0.5, 0.75), (0.9, 0.05), (0.0, 1.0)] {
            let q = surface.from_file(DVec2::new(u, v));
            assert!(surface.eval(q.x, q.y).distance(file.eval(u, v)) < 1e-9);
            let (_, fu, fv) = file.deriv1(u, v);
            let (_, su, sv) = surface.deriv1(q.x, q.y);
            let (nf, ns) = (fu.cross(fv).normalize(), su.cross(sv).normalize());
            assert!(
                nf.dot(ns) > 1.0 - 1e-9,
                "the normal turned with the parameters"
            );
        }
    }

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
        let s = Surface::Spline(Spline::new(
            BSplinePatch::new(3, 3, k5, k4, 5, 4, pts, None).unwrap(),
        ));
        for &(u, v) in &[(0.1, 0.2), (0.77, 0.9), (0.5, 0.5), (0.0, 1.0)] {
            let p = s.eval(u, v);
            let uv = s.param_of(p, None);
            assert!(s.eval(uv.x, uv.y).distance(p) < 1e-8, "({u}, {v}) → {uv}");
            let uv = s.param_of(p, Some(DVec2::new(u + 0.05, v - 0.05)));
            assert!((uv - DVec2::new(u, v)).length() < 1e-8);
        }
    }
}
