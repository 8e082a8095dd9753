//! The flatcut library facade: the pipeline stages as functions, composing the workspace crates
//! (design → mesh → flattening → report → pattern pieces → nesting → G-code).
//!
//! The glue that needs both worlds lives here: a flattened mesh boundary becomes a 2D pattern
//! piece, so `flatcut-pattern` never learns about meshes. Start reading at [`inspect`] and
//! [`pipeline`].

pub mod inspect;
pub mod pipeline;
pub mod project;

pub use flatcut_design as design;
pub use flatcut_flatten as flatten;
pub use flatcut_gcode as gcode;
pub use flatcut_geom as geom;
pub use flatcut_mesh as mesh;
pub use flatcut_nest as nest;
pub use flatcut_pattern as pattern;
pub use flatcut_report as report;
pub use flatcut_surface as surface;
