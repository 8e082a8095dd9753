//! `flatcut send JOB.gcode`: streams a G-code job to a GRBL controller, or to the embedded
//! simulator when no `--port` is given, and prints what happened.

use std::path::PathBuf;
use std::process::ExitCode;

use super::device::{StreamArgs, StreamOutcome, stream_file};

/// Arguments of `flatcut send`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The job: G-code, or HP-GL with `--protocol hpgl`.
    #[arg(value_name = "JOB")]
    pub job: PathBuf,
    #[command(flatten)]
    pub stream: StreamArgs,
    /// grbl (G-code, character counting) or hpgl (HP-GL with the profile's flow control).
    #[arg(long, default_value = "grbl", value_parser = ["grbl", "hpgl"])]
    pub protocol: String,
    /// The machine's profile. With `--protocol hpgl`: the plotter's (vinyl, pen-hpgl or a
    /// .toml; default vinyl). With G-code and no `--port`: the embedded simulator is the
    /// machine it describes (pen, knife, laser or a .toml: rates, acceleration, work area),
    /// instead of GRBL's defaults (200 mm of travel on each axis).
    #[arg(long, value_name = "NAME|FILE")]
    pub profile: Option<String>,
    /// Stream a laser job (its header says it needs `$32=1`) to a controller with `$32=0`.
    #[arg(long)]
    pub force: bool,
}

/// Runs `flatcut send`.
pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    if a.protocol == "hpgl" {
        let s = &a.stream;
        return super::hpgl::send(
            &a.job,
            a.profile.as_deref().unwrap_or("vinyl"),
            s.port.as_deref(),
            s.sim_trace.as_deref(),
        );
    }
    let mut stream = a.stream.clone();
    stream.force_laser |= a.force;
    if let Some(p) = &a.profile {
        let profile = flatcut::gcode::Profile::resolve(p)?;
        stream.sim_machine = Some(super::device::select::machine(&profile));
        stream.sim_laser |= profile.kind == flatcut::gcode::ToolKind::Laser;
    }
    let out = stream_file(&a.job, &stream)?;
    // A closed stdout (`flatcut send … | head`) ends the command normally.
    crate::outln!("{}", summary(&out));
    Ok(ExitCode::SUCCESS)
}

/// Parses a whole `flatcut ...` command line (argument 0 is the program name), for scripts and
/// tests that drive the command line in process without depending on clap themselves.
pub fn parse_command_line<I, T>(argv: I) -> Result<crate::Cli, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    <crate::Cli as clap::Parser>::try_parse_from(argv)
}

/// A few lines saying what the send did: lines, time, bytes, link use, final state.
pub fn summary(out: &StreamOutcome) -> String {
    let r = &out.report;
    let mut s = format!(
        "sent {} line(s){}{} to GRBL {} in {:.1} s (streaming {:.1} s, estimated motion {:.1} s)",
        r.lines_sent,
        if r.preamble_lines > 0 {
            format!(" + {} resume preamble line(s)", r.preamble_lines)
        } else {
            String::new()
        },
        if r.previously_done > 0 {
            format!(" ({} done in earlier runs)", r.previously_done)
        } else {
            String::new()
        },
        r.version,
        r.total_time.as_secs_f64(),
        r.stream_time.as_secs_f64(),
        r.estimated_time,
    );
    s.push_str(&format!(
        "\n{} bytes, link utilisation {:.0}% at {} baud, at most {} of {} RX bytes in flight, {} planner blocks",
        r.stream_bytes,
        100.0 * out.link_utilisation(),
        out.baud,
        r.max_in_flight_bytes,
        r.rx_size,
        r.planner_blocks,
    ));
    if r.checked {
        s.push_str("\ncheck mode ($C) pass: every line accepted before cutting");
    }
    match r.final_position {
        Some([x, y, z]) => s.push_str(&format!(
            "\nstate: idle, job complete at work position X{x:.3} Y{y:.3} Z{z:.3}"
        )),
        None => s.push_str("\nstate: idle, job complete"),
    }
    if let (Some(st), Some(trace)) = (&out.sim_stats, &out.sim_trace) {
        s.push_str(&format!(
            "\nsimulator: {} motion segment(s), {:.1} s simulated, {} line(s) received, {} error(s), {} byte(s) lost to RX overflow",
            trace.len(),
            out.sim_time.unwrap_or(0.0),
            st.lines_received,
            st.errors,
            st.bytes_dropped_overflow,
        ));
    }
    for n in &r.notices {
        s.push_str(&format!("\nnote: {n}"));
    }
    s.push_str(&format!("\njournal: {}", out.journal.display()));
    s
}
