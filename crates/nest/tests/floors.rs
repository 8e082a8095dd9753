//! Regression floors: on every ESICUP strip instance in tests/data/instances (source and
//! licence in its manifest.json), a fixed iteration budget (deterministic, not a timing test)
//! must reach at least the utilization recorded here, with every layout checked overlap-free by
//! geo's boolean operations.
//!
//! The floors are the figures measured when they were recorded minus one percentage point (the
//! search is deterministic per seed; the margin absorbs floating-point differences between
//! platforms). Raise them when the search gets better; never lower them to make a change pass.

mod common;

use common::{max_area_outside, max_pair_overlap, placed_polygons, rect};
use flatcut_nest::{NestOptions, Stock, load_bench_instance, nest};

/// Separation iterations per instance: a few seconds each in the test profile.
const ITERS: usize = 300;

/// (instance, utilization floor in percent).
const FLOORS: [(&str, f64); 7] = [
    ("trousers", 84.9),
    ("shirts", 78.2),
    ("swim", 64.6),
    ("dagli", 76.6),
    ("mao", 71.5),
    ("marques", 79.5),
    ("albano", 78.3),
];

fn check(name: &str, floor: f64) {
    let path = format!(
        "{}/tests/data/instances/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("instance missing at {path}: {e}"));
    let inst = load_bench_instance(&text).unwrap();
    let opts = NestOptions::default()
        .with_spacing(0.0)
        .with_seed(0)
        .with_max_iters(ITERS);
    let r = nest(
        &inst.items,
        Stock::Roll {
            width: inst.strip_height,
            max_length: None,
        },
        &opts,
        &mut |_| {},
    )
    .unwrap();
    eprintln!("{name}: {:.4} % after {ITERS} iterations", r.utilization);
    assert_eq!(
        r.placed.len(),
        inst.items.iter().map(|i| i.quantity).sum::<usize>()
    );
    assert!(
        r.utilization >= floor,
        "{name}: utilization {:.3} % fell below the recorded floor {floor} %",
        r.utilization
    );
    let polys = placed_polygons(&inst.items, &r);
    // zero spacing: pieces may touch; overlap is measured as area, relative to the strip
    let tol = 1e-6 * inst.strip_height * r.length;
    let overlap = max_pair_overlap(&polys);
    assert!(overlap < tol, "{name}: pieces overlap by {overlap}");
    let out = max_area_outside(&polys, &rect(r.length + 1e-9, inst.strip_height), 0);
    assert!(
        out < tol,
        "{name}: a piece sticks out of the strip by {out}"
    );
}

#[test]
fn floor_trousers() {
    check(FLOORS[0].0, FLOORS[0].1);
}

#[test]
fn floor_shirts() {
    check(FLOORS[1].0, FLOORS[1].1);
}

#[test]
fn floor_swim() {
    check(FLOORS[2].0, FLOORS[2].1);
}

#[test]
fn floor_dagli() {
    check(FLOORS[3].0, FLOORS[3].1);
}

#[test]
fn floor_mao() {
    check(FLOORS[4].0, FLOORS[4].1);
}

#[test]
fn floor_marques() {
    check(FLOORS[5].0, FLOORS[5].1);
}

#[test]
fn floor_albano() {
    check(FLOORS[6].0, FLOORS[6].1);
}
