//! End-to-end tests of flatcut: one test binary with a module tree (architecture rules, the
//! command line, the pipeline against the simulated controller).

mod assembly;
mod dxf;
mod hpgl;
mod pipeline;
mod stream;
mod tidy;
