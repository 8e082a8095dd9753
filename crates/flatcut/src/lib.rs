//! The flatcut library: from a 3D design to flat cutting patterns and the job that cuts them.
//!
//! The stages compose the workspace crates — design → mesh → flattening → report → pattern pieces
//! → nesting → G-code — and [`run`] runs a whole project through them, reporting events and
//! returning every output as a value; [`grbl`] streams a job to a GRBL controller. The glue that
//! needs both worlds lives here: a flattened mesh boundary becomes a 2D pattern piece, so
//! `flatcut-pattern` never learns about meshes.
//!
//! A design to a knife job in a few lines:
//!
//! ```
//! use flatcut::flat::{self, Limits};
//! use flatcut::flatten::{FlattenParams, Method};
//! use flatcut::geom::Tolerances;
//! use flatcut::nest::{NestOptions, Stock};
//! use flatcut::pieces::{self, PieceSettings};
//! use flatcut::pipeline::{self, NestGroup};
//!
//! let design = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
//!     .join("../design/examples/cylinder.toml");
//! // Flatten every piece (a cylinder unfolds exactly) and measure its distortion.
//! let params = FlattenParams::new(Method::Isometric);
//! let tol = Tolerances::DEFAULT.with_chord_mm(0.5);
//! let flats = flat::load_flat(&design, &tol, &params, Limits::default(), &mut |_, _, _| {})?;
//! assert!(flats[0].report.delta2_mean < 1e-6);
//! // Pattern pieces with a 10 mm seam allowance.
//! let settings = PieceSettings { seam_mm: Some(10.0), ..PieceSettings::default() };
//! let pieces = pieces::build_pieces(&flats, &settings)?;
//! // Two of each on 600 × 400 mm sheets.
//! let groups: Vec<NestGroup> = pieces.iter().map(|p| NestGroup::from_piece(p, 2, false)).collect();
//! let stock = Stock::Sheets { width: 600.0, height: 400.0, max_sheets: None };
//! let layout = pipeline::nest_groups(&groups, stock, &NestOptions::DEFAULT, &mut |_| {})?;
//! // The first sheet as a drag-knife job.
//! let profile = flatcut::gcode::Profile::knife();
//! let plan = flatcut::gcode::plan(&layout.sheets[0], &profile, &Default::default())?;
//! // Two pieces of 188.5 × 80 mm (2π·30 × 80) plus 10 mm allowance all round: over 1,200 mm of cut.
//! assert!(plan.summary().cut_length_mm > 1200.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Start reading at [`run`], then [`pipeline`].
#![warn(missing_docs)]

pub mod check;
pub mod dart_drawing;
pub mod dart_lines;
pub mod darting;
pub mod despiking;
pub mod error;
pub mod flat;
pub mod flat_piece;
pub mod flattening;
pub mod inspect;
pub mod inspect_figures;
pub mod inspect_step;
pub mod material;
pub mod mirrored;
pub mod nesting;
pub mod notch_points;
mod obj_vertex;
pub mod outline_edges;
pub mod piece_build;
pub mod pieces;
pub mod pipeline;
pub mod plot;
pub mod project;
pub mod run;
pub mod sanity;
pub mod splitting;

pub use flatcut_darts as darts;
pub use flatcut_design as design;
pub use flatcut_flatten as flatten;
pub use flatcut_gcode as gcode;
pub use flatcut_geom as geom;
pub use flatcut_grbl as grbl;
pub use flatcut_mesh as mesh;
pub use flatcut_nest as nest;
pub use flatcut_pattern as pattern;
pub use flatcut_report as report;
pub use flatcut_step as step;
pub use flatcut_surface as surface;
