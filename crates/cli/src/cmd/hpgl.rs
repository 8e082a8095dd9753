//! `flatcut hpgl FILE --profile vinyl|pen-hpgl|P.toml -o job.plt`: HP-GL/1 for a vinyl cutter
//! or pen plotter; and the HP-GL side of `flatcut send JOB.plt --protocol hpgl`, which streams
//! to a port with the profile's flow control or, without `--port`, to the embedded plotter.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use anyhow::Context as _;
use flatcut::gcode::{FlowControl, GcodeOptions, Profile};
use flatcut_device::grbl::hpgl::{HpglFlow, HpglStreamOptions, stream_hpgl};
use flatcut_device::sim::hpgl::{HpglPtySim, PlotterConfig};

use super::common::{self, FlattenArgs, PieceArgs};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A pattern or layout SVG or DXF, a design, or a flattened OBJ.
    pub file: PathBuf,
    /// vinyl, pen-hpgl, or a machine profile (.toml) with an `[hpgl]` section.
    #[arg(long, default_value = "vinyl")]
    pub profile: String,
    /// The HP-GL job to write.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub piece: PieceArgs,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let profile = Profile::resolve(&a.profile)?;
    let colours = profile.colour_table()?;
    let drawing = if common::is_pattern_file(&a.file) {
        common::read_pattern_file(&a.file, flatcut::plot::READ_CHORD_MM, &colours)?
    } else {
        super::gcode::load_drawing(&a.file, &a.piece, &a.flatten, &colours)?
    };
    let plan = flatcut::gcode::plan(&drawing, &profile, &GcodeOptions::default())
        .with_context(|| format!("cannot plan {}", a.file.display()))?;
    let text = plan.to_hpgl()?;
    common::write(&a.output, text.as_bytes())?;
    let s = plan.hpgl_summary()?;
    crate::outln!(
        "{} bytes, {} commands, {} paths; cut {:.1} mm, travel {:.1} mm",
        s.bytes,
        s.commands,
        s.paths,
        s.cut_length_mm,
        s.travel_length_mm
    );
    crate::outln!(
        "{}",
        flatcut::gcode::Marking::of(&profile, &drawing).note(&profile.name)
    );
    crate::outln!("wrote {}", a.output.display());
    Ok(ExitCode::SUCCESS)
}

/// The plotter the embedded simulator models: the profile's flow control and queries, a
/// 512-byte buffer (smaller than any job worth streaming).
pub fn embedded_plotter(buffer_query: bool) -> PlotterConfig {
    PlotterConfig {
        buffer_query,
        ..PlotterConfig::default()
    }
}

/// Streams an HP-GL job as the profile says, to `port` or to the embedded plotter (whose pen
/// trace is written as SVG to `trace` when given).
pub fn send(
    job: &Path,
    profile: &str,
    port: Option<&str>,
    trace: Option<&Path>,
) -> anyhow::Result<ExitCode> {
    let profile = Profile::resolve(profile)?;
    let h = profile.hpgl.clone().with_context(|| {
        format!(
            "profile {} has no [hpgl] section: use vinyl, pen-hpgl or a profile with one",
            profile.name
        )
    })?;
    let bytes = std::fs::read(job).with_context(|| format!("cannot read {}", job.display()))?;
    let flow = match h.flow_control {
        FlowControl::XonXoff => HpglFlow::XonXoff,
        FlowControl::RtsCts => HpglFlow::RtsCts,
    };
    let opts = HpglStreamOptions::new(flow, h.buffer_query, h.baud);
    let sim = match port {
        Some(_) => None,
        None => Some(HpglPtySim::spawn(
            embedded_plotter(h.buffer_query),
            h.baud,
            20.0,
        )?),
    };
    let path = match (&sim, port) {
        (Some(s), _) => s.path().display().to_string(),
        (None, Some(p)) => p.to_string(),
        (None, None) => unreachable!("a port or the simulator"),
    };
    let mut t = flatcut_device::grbl::open_port(&path, h.baud)?;
    if flow == HpglFlow::RtsCts {
        t.port_mut()
            .set_flow_control(serialport::FlowControl::Hardware)
            .with_context(|| format!("cannot enable RTS/CTS on {path}"))?;
    }
    let abort = AtomicBool::new(false);
    let bar = indicatif::ProgressBar::new(bytes.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("sending {bar:30} {pos}/{len} bytes {msg}")
            .expect("valid template"),
    );
    let report = stream_hpgl(&mut t, &bytes, &opts, &abort, &mut |p| {
        bar.set_position(p.sent as u64);
        bar.set_message(if p.held {
            "(device buffer full: XOFF)"
        } else {
            ""
        });
    })
    .with_context(|| format!("streaming {} to {path}", job.display()))?;
    bar.finish_and_clear();
    crate::outln!(
        "sent {} bytes to {path} in {:.1} s: XOFF {} / XON {}, {} buffer queries{}",
        report.bytes_sent,
        report.elapsed_s,
        report.xoff_received,
        report.xon_received,
        report.queries,
        report
            .device_buffer
            .map(|b| format!(", device buffer {b} bytes"))
            .unwrap_or_default()
    );
    if let Some(sim) = sim {
        sim.wait_idle(Duration::from_secs(600));
        let (tr, st) = sim.stop();
        crate::outln!(
            "plotter: {} pen-down segments, {} bytes received, {} lost, buffer high-water {} bytes",
            tr.len(),
            st.bytes_received,
            st.bytes_lost,
            st.high_water
        );
        if let Some(p) = trace {
            common::write(p, flatcut_device::sim::hpgl::trace_svg(&tr).as_bytes())?;
        }
        anyhow::ensure!(
            st.bytes_lost == 0,
            "the plotter lost {} bytes",
            st.bytes_lost
        );
    }
    Ok(ExitCode::SUCCESS)
}
