//! A pattern or layout SVG as an HP-GL/1 job, as `flatcut hpgl FILE.svg --profile P` writes it:
//! the SVG read back into a drawing (its layers from its groups or stroke colours, curves within
//! [`READ_CHORD_MM`]), planned for the profile's plotter and written as HP-GL.

use flatcut_gcode::{GcodeOptions, Profile};

/// Chordal tolerance of curves read from a pattern SVG or DXF for plotting (mm): a twentieth of
/// a vinyl cutter's blade offset.
pub const READ_CHORD_MM: f64 = 0.02;

/// Why an SVG cannot be plotted.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    #[error(transparent)]
    /// The machine profile cannot be used.
    Profile(#[from] flatcut_gcode::ProfileError),
    #[error(transparent)]
    /// The drawing could not be read or built.
    Pattern(#[from] flatcut_pattern::PatternError),
    #[error("cannot plan {name}: {source}")]
    /// The drawing's job could not be planned.
    Plan {
        /// The drawing's name.
        name: String,
        /// Why the plan failed.
        source: flatcut_gcode::GcodeError,
    },
    #[error("{name}: {source}")]
    /// The plan cannot be written as HP-GL.
    Hpgl {
        /// The drawing's name.
        name: String,
        /// Why HP-GL cannot be written.
        source: flatcut_gcode::hpgl::HpglError,
    },
}

/// The HP-GL/1 job of the SVG `text` (named `name` in errors) for `profile`, and the reader's
/// warnings.
pub fn hpgl_of_svg(
    text: &str,
    name: &str,
    profile: &Profile,
) -> Result<(String, Vec<String>), PlotError> {
    let colours = profile.colour_table()?;
    let import = flatcut_pattern::svg::read_svg(text, name, READ_CHORD_MM, &colours)?;
    let plan = flatcut_gcode::plan(&import.drawing, profile, &GcodeOptions::default()).map_err(
        |source| PlotError::Plan {
            name: name.to_string(),
            source,
        },
    )?;
    let hpgl = plan.to_hpgl().map_err(|source| PlotError::Hpgl {
        name: name.to_string(),
        source,
    })?;
    Ok((hpgl, import.warnings))
}
