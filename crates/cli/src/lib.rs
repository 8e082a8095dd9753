//! The `flatcut` command line: argument parsing, files, terminal output and serial devices.
//!
//! **Architecture invariant:** this is the only crate that writes the user's output files, talks to
//! the terminal, reads environment variables and opens serial ports on the user's behalf (the
//! libraries read the input files they are given), and the only one that uses `anyhow`. Every
//! command is a thin layer over the `flatcut` facade and `flatcut-grbl`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub mod cmd;

/// flatcut — from 3D designs to flat cutting patterns, and on to the cutter.
#[derive(Debug, Parser)]
#[command(name = "flatcut", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Describe a design or mesh file: pieces, area, bounding box, curvature, developability.
    Inspect(cmd::inspect::Args),
    /// Flatten a design or mesh to the plane; writes an OBJ with the 2D map as `vt` (mm).
    Flatten(cmd::flatten::Args),
    /// Distortion report of flattened OBJs (or of a design, flattened first): JSON, SVG, PNG, HTML.
    Report(cmd::report::Args),
    /// Pattern piece(s) from a design or flattened OBJ: SVG in true mm, optional DXF.
    Pattern(cmd::pattern::Args),
    /// Nest pattern pieces on sheets or a roll.
    Nest(cmd::nest::Args),
    /// G-code for a pen plotter, drag knife or laser from a pattern SVG, design or flattened OBJ.
    Gcode(cmd::gcode::Args),
    /// HP-GL/1 for a vinyl cutter or pen plotter from a pattern SVG/DXF, design or flattened OBJ.
    Hpgl(cmd::hpgl::Args),
    /// List serial ports.
    Ports(cmd::ports::Args),
    /// Stream a G-code job to a GRBL controller, or HP-GL to a plotter (default: embedded simulators).
    Send(cmd::send::Args),
    /// Run the simulated GRBL controller on a pseudo-terminal.
    Sim(cmd::sim::Args),
    /// The whole job: design → flatten → report → pattern → nest → G-code → send.
    Run(cmd::run::Args),
}

/// Exit code when a material or distortion limit is exceeded.
pub const EXIT_LIMIT: u8 = 3;

/// Runs the command line with the process arguments.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}

/// Runs a parsed command.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Flatten(a) => cmd::flatten::run(a),
        Command::Report(a) => cmd::report::run(a),
        Command::Pattern(a) => cmd::pattern::run(a),
        Command::Nest(a) => cmd::nest::run(a),
        Command::Gcode(a) => cmd::gcode::run(a),
        Command::Hpgl(a) => cmd::hpgl::run(a),
        Command::Ports(a) => cmd::ports::run(a),
        Command::Send(a) => cmd::send::run(a),
        Command::Sim(a) => cmd::sim::run(a),
        Command::Run(a) => cmd::run::run(a),
    }
}
