//! Axis-aligned bounding boxes in 2D and 3D (millimetres).

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// An axis-aligned box in 3D. An empty box has `min > max` componentwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb3 {
    /// The least corner (each coordinate the smallest of the points added).
    pub min: DVec3,
    /// The greatest corner (each coordinate the largest of the points added).
    pub max: DVec3,
}

impl Aabb3 {
    /// The empty box: adding any point makes it that point.
    pub const EMPTY: Self = Self {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The smallest box containing all points (empty for no points).
    pub fn from_points<I: IntoIterator<Item = DVec3>>(pts: I) -> Self {
        let mut b = Self::EMPTY;
        for p in pts {
            b.add(p);
        }
        b
    }

    /// Grows the box to contain `p`.
    pub fn add(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both boxes.
    pub fn union(&self, o: &Self) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True when no point has been added (`min > max` on some axis).
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Length of the diagonal (0 for an empty box): the scale that relative tolerances refer to.
    pub fn diagonal(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            (self.max - self.min).length()
        }
    }

    /// The extent along each axis (zero for an empty box).
    pub fn size(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }
}

/// An axis-aligned box in 2D. An empty box has `min > max` componentwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb2 {
    /// The least corner (each coordinate the smallest of the points added).
    pub min: DVec2,
    /// The greatest corner (each coordinate the largest of the points added).
    pub max: DVec2,
}

impl Aabb2 {
    /// The empty box: adding any point makes it that point.
    pub const EMPTY: Self = Self {
        min: DVec2::splat(f64::INFINITY),
        max: DVec2::splat(f64::NEG_INFINITY),
    };

    /// The smallest box containing all points (empty for no points).
    pub fn from_points<I: IntoIterator<Item = DVec2>>(pts: I) -> Self {
        let mut b = Self::EMPTY;
        for p in pts {
            b.add(p);
        }
        b
    }

    /// Grows the box to contain `p`.
    pub fn add(&mut self, p: DVec2) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both boxes.
    pub fn union(&self, o: &Self) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True when no point has been added (`min > max` on some axis).
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y
    }

    /// The extent along each axis (zero for an empty box).
    pub fn size(&self) -> DVec2 {
        if self.is_empty() {
            DVec2::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The extent along x (0 for an empty box).
    pub fn width(&self) -> f64 {
        self.size().x
    }

    /// The extent along y (0 for an empty box).
    pub fn height(&self) -> f64 {
        self.size().y
    }
}
