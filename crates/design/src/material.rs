//! Material files: a material's stretch and compression limits along its grain, across it and
//! on the 45° bias, and optionally its stiffness in those directions (TOML; the format and the
//! sources of the bundled figures are in `materials/README.md`). The bundled materials are
//! compiled in; any other name is read as a file path.

use std::path::Path;

use serde::Deserialize;

/// The bundled materials: name and file text, in the order `--help` lists them.
pub const BUNDLED: [(&str, &str); 6] = [
    ("leather", include_str!("../materials/leather.toml")),
    (
        "woven-cotton",
        include_str!("../materials/woven-cotton.toml"),
    ),
    ("canvas", include_str!("../materials/canvas.toml")),
    ("knit", include_str!("../materials/knit.toml")),
    (
        "carbon-prepreg",
        include_str!("../materials/carbon-prepreg.toml"),
    ),
    ("sailcloth", include_str!("../materials/sailcloth.toml")),
];

/// Largest material file read (bytes): a material is a dozen numbers.
const MAX_FILE_BYTES: u64 = 64 * 1024;

/// Three values: along the grain (warp), across it (weft), on the 45° bias.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Directions {
    /// Along the grain (warp), in percent.
    pub along: f64,
    /// Across the grain (weft), in percent.
    pub across: f64,
    /// On the 45° bias, in percent.
    pub bias: f64,
}

/// Stiffness relative to an isotropic sheet (1, 1, 1).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialStiffness {
    /// Stiffness along the grain (warp), relative to an isotropic sheet's 1.
    pub along: f64,
    /// Stiffness across the grain (weft), relative to an isotropic sheet's 1.
    pub across: f64,
    /// Shear stiffness (on the bias), relative to an isotropic sheet's 1.
    pub shear: f64,
}

/// A material: its limits per direction (percent) and stiffness.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// The material's name, as the report prints it.
    pub name: String,
    #[serde(default)]
    /// A line describing the material, for people reading the file.
    pub description: Option<String>,
    /// The largest stretch the material takes per direction, percent of the length (≥ 0).
    pub stretch_max_pct: Directions,
    /// The largest compression the material takes per direction, percent of the length (≥ 0).
    pub compress_max_pct: Directions,
    #[serde(default)]
    /// Relative stiffness per direction; absent: isotropic (1, 1, 1).
    pub stiffness: Option<MaterialStiffness>,
}

/// A material file that cannot be used: which file, which key, what is wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MaterialError {
    #[error(
        "material '{name}': no bundled material of that name and no such file ({source}); bundled: {}",
        bundled_names()
    )]
    /// The name is neither a bundled material nor a readable file.
    NotFound {
        /// The material as the design names it.
        name: String,
        /// Why the file of that name could not be read.
        source: std::io::Error,
    },
    /// `at` is `:line:column` where the parser knows it.
    #[error("{file}{at}: {msg}")]
    Syntax {
        /// The material file's path as given.
        file: String,
        /// Where in the file: `:line:column`, or empty when the parser does not say.
        at: String,
        /// The parser's description of the problem.
        msg: String,
    },
    #[error("{file}: {key}: {msg}")]
    /// A key whose value is out of range or inconsistent.
    Invalid {
        /// The material file's path as given (or the bundled material's name).
        file: String,
        /// The offending key, e.g. `stretch_max_pct.bias`.
        key: String,
        /// What is wrong with its value.
        msg: String,
    },
}

fn bundled_names() -> String {
    BUNDLED.map(|(n, _)| n).join(", ")
}

impl MaterialSpec {
    /// A bundled material by name, or the material file at `spec` (relative to `base`).
    pub fn load(spec: &str, base: Option<&Path>) -> Result<Self, MaterialError> {
        if let Some((_, text)) = BUNDLED.iter().find(|(n, _)| *n == spec) {
            return Self::parse(text, &format!("bundled material '{spec}'"));
        }
        let path = match base {
            Some(b) => b.join(spec),
            None => Path::new(spec).to_path_buf(),
        };
        let not_found = |source| MaterialError::NotFound {
            name: spec.to_string(),
            source,
        };
        let len = std::fs::metadata(&path).map_err(not_found)?.len();
        let file = path.display().to_string();
        if len > MAX_FILE_BYTES {
            return Err(MaterialError::Syntax {
                file,
                at: String::new(),
                msg: format!(
                    "{len} bytes is too large for a material file (at most {MAX_FILE_BYTES})"
                ),
            });
        }
        let text = std::fs::read_to_string(&path).map_err(not_found)?;
        Self::parse(&text, &file)
    }

    /// Parses and checks a material file's text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, MaterialError> {
        let spec: MaterialSpec = toml::from_str(text).map_err(|e| {
            let at = e.span().map_or(String::new(), |s| {
                let before = &text[..s.start.min(text.len())];
                format!(
                    ":{}:{}",
                    before.matches('\n').count() + 1,
                    before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1
                )
            });
            MaterialError::Syntax {
                file: file.to_string(),
                at,
                msg: e.message().to_string(),
            }
        })?;
        spec.validate(file)?;
        Ok(spec)
    }

    fn validate(&self, file: &str) -> Result<(), MaterialError> {
        let bad = |key: String, msg: String| MaterialError::Invalid {
            file: file.to_string(),
            key,
            msg,
        };
        if self.name.trim().is_empty() {
            return Err(bad("name".into(), "is empty".into()));
        }
        for (table, d) in [
            ("stretch_max_pct", self.stretch_max_pct),
            ("compress_max_pct", self.compress_max_pct),
        ] {
            for (k, v) in [("along", d.along), ("across", d.across), ("bias", d.bias)] {
                if !(v.is_finite() && (0.0..100.0).contains(&v)) {
                    return Err(bad(
                        format!("{table}.{k}"),
                        format!("{v} is not a percentage in [0, 100)"),
                    ));
                }
            }
        }
        if let Some(s) = self.stiffness {
            for (k, v) in [("along", s.along), ("across", s.across), ("shear", s.shear)] {
                if !(v.is_finite() && v > 0.0 && v <= 1e6) {
                    return Err(bad(
                        format!("stiffness.{k}"),
                        format!("{v} is not a positive stiffness ratio (at most 1e6)"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The stiffness (isotropic when the file gives none).
    pub fn stiffness_or_isotropic(&self) -> MaterialStiffness {
        self.stiffness.unwrap_or(MaterialStiffness {
            along: 1.0,
            across: 1.0,
            shear: 1.0,
        })
    }

    /// The tightest stretch and compression limits over the three directions: the isotropic
    /// band that holds every direction (a direction's stretch lies between the principal ones).
    pub fn tightest_pct(&self) -> (f64, f64) {
        let m = |d: Directions| d.along.min(d.across).min(d.bias);
        (m(self.stretch_max_pct), m(self.compress_max_pct))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bundled_material_loads_under_its_own_name() {
        for (name, _) in BUNDLED {
            let m = MaterialSpec::load(name, None).unwrap();
            assert_eq!(m.name, name);
            assert!(m.stiffness.is_some(), "{name}");
        }
    }

    #[test]
    fn woven_materials_are_softer_in_shear_and_on_the_bias() {
        for name in ["woven-cotton", "canvas", "carbon-prepreg", "sailcloth"] {
            let m = MaterialSpec::load(name, None).unwrap();
            let s = m.stiffness.unwrap();
            assert!(s.shear < 0.1 * s.along.min(s.across), "{name}");
            let d = m.stretch_max_pct;
            assert!(d.bias > 3.0 * d.along.max(d.across), "{name}");
        }
    }

    #[test]
    fn bad_files_say_which_file_key_and_what() {
        let ok = "name = \"x\"\n[stretch_max_pct]\nalong = 1\nacross = 2\nbias = 3\n[compress_max_pct]\nalong = 1\nacross = 1\nbias = 3\n";
        assert!(MaterialSpec::parse(ok, "m.toml").is_ok());
        let e = MaterialSpec::parse(&ok.replace("bias = 3\n[c", "bias = 130\n[c"), "m.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("m.toml") && e.contains("stretch_max_pct.bias") && e.contains("130"),
            "{e}"
        );
        let e = MaterialSpec::parse(
            &format!("{ok}[stiffness]\nalong = 1\nacross = 1\nshear = 0\n"),
            "m.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("stiffness.shear"), "{e}");
        let e = MaterialSpec::parse(&ok.replace("across = 2", "acros = 2"), "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("m.toml:") && e.contains("acros"), "{e}");
        let e = MaterialSpec::parse(
            &ok.replace("along = 1\nacross = 2", "along = \"x\"\nacross = 2"),
            "m.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("m.toml:3:"), "{e}");
        let e = MaterialSpec::load("no-such-material", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no-such-material") && e.contains("woven-cotton"),
            "{e}"
        );
    }

    #[test]
    fn a_users_file_is_read_relative_to_its_base() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("felt.toml"),
            "name = \"felt\"\n[stretch_max_pct]\nalong = 8\nacross = 8\nbias = 8\n[compress_max_pct]\nalong = 8\nacross = 8\nbias = 8\n",
        )
        .unwrap();
        let m = MaterialSpec::load("felt.toml", Some(dir.path())).unwrap();
        assert_eq!(m.name, "felt");
        assert_eq!(m.tightest_pct(), (8.0, 8.0));
        assert_eq!(m.stiffness_or_isotropic().shear, 1.0);
    }
}
