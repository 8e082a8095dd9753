//! Closed surfaces of any genus through `flatten --split auto`, checked from the files written:
//! a torus (genus 1) opened along short loops and split into parts within the limits (measured
//! here by the singular values of every face), covering the torus once (areas) with every
//! outline edge sewn to another at the same two 3D points and the same flat length, and every
//! seam in the report with its length and visibility cost; a surface that passes through itself,
//! a non-manifold one and limits no split can meet are refused, naming where.

use std::path::Path;

use clap::Parser;

use crate::darts::{Obj, measured_limits, read_obj, sewn_lengths, split_parts};

/// Largest difference of two sewn edges' flat lengths (mm) accepted here.
const SEWN_MM: f64 = 1e-5;

/// A torus (radii `r1` > `r2`, mm) of `n` × `m` quads as OBJ text.
fn torus_obj(r1: f64, r2: f64, n: usize, m: usize) -> String {
    use std::f64::consts::TAU;
    let mut s = String::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (TAU * i as f64 / n as f64, TAU * j as f64 / m as f64);
            let r = r1 + r2 * v.cos();
            s.push_str(&format!(
                "v {} {} {}\n",
                r * u.cos(),
                r * u.sin(),
                r2 * v.sin()
            ));
        }
    }
    let id = |i: usize, j: usize| (i % n) * m + j % m + 1;
    for i in 0..n {
        for j in 0..m {
            s.push_str(&format!(
                "f {} {} {}\n",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1)
            ));
            s.push_str(&format!(
                "f {} {} {}\n",
                id(i, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            ));
        }
    }
    s
}

/// Runs `flatcut flatten FILE -o DIR/flat.obj --report DIR/flat.json ARGS…`: its exit code (as
/// text) or its error.
fn flatten(file: &Path, dir: &Path, args: &[&str]) -> Result<String, String> {
    let (flat, report) = (dir.join("flat.obj"), dir.join("flat.json"));
    let mut argv = vec![
        "flatcut",
        "flatten",
        file.to_str().unwrap(),
        "-o",
        flat.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    argv.extend_from_slice(args);
    let cli = flatcut_cli::Cli::try_parse_from(argv).unwrap();
    flatcut_cli::run(cli)
        .map(|c| format!("{c:?}"))
        .map_err(|e| format!("{e:#}"))
}

fn area3(o: &Obj) -> f64 {
    o.f.iter()
        .map(|t| {
            let [a, b, c] = t.map(|x| o.v[x.0]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Split wherever a piece is beyond ±5 %.
const SPLIT_WITHIN_5_PCT: &[&str] = &[
    "--max-stretch",
    "5",
    "--max-compress",
    "5",
    "--split",
    "auto",
];

#[test]
fn a_torus_is_opened_and_split_into_parts_within_the_limits_that_close_it_again() {
    let dir = tempfile::tempdir().unwrap();
    let torus = dir.path().join("ring.obj");
    std::fs::write(&torus, torus_obj(60.0, 20.0, 48, 16)).unwrap();
    let code = flatten(
        &torus,
        dir.path(),
        &[
            "--max-stretch",
            "10",
            "--max-compress",
            "10",
            "--split",
            "auto",
            "--max-pieces",
            "32",
        ],
    )
    .unwrap();
    assert_eq!(code, format!("{:?}", std::process::ExitCode::SUCCESS));
    let parts = split_parts(dir.path(), "flat-ring");
    assert!(!parts.is_empty());
    let whole = read_obj(&torus);
    let total: f64 = parts.iter().map(area3).sum();
    assert!(
        (total - area3(&whole)).abs() < 1e-5 * total,
        "{total} vs {}",
        area3(&whole)
    );
    for (i, a) in parts.iter().enumerate() {
        let (s, c) = measured_limits(a);
        assert!(
            s <= 10.0 + 1e-6 && c <= 10.0 + 1e-6,
            "part {i}: {s} % / {c} %"
        );
        for (&u, &w) in &crate::darts::boundary_next(a) {
            let sewn = parts.iter().any(|b| {
                sewn_lengths(a, (u, w), b).is_some_and(|(la, lb)| (la - lb).abs() < SEWN_MM)
            });
            assert!(
                sewn,
                "part {i}: outline edge {} – {} is sewn to nothing",
                a.v[u], a.v[w]
            );
        }
    }
    // The report lists every seam with its length and its visibility cost.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("flat.json")).unwrap())
            .unwrap();
    let pieces = report
        .as_array()
        .cloned()
        .unwrap_or_else(|| vec![report.clone()]);
    let seams: Vec<&serde_json::Value> = pieces
        .iter()
        .flat_map(|p| p["mating_seams"].as_array().into_iter().flatten())
        .collect();
    assert!(!seams.is_empty());
    for s in seams {
        let (l, v) = (
            s["length_3d_mm"].as_f64().unwrap(),
            s["visibility_cost_mm"].as_f64().unwrap(),
        );
        assert!(l > 0.0 && v > 0.0, "{s}");
        // Visibility weighs the length by ½ to 1½ on a bare torus.
        assert!(v >= 0.5 * l - 1e-9 && v <= 1.5 * l + 1e-9, "{s}");
        assert!(s["mismatch_mm"].as_f64().unwrap() <= 0.1, "{s}");
    }
}

#[test]
fn a_surface_that_passes_through_itself_is_refused_naming_where() {
    let dir = tempfile::tempdir().unwrap();
    // Two tetrahedra, the second pushed into the first.
    let mut obj = String::new();
    for off in [0.0, 2.0] {
        for p in [
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [0.0, 0.0, 10.0],
        ] {
            obj.push_str(&format!("v {} {} {}\n", p[0] + off, p[1] + off, p[2] + off));
        }
    }
    for base in [0, 4] {
        for t in [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]] {
            obj.push_str(&format!(
                "f {} {} {}\n",
                t[0] + base + 1,
                t[1] + base + 1,
                t[2] + base + 1
            ));
        }
    }
    let file = dir.path().join("tets.obj");
    std::fs::write(&file, obj).unwrap();
    let err = flatten(&file, dir.path(), SPLIT_WITHIN_5_PCT).unwrap_err();
    assert!(
        err.contains("passes through itself") && err.contains("near ("),
        "{err}"
    );
    assert!(!dir.path().join("flat.json").exists());
}

#[test]
fn a_non_manifold_surface_is_refused_naming_the_edge() {
    let dir = tempfile::tempdir().unwrap();
    // A closed tetrahedron with a fin on its edge 1–2: that edge has three triangles.
    let obj = "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nv 10 10 10\n\
               f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\nf 2 3 5\n";
    let file = dir.path().join("fin.obj");
    std::fs::write(&file, obj).unwrap();
    let err = flatten(&file, dir.path(), SPLIT_WITHIN_5_PCT).unwrap_err();
    assert!(err.contains("edge 1-2"), "{err}");
}

#[test]
fn limits_no_split_can_meet_exit_3_with_the_excess_reached() {
    let dir = tempfile::tempdir().unwrap();
    let ball = dir.path().join("ball.obj");
    std::fs::write(&ball, crate::darts::ball_obj(40.0, 8, 16)).unwrap();
    let flat = dir.path().join("flat.obj");
    let cli = flatcut_cli::Cli::try_parse_from([
        "flatcut",
        "flatten",
        ball.to_str().unwrap(),
        "-o",
        flat.to_str().unwrap(),
        "--max-stretch",
        "0",
        "--max-compress",
        "0",
        "--split",
        "auto",
        "--max-pieces",
        "2",
    ])
    .unwrap();
    let result = flatcut_cli::run(cli);
    let text = match &result {
        Ok(code) => panic!("a ball cannot lie flat within 0 %, yet the run ended {code:?}"),
        Err(e) => format!("{e:#}"),
    };
    assert!(
        text.contains("beyond the limits") && text.contains("at most 2 parts"),
        "{text}"
    );
    assert_eq!(
        format!("{:?}", flatcut_cli::exit_code(result)),
        format!(
            "{:?}",
            std::process::ExitCode::from(flatcut_cli::EXIT_LIMIT)
        )
    );
    assert!(!flat.exists());
}
