//! `flatcut run PROJECT.toml`: the whole job in one command. The library runs the project's
//! stages (design → flatten → report → pattern → nest → G-code); this command renders their
//! events, writes the outputs into one folder, streams the jobs to the device (the embedded
//! simulator unless a port is given) and prints the summary.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context as _;
use flatcut::check::{CutSegment, blade_tip_deviation, trace_deviation};
use flatcut::geom::DVec2;
use flatcut::nest::Stock;
use flatcut::project::Project;
use flatcut::run::{Event, Observer, ProjectOutputs, RunOptions, Stage};

use super::common;
use super::device::{self, StreamArgs};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The project file (see patterns/README.md).
    pub project: PathBuf,
    /// Output folder (default: `out/<project name>`).
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
    #[arg(long, default_value_t = RunOptions::DEFAULT_NEST_ITERS, value_parser = crate::values::iterations)]
    pub nest_iters: usize,
    /// Largest difference between the two flat sides of a mating seam, or between a notch's
    /// offsets on them, in mm; beyond it the run counts as beyond its limits (exit code 3).
    #[arg(long, default_value_t = flatcut::report::DEFAULT_SEAM_TOLERANCE_MM, value_name = "MM", value_parser = crate::values::nonneg_mm)]
    pub seam_tolerance: f64,
    /// The material of pieces that name none, in place of the project's `[material]
    /// properties`: a bundled material (leather, woven-cotton, canvas, knit, carbon-prepreg,
    /// sailcloth) or a material file.
    #[arg(long, value_name = "NAME|FILE")]
    pub material: Option<String>,
    #[command(flatten)]
    pub stream: StreamArgs,
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let t0 = Instant::now();
    let mut proj = Project::load(&a.project)?;
    if let Some(m) = &a.material {
        proj.material.spec = Some(flatcut::design::material::MaterialSpec::load(m, None)?);
    }
    check_before_work(&proj, &a)?;
    let out = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(common::file_safe(&proj.name)));
    let mut opts = RunOptions::default()
        .with_nest_iters(a.nest_iters)
        .with_seam_tolerance_mm(a.seam_tolerance);
    // Ctrl-C stops the flattening, a split and the nesting at their cancel flag; nothing is
    // written then.
    let stop = crate::stop::Stoppable::register();
    let hooks = stop.hooks(opts.flatten_hooks.clone());
    opts = opts.with_flatten_hooks(hooks).with_cancel(stop.flag());
    let flatten_bar = (!a.stream.quiet).then(|| {
        let (hooks, bar) = common::progress_hooks(opts.flatten_hooks.clone(), 1);
        opts = opts.clone().with_flatten_hooks(hooks);
        bar
    });
    let mut log = StageLog::new(a.stream.quiet);
    log.bar = flatten_bar;
    let outputs = flatcut::run::run_project(&proj, &opts, &mut log);
    log.finish_bar();
    stop.check(|| format!("the run of {}", a.project.display()))?;
    drop(stop);
    let outputs = outputs?;
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    // All of the run's files land together or not at all (the simulator's traces come later).
    let mut set = crate::output::OutputSet::new();
    for f in &outputs.files {
        set.add(&out.join(&f.name), &f.bytes)?;
    }
    set.commit()?;
    // The project's [device] is the device (a --port on the command line wins).
    let mut stream = device::select::for_project(&proj.device, &outputs.profile, &a.stream);
    stream.force_laser = a.force;
    let a = Args { stream, ..a };
    let (stream_lines, exit) = send_stage(&a, &outputs, &out, &mut log)?;
    print_summary(&outputs, &stream_lines, &out, t0)?;
    Ok(exit)
}

/// Checks what can be checked before any work starts, so that a run that would fail at its
/// end fails before it writes anything: the design file is there, the machine profile loads,
/// and the device the jobs would stream to exists (a port) or can run (the simulator as the
/// profile's machine).
fn check_before_work(proj: &Project, a: &Args) -> anyhow::Result<()> {
    let design = proj.design_path();
    anyhow::ensure!(
        design.is_file(),
        "the project's design {} does not exist",
        design.display()
    );
    let profile = flatcut::gcode::Profile::resolve(&proj.profile_spec())
        .with_context(|| format!("the project's machine profile {}", proj.machine.profile))?;
    if a.no_send {
        return Ok(());
    }
    let stream = device::select::for_project(&proj.device, &profile, &a.stream);
    let target = stream.target()?;
    let checked = target.check();
    if let flatcut_device::Target::Port { path, .. } = &target {
        checked.with_context(|| format!("cannot open the serial port {path}"))?;
    } else {
        checked?;
    }
    Ok(())
}

/// Streams the jobs (all sheets to the simulator; the first, or all with `--all-sheets`, to a
/// machine), unless `--no-send` or the material limits forbid it. Returns one line per job.
fn send_stage(
    a: &Args,
    outputs: &ProjectOutputs,
    out: &Path,
    log: &mut StageLog,
) -> anyhow::Result<(Vec<String>, ExitCode)> {
    let started = |log: &mut StageLog, detail: &str| {
        log.event(&Event::Started {
            stage: Stage::Send,
            detail,
        })
    };
    if a.no_send {
        started(log, "skipped (--no-send)");
        let exit = if outputs.limits_exceeded() {
            ExitCode::from(crate::EXIT_LIMIT)
        } else {
            ExitCode::SUCCESS
        };
        return Ok((Vec::new(), exit));
    }
    if outputs.limits_exceeded() && !a.force {
        started(
            log,
            "skipped, the material limits or the seam tolerance are exceeded (see above; --force streams anyway)",
        );
        return Ok((Vec::new(), ExitCode::from(crate::EXIT_LIMIT)));
    }
    let jobs = &outputs.sheets;
    let to_send = if a.stream.uses_sim() || a.all_sheets {
        jobs.len()
    } else {
        1
    };
    started(
        log,
        &format!("{} job(s) to {}", to_send, a.stream.describe()),
    );
    let mut lines = Vec::new();
    for job in jobs.iter().take(to_send) {
        let mut sa = a.stream.clone();
        if sa.uses_sim() {
            let n = job.number;
            sa.sim_svg
                .get_or_insert_with(|| out.join(format!("sim-{n}.svg")));
            sa.sim_trace
                .get_or_insert_with(|| out.join(format!("sim-{n}.jsonl")));
            sa.sim_laser = outputs.profile.kind == flatcut::gcode::ToolKind::Laser;
        }
        // The job streams from memory; it is named after its file (`<file>.journal`).
        let path = out.join(&job.gcode_file);
        let text = outputs
            .files
            .iter()
            .find(|f| f.name == job.gcode_file)
            .map(|f| String::from_utf8_lossy(&f.bytes))
            .with_context(|| format!("the run wrote no {}", job.gcode_file))?;
        let o = device::stream_text(&text, &path.display().to_string(), &sa)?;
        let dev = match &o.sim_trace {
            Some(trace) => {
                let cut = cut_segments(trace);
                let axis = trace_deviation(&cut, &job.drawing, &outputs.profile);
                // A drag knife cuts with its blade tip, which trails the axis the trace
                // records by the blade offset: the tip is what lies on the pattern.
                match blade_tip_deviation(&cut, &job.drawing, &outputs.profile) {
                    Some(tip) => format!(
                        ", simulator traced {} segments, blade tip within {tip:.3} mm of the pattern (knife axis within {axis:.3} mm: it runs the blade offset ahead)",
                        trace.len()
                    ),
                    None => format!(
                        ", simulator traced {} segments, cut path within {axis:.3} mm of the pattern",
                        trace.len()
                    ),
                }
            }
            None => String::new(),
        };
        lines.push(format!(
            "sheet {} on {}: {} lines streamed in {:.1} s, link {:.0}% busy{}",
            job.number,
            o.device,
            o.report.lines_sent,
            o.report.total_time.as_secs_f64(),
            o.link_utilisation() * 100.0,
            dev
        ));
    }
    if to_send < jobs.len() {
        lines.push(format!(
            "{} more sheet(s): load the next sheet, then `flatcut send {}/job-N.gcode --port …`",
            jobs.len() - to_send,
            out.display()
        ));
    }
    Ok((lines, ExitCode::SUCCESS))
}

/// The simulator's tool-on cutting motions, in machine mm.
fn cut_segments(trace: &[flatcut_device::sim::TraceSegment]) -> Vec<CutSegment> {
    trace
        .iter()
        .filter(|s| s.tool_on && s.motion != "G0")
        .map(|s| CutSegment {
            from: DVec2::new(s.from[0], s.from[1]),
            to: DVec2::new(s.to[0], s.to[1]),
            arc: s
                .arc_center
                .map(|c| (DVec2::new(c[0], c[1]), s.motion == "G3")),
        })
        .collect()
}

fn print_summary(
    o: &ProjectOutputs,
    stream_lines: &[String],
    out: &Path,
    t0: Instant,
) -> anyhow::Result<()> {
    crate::outln!();
    crate::outln!(
        "{:<20} {:>4} {:>12} {:>10} {:>10} {:>10}",
        "piece",
        "qty",
        "area mm²",
        "δ2 mean",
        "stretch%",
        "compr.%"
    );
    for p in &o.summary.pieces {
        let qty = if p.mirrored > 0 {
            format!("{}+{}", p.quantity, p.mirrored)
        } else {
            p.quantity.to_string()
        };
        crate::outln!(
            "{:<20} {:>4} {:>12.0} {:>10.5} {:>10.2} {:>10.2}",
            p.name,
            qty,
            p.area_mm2,
            p.delta2_mean,
            p.stretch_max_pct,
            p.compress_max_pct
        );
    }
    for m in &o.summary.mating_seams {
        crate::outln!(
            "seam {:<15} {} / {}: flat {:.2} / {:.2} mm (3D {:.2}), mismatch {:.3} mm",
            m.name,
            m.pieces[0],
            m.pieces[1],
            m.length_2d_mm[0],
            m.length_2d_mm[1],
            m.length_3d_mm,
            m.worst_mm()
        );
    }
    let s = &o.summary;
    crate::outln!();
    match o.stock {
        Stock::Sheets { width, height, .. } => crate::outln!(
            "nesting      {} sheet(s) {width:.0}×{height:.0} mm, utilization {:.1}%",
            s.sheets,
            s.utilization_pct
        ),
        Stock::Roll { width, .. } => crate::outln!(
            "nesting      roll {width:.0} mm, length {:.0} mm, utilization {:.1}%",
            o.layout.result.length,
            s.utilization_pct
        ),
    }
    crate::outln!(
        "G-code       {} lines, cut {:.0} mm, travel {:.0} mm, estimated {}",
        s.gcode_lines,
        s.cut_length_mm,
        s.travel_length_mm,
        super::gcode::hms(s.est_time_s)
    );
    crate::outln!("labels       {}", s.labels);
    for (code, name) in &s.label_codes {
        crate::outln!("             {code} = {name}");
    }
    for l in stream_lines {
        crate::outln!("stream       {l}");
    }
    crate::outln!("outputs      {}", out.display());
    crate::outln!("run time     {:.1} s", t0.elapsed().as_secs_f64());
    Ok(())
}

/// Renders a run's events on stderr: a numbered line per stage, warnings always, progress lines
/// and the nesting bar unless quiet.
struct StageLog {
    quiet: bool,
    bar: Option<indicatif::ProgressBar>,
}

impl StageLog {
    fn new(quiet: bool) -> Self {
        Self { quiet, bar: None }
    }

    fn finish_bar(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}

impl Observer for StageLog {
    fn event(&mut self, e: &Event<'_>) {
        match *e {
            Event::Started { stage, detail } => {
                if !self.quiet {
                    let sep = if detail.is_empty() { "" } else { ": " };
                    let sep = if stage == Stage::Flatten { " " } else { sep };
                    eprintln!(
                        "[{}/{}] {}{sep}{detail}",
                        stage.number(),
                        Stage::ALL.len(),
                        stage.name()
                    );
                }
            }
            Event::Progress {
                stage: Stage::Flatten,
                done,
                total,
                what,
            } if !self.quiet => {
                let line = format!("flattening piece {}/{} '{}'", done + 1, total, what);
                match &self.bar {
                    Some(b) => b.suspend(|| eprintln!("{line}")),
                    None => eprintln!("{line}"),
                }
            }
            Event::Progress {
                stage: Stage::Nest,
                done,
                total,
                ..
            } if !self.quiet => {
                let bar = self.bar.get_or_insert_with(|| {
                    let b = indicatif::ProgressBar::new(total as u64);
                    b.set_style(
                        indicatif::ProgressStyle::with_template("nesting {bar:30} {pos}/{len}")
                            .expect("valid template"),
                    );
                    b
                });
                bar.set_position(done as u64);
            }
            Event::Progress { .. } => {}
            Event::Warning { message, .. } => {
                if let Some(b) = &self.bar {
                    b.suspend(|| eprintln!("  {message}"));
                } else {
                    eprintln!("  {message}");
                }
            }
            Event::Finished { .. } => self.finish_bar(),
        }
    }
}
