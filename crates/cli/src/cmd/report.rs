//! `flatcut report FLAT.obj [more.obj…] [--json] [--svg] [--png] [--html] [--measure]
//! [--limit-stretch P] [--limit-compress P]`: Duncan's distortion measures of flattened pieces
//! (a design is flattened first), with pictures; exits 3 when a limit is exceeded.

use std::path::PathBuf;
use std::process::ExitCode;

use flatcut::report::Measure;

use super::common::{self, FlattenArgs};
use crate::output::OutputSet;
use crate::values;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Flattened OBJs (with `vt`), or designs (flattened first with --method).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Write the figures as JSON (one object; an array for several inputs).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// With --json: add `per_face`, each face's index, 3D centroid and measures (μ1, μ2, δ1, δ2,
    /// area ratio, stretch, compression, flipped, and with a material its excess over the
    /// limits along, across or on the bias).
    #[arg(long, requires = "json")]
    pub per_face: bool,
    /// Heat map as SVG (true mm, one column per input).
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Heat map as PNG, rendered from the same SVG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Width of the PNG in pixels (default: 10 pixels per mm, the longest side at most 4096;
    /// at most 16384).
    #[arg(long, value_parser = values::png_width)]
    pub png_width: Option<u32>,
    /// Self-contained HTML report.
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// What the pictures show: delta1, delta2, stretch, area, or material (each face's largest
    /// excess over its material's limits along, across or on the bias, in percentage points;
    /// pieces flattened with a material).
    #[arg(long, default_value = "stretch", value_parser = parse_measure)]
    pub measure: Measure,
    /// Draw short ticks along the principal stretch directions.
    #[arg(long)]
    pub glyphs: bool,
    /// Exit with code 3 and list the regions stretched more than P percent.
    #[arg(long, value_name = "P", value_parser = values::limit_percent)]
    pub limit_stretch: Option<f64>,
    /// Exit with code 3 and list the regions compressed more than P percent.
    #[arg(long, value_name = "P", value_parser = values::limit_percent)]
    pub limit_compress: Option<f64>,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

fn parse_measure(s: &str) -> Result<Measure, String> {
    Measure::from_name(s).ok_or_else(|| {
        format!("unknown measure '{s}'; one of delta1, delta2, stretch, area, material")
    })
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    for (name, v) in [
        ("--limit-stretch", a.limit_stretch),
        ("--limit-compress", a.limit_compress),
    ] {
        if let Some(v) = v {
            anyhow::ensure!(
                v.is_finite() && v >= 0.0,
                "{name} must be a percentage >= 0, got {v}"
            );
        }
    }
    let mut flats = Vec::new();
    let mut sources = Vec::new();
    for f in &a.files {
        for flat in common::load_flat(f, &a.flatten, (a.limit_stretch, a.limit_compress), false)? {
            flats.push(flat);
            sources.push(f.as_path());
        }
    }
    flatcut::flat::tell_apart(&mut flats, &sources);
    // Flattened meshes of one split surface pair up by their seams' shared coordinates.
    flatcut::flat::pair_coincident(&mut flats);
    if a.measure == Measure::Material
        && let Some(f) = flats.iter().find(|f| f.report.grain.is_none())
    {
        anyhow::bail!(
            "--measure material: piece '{}' has no material to measure against; flatten a design \
             with --material NAME or a piece's material_properties (a flat OBJ does not carry \
             its grain)",
            f.name
        );
    }
    for f in &flats {
        let r = &f.report;
        crate::outln!("{}", f.name);
        crate::outln!(
            "  faces {}   flipped {}   area 3D {:.1} mm²   area 2D {:.1} mm²",
            r.faces,
            r.flipped,
            r.area_3d_mm2,
            r.area_2d_mm2
        );
        crate::outln!("  δ0 {:.5} ({})", r.delta0, r.delta0_method);
        crate::outln!(
            "  δ1 mean {:.5}  p90 {:.5}  max {:.5}",
            r.delta1_mean,
            r.delta1_p90,
            r.delta1_max
        );
        crate::outln!(
            "  δ2 mean {:.5}  p90 {:.5}  max {:.5}",
            r.delta2_mean,
            r.delta2_p90,
            r.delta2_max
        );
        crate::outln!(
            "  stretch max {:.2}%  compression max {:.2}%  area ratio mean {:.5}",
            r.stretch_max_pct,
            r.compress_max_pct,
            r.area_mean
        );
        crate::outln!(
            "  boundary length error {:+.4}%",
            r.boundary_length_error * 100.0
        );
        for s in &r.boundary_segments {
            crate::outln!(
                "    seam {}→{}: 3D {:.2} mm, 2D {:.2} mm ({:+.3}%)",
                s.from_vertex,
                s.to_vertex,
                s.length_3d_mm,
                s.length_2d_mm,
                s.relative_error * 100.0
            );
        }
    }
    let mut out = OutputSet::new();
    if let Some(p) = &a.json {
        // One object for one input, an array for several; keys in the report's own order.
        let json = match (a.per_face, flats.as_slice()) {
            (true, [f]) => {
                serde_json::to_string_pretty(&flatcut::report::with_faces(&f.report, &f.mesh))?
            }
            (true, all) => serde_json::to_string_pretty(
                &all.iter()
                    .map(|f| flatcut::report::with_faces(&f.report, &f.mesh))
                    .collect::<Vec<_>>(),
            )?,
            (false, [f]) => serde_json::to_string_pretty(&f.report)?,
            (false, all) => {
                serde_json::to_string_pretty(&all.iter().map(|f| &f.report).collect::<Vec<_>>())?
            }
        };
        out.add(p, json.as_bytes())?;
    }
    let cols = flatcut::flat::columns(&flats);
    if a.svg.is_some() || a.png.is_some() {
        let svg = flatcut::report::heatmap_svg(&cols, a.measure, a.glyphs);
        if let Some(p) = &a.svg {
            out.add(p, svg.as_bytes())?;
        }
        if let Some(p) = &a.png {
            out.add(p, &flatcut::report::render_png(&svg, a.png_width)?)?;
        }
    }
    if let Some(p) = &a.html {
        out.add(
            p,
            flatcut::report::html_report(&cols, a.measure, a.glyphs).as_bytes(),
        )?;
    }
    out.commit()?;
    common::print_seams(&flats)?;
    let limits_given = a.limit_stretch.is_some() || a.limit_compress.is_some();
    let over = common::report_limits(&flats, a.flatten.seam_tolerance, limits_given);
    if over {
        eprintln!("material limits or seam tolerance exceeded");
        return Ok(ExitCode::from(crate::EXIT_LIMIT));
    }
    Ok(ExitCode::SUCCESS)
}
