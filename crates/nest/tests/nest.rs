//! Nesting tests: no overlaps (checked without the engine), spacing, stock bounds, rotations,
//! grain and mirrored pairs, errors, determinism, and a benchmark instance against the
//! bottom-left-fill baseline.

mod common;

use flatcut_geom::DVec2;
use flatcut_nest::{
    NestError, NestItem, NestOptions, Rotations, Stock, load_bench_instance, load_scarpa_items,
    nest,
};
use std::f64::consts::{FRAC_PI_2, PI};

fn rect(w: f64, h: f64) -> Vec<DVec2> {
    vec![
        DVec2::ZERO,
        DVec2::new(w, 0.),
        DVec2::new(w, h),
        DVec2::new(0., h),
    ]
}

fn l_shape() -> Vec<DVec2> {
    vec![
        DVec2::ZERO,
        DVec2::new(60., 0.),
        DVec2::new(60., 20.),
        DVec2::new(20., 20.),
        DVec2::new(20., 50.),
        DVec2::new(0., 50.),
    ]
}

fn within(polys: &[(usize, Vec<DVec2>)], w: f64, h: f64, margin: f64) {
    for (_, p) in polys {
        for q in p {
            assert!(
                q.x >= margin - 1e-3
                    && q.y >= margin - 1e-3
                    && q.x <= w - margin + 1e-3
                    && q.y <= h - margin + 1e-3,
                "{q} outside"
            );
        }
    }
}

#[test]
fn sheets_no_overlap_spacing_and_bounds() {
    let items = vec![
        NestItem::new("L", l_shape(), 6),
        NestItem {
            rotations: Rotations::Quarter,
            ..NestItem::new("R", rect(40., 25.), 5)
        },
    ];
    let opts = NestOptions::default()
        .with_spacing(2.0)
        .with_max_iters(10)
        .with_samples(150);
    let r = nest(
        &items,
        Stock::Sheets {
            width: 200.,
            height: 120.,
            max_sheets: None,
        },
        &opts,
        &mut |_| {},
    )
    .unwrap();
    assert!(r.unplaced.is_empty());
    assert_eq!(r.placed.len(), 11);
    let polys = common::placed_polygons(&items, &r);
    let gap = common::min_gap(&polys);
    assert!(gap >= 2.0 * 0.99, "pieces closer than the spacing: {gap}");
    within(&polys, 200., 120., 1.0 * 0.99);
    let area: f64 = 6.0 * 1800.0 + 5.0 * 1000.0;
    let expect = 100.0 * area / (r.sheets as f64 * 200. * 120.);
    assert!((r.utilization - expect).abs() < 1e-9);
    // rotations only from the allowed set
    for p in &r.placed {
        let a = p.placement.rotation.rem_euclid(std::f64::consts::TAU);
        let allowed: &[f64] = if p.item == 0 {
            &[0.0, std::f64::consts::PI]
        } else {
            &[0.0, FRAC_PI_2, PI, 3.0 * FRAC_PI_2]
        };
        assert!(
            allowed
                .iter()
                .any(|b| (a - b).abs() < 1e-3 || (a - b - std::f64::consts::TAU).abs() < 1e-3),
            "{a}"
        );
    }
}

#[test]
fn grain_and_mirrored_pairs() {
    let grain = 0.3;
    let items = vec![NestItem {
        grain_angle: Some(grain),
        mirrored_pair: true,
        ..NestItem::new("quarter", l_shape(), 2)
    }];
    let opts = NestOptions::default().with_max_iters(5).with_samples(100);
    let r = nest(
        &items,
        Stock::Roll {
            width: 150.,
            max_length: None,
        },
        &opts,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(r.placed.len(), 4);
    assert_eq!(r.placed.iter().filter(|p| p.placement.mirror).count(), 2);
    for p in &r.placed {
        // the grain direction, carried by the placement, runs along ±x
        let g = DVec2::from_angle(grain);
        let d = p.placement.apply(g) - p.placement.apply(DVec2::ZERO);
        assert!(d.y.abs() < 1e-4, "grain not along the roll: {d}");
    }
    let polys = common::placed_polygons(&items, &r);
    assert!(common::min_gap(&polys) >= 2.0 * 0.99);
}

#[test]
fn piece_larger_than_the_sheet_is_named() {
    let items = vec![
        NestItem::new("small", rect(10., 10.), 1),
        NestItem::new("front-panel", rect(300., 50.), 1),
    ];
    let e = nest(
        &items,
        Stock::Sheets {
            width: 200.,
            height: 200.,
            max_sheets: None,
        },
        &NestOptions::default(),
        &mut |_| {},
    )
    .unwrap_err();
    assert!(matches!(e, NestError::PieceTooLarge { .. }));
    assert!(e.to_string().contains("front-panel"), "{e}");
}

#[test]
fn full_sheets_report_unplaced() {
    let items = vec![NestItem::new("block", rect(90., 90.), 5)];
    let r = nest(
        &items,
        Stock::Sheets {
            width: 200.,
            height: 100.,
            max_sheets: Some(1),
        },
        &NestOptions::default().with_max_iters(2),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(r.placed.len(), 2);
    assert_eq!(r.unplaced.len(), 3);
    assert!(r.unplaced.iter().all(|u| u.name == "block"));
}

#[test]
fn deterministic_with_a_seed() {
    let items = vec![
        NestItem::new("L", l_shape(), 5),
        NestItem::new("R", rect(30., 30.), 4),
    ];
    let opts = NestOptions::default()
        .with_max_iters(8)
        .with_samples(80)
        .with_seed(7);
    let a = nest(
        &items,
        Stock::Roll {
            width: 100.,
            max_length: None,
        },
        &opts,
        &mut |_| {},
    )
    .unwrap();
    let b = nest(
        &items,
        Stock::Roll {
            width: 100.,
            max_length: None,
        },
        &opts,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(a, b);
}

#[test]
fn trousers_beats_or_matches_bottom_left_fill() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/bench/nesting/instances/trousers.json"
    );
    let Ok(text) = std::fs::read_to_string(path) else {
        panic!("benchmark instance missing at {path}");
    };
    let inst = load_bench_instance(&text).unwrap();
    assert_eq!(inst.items.iter().map(|i| i.quantity).sum::<usize>(), 64);
    assert!((inst.total_area() - 17206.5).abs() < 1.0);
    let opts = NestOptions::default()
        .with_spacing(0.0)
        .with_max_iters(15)
        .with_samples(120);
    let mut calls = 0;
    let r = nest(
        &inst.items,
        Stock::Roll {
            width: inst.strip_height,
            max_length: None,
        },
        &opts,
        &mut |_| calls += 1,
    )
    .unwrap();
    assert!(r.unplaced.is_empty());
    assert_eq!(
        calls,
        r.iterations + 1,
        "progress after the construction and every iteration"
    );
    assert!(r.utilization >= r.baseline_utilization - 1e-9);
    assert!(r.utilization > 60.0, "{}", r.utilization);
    let polys = common::placed_polygons(&inst.items, &r);
    assert!(common::min_gap(&polys) >= -1e-9);
    // zero spacing: touching allowed, overlap not — check area overlap via the independent test
    // with a small tolerance for the engine's f32 coordinates
    within(&polys, f64::INFINITY, inst.strip_height, -1e-2);
}

#[test]
fn shoe_set_on_sheets_beats_or_matches_bottom_left_fill() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/bench/nesting/instances/Scarpa.json"
    );
    let text =
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("shoe set missing at {path}: {e}"));
    // 4 parts × 2 pairs × left/right = 16 pieces on 600 × 400 mm sheets, 2 mm knife clearance
    let items = load_scarpa_items(&text, 2).unwrap();
    assert_eq!(items.len(), 4);
    let opts = NestOptions {
        free_rotation_steps: 8,
        ..NestOptions::default().with_max_iters(12).with_samples(100)
    };
    let stock = Stock::Sheets {
        width: 600.,
        height: 400.,
        max_sheets: None,
    };
    let r = nest(&items, stock, &opts, &mut |_| {}).unwrap();
    assert!(r.unplaced.is_empty());
    assert_eq!(r.placed.len(), 16);
    assert_eq!(r.placed.iter().filter(|p| p.placement.mirror).count(), 8);
    assert!(r.utilization >= r.baseline_utilization - 1e-9);
    let polys = common::placed_polygons(&items, &r);
    assert!(common::min_gap(&polys) >= 2.0 * 0.99);
    within(&polys, 600., 400., 0.99);
    eprintln!(
        "shoe set: {} sheets, utilization {:.2} % (bottom-left fill {:.2} %)",
        r.sheets, r.utilization, r.baseline_utilization
    );
}

#[test]
fn pattern_pieces_nest_and_export_to_svg() {
    use flatcut_pattern::{Piece, PieceInput, PieceOptions, svg};
    let mut a = PieceInput::new("vamp", l_shape());
    a.grain = Some((DVec2::new(5., 5.), DVec2::new(5., 45.)));
    let pieces = vec![
        Piece::build(&a, &PieceOptions::default()).unwrap(),
        Piece::build(
            &PieceInput::new("tongue", rect(30., 60.)),
            &PieceOptions::default(),
        )
        .unwrap(),
    ];
    let items = vec![
        NestItem::from_piece(&pieces[0], 2, true),
        NestItem::from_piece(&pieces[1], 3, false),
    ];
    let opts = NestOptions::default().with_max_iters(5).with_samples(100);
    let r = nest(
        &items,
        Stock::Roll {
            width: 200.,
            max_length: None,
        },
        &opts,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(r.placed.len(), 7);
    let polys = common::placed_polygons(&items, &r);
    assert!(common::min_gap(&polys) >= 2.0 * 0.99);
    // the vamp's grain (drawn along +y) runs along the roll after placement
    for p in r.placed.iter().filter(|p| p.item == 0) {
        let d = p.placement.apply(DVec2::Y) - p.placement.apply(DVec2::ZERO);
        assert!(d.y.abs() < 1e-4, "{d}");
    }
    let placed = flatcut_nest::placed_pieces(&pieces, &r, 0);
    assert_eq!(placed.len(), 7);
    let text = svg::write_pieces(&placed, Some(DVec2::new(r.length.ceil() + 10.0, 200.)));
    for id in ["vamp-1-cut", "vamp-4-cut", "tongue-3-cut"] {
        assert!(text.contains(&format!("id=\"{id}\"")), "{id}");
    }
}

/// A square piece whose grain runs diagonally must turn 45° on a roll: its length along the
/// roll is then the square's diagonal, longer than either side, and the roll must still take it
/// (a roll working length sized by the bounding box's longer side refused it).
#[test]
fn grain_turned_piece_fits_a_roll() {
    let items = vec![NestItem {
        grain_angle: Some(std::f64::consts::FRAC_PI_4),
        ..NestItem::new("panel", rect(500., 500.), 1)
    }];
    let r = nest(
        &items,
        Stock::Roll {
            width: 914.,
            max_length: None,
        },
        &NestOptions::default().with_max_iters(4).with_samples(40),
        &mut |_| {},
    )
    .expect("a 500 mm square turned 45° (707 mm across) fits a 914 mm roll");
    assert!(r.unplaced.is_empty());
    // the diagonal plus at most the default spacing
    let diag = 500.0 * std::f64::consts::SQRT_2;
    assert!(
        r.length > diag - 1.0 && r.length < diag + 5.0,
        "used length {}",
        r.length
    );
}

/// A 10 mm square.
fn square10() -> Vec<DVec2> {
    vec![
        DVec2::ZERO,
        DVec2::new(10.0, 0.0),
        DVec2::new(10.0, 10.0),
        DVec2::new(0.0, 10.0),
    ]
}

#[test]
fn stock_beyond_what_the_engine_resolves_and_too_many_copies_are_refused() {
    let square = square10();
    let items = [NestItem::new("sq", square.clone(), 2)];
    for stock in [
        Stock::Sheets {
            width: 1e9,
            height: 1e9,
            max_sheets: None,
        },
        Stock::Roll {
            width: 1e308,
            max_length: None,
        },
    ] {
        let e = nest(&items, stock, &NestOptions::DEFAULT, &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("larger than the 1e5 mm"), "{e}");
    }
    let many = [NestItem::new("sq", square, 1_000_000)];
    let e = nest(
        &many,
        Stock::Roll {
            width: 1000.0,
            max_length: None,
        },
        &NestOptions::DEFAULT,
        &mut |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("1000000 piece copies"), "{e}");
}

#[test]
fn a_spacing_that_leaves_no_room_on_the_stock_is_named() {
    let e = nest(
        &[NestItem::new("sq", square10(), 1)],
        Stock::Sheets {
            width: 100.0,
            height: 40.0,
            max_sheets: None,
        },
        &NestOptions::DEFAULT.with_spacing(20.0),
        &mut |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("spacing of 20 mm from the edges leaves no room"),
        "{e}"
    );
}
