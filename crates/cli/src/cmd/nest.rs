//! `flatcut nest PIECES… --sheet 600x400 | --roll 1400 | --hide HIDE… -o layout.svg [--dxf …]`:
//! places pattern pieces (pattern SVGs, designs or flattened OBJs) on sheets, a roll or leather
//! hides; `flatcut nest --instance FILE.json` nests a strip-packing benchmark instance.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use flatcut::geom::DVec2;
use flatcut::nest::{
    GrainDirections, Hide, HideFormat, NestOptions, NestProgress, NestResult, Stock,
};
use flatcut::pattern::dxf::DxfLayers;
use flatcut::pattern::{Drawing, Layer, Stroke, StrokeKind};
use flatcut::pipeline::{self, NestGroup};

use super::common::{self, FlattenArgs, PieceArgs};
use crate::output::OutputSet;
use crate::values;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Pattern SVGs or DXFs (AAMA or plain CAD files), designs or flattened OBJs.
    #[arg(required_unless_present = "instance")]
    pub pieces: Vec<PathBuf>,
    /// Sheet size in mm, WIDTHxHEIGHT.
    #[arg(long, value_parser = values::sheet_size)]
    pub sheet: Option<(f64, f64)>,
    /// Nest on a roll of this width (mm) instead of sheets; the length is minimised.
    #[arg(long, value_name = "WIDTH", value_parser = values::positive_mm)]
    pub roll: Option<f64>,
    /// Nest on leather hides (JSON, DXF or SVG with an outline, defects, graded zones and
    /// direction lines), used in the order given; repeat for more hides.
    #[arg(long, value_name = "HIDE")]
    pub hide: Vec<PathBuf>,
    /// A strip-packing benchmark instance in jagua-rs's JSON format (the published instances of
    /// the strip-packing literature, such as those shipped with jagua-rs and sparrow): nested on
    /// its strip by its own rules (its allowed rotations, no spacing).
    #[arg(long, value_name = "FILE.json", conflicts_with_all = ["pieces", "sheet", "roll", "hide"])]
    pub instance: Option<PathBuf>,
    /// Gap between pieces (kerf), mm.
    #[arg(long, default_value_t = NestOptions::DEFAULT_SPACING, value_parser = values::nonneg_mm)]
    pub spacing: f64,
    /// Copies of each input piece, times the piece's own quantity (a design's, a pattern SVG's
    /// `data-flatcut-quantity`, or a DXF's `Quantity:`).
    #[arg(long, default_value_t = 1, value_parser = values::quantity)]
    pub quantity: usize,
    /// Also nest the mirror image of each piece (left and right shoe): the copies as drawn are
    /// named `<id>#<n>L` and their mirror images `<id>#<n>R`, and their pieces `<name> L` / `R`.
    #[arg(long)]
    pub mirrored_pairs: bool,
    /// The material's grain rule for pieces with a grain line: `fixed` (one way), `0,180`
    /// (either way) or `any` (no grain: pieces turn in quarter turns).
    #[arg(long, value_parser = parse_grain, default_value = "0,180")]
    pub grain: GrainDirections,
    /// How far a grain line may turn off the material's grain, degrees (0 to 90).
    #[arg(long, value_name = "DEGREES", default_value_t = 0.0, value_parser = grain_degrees)]
    pub grain_tolerance: f64,
    /// The worst hide grade the pieces accept (1 = first quality only; default: any grade).
    #[arg(long, value_name = "GRADE", value_parser = grade)]
    pub quality: Option<u32>,
    /// Output SVG; further sheets or hides go to `<stem>-2.svg`, …
    #[arg(short, long, required_unless_present = "instance")]
    pub output: Option<PathBuf>,
    /// Also write the layout as DXF; further sheets go to `<stem>-2.dxf`, …
    #[arg(long, value_name = "LAYOUT.dxf")]
    pub dxf: Option<PathBuf>,
    /// Seed of the search (same seed, workers and iterations → same layout).
    #[arg(long, default_value_t = NestOptions::DEFAULT_SEED)]
    pub seed: u64,
    /// Search budget in separation iterations.
    #[arg(long, default_value_t = NestOptions::DEFAULT_MAX_ITERS, value_parser = values::iterations)]
    pub iters: usize,
    /// Time budget in seconds, > 0 (results then depend on the machine's speed); with the
    /// default `--iters` the time alone bounds the search.
    #[arg(long, value_name = "SECONDS", value_parser = values::seconds)]
    pub time: Option<Duration>,
    /// Search workers (1 to 64): the layout depends on their number and the seed, not on the
    /// number of cores that run them.
    #[arg(long, default_value_t = NestOptions::DEFAULT_WORKERS, value_parser = workers)]
    pub workers: usize,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub piece: PieceArgs,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

/// Chordal tolerance used when reading pattern SVGs and DXFs (mm).
const SVG_CHORD_MM: f64 = 0.05;

fn parse_grain(s: &str) -> Result<GrainDirections, String> {
    GrainDirections::parse(s).ok_or_else(|| format!("expected fixed, 0,180 or any, got '{s}'"))
}

/// A grain tolerance: 0 to 90 degrees.
fn grain_degrees(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if (0.0..=90.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v}: give 0 to 90 degrees"))
    }
}

/// A hide grade: 1 (first quality) to 9.
fn grade(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=9).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': give a grade from 1 (first quality) to 9")),
    }
}

/// A worker count: 1 to 64.
fn workers(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if (1..=64).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': give 1 to 64 workers")),
    }
}

fn options(a: &Args, spacing: f64) -> anyhow::Result<NestOptions> {
    let time = a.time;
    Ok(NestOptions::DEFAULT
        .with_spacing(spacing)
        .with_seed(a.seed)
        .with_max_iters(
            if time.is_some() && a.iters == NestOptions::DEFAULT_MAX_ITERS {
                usize::MAX
            } else {
                a.iters
            },
        )
        .with_time_limit(time)
        .with_workers(a.workers))
}

/// A closed outline as a stroke of the layout drawing: a piece's cut line, or a drawn line
/// (a hide's outline, defects and zones, for the operator).
fn outline_stroke(id: String, points: Vec<DVec2>, layer: Layer, piece: Option<u32>) -> Stroke {
    Stroke {
        layer,
        points,
        closed: true,
        piece,
        kind: if layer == Layer::Cut {
            StrokeKind::Boundary
        } else {
            StrokeKind::Internal
        },
        id,
    }
}

fn progress_bar(a: &Args) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(1000);
    if a.json {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    bar.set_style(
        indicatif::ProgressStyle::with_template("nesting {bar:30} {percent:>3}% {msg}")
            .expect("valid template"),
    );
    bar
}

fn on_progress(bar: &indicatif::ProgressBar, p: &NestProgress) {
    bar.set_position((p.budget_used * 1000.0) as u64);
    bar.set_message(format!(
        "{}: utilization {:.1}%, {} sheet(s), length {:.0} mm",
        p.phase.name(),
        p.utilization,
        p.sheets,
        p.length
    ));
}

/// The `--instance --json` line: exactly these keys, in this order.
pub fn instance_json(name: &str, r: &NestResult, time_s: f64, seed: u64) -> String {
    format!(
        "{{\"name\":{},\"utilization\":{},\"length\":{},\"time_s\":{},\"seed\":{}}}",
        serde_json::Value::from(name),
        r.utilization,
        r.length,
        time_s,
        seed
    )
}

/// `--instance`: a benchmark instance on its strip.
fn run_instance(a: &Args, path: &Path) -> anyhow::Result<ExitCode> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let inst = flatcut::nest::load_bench_instance(&text)
        .with_context(|| format!("{}: not a strip-packing instance", path.display()))?;
    let opts = options(a, 0.0)?;
    let bar = progress_bar(a);
    let t0 = std::time::Instant::now();
    let r = flatcut::nest::nest(
        &inst.items,
        Stock::Roll {
            width: inst.strip_height,
            max_length: None,
        },
        &opts,
        &mut |p| on_progress(&bar, p),
    )
    .with_context(|| format!("nesting {}", path.display()))?;
    bar.finish_and_clear();
    let time_s = t0.elapsed().as_secs_f64();
    if let Some(out) = &a.output {
        let mut d = Drawing::default();
        for (k, p) in r.placed.iter().enumerate() {
            let pts = inst.items[p.item]
                .outline
                .iter()
                .map(|q| p.placement.apply(*q))
                .collect();
            let id = format!("{}-{}-cut", inst.items[p.item].name, p.copy + 1);
            d.strokes
                .push(outline_stroke(id, pts, Layer::Cut, Some(k as u32)));
        }
        let size = DVec2::new(r.length.max(1.0), inst.strip_height);
        let mut set = OutputSet::new();
        set.add(
            out,
            flatcut::pattern::svg::write_drawing(&d, Some(size)).as_bytes(),
        )?;
        set.commit()?;
    }
    if a.json {
        crate::outln!("{}", instance_json(&inst.name, &r, time_s, a.seed));
    } else {
        crate::outln!(
            "{}: utilization {:.2}%, length {:.3} (strip {}), {:.1} s, seed {}, {} iterations",
            inst.name,
            r.utilization,
            r.length,
            inst.strip_height,
            time_s,
            a.seed,
            r.iterations
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn read_hides(paths: &[PathBuf]) -> anyhow::Result<Vec<Hide>> {
    paths
        .iter()
        .map(|p| {
            let fmt = p
                .extension()
                .and_then(|e| HideFormat::from_extension(&e.to_string_lossy()))
                .with_context(|| {
                    format!("{}: a hide is a .json, .dxf or .svg file", p.display())
                })?;
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read {}", p.display()))?;
            Ok(flatcut::nest::read_hide(
                &text,
                &p.display().to_string(),
                fmt,
            )?)
        })
        .collect()
}

/// The hide's outline, defects and zones drawn under the pieces.
fn hide_strokes(h: &Hide) -> Vec<Stroke> {
    let mut out = vec![outline_stroke(
        format!("{}-outline", h.name),
        h.outline.clone(),
        Layer::Draw,
        None,
    )];
    for (k, d) in h.defects.iter().enumerate() {
        out.push(outline_stroke(
            format!("defect-{}", k + 1),
            d.clone(),
            Layer::Engrave,
            None,
        ));
    }
    for (k, z) in h.zones.iter().enumerate() {
        out.push(outline_stroke(
            format!("quality-{}-{}", z.grade, k + 1),
            z.outline.clone(),
            Layer::Draw,
            None,
        ));
    }
    out
}

/// The side of a mirrored pair (`L` as drawn, `R` mirrored) an unplaced copy is, when the
/// pieces are nested in pairs.
fn side(pairs: bool, mirrored: bool) -> Option<&'static str> {
    pairs.then(|| flatcut::nesting::PairSide::of(mirrored).letter())
}

fn print_json(r: &NestResult, time_s: f64, seed: u64, pairs: bool) -> anyhow::Result<()> {
    let unplaced: Vec<_> = r
        .unplaced
        .iter()
        .map(|u| {
            let mut j = serde_json::json!({"name": u.name, "copy": u.copy + 1, "mirrored": u.mirrored, "reason": u.reason});
            if let Some(side) = side(pairs, u.mirrored) {
                j["side"] = side.into();
            }
            j
        })
        .collect();
    let sheets: Vec<_> = r
        .sheet_use
        .iter()
        .map(|u| serde_json::json!({"name": u.name, "pieces": u.pieces, "piece_area_mm2": u.piece_area, "usable_area_mm2": u.usable_area, "yield_pct": u.yield_pct}))
        .collect();
    crate::outln!(
        "{}",
        serde_json::json!({
            "utilization": r.utilization,
            "length": r.length,
            "sheets": r.sheets,
            "placed": r.placed.len(),
            "unplaced": unplaced,
            "sheet_use": sheets,
            "time_s": time_s,
            "seed": seed,
        })
    );
    Ok(())
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    if let Some(path) = &a.instance {
        return run_instance(&a, path);
    }
    let hides = read_hides(&a.hide)?;
    let stock = match (a.sheet, a.roll, hides.is_empty()) {
        (None, None, false) => None,
        (_, _, false) => anyhow::bail!("give --hide, or --sheet, or --roll, not several"),
        (_, Some(w), true) => Some(Stock::Roll {
            width: w,
            max_length: None,
        }),
        (Some((w, h)), None, true) => Some(Stock::Sheets {
            width: w,
            height: h,
            max_sheets: None,
        }),
        (None, None, true) => {
            anyhow::bail!("give --sheet WIDTHxHEIGHT, --roll WIDTH or --hide HIDE")
        }
    };
    let mut groups = Vec::new();
    for f in &a.pieces {
        if common::is_pattern_file(f) {
            let d = common::read_pattern_file(
                f,
                SVG_CHORD_MM,
                &flatcut::pattern::ColourTable::default(),
            )?;
            let gs = NestGroup::from_drawing(&f.display().to_string(), &d);
            anyhow::ensure!(
                !gs.is_empty(),
                "{}: no closed cut contour found (nothing to nest)",
                f.display()
            );
            for mut g in gs {
                g.quantity = g.quantity.saturating_mul(a.quantity);
                g.mirrored_pair = a.mirrored_pairs;
                groups.push(g);
            }
        } else {
            let flats = common::load_flat(f, &a.flatten, (None, None), true)?;
            let pieces = common::build_pieces(&flats, &a.piece)?;
            for (p, fl) in pieces.iter().zip(&flats) {
                let q = if fl.def.is_some() {
                    fl.quantity as usize * a.quantity
                } else {
                    a.quantity
                };
                groups.push(NestGroup::from_piece(p, q, a.mirrored_pairs));
            }
        }
    }
    for g in &mut groups {
        g.grain_directions = a.grain;
        g.grain_tolerance_deg = a.grain_tolerance;
        g.quality = a.quality;
    }
    let opts = options(&a, a.spacing)?;
    let bar = progress_bar(&a);
    let t0 = std::time::Instant::now();
    let mut layout = match stock {
        Some(stock) => pipeline::nest_groups(&groups, stock, &opts, &mut |p| on_progress(&bar, p))?,
        None => {
            pipeline::nest_groups_on_hides(&groups, &hides, &opts, &mut |p| on_progress(&bar, p))?
        }
    };
    bar.finish_and_clear();
    let time_s = t0.elapsed().as_secs_f64();
    let output = a.output.clone().context("give -o layout.svg")?;
    let mut set = OutputSet::new();
    for (k, d) in layout.sheets.iter_mut().enumerate() {
        let size = match stock {
            Some(Stock::Sheets { width, height, .. }) => Some(DVec2::new(width, height)),
            Some(Stock::Roll { width, .. }) => {
                Some(DVec2::new(layout.result.length.max(1.0), width))
            }
            None => {
                let h = &hides[k];
                d.strokes.splice(0..0, hide_strokes(h));
                let bb = flatcut::geom::Aabb2::from_points(h.outline.iter().copied());
                Some(bb.max.max(DVec2::ZERO))
            }
        };
        let path = if k == 0 {
            output.clone()
        } else {
            common::sibling(&output, &(k + 1).to_string())
        };
        set.add(
            &path,
            flatcut::pattern::svg::write_drawing(d, size).as_bytes(),
        )?;
        if let Some(dxf) = &a.dxf {
            let p = if k == 0 {
                dxf.clone()
            } else {
                common::sibling(dxf, &(k + 1).to_string())
            };
            set.add(
                &p,
                flatcut::pattern::dxf::write_drawing(d, DxfLayers::Aama).as_bytes(),
            )?;
        }
    }
    set.commit()?;
    let r = &layout.result;
    if a.json {
        print_json(r, time_s, a.seed, a.mirrored_pairs)?;
    } else {
        crate::outln!(
            "placed {} of {} pieces",
            r.placed.len(),
            r.placed.len() + r.unplaced.len()
        );
        match stock {
            Some(Stock::Roll { width, .. }) => {
                crate::outln!("roll {width:.0} mm wide: length {:.1} mm", r.length)
            }
            Some(Stock::Sheets { .. }) => crate::outln!("sheets used: {}", r.sheets),
            None => {
                for u in &r.sheet_use {
                    crate::outln!(
                        "hide {}: {} pieces, yield {:.2}% ({:.0} of {:.0} mm² usable)",
                        u.name,
                        u.pieces,
                        u.yield_pct,
                        u.piece_area,
                        u.usable_area
                    );
                }
            }
        }
        crate::outln!(
            "utilization {:.2}% (first layout {:.2}%), {} iterations, {:.1} s",
            r.utilization,
            r.baseline_utilization,
            r.iterations,
            time_s
        );
    }
    for u in &r.unplaced {
        let side = match side(a.mirrored_pairs, u.mirrored) {
            Some(s) => format!(" {s}"),
            None if u.mirrored => " (mirrored)".to_string(),
            None => String::new(),
        };
        eprintln!(
            "unplaced: {}{side} copy {}: {}",
            u.name,
            u.copy + 1,
            u.reason
        );
    }
    Ok(if r.unplaced.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
