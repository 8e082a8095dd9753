//! 2D pattern pieces: outlines fitted to lines, arcs and cubics, seam allowance, notches, grain
//! lines, labels; SVG and DXF export; SVG import; the [`Drawing`] that the nester and the G-code
//! writer consume.
//!
//! **Architecture invariant:** this crate is 2D only. It cannot name a surface or a mesh type
//! (the crate graph enforces it); the facade turns a flattened boundary into a piece.

pub mod drawing;

pub use drawing::{Drawing, Layer, Stroke};
