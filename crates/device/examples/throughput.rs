//! Throughput benchmark against firmware-sim over a pseudo-terminal.
//!
//! 1. Instant motion at 115200 baud: how busy the sender keeps the link (job bytes per second
//!    of streaming against baud/10; the target is at least 90 %).
//! 2. Real-time motion on a job of short segments: how often the simulated planner ran dry.
//!
//! Run: `cargo run --release -p flatcut-device --example throughput [lines] [segments] [runs]`
//! (`segments` 0 skips part 2; `runs` repeats part 1, default 5).

use flatcut_firmware_sim::{PtySim, SimConfig};
use flatcut_grbl::{CancelToken, Job, SendOptions, open_port, send_job};
use flatcut_testkit::jobs::zigzag;
use std::time::Duration;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let lines = args.first().copied().unwrap_or(5000);
    let segments = args.get(1).copied().unwrap_or(400);
    let runs = args.get(2).copied().unwrap_or(5).max(1);
    let baud = 115_200u32;
    let opts = SendOptions::default().with_banner_timeout(Duration::from_millis(500));

    // 1. Link utilisation with instant motion, `runs` times (another build may share the CPU),
    // journaling every acknowledged line as `flatcut send` does.
    let job = Job::parse(&zigzag(lines, 0.012, 5.0, 3000.0)).expect("job");
    let journal = std::env::temp_dir().join(format!("throughput-{}.journal", std::process::id()));
    let journaled = opts.clone().with_journal(&journal);
    let cap = f64::from(baud) / 10.0;
    let mut busy = Vec::new();
    for run in 1..=runs {
        let sim = PtySim::spawn(
            SimConfig::default()
                .with_baud(baud)
                .with_instant_motion(true),
        )
        .expect("spawn firmware-sim");
        let mut port = open_port(sim.path().to_str().expect("utf-8 path"), baud).expect("open pty");
        let rep = send_job(
            &mut port,
            &job,
            &journaled,
            &mut |_| {},
            &CancelToken::new(),
        )
        .expect("send");
        drop(port);
        let stats = sim.stop().stats;
        let secs = rep.stream_time.as_secs_f64();
        let rate = rep.stream_bytes as f64 / secs;
        busy.push(100.0 * rate / cap);
        println!(
            "run {run}: instant motion, {lines} lines, {} bytes in {secs:.2} s: {rate:.0} B/s of {cap:.0} B/s = {:.1} % busy; max in flight {} of {} (device max RX fill {}, {} bytes dropped)",
            rep.stream_bytes,
            100.0 * rate / cap,
            rep.max_in_flight_bytes,
            rep.rx_size,
            stats.max_rx_fill,
            stats.bytes_dropped_overflow
        );
    }
    let min = busy.iter().copied().fold(f64::INFINITY, f64::min);
    let mean = busy.iter().sum::<f64>() / busy.len() as f64;
    println!("link busy over {runs} runs: min {min:.1} %, mean {mean:.1} % (target >= 90 %)");
    let _ = std::fs::remove_file(&journal);
    if segments == 0 {
        return;
    }

    // 2. Planner starvation with real motion on short segments.
    let job = Job::parse(&zigzag(segments, 0.5, 0.5, 1500.0)).expect("job");
    let sim = PtySim::spawn(SimConfig::default().with_baud(baud)).expect("spawn firmware-sim");
    let mut port = open_port(sim.path().to_str().expect("utf-8 path"), baud).expect("open pty");
    let rep = send_job(&mut port, &job, &opts, &mut |_| {}, &CancelToken::new()).expect("send");
    drop(port);
    let r = sim.stop();
    println!(
        "real motion, {segments} segments of {:.2} mm at F1500: sim time {:.2} s (estimate {:.2} s)",
        job.total_length / segments as f64,
        r.sim_time,
        rep.estimated_time
    );
    println!(
        "  planner starvations: {}, max planner fill {} blocks",
        r.stats.planner_starvations, r.stats.max_planner_fill
    );
}
