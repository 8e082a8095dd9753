//! DXF both ways, checked by ezdxf (an independent reader): the pattern and layout DXFs of the
//! lampshade pass ezdxf's audit with no error and have the AAMA structure; ezdxf's geometry
//! equals ours; the file written again by ezdxf's own writer reads back into flatcut with the
//! same geometry to 1e-6 mm; and `nest` and `gcode` take the DXF as input.
//!
//! The ezdxf checks need Python with ezdxf (`pip install -r tools/requirements.txt`); the
//! interpreter is `$FLATCUT_PYTHON` or `python3`. Without it they are skipped with a message.

use std::path::{Path, PathBuf};
use std::process::Command;

use flatcut::geom::DVec2;
use flatcut::pattern::dxf_read::read_dxf;
use flatcut::pattern::{Drawing, StrokeKind};

use crate::pipeline::{root, run_cli, run_project};

/// The Python that has ezdxf, or `None` (and a message saying why the check is skipped).
pub fn python_with(module: &str) -> Option<String> {
    let py = std::env::var("FLATCUT_PYTHON").unwrap_or_else(|_| "python3".into());
    let ok = Command::new(&py)
        .args(["-c", &format!("import {module}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        Some(py)
    } else {
        eprintln!(
            "SKIPPED: Python module `{module}` not found for `{py}` (pip install -r tools/requirements.txt, or set FLATCUT_PYTHON)"
        );
        None
    }
}

fn ezdxf_check(py: &str, file: &Path, resave: Option<&Path>) -> serde_json::Value {
    let script = root().join("tools/dxf/check_ezdxf.py");
    let mut cmd = Command::new(py);
    cmd.arg(&script).arg(file).arg("--aama");
    if let Some(r) = resave {
        cmd.arg("--resave").arg(r);
    }
    let out = cmd.output().expect("python runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let v: serde_json::Value = serde_json::from_str(text.trim()).unwrap_or_else(|e| {
        panic!(
            "ezdxf check printed no JSON ({e}): {text}\n{}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    eprintln!(
        "ezdxf {} on {}: audit errors {}, fixes {}, recover errors {}, {} block(s), {} insert(s), problems {}",
        v["ezdxf"],
        file.display(),
        v["audit_errors"],
        v["audit_fixes"],
        v["recover_errors"],
        v["blocks"].as_array().map_or(0, Vec::len),
        v["inserts"],
        v["problems"]
    );
    assert!(out.status.success(), "ezdxf check failed: {v}");
    assert_eq!(v["audit_errors"], 0);
    assert_eq!(v["dxfversion"], "AC1009");
    v
}

fn read(path: &Path) -> Drawing {
    let text = std::fs::read_to_string(path).unwrap();
    let r = read_dxf(&text, 0.01).unwrap();
    assert!(
        r.warnings.is_empty(),
        "{}: {:?}",
        path.display(),
        r.warnings
    );
    r.drawing
}

/// Largest distance between corresponding points of the two drawings' strokes (same order).
fn max_deviation(a: &Drawing, b: &Drawing) -> f64 {
    assert_eq!(a.strokes.len(), b.strokes.len());
    let mut worst = 0.0f64;
    for (s, t) in a.strokes.iter().zip(&b.strokes) {
        assert_eq!(
            (s.kind, s.layer, s.closed, s.piece),
            (t.kind, t.layer, t.closed, t.piece)
        );
        assert_eq!(s.points.len(), t.points.len(), "{}", s.id);
        for (p, q) in s.points.iter().zip(&t.points) {
            worst = worst.max(p.distance(*q));
        }
    }
    assert_eq!(a.pieces, b.pieces);
    worst
}

fn lampshade_outputs() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    run_project(
        "patterns/lampshade/project.toml",
        dir.path(),
        &["--no-send"],
    );
    let p = dir.path().to_path_buf();
    (dir, p)
}

#[test]
fn pattern_and_layout_dxf_pass_ezdxf_and_survive_its_writer() {
    let (_dir, out) = lampshade_outputs();
    let Some(py) = python_with("ezdxf") else {
        return;
    };
    for name in ["pattern.dxf", "layout-1.dxf"] {
        let file = out.join(name);
        let resaved = out.join(format!("ezdxf-{name}"));
        let v = ezdxf_check(&py, &file, Some(&resaved));
        let ours = read(&file);
        // ezdxf's world-coordinate boundary equals ours.
        let theirs: Vec<Vec<DVec2>> = v["entities"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["layer"] == "1" && e["type"] == "POLYLINE")
            .map(|e| {
                e["points"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|p| DVec2::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
                    .collect()
            })
            .collect();
        let boundaries: Vec<_> = ours.strokes.iter().filter(|s| s.is_outer()).collect();
        assert_eq!(theirs.len(), boundaries.len());
        for (t, o) in theirs.iter().zip(&boundaries) {
            assert_eq!(t.len(), o.points.len());
            for (p, q) in t.iter().zip(&o.points) {
                assert!(p.distance(*q) <= 1e-9, "{name}: ezdxf {p} vs flatcut {q}");
            }
        }
        let again = read(&resaved);
        let dev = max_deviation(&ours, &again);
        eprintln!("{name}: round trip through ezdxf's writer, largest deviation {dev:.2e} mm");
        assert!(dev <= 1e-6, "{name}: {dev} mm after ezdxf's writer");
    }
}

#[test]
fn nest_and_gcode_take_the_aama_dxf() {
    let (_dir, out) = lampshade_outputs();
    let dxf = out.join("pattern.dxf");
    let d = read(&dxf);
    let info = &d.pieces[0];
    assert_eq!(info.label.name, "shade");
    assert!(info.grain.is_some());
    assert_eq!(
        d.strokes
            .iter()
            .filter(|s| s.kind == StrokeKind::Boundary)
            .count(),
        1
    );
    let layout = out.join("from-dxf.svg");
    let layout_dxf = out.join("from-dxf.dxf");
    run_cli(&[
        "nest",
        dxf.to_str().unwrap(),
        "--sheet",
        "1200x900",
        "--quantity",
        "2",
        "-o",
        layout.to_str().unwrap(),
        "--dxf",
        layout_dxf.to_str().unwrap(),
        "--iters",
        "50",
    ]);
    let nested = read(&layout_dxf);
    assert_eq!(nested.pieces.len(), 2, "two copies placed");
    assert_eq!(nested.strokes.iter().filter(|s| s.is_outer()).count(), 2);
    // notches and drill holes travel with the piece
    let per_piece = |k| d.strokes.iter().filter(|s| s.kind == k).count();
    for k in [
        StrokeKind::Notch,
        StrokeKind::Drill,
        StrokeKind::Sew,
        StrokeKind::Grain,
    ] {
        assert_eq!(
            nested.strokes.iter().filter(|s| s.kind == k).count(),
            2 * per_piece(k),
            "{k:?}"
        );
    }
    let job = out.join("from-dxf.gcode");
    // The bundled knife with a table large enough for the 594 mm shade.
    let knife = std::fs::read_to_string(root().join("crates/gcode/profiles/knife.toml"))
        .unwrap()
        .replace(
            "work_area_mm = [600.0, 400.0]",
            "work_area_mm = [1200.0, 900.0]",
        )
        .replace("offset_mm = [0.0, 0.0]", "offset_mm = [10.0, 10.0]");
    let profile = out.join("big-knife.toml");
    std::fs::write(&profile, knife).unwrap();
    run_cli(&[
        "gcode",
        dxf.to_str().unwrap(),
        "--profile",
        profile.to_str().unwrap(),
        "-o",
        job.to_str().unwrap(),
    ]);
    assert!(
        std::fs::read_to_string(&job)
            .unwrap()
            .contains("shade-cut-1")
    );
}
