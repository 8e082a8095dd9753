//! `flatcut flatten FILE --method M -o flat.obj [--report report.json]`: one OBJ per piece with
//! the input's 3D vertices (`v`), one UV per vertex in mm (`vt`) and `f a/a b/b c/c`. Exits with
//! code 3 (outputs written) when a material limit (`--max-stretch`, `--max-compress`, or a `--material` file's limits along,
//! across or on the bias) is broken or a mating seam's sides differ by more than `--seam-tolerance`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use super::common::{self, FlattenArgs};
use crate::output::OutputSet;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A design (.toml, .json), a mesh (.obj, .stl, .ply) with disk topology, or a STEP model
    /// (.step, .stp; every face a piece).
    pub file: PathBuf,
    /// Output OBJ. With several pieces: `<stem>-<piece>.obj` beside it.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the distortion report (JSON).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Print where the time went: reading the mesh, the start map, the orderings, and over the
    /// Newton steps the assembly, the factorisations, the solves and the line searches, then
    /// the report and writing the outputs.
    #[arg(long)]
    pub timings: bool,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    // A mesh that already carries `vt` is flattened again from its 3D shape.
    let limits = (a.flatten.max_stretch, a.flatten.max_compress);
    let flats = common::flatten_again(&a.file, &a.flatten, limits, true)?;
    let seam_tolerance = a.flatten.seam_tolerance;
    let writing = Instant::now();
    let mut out = OutputSet::new();
    let several = flats.len() > 1;
    let mut reports = Vec::new();
    let mut lines = Vec::new();
    for f in &flats {
        let path = if several {
            common::sibling(&a.output, &common::file_safe(&f.name))
        } else {
            a.output.clone()
        };
        out.add(&path, f.obj().as_bytes())?;
        lines.push(format!(
            "{}: {} vertices, {} faces, mean δ2 {:.6} -> {}",
            f.name,
            f.mesh.positions.len(),
            f.report.faces,
            f.report.delta2_mean,
            path.display()
        ));
        reports.push(f.written_report());
    }
    if let Some(path) = &a.report {
        let json = if several {
            serde_json::to_string_pretty(&reports)?
        } else {
            serde_json::to_string_pretty(&reports[0])?
        };
        out.add(path, json.as_bytes())?;
    }
    out.commit()?;
    if a.timings {
        print_timings(&flats, writing.elapsed());
    }
    for l in lines {
        crate::outln!("{l}");
    }
    common::print_seams(&flats)?;
    // The outputs are written either way, so the user can see what breaks the limits.
    if common::report_limits(&flats, seam_tolerance, false) {
        eprintln!("material limits or seam tolerance exceeded");
        return Ok(ExitCode::from(crate::EXIT_LIMIT));
    }
    Ok(ExitCode::SUCCESS)
}

/// `--timings`: reading the input once, each piece's solve by its parts and its report, then
/// writing the outputs.
fn print_timings(flats: &[common::Flat], write: Duration) {
    let read = flats.first().map_or(Duration::ZERO, |f| f.times.read);
    eprintln!("  time: read {:.2} s", read.as_secs_f64());
    for f in flats {
        let solve = f.info.as_ref().map(|i| format!("{}, ", i.timings));
        eprintln!(
            "  time '{}': {}report {:.2} s",
            f.name,
            solve.unwrap_or_default(),
            f.times.report.as_secs_f64()
        );
    }
    eprintln!("  time: write {:.2} s", write.as_secs_f64());
}
