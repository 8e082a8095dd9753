//! A STEP model whose faces become separate pieces: the edges the faces share are mating seams,
//! flattened together so both sides come out equally long, and the seam in 3D is the edge as
//! OpenCASCADE measures it (`crates/step/tests/data/hull.edges.json`, written by
//! `tools/step/edge_lengths.py` from the same file: BRepGProp's length of the exact curve).

use std::path::{Path, PathBuf};

use flatcut::design::Design;
use flatcut::flatten::assembly::flatten_assembly;
use flatcut::flatten::{FlattenParams, Method};
use flatcut::geom::{DVec3, Tolerances};
use flatcut::mesh::TriMesh;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../step/tests/data")
        .join(name)
}

/// OCCT's edges: (length, start, end).
fn occt_edges() -> Vec<(f64, DVec3, DVec3)> {
    let text = std::fs::read_to_string(data("hull.edges.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let p = |x: &serde_json::Value| {
        let a: Vec<f64> = x
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_f64().unwrap())
            .collect();
        DVec3::new(a[0], a[1], a[2])
    };
    v["edges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["length_mm"].as_f64().unwrap(),
                p(&e["start"]),
                p(&e["end"]),
            )
        })
        .collect()
}

fn length<P: Copy>(pts: &[P], dist: impl Fn(P, P) -> f64) -> f64 {
    pts.windows(2).map(|w| dist(w[0], w[1])).sum()
}

#[test]
fn the_edges_a_step_models_pieces_share_are_seams_of_equal_length_as_long_as_occts_edges() {
    let path = data("hull.step");
    let d = Design::load(&path).unwrap();
    let tol = Tolerances::DEFAULT;
    let a = d.assemble(path.parent().unwrap(), &tol).unwrap();
    assert_eq!(a.pieces.len(), 4);
    // The keel and the two chines (the sheer lines and the stems are free edges).
    assert_eq!(
        a.seams.len(),
        3,
        "{:?}",
        a.seams.iter().map(|s| &s.name).collect::<Vec<_>>()
    );
    let meshes: Vec<&TriMesh> = a.pieces.iter().map(|p| &p.mesh).collect();
    let flats =
        flatten_assembly(&meshes, &a.seams, &FlattenParams::new(Method::Isometric)).unwrap();
    let occt = occt_edges();
    for s in &a.seams {
        let pts3 = s.points_3d(0, &meshes);
        assert_eq!(
            pts3,
            s.points_3d(1, &meshes),
            "{}: the same 3D points",
            s.name
        );
        let (first, last) = (pts3[0], pts3[pts3.len() - 1]);
        let &(l_occt, ..) = occt
            .iter()
            .find(|(_, a, b)| {
                (a.distance(first) < 1e-3 && b.distance(last) < 1e-3)
                    || (a.distance(last) < 1e-3 && b.distance(first) < 1e-3)
            })
            .unwrap_or_else(|| panic!("{}: no OCCT edge from {first} to {last}", s.name));
        let l3 = length(&pts3, DVec3::distance);
        let flat = |k: usize| {
            let side = &s.sides[k];
            let uv = &flats[side.piece].uv;
            let pts: Vec<_> = side.vertices.iter().map(|&v| uv[v as usize]).collect();
            length(&pts, |p, q| p.distance(q))
        };
        let (la, lb) = (flat(0), flat(1));
        eprintln!(
            "{}: OCCT {l_occt:.4} mm, 3D polyline {l3:.4} mm, flat {la:.4} / {lb:.4} mm",
            s.name
        );
        assert!((la - lb).abs() < 0.01, "{}: {la} vs {lb}", s.name);
        // The polyline's vertices lie on the curve: it is shorter than the curve by far less
        // than the chordal tolerance over a 900 mm edge.
        assert!(
            l3 <= l_occt + 1e-6 && l_occt - l3 < tol.chord_mm,
            "{}: {l3} vs {l_occt}",
            s.name
        );
        // Flattened (isometric, δ2: not length-keeping), the seam stretches as little as the
        // nearly developable faces need: 0.016–0.028 % measured; a bound of 0.05 %.
        assert!(
            (la - l_occt).abs() < 5e-4 * l_occt,
            "{}: {la} vs {l_occt}",
            s.name
        );
    }
}

#[test]
fn a_step_edge_named_as_a_style_line_splits_a_part_along_it() {
    // The keel (#206, between faces 0 and 2) cuts the hull's skin into starboard and port.
    let text = r#"
[[part]]
name = "skin"
[part.surface]
type = "step"
file = "hull.step"
[[part.line]]
name = "keel"
edge = 206
[[part.piece]]
name = "starboard"
at = [450, 15.032, 4.381]
[[part.piece]]
name = "port"
at = [450, -15.032, 4.381]
"#;
    let d = Design::from_toml_str(text, "skin.toml").unwrap();
    let tol = Tolerances::DEFAULT;
    let a = d.assemble(&data(""), &tol).unwrap();
    let names: Vec<&str> = a.pieces.iter().map(|p| p.def.name.as_str()).collect();
    assert_eq!(names, ["starboard", "port"]);
    assert_eq!(a.seams.len(), 1);
    let s = &a.seams[0];
    assert_eq!(s.name, "keel");
    let meshes: Vec<&TriMesh> = a.pieces.iter().map(|p| &p.mesh).collect();
    let pts3 = s.points_3d(0, &meshes);
    // The keel from stem to stern, as long as OCCT's edge to the chordal tolerance.
    let &(l_occt, e0, e1) = occt_edges()
        .iter()
        .find(|(l, ..)| (l - 901.8484).abs() < 1e-3)
        .unwrap();
    let ends = [pts3[0], pts3[pts3.len() - 1]];
    assert!(
        (ends[0].distance(e0) < 1e-6 && ends[1].distance(e1) < 1e-6)
            || (ends[0].distance(e1) < 1e-6 && ends[1].distance(e0) < 1e-6),
        "{ends:?}"
    );
    assert!(pts3.iter().all(|p| p.y.abs() < 1e-9), "on the keel, y = 0");
    let l3 = length(&pts3, DVec3::distance);
    assert!(
        l3 <= l_occt + 1e-6 && l_occt - l3 < tol.chord_mm,
        "{l3} vs {l_occt}"
    );
    let flats =
        flatten_assembly(&meshes, &a.seams, &FlattenParams::new(Method::Isometric)).unwrap();
    let flat = |k: usize| {
        let side = &s.sides[k];
        let pts: Vec<_> = side
            .vertices
            .iter()
            .map(|&v| flats[side.piece].uv[v as usize])
            .collect();
        length(&pts, |p, q| p.distance(q))
    };
    assert!(
        (flat(0) - flat(1)).abs() < 0.01,
        "{} vs {}",
        flat(0),
        flat(1)
    );
    // A line naming an edge the model does not have says so.
    let bad = text.replace("edge = 206", "edge = 207");
    let e = Design::from_toml_str(&bad, "skin.toml")
        .unwrap()
        .assemble(&data(""), &tol)
        .unwrap_err()
        .to_string();
    assert!(e.contains("#207 is not an edge"), "{e}");
}
