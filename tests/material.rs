//! Materials end to end: `flatcut flatten --material` and a piece's `material_properties`
//! flatten with the orthotropic energy and report the strain along, across and on the bias. A
//! cylinder sleeve is developable whichever way its grain runs, so with the grain along its axis
//! or around it every direction's strain is zero (read back from the flat OBJ and measured here,
//! independently of the report); `grain = "auto"` says it chose; a bad material file is refused
//! naming the file, the key and what is wrong.

use std::path::Path;

use clap::Parser as _;
use flatcut::geom::{DVec2, DVec3};
use flatcut::mesh::grain_strain::grain_strain;

use crate::pipeline::run_cli;

/// The sleeve of `crates/design/examples/cylinder.toml` with a grain and a material.
fn sleeve(dir: &Path, grain: &str, material: &str) -> std::path::PathBuf {
    let p = dir.join(format!("sleeve-{}.toml", grain.len()));
    std::fs::write(
        &p,
        format!(
            "[[piece]]\nname = \"sleeve\"\ngrain = {grain}\n{material}[piece.surface]\ntype = \"cylinder\"\nbase = [0, 0, 0]\nradius = 30\nheight = 80\n"
        ),
    )
    .unwrap();
    p
}

/// A dome 100 mm across, a biquadratic Bézier whose middle control point stands 60 mm up, with
/// `grain`, as `cap.toml` in `dir`: doubly curved, so no map keeps every thread's length.
fn dome(dir: &Path, grain: &str) -> std::path::PathBuf {
    let p = dir.join("cap.toml");
    std::fs::write(
        &p,
        format!(
            "[[piece]]\nname = \"cap\"\ngrain = {grain}\n[piece.surface]\ntype = \"bezier\"\ndegree = [2, 2]\npoints = [[0, 0, 0], [0, 50, 0], [0, 100, 0], [50, 0, 0], [50, 50, 60], [50, 100, 0], [100, 0, 0], [100, 50, 0], [100, 100, 0]]\n"
        ),
    )
    .unwrap();
    p
}

/// A material file `NAME.toml` in `dir` with the stretch limits along, across and on the bias, and
/// one compression limit for every direction.
fn material_file(dir: &Path, name: &str, stretch: [f64; 3], compress: f64) -> std::path::PathBuf {
    let p = dir.join(format!("{name}.toml"));
    let [a, b, c] = stretch;
    std::fs::write(
        &p,
        format!(
            "name = \"{name}\"\n[stretch_max_pct]\nalong = {a}\nacross = {b}\nbias = {c}\n[compress_max_pct]\nalong = {compress}\nacross = {compress}\nbias = {compress}\n"
        ),
    )
    .unwrap();
    p
}

fn flatten(design: &Path, out: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let obj = out.with_extension("obj");
    let report = out.with_extension("json");
    let mut args = vec![
        "flatten",
        design.to_str().unwrap(),
        "-o",
        obj.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let code = run_cli(&args);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let r = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    (r, std::fs::read_to_string(&obj).unwrap())
}

/// Largest |stretch − 1| of any thread (warp along +x of the flat map, weft, both biases),
/// measured from the OBJ's `v`, `vt` and `f a/a b/b c/c`.
fn worst_thread_strain(obj: &str) -> f64 {
    let (mut v, mut vt, mut worst) = (Vec::new(), Vec::new(), 0f64);
    let nums = |s: &str| -> Vec<f64> { s.split_whitespace().map(|x| x.parse().unwrap()).collect() };
    for line in obj.lines() {
        if let Some(r) = line.strip_prefix("v ") {
            let c = nums(r);
            v.push(DVec3::new(c[0], c[1], c[2]));
        } else if let Some(r) = line.strip_prefix("vt ") {
            let c = nums(r);
            vt.push(DVec2::new(c[0], c[1]));
        } else if let Some(r) = line.strip_prefix("f ") {
            let idx: Vec<usize> = r
                .split_whitespace()
                .map(|c| c.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                .collect();
            let t3 = [v[idx[0]], v[idx[1]], v[idx[2]]];
            let t2 = [vt[idx[0]], vt[idx[1]], vt[idx[2]]];
            let g = grain_strain(t3, t2, DVec2::X).unwrap();
            for s in [g.along, g.across, g.bias_max, g.bias_min] {
                worst = worst.max((s - 1.0).abs());
            }
        }
    }
    worst
}

#[test]
fn a_sleeve_flattens_exactly_with_its_grain_along_or_around_it() {
    let dir = tempfile::tempdir().unwrap();
    for (name, grain) in [
        ("along", "[[30, 0, 10], [30, 0, 70]]"),
        ("around", "[[30, 0, 40], [30, 10, 40]]"),
    ] {
        let design = sleeve(dir.path(), grain, "");
        let (r, obj) = flatten(
            &design,
            &dir.path().join(name),
            &["--material", "woven-cotton"],
        );
        assert_eq!(r["material"], "woven-cotton", "{name}");
        assert_eq!(r["grain_auto"], false, "{name}");
        for k in [
            "stretch_max_pct_along",
            "stretch_max_pct_across",
            "stretch_max_pct_bias",
            "compress_max_pct_along",
            "compress_max_pct_across",
            "compress_max_pct_bias",
        ] {
            let v = r[k].as_f64().unwrap();
            assert!(v < 1e-3, "{name}: {k} = {v}");
        }
        assert_eq!(r["faces_over_material_limits"], 0, "{name}");
        assert_eq!(r["limit_stretch_pct_bias"], 15.0);
        // The grain on the surface is the one drawn.
        let g = &r["grain_3d"];
        let axial = g[2].as_f64().unwrap().abs();
        let want = if name == "along" { 1.0 } else { 0.0 };
        assert!((axial - want).abs() < 1e-3, "{name}: grain {g}");
        // Measured from the OBJ: every thread keeps its length (warp along +x).
        let w = worst_thread_strain(&obj);
        assert!(w < 1e-5, "{name}: {w}");
    }
}

#[test]
fn a_pieces_own_material_and_auto_grain_are_used_and_said() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleeve(dir.path(), "\"auto\"", "material_properties = \"canvas\"\n");
    let (r, _) = flatten(&design, &dir.path().join("auto"), &[]);
    assert_eq!(r["material"], "canvas");
    assert_eq!(r["grain_auto"], true);
    assert_eq!(r["faces_over_material_limits"], 0);
}

#[test]
fn a_bad_material_file_names_the_file_the_key_and_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let m = material_file(dir.path(), "soft", [1.0, 1.0, -4.0], 1.0);
    let design = sleeve(dir.path(), "\"auto\"", "");
    let obj = dir.path().join("x.obj");
    let cli = flatcut_cli::Cli::try_parse_from([
        "flatcut",
        "flatten",
        design.to_str().unwrap(),
        "-o",
        obj.to_str().unwrap(),
        "--material",
        m.to_str().unwrap(),
    ])
    .unwrap();
    let e = format!("{:#}", flatcut_cli::run(cli).unwrap_err());
    assert!(
        e.contains("soft.toml") && e.contains("stretch_max_pct.bias") && e.contains("-4"),
        "{e}"
    );
    assert!(!obj.exists(), "no output on error");
}

#[test]
fn a_piece_over_its_materials_limits_exits_3_and_says_by_how_much() {
    // A dome 100 mm across and 30 mm high cannot lie flat within 0.5 % in every direction; the flat
    // outputs are written and the exit code says the limits are broken.
    let dir = tempfile::tempdir().unwrap();
    let m = material_file(dir.path(), "stiff", [0.5; 3], 0.5);
    let design = dome(dir.path(), "\"auto\"");
    let obj = dir.path().join("cap.obj");
    let report = dir.path().join("cap.json");
    let code = run_cli(&[
        "flatten",
        design.to_str().unwrap(),
        "-o",
        obj.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--material",
        m.to_str().unwrap(),
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::from(3))
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(r["faces_over_material_limits"].as_u64().unwrap() > 0, "{r}");
    assert!(r["material_excess_pct"].as_f64().unwrap() > 0.0, "{r}");
    assert!(obj.exists(), "the outputs are written either way");
}

/// A grain the flattening chose is drawn: the sleeve's pattern (a 188.5 × 80 mm rectangle) gets
/// a grain line along the warp, and the piece is turned with it along +x. The warp makes the
/// angle with the sleeve's axis that `grain_3d` in the report makes with it (the sleeve is
/// developable, so every grain ties at zero strain and the chosen one may lie on a helix), so
/// the rectangle's 80 mm sides make that angle with +x.
#[test]
fn an_auto_grain_is_drawn_as_the_pieces_grain_line() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleeve(dir.path(), "\"auto\"", "material_properties = \"canvas\"\n");
    let (r, _) = flatten(&design, &dir.path().join("auto"), &[]);
    let cos_axis = r["grain_3d"][2].as_f64().unwrap().abs();
    let svg = dir.path().join("sleeve.svg");
    let code = run_cli(&[
        "pattern",
        design.to_str().unwrap(),
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    let attr = |key: &str| -> String {
        text.split(key)
            .nth(1)
            .and_then(|s| s.split('"').nth(1))
            .unwrap_or_else(|| panic!("no {key} in the pattern"))
            .to_string()
    };
    let deg: f64 = attr("data-flatcut-grain-deg=").parse().unwrap();
    assert!(
        deg.abs() < 0.01 || (deg.abs() - 180.0).abs() < 0.01,
        "{deg}"
    );
    let line: Vec<f64> = numbers(&attr("id=\"sleeve-1-grain\" points="));
    assert!(
        (line[1] - line[3]).abs() < 1e-3,
        "grain line {line:?} not along +x"
    );
    // The sew line's corners; its 80 mm sides run along the sleeve's axis.
    let d = numbers(
        text.split("id=\"sleeve-1-sew\"")
            .next()
            .unwrap()
            .rsplit("d=\"")
            .next()
            .unwrap(),
    );
    let corners: Vec<[f64; 2]> = d.chunks(2).take(4).map(|p| [p[0], p[1]]).collect();
    let axial: Vec<f64> = (0..4)
        .filter_map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = dx.hypot(dy);
            ((len - 80.0).abs() < 0.5).then_some(dx.abs() / len)
        })
        .collect();
    assert_eq!(axial.len(), 2, "sew line corners {corners:?}");
    for c in axial {
        assert!(
            (c - cos_axis).abs() < 0.01,
            "axis at cos {c} to +x, grain at cos {cos_axis} to the axis"
        );
    }
}

/// The numbers of an SVG attribute value, in order.
fn numbers(s: &str) -> Vec<f64> {
    s.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
        .filter_map(|t| t.parse().ok())
        .collect()
}

/// `report --measure material` draws each face's excess over the material's limits along,
/// across or on the bias: the per-face figures behind the picture count the faces the report
/// says are over, and reach its largest excess; a flat OBJ, which does not carry its grain, is
/// refused with a reason.
#[test]
fn the_material_heat_map_shows_each_faces_excess_over_the_limits_per_direction() {
    let dir = tempfile::tempdir().unwrap();
    let m = material_file(dir.path(), "bias-soft", [1.0, 1.0, 8.0], 1.0);
    let design = dome(dir.path(), "[[0, 50, 0], [100, 50, 0]]");
    let (json, svg) = (dir.path().join("cap.json"), dir.path().join("cap.svg"));
    let args = [
        "report",
        design.to_str().unwrap(),
        "--material",
        m.to_str().unwrap(),
        "--measure",
        "material",
        "--json",
        json.to_str().unwrap(),
        "--per-face",
        "--svg",
        svg.to_str().unwrap(),
    ];
    let cli = flatcut_cli::Cli::try_parse_from(std::iter::once("flatcut").chain(args)).unwrap();
    flatcut_cli::run(cli).unwrap();
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let faces = r["per_face"].as_array().unwrap();
    let excess: Vec<f64> = faces
        .iter()
        .map(|f| f["material_excess_pct"].as_f64().unwrap())
        .collect();
    let over = excess.iter().filter(|&&e| e > 0.0).count();
    assert!(over > 0, "the dome is over a 1 % thread limit somewhere");
    assert_eq!(
        over as u64,
        r["faces_over_material_limits"].as_u64().unwrap()
    );
    let most = excess.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(most, r["material_excess_pct"].as_f64().unwrap());
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<path"), "a heat map");
    // The legend's scale reaches the largest excess (its ticks are signed).
    assert!(text.contains("piece-0"));
    // A flat OBJ carries no grain: refused, naming why.
    let obj = dir.path().join("flat.obj");
    run_cli(&[
        "flatten",
        design.to_str().unwrap(),
        "-o",
        obj.to_str().unwrap(),
    ]);
    let cli = flatcut_cli::Cli::try_parse_from([
        "flatcut",
        "report",
        obj.to_str().unwrap(),
        "--measure",
        "material",
        "--svg",
        svg.to_str().unwrap(),
    ])
    .unwrap();
    let e = format!("{:#}", flatcut_cli::run(cli).expect_err("no material"));
    assert!(e.contains("no material to measure against"), "{e}");
}
