//! Runs the nester on a strip-packing benchmark instance and prints one JSON line:
//! `cargo run --release -p flatcut-nest --example nest_bench -- INSTANCE.json SECONDS [SEED [WORKERS]]`
//! (`SECONDS` may be `iters:N` for an iteration budget instead).

use flatcut_nest::{NestOptions, Stock, load_bench_instance, nest};
use std::time::Duration;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: bench INSTANCE.json SECONDS|iters:N [SEED [WORKERS]]");
    let budget = args.get(2).map(String::as_str).unwrap_or("10");
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    let workers: usize = args
        .get(4)
        .and_then(|s| s.parse().ok())
        .unwrap_or(NestOptions::DEFAULT_WORKERS);
    let inst = load_bench_instance(&std::fs::read_to_string(path).expect("read instance"))
        .expect("parse instance");
    let mut opts = NestOptions::default()
        .with_spacing(0.0)
        .with_seed(seed)
        .with_workers(workers);
    if let Some(n) = budget.strip_prefix("iters:") {
        opts = opts.with_max_iters(n.parse().expect("iteration count"));
    } else {
        let secs: f64 = budget.parse().expect("seconds");
        opts = opts
            .with_max_iters(usize::MAX)
            .with_time_limit(Some(Duration::from_secs_f64(secs)));
    }
    let t0 = std::time::Instant::now();
    let verbose = std::env::var_os("NEST_VERBOSE").is_some();
    let r = nest(
        &inst.items,
        Stock::Roll {
            width: inst.strip_height,
            max_length: None,
        },
        &opts,
        &mut |p| {
            if verbose {
                eprintln!(
                    "{:>9} iter {:>6} {:>7.2} s length {:>9.3} utilization {:>6.2} %",
                    p.phase.name(),
                    p.iteration,
                    p.elapsed.as_secs_f64(),
                    p.length,
                    p.utilization
                );
            }
        },
    )
    .expect("nest");
    println!(
        "{{\"name\":\"{}\",\"utilization\":{:.4},\"length\":{:.4},\"time_s\":{:.2},\"seed\":{seed},\"workers\":{workers},\"iterations\":{},\"start_utilization\":{:.4}}}",
        inst.name,
        r.utilization,
        r.length,
        t0.elapsed().as_secs_f64(),
        r.iterations,
        r.baseline_utilization,
    );
}
