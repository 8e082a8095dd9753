//! End-to-end tests of flatcut: one test binary with a module tree (architecture rules, the
//! command line, the pipeline against the simulated controller).

mod assembly;
mod dxf;
mod fuzz;
mod hpgl;
mod pipeline;
mod regressions;
mod stream;
mod tidy;
