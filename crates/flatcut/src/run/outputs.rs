//! What a project run produces, as values: the pieces, the layout, one job per sheet, the summary,
//! and every file's name and bytes so the caller can write them as one set.

use flatcut_gcode::{Profile, Summary};
use flatcut_nest::Stock;
use flatcut_pattern::{Drawing, Piece};
use serde::Serialize;

use crate::flat::Flat;
use crate::pipeline::Layout;

/// One output file: its name relative to the output folder, and its contents.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputFile {
    /// The file's name relative to the output folder.
    pub name: String,
    /// The file's contents.
    pub bytes: Vec<u8>,
}

/// The job of one sheet (or of the roll).
#[derive(Clone, Debug)]
pub struct SheetJob {
    /// 1-based sheet number, as in the file names.
    pub number: usize,
    /// What is cut, in sheet coordinates (mm).
    pub drawing: Drawing,
    /// The G-code file's name among the outputs (`job-N.gcode`).
    pub gcode_file: String,
    /// The job's figures: lines, lengths, estimated time.
    pub summary: Summary,
}

/// One piece's line of the summary (keys in alphabetical order).
#[derive(Clone, Debug, Serialize)]
pub struct PieceSummary {
    /// The piece's 3D area (mm²).
    pub area_mm2: f64,
    /// The largest compression in the piece (percent).
    pub compress_max_pct: f64,
    /// The mean of the report's δ² distortion measure over the piece.
    pub delta2_mean: f64,
    /// What removing the surface's spikes changed (`despike = true`); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub despike: Option<crate::despiking::DespikeRecord>,
    /// Mirror images cut besides (`pairs`).
    pub mirrored: u32,
    /// The piece's name.
    pub name: String,
    /// How many are cut as drawn.
    pub quantity: u32,
    /// The largest stretch in the piece (percent).
    pub stretch_max_pct: f64,
}

/// The figures of a run (`summary.json`; keys in alphabetical order, as before).
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// Tool-down length of every job (mm).
    pub cut_length_mm: f64,
    /// Estimated run time of every job (s).
    pub est_time_s: f64,
    /// G-code lines of every job.
    pub gcode_lines: usize,
    /// The short codes written on pieces too small for a readable label, and the pieces they
    /// stand for.
    pub label_codes: std::collections::BTreeMap<String, String>,
    /// What the jobs write on the pieces: their labels, or that the profile leaves them
    /// unmarked ([`flatcut_gcode::Marking`]).
    pub labels: String,
    /// One line per region beyond the material limits and per mating seam beyond the seam
    /// tolerance.
    pub limits_exceeded: Vec<String>,
    /// Every mating seam: its sides' flat lengths and its notches' offsets.
    pub mating_seams: Vec<flatcut_report::MatingSeamReport>,
    /// One line per piece, in the design's order.
    pub pieces: Vec<PieceSummary>,
    /// The project's name.
    pub project: String,
    /// Sheets or hides used.
    pub sheets: usize,
    /// Tool-up length of every job (mm).
    pub travel_length_mm: f64,
    /// Copies that found no place.
    pub unplaced: usize,
    /// Placed piece area over used stock area (percent).
    pub utilization_pct: f64,
}

/// Everything a project run produced.
pub struct ProjectOutputs {
    /// The flattened pieces.
    pub flats: Vec<Flat>,
    /// The pattern pieces, one per flattened piece.
    pub pieces: Vec<Piece>,
    /// The nested layout.
    pub layout: Layout,
    /// The sheets or roll nested on.
    pub stock: Stock,
    /// The machine profile the jobs are planned for.
    pub profile: Profile,
    /// One job per sheet.
    pub sheets: Vec<SheetJob>,
    /// The run's figures (`summary.json`).
    pub summary: RunSummary,
    /// Every file, in the order a caller should write them.
    pub files: Vec<OutputFile>,
}

impl ProjectOutputs {
    /// True when some region exceeds the material limits.
    pub fn limits_exceeded(&self) -> bool {
        !self.summary.limits_exceeded.is_empty()
    }
}
