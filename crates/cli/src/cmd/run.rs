//! `flatcut run PROJECT.toml`: the whole job in one command — design → flatten → report →
//! pattern (SVG, DXF) → nest → G-code → stream to the device (the embedded simulator unless a
//! port is given) — with all outputs in one folder and a summary table at the end.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context as _;
use flatcut::flatten::Method;
use flatcut::gcode::{GcodeOptions, Profile};
use flatcut::geom::DVec2;
use flatcut::nest::{NestOptions, Stock};
use flatcut::pattern::dxf::DxfLayers;
use flatcut::pipeline::{self, NestGroup};
use flatcut::project::Project;
use flatcut::report::{Column, Measure};

use super::common::{self, FlattenArgs, PieceArgs};
use super::device::{self, StreamArgs};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The project file (see patterns/README.md).
    pub project: PathBuf,
    /// Output folder (default: out/<project name>).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Stop after writing the G-code (do not stream).
    #[arg(long)]
    pub no_send: bool,
    /// Stream every sheet's job, not just the first (the embedded simulator always runs all).
    #[arg(long)]
    pub all_sheets: bool,
    /// Stream even when the report finds material limits exceeded.
    #[arg(long)]
    pub force: bool,
    /// Nesting iterations.
    #[arg(long, default_value_t = 60)]
    pub nest_iters: usize,
    #[command(flatten)]
    pub stream: StreamArgs,
}

fn stage(k: usize, name: &str) {
    eprintln!("[{k}/6] {name}");
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let t0 = Instant::now();
    let proj = Project::load(&a.project)?;
    let out = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(common::file_safe(&proj.name)));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let method = proj
        .method
        .as_deref()
        .map(|m| Method::from_name(m).expect("validated"))
        .unwrap_or(Method::Isometric);
    let fa = FlattenArgs {
        method,
        max_stretch: proj.material.max_stretch_pct,
        max_compress: proj.material.max_compress_pct,
        chord: flatcut::geom::Tolerances::DEFAULT_CHORD_MM * 4.0,
        max_iters: None,
        flatten_time: None,
    };
    // Material limits are reported by the report stage; the flattening honours them where it can.
    let limits = (
        proj.material.max_stretch_pct,
        proj.material.max_compress_pct,
    );

    stage(
        1,
        &format!("flatten {} ({method})", proj.design_path().display()),
    );
    let flats = common::load_flat(&proj.design_path(), &fa, limits, true)?;
    for f in &flats {
        common::write(
            &out.join(format!("{}.obj", common::file_safe(&f.name))),
            flatcut::mesh::io::obj_string(&f.mesh).as_bytes(),
        )?;
    }

    stage(2, "distortion report");
    let reports: Vec<_> = flats.iter().map(|f| &f.report).collect();
    common::write(
        &out.join("report.json"),
        serde_json::to_string_pretty(&reports)?.as_bytes(),
    )?;
    let cols: Vec<Column<'_>> = flats
        .iter()
        .map(|f| Column {
            title: f.name.to_uppercase(),
            mesh: &f.mesh,
            report: &f.report,
        })
        .collect();
    let heat = flatcut::report::heatmap_svg(&cols, Measure::Stretch, false);
    common::write(&out.join("heatmap.svg"), heat.as_bytes())?;
    common::write(
        &out.join("heatmap.png"),
        &flatcut::report::render_png(&heat, None)?,
    )?;
    common::write(
        &out.join("report.html"),
        flatcut::report::html_report(&cols, Measure::Stretch, false).as_bytes(),
    )?;
    let over: Vec<String> = flats
        .iter()
        .flat_map(|f| {
            f.report.regions.iter().map(move |r| {
                format!(
                    "{}: {} {:.2}% over {:.0} mm² near ({:.0}, {:.0}, {:.0})",
                    f.name,
                    r.kind,
                    r.worst_pct,
                    r.area_mm2,
                    r.centroid_3d[0],
                    r.centroid_3d[1],
                    r.centroid_3d[2]
                )
            })
        })
        .collect();
    // The five worst regions per piece (regions are sorted worst first).
    for f in &flats {
        for r in f.report.regions.iter().take(5) {
            eprintln!(
                "  material limit exceeded: {}: {} {:.2}% over {:.0} mm² near ({:.0}, {:.0}, {:.0})",
                f.name,
                r.kind,
                r.worst_pct,
                r.area_mm2,
                r.centroid_3d[0],
                r.centroid_3d[1],
                r.centroid_3d[2]
            );
        }
        if f.report.regions.len() > 5 {
            eprintln!(
                "  … and {} more region(s) of '{}' (see report.html)",
                f.report.regions.len() - 5,
                f.name
            );
        }
    }

    stage(3, "pattern pieces");
    let pa = PieceArgs {
        seam: proj.seam_mm,
        corner: Default::default(),
        notch: Default::default(),
    };
    let pieces = common::build_pieces(&flats, &pa)?;
    let placed = common::row_layout(&pieces);
    common::write(
        &out.join("pattern.svg"),
        flatcut::pattern::svg::write_pieces(&placed, None).as_bytes(),
    )?;
    common::write(
        &out.join("pattern.dxf"),
        flatcut::pattern::dxf::write_pieces(
            &placed,
            DxfLayers::Aama,
            flatcut::pattern::PieceOptions::DEFAULT_CHORD_TOL,
        )
        .as_bytes(),
    )?;

    stage(4, "nesting");
    let stock = match (
        proj.sheet.width_mm,
        proj.sheet.height_mm,
        proj.sheet.roll_width_mm,
    ) {
        (Some(w), Some(h), _) => Stock::Sheets {
            width: w,
            height: h,
            max_sheets: None,
        },
        (_, _, Some(w)) => Stock::Roll {
            width: w,
            max_length: None,
        },
        _ => unreachable!("validated"),
    };
    let groups: Vec<NestGroup> = pieces
        .iter()
        .zip(&flats)
        .map(|(p, f)| NestGroup::from_piece(p, f.quantity as usize, false))
        .collect();
    let nopts = NestOptions::DEFAULT
        .with_spacing(proj.sheet.spacing_mm)
        .with_max_iters(a.nest_iters);
    let layout = pipeline::nest_groups(&groups, stock, &nopts, &mut |_| {})?;
    let sheet_size = match stock {
        Stock::Sheets { width, height, .. } => DVec2::new(width, height),
        Stock::Roll { width, .. } => DVec2::new(layout.result.length.max(1.0), width),
    };
    for u in &layout.result.unplaced {
        eprintln!("  unplaced: {} copy {}: {}", u.name, u.copy, u.reason);
    }

    stage(5, "G-code");
    let profile = Profile::resolve(&proj.profile_spec())?;
    let mut jobs = Vec::new();
    let (mut cut_mm, mut travel_mm, mut est_s, mut lines) = (0.0, 0.0, 0.0, 0usize);
    let mut drawings = Vec::new();
    for (k, d) in layout.sheets.iter().enumerate() {
        let n = k + 1;
        common::write(
            &out.join(format!("layout-{n}.svg")),
            flatcut::pattern::svg::write_drawing(d, Some(sheet_size)).as_bytes(),
        )?;
        common::write(
            &out.join(format!("layout-{n}.dxf")),
            flatcut::pattern::dxf::write_drawing(d, DxfLayers::Aama).as_bytes(),
        )?;
        let mut go = GcodeOptions::default();
        go.title = format!("flatcut {} sheet {n}", proj.name);
        let plan = flatcut::gcode::plan(d, &profile, &go).with_context(|| format!("sheet {n}"))?;
        let s = plan.summary();
        cut_mm += s.cut_length_mm;
        travel_mm += s.travel_length_mm;
        est_s += s.est_time_s;
        lines += s.lines;
        let path = out.join(format!("job-{n}.gcode"));
        common::write(&path, plan.to_gcode().as_bytes())?;
        common::write(
            &out.join(format!("job-{n}-frame.gcode")),
            flatcut::gcode::frame_job(plan.bbox(), &profile).as_bytes(),
        )?;
        jobs.push(path);
        drawings.push(d.clone());
    }

    let mut stream_lines = Vec::new();
    let mut exit = ExitCode::SUCCESS;
    if a.no_send {
        stage(6, "send: skipped (--no-send)");
    } else if !over.is_empty() && !a.force {
        stage(
            6,
            "send: skipped, the material limits are exceeded (see above; --force streams anyway)",
        );
        exit = ExitCode::from(crate::EXIT_LIMIT);
    } else {
        let to_send = if a.stream.uses_sim() || a.all_sheets {
            jobs.len()
        } else {
            1
        };
        stage(
            6,
            &format!(
                "send {} job(s) to {}",
                to_send,
                a.stream.port.as_deref().unwrap_or("the embedded simulator")
            ),
        );
        for (k, job) in jobs.iter().take(to_send).enumerate() {
            let mut sa = a.stream.clone();
            if sa.uses_sim() {
                if sa.sim_svg.is_none() {
                    sa.sim_svg = Some(out.join(format!("sim-{}.svg", k + 1)));
                }
                if sa.sim_trace.is_none() {
                    sa.sim_trace = Some(out.join(format!("sim-{}.jsonl", k + 1)));
                }
                sa.sim_laser = profile.kind == flatcut::gcode::ToolKind::Laser;
            }
            let o = device::stream_file(job, &sa)?;
            let dev = match &o.sim_trace {
                Some(trace) => {
                    let d = trace_deviation(trace, &drawings[k], &profile);
                    format!(
                        ", simulator traced {} segments, cut path within {:.3} mm of the pattern",
                        trace.len(),
                        d
                    )
                }
                None => String::new(),
            };
            stream_lines.push(format!(
                "sheet {}: {} lines streamed in {:.1} s, link {:.0}% busy{}",
                k + 1,
                o.report.lines_sent,
                o.report.total_time.as_secs_f64(),
                o.link_utilisation() * 100.0,
                dev
            ));
        }
        if to_send < jobs.len() {
            stream_lines.push(format!("{} more sheet(s): load the next sheet, then `flatcut send {}/job-N.gcode --port …`", jobs.len() - to_send, out.display()));
        }
    }

    // Summary.
    println!();
    println!(
        "{:<20} {:>4} {:>12} {:>10} {:>10} {:>10}",
        "piece", "qty", "area mm²", "δ2 mean", "stretch%", "compr.%"
    );
    for f in &flats {
        let r = &f.report;
        println!(
            "{:<20} {:>4} {:>12.0} {:>10.5} {:>10.2} {:>10.2}",
            f.name, f.quantity, r.area_3d_mm2, r.delta2_mean, r.stretch_max_pct, r.compress_max_pct
        );
    }
    let r = &layout.result;
    println!();
    match stock {
        Stock::Sheets { width, height, .. } => println!(
            "nesting      {} sheet(s) {width:.0}×{height:.0} mm, utilization {:.1}%",
            r.sheets, r.utilization
        ),
        Stock::Roll { width, .. } => println!(
            "nesting      roll {width:.0} mm, length {:.0} mm, utilization {:.1}%",
            r.length, r.utilization
        ),
    }
    println!(
        "G-code       {lines} lines, cut {cut_mm:.0} mm, travel {travel_mm:.0} mm, estimated {}",
        super::gcode::hms(est_s)
    );
    for l in &stream_lines {
        println!("stream       {l}");
    }
    println!("outputs      {}", out.display());
    println!("run time     {:.1} s", t0.elapsed().as_secs_f64());
    let summary = serde_json::json!({
        "project": proj.name,
        "pieces": flats.iter().map(|f| serde_json::json!({"name": f.name, "quantity": f.quantity, "area_mm2": f.report.area_3d_mm2,
            "delta2_mean": f.report.delta2_mean, "stretch_max_pct": f.report.stretch_max_pct, "compress_max_pct": f.report.compress_max_pct})).collect::<Vec<_>>(),
        "sheets": r.sheets, "utilization_pct": r.utilization, "unplaced": r.unplaced.len(),
        "gcode_lines": lines, "cut_length_mm": cut_mm, "travel_length_mm": travel_mm, "est_time_s": est_s,
        "limits_exceeded": over,
    });
    common::write(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(exit)
}

/// Largest distance from a tool-on point of the simulator's trace to the drawing's strokes in
/// machine coordinates (a one-sided Hausdorff distance, sampled every 0.5 mm).
fn trace_deviation(
    trace: &[flatcut_firmware_sim::TraceSegment],
    d: &flatcut::pattern::Drawing,
    profile: &Profile,
) -> f64 {
    let strokes: Vec<Vec<DVec2>> = d
        .strokes
        .iter()
        .filter(|s| profile.layer(s.layer).enabled)
        .map(|s| {
            let mut p: Vec<DVec2> = s.points.iter().map(|q| profile.to_machine(*q)).collect();
            if s.closed && !p.is_empty() {
                p.push(p[0]);
            }
            p
        })
        .collect();
    let dist = |q: DVec2| {
        strokes
            .iter()
            .flat_map(|s| s.windows(2))
            .map(|w| {
                let ab = w[1] - w[0];
                let t = if ab.length_squared() > 0.0 {
                    ((q - w[0]).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                q.distance(w[0] + ab * t)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let mut worst: f64 = 0.0;
    for seg in trace.iter().filter(|s| s.tool_on && s.motion != "G0") {
        let (a, b) = (
            DVec2::new(seg.from[0], seg.from[1]),
            DVec2::new(seg.to[0], seg.to[1]),
        );
        if let Some(c) = seg.arc_center {
            // Arcs: sample along the circle.
            let c = DVec2::new(c[0], c[1]);
            let ccw = seg.motion == "G3";
            for q in flatcut::gcode::arcs::sample_arc(a, b, c, ccw, 0.05) {
                worst = worst.max(dist(q));
            }
        } else {
            let n = ((a.distance(b) / 0.5).ceil() as usize).max(1);
            for k in 0..=n {
                worst = worst.max(dist(a + (b - a) * (k as f64 / n as f64)));
            }
        }
    }
    worst
}
