//! What an orthotropic flattening needs of its material: the stiffness of the warp, the weft and
//! the shear relative to an isotropic sheet, the stretch and compression limits along, across
//! and on the bias, and where the grain runs. The material files that give these numbers are
//! read by `flatcut-design`; this crate takes the numbers only.

use flatcut_geom::{DVec2, DVec3};
pub use flatcut_mesh::grain_strain::{ByDirection, DirectionalLimits};

/// Stiffness of a woven, knitted or fibrous sheet relative to an isotropic one: 1, 1, 1 is
/// Duncan's Green–Lagrange deviation (Poisson's ratio 0); a woven fabric has a shear stiffness
/// far below its thread stiffnesses, so its strain goes to the bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiffness {
    /// Along the warp (the grain).
    pub along: f64,
    /// Along the weft (across the grain).
    pub across: f64,
    /// In-plane shear between warp and weft.
    pub shear: f64,
}

impl Stiffness {
    /// The isotropic sheet.
    pub const ISOTROPIC: Stiffness = Stiffness {
        along: 1.0,
        across: 1.0,
        shear: 1.0,
    };

    /// Checks that every stiffness is a positive finite number.
    pub fn validate(&self) -> Result<(), String> {
        for (k, v) in [
            ("along", self.along),
            ("across", self.across),
            ("shear", self.shear),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("stiffness {k} = {v}: must be a positive number"));
            }
        }
        Ok(())
    }
}

/// Where the warp runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Grain {
    /// Along the design's grain line, from its first point to its second (on or near the
    /// surface): its image where it is drawn, in the isotropic flattening, becomes the
    /// pattern's grain.
    Line([DVec3; 2]),
    /// Along this direction of the pattern plane (radians from +x of the isotropic flattening).
    Angle(f64),
    /// Chosen by the flattening: the angle whose map exceeds the limits least.
    Auto,
}

/// The orthotropic flattening's material: stiffness, limits and grain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anisotropy {
    /// The material's stiffness along the warp, across it and in shear, weighting the Green
    /// strain in the grain frame.
    pub stiffness: Stiffness,
    /// The limits `Grain::Auto` minimises the excess over (none: the strain energy is minimised).
    pub limits: Option<DirectionalLimits>,
    /// Where the warp runs: a grain line, an angle in radians, or `Auto` to search the angle.
    pub grain: Grain,
}

/// The unit pattern direction of an angle.
pub fn grain_dir(angle: f64) -> DVec2 {
    DVec2::new(angle.cos(), angle.sin())
}
