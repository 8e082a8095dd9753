//! Running a project: design → flatten → report → pattern → nest → G-code, as named stages that
//! tell an [`Observer`] what they do and return every output as a value. The caller writes the
//! files (as one set) and streams the jobs to its device.
//!
//! The bundled lampshade (a cone, which unrolls exactly) run through every stage:
//!
//! ```
//! use flatcut::project::Project;
//! use flatcut::run::{run_project, RunOptions, Silent};
//!
//! let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
//!     .join("../../patterns/lampshade/project.toml");
//! let project = Project::load(&path)?;
//! let out = run_project(&project, &RunOptions::default().with_nest_iters(5), &mut Silent)?;
//! // Every output comes back as a value: the caller writes them (as one set).
//! let names: Vec<&str> = out.files.iter().map(|f| f.name.as_str()).collect();
//! assert!(names.contains(&"pattern.svg") && names.contains(&"job-1.gcode"), "{names:?}");
//! // A developable piece flattens without distortion, and everything is placed.
//! assert!(out.flats.iter().all(|f| f.report.delta2_max < 1e-6));
//! assert_eq!(out.summary.unplaced, 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod events;
mod outputs;

use std::time::Instant;

use flatcut_flatten::{FlattenHooks, FlattenParams, Method};
use flatcut_gcode::{GcodeOptions, Profile};
use flatcut_geom::{DVec2, Tolerances};
use flatcut_nest::{NestOptions, Stock};
use flatcut_pattern::Piece;
use flatcut_pattern::dxf::DxfLayers;
use flatcut_report::{Measure, Region};

pub use events::{Event, Observer, Silent, Stage};
pub use outputs::{OutputFile, PieceSummary, ProjectOutputs, RunSummary, SheetJob};

use crate::flat::{self, Flat, Limits};
use crate::pieces::{self, PieceSettings};
use crate::pipeline::{self, Layout, NestGroup, PipelineError};
use crate::project::Project;

/// How a project is run beyond what the project file says.
#[derive(Clone)]
pub struct RunOptions {
    /// Nesting iterations.
    pub nest_iters: usize,
    /// Chordal tolerance of the tessellation (mm).
    pub chord_mm: f64,
    /// Largest difference between the two sides of a mating seam, or between a notch's offsets
    /// on them (mm), before the run counts as beyond its limits.
    pub seam_tolerance_mm: f64,
    /// Progress callback and cancel flag handed to every piece's flattening.
    pub flatten_hooks: FlattenHooks,
    /// Set from another thread to stop the nesting (the best layout so far is returned; the
    /// caller that set it writes nothing).
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl RunOptions {
    /// Nesting iterations by default.
    pub const DEFAULT_NEST_ITERS: usize = 60;
    /// A project tessellates more coarsely than a single `flatten`: the pieces of a whole part
    /// are cut together, and 0.4 mm is below a knife's or a pen's width.
    pub const DEFAULT_CHORD_MM: f64 = Tolerances::DEFAULT_CHORD_MM * 4.0;

    /// These options with `n` nesting iterations.
    pub fn with_nest_iters(mut self, n: usize) -> Self {
        self.nest_iters = n;
        self
    }

    /// These options with a seam tolerance of `mm`.
    pub fn with_seam_tolerance_mm(mut self, mm: f64) -> Self {
        self.seam_tolerance_mm = mm;
        self
    }

    /// These options with the flattening's progress callback and cancel flag.
    pub fn with_flatten_hooks(mut self, hooks: FlattenHooks) -> Self {
        self.flatten_hooks = hooks;
        self
    }

    /// The nesting stops once `flag` is set ([`RunOptions::cancel`]).
    pub fn with_cancel(mut self, flag: std::sync::Arc<std::sync::atomic::AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            nest_iters: Self::DEFAULT_NEST_ITERS,
            chord_mm: Self::DEFAULT_CHORD_MM,
            seam_tolerance_mm: flatcut_report::DEFAULT_SEAM_TOLERANCE_MM,
            flatten_hooks: FlattenHooks::default(),
            cancel: None,
        }
    }
}

/// Why a project run stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    #[error(transparent)]
    /// A pipeline stage failed.
    Pipeline(#[from] PipelineError),
    #[error("project '{project}': {message}")]
    /// The project's settings do not allow the run.
    Project {
        /// The project's name.
        project: String,
        /// What is wrong.
        message: String,
    },
    #[error("machine profile: {0}")]
    /// The machine profile cannot be used.
    Profile(#[from] flatcut_gcode::ProfileError),
    #[error("heat map: {0}")]
    /// The heat map could not be rendered.
    Render(#[from] flatcut_report::ReportError),
    #[error("sheet {sheet}: {source}")]
    /// A sheet's job could not be planned.
    Gcode {
        /// The sheet's 1-based number.
        sheet: usize,
        /// Why the plan failed.
        source: flatcut_gcode::GcodeError,
    },
}

/// Runs every stage but streaming. Events go to `obs`; the outputs come back as values.
pub fn run_project(
    project: &Project,
    opts: &RunOptions,
    obs: &mut dyn Observer,
) -> Result<ProjectOutputs, RunError> {
    let flats = flatten_project(project, None, opts, obs)?;
    finish_project(project, flats, opts, obs)
}

/// The flatten stage of [`run_project`] alone: every piece flattened within the project's
/// limits and reported. `design`: the project's design as edited in memory, in place of its
/// file (mesh and STEP files it names still resolve against the file's directory).
pub fn flatten_project(
    project: &Project,
    design: Option<&flatcut_design::Design>,
    opts: &RunOptions,
    obs: &mut dyn Observer,
) -> Result<Vec<Flat>, RunError> {
    check_order(project, design)?;
    timed(obs, Stage::Flatten, &flatten_detail(project)?, |obs| {
        flatten_stage(project, design, opts, obs)
    })
}

/// Every stage of [`run_project`] after the flattening, on pieces [`flatten_project`] gave.
pub fn finish_project(
    project: &Project,
    flats: Vec<Flat>,
    opts: &RunOptions,
    obs: &mut dyn Observer,
) -> Result<ProjectOutputs, RunError> {
    let mut files: Vec<OutputFile> = flats
        .iter()
        .map(|f| OutputFile {
            name: format!("{}.obj", file_safe(&f.name)),
            bytes: f.obj().into_bytes(),
        })
        .collect();
    let limits_exceeded = timed(obs, Stage::Report, "", |obs| {
        report_stage(&flats, opts, obs, &mut files)
    })?;
    let pieces = timed(obs, Stage::Pattern, "", |obs| {
        pattern_stage(project, &flats, obs, &mut files)
    })?;
    let (layout, stock) = timed(obs, Stage::Nest, "", |obs| {
        nest_stage(project, &pieces, opts, obs)
    })?;
    let (profile, sheets) = timed(obs, Stage::Gcode, "", |_| {
        gcode_stage(project, &layout, stock, &mut files)
    })?;
    let summary = summarise(
        project,
        &flats,
        &pieces,
        &layout,
        (&profile, &sheets),
        limits_exceeded,
    );
    files.push(OutputFile {
        name: "summary.json".into(),
        bytes: json(&summary),
    });
    Ok(ProjectOutputs {
        flats,
        pieces,
        layout,
        stock,
        profile,
        sheets,
        summary,
        files,
    })
}

/// Runs one stage between its Started and Finished events.
fn timed<T>(
    obs: &mut dyn Observer,
    stage: Stage,
    detail: &str,
    f: impl FnOnce(&mut dyn Observer) -> Result<T, RunError>,
) -> Result<T, RunError> {
    obs.event(&Event::Started { stage, detail });
    let t0 = Instant::now();
    let out = f(obs)?;
    obs.event(&Event::Finished {
        stage,
        elapsed: t0.elapsed(),
    });
    Ok(out)
}

/// Refuses an `[order]` that names a size the design's grading does not have, or any size of a
/// design without grading, before anything is flattened.
fn check_order(project: &Project, design: Option<&flatcut_design::Design>) -> Result<(), RunError> {
    let Some(order) = &project.order else {
        return Ok(());
    };
    let path = project.design_path();
    let loaded;
    let design = match design {
        Some(d) => d,
        None => {
            loaded = flatcut_design::Design::load(&path).map_err(PipelineError::from)?;
            &loaded
        }
    };
    let sizes: Vec<&str> = design
        .grading
        .as_ref()
        .map(|g| g.sizes.iter().map(|z| z.name.as_str()).collect())
        .unwrap_or_default();
    for size in order.keys() {
        if !sizes.contains(&size.as_str()) {
            return Err(RunError::Project {
                project: project.name.clone(),
                message: if sizes.is_empty() {
                    format!(
                        "[order] names size '{size}', but {} has no [grading]",
                        path.display()
                    )
                } else {
                    format!(
                        "[order] names size '{size}', which the grading of {} has not (its sizes: {})",
                        path.display(),
                        sizes.join(", ")
                    )
                },
            });
        }
    }
    Ok(())
}

fn method(project: &Project) -> Result<Method, RunError> {
    match project.method.as_deref() {
        None => Ok(Method::Isometric),
        Some(m) => Method::from_name(m).ok_or_else(|| RunError::Project {
            project: project.name.clone(),
            message: format!("unknown flattening method '{m}'"),
        }),
    }
}

fn flatten_detail(project: &Project) -> Result<String, RunError> {
    Ok(format!(
        "{} ({})",
        project.design_path().display(),
        method(project)?
    ))
}

fn limits(project: &Project) -> Limits {
    Limits {
        stretch_pct: project.material.max_stretch_pct,
        compress_pct: project.material.max_compress_pct,
        darts: (project.darts == Some(flatcut_design::DartsDef::Auto))
            .then(crate::darting::DartSettings::default),
        split: (project.split == Some(flatcut_design::DartsDef::Auto)).then(|| {
            crate::splitting::SplitSettings {
                seam_allowance_mm: project.seam_mm.unwrap_or(0.0),
                // Checked when the project was loaded.
                symmetry: project.symmetry_settings().unwrap_or_default(),
                despike_max_mm: project.despike_max_mm().unwrap_or_default(),
                ..Default::default()
            }
        }),
        material: project.material.spec.clone(),
    }
}

/// Flattens every piece of the design (its file, or `design` in its place).
fn flatten_stage(
    project: &Project,
    design: Option<&flatcut_design::Design>,
    opts: &RunOptions,
    obs: &mut dyn Observer,
) -> Result<Vec<Flat>, RunError> {
    let m = method(project)?;
    let params = FlattenParams::new(m)
        .with_max_stretch_pct(project.material.max_stretch_pct)
        .with_max_compress_pct(project.material.max_compress_pct)
        .with_hooks(opts.flatten_hooks.clone());
    let tol = Tolerances::DEFAULT.with_chord_mm(opts.chord_mm);
    let mut progress = |name: &str, k, n| {
        obs.event(&Event::Progress {
            stage: Stage::Flatten,
            done: k,
            total: n,
            what: name,
        })
    };
    let path = project.design_path();
    let flats = match design {
        Some(d) => flat::flatten_and_report_loaded(
            d.clone(),
            path.parent().unwrap_or(std::path::Path::new(".")),
            &tol,
            &params,
            limits(project),
            &mut progress,
        )?,
        None => flat::load_flat(&path, &tol, &params, limits(project), &mut progress)?,
    };
    for f in &flats {
        if let Some(info) = &f.info {
            for w in &info.warnings {
                obs.event(&Event::Warning {
                    stage: Stage::Flatten,
                    message: &format!("piece '{}': {w}", f.name),
                });
            }
        }
    }
    Ok(flats)
}

/// Most regions beyond the limits reported per piece as warnings (all are in the report).
const WARNED_REGIONS: usize = 5;

/// Distortion report: JSON, heat map (SVG, PNG) and the HTML page; returns one line per region
/// beyond the material limits and per mating seam whose sides differ beyond the tolerance.
fn report_stage(
    flats: &[Flat],
    opts: &RunOptions,
    obs: &mut dyn Observer,
    files: &mut Vec<OutputFile>,
) -> Result<Vec<String>, RunError> {
    let reports: Vec<_> = flats.iter().map(|f| &f.report).collect();
    files.push(OutputFile {
        name: "report.json".into(),
        bytes: json(&reports),
    });
    let cols = flat::columns(flats);
    let heat = flatcut_report::heatmap_svg(&cols, Measure::Stretch, false);
    let png = flatcut_report::render_png(&heat, None)?;
    files.push(OutputFile {
        name: "heatmap.svg".into(),
        bytes: heat.into_bytes(),
    });
    files.push(OutputFile {
        name: "heatmap.png".into(),
        bytes: png,
    });
    files.push(OutputFile {
        name: "report.html".into(),
        bytes: flatcut_report::html_report(&cols, Measure::Stretch, false).into_bytes(),
    });
    let mut over = Vec::new();
    for f in flats {
        for (k, r) in f.report.regions.iter().enumerate() {
            let line = region_line(&f.name, r);
            if k < WARNED_REGIONS {
                obs.event(&Event::Warning {
                    stage: Stage::Report,
                    message: &format!("material limit exceeded: {line}"),
                });
            }
            over.push(line);
        }
        if f.report.regions.len() > WARNED_REGIONS {
            obs.event(&Event::Warning {
                stage: Stage::Report,
                message: &format!(
                    "… and {} more region(s) of '{}' (see report.html)",
                    f.report.regions.len() - WARNED_REGIONS,
                    f.name
                ),
            });
        }
    }
    for line in flat::materials_over(flats)
        .into_iter()
        .chain(flat::seams_over(flats, opts.seam_tolerance_mm))
        .chain(crate::sanity::insane(flats).iter().map(ToString::to_string))
    {
        obs.event(&Event::Warning {
            stage: Stage::Report,
            message: &line,
        });
        over.push(line);
    }
    Ok(over)
}

fn region_line(piece: &str, r: &Region) -> String {
    format!(
        "{piece}: {} {:.2}% over {:.0} mm², worst at ({:.0}, {:.0}, {:.0}) on the surface",
        r.kind, r.worst_pct, r.area_mm2, r.worst_at_3d[0], r.worst_at_3d[1], r.worst_at_3d[2]
    )
}

/// Pattern pieces, laid out in a row per size (`pattern.svg`, `pattern.dxf`), and for a graded
/// design the graded nest of every piece (`graded-<piece>.svg`); a warning for every piece
/// whose label could not be written at a readable height.
fn pattern_stage(
    project: &Project,
    flats: &[Flat],
    obs: &mut dyn Observer,
    files: &mut Vec<OutputFile>,
) -> Result<Vec<Piece>, RunError> {
    let settings = PieceSettings {
        seam_mm: project.seam_mm,
        ..PieceSettings::default()
    };
    let pieces = pieces::build_pieces(flats, &settings)?;
    for p in &pieces {
        if p.label_height < flatcut_pattern::MIN_LABEL_HEIGHT - 1e-9 {
            obs.event(&Event::Warning {
                stage: Stage::Pattern,
                message: &format!(
                    "piece '{}': its label ({}) is written {:.1} mm high, below the {} mm a cutter reads: the piece has no room for more",
                    p.name,
                    p.label_text.join(" / "),
                    p.label_height,
                    flatcut_pattern::MIN_LABEL_HEIGHT
                ),
            });
        }
    }
    let placed = pieces::row_layout(&pieces);
    files.push(OutputFile {
        name: "pattern.svg".into(),
        bytes: flatcut_pattern::svg::write_pieces(&placed, None).into_bytes(),
    });
    files.push(OutputFile {
        name: "pattern.dxf".into(),
        bytes: flatcut_pattern::dxf::write_pieces(
            &placed,
            DxfLayers::Aama,
            flatcut_pattern::PieceOptions::DEFAULT_CHORD_TOL,
        )
        .into_bytes(),
    });
    for (name, sizes) in pieces::graded_sets(flats, &pieces) {
        let sizes: Vec<(&str, &Piece)> = sizes.iter().map(|(s, p)| (s.as_str(), *p)).collect();
        files.push(OutputFile {
            name: format!("graded-{}.svg", file_safe(&name)),
            bytes: flatcut_pattern::graded::graded_svg(&name, &sizes).into_bytes(),
        });
    }
    Ok(pieces)
}

/// The project's stock: sheets of a size, or a roll.
pub fn stock(project: &Project) -> Result<Stock, RunError> {
    let s = &project.sheet;
    match (s.width_mm, s.height_mm, s.roll_width_mm) {
        (Some(width), Some(height), None) => Ok(Stock::Sheets {
            width,
            height,
            max_sheets: None,
        }),
        (None, None, Some(width)) => Ok(Stock::Roll {
            width,
            max_length: None,
        }),
        _ => Err(RunError::Project {
            project: project.name.clone(),
            message: "[sheet] needs width_mm and height_mm, or roll_width_mm".into(),
        }),
    }
}

/// How many of a pattern piece the job cuts: its label's quantity (per set), times the sets
/// the project's `[order]` asks of its size.
fn cut_count(project: &Project, p: &Piece) -> usize {
    let per_set = p.label.quantity as usize;
    match &project.order {
        Some(order) => per_set * order.get(&p.label.size).copied().unwrap_or(0) as usize,
        None => per_set,
    }
}

/// Nests every piece (both sides of a pair), as many times as its label says (times its size's
/// `[order]`), on the project's stock.
fn nest_stage(
    project: &Project,
    pieces: &[Piece],
    opts: &RunOptions,
    obs: &mut dyn Observer,
) -> Result<(Layout, Stock), RunError> {
    let stock = stock(project)?;
    let groups: Vec<NestGroup> = pieces
        .iter()
        .filter_map(|p| {
            let n = cut_count(project, p);
            (n > 0).then(|| {
                let mut g = NestGroup::from_piece(p, n, false);
                // The nesting keeps a grain line along the material's grain by the material's
                // rule (one way, either way, or not at all) within its tolerance, mirrored
                // copies too.
                g.grain_directions = project.material.grain_rule();
                g.grain_tolerance_deg = project.material.grain_tolerance();
                g
            })
        })
        .collect();
    let mut nopts = NestOptions::DEFAULT
        .with_spacing(project.sheet.spacing_mm)
        .with_max_iters(opts.nest_iters);
    if let Some(flag) = &opts.cancel {
        nopts = nopts.with_cancel(flag.clone());
    }
    let layout = pipeline::nest_groups(&groups, stock, &nopts, &mut |p| {
        obs.event(&Event::Progress {
            stage: Stage::Nest,
            done: p.iteration,
            total: opts.nest_iters,
            what: "",
        })
    })?;
    for u in &layout.result.unplaced {
        obs.event(&Event::Warning {
            stage: Stage::Nest,
            message: &format!("unplaced: {} copy {}: {}", u.name, u.copy, u.reason),
        });
    }
    Ok((layout, stock))
}

/// One G-code job per sheet (`job-N.gcode`, `job-N-frame.gcode`) with the sheet's layout
/// (`layout-N.svg`, `layout-N.dxf`).
fn gcode_stage(
    project: &Project,
    layout: &Layout,
    stock: Stock,
    files: &mut Vec<OutputFile>,
) -> Result<(Profile, Vec<SheetJob>), RunError> {
    let profile = Profile::resolve(&project.profile_spec())?;
    let sheet_size = match stock {
        Stock::Sheets { width, height, .. } => DVec2::new(width, height),
        Stock::Roll { width, .. } => DVec2::new(layout.result.length.max(1.0), width),
    };
    let mut jobs = Vec::new();
    for (k, d) in layout.sheets.iter().enumerate() {
        let n = k + 1;
        files.push(OutputFile {
            name: format!("layout-{n}.svg"),
            bytes: flatcut_pattern::svg::write_drawing(d, Some(sheet_size)).into_bytes(),
        });
        files.push(OutputFile {
            name: format!("layout-{n}.dxf"),
            bytes: flatcut_pattern::dxf::write_drawing(d, DxfLayers::Aama).into_bytes(),
        });
        let mut go = GcodeOptions::default();
        go.title = format!("flatcut {} sheet {n}", project.name);
        let plan = flatcut_gcode::plan(d, &profile, &go)
            .map_err(|source| RunError::Gcode { sheet: n, source })?;
        let gcode_file = format!("job-{n}.gcode");
        files.push(OutputFile {
            name: gcode_file.clone(),
            bytes: plan.to_gcode().into_bytes(),
        });
        files.push(OutputFile {
            name: format!("job-{n}-frame.gcode"),
            bytes: flatcut_gcode::frame_job(plan.bbox(), &profile).into_bytes(),
        });
        jobs.push(SheetJob {
            number: n,
            drawing: d.clone(),
            gcode_file,
            summary: plan.summary(),
        });
    }
    Ok((profile, jobs))
}

fn summarise(
    project: &Project,
    flats: &[Flat],
    pieces: &[Piece],
    layout: &Layout,
    (profile, sheets): (&flatcut_gcode::Profile, &[SheetJob]),
    limits_exceeded: Vec<String>,
) -> RunSummary {
    let r = &layout.result;
    let mut all = flatcut_pattern::Drawing::default();
    for s in sheets {
        all.strokes.extend(s.drawing.strokes.iter().cloned());
    }
    RunSummary {
        cut_length_mm: sheets.iter().map(|s| s.summary.cut_length_mm).sum(),
        est_time_s: sheets.iter().map(|s| s.summary.est_time_s).sum(),
        gcode_lines: sheets.iter().map(|s| s.summary.lines).sum(),
        label_codes: pieces
            .iter()
            .filter(|p| p.label_text.len() == 1 && p.label_text[0] == p.label_code())
            .map(|p| (p.label_code(), p.name.clone()))
            .collect(),
        labels: flatcut_gcode::Marking::of(profile, &all).note(&profile.name),
        limits_exceeded,
        mating_seams: flat::mating_seams(flats),
        pieces: flats
            .iter()
            .map(|f| PieceSummary {
                area_mm2: f.report.area_3d_mm2,
                compress_max_pct: f.report.compress_max_pct,
                delta2_mean: f.report.delta2_mean,
                despike: f.despike.clone(),
                name: f.name.clone(),
                mirrored: f.mirrored,
                quantity: f.quantity,
                stretch_max_pct: f.report.stretch_max_pct,
            })
            .collect(),
        project: project.name.clone(),
        sheets: r.sheets,
        travel_length_mm: sheets.iter().map(|s| s.summary.travel_length_mm).sum(),
        unplaced: r.unplaced.len(),
        utilization_pct: r.utilization,
    }
}

/// Pretty JSON; serialising these plain structs cannot fail (non-finite numbers become null).
fn json<T: serde::Serialize + ?Sized>(v: &T) -> Vec<u8> {
    serde_json::to_vec_pretty(v).unwrap_or_default()
}

/// A name usable in a file name: ASCII letters, digits, `-` and `_`; anything else becomes `_`.
pub fn file_safe(name: &str) -> String {
    flatcut_pattern::safe_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `darts` and `split` in a project reach the flattening's limits; absent, neither is asked.
    #[test]
    fn a_projects_darts_and_split_reach_the_flattening() {
        let dir = tempfile::tempdir().unwrap();
        let write = |extra: &str| {
            let p = dir.path().join("project.toml");
            std::fs::write(
                &p,
                format!(
                    "name = \"t\"\ndesign = \"d.toml\"\n{extra}[material]\nname = \"m\"\nmax_stretch_pct = 3.0\nmax_compress_pct = 3.0\n[sheet]\nwidth_mm = 600.0\nheight_mm = 400.0\n[machine]\nprofile = \"pen\"\n"
                ),
            )
            .unwrap();
            Project::load(&p).unwrap()
        };
        let l = limits(&write("darts = \"auto\"\nsplit = \"auto\"\n"));
        assert_eq!(l.darts, Some(crate::darting::DartSettings::default()));
        assert_eq!(l.split, Some(crate::splitting::SplitSettings::default()));
        let l = limits(&write(""));
        assert!(l.darts.is_none() && l.split.is_none());
        assert_eq!((l.stretch_pct, l.compress_pct), (Some(3.0), Some(3.0)));
    }

    /// `symmetry`, `symmetry_tolerance_pct` and `symmetry_plane` reach the split as the flags
    /// do; an unknown mode, a plane that is none, both a mode and a plane, or either without
    /// `split = "auto"` are refused naming the file, the key and the value.
    #[test]
    fn a_projects_symmetry_reaches_the_split_and_bad_values_are_refused() {
        use crate::splitting::SymmetryMode;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("project.toml");
        let load = |extra: &str| {
            std::fs::write(
                &p,
                format!(
                    "name = \"t\"\ndesign = \"d.obj\"\n{extra}[material]\nname = \"m\"\nmax_stretch_pct = 3.0\n[sheet]\nwidth_mm = 600.0\nheight_mm = 400.0\n[machine]\nprofile = \"pen\"\n"
                ),
            )
            .unwrap();
            Project::load(&p)
        };
        let symmetry = |extra: &str| limits(&load(extra).unwrap()).split.unwrap().symmetry;
        let s = symmetry("split = \"auto\"\n");
        assert_eq!(s, crate::splitting::SymmetrySettings::default());
        let s = symmetry("split = \"auto\"\nsymmetry = \"y\"\nsymmetry_tolerance_pct = 2.5\n");
        assert_eq!(s.mode, SymmetryMode::Axis(flatcut_geom::DVec3::Y));
        assert!((s.tolerance - 0.025).abs() < 1e-15);
        assert_eq!(
            symmetry("split = \"auto\"\nsymmetry = \"auto\"\n").mode,
            SymmetryMode::Auto
        );
        let s = symmetry("split = \"auto\"\nsymmetry_plane = [10, 0, 5, 0, 0, -2]\n");
        let SymmetryMode::Plane(plane) = s.mode else {
            panic!("{s:?}")
        };
        assert_eq!(plane.point, flatcut_geom::DVec3::new(10.0, 0.0, 5.0));
        assert_eq!(plane.normal, -flatcut_geom::DVec3::Z);
        for (extra, said) in [
            ("split = \"auto\"\nsymmetry = \"w\"\n", "symmetry = \"w\""),
            (
                "split = \"auto\"\nsymmetry_plane = [0, 0, 0, 0, 0, 0]\n",
                "symmetry_plane = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]: the normal (0, 0, 0) has no direction",
            ),
            (
                "split = \"auto\"\nsymmetry_plane = [0, 0, nan, 1, 0, 0]\n",
                "symmetry_plane = [0.0, 0.0, NaN, 1.0, 0.0, 0.0]: NaN is not a finite number",
            ),
            (
                "split = \"auto\"\nsymmetry = \"x\"\nsymmetry_plane = [0, 0, 0, 1, 0, 0]\n",
                "symmetry = \"x\" and symmetry_plane",
            ),
            (
                "split = \"auto\"\nsymmetry_tolerance_pct = 100.0\n",
                "symmetry_tolerance_pct = 100",
            ),
            ("symmetry = \"auto\"\n", "need split = \"auto\""),
        ] {
            let e = load(extra).unwrap_err().to_string();
            assert!(
                e.starts_with(&p.display().to_string()) && e.contains(said),
                "{extra}: {e}"
            );
        }
        // Off is no request: harmless without a split.
        assert!(load("symmetry = \"off\"\n").is_ok());
    }

    /// A darted piece's OBJ from a run carries its darts' sew lines, as `flatten` writes it, and
    /// reads back with the same darts (`run` once wrote the mesh alone).
    #[test]
    fn a_run_writes_a_darted_pieces_obj_with_its_darts() {
        let dir = tempfile::tempdir().unwrap();
        let cap = flatcut_flatten::testmesh::spherical_cap(100.0, 0.8, 12);
        std::fs::write(
            dir.path().join("cap.obj"),
            flatcut_mesh::io::obj_string(&cap),
        )
        .unwrap();
        let path = dir.path().join("project.toml");
        std::fs::write(
            &path,
            "name = \"t\"\ndesign = \"cap.obj\"\ndarts = \"auto\"\n[material]\nname = \"m\"\nmax_stretch_pct = 5.0\nmax_compress_pct = 2.0\n[sheet]\nwidth_mm = 600.0\nheight_mm = 400.0\n[machine]\nprofile = \"pen\"\n",
        )
        .unwrap();
        let project = Project::load(&path).unwrap();
        let opts = RunOptions::default().with_nest_iters(1);
        let out = run_project(&project, &opts, &mut Silent).unwrap();
        let f = &out.flats[0];
        assert!(!f.darts.is_empty(), "the cap needs darts at 5 % / 2 %");
        let file = out.files.iter().find(|o| o.name == "cap.obj").unwrap();
        assert_eq!(file.bytes, f.obj().into_bytes());
        let text = String::from_utf8(file.bytes.clone()).unwrap();
        assert_eq!(text.matches("\ng dart-").count(), f.darts.len());
        let written = dir.path().join("flat.obj");
        std::fs::write(&written, &text).unwrap();
        let back = crate::flat::read_flat_mesh(&written, &Limits::default())
            .unwrap()
            .unwrap();
        assert_eq!(back.darts.len(), f.darts.len());
        for (a, b) in back.darts.iter().zip(&f.darts) {
            assert_eq!(a.legs.sides, b.legs.sides);
            // Measured again from the OBJ's printed coordinates.
            assert!((a.length_3d_mm - b.length_3d_mm).abs() < 1e-4);
        }
    }
}
