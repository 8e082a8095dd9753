//! Broken and hostile STEP files: every one ends in a clear error naming the instance (or the
//! line), never a panic or a hang; a model with an unusable face still serves its other faces.

mod common;

use common::data_dir;
use flatcut_geom::Tolerances;
use flatcut_mesh::tessellate::TessOptions;
use flatcut_step::{Model, StepError, StepFile, Tessellation};

fn text(name: &str) -> String {
    std::fs::read_to_string(data_dir().join(format!("{name}.step"))).unwrap()
}

/// Reads the text as a model and tessellates every face; the first error as text.
fn read_all(text: String) -> Result<(), String> {
    let file = StepFile::parse(text).map_err(|e| e.to_string())?;
    let model = Model::from_file(&file).map_err(|e| e.to_string())?;
    let all: Vec<usize> = (0..model.faces.len()).collect();
    Tessellation::new(&model, &all, &Tolerances::DEFAULT, &TessOptions::DEFAULT)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn replace_once(s: &str, from: &str, to: &str) -> String {
    assert!(s.contains(from), "the test data has no {from:?}");
    s.replacen(from, to, 1)
}

#[test]
fn a_truncated_file_names_the_last_instance_read() {
    let t = text("dome");
    let cut = &t[..t.find("#300 = ").unwrap() + 20];
    let e = read_all(cut.to_string()).unwrap_err();
    assert!(e.contains("truncated") && e.contains("#300"), "{e}");
}

#[test]
fn a_wrong_header_is_refused() {
    let e = read_all(replace_once(
        &text("cone"),
        "ISO-10303-21;",
        "ISO-10303-22;",
    ))
    .unwrap_err();
    assert!(e.contains("not an ISO 10303-21"), "{e}");
    let e = read_all(replace_once(&text("cone"), "HEADER;", "HEADR;")).unwrap_err();
    assert!(e.starts_with("line 2") && e.contains("HEADER"), "{e}");
    let e = read_all("solid cube\nfacet normal 0 0 1\n".into()).unwrap_err();
    assert!(e.contains("not an ISO 10303-21"), "{e}");
}

#[test]
fn a_dangling_reference_names_both_instances() {
    let t = replace_once(
        &text("cylinder"),
        "#21 = EDGE_CURVE('',#22,#24,",
        "#21 = EDGE_CURVE('',#99999,#24,",
    );
    let file = StepFile::parse(t).unwrap();
    let model = Model::from_file(&file).unwrap();
    let bad = model.edges.iter().find(|e| e.entity == 21).unwrap();
    assert_eq!(
        bad.geometry.as_ref().unwrap_err(),
        &StepError::Dangling {
            from: 21,
            to: 99999
        }
    );
    let e = Tessellation::new(&model, &[0], &Tolerances::DEFAULT, &TessOptions::DEFAULT)
        .unwrap_err()
        .to_string();
    assert!(e.contains("#21 refers to #99999"), "{e}");
}

#[test]
fn cyclic_references_are_found() {
    // A placement whose location is the placement itself.
    let t = replace_once(
        &text("cylinder"),
        "#33 = AXIS2_PLACEMENT_3D('',#34,",
        "#33 = AXIS2_PLACEMENT_3D('',#33,",
    );
    let e = read_all(t).unwrap_err();
    assert!(e.contains("#33 refers to itself"), "{e}");
    // A B-spline surface whose control point is the surface.
    let t = replace_once(&text("dome"), "(#249,#250,", "(#248,#250,");
    let e = read_all(t).unwrap_err();
    assert!(e.contains("#248 refers to itself"), "{e}");
}

#[test]
fn knots_must_increase_and_multiplicities_must_fit() {
    let t = replace_once(
        &text("dome"),
        "(4,1,1,1,1,1,4),(0.,\n    0.183882603129",
        "(4,1,1,1,1,1,4),(0.,\n    0.9",
    );
    let e = read_all(t).unwrap_err();
    assert!(
        e.contains("#248 = B_SPLINE_SURFACE_WITH_KNOTS") && e.contains("knots must increase"),
        "{e}"
    );
    // A multiplicity of 10^15 is refused before anything is expanded.
    let t = replace_once(
        &text("dome"),
        "(4,1,1,1,1,1,4),(4,1,1,1,1,1,4)",
        "(4,1,1,1,1,1,4),(4,1000000000000000,1,1,1,1,4)",
    );
    let e = read_all(t).unwrap_err();
    assert!(e.contains("#248") && e.contains("multiplicities"), "{e}");
    let t = replace_once(
        &text("dome"),
        "B_SPLINE_SURFACE_WITH_KNOTS('',3,3,",
        "B_SPLINE_SURFACE_WITH_KNOTS('',300,3,",
    );
    let e = read_all(t).unwrap_err();
    assert!(e.contains("#248") && e.contains("u_degree"), "{e}");
}

#[test]
fn weights_must_be_positive() {
    let t = replace_once(
        &text("hull"),
        "RATIONAL_B_SPLINE_CURVE((1.,",
        "RATIONAL_B_SPLINE_CURVE((0.,",
    );
    let e = read_all(t).unwrap_err();
    assert!(
        e.contains("weights must be > 0") && e.contains("#105"),
        "{e}"
    );
}

#[test]
fn non_finite_and_non_numbers_are_refused() {
    let t = replace_once(
        &text("cylinder"),
        "#34 = CARTESIAN_POINT('',(0.,",
        "#34 = CARTESIAN_POINT('',(1.E+999,",
    );
    let e = read_all(t).unwrap_err();
    assert!(e.contains("(#34)") && e.contains("out of range"), "{e}");
    let t = replace_once(
        &text("cylinder"),
        "#34 = CARTESIAN_POINT('',(0.,",
        "#34 = CARTESIAN_POINT('',(NaN,",
    );
    let e = read_all(t).unwrap_err();
    assert!(e.contains("(#34)"), "{e}");
    let t = replace_once(
        &text("cylinder"),
        "CYLINDRICAL_SURFACE('',#33,30.)",
        "CYLINDRICAL_SURFACE('',#33,'thirty')",
    );
    let e = read_all(t).unwrap_err();
    assert!(
        e.contains("CYLINDRICAL_SURFACE: attribute 3 (radius): expected a number, found a string"),
        "{e}"
    );
    let t = replace_once(
        &text("cylinder"),
        "CYLINDRICAL_SURFACE('',#33,30.)",
        "CYLINDRICAL_SURFACE('',#33,-30.)",
    );
    let e = read_all(t).unwrap_err();
    assert!(
        e.contains("#32 = CYLINDRICAL_SURFACE") && e.contains("radius"),
        "{e}"
    );
}

#[test]
fn an_unsupported_face_is_named_and_the_others_still_load() {
    let t = replace_once(
        &text("fillet_box"),
        "#32 = PLANE('',#33);",
        "#32 = OFFSET_SURFACE('',#44,1.,.F.);",
    );
    let file = StepFile::parse(t).unwrap();
    let model = Model::from_file(&file).unwrap();
    let bad: Vec<usize> = (0..model.faces.len())
        .filter(|&f| model.face(f).is_err())
        .collect();
    assert_eq!(bad, [0]);
    assert_eq!(
        model.face(0).unwrap_err().to_string(),
        "#32 = OFFSET_SURFACE: not supported"
    );
    let others: Vec<usize> = (1..model.faces.len()).collect();
    Tessellation::new(&model, &others, &Tolerances::DEFAULT, &TessOptions::DEFAULT).unwrap();
    let e = Tessellation::new(&model, &[0, 1], &Tolerances::DEFAULT, &TessOptions::DEFAULT)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("face 0 (#17)") && e.contains("#32 = OFFSET_SURFACE: not supported"),
        "{e}"
    );
}

#[test]
fn a_file_without_shells_or_with_garbage_says_so() {
    let t = text("cone");
    let start = t.find("DATA;").unwrap() + 5;
    let end = t.find("ENDSEC;\nEND-ISO").unwrap();
    let empty = format!(
        "{}\n#1 = CARTESIAN_POINT('',(0.,0.,0.));\n{}",
        &t[..start],
        &t[end..]
    );
    assert_eq!(
        read_all(empty).unwrap_err(),
        StepError::NoShells.to_string()
    );
    let e = read_all(replace_once(&t, "#20 = ", "#20 = = ")).unwrap_err();
    assert!(e.contains("(#20)"), "{e}");
    let e = read_all(replace_once(&t, "#20 = ", "#20 = \u{7}")).unwrap_err();
    assert!(e.contains("(#20)") && e.contains("unexpected"), "{e}");
}

/// A 100 MB file: a real model followed by a million unreferenced points reads in one linear pass
/// (the points are indexed, never parsed), and the same file cut short names its last instance.
#[test]
fn a_hundred_megabyte_file_is_read_in_bounded_work() {
    let t = text("cylinder");
    let end = t.find("ENDSEC;\nEND-ISO").unwrap();
    let mut big = String::with_capacity(105 << 20);
    big.push_str(&t[..end]);
    let mut id = 1_000_000u64;
    while big.len() < 100 << 20 {
        big.push_str(&format!(
            "#{id} = CARTESIAN_POINT('',(1.234567890123,-9.87654321098E-01,{}.5));\n",
            id % 977
        ));
        id += 1;
    }
    let last = id - 1;
    let cut = big.clone();
    big.push_str(&t[end..]);
    let file = StepFile::parse(big).unwrap();
    assert!(file.len() > 1_000_000);
    let model = Model::from_file(&file).unwrap();
    assert_eq!(model.faces.len(), 1);
    drop(file);
    let e = read_all(cut).unwrap_err();
    assert!(
        e.contains("truncated") && e.contains(&format!("#{last}")),
        "{e}"
    );
}
