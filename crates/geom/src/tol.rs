//! Named tolerances. Lengths are in millimetres; relative values are fractions of a reference size.
//!
//! A 2 m sail and a 20 mm toe cap run through the same code, so algorithms that need a "small"
//! length take it from a [`Tolerances`] value rather than from a literal.

use serde::{Deserialize, Serialize};

/// The tolerances passed down the pipeline. Construct with [`Tolerances::DEFAULT`] and the
/// `with_*` builders.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Tolerances {
    /// Chordal tolerance for tessellating surfaces and flattening curves to polylines, in mm:
    /// the Hausdorff distance between the exact geometry and its piecewise-linear approximation.
    pub chord_mm: f64,
    /// Tolerance for fitting outlines with lines, arcs and cubics, in mm.
    pub fit_mm: f64,
    /// Two points closer than this are the same point (welding, deduplication), in mm.
    pub weld_mm: f64,
    /// Relative tolerance of iterative numerical methods (arc length, Newton, quadrature).
    pub rel: f64,
    /// The largest defect of an imported CAD model healed (gaps, edges off their faces), in mm;
    /// `None`: the importer's default (a fraction of the model's size).
    pub heal_mm: Option<f64>,
}

impl Tolerances {
    /// Chordal tolerance default: 0.05 mm is below the kerf of a drag knife or a laser.
    pub const DEFAULT_CHORD_MM: f64 = 0.05;
    /// Outline fitting default: 0.02 mm, well below what a cutter reproduces.
    pub const DEFAULT_FIT_MM: f64 = 0.02;
    /// Welding default: 1 µm.
    pub const DEFAULT_WELD_MM: f64 = 1e-3;
    /// Relative accuracy default for numerical methods.
    pub const DEFAULT_REL: f64 = 1e-10;

    /// Every tolerance at its default.
    pub const DEFAULT: Self = Self {
        chord_mm: Self::DEFAULT_CHORD_MM,
        fit_mm: Self::DEFAULT_FIT_MM,
        weld_mm: Self::DEFAULT_WELD_MM,
        rel: Self::DEFAULT_REL,
        heal_mm: None,
    };

    /// These tolerances with the chord tolerance `v` mm.
    pub const fn with_chord_mm(mut self, v: f64) -> Self {
        self.chord_mm = v;
        self
    }

    /// These tolerances with the outline-fitting tolerance `v` mm.
    pub const fn with_fit_mm(mut self, v: f64) -> Self {
        self.fit_mm = v;
        self
    }

    /// These tolerances with the welding distance `v` mm.
    pub const fn with_weld_mm(mut self, v: f64) -> Self {
        self.weld_mm = v;
        self
    }

    /// These tolerances with the largest defect healed `v` mm (`None`: the importer's default).
    pub const fn with_heal_mm(mut self, v: Option<f64>) -> Self {
        self.heal_mm = v;
        self
    }
}

impl Default for Tolerances {
    fn default() -> Self {
        Self::DEFAULT
    }
}
