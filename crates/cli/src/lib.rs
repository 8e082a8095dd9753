//! The `flatcut` command line: argument parsing, files, terminal output and serial devices.
//!
//! **Architecture invariant:** this is the only crate that writes the user's output files, talks to
//! the terminal, reads environment variables and opens serial ports on the user's behalf (the
//! libraries read the input files they are given), and the only one that uses `anyhow`. Every
//! command is a thin layer over the `flatcut` facade and the device library `flatcut-device`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub mod cmd;
pub mod output;
pub mod stdout;
pub mod stop;
pub mod values;

/// flatcut — from 3D designs to flat cutting patterns, and on to the cutter.
#[derive(Debug, Parser)]
#[command(name = "flatcut", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The commands. Each takes negative numbers as values (`--seam -5` reaches the value's own
/// check instead of being read as a flag `-5`).
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Describe a design or mesh file: pieces, area, bounding box, curvature, developability.
    #[command(allow_negative_numbers = true)]
    Inspect(cmd::inspect::Args),
    /// Flatten a design or mesh to the plane; writes an OBJ with the 2D map as `vt` (mm).
    #[command(allow_negative_numbers = true)]
    Flatten(cmd::flatten::Args),
    /// Distortion report of flattened OBJs (or of a design, flattened first): JSON, SVG, PNG, HTML.
    #[command(allow_negative_numbers = true)]
    Report(cmd::report::Args),
    /// Pattern piece(s) from a design or flattened OBJ: SVG in true mm, optional DXF.
    #[command(allow_negative_numbers = true)]
    Pattern(cmd::pattern::Args),
    /// Nest pattern pieces on sheets, a roll or leather hides (or a benchmark instance).
    #[command(allow_negative_numbers = true)]
    Nest(cmd::nest::Args),
    /// G-code for a pen plotter, drag knife or laser from a pattern SVG, design or flattened OBJ.
    #[command(allow_negative_numbers = true)]
    Gcode(cmd::gcode::Args),
    /// HP-GL/1 for a vinyl cutter or pen plotter from a pattern SVG/DXF, design or flattened OBJ.
    #[command(allow_negative_numbers = true)]
    Hpgl(cmd::hpgl::Args),
    /// List serial ports.
    #[command(allow_negative_numbers = true)]
    Ports(cmd::ports::Args),
    /// Stream a G-code job to a GRBL controller, or HP-GL to a plotter (default: embedded simulators).
    #[command(allow_negative_numbers = true)]
    Send(cmd::send::Args),
    /// Run the simulated GRBL controller on a pseudo-terminal.
    #[command(allow_negative_numbers = true)]
    Sim(cmd::sim::Args),
    /// The whole job: design → flatten → report → pattern → nest → G-code → send.
    #[command(allow_negative_numbers = true)]
    Run(cmd::run::Args),
    /// The workbench in the browser: draw style lines on the 3D form, see the pieces and their
    /// strain live, nest, and run the cutter.
    #[command(allow_negative_numbers = true)]
    Serve(cmd::serve::Args),
}

/// Exit code when a material or distortion limit is exceeded.
pub const EXIT_LIMIT: u8 = 3;

/// Runs the command line with the process arguments, with the process's signal handler in
/// place (see [`install_signal_handler`]).
pub fn main() -> ExitCode {
    if let Err(e) = install_signal_handler() {
        eprintln!("warning: Ctrl-C will neither pause a job nor clean up temporary files: {e}");
    }
    exit_code(run(Cli::parse()))
}

/// Installs the binary's handler of SIGINT, SIGTERM and SIGHUP: during a send the first is a
/// feed hold and a question (an abort without a terminal), otherwise the command's temporary
/// outputs are removed and the process ends (130). Only the binary installs it (an embedding
/// program owns its signals); a program that drives the command line in process and wants the
/// same calls it once.
pub fn install_signal_handler() -> Result<(), String> {
    cmd::device::install_handler()
}

/// The process's exit code for a command's result, printing an error; a closed standard
/// output (the reader of `… | head` has gone) is a normal end.
pub fn exit_code(result: anyhow::Result<ExitCode>) -> ExitCode {
    match result {
        Ok(code) => code,
        Err(e) if stdout::is_closed(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprint!("{}", error_report(&e));
            if e.chain()
                .any(|c| c.downcast_ref::<stop::Interrupted>().is_some())
            {
                return ExitCode::from(stop::EXIT_INTERRUPTED);
            }
            // Limits that no dart could meet are a limit exceeded, not a failure to run.
            let out_of_limits = e.chain().any(|c| {
                c.downcast_ref::<flatcut::pipeline::PipelineError>()
                    .is_some_and(flatcut::darting::is_out_of_limits)
            });
            if out_of_limits {
                ExitCode::from(EXIT_LIMIT)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// The error and its causes, one a line; a cause whose text the lines above already say (a
/// typed error that prints its source, wrapped by a context that repeats it) is not repeated.
pub fn error_report(e: &anyhow::Error) -> String {
    let mut said = format!("error: {e}\n");
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !said.contains(&text) {
            said.push_str(&format!("  caused by: {text}\n"));
        }
    }
    if let Some(h) = hint(e) {
        said.push_str(&format!("  hint: {h}\n"));
    }
    said
}

/// The command-line flag that answers an error the libraries state as a condition.
fn hint(e: &anyhow::Error) -> Option<&'static str> {
    use flatcut::flatten::FlattenError;
    e.chain()
        .find_map(|c| c.downcast_ref::<FlattenError>())
        .and_then(|f| match f {
            FlattenError::NotDevelopable { .. } => {
                Some("--method isometric flattens any surface with the least distortion")
            }
            _ => None,
        })
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
        Command::Serve(a) => cmd::serve::run(a),
    }
}

#[cfg(test)]
mod tests {
    #[derive(Debug)]
    struct Inner;
    impl std::fmt::Display for Inner {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("vertex 3 is out of range")
        }
    }
    impl std::error::Error for Inner {}

    #[derive(Debug)]
    struct Outer(Inner);
    impl std::fmt::Display for Outer {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "piece 'a': {}", self.0)
        }
    }
    impl std::error::Error for Outer {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn a_cause_already_said_is_not_repeated() {
        let e = anyhow::Error::from(Outer(Inner)).context("cannot flatten d.toml");
        assert_eq!(
            super::error_report(&e),
            "error: cannot flatten d.toml\n  caused by: piece 'a': vertex 3 is out of range\n"
        );
    }

    #[test]
    fn a_surface_that_is_not_developable_is_told_the_method_that_flattens_it() {
        let e = anyhow::Error::new(flatcut::flatten::FlattenError::NotDevelopable {
            max_abs_k: 1e-3,
            angle_defect: 0.1,
            vertex: 3,
            x: 0.0,
            y: 0.0,
            z: 0.0,
        })
        .context("cannot flatten d.toml");
        let r = super::error_report(&e);
        assert!(
            r.ends_with(
                "  hint: --method isometric flattens any surface with the least distortion\n"
            ),
            "{r}"
        );
        let other = anyhow::Error::from(Outer(Inner));
        assert!(!super::error_report(&other).contains("hint"));
    }
}
