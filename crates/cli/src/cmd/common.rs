//! What several commands share: loading designs or flattened meshes as pattern pieces, laying
//! pieces out in a row, parsing sizes, writing files whole.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use flatcut::darting::{DartFit, DartSettings};
use flatcut::design::material::MaterialSpec;
use flatcut::flat::Limits;
use flatcut::flatten::{FlattenHooks, FlattenParams, FlattenProgress, Method};
use flatcut::geom::Tolerances;
use flatcut::pattern::{CornerStyle, NotchStyle, Piece, PieceOptions};
use flatcut::pieces::PieceSettings;
use flatcut::splitting::{SplitSettings, SymmetryMode, SymmetrySettings};

use crate::values;

/// Flattening options shared by the commands that flatten.
#[derive(Debug, Clone, clap::Args)]
pub struct FlattenArgs {
    /// Flattening method: isometric, conformal, lscm, conformal-boundary, arap, developable, minmax, boundary-isometric, orthotropic (needs --material; chosen by it).
    #[arg(long, default_value = "isometric", value_parser = parse_method)]
    pub method: Method,
    /// Largest allowed stretch in percent (principal stretch).
    #[arg(long, value_name = "P", value_parser = values::material_percent)]
    pub max_stretch: Option<f64>,
    /// Largest allowed compression in percent (leather: 0).
    #[arg(long, value_name = "P", value_parser = values::material_percent)]
    pub max_compress: Option<f64>,
    /// Chordal tolerance of the tessellation in mm.
    #[arg(long, default_value_t = Tolerances::DEFAULT_CHORD_MM, value_name = "MM", value_parser = values::positive_mm)]
    pub chord: f64,
    /// The largest defect of a STEP model healed, in mm (gaps between edges, edges off their
    /// faces); beyond it the file is refused [default: 0.2 % of the model's size].
    #[arg(long, value_name = "MM", value_parser = values::positive_mm)]
    pub heal_tolerance: Option<f64>,
    /// Iteration cap of every stage of a piece's flattening, over all the solves of the stage:
    /// the method's own solve (minmax, boundary-isometric and orthotropic: their start and their
    /// descent, two stages), the material limits, the joint solve of pieces sewn together
    /// (seams), the darts, the split. Each stage's count is printed; a piece takes at most N
    /// times its stages [default: 200; minmax's descent: 1000; the limits and the darts: 2000;
    /// the split: 100,000].
    #[arg(long, value_name = "N", value_parser = values::iterations)]
    pub max_iters: Option<usize>,
    /// Time limit of every stage of a piece's flattening (the stages of --max-iters) in
    /// seconds: when it runs out, the stage keeps the best flip-free map found so far, with a
    /// warning.
    #[arg(long, value_name = "S", value_parser = values::seconds)]
    pub flatten_time: Option<std::time::Duration>,
    /// Largest difference between the two flat sides of a mating seam, or between a notch's
    /// offsets on them, in mm; beyond it the command exits with code 3.
    #[arg(long, default_value_t = flatcut::report::DEFAULT_SEAM_TOLERANCE_MM, value_name = "MM", value_parser = values::nonneg_mm)]
    pub seam_tolerance: f64,
    /// `auto`: cut darts where a piece exceeds --max-stretch/--max-compress (the fewest darts
    /// that bring every face within them), then flatten with the limits held.
    #[arg(long, value_name = "MODE", value_parser = parse_darts)]
    pub darts: Option<DartMode>,
    /// Most darts in one piece.
    #[arg(long, value_name = "N", default_value_t = DartSettings::default().max_darts, value_parser = values::dart_count)]
    pub max_darts: usize,
    /// Least distance between two darts (mm).
    #[arg(long, value_name = "MM", default_value_t = DartSettings::default().min_spacing_mm, value_parser = values::nonneg_mm)]
    pub dart_min_spacing: f64,
    /// How far short of its point a dart's drill mark sits (mm).
    #[arg(long, value_name = "MM", default_value_t = DartSettings::default().drill_offset_mm, value_parser = values::nonneg_mm)]
    pub dart_drill: f64,
    /// How the darted piece's final map uses the material's give: `least-strain` (the least
    /// strained map within the limits) or `tight` (every dart drawn shut as far as the limits
    /// let it: the darts open least, the material sits at its limits around them).
    #[arg(long, value_name = "FIT", default_value = "least-strain", value_parser = parse_dart_fit)]
    pub dart_fit: DartFit,
    /// `auto`: split a piece that exceeds --max-stretch/--max-compress, and that darts (when
    /// asked for too) cannot bring within them, into parts sewn together along new seams (with
    /// balance notches), every part within the limits; a surface that is not a disk (closed, of
    /// any genus, or with several boundary loops: a plush toy, a ring, a boot with eyelets) is
    /// opened first along short loops round its handles (a sphere along a slit).
    #[arg(long, value_name = "MODE", value_parser = parse_split)]
    pub split: Option<DartMode>,
    /// Most parts one piece may be split into.
    #[arg(long, value_name = "N", default_value_t = SplitSettings::default().max_pieces, value_parser = values::piece_count)]
    pub max_pieces: usize,
    /// Time limit of one piece's split in seconds of the process's CPU time (all its threads,
    /// so a busy machine does not change how far the split gets; two cores at work spend it
    /// twice as fast as the wall clock): when it runs out, the best split found so far is
    /// written, with a warning (and exit code 3 while a face is beyond the limits).
    #[arg(long, value_name = "S", value_parser = values::seconds)]
    pub split_time: Option<std::time::Duration>,
    /// With --split auto, a closed surface that is its own mirror image as left and right
    /// pairs: `auto` finds the mirror plane (through the principal axes, refined), `x`, `y` or
    /// `z` takes the plane normal to that axis (an error when the surface is not symmetric
    /// across it), `off` (the default) splits without symmetry. One half is split, the other's
    /// parts are its mirror images (`<piece>-<k>L` and `-<k>R`); a surface with no mirror
    /// plane is split without symmetry, with a note. A plane in any other pose:
    /// --symmetry-plane.
    #[arg(long, value_name = "MODE", default_value = "off", value_parser = parse_symmetry)]
    pub symmetry: SymmetryMode,
    /// With --split auto, a closed surface split as left and right pairs across this plane: a
    /// point of it and its normal, `X,Y,Z,NX,NY,NZ` in mm (the normal of any length), for a
    /// model whose plane is no coordinate plane through its middle. The plane is taken as
    /// given, not refined; a surface that is not its own mirror image across it within
    /// --symmetry-tolerance is an error, nothing written. In place of --symmetry.
    #[arg(long, value_name = "X,Y,Z,NX,NY,NZ", value_parser = parse_symmetry_plane, conflicts_with = "symmetry", allow_hyphen_values = true)]
    pub symmetry_plane: Option<SymmetryMode>,
    /// Largest deviation of the surface from its mirror image that --symmetry accepts, in
    /// percent of its bounding box diagonal.
    #[arg(long, value_name = "PCT", default_value_t = 100.0 * flatcut::mesh::symmetry::DEFAULT_TOLERANCE, value_parser = values::material_percent)]
    pub symmetry_tolerance: f64,
    /// With --split auto, move a scan's spikes back into its surface before it is flattened and
    /// split: the inside vertices whose angle defect is more than their corners can absorb
    /// within the limits (no part within them holds one inside), each to the plane of its
    /// neighbours or their centroid (their neighbours too, only where that is not enough),
    /// never folding a face. Nothing else moves; what moved is printed and recorded in the
    /// report (`despike`).
    #[arg(long)]
    pub despike: bool,
    /// With --despike, the farthest a vertex may move (mm); a spike that needs more is left,
    /// counted in the report, and the split refuses it as without --despike. The default is
    /// about twice a scan's spike: a larger move changes the shape rather than its noise.
    #[arg(long, value_name = "MM", default_value_t = flatcut::despiking::DEFAULT_MAX_MM, value_parser = values::positive_mm, requires = "despike")]
    pub despike_max_mm: f64,
    /// The material of pieces that name none: leather, woven-cotton, canvas, knit,
    /// carbon-prepreg, sailcloth, or a material file (TOML). Flattens with the orthotropic
    /// energy along each piece's grain (chosen when the piece has none) and checks the limits
    /// along, across and on the bias.
    #[arg(long, value_name = "NAME|FILE")]
    pub material: Option<String>,
}

impl FlattenArgs {
    /// The `--material`, read.
    pub fn material(&self) -> anyhow::Result<Option<MaterialSpec>> {
        self.material
            .as_deref()
            .map(|m| MaterialSpec::load(m, None))
            .transpose()
            .map_err(anyhow::Error::from)
    }
}

/// Shows a flattening's progress (stage, iteration of the cap, objective) as a bar on stderr
/// (indicatif hides it when stderr is not a terminal). Returns the params with the hook and the
/// bar, to be cleared when the flattening returns.
pub fn with_progress_bar(params: FlattenParams) -> (FlattenParams, indicatif::ProgressBar) {
    let (hooks, bar) = progress_hooks(params.hooks.clone(), params.max_iters);
    (params.with_hooks(hooks), bar)
}

/// `hooks` with a progress callback drawing a bar (initially of `len` steps) on stderr.
pub fn progress_hooks(hooks: FlattenHooks, len: usize) -> (FlattenHooks, indicatif::ProgressBar) {
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{prefix} {bar:30} {pos}/{len} {msg} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let shown = bar.clone();
    let splitting = std::sync::atomic::AtomicBool::new(false);
    let hooks = hooks.with_progress(std::sync::Arc::new(move |p: &FlattenProgress| {
        if p.stage == "split" && !splitting.swap(true, std::sync::atomic::Ordering::Relaxed) {
            shown.suspend(|| {
                eprintln!(
                    "splitting where the limits demand (Ctrl-C stops it; nothing is written then)"
                )
            });
        }
        shown.set_prefix(p.stage);
        shown.set_length(p.max_iterations as u64);
        shown.set_position(p.iteration as u64);
        shown.set_message(format!("energy {:.6e}", p.energy));
    }));
    (hooks, bar)
}

/// `--darts` and `--split`: when darts are cut, and when pieces are split.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DartMode {
    /// Where a piece exceeds its limits.
    Auto,
}

fn parse_darts(s: &str) -> Result<DartMode, String> {
    match s {
        "auto" => Ok(DartMode::Auto),
        _ => Err(format!("unknown dart mode '{s}'; the mode is auto")),
    }
}

fn parse_dart_fit(s: &str) -> Result<DartFit, String> {
    DartFit::from_name(s)
        .ok_or_else(|| format!("unknown dart fit '{s}'; the fits are least-strain and tight"))
}

fn parse_symmetry(s: &str) -> Result<SymmetryMode, String> {
    SymmetryMode::from_name(s).ok_or_else(|| {
        format!(
            "unknown symmetry '{s}'; one of: {}",
            SymmetryMode::NAMES.join(", ")
        )
    })
}

/// `X,Y,Z,NX,NY,NZ`: a point of the mirror plane and its normal.
fn parse_symmetry_plane(s: &str) -> Result<SymmetryMode, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let Ok(v) = <[&str; 6]>::try_from(parts) else {
        return Err(format!(
            "'{s}' is not a plane: give a point and a normal as six numbers X,Y,Z,NX,NY,NZ (mm)"
        ));
    };
    let mut n = [0.0; 6];
    for (x, t) in n.iter_mut().zip(v) {
        *x = t
            .parse()
            .map_err(|_| format!("'{t}' in '{s}' is not a number"))?;
    }
    SymmetryMode::plane(n).map_err(|e| format!("'{s}' is not a plane: {e}"))
}

fn parse_split(s: &str) -> Result<DartMode, String> {
    match s {
        "auto" => Ok(DartMode::Auto),
        _ => Err(format!("unknown split mode '{s}'; the mode is auto")),
    }
}

pub fn parse_method(s: &str) -> Result<Method, String> {
    Method::from_name(s).ok_or_else(|| {
        format!(
            "unknown method '{s}'; one of: {}",
            Method::ALL
                .iter()
                .map(|m| m.name())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

impl FlattenArgs {
    pub fn params(&self) -> anyhow::Result<FlattenParams> {
        for (name, v) in [
            ("--max-stretch", self.max_stretch),
            ("--max-compress", self.max_compress),
        ] {
            if let Some(v) = v {
                anyhow::ensure!(
                    v.is_finite() && (0.0..100.0).contains(&v),
                    "{name} must be a percentage in [0, 100), got {v}"
                );
            }
        }
        let mut p = FlattenParams::new(self.method)
            .with_max_stretch_pct(self.max_stretch)
            .with_max_compress_pct(self.max_compress)
            .with_time_limit(self.flatten_time);
        if let Some(n) = self.max_iters {
            p = p.with_max_iters(n);
        }
        Ok(p)
    }

    /// True when the command line gives limits: a stretch or compression limit, or a material
    /// (darts and splits for it hold the tightest of its limits along, across and on the bias,
    /// [`flatcut::material::dart_params`], and so all of them).
    fn has_limits(&self) -> bool {
        self.max_stretch.is_some() || self.max_compress.is_some() || self.material.is_some()
    }

    /// The dart settings when darts are asked for on the command line.
    pub fn darts(&self) -> anyhow::Result<Option<DartSettings>> {
        if self.darts != Some(DartMode::Auto) {
            return Ok(None);
        }
        anyhow::ensure!(
            self.has_limits(),
            "--darts auto needs --max-stretch and/or --max-compress, or --material: the limits the darts are for"
        );
        Ok(Some(DartSettings {
            max_darts: self.max_darts,
            min_spacing_mm: self.dart_min_spacing,
            drill_offset_mm: self.dart_drill,
            fit: self.dart_fit,
        }))
    }

    /// The split settings when splitting is asked for on the command line.
    pub fn split(&self) -> anyhow::Result<Option<SplitSettings>> {
        if self.split != Some(DartMode::Auto) {
            anyhow::ensure!(
                !self.despike,
                "--despike needs --split auto: it removes the spikes no part within the limits can hold"
            );
            return Ok(None);
        }
        anyhow::ensure!(
            self.has_limits(),
            "--split auto needs --max-stretch and/or --max-compress, or --material: the limits the parts are for"
        );
        Ok(Some(SplitSettings {
            max_pieces: self.max_pieces,
            time_limit: self.split_time,
            symmetry: SymmetrySettings {
                mode: self.symmetry_plane.unwrap_or(self.symmetry),
                tolerance: self.symmetry_tolerance / 100.0,
            },
            despike_max_mm: self.despike.then_some(self.despike_max_mm),
            ..SplitSettings::default()
        }))
    }

    pub fn tolerances(&self) -> anyhow::Result<Tolerances> {
        anyhow::ensure!(
            self.chord.is_finite() && self.chord > 0.0,
            "--chord must be a positive length in mm, got {}",
            self.chord
        );
        Ok(Tolerances::DEFAULT
            .with_chord_mm(self.chord)
            .with_heal_mm(self.heal_tolerance))
    }
}

/// Options of pattern pieces shared by `pattern`, `nest`, `gcode` and `run`.
#[derive(Debug, Clone, clap::Args)]
pub struct PieceArgs {
    /// Seam allowance in mm where the design gives none.
    #[arg(long, value_name = "MM", value_parser = values::nonneg_mm)]
    pub seam: Option<f64>,
    /// Corner style of the allowance: mitred, squared or reflected.
    #[arg(long, default_value = "mitred", value_parser = parse_corner)]
    pub corner: CornerStyle,
    /// Notch shape: slit or v.
    #[arg(long, default_value = "slit", value_parser = parse_notch)]
    pub notch: NotchStyle,
}

fn parse_corner(s: &str) -> Result<CornerStyle, String> {
    match s {
        "mitred" | "mitered" => Ok(CornerStyle::Mitred),
        "squared" => Ok(CornerStyle::Squared),
        "reflected" => Ok(CornerStyle::Reflected),
        _ => Err(format!(
            "unknown corner style '{s}'; one of mitred, squared, reflected"
        )),
    }
}

fn parse_notch(s: &str) -> Result<NotchStyle, String> {
    match s {
        "slit" => Ok(NotchStyle::Slit),
        "v" | "V" => Ok(NotchStyle::V),
        _ => Err(format!("unknown notch style '{s}'; one of slit, v")),
    }
}

impl PieceArgs {
    pub fn options(&self) -> anyhow::Result<PieceOptions> {
        let mut o = PieceOptions::DEFAULT.with_notch_style(self.notch);
        if let Some(s) = self.seam {
            anyhow::ensure!(
                s.is_finite() && s >= 0.0,
                "--seam must be a width in mm >= 0, got {s}"
            );
            o = o.with_default_seam(s);
        }
        Ok(o)
    }
}

/// True when the path names a flattened mesh rather than a design.
pub fn is_mesh(path: &Path) -> bool {
    flatcut::mesh::io::is_mesh_path(path)
}

pub use flatcut::flat::Flat;
pub use flatcut::pieces::{ROW_GAP_MM, row_layout};

/// Loads a flattened OBJ (with `vt`) as it is, or flattens every piece of a design; `verbose`
/// prints each piece's progress and figures on stderr.
pub fn load_flat(
    path: &Path,
    fa: &FlattenArgs,
    limits: (Option<f64>, Option<f64>),
    verbose: bool,
) -> anyhow::Result<Vec<Flat>> {
    load_with(path, fa, limits, verbose, flatcut::flat::load_flat)
}

/// [`load_flat`], except that a mesh carrying a flat map (`vt`) is flattened again from its 3D
/// shape, as `flatten` promises.
pub fn flatten_again(
    path: &Path,
    fa: &FlattenArgs,
    limits: (Option<f64>, Option<f64>),
    verbose: bool,
) -> anyhow::Result<Vec<Flat>> {
    load_with(path, fa, limits, verbose, flatcut::flat::flatten_and_report)
}

/// The loader `load` (a flattened OBJ as it is or a design flattened, or everything flattened)
/// with the command line's settings, its progress and figures on stderr when `verbose`.
fn load_with(
    path: &Path,
    fa: &FlattenArgs,
    limits: (Option<f64>, Option<f64>),
    verbose: bool,
    load: fn(
        &Path,
        &Tolerances,
        &FlattenParams,
        Limits,
        &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Vec<Flat>, flatcut::pipeline::PipelineError>,
) -> anyhow::Result<Vec<Flat>> {
    // Ctrl-C stops the flattening (and a split) at its cancel flag; nothing is written then.
    let stop = crate::stop::Stoppable::register();
    let (params, bar) = with_progress_bar(fa.params()?);
    let params = params.clone().with_hooks(stop.hooks(params.hooks));
    let tol = fa.tolerances()?;
    let limits = Limits {
        stretch_pct: limits.0,
        compress_pct: limits.1,
        darts: fa.darts()?,
        split: fa.split()?,
        material: fa.material()?,
    };
    let limits_split = limits.split.is_some();
    let t0 = std::time::Instant::now();
    let method = match &limits.material {
        Some(m) => format!("{} for {}", Method::Orthotropic, m.name),
        None => params.method.to_string(),
    };
    let flats = load(path, &tol, &params, limits, &mut |name, k, n| {
        if verbose {
            bar.suspend(|| eprintln!("flattening piece {}/{} '{}' ({})", k + 1, n, name, method));
        }
    });
    bar.finish_and_clear();
    stop.check(|| {
        let what = if limits_split { "split" } else { "flattening" };
        format!("the {what} of {}", path.display())
    })?;
    let flats = flats.with_context(|| format!("cannot flatten {}", path.display()))?;
    print_despiked(&flats);
    for f in &flats {
        let Some(info) = &f.info else { continue };
        for w in &info.warnings {
            eprintln!("warning: piece '{}': {w}", f.name);
        }
        if verbose {
            let r = &f.report;
            eprintln!(
                "  '{}': {} faces, {} iterations{}, mean δ2 {:.5}, stretch max {:.2}%, compression max {:.2}%, {:.2} s",
                f.name,
                r.faces,
                info.iterations,
                stage_counts(info),
                r.delta2_mean,
                r.stretch_max_pct,
                r.compress_max_pct,
                t0.elapsed().as_secs_f64()
            );
            if !f.darts.is_empty() {
                let total: f64 = f.darts.iter().map(|d| d.length_3d_mm).sum();
                eprintln!("  {} darts, {total:.1} mm in all", f.darts.len());
            }
            if let Some(g) = &r.grain {
                eprintln!("{}", grain_line(g));
            }
        }
    }
    Ok(flats)
}

/// Prints on stderr what removing each piece's spikes changed (`--despike`), once per piece
/// (its parts carry the same record).
pub fn print_despiked(flats: &[Flat]) {
    let mut seen: Vec<&str> = Vec::new();
    for d in flats.iter().filter_map(|f| f.despike.as_ref()) {
        if !seen.contains(&d.piece.as_str()) {
            seen.push(&d.piece);
            eprintln!("{}", d.line());
        }
    }
}

/// " (isometric 7/200, limits 12/200)": each stage's iterations against its cap, empty for a
/// method without stages.
pub fn stage_counts(info: &flatcut::flatten::FlattenInfo) -> String {
    if info.stages.is_empty() {
        return String::new();
    }
    let each: Vec<String> = info.stages.iter().map(|s| s.to_string()).collect();
    format!(" ({})", each.join(", "))
}

/// Prints, on stderr, every region beyond the material limits (where on the 3D surface and by
/// how much), every mating seam beyond `seam_tolerance` mm and, with `flips`, every piece with
/// flipped faces; true when there is any, for the caller to exit with [`crate::EXIT_LIMIT`].
pub fn report_limits(flats: &[Flat], seam_tolerance: f64, flips: bool) -> bool {
    let mut over = false;
    for f in flats {
        if flips && f.report.flipped > 0 {
            eprintln!(
                "{}: {} flipped faces (the pattern folds over itself)",
                f.name, f.report.flipped
            );
            over = true;
        }
        for r in &f.report.regions {
            over = true;
            eprintln!(
                "{}: {} {:.2}% over {:.1} mm², worst at 3D ({:.1}, {:.1}, {:.1}) / 2D ({:.1}, {:.1}) \
                 on the surface",
                f.name,
                r.kind,
                r.worst_pct,
                r.area_mm2,
                r.worst_at_3d[0],
                r.worst_at_3d[1],
                r.worst_at_3d[2],
                r.worst_at_2d[0],
                r.worst_at_2d[1]
            );
        }
    }
    for line in flatcut::flat::materials_over(flats)
        .into_iter()
        .chain(flatcut::flat::seams_over(flats, seam_tolerance))
        .chain(
            flatcut::sanity::insane(flats)
                .iter()
                .map(ToString::to_string),
        )
    {
        eprintln!("{line}");
        over = true;
    }
    over
}

/// Prints every mating seam: its sides' flat lengths against 3D and its notches' offsets.
pub fn print_seams(flats: &[Flat]) -> anyhow::Result<()> {
    for s in flatcut::flat::mating_seams(flats) {
        crate::outln!(
            "mating seam '{}' ({} / {}): 3D {:.2} mm, flat {:.3} / {:.3} mm, mismatch {:.4} mm",
            s.name,
            s.pieces[0],
            s.pieces[1],
            s.length_3d_mm,
            s.length_2d_mm[0],
            s.length_2d_mm[1],
            s.mismatch_mm
        );
        for n in &s.notches {
            crate::outln!(
                "  notch '{}': {:.3} / {:.3} mm from the seam's start",
                n.name,
                n.offset_mm[0],
                n.offset_mm[1]
            );
        }
    }
    Ok(())
}

/// Builds the pattern piece of each flattened piece.
pub fn build_pieces(flats: &[Flat], pa: &PieceArgs) -> anyhow::Result<Vec<Piece>> {
    let settings = PieceSettings {
        options: pa.options()?,
        seam_mm: pa.seam,
        corner: pa.corner,
    };
    Ok(flatcut::pieces::build_pieces(flats, &settings)?)
}

/// True when the path names a 2D pattern file (SVG or DXF) rather than a design or mesh.
pub fn is_pattern_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg") || e.eq_ignore_ascii_case("dxf"))
}

/// Reads a pattern SVG or DXF (AAMA or plain) as a drawing in mm, curves flattened within
/// `chord_mm`, SVG stroke colours mapped to layers by `colours`; the reader's warnings are
/// printed.
pub fn read_pattern_file(
    path: &Path,
    chord_mm: f64,
    colours: &flatcut::pattern::ColourTable,
) -> anyhow::Result<flatcut::pattern::Drawing> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let name = path.display().to_string();
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("dxf"))
    {
        let import = flatcut::pattern::dxf_read::read_dxf(&text, chord_mm)
            .with_context(|| format!("cannot read {name}"))?;
        for w in &import.warnings {
            eprintln!("warning: {name}: {w}");
        }
        return Ok(import.drawing);
    }
    let import = flatcut::pattern::svg::read_svg(&text, &name, chord_mm, colours)?;
    for w in &import.warnings {
        eprintln!("warning: {name}: {w}");
    }
    Ok(import.drawing)
}

/// Writes one file whole or not at all, naming it in errors (a set of one: see
/// [`OutputSet`](crate::output::OutputSet) for a command's several outputs).
pub fn write(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let mut set = crate::output::OutputSet::new();
    set.add(path, bytes)?;
    set.commit().map(drop)
}

/// `dir/stem-suffix.ext` next to `path`.
pub fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!("{stem}-{suffix}{ext}"))
}

pub use flatcut::run::file_safe;

/// One line on a piece's material: where its grain runs (and whether it was chosen), its
/// largest stretch and compression along, across and on the bias, and the faces over the
/// material's limits.
pub fn grain_line(g: &flatcut::report::GrainReport) -> String {
    format!(
        "  material {}: grain{} along ({:.3}, {:.3}, {:.3}); stretch/compression max along {:.2}/{:.2}%, across {:.2}/{:.2}%, bias {:.2}/{:.2}%; bias share of the strain {:.2}; {} faces over the material's limits",
        g.material,
        if g.grain_auto { " (chosen)" } else { "" },
        g.grain_3d[0],
        g.grain_3d[1],
        g.grain_3d[2],
        g.stretch_max_pct_along,
        g.compress_max_pct_along,
        g.stretch_max_pct_across,
        g.compress_max_pct_across,
        g.stretch_max_pct_bias,
        g.compress_max_pct_bias,
        g.bias_strain_share,
        g.faces_over_material_limits
    )
}
