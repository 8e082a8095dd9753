//! Axis-aligned bounding boxes in 2D and 3D (millimetres): one box over any corner type
//! ([`Corner`]), so the 2D and 3D boxes cannot drift apart.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// A point type a box can be built over: componentwise least and greatest, and a test for an
/// inverted (empty) extent.
pub trait Corner: Copy + PartialEq {
    /// Every coordinate `+∞`: the least corner of the empty box.
    const INFINITY: Self;
    /// Every coordinate `−∞`: the greatest corner of the empty box.
    const NEG_INFINITY: Self;
    /// Every coordinate 0: the extent of an empty box.
    const ZERO: Self;
    /// Each coordinate the smaller of the two.
    fn least(self, o: Self) -> Self;
    /// Each coordinate the larger of the two.
    fn greatest(self, o: Self) -> Self;
    /// True when some coordinate of `self` exceeds that of `o`.
    fn any_above(self, o: Self) -> bool;
    /// `self − o`, coordinate by coordinate.
    fn minus(self, o: Self) -> Self;
}

impl Corner for DVec2 {
    const INFINITY: Self = DVec2::splat(f64::INFINITY);
    const NEG_INFINITY: Self = DVec2::splat(f64::NEG_INFINITY);
    const ZERO: Self = DVec2::ZERO;
    fn least(self, o: Self) -> Self {
        self.min(o)
    }
    fn greatest(self, o: Self) -> Self {
        self.max(o)
    }
    fn any_above(self, o: Self) -> bool {
        self.cmpgt(o).any()
    }
    fn minus(self, o: Self) -> Self {
        self - o
    }
}

impl Corner for DVec3 {
    const INFINITY: Self = DVec3::splat(f64::INFINITY);
    const NEG_INFINITY: Self = DVec3::splat(f64::NEG_INFINITY);
    const ZERO: Self = DVec3::ZERO;
    fn least(self, o: Self) -> Self {
        self.min(o)
    }
    fn greatest(self, o: Self) -> Self {
        self.max(o)
    }
    fn any_above(self, o: Self) -> bool {
        self.cmpgt(o).any()
    }
    fn minus(self, o: Self) -> Self {
        self - o
    }
}

/// An axis-aligned box. An empty box has `min > max` componentwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb<V> {
    /// The least corner (each coordinate the smallest of the points added).
    pub min: V,
    /// The greatest corner (each coordinate the largest of the points added).
    pub max: V,
}

/// An axis-aligned box in 3D.
pub type Aabb3 = Aabb<DVec3>;

/// An axis-aligned box in 2D.
pub type Aabb2 = Aabb<DVec2>;

impl<V: Corner> Aabb<V> {
    /// The empty box: adding any point makes it that point.
    pub const EMPTY: Self = Self {
        min: V::INFINITY,
        max: V::NEG_INFINITY,
    };

    /// The smallest box containing all points (empty for no points).
    pub fn from_points<I: IntoIterator<Item = V>>(pts: I) -> Self {
        let mut b = Self::EMPTY;
        for p in pts {
            b.add(p);
        }
        b
    }

    /// Grows the box to contain `p`.
    pub fn add(&mut self, p: V) {
        self.min = self.min.least(p);
        self.max = self.max.greatest(p);
    }

    /// The smallest box containing both boxes.
    pub fn union(&self, o: &Self) -> Self {
        Self {
            min: self.min.least(o.min),
            max: self.max.greatest(o.max),
        }
    }

    /// True when no point has been added (`min > max` on some axis).
    pub fn is_empty(&self) -> bool {
        self.min.any_above(self.max)
    }

    /// The extent along each axis (zero for an empty box).
    pub fn size(&self) -> V {
        if self.is_empty() {
            V::ZERO
        } else {
            self.max.minus(self.min)
        }
    }
}

impl Aabb3 {
    /// Length of the diagonal (0 for an empty box): the scale that relative tolerances refer to.
    pub fn diagonal(&self) -> f64 {
        self.size().length()
    }
}

impl Aabb2 {
    /// The extent along x (0 for an empty box).
    pub fn width(&self) -> f64 {
        self.size().x
    }

    /// The extent along y (0 for an empty box).
    pub fn height(&self) -> f64 {
        self.size().y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_holds_its_points_and_an_empty_one_has_no_extent() {
        let b = Aabb3::from_points([DVec3::new(1.0, -2.0, 3.0), DVec3::new(-1.0, 2.0, 5.0)]);
        assert_eq!(b.min, DVec3::new(-1.0, -2.0, 3.0));
        assert_eq!(b.max, DVec3::new(1.0, 2.0, 5.0));
        assert_eq!(b.diagonal(), (4.0f64 + 16.0 + 4.0).sqrt());
        assert!(Aabb3::EMPTY.is_empty() && Aabb2::EMPTY.is_empty());
        assert_eq!(Aabb3::EMPTY.diagonal(), 0.0);
        assert_eq!(Aabb2::EMPTY.size(), DVec2::ZERO);
        let mut c = Aabb2::from_points([DVec2::new(0.0, 0.0)]);
        assert!(!c.is_empty() && c.size() == DVec2::ZERO);
        c = c.union(&Aabb2::from_points([DVec2::new(3.0, -4.0)]));
        assert_eq!((c.width(), c.height()), (3.0, 4.0));
        // Empty on one axis only is empty.
        let flat = Aabb2 {
            min: DVec2::new(0.0, 1.0),
            max: DVec2::new(1.0, 0.0),
        };
        assert!(flat.is_empty() && flat.width() == 0.0);
    }
}
