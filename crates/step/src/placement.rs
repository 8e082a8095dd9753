//! Rigid placements `p ↦ rot · p + origin`: where an assembly puts a body, and the frame
//! geometry is read in. The assembly composes them and the reader applies them.

use flatcut_geom::{DMat3, DVec3};
use flatcut_surface::curve::Frame;

/// A rigid placement: `p ↦ rot · p + origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The rotation (orthonormal, determinant 1).
    pub rot: DMat3,
    /// The translation (mm), applied after the rotation.
    pub origin: DVec3,
}

impl Placement {
    /// The placement that moves nothing.
    pub const IDENTITY: Self = Self {
        rot: DMat3::IDENTITY,
        origin: DVec3::ZERO,
    };

    /// The placement of a frame: local coordinates to the frame's space.
    pub fn of_frame(f: &Frame) -> Self {
        Self {
            rot: DMat3::from_cols(f.x, f.y, f.z),
            origin: f.origin,
        }
    }

    /// A point placed: `rot · p + origin`.
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.rot * p + self.origin
    }

    /// A direction placed: `rot · v` (no translation).
    pub fn vector(&self, v: DVec3) -> DVec3 {
        self.rot * v
    }

    /// `self ∘ other`: `other` first.
    pub fn then_outer(&self, other: &Placement) -> Placement {
        Placement {
            rot: self.rot * other.rot,
            origin: self.rot * other.origin + self.origin,
        }
    }

    /// The inverse (the rotation is orthonormal).
    pub fn inverse(&self) -> Placement {
        let rt = self.rot.transpose();
        Placement {
            rot: rt,
            origin: -(rt * self.origin),
        }
    }

    /// True for the identity within round-off.
    pub fn is_identity(&self) -> bool {
        (self.rot - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|x| x.abs() < 1e-14)
            && self.origin.length() < 1e-12
    }
}
