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
    // A mesh that already carries `vt` is flattened again from its 3D shape. A mesh that may be
    // split into several pieces goes the way of a design's pieces.
    // Reading the mesh, the flattening's own parts and the report, for --timings.
    let mut spent: Option<(Duration, flatcut::flatten::Timings, Duration)> = None;
    let flats = if common::is_mesh(&a.file) && a.flatten.split.is_none() {
        let reading = Instant::now();
        let mut mesh = flatcut::mesh::read_mesh(&a.file).map_err(anyhow::Error::from)?;
        let read = reading.elapsed();
        mesh.flat = None;
        let name = a
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "mesh".into());
        // Ctrl-C stops the flattening at its cancel flag; nothing is written then.
        let stop = crate::stop::Stoppable::register();
        let (params, bar) = common::with_progress_bar(a.flatten.params()?);
        let params = params.clone().with_hooks(stop.hooks(params.hooks));
        let material = a.flatten.material()?;
        // Checked before the solve: darts without limits are refused at once, not after it.
        let settings = a.flatten.darts()?;
        eprintln!(
            "flattening '{name}' ({} faces) with {}",
            mesh.triangles.len(),
            match &material {
                Some(m) => format!("{} for {}", flatcut::flatten::Method::Orthotropic, m.name),
                None => params.method.to_string(),
            }
        );
        let t0 = std::time::Instant::now();
        let solved = match &material {
            Some(m) => flatcut::material::flatten(&name, &mesh, &params, m, None)
                .map(|(f, g)| (f, Some(g)))
                .map_err(|e| anyhow::Error::new(e).context(a.file.display().to_string())),
            None => flatcut::flatten::flatten(&mesh, &params)
                .map(|f| (f, None))
                .map_err(|e| anyhow::anyhow!("{}: {e}", a.file.display())),
        };
        bar.finish_and_clear();
        stop.check(|| format!("the flattening of {}", a.file.display()))?;
        let (f, grain) = solved?;
        let dart_limits = match (&material, &grain) {
            (Some(m), Some(g)) => flatcut::material::dart_limits(&params, m, g, None, &mesh),
            _ => flatcut::darting::DartLimits::of(&params),
        };
        let before = (mesh.clone(), f.uv.clone());
        let flatcut::darting::Finished {
            mesh: darted,
            info,
            darts,
            grain_kept,
        } = flatcut::darting::finish(
            &name,
            None,
            mesh,
            f.uv,
            f.info,
            &dart_limits,
            settings.as_ref(),
        )
        .map_err(|e| anyhow::Error::new(e).context(a.file.display().to_string()))?;
        mesh = darted;
        let grain = grain.map(|g| {
            if grain_kept {
                g
            } else {
                let uv = mesh.flat.as_deref().unwrap_or_default();
                flatcut::material::carry_over(&g, (&before.0, &before.1), (&mesh, uv))
            }
        });
        if !darts.is_empty() {
            let total: f64 = darts.iter().map(|d| d.length_3d_mm).sum();
            eprintln!("  {} darts, {total:.1} mm in all", darts.len());
        }
        for w in &info.warnings {
            eprintln!("warning: {w}");
        }
        let reporting = Instant::now();
        let mut report = flatcut::pipeline::report_piece(
            &name,
            &mesh,
            &[],
            a.flatten.max_stretch,
            a.flatten.max_compress,
        )?;
        spent = Some((read, info.timings, reporting.elapsed()));
        report.darts = flatcut::darting::dart_reports(&darts);
        report.set_grain(
            grain
                .as_ref()
                .and_then(|g| flatcut::material::report(g, &mesh)),
        );
        eprintln!(
            "  {} iterations{}, mean δ2 {:.6}, stretch max {:.2}%, compression max {:.2}%, {:.2} s",
            info.iterations,
            common::stage_counts(&info),
            report.delta2_mean,
            report.stretch_max_pct,
            report.compress_max_pct,
            t0.elapsed().as_secs_f64()
        );
        if let Some(g) = &report.grain {
            eprintln!("{}", common::grain_line(g));
        }
        vec![common::Flat {
            name,
            def: None,
            mesh,
            report,
            quantity: 1,
            mirrored: 0,
            notches: Vec::new(),
            info: Some(info),
            darts,
            grain,
            grain_dir: None,
        }]
    } else {
        let limits = (a.flatten.max_stretch, a.flatten.max_compress);
        common::flatten_again(&a.file, &a.flatten, limits, true)?
    };
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
        let obj = flatcut::mesh::io::obj_string(&f.mesh) + &flatcut::dart_lines::write(&f.darts);
        out.add(&path, obj.as_bytes())?;
        lines.push(format!(
            "{}: {} vertices, {} faces, mean δ2 {:.6} -> {}",
            f.name,
            f.mesh.positions.len(),
            f.report.faces,
            f.report.delta2_mean,
            path.display()
        ));
        reports.push(&f.report);
    }
    if let Some(path) = &a.report {
        let json = if several {
            serde_json::to_string_pretty(&reports)?
        } else {
            serde_json::to_string_pretty(reports[0])?
        };
        out.add(path, json.as_bytes())?;
    }
    out.commit()?;
    if a.timings {
        let write = writing.elapsed().as_secs_f64();
        match spent {
            Some((read, t, report)) => eprintln!(
                "  time: read {:.2} s, {t}, report {:.2} s, write {write:.2} s",
                read.as_secs_f64(),
                report.as_secs_f64()
            ),
            None => {
                for f in &flats {
                    if let Some(info) = &f.info {
                        eprintln!("  time '{}': {}", f.name, info.timings);
                    }
                }
                eprintln!("  time: write {write:.2} s");
            }
        }
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
