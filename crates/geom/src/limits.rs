//! The sane range of input: how large a coordinate, a count or a degree may be before flatcut
//! refuses the input at load instead of running out of time or memory on it.
//!
//! Every reader (designs, meshes, SVGs) and the command line check their numbers against these
//! constants, so a file with a vertex at 1e308 mm or a B-spline with 2³² poles gets a clear error
//! naming the element, never an overflow, a NaN, a hang or a 13 GB allocation.

/// Largest coordinate magnitude accepted from any input, in mm: one kilometre. A sail, a hull
/// panel or a roll of fabric is far smaller; squares of such coordinates (areas, dot products)
/// stay exact enough in f64 for the geometry that follows.
pub const MAX_COORD_MM: f64 = 1e6;

/// Largest polynomial degree of a curve or patch read from a design. Degrees beyond a few tens
/// are numerically meaningless (the Bernstein basis loses every digit) and only cost memory.
pub const MAX_DEGREE: usize = 30;

/// Largest number of control points of one curve or patch read from a design (one million):
/// far beyond hand-written designs, small enough to allocate.
pub const MAX_CONTROL_POINTS: usize = 1_000_000;

/// Largest number of copies of one piece (a design's `quantity`, `nest --quantity`): a cutting
/// room's largest lay, and a bound on the instances a nesting run allocates.
pub const MAX_QUANTITY: u32 = 10_000;

/// True when `x` is finite and within [`MAX_COORD_MM`] of zero.
pub fn in_range(x: f64) -> bool {
    x.is_finite() && x.abs() <= MAX_COORD_MM
}

/// True when every component is finite and within [`MAX_COORD_MM`].
pub fn in_range2(p: crate::DVec2) -> bool {
    in_range(p.x) && in_range(p.y)
}

/// True when every component is finite and within [`MAX_COORD_MM`].
pub fn in_range3(p: crate::DVec3) -> bool {
    in_range(p.x) && in_range(p.y) && in_range(p.z)
}

/// Why a coordinate is refused, for messages: "is not finite" or "is beyond ±1e6 mm".
pub fn out_of_range_reason(x: f64) -> String {
    if x.is_finite() {
        format!("{x:e} is beyond the accepted range of ±{MAX_COORD_MM:e} mm")
    } else {
        format!("{x} is not a finite number")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_edges() {
        assert!(in_range(MAX_COORD_MM) && in_range(-MAX_COORD_MM) && in_range(0.0));
        assert!(!in_range(MAX_COORD_MM * 1.000_001));
        assert!(!in_range(f64::NAN) && !in_range(f64::INFINITY) && !in_range(-1e308));
        assert!(out_of_range_reason(1e9).contains("beyond"));
        assert!(out_of_range_reason(f64::NAN).contains("not a finite"));
    }
}
