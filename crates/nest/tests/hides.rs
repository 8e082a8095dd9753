//! Nesting on leather hides: every piece inside its hide and off every defect, quality zones
//! respected, grain kept along the hide's direction field, checked independently (geo's boolean
//! operations) and by jagua-rs; the Baldacci et al. (2014) Scarpa instance placed on its hides.

mod common;

use common::{
    geo_poly, hide_container, jagua_collision_free, max_area_inside, max_area_outside,
    max_pair_overlap, placed_polygons, rect,
};
use flatcut_geom::DVec2;
use flatcut_nest::{
    GrainDirections, Hide, NestItem, NestOptions, NestResult, QualityZone, Rotations, load_scarpa,
    nest_hides,
};
use geo::{Area, BooleanOps, BoundingRect, Intersects};

fn scarpa_path() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/instances/Scarpa.json"
    )
    .to_string()
}

/// An irregular hide: a blunt octagon 600 × 400 mm with two defects and two graded zones.
fn test_hide() -> Hide {
    let outline = vec![
        DVec2::new(60., 0.),
        DVec2::new(540., 10.),
        DVec2::new(600., 80.),
        DVec2::new(590., 330.),
        DVec2::new(520., 400.),
        DVec2::new(80., 390.),
        DVec2::new(0., 320.),
        DVec2::new(10., 70.),
    ];
    let mut h = Hide::new("test-hide", outline);
    h.defects = vec![
        vec![
            DVec2::new(200., 150.),
            DVec2::new(240., 150.),
            DVec2::new(240., 230.),
            DVec2::new(200., 230.),
        ],
        vec![
            DVec2::new(420., 280.),
            DVec2::new(460., 300.),
            DVec2::new(430., 330.),
        ],
    ];
    h.zones = vec![
        QualityZone {
            grade: 2,
            outline: vec![
                DVec2::new(0., 0.),
                DVec2::new(300., 0.),
                DVec2::new(300., 90.),
                DVec2::new(0., 90.),
            ],
        },
        QualityZone {
            grade: 4,
            outline: vec![
                DVec2::new(450., 0.),
                DVec2::new(600., 0.),
                DVec2::new(600., 400.),
                DVec2::new(450., 400.),
            ],
        },
    ];
    h
}

/// Independent check of a hide layout: pieces inside the outline, off the defects, out of
/// zones graded worse than they accept, not overlapping each other.
fn check_hide_layout(items: &[NestItem], hides: &[Hide], r: &NestResult) {
    let polys = placed_polygons(items, r);
    // pairs whose boxes meet, then their exact overlap
    let boxes: Vec<_> = polys
        .iter()
        .map(|(_, p)| geo_poly(p).bounding_rect().unwrap())
        .collect();
    let mut worst: f64 = 0.0;
    for i in 0..polys.len() {
        for j in i + 1..polys.len() {
            if polys[i].0 == polys[j].0 && boxes[i].intersects(&boxes[j]) {
                let a = geo_poly(&polys[i].1).intersection(&geo_poly(&polys[j].1));
                worst = worst.max(a.unsigned_area());
            }
        }
    }
    assert!(worst < 1e-3, "two pieces overlap by {worst} mm²");
    if polys.len() < 60 {
        assert!(max_pair_overlap(&polys) < 1e-3);
    }
    for (h, hide) in hides.iter().enumerate() {
        let out = max_area_outside(&polys, &hide.outline, h);
        assert!(
            out < 1e-3,
            "a piece sticks out of {} by {out} mm²",
            hide.name
        );
        for d in &hide.defects {
            let on = max_area_inside(&polys, d, h);
            assert!(
                on < 1e-3,
                "a piece covers a defect of {} by {on} mm²",
                hide.name
            );
        }
        for z in &hide.zones {
            let zone = geo_poly(&z.outline);
            for (k, p) in r.placed.iter().enumerate().filter(|(_, p)| p.sheet == h) {
                let accepts = items[p.item].quality.unwrap_or(u32::MAX);
                if z.grade > accepts {
                    let a = geo_poly(&polys[k].1).intersection(&zone).unsigned_area();
                    assert!(
                        a < 1e-3,
                        "`{}` (accepts grade {accepts}) lies {a} mm² on a grade-{} zone",
                        items[p.item].name,
                        z.grade
                    );
                }
            }
        }
        let q = |item: usize| {
            Some(10usize.saturating_sub(items[item].quality.map_or(10, |q| q as usize)))
        };
        assert!(
            jagua_collision_free(items, r, h, hide_container(hide), 0.0, q),
            "jagua-rs finds a collision on {}",
            hide.name
        );
    }
}

#[test]
fn pieces_keep_off_defects_and_worse_zones() {
    let hide = test_hide();
    let items = vec![
        NestItem {
            rotations: Rotations::Free,
            quality: Some(1),
            ..NestItem::new("vamp", rect(90., 50.), 6)
        },
        NestItem {
            rotations: Rotations::Quarter,
            quality: Some(4),
            ..NestItem::new("lining", rect(60., 40.), 12)
        },
    ];
    let opts = NestOptions::default()
        .with_spacing(0.0)
        .with_max_iters(60)
        .with_samples(30);
    let r = nest_hides(&items, std::slice::from_ref(&hide), &opts, &mut |_| {}).unwrap();
    assert!(r.unplaced.is_empty(), "{:?}", r.unplaced);
    check_hide_layout(&items, std::slice::from_ref(&hide), &r);
    // yield = piece area / (outline − defects)
    let u = &r.sheet_use[0];
    let usable = geo_poly(&hide.outline).unsigned_area()
        - hide
            .defects
            .iter()
            .map(|d| geo_poly(d).unsigned_area())
            .sum::<f64>();
    assert!((u.usable_area - usable).abs() < 1e-6 * usable);
    let area = 6.0 * 4500.0 + 12.0 * 2400.0;
    assert!((u.yield_pct - 100.0 * area / usable).abs() < 1e-6);
}

#[test]
fn what_does_not_fit_is_reported_per_piece() {
    let hide = test_hide();
    let items = vec![NestItem {
        quality: Some(1),
        ..NestItem::new("panel", rect(150., 150.), 9)
    }];
    let opts = NestOptions::default()
        .with_spacing(0.0)
        .with_max_iters(20)
        .with_samples(30);
    let r = nest_hides(&items, std::slice::from_ref(&hide), &opts, &mut |_| {}).unwrap();
    assert!(!r.unplaced.is_empty() && !r.placed.is_empty());
    assert_eq!(r.placed.len() + r.unplaced.len(), 9);
    assert!(r.unplaced.iter().all(|u| u.name == "panel"));
    check_hide_layout(&items, std::slice::from_ref(&hide), &r);
}

/// A slanted backbone: every grain-constrained piece lies along it within the tolerance.
#[test]
fn grain_follows_the_hide_direction_field() {
    let mut hide = Hide::new("slanted", rect(700., 500.));
    let dir = 30f64.to_radians();
    hide.directions = vec![vec![
        DVec2::new(50., 50.),
        DVec2::new(50., 50.) + 700.0 * DVec2::from_angle(dir),
    ]];
    let tol = 3.0;
    let items = vec![NestItem {
        grain_angle: Some(0.0),
        grain_directions: GrainDirections::Reversible,
        grain_tolerance_deg: tol,
        ..NestItem::new("strap", rect(120., 30.), 10)
    }];
    let opts = NestOptions::default()
        .with_spacing(1.0)
        .with_max_iters(40)
        .with_samples(30);
    let r = nest_hides(&items, std::slice::from_ref(&hide), &opts, &mut |_| {}).unwrap();
    assert!(r.unplaced.is_empty());
    for p in &r.placed {
        let g = p.placement.rotation; // grain along the piece's x axis
        let d = (g - dir).rem_euclid(std::f64::consts::PI);
        let off = d.min(std::f64::consts::PI - d).to_degrees();
        assert!(off <= tol + 0.05, "grain {:.2}° off the backbone", off);
    }
    check_hide_layout(&items, std::slice::from_ref(&hide), &r);
}

/// Baldacci et al. (2014), "Algorithms for nesting with defects", Discrete Applied Mathematics
/// 163: the Scarpa instance (4 shoe parts × 60, two hides). Short budget: checks validity, not
/// yield (the yields at 60 s are in the README's benchmark table).
#[test]
fn scarpa_on_its_hides() {
    let text = std::fs::read_to_string(scarpa_path())
        .unwrap_or_else(|e| panic!("Scarpa instance missing at {}: {e}", scarpa_path()));
    let (items, hides) = load_scarpa(&text).unwrap();
    assert_eq!(items.len(), 4);
    assert_eq!(items.iter().map(|i| i.quantity).sum::<usize>(), 240);
    assert_eq!(hides.len(), 2);
    assert_eq!(hides[0].defects.len(), 33);
    // levels 1..3 of the file: grades 4..2; pieces of base 2 accept grade 3, of base 3 grade 2
    assert_eq!(
        items.iter().map(|i| i.quality).collect::<Vec<_>>(),
        vec![Some(3), Some(2), Some(3), Some(3)]
    );
    let opts = NestOptions::default().with_spacing(0.0).with_max_iters(10);
    let r = nest_hides(&items, &hides, &opts, &mut |_| {}).unwrap();
    eprintln!(
        "Scarpa: {} placed, {} unplaced; yields {:?}",
        r.placed.len(),
        r.unplaced.len(),
        r.sheet_use
            .iter()
            .map(|u| format!("{}: {:.1} %", u.name, u.yield_pct))
            .collect::<Vec<_>>()
    );
    assert!(r.placed.len() >= 200, "{}", r.placed.len());
    check_hide_layout(&items, &hides, &r);
}
