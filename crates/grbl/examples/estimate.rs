//! The sender's run-time estimate against the simulated controller on virtual time, for any job
//! file and any controller settings: the lines are fed as GRBL's RX buffer frees, so the planner
//! stays full as it does behind a character-counting sender.
//!
//! Run: `cargo run --release -p flatcut-grbl --example estimate -- JOB.gcode [N=VALUE]...`
//! (`N=VALUE` are `$N` settings of the simulated controller and of the estimate, e.g.
//! `110=5000 111=5000 120=400 121=400`; without any, GRBL 1.1h's defaults).

use flatcut_firmware_sim::{Grbl, SimConfig};
use flatcut_grbl::{Job, MachineLimits};
use std::collections::BTreeMap;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: estimate JOB.gcode [N=VALUE]...");
        std::process::exit(2);
    };
    let text = std::fs::read_to_string(&path).expect("read the job");
    let mut settings = BTreeMap::new();
    for a in args {
        let (n, v) = a.split_once('=').expect("N=VALUE");
        settings.insert(
            n.parse::<u16>().expect("N"),
            v.parse::<f64>().expect("VALUE"),
        );
    }
    let limits = MachineLimits::from_settings(&settings);
    let job = Job::parse_with(&text, &limits).expect("parse the job");
    let cfg = SimConfig {
        settings: settings.iter().map(|(n, v)| (*n, *v)).collect(),
        ..SimConfig::default()
    };
    let mut g = Grbl::new(&cfg);
    for l in &job.lines {
        while g.rx_free() < l.text.len() + 1 {
            g.tick(0.001);
        }
        g.receive_all(format!("{}\n", l.text).as_bytes());
    }
    g.run_until_idle(24.0 * 3600.0);
    let sim = g.clock();
    println!(
        "{path}: {} lines, estimate {:.2} s, simulated {sim:.2} s ({:+.2} %), settings {settings:?}",
        job.len(),
        job.total_time,
        100.0 * (job.total_time - sim) / sim
    );
}
