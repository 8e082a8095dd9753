//! `type = "step"` pieces: expansion per face and per smooth group, the face selection checked
//! against the model, and errors that name the file, the piece and what is wrong.

use std::path::{Path, PathBuf};

use flatcut_design::{Design, PieceGeometry, StepFaces, SurfaceDef};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../step/tests/data")
        .join(name)
}

/// Loads a design with one step piece whose `[piece.surface]` has the extra keys.
fn load(extra: &str, piece_extra: &str) -> Result<Design, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("design.toml");
    std::fs::write(
        &path,
        format!(
            "[[piece]]\nname = \"part\"\n{piece_extra}\n[piece.surface]\ntype = \"step\"\nfile = {:?}\n{extra}\n",
            data("fillet_box.step")
        ),
    )
    .unwrap();
    Design::load(&path).map_err(|e| e.to_string())
}

fn faces(d: &Design) -> Vec<Vec<usize>> {
    d.pieces
        .iter()
        .map(|p| match &p.surface {
            SurfaceDef::Step {
                faces: StepFaces::List(f),
                ..
            } => f.clone(),
            other => panic!("not expanded: {other:?}"),
        })
        .collect()
}

#[test]
fn pieces_expand_per_face_and_per_smooth_group() {
    let d = load("", "").unwrap();
    assert_eq!(faces(&d), (0..7).map(|f| vec![f]).collect::<Vec<_>>());
    assert_eq!(d.pieces[3].name, "part-f3");
    // The fillet (face 2) blends the 40 × 20 and 30 × 20 sides (faces 5 and 0); the end faces
    // (1 and 4) meet it at right angles.
    let d = load("group = \"smooth\"", "").unwrap();
    assert_eq!(
        faces(&d),
        [vec![0, 2, 5], vec![1], vec![3], vec![4], vec![6]]
    );
    let d = load("faces = [5, 2]\ngroup = \"smooth\"", "quantity = 2").unwrap();
    assert_eq!(faces(&d), [vec![2, 5]]);
    assert_eq!(
        (d.pieces[0].name.as_str(), d.pieces[0].quantity),
        ("part", 2)
    );
    // The pieces share one read of the model.
    let d = load("", "").unwrap();
    let model = |k: usize| match &d.pieces[k].surface {
        SurfaceDef::Step { model: Some(m), .. } => m.clone(),
        _ => panic!(),
    };
    assert_eq!(model(0), model(6));
    match d.pieces[2].build(Path::new(".")).unwrap() {
        PieceGeometry::Step(s) => assert_eq!(s.faces, [2]),
        _ => panic!("a STEP piece"),
    }
}

#[test]
fn a_step_file_loads_as_a_design_of_its_faces() {
    let d = Design::load(&data("hull.step")).unwrap();
    let names: Vec<&str> = d.pieces.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["hull-f0", "hull-f1", "hull-f2", "hull-f3"]);
}

#[test]
fn bad_selections_are_named() {
    let e = load("faces = \"some\"", "").unwrap_err();
    assert!(
        e.contains("piece 0 'part'") && e.contains("\"all\" or a list"),
        "{e}"
    );
    let e = load("faces = [7]", "").unwrap_err();
    assert!(
        e.contains("face 7 does not exist (the model has 7 faces, 0 to 6)"),
        "{e}"
    );
    let e = load("faces = []", "").unwrap_err();
    assert!(e.contains("the face list is empty"), "{e}");
    let e = load("group = \"ply\"", "").unwrap_err();
    assert!(e.contains("ply"), "{e}");
    let e = load("", "grain = [[0, 0, 0], [1, 0, 0]]").unwrap_err();
    assert!(
        e.contains("make 7 pieces") && e.contains("one piece"),
        "{e}"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("design.toml");
    std::fs::write(
        &path,
        "[[piece]]\nname = \"x\"\n[piece.surface]\ntype = \"step\"\nfile = \"missing.step\"\n",
    )
    .unwrap();
    let e = Design::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("piece 0 'x'") && e.contains("missing.step"),
        "{e}"
    );
}

/// The first half of a STEP file, cut inside its data section.
fn truncated(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(data("fillet_box.step")).unwrap();
    let path = dir.join("cut.step");
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    path
}

#[test]
fn a_truncated_step_file_loaded_as_a_design_is_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let path = truncated(dir.path());
    let e = Design::load(&path).unwrap_err().to_string();
    let name = path.display().to_string();
    assert_eq!(e.matches(&name).count(), 1, "{e}");
    assert!(e.starts_with(&format!("{name}: line ")), "{e}");
    assert!(e.ends_with("(is it truncated?)"), "{e}");
    assert!(!e.contains("piece 0"), "{e}");
}

#[test]
fn a_truncated_step_file_of_a_design_names_the_design_the_piece_and_the_model_once() {
    let dir = tempfile::tempdir().unwrap();
    let step = truncated(dir.path());
    let path = dir.path().join("design.toml");
    std::fs::write(
        &path,
        "[[piece]]\nname = \"x\"\n[piece.surface]\ntype = \"step\"\nfile = \"cut.step\"\n",
    )
    .unwrap();
    let e = Design::load(&path).unwrap_err().to_string();
    let (design, model) = (path.display().to_string(), step.display().to_string());
    assert!(
        e.starts_with(&format!("{design}: piece 0 'x': {model}: line ")),
        "{e}"
    );
    assert_eq!(e.matches("cut.step").count(), 1, "{e}");
    assert!(e.ends_with("(is it truncated?)"), "{e}");
}

#[test]
fn a_missing_step_file_is_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gone.step");
    let e = Design::load(&path).unwrap_err().to_string();
    assert_eq!(e.matches("gone.step").count(), 1, "{e}");
    let design = dir.path().join("design.toml");
    std::fs::write(
        &design,
        "[[piece]]\nname = \"x\"\n[piece.surface]\ntype = \"step\"\nfile = \"gone.step\"\n",
    )
    .unwrap();
    let e = Design::load(&design).unwrap_err().to_string();
    assert_eq!(e.matches("gone.step").count(), 1, "{e}");
    assert!(e.contains("piece 0 'x'"), "{e}");
}
