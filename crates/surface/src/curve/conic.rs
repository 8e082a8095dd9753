//! Lines, circles and ellipses in the parametrisation of ISO 10303-42 (STEP), the form CAD files
//! give them in: a line `P + t·V`, a circle `C + R (cos t·x + sin t·y)` and an ellipse
//! `C + a cos t·x + b sin t·y` in a placement frame, `t` in radians for the conics.
//!
//! The NURBS arcs of [`super::Nurbs::circle_arc`] trace the same circles with a rational
//! parameter; these types keep the angle, so a parameter read from a file means the same point
//! here. Each carries the parameter interval it is used over (`with_domain`); evaluation is total
//! for every `t`.

use glam::DVec3;

use crate::{ParamCurve, SurfaceError};

/// A right-handed orthonormal frame: origin and axes `x`, `y`, `z = x × y` (STEP's
/// `AXIS2_PLACEMENT_3D`: `z` is the axis, `x` the reference direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The frame's origin (mm): the centre of a circle, ellipse, sphere or torus.
    pub origin: DVec3,
    /// Unit reference direction, where angle 0 lies.
    pub x: DVec3,
    /// Unit `z × x`: angle π/2.
    pub y: DVec3,
    /// The unit axis.
    pub z: DVec3,
}

/// Smallest length of the reference direction left after removing its component along the axis,
/// relative to its own length: below this the two directions are parallel and the frame is
/// undefined.
const FRAME_PARALLEL_REL: f64 = 1e-12;

impl Frame {
    /// The world frame.
    pub const WORLD: Self = Self {
        origin: DVec3::ZERO,
        x: DVec3::X,
        y: DVec3::Y,
        z: DVec3::Z,
    };

    /// A frame from an origin, an axis and a reference direction (neither needs unit length);
    /// the reference direction is made orthogonal to the axis as STEP prescribes. Without a
    /// reference direction an arbitrary one orthogonal to the axis is chosen (STEP's default).
    pub fn new(origin: DVec3, axis: DVec3, reference: Option<DVec3>) -> Result<Self, SurfaceError> {
        if !(flatcut_geom::finite3(origin) && flatcut_geom::finite3(axis)) {
            return Err(SurfaceError::FrameNotFinite {
                what: "frame origin or axis",
            });
        }
        let z = axis
            .try_normalize()
            .ok_or(SurfaceError::ZeroLength { what: "frame axis" })?;
        let r = match reference {
            Some(r) if flatcut_geom::finite3(r) => r,
            Some(_) => {
                return Err(SurfaceError::FrameNotFinite {
                    what: "frame reference direction",
                });
            }
            None => z.any_orthonormal_vector(),
        };
        let rl = r.length();
        let rp = r - z * r.dot(z);
        if rp.length() <= FRAME_PARALLEL_REL * rl || rl == 0.0 {
            return Err(SurfaceError::ReferenceAlongAxis);
        }
        let x = rp.normalize();
        Ok(Self {
            origin,
            x,
            y: z.cross(x),
            z,
        })
    }

    /// `cos t·x + sin t·y`, the unit radial direction at angle `t`.
    #[inline]
    pub fn radial(&self, t: f64) -> DVec3 {
        let (s, c) = t.sin_cos();
        self.x * c + self.y * s
    }

    /// Local coordinates of a world point.
    #[inline]
    pub fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.x), d.dot(self.y), d.dot(self.z))
    }
}

fn check_domain(t0: f64, t1: f64) -> Result<(f64, f64), SurfaceError> {
    if t0.is_finite() && t1.is_finite() && t0 < t1 {
        Ok((t0, t1))
    } else {
        Err(SurfaceError::EmptyInterval { t0, t1 })
    }
}

/// The straight line `P + t·V` (STEP `LINE`: `V` is the direction times the vector's magnitude).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// The point at `t = 0` (mm).
    pub point: DVec3,
    /// The direction times the vector's magnitude: the motion per unit of `t` (mm).
    pub vector: DVec3,
    domain: (f64, f64),
}

impl Line {
    /// A line over `t ∈ [0, 1]`; `vector` must be finite and nonzero.
    pub fn new(point: DVec3, vector: DVec3) -> Result<Self, SurfaceError> {
        if !(flatcut_geom::finite3(point) && flatcut_geom::finite3(vector)) {
            return Err(SurfaceError::NonFinite {
                what: "line point or vector",
                index: 0,
            });
        }
        if vector.length_squared() == 0.0 {
            return Err(SurfaceError::ZeroLength {
                what: "line vector",
            });
        }
        Ok(Self {
            point,
            vector,
            domain: (0.0, 1.0),
        })
    }

    /// The same line used over `[t0, t1]`.
    pub fn with_domain(mut self, t0: f64, t1: f64) -> Result<Self, SurfaceError> {
        self.domain = check_domain(t0, t1)?;
        Ok(self)
    }

    /// The parameter of the point of the line closest to `p`.
    pub fn param_of(&self, p: DVec3) -> f64 {
        (p - self.point).dot(self.vector) / self.vector.length_squared()
    }
}

impl ParamCurve for Line {
    fn domain(&self) -> (f64, f64) {
        self.domain
    }
    fn eval(&self, t: f64) -> DVec3 {
        self.point + self.vector * t
    }
    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        match k {
            0 => self.eval(t),
            1 => self.vector,
            _ => DVec3::ZERO,
        }
    }
}

/// The ellipse `C + a cos t·x + b sin t·y` in `frame` (a circle when `a = b`), `t` in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipse {
    /// The placement: `frame.origin` is the centre, `x` the major axis.
    pub frame: Frame,
    /// Semi-axis along `frame.x` (mm, > 0).
    pub a: f64,
    /// Semi-axis along `frame.y` (mm, > 0).
    pub b: f64,
    domain: (f64, f64),
}

impl Ellipse {
    /// The whole ellipse, `t ∈ [0, 2π]`; semi-axes finite and > 0.
    pub fn new(frame: Frame, a: f64, b: f64) -> Result<Self, SurfaceError> {
        for (what, x) in [("semi-axis 1", a), ("semi-axis 2", b)] {
            if !(x.is_finite() && x > 0.0) {
                return Err(SurfaceError::NotPositive {
                    what: format!("ellipse {what}"),
                    value: x,
                });
            }
        }
        Ok(Self {
            frame,
            a,
            b,
            domain: (0.0, std::f64::consts::TAU),
        })
    }

    /// The circle of radius `r` (STEP `CIRCLE`).
    pub fn circle(frame: Frame, r: f64) -> Result<Self, SurfaceError> {
        Self::new(frame, r, r)
    }

    /// The same curve used over `[t0, t1]` (any finite interval: the curve is periodic).
    pub fn with_domain(mut self, t0: f64, t1: f64) -> Result<Self, SurfaceError> {
        self.domain = check_domain(t0, t1)?;
        Ok(self)
    }

    /// The angle parameter of the point of the curve nearest to `p`'s projection into the
    /// curve's plane, in `(−π, π]`: exact for a circle, and exact for an ellipse when `p` lies on
    /// it (which is how edge ends are located).
    pub fn param_of(&self, p: DVec3) -> f64 {
        let q = self.frame.local(p);
        (q.y / self.b).atan2(q.x / self.a)
    }
}

impl ParamCurve for Ellipse {
    fn domain(&self) -> (f64, f64) {
        self.domain
    }
    fn eval(&self, t: f64) -> DVec3 {
        let (s, c) = t.sin_cos();
        self.frame.origin + self.frame.x * (self.a * c) + self.frame.y * (self.b * s)
    }
    fn deriv(&self, t: f64, k: usize) -> DVec3 {
        if k == 0 {
            return self.eval(t);
        }
        // d^k/dt^k (cos t, sin t) = (cos(t + kπ/2), sin(t + kπ/2)).
        let (s, c) = (t + k as f64 * std::f64::consts::FRAC_PI_2).sin_cos();
        self.frame.x * (self.a * c) + self.frame.y * (self.b * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CurveExt;

    fn tilted() -> Frame {
        Frame::new(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(0.3, -0.2, 1.0),
            Some(DVec3::new(1.0, 0.5, 0.0)),
        )
        .unwrap()
    }

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        let f = tilted();
        assert!((f.x.length() - 1.0).abs() < 1e-15 && (f.y.length() - 1.0).abs() < 1e-15);
        assert!(f.x.dot(f.z).abs() < 1e-15 && f.y.dot(f.z).abs() < 1e-15);
        assert!((f.x.cross(f.y) - f.z).length() < 1e-15);
        assert!(Frame::new(DVec3::ZERO, DVec3::Z, Some(DVec3::Z * 2.0)).is_err());
        assert!(Frame::new(DVec3::ZERO, DVec3::ZERO, None).is_err());
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let e = Ellipse::new(tilted(), 30.0, 12.0).unwrap();
        let l = Line::new(DVec3::ONE, DVec3::new(2.0, -1.0, 0.5)).unwrap();
        let h = 1e-5;
        for t in [-2.0, 0.3, 1.7, 4.0] {
            for c in [&e as &dyn ParamCurve, &l] {
                for k in 1..=3 {
                    let fd = (c.deriv(t + h, k - 1) - c.deriv(t - h, k - 1)) / (2.0 * h);
                    assert!((fd - c.deriv(t, k)).length() < 1e-6 * (1.0 + fd.length()));
                }
            }
        }
    }

    #[test]
    fn circle_length_and_parameter_round_trip() {
        let c = Ellipse::circle(tilted(), 25.0).unwrap();
        assert!((c.arclen(1e-10) - std::f64::consts::TAU * 25.0).abs() < 1e-8);
        for t in [-3.0, -1.0, 0.0, 0.5, 3.1] {
            assert!((c.param_of(c.eval(t)) - t).abs() < 1e-12);
        }
        let e = Ellipse::new(tilted(), 30.0, 12.0).unwrap();
        assert!((e.param_of(e.eval(2.0)) - 2.0).abs() < 1e-12);
        let l = Line::new(DVec3::ONE, DVec3::new(2.0, -1.0, 0.5)).unwrap();
        assert!((l.param_of(l.eval(-3.25)) + 3.25).abs() < 1e-12);
    }
}
