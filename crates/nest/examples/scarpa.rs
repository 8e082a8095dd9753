//! Nests the Baldacci et al. (2014) leather instance `Scarpa.json` (4 shoe parts × 60 on two
//! hides with defects and graded zones) and prints the yield per hide as one JSON line:
//! `cargo run --release -p flatcut-nest --example scarpa -- Scarpa.json SECONDS|iters:N [SEED]`.

use flatcut_nest::{NestOptions, load_scarpa, nest_hides};
use std::time::Duration;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: scarpa Scarpa.json SECONDS|iters:N [SEED]");
    let budget = args.get(2).map(String::as_str).unwrap_or("60");
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    let (items, hides) =
        load_scarpa(&std::fs::read_to_string(path).expect("read instance")).expect("parse");
    let mut opts = NestOptions::default().with_spacing(0.0).with_seed(seed);
    if let Some(n) = budget.strip_prefix("iters:") {
        opts = opts.with_max_iters(n.parse().expect("iteration count"));
    } else {
        opts = opts
            .with_max_iters(usize::MAX)
            .with_time_limit(Some(Duration::from_secs_f64(
                budget.parse().expect("seconds"),
            )));
    }
    let t0 = std::time::Instant::now();
    let verbose = std::env::var_os("NEST_VERBOSE").is_some();
    let r = nest_hides(&items, &hides, &opts, &mut |p| {
        if verbose {
            eprintln!(
                "{:>9} iter {:>6} {:>7.2} s hides {} utilization {:>6.2} %",
                p.phase.name(),
                p.iteration,
                p.elapsed.as_secs_f64(),
                p.sheets,
                p.utilization
            );
        }
    })
    .expect("nest");
    let per: Vec<String> = r
        .sheet_use
        .iter()
        .map(|u| {
            format!(
                "{{\"hide\":\"{}\",\"pieces\":{},\"piece_area\":{:.0},\"usable_area\":{:.0},\"yield_pct\":{:.2}}}",
                u.name, u.pieces, u.piece_area, u.usable_area, u.yield_pct
            )
        })
        .collect();
    println!(
        "{{\"placed\":{},\"unplaced\":{},\"hides\":[{}],\"utilization\":{:.2},\"time_s\":{:.1},\"seed\":{seed},\"iterations\":{}}}",
        r.placed.len(),
        r.unplaced.len(),
        per.join(","),
        r.utilization,
        t0.elapsed().as_secs_f64(),
        r.iterations
    );
}
