//! Nesting tests on rolls and sheets: no overlaps (checked by jagua-rs and independently by
//! geo's boolean operations), spacing, stock bounds, rotations, grain rules and mirrored pairs,
//! errors on absurd input, the cancel hook and progress, determinism.

mod common;

use common::{
    jagua_collision_free, max_area_outside, max_pair_overlap, min_gap, placed_polygons, rect,
    rect_container,
};
use flatcut_geom::DVec2;
use flatcut_nest::{
    GrainDirections, NestError, NestItem, NestOptions, NestPhase, Rotations, Stock, nest,
};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

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

fn quick() -> NestOptions {
    NestOptions::default().with_max_iters(40).with_samples(30)
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

fn angle_in(a: f64, allowed: &[f64], tol: f64) -> bool {
    allowed.iter().any(|b| {
        let d = (a - b).rem_euclid(TAU);
        d.min(TAU - d) <= tol
    })
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
    let stock = Stock::Sheets {
        width: 200.,
        height: 120.,
        max_sheets: None,
    };
    let r = nest(&items, stock, &quick().with_spacing(2.0), &mut |_| {}).unwrap();
    assert!(r.unplaced.is_empty());
    assert_eq!(r.placed.len(), 11);
    let polys = placed_polygons(&items, &r);
    let gap = min_gap(&polys);
    assert!(gap >= 2.0 * 0.99, "pieces closer than the spacing: {gap}");
    within(&polys, 200., 120., 1.0 * 0.99);
    assert!(max_pair_overlap(&polys) < 1e-6);
    for s in 0..r.sheets {
        assert!(jagua_collision_free(
            &items,
            &r,
            s,
            rect_container(200., 120.),
            1.9,
            |_| None
        ));
    }
    let area: f64 = 6.0 * 1800.0 + 5.0 * 1000.0;
    let expect = 100.0 * area / (r.sheets as f64 * 200. * 120.);
    assert!((r.utilization - expect).abs() < 1e-9);
    assert_eq!(r.sheet_use.len(), r.sheets);
    for p in &r.placed {
        let allowed: &[f64] = if p.item == 0 {
            &[0.0, PI]
        } else {
            &[0.0, FRAC_PI_2, PI, 3.0 * FRAC_PI_2]
        };
        assert!(angle_in(p.placement.rotation, allowed, 1e-3), "{p:?}");
    }
}

#[test]
fn grain_and_mirrored_pairs_on_a_roll() {
    let grain = 0.3;
    let items = vec![NestItem {
        grain_angle: Some(grain),
        mirrored_pair: true,
        ..NestItem::new("quarter", l_shape(), 2)
    }];
    let stock = Stock::Roll {
        width: 150.,
        max_length: None,
    };
    let r = nest(&items, stock, &quick(), &mut |_| {}).unwrap();
    assert_eq!(r.placed.len(), 4);
    assert_eq!(r.placed.iter().filter(|p| p.placement.mirror).count(), 2);
    for p in &r.placed {
        // the grain direction, carried by the placement, runs along ±x
        let g = DVec2::from_angle(grain);
        let d = p.placement.apply(g) - p.placement.apply(DVec2::ZERO);
        assert!(d.y.abs() < 1e-4, "grain not along the roll: {d}");
    }
    let polys = placed_polygons(&items, &r);
    assert!(min_gap(&polys) >= 2.0 * 0.99);
    assert!(max_pair_overlap(&polys) < 1e-6);
    // a mirrored copy is the mirror image: its signed area flips sign before re-orienting
    let m = r.placed.iter().find(|p| p.placement.mirror).unwrap();
    let img: Vec<DVec2> = l_shape().iter().map(|q| m.placement.apply(*q)).collect();
    assert!(flatcut_nest::polygon_area(&img) < 0.0);
}

/// Issue 15: with mirrored pairs the reported roll length is where the pieces end.
#[test]
fn mirrored_pairs_roll_length_is_where_the_pieces_end() {
    let items = vec![NestItem {
        mirrored_pair: true,
        grain_angle: Some(FRAC_PI_2),
        ..NestItem::new("quarter", l_shape(), 3)
    }];
    let r = nest(
        &items,
        Stock::Roll {
            width: 120.,
            max_length: None,
        },
        &quick(),
        &mut |_| {},
    )
    .unwrap();
    let end = placed_polygons(&items, &r)
        .iter()
        .flat_map(|(_, p)| p.iter().map(|q| q.x))
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (r.length - end).abs() < 1e-6,
        "length {} but the pieces end at {end}",
        r.length
    );
    let area = 6.0 * 1800.0;
    assert!((r.utilization - 100.0 * area / (end * 120.0)).abs() < 1e-6);
}

#[test]
fn grain_tolerance_and_one_way_grain() {
    let tol = 5.0f64;
    let items = vec![NestItem {
        grain_angle: Some(0.4),
        grain_directions: GrainDirections::Fixed,
        grain_tolerance_deg: tol,
        ..NestItem::new("panel", l_shape(), 6)
    }];
    let r = nest(
        &items,
        Stock::Roll {
            width: 130.,
            max_length: None,
        },
        &quick(),
        &mut |_| {},
    )
    .unwrap();
    for p in &r.placed {
        let g = p.placement.rotation + 0.4;
        // one way: along +x only, within the tolerance
        assert!(angle_in(g, &[0.0], tol.to_radians() + 1e-4), "{g}");
    }
    assert!(max_pair_overlap(&placed_polygons(&items, &r)) < 1e-6);
}

/// Issue 15: the sail's 2,544 × 823 mm panel with its grain across does not fit a 2,900 × 2,400
/// sheet with the grain along x, and does when the material's grain is "any".
#[test]
fn grain_any_lets_a_panel_turn() {
    let panel = NestItem {
        grain_angle: Some(FRAC_PI_2),
        ..NestItem::new("sail-panel", rect(2544., 823.), 1)
    };
    let sheet = Stock::Sheets {
        width: 2900.,
        height: 2400.,
        max_sheets: None,
    };
    let e = nest(std::slice::from_ref(&panel), sheet, &quick(), &mut |_| {}).unwrap_err();
    assert!(matches!(e, NestError::PieceTooLarge { .. }), "{e}");
    let any = NestItem {
        grain_directions: GrainDirections::Any,
        rotations: Rotations::Quarter,
        ..panel
    };
    let r = nest(std::slice::from_ref(&any), sheet, &quick(), &mut |_| {}).unwrap();
    assert_eq!(r.placed.len(), 1);
    within(&placed_polygons(&[any], &r), 2900., 2400., 0.99);
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
        &quick(),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(r.placed.len(), 2);
    assert_eq!(r.unplaced.len(), 3);
    assert!(r.unplaced.iter().all(|u| u.name == "block"));
}

/// Sheets: as few as the area needs, here two for 8 squares of a quarter sheet each plus one.
#[test]
fn sheets_are_emptied_into_earlier_ones() {
    let items = vec![NestItem::new("tile", rect(48., 48.), 9)];
    let r = nest(
        &items,
        Stock::Sheets {
            width: 100.,
            height: 100.,
            max_sheets: None,
        },
        &quick().with_spacing(1.0),
        &mut |_| {},
    )
    .unwrap();
    assert!(r.unplaced.is_empty());
    assert_eq!(r.sheets, 3, "4 tiles fit a sheet with 1 mm spacing");
    assert_eq!(r.sheet_use.iter().map(|u| u.pieces).sum::<usize>(), 9);
    assert_eq!(r.sheet_use[0].pieces, 4);
}

#[test]
fn deterministic_with_a_seed_whatever_the_thread_count() {
    let items = vec![
        NestItem::new("L", l_shape(), 5),
        NestItem::new("R", rect(30., 30.), 4),
    ];
    let stock = Stock::Roll {
        width: 100.,
        max_length: None,
    };
    let opts = quick().with_seed(7);
    let a = nest(&items, stock, &opts.clone().with_threads(1), &mut |_| {}).unwrap();
    let b = nest(&items, stock, &opts.clone().with_threads(2), &mut |_| {}).unwrap();
    let c = nest(&items, stock, &opts, &mut |_| {}).unwrap();
    assert_eq!(a, b);
    assert_eq!(a, c);
    let d = nest(&items, stock, &opts.with_seed(8), &mut |_| {}).unwrap();
    assert_ne!(a.placed, d.placed, "another seed, another search");
}

/// Issue 14: absurd stocks and options are refused at once with a message, never a panic or
/// a hang.
#[test]
fn absurd_inputs_are_refused_quickly() {
    let items = vec![NestItem::new("R", rect(30., 30.), 2)];
    let t = Instant::now();
    for stock in [
        Stock::Sheets {
            width: 1e308,
            height: 1e308,
            max_sheets: None,
        },
        Stock::Sheets {
            width: 1e9,
            height: 1e9,
            max_sheets: None,
        },
        Stock::Sheets {
            width: f64::NAN,
            height: 10.0,
            max_sheets: None,
        },
        Stock::Roll {
            width: f64::INFINITY,
            max_length: None,
        },
        Stock::Roll {
            width: -5.0,
            max_length: None,
        },
    ] {
        let e = nest(&items, stock, &NestOptions::default(), &mut |_| {}).unwrap_err();
        assert!(matches!(e, NestError::InvalidStock { .. }), "{e}");
    }
    let roll = Stock::Roll {
        width: 100.,
        max_length: None,
    };
    for opts in [
        NestOptions::default().with_spacing(f64::NAN),
        NestOptions::default().with_spacing(-1.0),
        NestOptions::default().with_workers(0),
    ] {
        assert!(nest(&items, roll, &opts, &mut |_| {}).is_err());
    }
    let huge = vec![NestItem::new("R", rect(3., 3.), 1_000_000)];
    let e = nest(&huge, roll, &NestOptions::default(), &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("at most"), "{e}");
    let nan = vec![NestItem::new(
        "bad",
        vec![DVec2::ZERO, DVec2::new(f64::NAN, 1.), DVec2::ONE],
        1,
    )];
    let e = nest(&nan, roll, &NestOptions::default(), &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("bad"), "{e}");
    let far = vec![NestItem::new(
        "far",
        vec![DVec2::ZERO, DVec2::new(1e9, 0.), DVec2::new(1e9, 1.)],
        1,
    )];
    assert!(nest(&far, roll, &NestOptions::default(), &mut |_| {}).is_err());
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
}

/// A zero time budget still returns a feasible layout (the construction) at once; the time
/// limit and the cancel hook stop a search with a huge iteration budget.
#[test]
fn time_limit_and_cancel_are_honoured() {
    let items = vec![
        NestItem::new("L", l_shape(), 12),
        NestItem::new("R", rect(30., 30.), 8),
    ];
    let roll = Stock::Roll {
        width: 110.,
        max_length: None,
    };
    let big = NestOptions::default().with_max_iters(usize::MAX);
    let t = Instant::now();
    let r = nest(
        &items,
        roll,
        &big.clone().with_time_limit(Some(Duration::ZERO)),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(r.placed.len(), 20);
    assert!(t.elapsed() < Duration::from_secs(20));
    let t = Instant::now();
    let r = nest(
        &items,
        roll,
        &big.clone()
            .with_time_limit(Some(Duration::from_millis(700))),
        &mut |_| {},
    )
    .unwrap();
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    assert!(max_pair_overlap(&placed_polygons(&items, &r)) < 1e-6);
    let flag = Arc::new(AtomicBool::new(false));
    let f2 = flag.clone();
    let stopper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(500));
        f2.store(true, Ordering::Relaxed);
    });
    let t = Instant::now();
    let r = nest(&items, roll, &big.with_cancel(flag), &mut |_| {}).unwrap();
    stopper.join().unwrap();
    assert!(r.cancelled);
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    assert_eq!(r.placed.len(), 20);
    assert!(max_pair_overlap(&placed_polygons(&items, &r)) < 1e-6);
}

#[test]
fn progress_reports_every_phase_in_order() {
    let items = vec![NestItem::new("L", l_shape(), 8)];
    let mut phases = Vec::new();
    let mut fractions = Vec::new();
    nest(
        &items,
        Stock::Roll {
            width: 100.,
            max_length: None,
        },
        &NestOptions::default().with_max_iters(300).with_samples(30),
        &mut |p| {
            if phases.last() != Some(&p.phase) {
                phases.push(p.phase);
            }
            fractions.push(p.budget_used);
        },
    )
    .unwrap();
    assert_eq!(phases.first(), Some(&NestPhase::Construct));
    assert!(phases.contains(&NestPhase::Explore), "{phases:?}");
    assert!(fractions.windows(2).all(|w| w[1] >= w[0]));
    assert!(fractions.iter().all(|f| (0.0..=1.0).contains(f)));
    let mut phases = Vec::new();
    nest(
        &items,
        Stock::Sheets {
            width: 100.,
            height: 100.,
            max_sheets: None,
        },
        &quick(),
        &mut |p| phases.push(p.phase),
    )
    .unwrap();
    assert_eq!(phases.first(), Some(&NestPhase::Construct));
    assert_eq!(phases.last(), Some(&NestPhase::Done));
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
    let r = nest(
        &items,
        Stock::Roll {
            width: 200.,
            max_length: None,
        },
        &quick(),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(r.placed.len(), 7);
    let polys = placed_polygons(&items, &r);
    assert!(min_gap(&polys) >= 2.0 * 0.99);
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
/// roll is then the square's diagonal, longer than either side, and the roll must still take it.
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
        &quick(),
        &mut |_| {},
    )
    .expect("a 500 mm square turned 45° (707 mm across) fits a 914 mm roll");
    assert!(r.unplaced.is_empty());
    let diag = 500.0 * std::f64::consts::SQRT_2;
    assert!(
        r.length > diag - 1.0 && r.length < diag + 5.0,
        "used length {}",
        r.length
    );
    assert!(max_area_outside(&placed_polygons(&items, &r), &rect(r.length + 1.0, 914.), 0) < 1e-6);
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
