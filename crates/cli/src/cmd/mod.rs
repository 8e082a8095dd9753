//! One module per subcommand, plus the shared device handling (`device`) and output helpers.

pub mod common;
pub mod device;
pub mod flatten;
pub mod gcode;
pub mod hpgl;
pub mod inspect;
pub mod nest;
pub mod pattern;
pub mod ports;
pub mod report;
pub mod run;
pub mod send;
pub mod serve;
pub mod sim;
