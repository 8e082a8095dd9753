//! The shared vocabulary of flatcut: points and vectors in millimetres, bounding boxes,
//! named tolerances and small numeric kernels.
//!
//! Every length in flatcut is an `f64` in millimetres. Conversions to other units happen only at
//! the edges (SVG writer, G-code writer, file readers), never here.
//!
//! **Architecture invariant:** this crate depends on no other workspace crate and does no IO.
#![warn(missing_docs)]

pub mod aabb;
pub mod limits;
pub mod num;
pub mod polygon;
pub mod tol;

pub use aabb::{Aabb, Aabb2, Aabb3, Corner};
pub use glam::{DMat2, DMat3, DVec2, DVec3};
pub use tol::Tolerances;

/// Returns true when every component of the vector is finite (no NaN, no infinity).
pub fn finite3(p: DVec3) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.z.is_finite()
}

/// Returns true when both components are finite.
pub fn finite2(p: DVec2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}
