//! Elementary and swept surfaces in the parametrisation of ISO 10303-42 (STEP), the form CAD
//! files give them in: plane, cylinder, cone, sphere, torus in a placement [`Frame`], the
//! surface of linear extrusion of a curve and the surface of revolution of a curve.
//!
//! | surface | σ(u, v) |
//! |---|---|
//! | plane | `C + u x + v y` |
//! | cylinder | `C + R e(u) + v z`, `e(u) = cos u x + sin u y` |
//! | cone | `C + (R + v tan α) e(u) + v z` (v is the height along the axis) |
//! | sphere | `C + R cos v e(u) + R sin v z` |
//! | torus | `C + (R + r cos v) e(u) + r sin v z` |
//! | extrusion | `c(u) + v V` |
//! | revolution | `A + rot(a, u)(c(v) − A)` (Rodrigues' rotation about the unit axis a) |
//!
//! Angles are radians. The rational B-spline sphere, cylinder, cone and torus of
//! [`super::BSplinePatch`] trace the same shapes with rational parameters; these keep the
//! angles, so parameters read from a file (trim curves in (u, v)) mean the same points here.
//!
//! Each surface carries the parameter rectangle it is used over ([`ParamSurface::domain`]; set
//! with `with_domain`, e.g. the bounding box of a trimmed face's loops); evaluation is total for
//! every (u, v). [`Analytic::param_of`] inverts the map: the parameters of a point on (or the
//! closest point to a point near) the surface, angles unwrapped to the period nearest a hint.

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use glam::{DVec2, DVec3};

use crate::curve::CurveExt;
use crate::curve::conic::Frame;
use crate::{Domain2, ParamCurve, ParamSurface, SurfaceDerivs, SurfaceError};

/// Accuracy (mm) of the closest-point search on the swept curve of an extrusion or revolution.
const CURVE_NEAREST_ACCURACY: f64 = 1e-10;

/// Which elementary or swept surface, with its defining data.
#[derive(Clone, Debug)]
pub enum AnalyticKind {
    /// `C + u x + v y`.
    Plane,
    /// `C + R e(u) + v z`.
    Cylinder {
        /// `R` (mm, > 0).
        radius: f64,
    },
    /// `radius` at v = 0 and the semi-angle α between the axis and the cone's lines.
    Cone {
        /// `R` at v = 0 (mm, ≥ 0).
        radius: f64,
        /// α in radians, in (0, π/2).
        semi_angle: f64,
    },
    /// `C + R cos v e(u) + R sin v z`.
    Sphere {
        /// `R` (mm, > 0).
        radius: f64,
    },
    /// `C + (R + r cos v) e(u) + r sin v z`.
    Torus {
        /// `R`, the centre circle's radius (mm, above `minor`).
        major: f64,
        /// `r`, the tube's radius (mm, > 0).
        minor: f64,
    },
    /// The swept curve `c(u)` and the extrusion vector `V` (direction times length).
    Extrusion {
        /// The swept curve `c(u)`.
        curve: Arc<dyn ParamCurve>,
        /// `V`: the extrusion direction times its length (mm).
        vector: DVec3,
    },
    /// The swept curve `c(v)` turned about the axis through `frame.origin` along `frame.z`.
    Revolution {
        /// The profile `c(v)`.
        curve: Arc<dyn ParamCurve>,
    },
}

/// An elementary or swept surface (see the module documentation for the parametrisations).
#[derive(Clone, Debug)]
pub struct Analytic {
    /// The placement: `C` is `frame.origin`, the axis `frame.z`, angle 0 along `frame.x`.
    pub frame: Frame,
    /// Which surface, with its defining data.
    pub kind: AnalyticKind,
    domain: Domain2,
}

fn positive(what: &str, x: f64) -> Result<(), SurfaceError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SurfaceError::NotPositive {
            what: what.to_string(),
            value: x,
        })
    }
}

/// `x + k·TAU` for the integer k that brings it nearest to `near`.
pub fn unwrap_angle(x: f64, near: f64) -> f64 {
    x + TAU * ((near - x) / TAU).round()
}

impl Analytic {
    fn with_kind(frame: Frame, kind: AnalyticKind, domain: Domain2) -> Self {
        Self {
            frame,
            kind,
            domain,
        }
    }

    /// The plane through `frame.origin` spanned by `frame.x`, `frame.y`.
    pub fn plane(frame: Frame) -> Self {
        Self::with_kind(frame, AnalyticKind::Plane, Domain2::UNIT)
    }

    /// The cylinder of the given radius about `frame.z`.
    pub fn cylinder(frame: Frame, radius: f64) -> Result<Self, SurfaceError> {
        positive("cylinder radius", radius)?;
        Ok(Self::with_kind(
            frame,
            AnalyticKind::Cylinder { radius },
            Domain2 {
                u: (0.0, TAU),
                v: (0.0, 1.0),
            },
        ))
    }

    /// The cone about `frame.z` with `radius` ≥ 0 at v = 0 and semi-angle in (0, π/2).
    pub fn cone(frame: Frame, radius: f64, semi_angle: f64) -> Result<Self, SurfaceError> {
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(SurfaceError::Negative {
                what: "cone radius",
                value: radius,
            });
        }
        if !(semi_angle.is_finite() && semi_angle > 0.0 && semi_angle < 0.5 * PI) {
            return Err(SurfaceError::ConeAngle { semi_angle });
        }
        Ok(Self::with_kind(
            frame,
            AnalyticKind::Cone { radius, semi_angle },
            Domain2 {
                u: (0.0, TAU),
                v: (0.0, 1.0),
            },
        ))
    }

    /// The sphere of the given radius about `frame.origin`.
    pub fn sphere(frame: Frame, radius: f64) -> Result<Self, SurfaceError> {
        positive("sphere radius", radius)?;
        Ok(Self::with_kind(
            frame,
            AnalyticKind::Sphere { radius },
            Domain2 {
                u: (0.0, TAU),
                v: (-0.5 * PI, 0.5 * PI),
            },
        ))
    }

    /// The torus about `frame.z`: centre circle of radius `major`, tube of radius `minor`.
    pub fn torus(frame: Frame, major: f64, minor: f64) -> Result<Self, SurfaceError> {
        positive("torus major radius", major)?;
        positive("torus minor radius", minor)?;
        Ok(Self::with_kind(
            frame,
            AnalyticKind::Torus { major, minor },
            Domain2 {
                u: (0.0, TAU),
                v: (0.0, TAU),
            },
        ))
    }

    /// The surface swept by `curve` moving along `vector`.
    pub fn extrusion(curve: Arc<dyn ParamCurve>, vector: DVec3) -> Result<Self, SurfaceError> {
        if !flatcut_geom::finite3(vector) || vector.length_squared() == 0.0 {
            return Err(SurfaceError::ZeroVector {
                what: "extrusion vector",
            });
        }
        let (t0, t1) = curve.domain();
        Ok(Self::with_kind(
            Frame::WORLD,
            AnalyticKind::Extrusion { curve, vector },
            Domain2 {
                u: (t0, t1),
                v: (0.0, 1.0),
            },
        ))
    }

    /// The surface swept by `curve` turning about the axis through `axis_point` along
    /// `axis_dir`.
    pub fn revolution(
        curve: Arc<dyn ParamCurve>,
        axis_point: DVec3,
        axis_dir: DVec3,
    ) -> Result<Self, SurfaceError> {
        let frame = Frame::new(axis_point, axis_dir, None)?;
        let (t0, t1) = curve.domain();
        Ok(Self::with_kind(
            frame,
            AnalyticKind::Revolution { curve },
            Domain2 {
                u: (0.0, TAU),
                v: (t0, t1),
            },
        ))
    }

    /// The same surface used over the parameter rectangle `d` (finite, non-empty).
    pub fn with_domain(mut self, d: Domain2) -> Result<Self, SurfaceError> {
        let ok = |(a, b): (f64, f64)| a.is_finite() && b.is_finite() && a < b;
        if !(ok(d.u) && ok(d.v)) {
            return Err(SurfaceError::EmptyDomain { domain: d });
        }
        self.domain = d;
        Ok(self)
    }

    /// True for the developable kinds (plane, cylinder, cone, extrusion); their lines
    /// `u = const` are straight (rulings) and the surface is flat along them.
    pub fn is_developable(&self) -> bool {
        matches!(
            self.kind,
            AnalyticKind::Plane
                | AnalyticKind::Cylinder { .. }
                | AnalyticKind::Cone { .. }
                | AnalyticKind::Extrusion { .. }
        )
    }

    /// Which parameters are angles of period 2π: `(u, v)`.
    pub fn periodic(&self) -> (bool, bool) {
        match self.kind {
            AnalyticKind::Plane | AnalyticKind::Extrusion { .. } => (false, false),
            AnalyticKind::Cylinder { .. }
            | AnalyticKind::Cone { .. }
            | AnalyticKind::Sphere { .. }
            | AnalyticKind::Revolution { .. } => (true, false),
            AnalyticKind::Torus { .. } => (true, true),
        }
    }

    /// The kind's name in STEP-neutral words (`plane`, `cylinder`, …).
    pub fn name(&self) -> &'static str {
        match self.kind {
            AnalyticKind::Plane => "plane",
            AnalyticKind::Cylinder { .. } => "cylinder",
            AnalyticKind::Cone { .. } => "cone",
            AnalyticKind::Sphere { .. } => "sphere",
            AnalyticKind::Torus { .. } => "torus",
            AnalyticKind::Extrusion { .. } => "extrusion",
            AnalyticKind::Revolution { .. } => "revolution",
        }
    }

    /// The parameters `(u, v)` of `p` if it lies on the surface, else of the surface point
    /// closest to it (for the sphere and torus: on the same meridian). Angles are brought to
    /// the period nearest `near` (the parameters of a neighbouring point), or into (−π, π].
    pub fn param_of(&self, p: DVec3, near: Option<DVec2>) -> DVec2 {
        let f = &self.frame;
        let q = f.local(p);
        let angle = q.y.atan2(q.x);
        let uv = match &self.kind {
            AnalyticKind::Plane => DVec2::new(q.x, q.y),
            AnalyticKind::Cylinder { .. } | AnalyticKind::Cone { .. } => DVec2::new(angle, q.z),
            AnalyticKind::Sphere { .. } => DVec2::new(angle, q.z.atan2(q.x.hypot(q.y))),
            AnalyticKind::Torus { major, .. } => {
                DVec2::new(angle, q.z.atan2(q.x.hypot(q.y) - major))
            }
            AnalyticKind::Extrusion { curve, vector } => {
                let along = vector.normalize();
                let section = Projected {
                    curve: curve.as_ref(),
                    along,
                };
                let (t, _) = section.nearest(p - along * p.dot(along), CURVE_NEAREST_ACCURACY);
                let v = (p - curve.eval(t)).dot(*vector) / vector.length_squared();
                DVec2::new(t, v)
            }
            AnalyticKind::Revolution { curve } => {
                let meridian = Meridian {
                    curve: curve.as_ref(),
                    frame: *f,
                };
                let target = DVec3::new(q.x.hypot(q.y), q.z, 0.0);
                let (t, _) = meridian.nearest(target, CURVE_NEAREST_ACCURACY);
                let c = f.local(curve.eval(t));
                let u = q.y.atan2(q.x) - c.y.atan2(c.x);
                DVec2::new(u, t)
            }
        };
        let (pu, pv) = self.periodic();
        let u = match near {
            Some(n) if pu => unwrap_angle(uv.x, n.x),
            _ if pu => unwrap_angle(uv.x, 0.0),
            _ => uv.x,
        };
        let v = match near {
            Some(n) if pv => unwrap_angle(uv.y, n.y),
            _ => uv.y,
        };
        DVec2::new(u, v)
    }

    fn derivs(&self, u: f64, v: f64, second: bool) -> SurfaceDerivs {
        let f = &self.frame;
        let e = f.radial(u);
        let de = f.radial(u + 0.5 * PI);
        let mut d = SurfaceDerivs::default();
        match &self.kind {
            AnalyticKind::Plane => {
                d.p = f.origin + f.x * u + f.y * v;
                d.su = f.x;
                d.sv = f.y;
            }
            AnalyticKind::Cylinder { radius } => {
                d.p = f.origin + e * *radius + f.z * v;
                d.su = de * *radius;
                d.sv = f.z;
                d.suu = -e * *radius;
            }
            AnalyticKind::Cone { radius, semi_angle } => {
                let k = semi_angle.tan();
                let r = radius + v * k;
                d.p = f.origin + e * r + f.z * v;
                d.su = de * r;
                d.sv = e * k + f.z;
                d.suu = -e * r;
                d.suv = de * k;
            }
            AnalyticKind::Sphere { radius } => {
                let (sv, cv) = v.sin_cos();
                d.p = f.origin + (e * cv + f.z * sv) * *radius;
                d.su = de * (radius * cv);
                d.sv = (f.z * cv - e * sv) * *radius;
                d.suu = -e * (radius * cv);
                d.suv = -de * (radius * sv);
                d.svv = -(e * cv + f.z * sv) * *radius;
            }
            AnalyticKind::Torus { major, minor } => {
                let (sv, cv) = v.sin_cos();
                let r = major + minor * cv;
                d.p = f.origin + e * r + f.z * (minor * sv);
                d.su = de * r;
                d.sv = (f.z * cv - e * sv) * *minor;
                d.suu = -e * r;
                d.suv = -de * (minor * sv);
                d.svv = -(e * cv + f.z * sv) * *minor;
            }
            AnalyticKind::Extrusion { curve, vector } => {
                d.p = curve.eval(u) + *vector * v;
                d.su = curve.deriv(u, 1);
                d.sv = *vector;
                if second {
                    d.suu = curve.deriv(u, 2);
                }
            }
            AnalyticKind::Revolution { curve } => {
                let a = f.z;
                let (s, c) = u.sin_cos();
                // Rodrigues: rot(x) = x cos u + (a × x) sin u + a (a·x)(1 − cos u), and its
                // derivative in u: −x sin u + (a × x) cos u + a (a·x) sin u.
                let rot = |x: DVec3| x * c + a.cross(x) * s + a * (a.dot(x) * (1.0 - c));
                let rot_u = |x: DVec3| -x * s + a.cross(x) * c + a * (a.dot(x) * s);
                let rot_uu = |x: DVec3| -x * c - a.cross(x) * s + a * (a.dot(x) * c);
                let x = curve.eval(v) - f.origin;
                let x1 = curve.deriv(v, 1);
                d.p = f.origin + rot(x);
                d.su = rot_u(x);
                d.sv = rot(x1);
                if second {
                    d.suu = rot_uu(x);
                    d.suv = rot_u(x1);
                    d.svv = rot(curve.deriv(v, 2));
                }
            }
        }
        d
    }
}

impl ParamSurface for Analytic {
    fn domain(&self) -> Domain2 {
        self.domain
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.derivs(u, v, false).p
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let d = self.derivs(u, v, false);
        (d.p, d.su, d.sv)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        self.derivs(u, v, true)
    }
}

/// A curve with its component along a unit direction removed: the cross-section of an
/// extrusion, for the closest-point search.
#[derive(Debug)]
struct Projected<'a> {
    curve: &'a dyn ParamCurve,
    along: DVec3,
}

impl ParamCurve for Projected<'_> {
    fn domain(&self) -> (f64, f64) {
        self.curve.domain()
    }
    fn eval(&self, t: f64) -> DVec3 {
        self.deriv(t, 0)
    }
    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        let d = self.curve.deriv(t, k);
        d - self.along * d.dot(self.along)
    }
}

/// A swept curve as (distance from the axis, height along it, 0): the meridian of a surface of
/// revolution, for the closest-point search.
#[derive(Debug)]
struct Meridian<'a> {
    curve: &'a dyn ParamCurve,
    frame: Frame,
}

impl ParamCurve for Meridian<'_> {
    fn domain(&self) -> (f64, f64) {
        self.curve.domain()
    }
    fn eval(&self, t: f64) -> DVec3 {
        self.deriv(t, 0)
    }
    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        let a = self.frame.z;
        let perp = |x: DVec3| x - a * x.dot(a);
        let w = perp(self.curve.eval(t) - self.frame.origin);
        let rho = w.length();
        let h = (self.curve.eval(t) - self.frame.origin).dot(a);
        if k == 0 {
            return DVec3::new(rho, h, 0.0);
        }
        let d1 = self.curve.deriv(t, 1);
        let w1 = perp(d1);
        if rho == 0.0 {
            // On the axis the distance is not differentiable; its one-sided slope is |w'|.
            return if k == 1 {
                DVec3::new(w1.length(), d1.dot(a), 0.0)
            } else {
                DVec3::ZERO
            };
        }
        let rho1 = w.dot(w1) / rho;
        match k {
            1 => DVec3::new(rho1, d1.dot(a), 0.0),
            2 => {
                let d2 = self.curve.deriv(t, 2);
                let w2 = perp(d2);
                let rho2 = (w1.dot(w1) + w.dot(w2)) / rho - rho1 * rho1 / rho;
                DVec3::new(rho2, d2.dot(a), 0.0)
            }
            _ => DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::conic::{Ellipse, Line};
    use crate::curve::{BSpline, Nurbs};
    use crate::patch::testutil::check_derivs_fd;

    fn frame() -> Frame {
        Frame::new(
            DVec3::new(5.0, -3.0, 2.0),
            DVec3::new(0.2, 0.1, 1.0),
            Some(DVec3::new(1.0, 0.3, 0.0)),
        )
        .unwrap()
    }

    fn profile() -> Arc<dyn ParamCurve> {
        Arc::new(
            BSpline::clamped_uniform(
                3,
                vec![
                    DVec3::new(20.0, 0.0, 0.0),
                    DVec3::new(30.0, 5.0, 10.0),
                    DVec3::new(25.0, -4.0, 25.0),
                    DVec3::new(35.0, 2.0, 40.0),
                ],
            )
            .unwrap(),
        )
    }

    fn all() -> Vec<Analytic> {
        let f = frame();
        vec![
            Analytic::plane(f),
            Analytic::cylinder(f, 30.0).unwrap(),
            Analytic::cone(f, 12.0, 0.4).unwrap(),
            Analytic::sphere(f, 25.0).unwrap(),
            Analytic::torus(f, 40.0, 10.0).unwrap(),
            Analytic::extrusion(profile(), DVec3::new(3.0, 40.0, 5.0)).unwrap(),
            Analytic::revolution(profile(), f.origin, f.z).unwrap(),
        ]
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for s in all() {
            let s = s
                .with_domain(Domain2 {
                    u: (0.2, 1.1),
                    v: (0.1, 0.9),
                })
                .unwrap();
            check_derivs_fd(&s, 1e-6);
        }
    }

    #[test]
    fn param_of_inverts_eval() {
        for s in all() {
            for &(u, v) in &[(0.3, 0.2), (0.9, 0.7), (0.6, 0.45)] {
                let p = s.eval(u, v);
                let uv = s.param_of(p, Some(DVec2::new(u + 0.1, v - 0.05)));
                assert!(
                    (uv - DVec2::new(u, v)).length() < 1e-8,
                    "{}: ({u}, {v}) came back as {uv}",
                    s.name()
                );
            }
        }
    }

    #[test]
    fn angles_unwrap_to_the_period_of_the_hint() {
        let s = Analytic::cylinder(frame(), 30.0).unwrap();
        let p = s.eval(0.1, 5.0);
        assert!((s.param_of(p, Some(DVec2::new(6.2, 5.0))).x - (0.1 + TAU)).abs() < 1e-12);
        assert!((s.param_of(p, None).x - 0.1).abs() < 1e-12);
    }

    #[test]
    fn shapes_are_the_named_ones() {
        let f = frame();
        // Every point of the cylinder is at its radius from the axis, of the sphere at its
        // radius from the centre, of the torus at the tube radius from the centre circle.
        let cyl = Analytic::cylinder(f, 30.0).unwrap();
        let sph = Analytic::sphere(f, 25.0).unwrap();
        let tor = Analytic::torus(f, 40.0, 10.0).unwrap();
        let cone = Analytic::cone(f, 12.0, 0.4).unwrap();
        for &(u, v) in &[(0.0, 0.3), (1.3, -0.7), (4.0, 1.2)] {
            let q = f.local(cyl.eval(u, v));
            assert!((q.x.hypot(q.y) - 30.0).abs() < 1e-12);
            assert!((sph.eval(u, v) - f.origin).length() - 25.0 < 1e-12);
            let q = f.local(tor.eval(u, v));
            assert!(((q.x.hypot(q.y) - 40.0).hypot(q.z) - 10.0).abs() < 1e-12);
            let q = f.local(cone.eval(u, v));
            assert!((q.x.hypot(q.y) - (12.0 + q.z * 0.4f64.tan())).abs() < 1e-12);
        }
        // The lines u = const of the developable kinds are straight.
        for s in [&cyl, &cone] {
            assert!(s.is_developable());
            let (a, b, c) = (s.eval(0.7, -3.0), s.eval(0.7, 1.0), s.eval(0.7, 9.0));
            assert!((b - a).cross(c - a).length() < 1e-9);
        }
        assert!(!sph.is_developable() && !tor.is_developable());
        // A revolved circle about its plane's axis is the same torus.
        let circle = Ellipse::circle(
            Frame::new(f.origin + f.x * 40.0, f.y, Some(f.x)).unwrap(),
            10.0,
        )
        .unwrap();
        let rev = Analytic::revolution(Arc::new(circle), f.origin, f.z).unwrap();
        for &(u, v) in &[(0.3, 0.2), (2.0, 4.0)] {
            let q = f.local(rev.eval(u, v));
            assert!(((q.x.hypot(q.y) - 40.0).hypot(q.z) - 10.0).abs() < 1e-12);
        }
        // An extruded line is a plane strip; an extruded NURBS arc a cylinder piece.
        let arc = Nurbs::circle_arc(DVec3::ZERO, DVec3::X, DVec3::Y, 15.0, 0.0, 1.5).unwrap();
        let ext = Analytic::extrusion(Arc::new(arc), DVec3::Z * 10.0).unwrap();
        let q = ext.eval(0.4, 0.3);
        assert!((q.truncate().length() - 15.0).abs() < 1e-12 && (q.z - 3.0).abs() < 1e-12);
        let line = Line::new(DVec3::ZERO, DVec3::X).unwrap();
        let strip = Analytic::extrusion(Arc::new(line), DVec3::Y).unwrap();
        assert_eq!(strip.eval(2.0, 3.0), DVec3::new(2.0, 3.0, 0.0));
    }
}
