//! Tests of the device layer: the status line, fault flags, the journal path and the simulated bed.

use super::args::{DEFAULT_SIM_SPEED, StreamArgs};
use super::status::status_text;
use flatcut_device::Target;
use flatcut_device::grbl::driver::Phase;
use flatcut_device::grbl::{Job, MachineState, Progress, SendOptions};
use std::path::PathBuf;
use std::time::Duration;

fn progress() -> Progress {
    Progress {
        phase: Phase::Streaming,
        lines_acked: 40,
        lines_done: 30,
        lines_total: 100,
        last_acked: None,
        length_done: 250.0,
        length_total: 1000.0,
        eta: Some(Duration::from_secs(125)),
        state: Some(MachineState::Run),
        position: Some([10.0, 5.25, -0.5]),
        elapsed: Duration::from_secs(3),
        bytes_written: 1234,
        holding: false,
        paused_at: None,
        notices: Vec::new(),
    }
}

#[test]
fn status_line_shows_path_fraction_eta_state_and_position() {
    let p = progress();
    assert_eq!(
        status_text(&p, Some(1.0)),
        " 25.0% of path · ETA 2:05 · Run · X10.000 Y5.250 Z-0.500"
    );
    // The embedded simulator at 50x: 125 s of machine time is 2.5 s, shown rounded.
    assert!(status_text(&p, Some(1.0 / 50.0)).contains("ETA 0:03"));
    // Instant motion: no ETA at all.
    assert!(!status_text(&p, None).contains("ETA"));
    let held = Progress {
        holding: true,
        state: Some(MachineState::Hold { complete: true }),
        ..p
    };
    assert!(status_text(&held, Some(1.0)).contains("Hold:0 (held)"));
    // The job's own pause says so, naming the line once.
    let paused = Progress {
        state: Some(MachineState::Hold { complete: true }),
        paused_at: Some(flatcut_device::grbl::driver::LineRef {
            index: 6,
            source_line: 7,
            text: "M0".into(),
        }),
        ..progress()
    };
    assert_eq!(
        status_text(&paused, Some(1.0)),
        " 25.0% of path · ETA 2:05 · Hold:0 · paused by the job at line 7 (`M0`) · X10.000 Y5.250 Z-0.500"
    );
}

#[test]
fn journal_path_and_sim_bed() {
    let a = StreamArgs::default();
    assert_eq!(
        a.journal_path("out/job-1.gcode"),
        PathBuf::from("out/job-1.gcode.journal")
    );
    assert_eq!(
        a.clone().with_journal("j").journal_path("x.gcode"),
        PathBuf::from("j")
    );
    assert!(a.uses_sim() && !a.clone().with_port("/dev/ttyUSB0").uses_sim());
    // The simulated machine is GRBL's, or the profile's: it does not grow to fit a job.
    let Ok(Target::Simulator(s)) = a.target() else {
        panic!("not the simulator")
    };
    let cfg = s.config().unwrap();
    assert!(cfg.settings.is_empty());
    assert_eq!(cfg.time_scale, DEFAULT_SIM_SPEED);
    let bad = StreamArgs {
        sim_speed: 0.0,
        ..StreamArgs::default()
    };
    assert!(bad.target().unwrap().check().is_err());
}

/// A terminal output that blocks at its first write until released (a terminal paused with
/// Ctrl-S), keeping what it is given.
struct PausedTerminal {
    release: std::sync::mpsc::Receiver<()>,
    released: bool,
    out: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
}

impl std::io::Write for PausedTerminal {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        if !self.released {
            let _ = self.release.recv();
            self.released = true;
        }
        self.out
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Issue 14, item 5: a terminal that stops reading (Ctrl-S) does not stop the stream: the
/// whole job streams to firmware-sim while the view's output is blocked (the device never
/// waits for a subscriber), and everything (the feed notice first, the final line last) is
/// printed once the terminal reads again.
#[test]
fn a_paused_terminal_does_not_stall_the_stream() {
    use super::view::View;
    use flatcut_device::{Device, DeviceEvent, JobRequest, SimSetup};
    use std::sync::atomic::AtomicBool;
    use std::sync::{Arc, Mutex};

    let (release, rx) = std::sync::mpsc::channel();
    let out = Arc::new(Mutex::new(Vec::new()));
    let mut view = View {
        bar: indicatif::ProgressBar::hidden(),
        interactive: false,
        plain: true,
        plain_interval: Duration::ZERO,
        notices: true,
        eta_scale: None,
        prompting: Arc::new(AtomicBool::new(false)),
        out: Box::new(PausedTerminal {
            release: rx,
            released: false,
            out: out.clone(),
        }),
        last_plain: std::time::Instant::now(),
        notices_shown: 0,
    };
    // 300 strokes along Y at F3000 on a controller at GRBL's default 500 mm/min.
    let mut text = String::from("G21 G90\n");
    for i in 1..=300 {
        text.push_str(&format!(
            "G1 X{:.3} Y{} F3000\n",
            i as f64 * 0.012,
            (i % 2) * 5
        ));
    }
    let job = Job::parse(&text).unwrap();
    let device = Device::open(Target::Simulator(SimSetup::default().with_instant(true))).unwrap();
    let events = device.subscribe();
    let opts = SendOptions::default().with_banner_timeout(Duration::from_millis(500));
    let handle = device
        .start(JobRequest::new("strokes", job.clone()).with_options(opts))
        .unwrap();
    let watcher = std::thread::spawn(move || {
        while let Some(e) = events.recv() {
            match e {
                DeviceEvent::Progress(p) => view.show(&p),
                DeviceEvent::JobFinished { .. } => break,
                _ => {}
            }
        }
    });
    let rep = handle.wait().unwrap().report;
    let trace = device.close().sim.unwrap().trace;
    assert_eq!(rep.lines_sent, job.len());
    assert_eq!(trace.len(), job.motions().len());
    // Nothing reached the terminal while it was paused.
    assert!(out.lock().unwrap().is_empty());
    release.send(()).unwrap();
    watcher.join().unwrap();
    let printed = String::from_utf8(out.lock().unwrap().clone()).unwrap();
    let lines: Vec<&str> = printed.lines().collect();
    // The notice comes before any line of the stream (only the line of the connection, which
    // the paused terminal held, comes first); ticks the paused terminal missed were dropped,
    // the final one was not.
    let warning = lines.iter().position(|l| {
        l.starts_with(
            "warning: the job asks F3000 (line 2) but the controller's Y max rate ($111) is 500 mm/min",
        )
    });
    let first_of_stream = lines
        .iter()
        .position(|l| !l.starts_with("connecting:") && !l.starts_with("warning:"));
    assert!(warning.is_some() && warning < first_of_stream, "{printed}");
    assert!(lines.len() < 20, "{printed}");
    assert_eq!(
        lines.iter().filter(|l| l.starts_with("warning:")).count(),
        1
    );
    assert!(
        lines.last().unwrap().starts_with("done: line 301/301"),
        "{printed}"
    );
}
