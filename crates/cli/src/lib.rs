//! The `flatcut` command line: argument parsing, files, terminal output and serial devices.
//!
//! **Architecture invariant:** this is the only crate that touches the file system, the terminal,
//! environment variables and serial ports on behalf of the user, and the only one that uses
//! `anyhow`. Every command is a thin layer over the `flatcut` facade and `flatcut-grbl`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cmd;

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
}

/// Exit codes: 0 success, 1 error, 2 usage error (clap), 3 a material or distortion limit was exceeded.
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
    }
}
