//! Per-triangle distortion of a map from a 3D triangle to a 2D triangle, in Duncan's terms.
//!
//! For the linear map J taking the 3D triangle (in an orthonormal frame of its plane) to its 2D
//! image, Duncan's μ1 ≥ μ2 (the extreme values of ds̄²/ds², thesis ch. 6) are the squared singular
//! values σ1², σ2² of J. From them:
//! - conformal distortion δ1 = log(μ1/μ2) = 2 log(σ1/σ2),
//! - isometric distortion δ2 = (μ1 + 1/μ1 + μ2 + 1/μ2 − 4)/2 (the symmetric Dirichlet energy density
//!   less its minimum, halved),
//! - area ratio σ1σ2 (signed: negative for a flipped triangle).
//!
//! The determinant is signed: a folded triangle is reported as flipped, never as undistorted.

use glam::{DMat2, DVec2, DVec3};

/// The distortion of one triangle's map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceDistortion {
    /// Largest singular value σ1 of the Jacobian (largest stretch factor, 1 = no stretch).
    pub sigma1: f64,
    /// Smallest singular value σ2 (smallest stretch factor).
    pub sigma2: f64,
    /// Signed determinant σ1σ2 of the Jacobian: the area ratio, negative when the triangle is flipped.
    pub det: f64,
    /// Unit direction in the 3D triangle's plane (in 3D coordinates) of the largest stretch.
    pub dir_max_3d: DVec3,
    /// Unit direction in the plane of the image of the largest stretch.
    pub dir_max_2d: DVec2,
}

impl FaceDistortion {
    /// Duncan's μ1 = σ1².
    pub fn mu1(&self) -> f64 {
        self.sigma1 * self.sigma1
    }
    /// Duncan's μ2 = σ2².
    pub fn mu2(&self) -> f64 {
        self.sigma2 * self.sigma2
    }
    /// Duncan's conformal distortion δ1 = log(μ1/μ2) (∞ for a degenerate image).
    pub fn delta1(&self) -> f64 {
        2.0 * (self.sigma1 / self.sigma2).ln()
    }
    /// Duncan's isometric distortion δ2 = (μ1 + 1/μ1 + μ2 + 1/μ2 − 4)/2 (∞ for a degenerate image).
    pub fn delta2(&self) -> f64 {
        let (m1, m2) = (self.mu1(), self.mu2());
        0.5 * (m1 + 1.0 / m1 + m2 + 1.0 / m2 - 4.0)
    }
    /// True when the image triangle has the opposite orientation (or is degenerate).
    pub fn flipped(&self) -> bool {
        self.det <= 0.0
    }
}

/// An orthonormal frame of the triangle's plane: origin at `a`, x along `b − a`.
/// Returns the 2D coordinates of the three corners in that frame and the frame axes,
/// or `None` for a degenerate triangle.
pub fn local_frame(a: DVec3, b: DVec3, c: DVec3) -> Option<([DVec2; 3], DVec3, DVec3)> {
    let e1 = b - a;
    let l1 = e1.length();
    let n = e1.cross(c - a);
    let nl = n.length();
    if l1.is_nan() || l1 <= 0.0 || nl.is_nan() || nl <= 0.0 || !nl.is_finite() {
        return None;
    }
    let x = e1 / l1;
    let y = (n / nl).cross(x);
    let q = c - a;
    Some((
        [
            DVec2::ZERO,
            DVec2::new(l1, 0.0),
            DVec2::new(q.dot(x), q.dot(y)),
        ],
        x,
        y,
    ))
}

/// The distortion of the affine map taking triangle (a, b, c) in 3D to (p, q, r) in 2D.
/// Returns `None` for a degenerate 3D triangle.
pub fn face_distortion(tri3: [DVec3; 3], tri2: [DVec2; 3]) -> Option<FaceDistortion> {
    let (loc, x3, y3) = local_frame(tri3[0], tri3[1], tri3[2])?;
    // Jacobian J with J * (loc[i] - loc[0]) = tri2[i] - tri2[0].
    let s = DMat2::from_cols(loc[1] - loc[0], loc[2] - loc[0]);
    let t = DMat2::from_cols(tri2[1] - tri2[0], tri2[2] - tri2[0]);
    let j = t * s.inverse();
    Some(jacobian_distortion(j, x3, y3))
}

/// Singular values and principal direction of a 2×2 Jacobian given in the frame (x3, y3).
pub fn jacobian_distortion(j: DMat2, x3: DVec3, y3: DVec3) -> FaceDistortion {
    // Closed-form SVD of a 2x2 matrix [[a, b], [c, d]] (columns are images of the frame axes).
    let (a, c) = (j.x_axis.x, j.x_axis.y);
    let (b, d) = (j.y_axis.x, j.y_axis.y);
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = (e * e + h * h).sqrt();
    let r = (f * f + g * g).sqrt();
    let sigma1 = q + r;
    let sigma2 = (q - r).abs();
    let det = a * d - b * c;
    // Right singular vector of the largest singular value: angle (a2 - a1)/2 with
    // a1 = atan2(g, f), a2 = atan2(h, e).
    let a1 = g.atan2(f);
    let a2 = h.atan2(e);
    let theta = 0.5 * (a2 - a1);
    let phi = 0.5 * (a2 + a1);
    let v = DVec2::new(theta.cos(), -theta.sin());
    let u = DVec2::new(phi.cos(), phi.sin());
    FaceDistortion {
        sigma1,
        sigma2,
        det,
        dir_max_3d: (x3 * v.x + y3 * v.y).normalize_or_zero(),
        dir_max_2d: u,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [DVec3; 3] {
        [
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(4.0, 2.5, 3.0),
            DVec3::new(2.0, 5.0, 4.0),
        ]
    }

    fn unfold(t: [DVec3; 3]) -> [DVec2; 3] {
        local_frame(t[0], t[1], t[2]).unwrap().0
    }

    #[test]
    fn isometry_has_no_distortion() {
        let t = tri();
        let mut f = unfold(t);
        let rot = DMat2::from_angle(0.7);
        for p in &mut f {
            *p = rot * *p + DVec2::new(10.0, -3.0);
        }
        let d = face_distortion(t, f).unwrap();
        assert!((d.sigma1 - 1.0).abs() < 1e-12 && (d.sigma2 - 1.0).abs() < 1e-12);
        assert!(d.delta1().abs() < 1e-12 && d.delta2().abs() < 1e-12 && !d.flipped());
    }

    #[test]
    fn uniform_scale_and_shear_have_known_singular_values() {
        let t = tri();
        let f = unfold(t);
        let d = face_distortion(t, f.map(|p| p * 1.5)).unwrap();
        assert!(
            (d.mu1() - 2.25).abs() < 1e-12
                && (d.mu2() - 2.25).abs() < 1e-12
                && d.delta1().abs() < 1e-12
        );
        // Stretch 2 along the frame's x (the direction of b - a), 0.5 along y.
        let d = face_distortion(t, f.map(|p| DVec2::new(2.0 * p.x, 0.5 * p.y))).unwrap();
        assert!((d.sigma1 - 2.0).abs() < 1e-12 && (d.sigma2 - 0.5).abs() < 1e-12);
        let x = (t[1] - t[0]).normalize();
        assert!(d.dir_max_3d.dot(x).abs() > 1.0 - 1e-12);
        assert!((d.delta2() - 0.5 * (4.0 + 0.25 + 0.25 + 4.0 - 4.0)).abs() < 1e-12);
    }

    #[test]
    fn mirror_is_flipped() {
        let t = tri();
        let d = face_distortion(t, unfold(t).map(|p| DVec2::new(-p.x, p.y))).unwrap();
        assert!(d.flipped());
        assert!((d.sigma1 - 1.0).abs() < 1e-12);
    }
}
