//! Runs the nester on a benchmark instance and prints one JSON line:
//! `cargo run --release -p flatcut-nest --example bench -- INSTANCE.json SECONDS [SEED [SAMPLES]]`.

use flatcut_nest::{NestOptions, Stock, load_bench_instance, nest};
use std::time::Duration;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: bench INSTANCE.json SECONDS [SEED]");
    let secs: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    let inst = load_bench_instance(&std::fs::read_to_string(path).expect("read instance"))
        .expect("parse instance");
    let opts = NestOptions::default()
        .with_spacing(0.0)
        .with_seed(seed)
        .with_max_iters(usize::MAX)
        .with_samples(
            args.get(4)
                .and_then(|s| s.parse().ok())
                .unwrap_or(NestOptions::DEFAULT_SAMPLES),
        )
        .with_time_limit(Some(Duration::from_secs_f64(secs)));
    let mut last = 0.0;
    let r = nest(
        &inst.items,
        Stock::Roll {
            width: inst.strip_height,
            max_length: None,
        },
        &opts,
        &mut |p| {
            if p.utilization > last + 0.05 {
                last = p.utilization;
                eprintln!(
                    "iter {:>5}  {:>6.2} s  length {:>9.2}  utilization {:>5.2} %",
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
        "{{\"instance\":\"{}\",\"seconds\":{secs},\"seed\":{seed},\"strip_length\":{:.2},\"utilization\":{:.2},\"blf_length\":{:.2},\"blf_utilization\":{:.2},\"iterations\":{},\"unplaced\":{}}}",
        inst.name,
        r.length,
        r.utilization,
        r.baseline_length,
        r.baseline_utilization,
        r.iterations,
        r.unplaced.len()
    );
}
