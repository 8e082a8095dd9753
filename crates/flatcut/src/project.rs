//! The project file of `flatcut run`: which design, which material and its limits, the sheet or
//! roll, the machine profile and the device. TOML, unknown keys rejected.
//!
//! ```toml
//! name = "lampshade"
//! design = "design.toml"        # relative to the project file
//! method = "developable"        # flattening method (default isometric)
//! seam_mm = 10.0                # allowance where the design gives none
//! darts = "auto"                # optional: cut darts where a piece exceeds the limits
//! split = "auto"                # optional: split a piece darts cannot bring within them
//! symmetry = "auto"             # optional, with split: a closed surface as L/R pairs
//!                               # (off | auto | x | y | z, as --symmetry; default off)
//! symmetry_tolerance_pct = 1.0  # its largest deviation from its mirror image (% of its size)
//! # symmetry_plane = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0]   # or this plane: a point, a normal (mm)
//! # despike = true              # optional, with split: move a scan's spikes back into its
//! # despike_max_mm = 2.0        # surface first, no vertex farther than this (as --despike)
//! [material]
//! name = "parchment"
//! max_stretch_pct = 2.0
//! max_compress_pct = 0.0
//! grain = "0,180"               # "fixed" (one way), "0,180" (either way, default) or "any"
//! grain_tolerance_deg = 0.0     # how far a piece's grain line may turn off the material's
//! # properties = "leather"      # optional: a bundled material or a material file: limits along,
//!                               # across and on the bias drive the orthotropic flattening
//! [sheet]
//! width_mm = 600.0              # sheets of width × height, or
//! height_mm = 400.0
//! # roll_width_mm = 1400.0      # a roll of this width
//! spacing_mm = 2.0
//! [machine]
//! profile = "pen"               # pen | knife | laser | path to a profile .toml
//! [order]                       # optional, for a graded design: sets to cut per size
//! S = 2                         # (every piece's quantity, both sides of a pair, times this)
//! M = 4
//! [device]
//! # port = "/dev/ttyUSB0"       # the controller; "simulator" or absent: the embedded simulator
//! baud = 115200                 # 1200..=2000000
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use flatcut_nest::GrainDirections;

use crate::splitting::{SymmetryMode, SymmetrySettings};

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
/// The project's `[material]`: its name and limits, and its grain rule.
pub struct Material {
    /// The material's name, printed on the pieces' labels.
    pub name: String,
    #[serde(default)]
    /// The largest stretch allowed (percent); absent: no limit.
    pub max_stretch_pct: Option<f64>,
    #[serde(default)]
    /// The largest compression allowed (percent); absent: no limit.
    pub max_compress_pct: Option<f64>,
    /// The material's grain rule for pieces with a grain line: `"fixed"` (along the grain one
    /// way), `"0,180"` (either way; the default) or `"any"` (no grain: pieces turn freely in
    /// quarter turns).
    #[serde(default)]
    pub grain: Option<String>,
    /// How far a piece's grain line may turn off the material's grain (degrees).
    #[serde(default)]
    pub grain_tolerance_deg: Option<f64>,
    /// A bundled material (`leather`, `woven-cotton`, …) or a material file (relative to the
    /// project): its limits per direction and stiffness ([`flatcut_design::material`]).
    #[serde(default)]
    pub properties: Option<String>,
    /// The material `properties` names, read at load time.
    #[serde(skip)]
    pub spec: Option<flatcut_design::material::MaterialSpec>,
}

impl Material {
    /// The grain rule (validated at load time); the nesting's own type, so the project and
    /// `flatcut nest --grain` read the same spellings.
    pub fn grain_rule(&self) -> GrainDirections {
        self.grain
            .as_deref()
            .and_then(GrainDirections::parse)
            .unwrap_or_default()
    }

    /// How far a piece's grain line may turn off the material's grain (degrees; 0 by default).
    pub fn grain_tolerance(&self) -> f64 {
        self.grain_tolerance_deg.unwrap_or(0.0)
    }
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
/// The project's `[sheet]`: sheets of width × height, or a roll of a width.
pub struct Sheet {
    #[serde(default)]
    /// Sheet width (mm); with `height_mm`.
    pub width_mm: Option<f64>,
    #[serde(default)]
    /// Sheet height (mm); with `width_mm`.
    pub height_mm: Option<f64>,
    #[serde(default)]
    /// Roll width (mm), instead of sheets.
    pub roll_width_mm: Option<f64>,
    #[serde(default = "Sheet::default_spacing")]
    /// Smallest gap between nested pieces (mm, default 2).
    pub spacing_mm: f64,
}

impl Sheet {
    fn default_spacing() -> f64 {
        2.0
    }
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
/// The project's `[machine]`.
pub struct Machine {
    /// A bundled profile's name (`pen`, `knife`, `laser`, …) or a profile file relative to the
    /// project.
    pub profile: String,
}

/// The `[device]` a project's jobs stream to: a serial port, or the embedded simulator.
#[derive(Clone, Debug, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Device {
    /// The controller's serial port; [`Device::SIMULATOR`] or absent: the embedded simulator.
    #[serde(default)]
    pub port: Option<String>,
    /// Baud rate of the link (GRBL: 115200), within [`Device::BAUD_RANGE`].
    #[serde(default)]
    pub baud: Option<u32>,
}

impl Device {
    /// The `port` that names the embedded simulator.
    pub const SIMULATOR: &'static str = "simulator";
    /// Baud rates a serial link to a controller can have: 1200 (the slowest plotters) to 2 Mbaud
    /// (the fastest USB serial adapters).
    pub const BAUD_RANGE: std::ops::RangeInclusive<u32> = 1200..=2_000_000;

    /// Whether the jobs go to the embedded simulator.
    pub fn is_simulator(&self) -> bool {
        self.port.as_deref().is_none_or(|p| p == Device::SIMULATOR)
    }

    fn validate(&self) -> Result<(), String> {
        if let Some(b) = self.baud
            && !Device::BAUD_RANGE.contains(&b)
        {
            return Err(format!(
                "[device] baud = {b}: a serial link runs at {}..={} baud (GRBL: 115200)",
                Device::BAUD_RANGE.start(),
                Device::BAUD_RANGE.end()
            ));
        }
        if self.port.as_deref().is_some_and(|p| p.trim().is_empty()) {
            return Err(format!(
                "[device] port is empty: name the controller's serial port, or \"{}\"",
                Device::SIMULATOR
            ));
        }
        Ok(())
    }
}

/// A `flatcut run` project.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Project {
    /// The project's name, used in the summary and messages.
    pub name: String,
    /// The design file, relative to the project file.
    pub design: PathBuf,
    #[serde(default)]
    /// The flattening method (as `flatcut flatten --method`); absent: the default.
    pub method: Option<String>,
    #[serde(default)]
    /// Seam allowance (mm) where the design gives none.
    pub seam_mm: Option<f64>,
    /// `"auto"`: cut darts into the pieces that cannot meet the material's limits otherwise.
    #[serde(default)]
    pub darts: Option<flatcut_design::DartsDef>,
    /// `"auto"`: split the pieces that darts (when asked for) cannot bring within the material's
    /// limits into parts sewn together.
    #[serde(default)]
    pub split: Option<flatcut_design::DartsDef>,
    /// With `split = "auto"`, whether a closed surface is split as left and right pairs, as
    /// `--symmetry`: `"off"` (the default), `"auto"`, `"x"`, `"y"` or `"z"`
    /// ([`SymmetryMode::NAMES`]).
    #[serde(default)]
    pub symmetry: Option<String>,
    /// The largest deviation of the surface from its mirror image the split accepts, in percent
    /// of its bounding box diagonal, as `--symmetry-tolerance`.
    #[serde(default)]
    pub symmetry_tolerance_pct: Option<f64>,
    /// With `split = "auto"`, the mirror plane as a point and a normal, `[x, y, z, nx, ny, nz]`
    /// (mm; the normal of any length), taken as given, as `--symmetry-plane`; in place of
    /// `symmetry`.
    #[serde(default)]
    pub symmetry_plane: Option<[f64; 6]>,
    /// With `split = "auto"`, whether a scan's spikes are moved back into its surface before it
    /// is flattened and split, as `--despike` ([`crate::despiking`]).
    #[serde(default)]
    pub despike: bool,
    /// With `despike = true`, the largest move of a vertex (mm), as `--despike-max-mm`
    /// ([`crate::despiking::DEFAULT_MAX_MM`] when absent).
    #[serde(default)]
    pub despike_max_mm: Option<f64>,
    /// The material the pieces are cut from.
    pub material: Material,
    /// What the pieces are nested on.
    pub sheet: Sheet,
    /// The machine that cuts them.
    pub machine: Machine,
    /// Sets to cut per size of a graded design (`S = 2`, `M = 4`): the nesting places every
    /// piece of a size its quantity times this; sizes not named are not cut. Absent: one set
    /// of every size.
    #[serde(default)]
    pub order: Option<std::collections::BTreeMap<String, u32>>,
    #[serde(default)]
    /// Where the jobs stream to (default: the embedded simulator).
    pub device: Device,
    /// The project file's directory (set at load time).
    #[serde(skip)]
    pub dir: PathBuf,
}

/// A project file that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProjectError {
    #[error("{path}: {source}")]
    /// The project file could not be read.
    Io {
        /// The project file's path.
        path: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    #[error("{path}:{line}:{col}: {message}")]
    /// The project file is not valid TOML or does not fit the schema.
    Syntax {
        /// The project file's path.
        path: String,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        col: usize,
        /// The parser's description.
        message: String,
    },
    #[error("{path}: {message}")]
    /// A value out of range, or keys that do not go together.
    Invalid {
        /// The project file's path.
        path: String,
        /// What is wrong.
        message: String,
    },
}

impl Project {
    /// Reads and checks a project file; `dir` is set to its folder.
    pub fn load(path: &Path) -> Result<Self, ProjectError> {
        let p = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ProjectError::Io {
            path: p.clone(),
            source,
        })?;
        let mut proj: Project = toml::from_str(&text).map_err(|e| {
            let (line, col) = e.span().map_or((0, 0), |s| {
                let before = &text[..s.start.min(text.len())];
                (
                    before.matches('\n').count() + 1,
                    before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1,
                )
            });
            ProjectError::Syntax {
                path: p.clone(),
                line,
                col,
                message: e.message().to_string(),
            }
        })?;
        proj.dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        proj.validate().map_err(|message| ProjectError::Invalid {
            path: p.clone(),
            message,
        })?;
        if let Some(spec) = &proj.material.properties {
            proj.material.spec = Some(
                flatcut_design::material::MaterialSpec::load(spec, Some(&proj.dir)).map_err(
                    |e| ProjectError::Invalid {
                        path: p,
                        message: format!("[material] properties: {e}"),
                    },
                )?,
            );
        }
        Ok(proj)
    }

    fn validate(&self) -> Result<(), String> {
        let pos = |v: Option<f64>| v.is_none_or(|v| v > 0.0 && flatcut_geom::limits::in_range(v));
        match (
            self.sheet.width_mm,
            self.sheet.height_mm,
            self.sheet.roll_width_mm,
        ) {
            (Some(_), Some(_), None) | (None, None, Some(_)) => {}
            _ => return Err("[sheet] needs width_mm and height_mm, or roll_width_mm".into()),
        }
        if !(pos(self.sheet.width_mm) && pos(self.sheet.height_mm) && pos(self.sheet.roll_width_mm))
        {
            return Err(format!(
                "[sheet] sizes must be positive and at most {:e} mm",
                flatcut_geom::limits::MAX_COORD_MM
            ));
        }
        if !(self.sheet.spacing_mm >= 0.0 && flatcut_geom::limits::in_range(self.sheet.spacing_mm))
        {
            return Err("[sheet] spacing_mm must be >= 0".into());
        }
        for (k, v) in [
            ("max_stretch_pct", self.material.max_stretch_pct),
            ("max_compress_pct", self.material.max_compress_pct),
        ] {
            if v.is_some_and(|v| !(v.is_finite() && (0.0..100.0).contains(&v))) {
                return Err(format!("[material] {k} must be a percentage in [0, 100)"));
            }
        }
        if let Some(g) = &self.material.grain
            && GrainDirections::parse(g).is_none()
        {
            return Err(format!(
                "[material] grain must be \"fixed\", \"0,180\" or \"any\", got \"{g}\""
            ));
        }
        if self
            .material
            .grain_tolerance_deg
            .is_some_and(|v| !(v.is_finite() && (0.0..=90.0).contains(&v)))
        {
            return Err("[material] grain_tolerance_deg must be an angle in [0, 90]".into());
        }
        if self
            .seam_mm
            .is_some_and(|v| !(v >= 0.0 && flatcut_geom::limits::in_range(v)))
        {
            return Err("seam_mm must be >= 0".into());
        }
        if let Some(m) = &self.method
            && flatcut_flatten::Method::from_name(m).is_none()
        {
            return Err(format!("unknown method '{m}'"));
        }
        self.symmetry_settings()?;
        self.despike_max_mm()?;
        if let Some(order) = &self.order {
            if let Some((size, n)) = order
                .iter()
                .find(|(_, n)| **n > flatcut_geom::limits::MAX_QUANTITY)
            {
                return Err(format!(
                    "[order] {size} = {n}: at most {} sets per size",
                    flatcut_geom::limits::MAX_QUANTITY
                ));
            }
            if order.values().all(|n| *n == 0) {
                return Err("[order] cuts nothing: give at least one size a count".into());
            }
        }
        self.device.validate()
    }

    /// How a split looks for symmetry (`symmetry`, `symmetry_tolerance_pct`, `symmetry_plane`),
    /// or what is wrong with those keys: an unknown mode, a tolerance that is no percentage, a
    /// plane that is none, a mode and a plane both, or a mirrored split or its tolerance asked
    /// for without `split = "auto"`.
    pub fn symmetry_settings(&self) -> Result<SymmetrySettings, String> {
        let mut s = SymmetrySettings::default();
        if let Some(m) = &self.symmetry {
            s.mode = SymmetryMode::from_name(m).ok_or_else(|| {
                format!(
                    "symmetry = \"{m}\": unknown symmetry; one of: {}",
                    SymmetryMode::NAMES.join(", ")
                )
            })?;
        }
        if let Some(v) = self.symmetry_plane {
            if let Some(m) = &self.symmetry {
                return Err(format!(
                    "symmetry = \"{m}\" and symmetry_plane both say where the mirror plane is: give one"
                ));
            }
            s.mode = SymmetryMode::plane(v).map_err(|e| {
                format!("symmetry_plane = {v:?}: {e}; give a point and a normal, [x, y, z, nx, ny, nz] (mm)")
            })?;
        }
        if let Some(t) = self.symmetry_tolerance_pct {
            if !(t.is_finite() && (0.0..100.0).contains(&t)) {
                return Err(format!(
                    "symmetry_tolerance_pct = {t}: a percentage in [0, 100)"
                ));
            }
            s.tolerance = t / 100.0;
        }
        let asked = s.mode != SymmetryMode::Off || self.symmetry_tolerance_pct.is_some();
        if asked && self.split != Some(flatcut_design::DartsDef::Auto) {
            return Err(
                "symmetry, symmetry_plane and symmetry_tolerance_pct are for the split: they need split = \"auto\"".into(),
            );
        }
        Ok(s)
    }

    /// The largest move of a vertex when the split first removes a scan's spikes
    /// (`despike`, `despike_max_mm`), `None` when it does not, or what is wrong with those keys:
    /// a length that is not positive, or either key without `split = "auto"` (or the length
    /// without `despike = true`).
    pub fn despike_max_mm(&self) -> Result<Option<f64>, String> {
        if let Some(mm) = self.despike_max_mm {
            if !(mm > 0.0 && flatcut_geom::limits::in_range(mm)) {
                return Err(format!("despike_max_mm = {mm}: a positive length in mm"));
            }
            if !self.despike {
                return Err("despike_max_mm needs despike = true".into());
            }
        }
        if self.despike && self.split != Some(flatcut_design::DartsDef::Auto) {
            return Err("despike is for the split: it needs split = \"auto\"".into());
        }
        Ok(self.despike.then(|| {
            self.despike_max_mm
                .unwrap_or(crate::despiking::DEFAULT_MAX_MM)
        }))
    }

    /// The design file's path.
    pub fn design_path(&self) -> PathBuf {
        self.dir.join(&self.design)
    }

    /// The machine profile's name or path (a path is relative to the project file).
    pub fn profile_spec(&self) -> String {
        let p = &self.machine.profile;
        if p.ends_with(".toml") {
            self.dir.join(p).display().to_string()
        } else {
            p.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn project(extra: &str) -> Project {
        let text = format!(
            "name = \"p\"\ndesign = \"d.toml\"\n{extra}\n[material]\nname = \"m\"\nmax_stretch_pct = 10.0\n[sheet]\nwidth_mm = 600.0\nheight_mm = 400.0\n[machine]\nprofile = \"pen\"\n"
        );
        toml::from_str(&text).unwrap()
    }

    #[test]
    fn despike_is_for_the_split_and_moves_at_most_its_length() {
        assert_eq!(project("").despike_max_mm(), Ok(None));
        assert_eq!(
            project("split = \"auto\"\ndespike = true").despike_max_mm(),
            Ok(Some(crate::despiking::DEFAULT_MAX_MM))
        );
        assert_eq!(
            project("split = \"auto\"\ndespike = true\ndespike_max_mm = 5.0").despike_max_mm(),
            Ok(Some(5.0))
        );
        for (bad, said) in [
            ("despike = true", "needs split"),
            (
                "split = \"auto\"\ndespike_max_mm = 5.0",
                "needs despike = true",
            ),
            (
                "split = \"auto\"\ndespike = true\ndespike_max_mm = 0.0",
                "a positive length",
            ),
        ] {
            let e = project(bad).validate().unwrap_err();
            assert!(e.contains(said), "{bad}: {e}");
        }
    }
}
