//! HP-GL end to end on the bench drawing (../shared/bench/plotter, 300 paths): `flatcut hpgl`
//! writes it; ezhpgl (a third-party HP-GL interpreter) and the simulated plotter's own
//! interpreter agree on every pen-down move; streamed to the simulated plotter over a
//! pseudo-terminal, the pen trace lies within 0.05 mm of the drawing and no byte is lost.

use std::path::Path;
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use flatcut::geom::DVec2;
use flatcut_firmware_sim::hpgl::{HpglPtySim, Interpreter, PlotterConfig};
use flatcut_grbl::hpgl::{HpglFlow, HpglStreamOptions, stream_hpgl};

use crate::dxf::python_with;
use crate::pipeline::{root, run_cli};

/// The bench drawing as SVG, made by its generator (needs only Python's standard library).
fn bench_drawing(dir: &Path) -> Option<std::path::PathBuf> {
    let gen_script = root().join("../shared/bench/plotter/generate_drawing.py");
    if !gen_script.exists() {
        eprintln!(
            "SKIPPED: {} not found (../shared beside the repository)",
            gen_script.display()
        );
        return None;
    }
    let py = python_with("math")?;
    let out = dir.join("drawing.svg");
    let ok = Command::new(py)
        .arg(&gen_script)
        .arg(&out)
        .arg("12345")
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "the bench drawing generator failed");
    Some(out)
}

fn dist_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

#[test]
fn bench_drawing_as_hpgl_agrees_with_ezhpgl_and_the_plotter_traces_it() {
    let dir = tempfile::tempdir().unwrap();
    let Some(svg) = bench_drawing(dir.path()) else {
        return;
    };
    // pen-hpgl with a table for the 400 × 300 mm drawing
    let profile = std::fs::read_to_string(root().join("crates/gcode/profiles/pen-hpgl.toml"))
        .unwrap()
        .replace(
            "work_area_mm = [400.0, 270.0]",
            "work_area_mm = [420.0, 320.0]",
        );
    let prof = dir.path().join("pen-a3.toml");
    std::fs::write(&prof, profile).unwrap();
    let plt = dir.path().join("drawing.plt");
    run_cli(&[
        "hpgl",
        svg.to_str().unwrap(),
        "--profile",
        prof.to_str().unwrap(),
        "-o",
        plt.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&plt).unwrap();
    // Our reference interpreter (the plotter model's own).
    let mut ours = Interpreter::default();
    for c in text.split(';') {
        ours.execute(c);
    }
    // The third-party one.
    if let Some(py) = python_with("ezhpgl") {
        let out = Command::new(py)
            .arg(root().join("tools/hpgl/check_ezhpgl.py"))
            .arg(&plt)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let mut theirs = Vec::new();
        for pl in v["polylines"].as_array().unwrap() {
            let pts: Vec<[f64; 2]> = pl
                .as_array()
                .unwrap()
                .iter()
                .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
                .collect();
            theirs.extend(pts.windows(2).map(|w| (w[0], w[1])));
        }
        assert_eq!(theirs.len(), ours.trace.len(), "pen-down moves");
        let mut worst = 0.0f64;
        for (t, o) in theirs.iter().zip(&ours.trace) {
            for (p, q) in [(t.0, o.from), (t.1, o.to)] {
                worst = worst.max((p[0] - q[0]).hypot(p[1] - q[1]));
            }
        }
        eprintln!(
            "ezhpgl and the plotter model: {} pen-down moves, largest disagreement {worst:.2e} mm ({})",
            theirs.len(),
            v["completeness"]
        );
        assert!(worst < 1e-9, "{worst}");
    }
    // Closed loop: stream to the simulated plotter, compare its trace with the drawing.
    let baud = 115_200;
    let sim = HpglPtySim::spawn(PlotterConfig::default(), baud, 50.0).unwrap();
    let mut port = flatcut_grbl::open_port(&sim.path().display().to_string(), baud).unwrap();
    let opts = HpglStreamOptions::new(HpglFlow::XonXoff, true, baud);
    let report = stream_hpgl(
        &mut port,
        text.as_bytes(),
        &opts,
        &AtomicBool::new(false),
        &mut |_| {},
    )
    .unwrap();
    assert!(sim.wait_idle(Duration::from_secs(120)));
    let (trace, st) = sim.stop();
    assert_eq!(st.bytes_lost, 0);
    assert_eq!(trace.len(), ours.trace.len());
    let drawing = flatcut::pattern::svg::read_svg(
        &std::fs::read_to_string(&svg).unwrap(),
        "drawing.svg",
        0.005,
        &flatcut::pattern::ColourTable::default(),
    )
    .unwrap()
    .drawing;
    let segs: Vec<(DVec2, DVec2)> = drawing
        .strokes
        .iter()
        .flat_map(|s| {
            let mut p = s.points.clone();
            if s.closed {
                p.push(p[0]);
            }
            p.windows(2).map(|w| (w[0], w[1])).collect::<Vec<_>>()
        })
        .collect();
    let mut worst = 0.0f64;
    for t in &trace {
        for k in 0..=4 {
            let f = k as f64 / 4.0;
            let p = DVec2::new(
                t.from[0] + (t.to[0] - t.from[0]) * f,
                t.from[1] + (t.to[1] - t.from[1]) * f,
            );
            let d = segs
                .iter()
                .map(|(a, b)| dist_to_segment(p, *a, *b))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
    }
    eprintln!(
        "HP-GL plotter trace: {} segments, deviation from the drawing at most {worst:.4} mm; {} bytes streamed, high-water {} of 512, {} queries, XOFF {}",
        trace.len(),
        report.bytes_sent,
        st.high_water,
        report.queries,
        st.xoff_sent
    );
    assert!(
        worst < 0.05,
        "the plotter drew {worst} mm away from the drawing"
    );
    // The command line streams too (embedded plotter).
    let small = dir.path().join("small.plt");
    std::fs::write(
        &small,
        "IN;SP1;PU400,400;PD800,400,800,800,400,800,400,400;PU0,0;SP0;\n",
    )
    .unwrap();
    run_cli(&[
        "send",
        small.to_str().unwrap(),
        "--protocol",
        "hpgl",
        "--profile",
        "pen-hpgl",
    ]);
}
