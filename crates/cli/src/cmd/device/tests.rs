//! Tests of the device layer: the status line, fault flags, the journal path and the simulated bed.

use super::display::status_text;
use super::*;
use flatcut_grbl::MachineState;
use flatcut_grbl::Progress;
use flatcut_grbl::driver::Phase;
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
    // A 600 x 150 mm job: the simulated bed grows in X only, to 610 mm.
    let job = Job::parse("G0 X0 Y0\nG1 X600 Y150 F1000\n").unwrap();
    let cfg = sim_config(&job, &a).unwrap();
    assert_eq!(cfg.settings, vec![(130, 610.0)]);
    assert_eq!(cfg.time_scale, DEFAULT_SIM_SPEED);
    let bad = StreamArgs {
        sim_speed: 0.0,
        ..StreamArgs::default()
    };
    assert!(sim_config(&job, &bad).is_err());
}
