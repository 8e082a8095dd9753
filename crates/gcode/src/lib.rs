//! G-code for pen plotters, drag knives and laser cutters, in the GRBL 1.1 dialect.
//!
//! [`plan()`] turns a [`flatcut_pattern::Drawing`] into a [`Plan`]: strokes mapped into machine
//! coordinates, ordered (engrave, draw, inner cuts, outer cuts; travel minimised by nearest
//! neighbour and 2-opt), compensated (drag-knife blade offset with corner swivels and overcut) and
//! arc-fitted. [`Plan::to_gcode`] writes deterministic text; [`Plan::summary`] estimates run time
//! with GRBL's own motion model (junction deviation and trapezoidal acceleration).
//!
//! **Architecture invariant:** depends on neither the sender (`flatcut-grbl`) nor the simulator:
//! the simulator is the independent check on what this crate writes.
#![warn(missing_docs)]

pub mod arcs;
pub mod cutter;
pub mod emit;
pub mod hpgl;
pub mod knife;
pub mod marking;
pub mod moves;
pub mod order;
pub mod plan;
pub mod profile;
pub mod time;

pub use emit::{GRBL_MAX_LINE, frame_job};
pub use hpgl::{HpglError, HpglSummary};
pub use marking::Marking;
pub use plan::{GcodeError, GcodeOptions, Move, Plan, Summary, Toolpath, plan};
pub use profile::{FlowControl, HpglConfig, Profile, ProfileError, ToolKind};
