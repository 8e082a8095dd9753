//! `flatcut nest` from the command line: a benchmark instance with `--instance --json`, and
//! pieces on a leather hide with `--hide` (outline, defect, graded zone), checked on the SVG
//! the command writes.

use std::path::{Path, PathBuf};

use clap::Parser as _;
use flatcut::geom::DVec2;
use flatcut::pattern::Layer;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run_cli(args: &[&str]) -> std::process::ExitCode {
    let cli =
        flatcut_cli::Cli::try_parse_from(std::iter::once("flatcut").chain(args.iter().copied()))
            .expect("valid arguments");
    flatcut_cli::run(cli).expect("the command succeeds")
}

fn cut_outlines(svg: &Path) -> Vec<Vec<DVec2>> {
    let text = std::fs::read_to_string(svg).unwrap();
    let d = flatcut::pattern::svg::read_svg(
        &text,
        "layout",
        0.01,
        &flatcut::pattern::ColourTable::default(),
    )
    .unwrap()
    .drawing;
    d.strokes
        .into_iter()
        .filter(|s| s.closed && s.layer == Layer::Cut)
        .map(|s| s.points)
        .collect()
}

#[test]
fn nest_instance_writes_every_piece_and_the_json_line() {
    let out = tempfile::tempdir().unwrap();
    let svg = out.path().join("dagli.svg");
    let inst = root().join("crates/nest/tests/data/instances/dagli.json");
    let code = run_cli(&[
        "nest",
        "--instance",
        inst.to_str().unwrap(),
        "--iters",
        "20",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    // dagli: 30 pieces on a strip 60 high
    let pieces = cut_outlines(&svg);
    assert_eq!(pieces.len(), 30);
    for p in &pieces {
        for q in p {
            assert!(q.y > -1e-3 && q.y < 60.0 + 1e-3, "{q}");
        }
    }
    let r = flatcut::nest::NestResult {
        placed: vec![],
        unplaced: vec![],
        utilization: 81.5,
        length: 62.25,
        sheets: 1,
        sheet_use: vec![],
        baseline_utilization: 0.0,
        baseline_length: 0.0,
        iterations: 0,
        cancelled: false,
    };
    let line = flatcut_cli::cmd::nest::instance_json("dagli", &r, 1.5, 2);
    assert_eq!(
        line,
        r#"{"name":"dagli","utilization":81.5,"length":62.25,"time_s":1.5,"seed":2}"#
    );
}

#[test]
fn nest_on_a_hide_keeps_off_its_defect_and_worse_zone() {
    let out = tempfile::tempdir().unwrap();
    let hide = out.path().join("hide.json");
    std::fs::write(
        &hide,
        r#"{"outline": [[0,0],[300,0],[320,200],[0,220]],
            "defects": [[[100,80],[140,80],[140,120],[100,120]]],
            "zones": [{"grade": 3, "outline": [[200,0],[300,0],[320,200],[200,200]]}]}"#,
    )
    .unwrap();
    let pieces = out.path().join("pieces.svg");
    std::fs::write(
        &pieces,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="60mm" viewBox="0 0 100 60">
             <path d="M 0 0 L 50 0 L 50 30 L 0 30 Z" stroke="red" fill="none"/>
           </svg>"#,
    )
    .unwrap();
    let layout = out.path().join("layout.svg");
    let code = run_cli(&[
        "nest",
        pieces.to_str().unwrap(),
        "--hide",
        hide.to_str().unwrap(),
        "--quantity",
        "12",
        "--quality",
        "1",
        "--spacing",
        "1",
        "--iters",
        "30",
        "-o",
        layout.to_str().unwrap(),
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let placed = cut_outlines(&layout);
    assert_eq!(placed.len(), 12);
    let outline = [
        DVec2::new(0., 0.),
        DVec2::new(300., 0.),
        DVec2::new(320., 200.),
        DVec2::new(0., 220.),
    ];
    for p in &placed {
        for q in p {
            assert!(
                flatcut::pattern::poly::contains(&outline, *q)
                    || outline.iter().any(|o| o.distance(*q) < 1e-6)
            );
            // off the defect and the grade-3 zone (first quality only)
            assert!(
                !(q.x > 100.0 + 1e-6
                    && q.x < 140.0 - 1e-6
                    && q.y > 80.0 + 1e-6
                    && q.y < 120.0 - 1e-6)
            );
            assert!(q.x <= 200.0 + 1e-6, "{q} on the grade-3 zone");
        }
    }
}

/// `--mirrored-pairs` names each copy by its side, `#<n>L` as drawn and `#<n>R` mirrored, and
/// the R copies are the mirror images: a scalene wedge's edges run the other way round.
#[test]
fn mirrored_pairs_name_their_copies_left_and_right() {
    let out = tempfile::tempdir().unwrap();
    let wedge = out.path().join("wedge.svg");
    std::fs::write(
        &wedge,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm" viewBox="0 0 200 100"><path id="wedge" d="M 10 90 L 130 90 L 10 40 Z" stroke="#ff0000" fill="none"/></svg>"##,
    )
    .unwrap();
    let svg = out.path().join("layout.svg");
    let code = run_cli(&[
        "nest",
        wedge.to_str().unwrap(),
        "--sheet",
        "600x400",
        "--mirrored-pairs",
        "--quantity",
        "2",
        "--iters",
        "3",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    let d = flatcut::pattern::svg::read_svg(
        &text,
        "layout",
        0.01,
        &flatcut::pattern::ColourTable::default(),
    )
    .unwrap()
    .drawing;
    let mut ids: Vec<&str> = d.strokes.iter().map(|s| s.id.as_str()).collect();
    ids.sort_unstable();
    assert_eq!(ids, ["wedge#1L", "wedge#1R", "wedge#2L", "wedge#2R"]);
    // The edge lengths (120, 130, 50 mm) counter-clockwise from the longest: one order for the
    // copies as drawn, the other for their mirror images.
    let turn = |pts: &[DVec2]| -> Vec<i64> {
        let mut p = pts.to_vec();
        if p.first()
            .zip(p.last())
            .is_some_and(|(a, b)| a.distance(*b) < 1e-6)
        {
            p.pop();
        }
        let area: f64 = (0..p.len())
            .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
            .sum();
        if area < 0.0 {
            p.reverse();
        }
        let mut e: Vec<i64> = (0..p.len())
            .map(|i| p[i].distance(p[(i + 1) % p.len()]).round() as i64)
            .collect();
        let k = (0..e.len()).max_by_key(|&i| e[i]).unwrap();
        e.rotate_left(k);
        e
    };
    let side = |suffix: &str| -> Vec<Vec<i64>> {
        d.strokes
            .iter()
            .filter(|s| s.id.ends_with(suffix))
            .map(|s| turn(&s.points))
            .collect()
    };
    let (l, r) = (side("L"), side("R"));
    assert_eq!(l.len(), 2);
    assert_eq!(l[0], l[1]);
    let mirrored = vec![l[0][0], l[0][2], l[0][1]];
    assert_eq!(r, [mirrored.clone(), mirrored]);
    assert_ne!(l[0], r[0]);
}
