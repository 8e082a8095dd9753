//! The bundled shoe as a production pattern set: one AAMA block per piece cut (each side of a
//! pair and each size its own, with its own piece text) that `nest` and `gcode` read back;
//! allowances by edge (a 16 mm lasting margin at the featherline, lapped seams cut raw on top
//! with a 10 mm underlay below, a 5 mm folded topline, a 2 mm closed back seam) measured from
//! the DXF by ezdxf, an independent reader; sizes 40, 42 and 44 graded and nested together as
//! the project's order asks; labels a cutter can read, and a knife job that says its pieces
//! come off the table unmarked.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use flatcut::pattern::dxf_read::read_dxf;
use flatcut::pattern::{Drawing, StrokeKind};

use crate::dxf::python_with;
use crate::pipeline::{root, run_cli, run_project};

const SIZES: [&str; 3] = ["40", "42", "44"];
const PIECES: [&str; 4] = ["toe cap", "vamp", "lateral quarter", "medial quarter"];

/// The shoe project run once for every test of this module (the outputs are only read).
fn shoe() -> &'static Path {
    static OUT: OnceLock<tempfile::TempDir> = OnceLock::new();
    OUT.get_or_init(|| {
        let out = tempfile::tempdir().unwrap();
        run_project("patterns/shoe/project.toml", out.path(), &["--no-send"]);
        out
    })
    .path()
}

fn read(path: &Path) -> Drawing {
    let r = read_dxf(&std::fs::read_to_string(path).unwrap(), 0.01).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    r.drawing
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Every piece cut: `<piece> <size> <side>`.
fn piece_names() -> Vec<String> {
    let mut v = Vec::new();
    for size in SIZES {
        for piece in PIECES {
            for side in ["L", "R"] {
                v.push(format!("{piece} {size} {side}"));
            }
        }
    }
    v
}

#[test]
fn the_pattern_dxf_has_a_block_per_piece_with_its_own_text_and_reads_back() {
    let dxf = shoe().join("pattern.dxf");
    let text = std::fs::read_to_string(&dxf).unwrap();
    assert_eq!(text.matches("\n  0\nBLOCK\n").count(), 24);
    assert_eq!(text.matches("\n  0\nINSERT\n").count(), 24);
    let d = read(&dxf);
    let mut names: Vec<String> = d.pieces.iter().map(|i| i.label.name.clone()).collect();
    names.sort();
    let mut want = piece_names();
    want.sort();
    assert_eq!(names, want);
    for info in &d.pieces {
        let size = info.label.name.split(' ').rev().nth(1).unwrap();
        assert_eq!(info.label.size, size, "{}", info.label.name);
        assert_eq!(info.label.quantity, 1, "{}", info.label.name);
        assert_eq!(info.label.material, "leather", "{}", info.label.name);
        assert!(info.grain.is_some(), "{}", info.label.name);
        let outer = d
            .strokes
            .iter()
            .filter(|s| s.piece == Some(info.piece) && s.is_outer())
            .count();
        assert_eq!(outer, 1, "{}", info.label.name);
    }
    // `nest` places every block, `gcode` cuts every one (on a table as large as the sheet).
    let out = tempfile::tempdir().unwrap();
    let layout = out.path().join("layout.dxf");
    run_cli(&[
        "nest",
        dxf.to_str().unwrap(),
        "--sheet",
        "1400x1000",
        "--spacing",
        "3",
        "-o",
        out.path().join("layout.svg").to_str().unwrap(),
        "--dxf",
        layout.to_str().unwrap(),
        "--iters",
        "5",
    ]);
    let nested = read(&layout);
    assert_eq!(nested.pieces.len(), 24, "every block placed");
    let knife = std::fs::read_to_string(root().join("crates/gcode/profiles/knife.toml"))
        .unwrap()
        .replace(
            "work_area_mm = [600.0, 400.0]",
            "work_area_mm = [1500.0, 1100.0]",
        );
    let profile = out.path().join("table.toml");
    std::fs::write(&profile, knife).unwrap();
    let job = out.path().join("job.gcode");
    run_cli(&[
        "gcode",
        layout.to_str().unwrap(),
        "--profile",
        profile.to_str().unwrap(),
        "-o",
        job.to_str().unwrap(),
    ]);
    let g = std::fs::read_to_string(&job).unwrap();
    for name in piece_names() {
        assert!(
            g.contains(&format!("{name}-cut-1")),
            "{name} cut in the job"
        );
    }
}

/// What each piece's edges are: (edge, kind, allowance mm).
fn expected_edges(piece: &str) -> Vec<(&'static str, &'static str, f64)> {
    match piece {
        "toe cap" => vec![("toe-cap", "raw", 0.0), ("featherline", "lasting", 16.0)],
        "vamp" => vec![
            ("topline", "fold", 5.0),
            ("vamp-lateral", "raw", 0.0),
            ("vamp-medial", "raw", 0.0),
            ("featherline", "lasting", 16.0),
            ("toe-cap", "seam", 10.0),
        ],
        "lateral quarter" => vec![
            ("vamp-lateral", "seam", 10.0),
            ("featherline", "lasting", 16.0),
            ("back", "seam", 2.0),
            ("topline", "fold", 5.0),
        ],
        _ => vec![
            ("vamp-medial", "seam", 10.0),
            ("featherline", "lasting", 16.0),
            ("back", "seam", 2.0),
            ("topline", "fold", 5.0),
        ],
    }
}

#[test]
fn ezdxf_measures_every_edges_allowance_from_sew_line_to_cut_line() {
    let Some(py) = python_with("ezdxf") else {
        return;
    };
    if python_with("scipy").is_none() {
        return;
    }
    let script = root().join("tools/dxf/allowances.py");
    let out = std::process::Command::new(&py)
        .arg(&script)
        .arg(shoe().join("pattern.dxf"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let v: serde_json::Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("no JSON from allowances.py ({e}): {text}"));
    assert!(out.status.success(), "allowances.py: {}", v["problems"]);
    let blocks = v["blocks"].as_array().unwrap();
    assert_eq!(blocks.len(), 24);
    for b in blocks {
        let block = b["block"].as_str().unwrap();
        let name = b["texts"]
            .as_array()
            .unwrap()
            .iter()
            .find_map(|t| t.as_str().unwrap().strip_prefix("Piece Name: "))
            .unwrap();
        let piece = PIECES.iter().find(|p| name.starts_with(*p)).unwrap();
        // every edge the piece has, each measured where the DXF says it is
        let mut got: Vec<(String, String, f64, f64)> = b["edges"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| {
                (
                    e["edge"].as_str().unwrap().to_string(),
                    e["kind"].as_str().unwrap().to_string(),
                    e["stated_mm"].as_f64().unwrap(),
                    e["measured_mm"][1].as_f64().unwrap(),
                )
            })
            .collect();
        got.sort_by(|a, b| a.0.cmp(&b.0));
        got.dedup_by(|a, b| a.0 == b.0);
        let mut want = expected_edges(piece);
        want.sort_by(|a, b| a.0.cmp(b.0));
        assert_eq!(got.len(), want.len(), "{block}: {got:?}");
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(
                (g.0.as_str(), g.1.as_str(), g.2),
                (w.0, w.1, w.2),
                "{block}"
            );
            assert!((g.3 - w.2).abs() <= 0.02, "{block} {}: {} mm", g.0, g.3);
        }
    }
}

#[test]
fn sizes_grade_evenly_and_the_order_is_nested_together() {
    let out = shoe();
    let summary = json(&out.join("summary.json"));
    // Every seam of every size: its sides equal, and longer from size to size.
    let mut by_seam: BTreeMap<String, Vec<(String, f64)>> = BTreeMap::new();
    for s in summary["mating_seams"].as_array().unwrap() {
        let name = s["name"].as_str().unwrap();
        let (seam, size) = name.rsplit_once(' ').unwrap();
        let l = &s["length_2d_mm"];
        let (la, lb) = (l[0].as_f64().unwrap(), l[1].as_f64().unwrap());
        assert!((la - lb).abs() < 1e-3, "{name}: {la} vs {lb}");
        by_seam
            .entry(seam.to_string())
            .or_default()
            .push((size.to_string(), la));
    }
    assert_eq!(by_seam.len(), 4);
    for (seam, v) in &by_seam {
        let sizes: Vec<&str> = v.iter().map(|(s, _)| s.as_str()).collect();
        assert_eq!(sizes, SIZES, "{seam}");
        assert!(v[0].1 < v[1].1 && v[1].1 < v[2].1, "{seam}: {v:?}");
        eprintln!("graded seam {seam}: {v:?}");
    }
    // The order (40 = 1, 42 = 2, 44 = 1 pairs): 8 + 16 + 8 pieces placed, per size.
    let mut placed: BTreeMap<String, usize> = BTreeMap::new();
    let mut k = 1;
    while out.join(format!("layout-{k}.dxf")).is_file() {
        for info in read(&out.join(format!("layout-{k}.dxf"))).pieces {
            *placed.entry(info.label.size).or_default() += 1;
        }
        k += 1;
    }
    let want: BTreeMap<String, usize> = [("40", 8), ("42", 16), ("44", 8)]
        .into_iter()
        .map(|(s, n)| (s.to_string(), n))
        .collect();
    assert_eq!(placed, want);
    assert_eq!(summary["unplaced"], 0);
    // A graded nest per piece, every size stacked on its reference point.
    for piece in PIECES {
        let f = out.join(format!("graded-{}.svg", piece.replace(' ', "_")));
        let svg = std::fs::read_to_string(&f).unwrap();
        for size in SIZES {
            assert!(
                svg.contains(&format!("id=\"size-{size}\"")),
                "{piece} {size}"
            );
        }
    }
}

#[test]
fn labels_are_readable_and_a_knife_job_says_its_pieces_are_unmarked() {
    let out = shoe();
    let summary = json(&out.join("summary.json"));
    let labels = summary["labels"].as_str().unwrap();
    assert!(labels.starts_with("pieces are unmarked"), "{labels}");
    // The layout's label strokes: every piece's written at 3 mm cap height or more, its name
    // (size and side in it) first; a pen writes them all.
    let svg = std::fs::read_to_string(out.join("layout-1.svg")).unwrap();
    let import = flatcut::pattern::svg::read_svg(&svg, "layout-1.svg", 0.01, &Default::default())
        .unwrap()
        .drawing;
    let pen = flatcut::gcode::Profile::pen();
    let marking = flatcut::gcode::Marking::of(&pen, &import);
    assert!(marking.all_marked(), "{marking:?}");
    let knife = flatcut::gcode::Profile::knife();
    assert!(!flatcut::gcode::Marking::of(&knife, &import).all_marked());
    // Measured on the pattern sheet, where every piece stands upright: the tallest single stroke
    // of a label is its cap height (capitals, digits and ascenders span it; descenders less).
    let pattern = std::fs::read_to_string(out.join("pattern.svg")).unwrap();
    let pattern =
        flatcut::pattern::svg::read_svg(&pattern, "pattern.svg", 0.01, &Default::default())
            .unwrap()
            .drawing;
    let mut cap: BTreeMap<String, f64> = BTreeMap::new();
    for s in pattern.strokes.iter().filter(|s| {
        s.kind == StrokeKind::Text && s.id.contains("-label-") && !s.id.contains("-label-lasting")
    }) {
        let piece = s.id[..s.id.find("-label-").unwrap()].to_string();
        let (lo, hi) = s
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                (lo.min(q.y), hi.max(q.y))
            });
        let e = cap.entry(piece).or_insert(0.0);
        *e = e.max(hi - lo);
    }
    assert_eq!(cap.len(), 24, "{cap:?}");
    for (piece, h) in &cap {
        assert!(*h >= 3.0 - 1e-3, "{piece}: label {h:.2} mm high");
    }
    eprintln!("label cap heights: {cap:?}");
}

/// The shoe's design and project copied into `dir` with `edit` applied to the design text.
fn broken_shoe(dir: &Path, edit: impl Fn(&str) -> String) -> PathBuf {
    let shoe = root().join("patterns/shoe");
    let design = std::fs::read_to_string(shoe.join("design.toml")).unwrap();
    let edited = edit(&design);
    assert_ne!(edited, design, "the edit changes the design");
    std::fs::write(dir.join("design.toml"), edited).unwrap();
    std::fs::copy(shoe.join("project.toml"), dir.join("project.toml")).unwrap();
    dir.join("project.toml")
}

#[test]
fn bad_edges_laps_and_sizes_are_refused_by_name_with_nothing_written() {
    use clap::Parser as _;
    let cases: Vec<(&str, Box<dyn Fn(&str) -> String>, Vec<&str>)> = vec![
        (
            "an edge off the outline",
            Box::new(|d: &str| d.replacen("from = [-4, 0, 0]", "from = [120, 0, 90]", 1)),
            vec![
                "part 0 'upper'",
                "edge 'featherline'",
                "`from`",
                "from the boundary",
            ],
        ),
        (
            "two edges that overlap",
            Box::new(|d: &str| {
                d.replacen(
                    "[[part.piece]]",
                    "[[part.edge]]\nname = \"heel\"\nfrom = [-4, 0, 0]\nto = [152, 47, 0]\nallowance_mm = 12\n\n[[part.piece]]",
                    1,
                )
            }),
            vec!["edge 'heel'", "overlaps edge 'featherline'"],
        ),
        (
            "a lap naming a piece not beside the line",
            Box::new(|d: &str| d.replacen("lap = \"toe cap\"", "lap = \"lateral quarter\"", 1)),
            vec![
                "line 'toe-cap'",
                "lap = \"lateral quarter\"",
                "not beside the line",
            ],
        ),
        (
            "a scale of zero",
            Box::new(|d: &str| d.replacen("scale = [0.95134", "scale = [0", 1)),
            vec!["[grading] size '40'", "must be finite and > 0"],
        ),
        (
            "a size whose design lacks a line",
            Box::new(|d: &str| {
                d.replacen(
                    "name = \"44\"\nscale = [1.04866, 1.04082, 1.04082]",
                    "name = \"44\"\ndesign = \"size-44.toml\"",
                    1,
                )
            }),
            vec!["[grading] size '44'", "size-44.toml", "no line 'back'"],
        ),
    ];
    for (what, edit, want) in cases {
        let dir = tempfile::tempdir().unwrap();
        let project = broken_shoe(dir.path(), edit);
        // the size's own design: the shoe without its back seam line
        let design = std::fs::read_to_string(root().join("patterns/shoe/design.toml")).unwrap();
        let at = design.find("[[part.line]]\n# The back seam").unwrap();
        let end = at + design[at..].find("\n\n").unwrap();
        let without_back = format!("{}{}", &design[..at], &design[end + 2..]);
        let without_back = without_back[..without_back.find("[grading]").unwrap()].to_string();
        std::fs::write(dir.path().join("size-44.toml"), without_back).unwrap();
        let out = dir.path().join("out");
        let args = [
            "flatcut",
            "run",
            project.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
            "--no-send",
        ];
        let err =
            flatcut_cli::run(flatcut_cli::Cli::try_parse_from(args).unwrap()).expect_err(what);
        let err = format!("{err:#}");
        assert!(err.contains("design.toml"), "{what}: {err}");
        for w in want {
            assert!(err.contains(w), "{what}: `{w}` not in: {err}");
        }
        assert!(!out.exists(), "{what}: nothing is written");
    }
}

/// `report` on the run's piece OBJs names a seam by its pieces (the OBJ's object name) and finds
/// its notches where the design run put them: the same offsets along the seam, on both sides.
#[test]
fn report_on_piece_objs_names_seams_by_piece_and_carries_their_notches() {
    let out = shoe();
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("report.json");
    let obj = |f: &str| out.join(f).to_str().unwrap().to_string();
    let (cap, vamp) = (obj("toe_cap_42.obj"), obj("vamp_42.obj"));
    let code = run_cli(&["report", &cap, &vamp, "--json", report.to_str().unwrap()]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let pieces = json(&report);
    assert_eq!(pieces[0]["name"], "toe cap 42");
    assert_eq!(pieces[1]["name"], "vamp 42");
    let seam = &pieces[0]["mating_seams"][0];
    assert_eq!(seam["name"], "toe cap 42/vamp 42");
    assert_eq!(seam["pieces"], serde_json::json!(["toe cap 42", "vamp 42"]));
    // The design run's own measure of the same seam (`toe-cap 42`), notch for notch.
    let summary = json(&out.join("summary.json"));
    let run_seam = summary["mating_seams"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == "toe-cap 42")
        .unwrap();
    let offsets = |s: &serde_json::Value| -> Vec<(String, f64, f64)> {
        let mut v: Vec<(String, f64, f64)> = s["notches"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| {
                let o = &n["offset_mm"];
                let (a, b) = (o[0].as_f64().unwrap(), o[1].as_f64().unwrap());
                (n["name"].as_str().unwrap().to_string(), a.min(b), a.max(b))
            })
            .collect();
        v.sort_by(|x, y| x.0.cmp(&y.0));
        v
    };
    let (got, want) = (offsets(seam), offsets(run_seam));
    assert_eq!(got.len(), 3, "{got:?}");
    let length = seam["length_2d_mm"][0].as_f64().unwrap();
    for ((gn, ga, gb), (wn, wa, wb)) in got.iter().zip(&want) {
        assert_eq!(gn, wn);
        // Measured from either end of the seam: the run's sides may run the other way.
        let same = |g: f64, w: f64| (g - w).abs() < 1e-4 || (g - (length - w)).abs() < 1e-4;
        assert!(
            same(*ga, *wa) && same(*gb, *wb),
            "{gn}: {ga}/{gb} vs {wa}/{wb}"
        );
    }
}
