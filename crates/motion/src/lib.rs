//! flatcut-motion: how long a GRBL controller takes to run a job, from GRBL 1.1h's own motion
//! model (`planner.c`, `motion_control.c`): per-axis rate and acceleration limits projected on
//! each move, junction speeds by the junction-deviation rule, look-ahead over the whole job
//! (backward and forward passes) and trapezoidal velocity profiles; arcs split into the chords
//! `mc_arc` makes; the step idle delay `$1` at every stop and dwells in whole 50 ms steps.
//!
//! Both the G-code writer's estimate (`flatcut-gcode`) and the sender's ETA (`flatcut-grbl`) call
//! this one model, so `flatcut gcode` and `flatcut send` agree on a job's time.
//!
//! ```
//! use flatcut_motion::{Estimator, Feed, Limits};
//! let mut e = Estimator::new(&Limits { max_rate: [6000.0; 3], ..Limits::GRBL_DEFAULT });
//! // 100 mm at F600 (10 mm/s) with 10 mm/s²: 1 s up, 9 s cruise, 1 s down, then the 25 ms
//! // step idle delay ($1) of the stop.
//! e.segment(0, [0.0; 3], [100.0, 0.0, 0.0], Feed::PerMinute(600.0));
//! assert!((e.total() - 11.025).abs() < 1e-9);
//! ```
//!
//! **Architecture invariant:** no dependency on any workspace crate and no IO: the sender, which
//! must not depend on the G-code writer, and the writer both use it.
#![warn(missing_docs)]

mod arc;
mod estimate;
mod limits;
mod profile;

pub use arc::{ArcChords, FULL_CIRCLE_EPS, N_ARC_CORRECTION, arc_chords, mc_arc};
pub use estimate::{Estimator, Feed};
pub use limits::{Limits, axis_limited};
pub use profile::trapezoid_time;
