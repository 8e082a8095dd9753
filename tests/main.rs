//! End-to-end tests of flatcut: one test binary with a module tree (architecture rules, the
//! command line, the pipeline against the simulated controller, STEP models in).

mod assembly;
mod dart_drawing;
mod darts;
mod despike;
mod dxf;
mod fuzz;
mod genus;
mod guide;
mod hpgl;
mod licences;
mod material;
mod nest;
mod pipeline;
mod readme;
mod regressions;
mod serve;
mod shoe;
mod step;
mod stream;
mod tidy;
