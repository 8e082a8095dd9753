//! `flatcut nest PIECES… --sheet 600x400 [--roll 1400] --spacing 2 -o layout.svg [--dxf layout.dxf]`:
//! places pattern pieces (pattern SVGs, designs or flattened OBJs) on sheets or a roll.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use flatcut::geom::DVec2;
use flatcut::nest::{NestOptions, Stock};
use flatcut::pattern::dxf::DxfLayers;
use flatcut::pipeline::{self, NestGroup};

use super::common::{self, FlattenArgs, PieceArgs};
use crate::output::OutputSet;
use crate::values;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Pattern SVGs or DXFs (AAMA or plain CAD files), designs or flattened OBJs.
    #[arg(required = true)]
    pub pieces: Vec<PathBuf>,
    /// Sheet size in mm, WIDTHxHEIGHT.
    #[arg(long, value_parser = values::sheet_size)]
    pub sheet: Option<(f64, f64)>,
    /// Nest on a roll of this width (mm) instead of sheets; the length is minimised.
    #[arg(long, value_name = "WIDTH", value_parser = values::positive_mm)]
    pub roll: Option<f64>,
    /// Gap between pieces (kerf), mm.
    #[arg(long, default_value_t = NestOptions::DEFAULT_SPACING, value_parser = values::nonneg_mm)]
    pub spacing: f64,
    /// Copies of each input piece, times the piece's own quantity (a design's, a pattern SVG's
    /// `data-flatcut-quantity`, or a DXF's `Quantity:`).
    #[arg(long, default_value_t = 1, value_parser = values::quantity)]
    pub quantity: usize,
    /// Also nest the mirror image of each piece (left and right shoe).
    #[arg(long)]
    pub mirrored_pairs: bool,
    /// Output SVG; further sheets go to `<stem>-2.svg`, …
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the layout as DXF (R12, AAMA layers); further sheets go to `<stem>-2.dxf`, …
    #[arg(long, value_name = "LAYOUT.dxf")]
    pub dxf: Option<PathBuf>,
    /// Seed of the search (same seed and budget → same layout).
    #[arg(long, default_value_t = NestOptions::DEFAULT_SEED)]
    pub seed: u64,
    /// Local-search iterations.
    #[arg(long, default_value_t = NestOptions::DEFAULT_MAX_ITERS, value_parser = values::iterations)]
    pub iters: usize,
    /// Time budget in seconds, > 0 (results then depend on the machine's speed).
    #[arg(long, value_name = "SECONDS", value_parser = values::seconds)]
    pub time: Option<Duration>,
    #[command(flatten)]
    pub piece: PieceArgs,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

/// Chordal tolerance used when reading pattern SVGs and DXFs (mm).
const SVG_CHORD_MM: f64 = 0.05;

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let stock = match (a.sheet, a.roll) {
        (_, Some(w)) => Stock::Roll {
            width: w,
            max_length: None,
        },
        (Some((w, h)), None) => Stock::Sheets {
            width: w,
            height: h,
            max_sheets: None,
        },
        (None, None) => anyhow::bail!("give --sheet WIDTHxHEIGHT or --roll WIDTH"),
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
    let opts = NestOptions::DEFAULT
        .with_spacing(a.spacing)
        .with_seed(a.seed)
        .with_max_iters(a.iters)
        .with_time_limit(a.time);
    let bar = indicatif::ProgressBar::new(a.iters as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("nesting {bar:30} {pos}/{len} {msg}")
            .expect("valid template"),
    );
    let layout = pipeline::nest_groups(&groups, stock, &opts, &mut |p| {
        bar.set_position(p.iteration as u64);
        bar.set_message(format!(
            "utilization {:.1}%, {} sheet(s), length {:.0} mm",
            p.utilization, p.sheets, p.length
        ));
    })?;
    bar.finish_and_clear();
    let sheet_size = match stock {
        Stock::Sheets { width, height, .. } => DVec2::new(width, height),
        Stock::Roll { width, .. } => DVec2::new(layout.result.length.max(1.0), width),
    };
    let mut out = OutputSet::new();
    for (k, d) in layout.sheets.iter().enumerate() {
        let path = if k == 0 {
            a.output.clone()
        } else {
            common::sibling(&a.output, &(k + 1).to_string())
        };
        out.add(
            &path,
            flatcut::pattern::svg::write_drawing(d, Some(sheet_size)).as_bytes(),
        )?;
        if let Some(dxf) = &a.dxf {
            let p = if k == 0 {
                dxf.clone()
            } else {
                common::sibling(dxf, &(k + 1).to_string())
            };
            out.add(
                &p,
                flatcut::pattern::dxf::write_drawing(d, DxfLayers::Aama).as_bytes(),
            )?;
        }
    }
    out.commit()?;
    let r = &layout.result;
    crate::outln!(
        "placed {} of {} pieces",
        r.placed.len(),
        r.placed.len() + r.unplaced.len()
    );
    match stock {
        Stock::Roll { width, .. } => {
            crate::outln!("roll {width:.0} mm wide: length {:.1} mm", r.length)
        }
        Stock::Sheets { .. } => crate::outln!("sheets used: {}", r.sheets),
    }
    crate::outln!(
        "utilization {:.2}% (bottom-left fill baseline {:.2}%), {} iterations",
        r.utilization,
        r.baseline_utilization,
        r.iterations
    );
    for u in &r.unplaced {
        eprintln!(
            "unplaced: {} copy {}{}: {}",
            u.name,
            u.copy,
            if u.mirrored { " (mirrored)" } else { "" },
            u.reason
        );
    }
    Ok(if r.unplaced.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
