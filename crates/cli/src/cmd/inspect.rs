//! `flatcut inspect FILE [--json]`: what a design, mesh or STEP file contains.

use std::path::PathBuf;
use std::process::ExitCode;

use flatcut::geom::Tolerances;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A design file (.toml, .json), a mesh (.obj, .stl, .ply) or a STEP model (.step, .stp).
    pub file: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Chordal tolerance of the tessellation in mm.
    #[arg(long, default_value_t = Tolerances::DEFAULT_CHORD_MM, value_parser = crate::values::positive_mm)]
    pub chord: f64,
    /// The largest defect of a STEP model healed, in mm (gaps between edges, edges off their
    /// faces); beyond it the file is refused [default: 0.2 % of the model's size].
    #[arg(long, value_name = "MM", value_parser = crate::values::positive_mm)]
    pub heal_tolerance: Option<f64>,
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        a.chord.is_finite() && a.chord > 0.0,
        "--chord must be a positive length in mm, got {}",
        a.chord
    );
    let tol = Tolerances::DEFAULT
        .with_chord_mm(a.chord)
        .with_heal_mm(a.heal_tolerance);
    // Every error of a design, mesh or STEP file names the file: no context to add.
    let report = flatcut::inspect::inspect_file(&a.file, &tol)?;
    if a.json {
        crate::outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        crate::out!("{report}");
    }
    Ok(ExitCode::SUCCESS)
}
