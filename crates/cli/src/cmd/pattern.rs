//! `flatcut pattern FILE -o piece.svg [--seam 10] [--dxf piece.dxf]`: pattern pieces (sew line,
//! cut line with allowance, notches, drill holes, grain line, label) in true millimetres.

use std::path::PathBuf;
use std::process::ExitCode;

use flatcut::pattern::dxf::DxfLayers;

use super::common::{self, FlattenArgs, PieceArgs};
use crate::output::OutputSet;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A design (flattened first) or a flattened OBJ from `flatcut flatten`.
    pub file: PathBuf,
    /// Output SVG (all pieces side by side, 1 user unit = 1 mm).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a DXF (R12, AAMA layers).
    #[arg(long)]
    pub dxf: Option<PathBuf>,
    /// DXF layer names: aama (numbers) or named (CUT, DRAW, NOTCH, DRILL, TEXT).
    #[arg(long, default_value = "aama")]
    pub dxf_layers: String,
    #[command(flatten)]
    pub piece: PieceArgs,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let layers = match a.dxf_layers.as_str() {
        "aama" => DxfLayers::Aama,
        "named" => DxfLayers::Named,
        o => anyhow::bail!("--dxf-layers must be aama or named, got '{o}'"),
    };
    let flats = common::load_flat(&a.file, &a.flatten, (None, None), true)?;
    let pieces = common::build_pieces(&flats, &a.piece)?;
    let placed = common::row_layout(&pieces);
    let mut out = OutputSet::new();
    let svg = flatcut::pattern::svg::write_pieces(&placed, None);
    out.add(&a.output, svg.as_bytes())?;
    if let Some(p) = &a.dxf {
        let dxf = flatcut::pattern::dxf::write_pieces(
            &placed,
            layers,
            flatcut::pattern::PieceOptions::DEFAULT_CHORD_TOL,
        );
        out.add(p, dxf.as_bytes())?;
    }
    for p in &pieces {
        let b = p.bbox();
        crate::outln!(
            "{}: cut line {:.1} mm, area {:.0} mm², {:.1} × {:.1} mm, {} notches, {} drill holes",
            p.name,
            p.cut_length(),
            p.cut_area(),
            b.width(),
            b.height(),
            p.notches.len(),
            p.drills.len()
        );
    }
    out.commit()?;
    crate::outln!(
        "wrote {}{}",
        a.output.display(),
        a.dxf
            .as_ref()
            .map(|d| format!(" and {}", d.display()))
            .unwrap_or_default()
    );
    Ok(ExitCode::SUCCESS)
}
