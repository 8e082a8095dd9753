//! STEP models through the whole tool: `inspect` of a file in inches, developable faces and
//! smooth groups that flatten with no distortion, a project whose design is a STEP file, the
//! bundled kayak skin, and the seams of real models: every shared edge one mating seam of its
//! full length, and separate sheet bodies sewn where they meet.

use std::path::{Path, PathBuf};

use clap::Parser as _;
use flatcut::flatten::{FlattenParams, Method};
use flatcut::geom::Tolerances;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn data(name: &str) -> PathBuf {
    root().join("crates/step/tests/data").join(name)
}

fn run_cli(args: &[&str]) -> std::process::ExitCode {
    let cli =
        flatcut_cli::Cli::try_parse_from(std::iter::once("flatcut").chain(args.iter().copied()))
            .expect("valid arguments");
    flatcut_cli::run(cli).expect("the command succeeds")
}

#[test]
fn inspect_of_a_step_file_lists_faces_edges_and_its_unit() {
    let r =
        flatcut::inspect::inspect_file(&data("bracket_inch.step"), &Tolerances::DEFAULT).unwrap();
    let j = serde_json::to_value(&r).unwrap();
    assert_eq!(j["unit"]["name"], "inch");
    assert_eq!(j["unit"]["mm"], 25.4);
    let faces = j["faces"].as_array().unwrap();
    let pieces = j["pieces"].as_array().unwrap();
    assert_eq!((faces.len(), pieces.len()), (11, 11));
    assert_eq!(j["edges"].as_array().unwrap().len(), 27);
    // The plate's top: 3 × 1.5 in less a 0.5 in hole and a 0.75 × 0.5 in slot, in mm² (the hole
    // is a fine polygon when the area is integrated: 1e-5 relative at most).
    let top = (3.0 * 1.5 - std::f64::consts::PI * 0.25 * 0.25 - 0.75 * 0.5) * 25.4 * 25.4;
    let found = faces
        .iter()
        .filter_map(|f| f["area_mm2"].as_f64())
        .filter(|a| (a - top).abs() < 1e-5 * top)
        .count();
    assert_eq!(found, 2, "top and bottom faces of {top} mm²");
    let piece_area: f64 = pieces.iter().map(|p| p["area_mm2"].as_f64().unwrap()).sum();
    let face_area: f64 = faces.iter().map(|f| f["area_mm2"].as_f64().unwrap()).sum();
    assert!((piece_area - face_area).abs() < 1e-9 * face_area);
    // Every edge of the closed solid joins two faces; the hole's seam joins its face to itself.
    for e in j["edges"].as_array().unwrap() {
        assert_eq!(e["faces"].as_array().unwrap().len(), 2, "{e}");
    }
    assert!(faces.iter().all(|f| f["developable"] == true));
    let text = r.to_string();
    assert!(
        text.contains("unit inch (25.4 mm)") && text.contains("cylinder"),
        "{text}"
    );
}

#[test]
fn inspect_of_a_truncated_step_file_names_the_file_once() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(data("bracket_inch.step")).unwrap();
    let path = dir.path().join("half.step");
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    let name = path.to_str().unwrap();
    let cli = flatcut_cli::Cli::try_parse_from(["flatcut", "inspect", name]).unwrap();
    let report = flatcut_cli::error_report(&flatcut_cli::run(cli).expect_err("refused"));
    assert_eq!(report.matches(name).count(), 1, "{report}");
    assert!(
        report.starts_with(&format!("error: {name}: line ")),
        "{report}"
    );
    assert!(report.contains("(is it truncated?)"), "{report}");
}

/// Flattens every piece of a design (or a STEP file) and returns (name, δ2 max) per piece.
fn delta2(path: &Path) -> Vec<(String, f64)> {
    let flat = flatcut::pipeline::flatten_design(
        path,
        &Tolerances::DEFAULT,
        &FlattenParams::new(Method::Isometric),
        None,
        None,
        None,
        &mut |_, _, _| {},
    )
    .unwrap();
    flat.pieces
        .iter()
        .map(|p| {
            let r = flatcut::pipeline::report_piece(&p.def.name, &p.mesh, &[], None, None).unwrap();
            (p.def.name.clone(), r.delta2_max)
        })
        .collect()
}

#[test]
fn developable_step_faces_flatten_without_distortion() {
    for model in ["cylinder", "cone", "extrusion", "fillet_box"] {
        for (name, d) in delta2(&data(&format!("{model}.step"))) {
            assert!(d < 1e-8, "{model} {name}: δ2 max {d}");
        }
    }
}

#[test]
fn smooth_faces_form_one_piece_that_still_unfolds_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let design = dir.path().join("design.toml");
    std::fs::write(
        &design,
        format!(
            "[[piece]]\nname = \"box\"\n[piece.surface]\ntype = \"step\"\nfile = {:?}\ngroup = \"smooth\"\n",
            data("fillet_box.step")
        ),
    )
    .unwrap();
    let d = flatcut::design::Design::load(&design).unwrap();
    // Seven faces: the fillet and the two planes it blends make one piece.
    let groups: Vec<Vec<usize>> = d
        .pieces
        .iter()
        .map(|p| match &p.surface {
            flatcut::design::SurfaceDef::Step {
                faces: flatcut::design::StepFaces::List(f),
                ..
            } => f.clone(),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(groups.len(), 5, "{groups:?}");
    let blended = d.pieces.iter().find(|p| match &p.surface {
        flatcut::design::SurfaceDef::Step {
            faces: flatcut::design::StepFaces::List(f),
            ..
        } => f.len() == 3,
        _ => false,
    });
    let blended = blended.expect("one piece of three faces");
    assert!(blended.name.starts_with("box-f"));
    for (name, d2) in delta2(&design) {
        assert!(d2 < 1e-8, "{name}: δ2 max {d2}");
    }
}

#[test]
fn a_project_whose_design_is_a_step_file_runs() {
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("project.toml");
    std::fs::write(
        &project,
        format!(
            "name = \"cone\"\ndesign = {:?}\nmethod = \"isometric\"\nseam_mm = 5.0\n[material]\nname = \"felt\"\n[sheet]\nwidth_mm = 600.0\nheight_mm = 400.0\n[machine]\nprofile = \"knife\"\n",
            data("cone.step")
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let code = run_cli(&[
        "run",
        project.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--no-send",
        "--quiet",
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    // The whole cone frustum, cut open along its seam edge, lies flat with no distortion.
    assert!(
        report[0]["delta2_max"].as_f64().unwrap() < 1e-8,
        "{}",
        report[0]
    );
    for f in ["pattern.svg", "layout-1.svg", "job-1.gcode"] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

#[test]
fn the_kayak_skin_is_cut_from_its_cad_model() {
    // Panel areas as OpenCASCADE gives them for patterns/kayak/hull.step (make.py).
    let r = flatcut::inspect::inspect_file(
        &root().join("patterns/kayak/design.toml"),
        &Tolerances::DEFAULT.with_chord_mm(0.2),
    )
    .unwrap();
    let want = [
        ("bottom starboard", 598_571.4),
        ("side starboard", 757_222.8),
        ("bottom port", 598_571.4),
        ("side port", 757_222.8),
    ];
    assert_eq!(r.pieces.len(), 4);
    for (p, (name, area)) in r.pieces.iter().zip(want) {
        assert_eq!(p.name, name);
        assert!(
            (p.area_mm2 - area).abs() < 1e-3 * area,
            "{name}: {}",
            p.area_mm2
        );
    }
    let out = tempfile::tempdir().unwrap();
    let p = root().join("patterns/kayak/project.toml");
    let code = run_cli(&[
        "run",
        p.to_str().unwrap(),
        "-o",
        out.path().to_str().unwrap(),
        "--no-send",
        "--quiet",
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("report.json")).unwrap())
            .unwrap();
    for piece in report.as_array().unwrap() {
        assert_eq!(piece["flipped"], 0);
        assert!(piece["stretch_max_pct"].as_f64().unwrap() < 3.0, "{piece}");
    }
    for f in ["pattern.svg", "pattern.dxf", "layout-1.svg", "job-1.gcode"] {
        assert!(out.path().join(f).is_file(), "{f}");
    }
}

fn corpus(name: &str) -> PathBuf {
    root().join("crates/step/tests/corpus").join(name)
}

/// A corpus file assembled as a design (every face a piece) at chordal tolerance `chord` mm.
fn assembled(name: &str, chord: f64) -> flatcut::design::Assembly {
    let path = corpus(name);
    let design = flatcut::design::Design::load(&path).unwrap();
    let tol = Tolerances::DEFAULT.with_chord_mm(chord);
    design.assemble(path.parent().unwrap(), &tol).unwrap()
}

/// The length of a seam side: its polyline on the piece's mesh.
fn side_length(a: &flatcut::design::Assembly, side: &flatcut::mesh::mating::SeamSide) -> f64 {
    let m = &a.pieces[side.piece].mesh;
    side.vertices
        .windows(2)
        .map(|w| m.positions[w[0] as usize].distance(m.positions[w[1] as usize]))
        .sum()
}

#[test]
fn every_edge_of_a_filleted_box_is_one_mating_seam_of_its_full_length() {
    // A 60 × 40 × 30 box with every edge filleted R 6 (OCCT): 26 faces, each a piece. Its 48
    // edges are 24 straight fillet edges (2 × (4 × 48 + 4 × 28 + 4 × 18) mm) and 24 quarter
    // circles of R 6 where the fillets meet the sphere corners; once each fillet's end arc and
    // the corner beside it were sampled apart (T-junctions) and most arcs left unsewn.
    let a = assembled("occt_box_filleted.step", 0.1);
    assert_eq!(a.pieces.len(), 26);
    let lines = 2.0 * (4.0 * 48.0 + 4.0 * 28.0 + 4.0 * 18.0);
    let arcs = 24.0 * 3.0 * std::f64::consts::PI;
    let mut total = 0.0;
    for s in &a.seams {
        let (l0, l1) = (side_length(&a, &s.sides[0]), side_length(&a, &s.sides[1]));
        assert!((l0 - l1).abs() < 1e-9, "{}: sides {l0} and {l1} mm", s.name);
        total += l0;
    }
    assert_eq!(a.seams.len(), 48);
    // The arcs' chords at 0.1 mm fall short of the arcs by 1e-3 relative at most.
    assert!(
        (total - (lines + arcs)).abs() < 1e-3 * (lines + arcs),
        "seams total {total} mm, edges {} mm",
        lines + arcs
    );
    // The pieces weld back into the closed box: every boundary edge of a piece is on a seam.
    let boundary: usize = a
        .pieces
        .iter()
        .map(|p| {
            flatcut::mesh::Topology::build(&p.mesh)
                .unwrap()
                .boundary_loops
                .iter()
                .map(Vec::len)
                .sum::<usize>()
        })
        .sum();
    let on_seams: usize = a
        .seams
        .iter()
        .flat_map(|s| &s.sides)
        .map(|s| s.vertices.len() - 1)
        .sum();
    assert_eq!(boundary, on_seams, "boundary edges not on a seam");
}

#[test]
fn a_disk_sewn_to_a_sphere_rim_is_sewn_along_the_rim_once() {
    // A sphere R 100 cut at y = 50 (OCCT): a disk of radius √7500 sewn to the sphere's rim. The
    // rim was once reported as seams of twice its length (and the sphere's face read as the cap
    // it leaves out).
    let a = assembled("occt_sphere_cut_y.step", 0.1);
    let rim = 2.0 * std::f64::consts::PI * 7500f64.sqrt();
    let total: f64 = a.seams.iter().map(|s| side_length(&a, &s.sides[0])).sum();
    for s in &a.seams {
        let (l0, l1) = (side_length(&a, &s.sides[0]), side_length(&a, &s.sides[1]));
        assert!((l0 - l1).abs() < 1e-9, "{}: sides {l0} and {l1} mm", s.name);
    }
    assert!(
        (total - rim).abs() < 1e-3 * rim,
        "seams total {total} mm, the rim {rim} mm"
    );
    let disk = a
        .pieces
        .iter()
        .find(|p| p.mesh.positions.iter().all(|q| (q.y - 50.0).abs() < 1e-6))
        .expect("the disk");
    let area = disk.mesh.area();
    let want = std::f64::consts::PI * 7500.0;
    assert!((area - want).abs() < 2e-3 * want, "disk {area} mm², {want}");
}

#[test]
fn separate_sheet_bodies_meet_at_mating_seams() {
    // A tube of two half-cylinder sheets (R 30, 80 long), each its own shell with edges of its
    // own (OCCT): the two 80 mm lines where they meet were two free borders each, no seam. Sewn,
    // they are two mating seams of their full length, equal on both sides, and the pieces'
    // boundaries off the seams are the two end circles.
    let a = assembled("occt_cylinder_panels.step", 0.05);
    assert_eq!(a.pieces.len(), 2);
    assert_eq!(
        a.seams.len(),
        2,
        "{:?}",
        a.seams.iter().map(|s| &s.name).collect::<Vec<_>>()
    );
    for s in &a.seams {
        let (l0, l1) = (side_length(&a, &s.sides[0]), side_length(&a, &s.sides[1]));
        assert!(
            (l0 - 80.0).abs() < 1e-9 && (l1 - 80.0).abs() < 1e-9,
            "{}: {l0}, {l1}",
            s.name
        );
    }
}

#[test]
fn inspect_says_which_edge_each_sewn_edge_was_sewn_into() {
    // The two-sheet tube: each meeting line was an edge of each sheet. The edge sewing dropped
    // bounds no face of its own; inspect names the edge it became (it used to list it with no
    // faces, as if it bounded nothing).
    let r =
        flatcut::inspect::inspect_file(&corpus("occt_cylinder_panels.step"), &Tolerances::DEFAULT)
            .unwrap();
    let j = serde_json::to_value(&r).unwrap();
    let edges = j["edges"].as_array().unwrap();
    let sewn: Vec<&serde_json::Value> = edges.iter().filter(|e| e["sewn_into"].is_u64()).collect();
    assert_eq!(sewn.len(), 2, "{edges:?}");
    for e in &sewn {
        assert!(e["faces"].as_array().unwrap().is_empty(), "{e}");
        let into = &edges[e["sewn_into"].as_u64().unwrap() as usize];
        assert_eq!(into["faces"].as_array().unwrap().len(), 2, "{into}");
        assert!(into["sewn_into"].is_null());
        assert!(
            (into["length_mm"].as_f64().unwrap() - 80.0).abs() < 1e-9,
            "{into}"
        );
        let line = format!("sewn into {} (#{})", into["index"], into["entity"]);
        assert!(r.to_string().contains(&line), "{line} not in\n{r}");
    }
    // Edges sewing did not touch say nothing of it.
    assert_eq!(
        edges
            .iter()
            .filter(|e| e.get("sewn_into").is_some())
            .count(),
        2
    );
}

#[test]
fn an_assembly_places_its_instances_and_counts_them() {
    // One 40 × 30 × 20 box placed three times by an OCCT (XCAF) assembly, the third turned 30°
    // about z: three shells where OCCT puts them (the corpus test compares the centre of area
    // with OCCT's), and one body of quantity 3.
    let r = flatcut::inspect::inspect_file(&corpus("occt_assembly.step"), &Tolerances::DEFAULT)
        .unwrap();
    let j = serde_json::to_value(&r).unwrap();
    assert_eq!(j["shells"].as_array().unwrap().len(), 3);
    let bodies = j["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 1, "{bodies:?}");
    assert_eq!(bodies[0]["quantity"], 3);
    let faces = j["faces"].as_array().unwrap();
    assert_eq!(faces.len(), 18);
    let area: f64 = faces.iter().map(|f| f["area_mm2"].as_f64().unwrap()).sum();
    assert!((area - 3.0 * 5200.0).abs() < 1e-6 * area, "{area}");
    // The turned box reaches furthest in x at its part corner (40, 0): (100, 0) + 40 (cos 30°,
    // sin 30°), and in y at (40, 30) turned: 40 sin 30° + 30 cos 30°.
    let c = 30f64.to_radians();
    let max = |k: usize| {
        faces
            .iter()
            .map(|f| f["bbox_mm"][1][k].as_f64().unwrap())
            .fold(f64::NEG_INFINITY, f64::max)
    };
    assert!(
        (max(0) - (100.0 + 40.0 * c.cos())).abs() < 1e-6,
        "{}",
        max(0)
    );
    assert!(
        (max(1) - (40.0 * c.sin() + 30.0 * c.cos())).abs() < 1e-6,
        "{}",
        max(1)
    );
}
