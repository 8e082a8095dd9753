//! `flatcut hpgl FILE --profile vinyl|pen-hpgl|P.toml -o job.plt`: HP-GL/1 for a vinyl cutter
//! or pen plotter; and the HP-GL side of `flatcut send JOB.plt --protocol hpgl`, which streams
//! to a port with the profile's flow control or, without `--port`, to the embedded plotter.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use flatcut::gcode::{GcodeOptions, Profile};
use flatcut_device::{Device, DeviceEvent, PlotRequest, PlotterSimSetup, Target};

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

/// Streams an HP-GL job as the profile says, to `port` or to the embedded plotter (whose pen
/// trace is written as SVG to `trace` when given): the device library's plotter, as the
/// workbench streams it.
pub fn send(
    job: &Path,
    profile: &str,
    port: Option<&str>,
    trace: Option<&Path>,
) -> anyhow::Result<ExitCode> {
    let profile = Profile::resolve(profile)?;
    let link = flatcut_server::plotters::plotter_link(&profile).map_err(anyhow::Error::msg)?;
    let bytes = std::fs::read(job).with_context(|| format!("cannot read {}", job.display()))?;
    let target = match port {
        Some(p) => Target::Plotter {
            path: p.to_string(),
            link,
        },
        None => Target::PlotterSim(PlotterSimSetup {
            link,
            speed: EMBEDDED_SPEED,
        }),
    };
    let device = Device::open(target)?;
    let path = device.link().to_string();
    let events = device.subscribe();
    let handle = device.start_plot(PlotRequest::new(job.display().to_string(), bytes.clone()))?;
    let bar = indicatif::ProgressBar::new(bytes.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("sending {bar:30} {pos}/{len} bytes {msg}")
            .expect("valid template"),
    );
    while let Some(e) = events.recv() {
        match e {
            DeviceEvent::Plot(p) => {
                bar.set_position(p.bytes_sent as u64);
                bar.set_message(if p.held {
                    "(device buffer full: XOFF)"
                } else {
                    ""
                });
            }
            DeviceEvent::JobFinished { .. } => break,
            _ => {}
        }
    }
    let report = handle
        .wait()
        .with_context(|| format!("streaming {} to {path}", job.display()))?;
    bar.finish_and_clear();
    crate::outln!(
        "sent {} bytes to {path} in {:.1} s: XOFF {} / XON {}, {} buffer queries{}",
        report.report.bytes_sent,
        report.report.elapsed_s,
        report.report.xoff_received,
        report.report.xon_received,
        report.report.queries,
        report
            .report
            .device_buffer
            .map(|b| format!(", device buffer {b} bytes"))
            .unwrap_or_default()
    );
    if let Some(plotter) = device.close().plotter {
        let st = &plotter.stats;
        crate::outln!(
            "plotter: {} pen-down segments, {} bytes received, {} lost, buffer high-water {} bytes",
            plotter.strokes.len(),
            st.bytes_received,
            st.bytes_lost,
            st.high_water
        );
        if let Some(p) = trace {
            common::write(
                p,
                flatcut_device::sim::hpgl::trace_svg(&plotter.strokes).as_bytes(),
            )?;
        }
        anyhow::ensure!(
            st.bytes_lost == 0,
            "the plotter lost {} bytes",
            st.bytes_lost
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The embedded plotter's time scale for `flatcut send --protocol hpgl`.
const EMBEDDED_SPEED: f64 = 20.0;
