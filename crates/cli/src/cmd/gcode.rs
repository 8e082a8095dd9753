//! `flatcut gcode FILE --profile pen|knife|laser|PATH.toml -o job.gcode [--frame]`: G-code for a
//! GRBL controller from a pattern SVG, a design or a flattened OBJ.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use flatcut::gcode::{GcodeOptions, Profile};
use flatcut::pattern::Drawing;

use super::common::{self, FlattenArgs, PieceArgs};
use crate::output::OutputSet;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A pattern or layout SVG (mm) or DXF (AAMA or plain), a design, or a flattened OBJ.
    pub file: PathBuf,
    /// pen, knife, laser, or a path to a machine profile (.toml).
    #[arg(long, default_value = "pen")]
    pub profile: String,
    /// The G-code job to write (GRBL dialect, mm); `flatcut send` streams it.
    #[arg(short, long, value_name = "JOB.gcode")]
    pub output: PathBuf,
    /// Also write `<stem>-frame.gcode`: the bounding box traced with the tool off.
    #[arg(long)]
    pub frame: bool,
    /// Keep the drawing's order (no travel optimisation).
    #[arg(long)]
    pub no_reorder: bool,
    /// Lines only (no G2/G3 arcs).
    #[arg(long)]
    pub no_arcs: bool,
    #[command(flatten)]
    pub piece: PieceArgs,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

/// Chordal tolerance used when reading SVGs and DXFs (mm).
const SVG_CHORD_MM: f64 = 0.02;

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let profile = Profile::resolve(&a.profile)?;
    anyhow::ensure!(
        profile.hpgl.is_none(),
        "profile {} drives an HP-GL device: use `flatcut hpgl`",
        profile.name
    );
    let drawing = load_drawing(&a.file, &a.piece, &a.flatten, &profile.colour_table()?)?;
    let mut opts = GcodeOptions::default();
    opts.reorder = !a.no_reorder;
    opts.arcs = !a.no_arcs;
    opts.title = format!(
        "flatcut {}",
        a.file
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let plan = flatcut::gcode::plan(&drawing, &profile, &opts)
        .with_context(|| format!("cannot plan {}", a.file.display()))?;
    let mut out = OutputSet::new();
    out.add(&a.output, plan.to_gcode().as_bytes())?;
    let frame = common::sibling(&a.output, "frame");
    if a.frame {
        out.add(
            &frame,
            flatcut::gcode::frame_job(plan.bbox(), &profile).as_bytes(),
        )?;
    }
    out.commit()?;
    let s = plan.summary();
    crate::outln!("{} lines, {} paths", s.lines, s.paths);
    crate::outln!(
        "cut length {:.1} mm, travel {:.1} mm, estimated time {}",
        s.cut_length_mm,
        s.travel_length_mm,
        hms(s.est_time_s)
    );
    crate::outln!(
        "{}",
        flatcut::gcode::Marking::of(&profile, &drawing).note(&profile.name)
    );
    crate::outln!("wrote {}", a.output.display());
    if a.frame {
        crate::outln!("wrote {} (bounding box, tool off)", frame.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The drawing of an SVG or DXF, or of the pieces of a design / flattened OBJ laid out in a row.
pub fn load_drawing(
    path: &std::path::Path,
    pa: &PieceArgs,
    fa: &FlattenArgs,
    colours: &flatcut::pattern::ColourTable,
) -> anyhow::Result<Drawing> {
    if common::is_pattern_file(path) {
        return common::read_pattern_file(path, SVG_CHORD_MM, colours);
    }
    let flats = common::load_flat(path, fa, (None, None), true)?;
    let pieces = common::build_pieces(&flats, pa)?;
    let mut d = Drawing::default();
    for (k, p) in common::row_layout(&pieces).iter().enumerate() {
        let mut pd = p.to_drawing();
        for s in &mut pd.strokes {
            s.piece = Some(k as u32);
        }
        d.strokes.extend(pd.strokes);
    }
    Ok(d)
}

/// Seconds as `1h 02m 03s` / `2m 03s` / `4.2 s`.
pub fn hms(s: f64) -> String {
    let t = s.round() as u64;
    match t {
        0..60 => format!("{s:.1} s"),
        60..3600 => format!("{}m {:02}s", t / 60, t % 60),
        _ => format!("{}h {:02}m {:02}s", t / 3600, (t % 3600) / 60, t % 60),
    }
}
