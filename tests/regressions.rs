//! The bad inputs of issue 14 (tests/regressions/), one test per item, each named after what it
//! guards: every input gets a clear error naming the file and the element, or is handled as the
//! issue asks, with no panic, no hang and no unbounded allocation.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use flatcut_cli::cmd::send::parse_command_line;

fn corpus(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/regressions")
        .join(name)
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs a command line in process; `Err` carries the whole error report.
fn run(args: &[&str]) -> Result<ExitCode, String> {
    let cli = parse_command_line(std::iter::once("flatcut").chain(args.iter().copied()))
        .map_err(|e| e.to_string())?;
    flatcut_cli::run(cli).map_err(|e| flatcut_cli::error_report(&e))
}

fn err(args: &[&str]) -> String {
    run(args).expect_err("the command is refused")
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn item06_bspline_counts_are_refused_before_any_allocation() {
    let f = corpus("bspline-counts-2e32.toml");
    let e = err(&["inspect", p(&f)]);
    assert!(
        e.contains("bspline-counts-2e32.toml: piece 0 'big'") && e.contains("control points"),
        "{e}"
    );
}

#[test]
fn item06_png_width_and_quantity_are_capped() {
    for args in [
        &["report", "x.obj", "--png", "x.png", "--png-width", "100000"][..],
        &[
            "nest",
            "x.svg",
            "--sheet",
            "600x400",
            "-o",
            "l.svg",
            "--quantity",
            "4294967296",
        ],
        &[
            "nest",
            "x.svg",
            "--sheet",
            "600x400",
            "-o",
            "l.svg",
            "--quantity",
            "0",
        ],
    ] {
        let e = err(args);
        assert!(e.contains("invalid value"), "{args:?}: {e}");
    }
}

#[test]
fn item07_numbers_at_the_command_line_are_refused_by_the_parser() {
    for (args, flag) in [
        (
            &["nest", "x.svg", "--sheet", "1e308x1e308", "-o", "l.svg"][..],
            "--sheet",
        ),
        (
            &[
                "nest",
                "x.svg",
                "--sheet",
                "600x400",
                "--time=-1",
                "-o",
                "l.svg",
            ],
            "--time",
        ),
        (
            &[
                "nest", "x.svg", "--sheet", "600x400", "--time", "NaN", "-o", "l.svg",
            ],
            "--time",
        ),
        (&["nest", "x.svg", "--roll", "inf", "-o", "l.svg"], "--roll"),
        (
            &["flatten", "x.toml", "-o", "f.obj", "--max-stretch", "NaN"],
            "--max-stretch",
        ),
        (&["pattern", "x.toml", "-o", "p.svg", "--seam=-3"], "--seam"),
        (&["inspect", "x.toml", "--chord", "0"], "--chord"),
    ] {
        let e = err(args);
        assert!(
            e.contains("invalid value") && e.contains(flag),
            "{args:?}: {e}"
        );
    }
}

#[test]
fn item07_a_closed_stdout_is_a_normal_end() {
    let closed = anyhow::Error::from(flatcut_cli::stdout::ClosedStdout).context("inspect");
    assert_eq!(
        format!("{:?}", flatcut_cli::exit_code(Err(closed))),
        format!("{:?}", ExitCode::SUCCESS)
    );
    let other = anyhow::anyhow!("disk full");
    assert_eq!(
        format!("{:?}", flatcut_cli::exit_code(Err(other))),
        format!("{:?}", ExitCode::FAILURE)
    );
}

#[test]
fn item08_huge_sheets_are_refused_at_the_boundary() {
    let e = err(&["nest", "x.svg", "--sheet", "1e9x1e9", "-o", "l.svg"]);
    assert!(e.contains("--sheet"), "{e}");
    // Within the coordinate range, beyond what the nester resolves: refused at its entry.
    let d = tempfile::tempdir().unwrap();
    let svg = d.path().join("p.svg");
    run(&[
        "pattern",
        p(&root().join("patterns/lampshade/design.toml")),
        "-o",
        p(&svg),
    ])
    .unwrap();
    let e = err(&[
        "nest",
        p(&svg),
        "--sheet",
        "200000x200000",
        "-o",
        p(&d.path().join("l.svg")),
    ]);
    assert!(
        e.contains("larger than the 1e5 mm the nester accepts"),
        "{e}"
    );
    let e = err(&[
        "run",
        p(&corpus("huge-sheet/project.toml")),
        "--no-send",
        "-o",
        p(d.path()),
    ]);
    assert!(
        e.contains("[sheet] sizes must be positive and at most 1e6 mm"),
        "{e}"
    );
}

#[test]
fn item08_design_coordinates_beyond_the_range_are_an_error_at_load() {
    let e = err(&["inspect", p(&corpus("coordinates-1e9.toml"))]);
    assert!(
        e.contains("piece 0 'far'") && e.contains("point 1") && e.contains("beyond"),
        "{e}"
    );
}

#[test]
fn item09_non_finite_and_overflowing_geometry_is_refused_naming_the_element() {
    let e = err(&["inspect", p(&corpus("vertex-minus-1e308.obj"))]);
    assert!(
        e.contains("vertex-minus-1e308.obj:5:3: vertex coordinate") && e.contains("beyond"),
        "{e}"
    );
    let e = err(&["inspect", p(&corpus("coordinates-1e308.toml"))]);
    assert!(
        e.contains("piece 0 'overflow'") && e.contains("point 3") && !e.contains("internal error"),
        "{e}"
    );
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn item10_outputs_are_written_all_or_nothing() {
    let d = tempfile::tempdir().unwrap();
    let design = root().join("patterns/lampshade/design.toml");
    // The DXF cannot be written (its directory is a file): the SVG must not appear either.
    std::fs::write(d.path().join("blocked"), b"").unwrap();
    let svg = d.path().join("pattern.svg");
    let dxf = d.path().join("blocked/pattern.dxf");
    err(&["pattern", p(&design), "-o", p(&svg), "--dxf", p(&dxf)]);
    assert_eq!(names(d.path()), ["blocked"]);
    // Flatten: the OBJ is not kept when the report cannot be written.
    let obj = d.path().join("flat.obj");
    let rep = d.path().join("blocked/r.json");
    err(&[
        "flatten",
        p(&design),
        "--method",
        "developable",
        "-o",
        p(&obj),
        "--report",
        p(&rep),
    ]);
    assert_eq!(names(d.path()), ["blocked"]);
    // Report: the JSON is not kept when the PNG cannot be written.
    run(&[
        "flatten",
        p(&design),
        "--method",
        "developable",
        "-o",
        p(&obj),
    ])
    .unwrap();
    let json = d.path().join("r.json");
    err(&[
        "report",
        p(&obj),
        "--json",
        p(&json),
        "--png",
        p(&d.path().join("blocked/h.png")),
    ]);
    assert_eq!(names(d.path()), ["blocked", "flat.obj"]);
    // And when everything can be written, everything is.
    run(&[
        "pattern",
        p(&design),
        "-o",
        p(&svg),
        "--dxf",
        p(&d.path().join("pattern.dxf")),
    ])
    .unwrap();
    assert_eq!(
        names(d.path()),
        ["blocked", "flat.obj", "pattern.dxf", "pattern.svg"]
    );
}

#[test]
fn item11_piece_names_that_collide_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let e = err(&[
        "flatten",
        p(&corpus("names-collide.toml")),
        "-o",
        p(&d.path().join("flat.obj")),
    ]);
    assert!(
        e.contains("pieces 'a/b' and 'a_b' would share the name 'a_b'"),
        "{e}"
    );
    assert!(names(d.path()).is_empty());
}

fn import(name: &str) -> Result<flatcut::pattern::svg::SvgImport, String> {
    let f = corpus(name);
    flatcut::pattern::svg::read_svg(
        &std::fs::read_to_string(&f).unwrap(),
        name,
        0.05,
        &flatcut::pattern::ColourTable::default(),
    )
    .map_err(|e| e.to_string())
}

#[test]
fn item14_svg_colours_text_fills_and_sizes_are_mapped_or_named() {
    let e = import("width-percent.svg").unwrap_err();
    assert!(
        e.contains("width-percent.svg") && e.contains("percentage"),
        "{e}"
    );
    let r = import("no-size.svg").unwrap();
    assert!(
        r.warnings.iter().any(|w| w.contains("read as CSS px")),
        "{:?}",
        r.warnings
    );
    let r = import("colours-text-fill.svg").unwrap();
    use flatcut::pattern::Layer;
    let count = |l| r.drawing.strokes.iter().filter(|s| s.layer == l).count();
    assert_eq!(
        (count(Layer::Cut), count(Layer::Draw), count(Layer::Engrave)),
        (1, 1, 1)
    );
    let w = r.warnings.join("\n");
    for said in [
        "LightBurn layer 03",
        "<text>",
        "filled shape(s) without a stroke",
    ] {
        assert!(w.contains(said), "{said}: {w}");
    }
}

#[test]
fn item16_nesting_from_pattern_svgs_keeps_grain_and_quantity() {
    // The helmet's caps are [[piece]]s with grain lines (the shoe is now a part, whose pieces
    // are not in `design.pieces`).
    let d = tempfile::tempdir().unwrap();
    let svg = d.path().join("shoe.svg");
    run(&[
        "pattern",
        p(&root().join("patterns/helmet/design.toml")),
        "-o",
        p(&svg),
    ])
    .unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    let import = flatcut::pattern::svg::read_svg(
        &text,
        "shoe.svg",
        0.05,
        &flatcut::pattern::ColourTable::default(),
    )
    .unwrap();
    let groups = flatcut::pipeline::NestGroup::from_drawing("shoe.svg", &import.drawing);
    let design =
        flatcut::design::Design::load(&root().join("patterns/helmet/design.toml")).unwrap();
    assert_eq!(groups.len(), design.pieces.len());
    for (g, def) in groups.iter().zip(&design.pieces) {
        assert_eq!(g.quantity, def.quantity as usize, "{}", g.name);
        assert_eq!(g.grain_angle.is_some(), def.grain.is_some(), "{}", g.name);
    }
}

#[test]
fn item19_gcode_output_and_nest_dxf_have_help() {
    use clap::CommandFactory as _;
    let cli = flatcut_cli::Cli::command();
    for (sub, arg) in [("gcode", "output"), ("nest", "dxf")] {
        let c = cli.find_subcommand(sub).unwrap();
        let a = c.get_arguments().find(|a| a.get_id() == arg).unwrap();
        assert!(a.get_help().is_some(), "{sub} --{arg} has no help");
    }
}

/// The outer cut contours of a pattern SVG written by `pattern`, with the grain direction
/// (degrees) of each piece that has one.
fn pattern_pieces(design: &Path) -> Vec<(Vec<flatcut::geom::DVec2>, Option<f64>)> {
    let d = tempfile::tempdir().unwrap();
    let svg = d.path().join("p.svg");
    run(&["pattern", p(design), "-o", p(&svg)]).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    let drawing = flatcut::pattern::svg::read_svg(
        &text,
        "p.svg",
        0.01,
        &flatcut::pattern::ColourTable::default(),
    )
    .unwrap()
    .drawing;
    drawing
        .strokes
        .iter()
        .filter(|s| s.is_outer() && s.closed)
        .map(|s| {
            let grain = s
                .piece
                .and_then(|k| drawing.piece_info(k))
                .and_then(|i| i.grain)
                .map(|(a, b)| (b - a).y.atan2((b - a).x).to_degrees());
            (s.points.clone(), grain)
        })
        .collect()
}

fn extent(pts: &[flatcut::geom::DVec2]) -> flatcut::geom::DVec2 {
    let b = flatcut::geom::Aabb2::from_points(pts.iter().copied());
    b.max - b.min
}

#[test]
fn item15_the_sleeve_lies_with_its_grain_along_x() {
    let pieces = pattern_pieces(&root().join("patterns/sleeve/design.toml"));
    assert_eq!(pieces.len(), 1);
    let (cut, grain) = &pieces[0];
    // 2π·55 = 345.6 around plus 2 × 10 allowance, 500 long plus 2 × 10: the arm along the grain
    let e = extent(cut);
    assert!(
        (e.x - 520.0).abs() < 0.5 && (e.y - 365.6).abs() < 0.5,
        "sleeve cut line {:.1} × {:.1} mm",
        e.x,
        e.y
    );
    let g = grain.expect("the sleeve has a grain line");
    assert!(g.abs() < 1e-6, "grain at {g}°");
}

#[test]
fn item15_a_square_given_at_45_degrees_comes_out_square_to_the_axes() {
    let pieces = pattern_pieces(&corpus("square-45.toml"));
    assert_eq!(pieces.len(), 1);
    let e = extent(&pieces[0].0);
    assert!(
        (e.x - 100.0).abs() < 0.05 && (e.y - 100.0).abs() < 0.05,
        "square {:.3} × {:.3} mm",
        e.x,
        e.y
    );
}

/// A negative number after a flag is that flag's value, checked by the flag's own rule; clap
/// would otherwise read `-5` as an unknown flag and hide the real complaint.
#[test]
fn a_negative_value_reaches_its_flags_check() {
    use clap::Parser as _;
    let err = flatcut_cli::Cli::try_parse_from([
        "flatcut", "pattern", "x.toml", "-o", "x.svg", "--seam", "-5",
    ])
    .expect_err("a negative seam allowance is refused");
    let text = err.to_string();
    assert!(!text.contains("unexpected argument"), "{text}");
    assert!(text.contains("--seam") && text.contains("-5"), "{text}");
    // Every command takes negative numbers as values, not just the one above.
    use clap::CommandFactory as _;
    for sub in flatcut_cli::Cli::command().get_subcommands() {
        assert!(
            sub.is_allow_negative_numbers_set(),
            "{} reads -5 as a flag",
            sub.get_name()
        );
    }
}
