//! Tests of the design file format: every example loads and tessellates, every error names the
//! file, the piece and the problem.

use super::*;
use flatcut_geom::Tolerances;
use flatcut_mesh::TriMesh;
use std::path::{Path, PathBuf};

fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

const TOL: Tolerances = Tolerances::DEFAULT.with_chord_mm(0.1);

fn load_example(name: &str) -> (Design, TriMesh) {
    let path = examples_dir().join(name);
    let d = Design::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let p = &d.pieces[0];
    let m = p
        .mesh(&examples_dir(), &TOL)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(m.triangle_count() > 0, "{name}");
    assert!(m.positions.iter().all(|p| flatcut_geom::finite3(*p)));
    (d, m)
}

#[test]
fn every_example_loads_builds_and_tessellates() {
    let mut seen = Vec::new();
    for e in std::fs::read_dir(examples_dir()).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "toml") {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let (d, m) = load_example(&name);
            assert_eq!(d.pieces.len(), 1, "{name}");
            // Every parametric example is a disk after tessellation and seams (closed surfaces
            // are cut at their parameter seam), so it is ready for flattening.
            flatcut_mesh::check_disk(&m).unwrap_or_else(|e| panic!("{name}: {e}"));
            seen.push(name);
        }
    }
    seen.sort();
    let expected = [
        "bezier",
        "bspline",
        "cone",
        "coons",
        "cylinder",
        "developable",
        "gordon",
        "hermite",
        "mesh",
        "nurbs",
        "patches",
        "ruled",
        "sphere",
        "torus",
        "triangular-bezier",
    ];
    assert_eq!(
        seen,
        expected
            .iter()
            .map(|s| format!("{s}.toml"))
            .collect::<Vec<_>>()
    );
}

#[test]
fn exact_surfaces_have_their_analytic_area() {
    use std::f64::consts::PI;
    let area = |n: &str| load_example(n).1.area();
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(rel(area("sphere.toml"), 4.0 * PI * 1600.0) < 5e-3);
    assert!(rel(area("cylinder.toml"), 2.0 * PI * 30.0 * 80.0) < 5e-3);
    assert!(rel(area("torus.toml"), 4.0 * PI * PI * 60.0 * 20.0) < 5e-3);
    // Frustum in inches: π (R + r) · slant, converted to mm².
    let slant = (2.0f64.powi(2) + 3.0f64.powi(2)).sqrt();
    assert!(rel(area("cone.toml"), PI * 6.0 * slant * 25.4 * 25.4) < 5e-3);
    // The NURBS quarter tube: a quarter of 2π·80 times 120.
    assert!(rel(area("nurbs.toml"), 0.5 * PI * 80.0 * 120.0) < 5e-3);
}

#[test]
fn units_are_converted_once_at_load() {
    let (d, m) = load_example("hermite.toml");
    assert_eq!(d.units, Units::Cm);
    let bb = m.bbox();
    assert!(
        (bb.max.x - 100.0).abs() < 1e-9 && (bb.max.z - 20.0).abs() < 1e-9,
        "{bb:?}"
    );
    let d = Design::from_toml_str(
        "units = \"m\"\n[[piece]]\nname = \"p\"\ngrain = [[0,0,0],[1,0,0]]\nmarks = [{name = \"n\", points = [[0.5, 0, 0]]}]\n[piece.surface]\ntype = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\n",
        "m.toml",
    )
    .unwrap();
    let p = &d.pieces[0];
    assert_eq!(
        p.surface,
        SurfaceDef::Sphere {
            center: [0.0, 0.0, 1000.0],
            radius: 500.0
        }
    );
    assert_eq!(p.grain.unwrap().line().unwrap()[1], [1000.0, 0.0, 0.0]);
    assert_eq!(p.marks[0].points[0], [500.0, 0.0, 0.0]);
    assert_eq!(p.quantity, 1);
}

#[test]
fn mesh_pieces_and_plain_mesh_files() {
    let (_, m) = load_example("mesh.toml");
    assert_eq!(m.vertex_count(), 9);
    assert_eq!(m.triangle_count(), 8);
    let d = Design::load(&examples_dir().join("quad.obj")).unwrap();
    assert_eq!(d.pieces[0].name, "quad");
    let m2 = d.pieces[0].mesh(&examples_dir(), &TOL).unwrap();
    assert_eq!(m, m2);
    // Mesh in cm: scaled to mm when read.
    let d = Design::from_toml_str(
        "units = \"cm\"\n[[piece]]\nname = \"s\"\nseams = [[4, 5]]\n[piece.surface]\ntype = \"mesh\"\nfile = \"quad.obj\"\n",
        "s.toml",
    )
    .unwrap();
    let m3 = d.pieces[0].mesh(&examples_dir(), &TOL).unwrap();
    assert!((m3.bbox().max.x - 1000.0).abs() < 1e-9);
    // The seam from the centre vertex 4 to the edge midpoint 5 is a slit: the boundary end is
    // duplicated, the interior end stays one vertex.
    assert_eq!(m3.vertex_count(), 10);
    flatcut_mesh::check_disk(&m3).unwrap();
}

#[test]
fn json_designs_load_like_toml() {
    let d = Design::from_json_str(
        r#"{"units": "mm", "piece": [{"name": "p", "quantity": 3,
            "surface": {"type": "cylinder", "base": [0, 0, 0], "radius": 10, "height": 20}}]}"#,
        "p.json",
    )
    .unwrap();
    assert_eq!(d.pieces[0].quantity, 3);
    let m = d.pieces[0].mesh(Path::new("."), &TOL).unwrap();
    assert!(m.area() > 0.0);
}

fn err_toml(text: &str) -> String {
    Design::from_toml_str(text, "bad.toml")
        .unwrap_err()
        .to_string()
}

#[test]
fn syntax_errors_carry_line_and_column() {
    let e = err_toml("[[piece]]\nname = \"a\"\nquantity = = 2\n");
    assert!(e.starts_with("bad.toml:3:"), "{e}");
    let e = err_toml("[[piece]]\nname = \"a\"\n[piece.surface]\ntype = \"blob\"\n");
    assert!(e.starts_with("bad.toml:") && e.contains("blob"), "{e}");
    let e = err_toml(
        "[[piece]]\nname = \"a\"\ncolour = \"red\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0,0,0]\nradius = 1\n",
    );
    assert!(e.contains("colour"), "{e}");
    let e = err_toml(
        "[[piece]]\nname = \"a\"\n[piece.surface]\ntype = \"sphere\"\ncentre = [0,0,0]\nradius = 1\n",
    );
    assert!(e.contains("centre"), "{e}");
    let e = Design::from_json_str("{\"piece\": [\n{\"name\": 1}]}", "bad.json")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("bad.json:2:"), "{e}");
    assert!(err_toml("units = \"mm\"\n").contains("no [[piece]]"));
    let e = err_toml(
        "units = \"furlong\"\n[[piece]]\nname = \"a\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0,0,0]\nradius = 1\n",
    );
    assert!(e.starts_with("bad.toml:1:") && e.contains("furlong"), "{e}");
}

const HEAD: &str = "[[piece]]\nname = \"first\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0,0,0]\nradius = 1\n[[piece]]\nname = \"panel\"\n[piece.surface]\n";

#[test]
fn geometry_errors_name_the_piece() {
    let panel = |body: &str| -> String {
        let d = Design::from_toml_str(&format!("{HEAD}{body}"), "bad.toml");
        match d {
            Err(e) => e.to_string(),
            Ok(d) => match d.pieces[1].build(Path::new(".")) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("built {body}"),
            },
        }
    };
    let e = panel("type = \"bezier\"\ndegree = [1, 1]\npoints = [[0,0,0],[1,0,0],[0,1,0]]\n");
    assert!(e.starts_with("bad.toml: piece 1 'panel': bezier:"), "{e}");
    assert!(e.contains("expected 4, got 3"), "{e}");
    let e = panel(
        "type = \"bspline\"\ndegree = [1, 1]\ncounts = [2, 2]\nknots_u = [0, 0, 1, 0.5]\npoints = [[0,0,0],[0,1,0],[1,0,0],[1,1,0]]\n",
    );
    assert!(
        e.contains("piece 1 'panel'") && e.contains("decreas"),
        "{e}"
    );
    let e = panel(
        "type = \"nurbs\"\ndegree = [1, 1]\ncounts = [2, 2]\npoints = [[0,0,0],[0,1,0],[1,0,0],[1,1,0]]\nweights = [1, 0, 1, 1]\n",
    );
    assert!(
        e.contains("piece 1 'panel'") && e.contains("weight 1"),
        "{e}"
    );
    let e = panel(
        "type = \"nurbs\"\ndegree = [1, 1]\ncounts = [2, 2]\npoints = [[0,0,0],[0,1,0],[1,0,0],[1,1,0]]\nweights = [1, -2, 1, 1]\n",
    );
    assert!(e.contains("weight 1"), "{e}");
    let e =
        panel("type = \"bezier\"\ndegree = [1, 1]\npoints = [[0,0,0],[1,0,nan],[0,1,0],[1,1,0]]\n");
    assert!(
        e.contains("piece 1 'panel'") && e.contains("point 1: coordinate NaN is not a finite"),
        "{e}"
    );
    let e = panel("type = \"sphere\"\ncenter = [0,0,0]\nradius = -3\n");
    assert!(e.contains("sphere radius must be finite, > 0"), "{e}");
    let e = panel("type = \"cylinder\"\nbase = [0,0,0]\nradius = inf\nheight = 3\n");
    assert!(e.contains("cylinder radius"), "{e}");
    let e = panel(
        "type = \"coons\"\nv0 = { type = \"bezier\", points = [[0,0,0],[1,0,0]] }\nv1 = { type = \"bezier\", points = [[0,1,0],[1,1,0]] }\nu0 = { type = \"bezier\", points = [[0,0,0],[0,1,0]] }\nu1 = { type = \"bezier\", points = [[5,0,0],[5,1,0]] }\n",
    );
    assert!(e.contains("piece 1 'panel': coons"), "{e}");
    let e = panel("type = \"mesh\"\nfile = \"missing.obj\"\n");
    assert!(
        e.contains("piece 1 'panel'") && e.contains("missing.obj"),
        "{e}"
    );
    let e = panel("type = \"patches\"\npatches = []\n");
    assert!(e.contains("patches: the list is empty"), "{e}");
    let e = err_toml(&format!(
        "{HEAD}type = \"sphere\"\ncenter = [0,0,0]\nradius = 1\n[[piece.marks]]\nname = \"n\"\npoints = []\n"
    ));
    assert!(e.contains("piece 1 'panel': mark 'n' has no points"), "{e}");
    let e = err_toml(
        &format!("{HEAD}type = \"sphere\"\ncenter = [0,0,0]\nradius = 1\n")
            .replace("name = \"panel\"\n", "name = \"panel\"\nquantity = 0\n"),
    );
    assert!(e.contains("piece 1 'panel': quantity"), "{e}");
}

#[test]
fn seams_in_uv_cut_a_closed_cylinder_open_along_a_generator() {
    // A torus is cut at both parameter seams already; a (u, v) seam across it adds a slit.
    let text = "[[piece]]\nname = \"t\"\nseams = [[[0.0, 0.5], [0.5, 0.5]]]\n[piece.surface]\ntype = \"torus\"\ncenter = [0,0,0]\nmajor = 60\nminor = 20\n";
    let d = Design::from_toml_str(text, "t.toml").unwrap();
    assert!(matches!(d.pieces[0].seams[0], SeamDef::Params(_)));
    let plain = d.pieces[0]
        .build(Path::new("."))
        .unwrap()
        .tessellate(&TOL)
        .unwrap();
    let cut = d.pieces[0].mesh(Path::new("."), &TOL).unwrap();
    assert!(cut.vertex_count() > plain.vertex_count());
    flatcut_mesh::check_disk(&cut).unwrap();
    assert!((cut.area() - plain.area()).abs() < 1e-9 * plain.area());
}

#[test]
fn darts_and_no_cut_regions_are_read_and_scaled() {
    let text = "units = \"cm\"\n[[piece]]\nname = \"cap\"\ndarts = \"auto\"\nno_cut = [[[0, 0, 1], [1, 0, 1], [0, 1, 1]]]\n[piece.surface]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
    let d = Design::from_toml_str(text, "t.toml").unwrap();
    let p = &d.pieces[0];
    assert_eq!(p.darts, Some(crate::DartsDef::Auto));
    assert_eq!(p.no_cut[0][1], [10.0, 0.0, 10.0]);
    let bad = text.replace("darts = \"auto\"", "darts = \"sometimes\"");
    let e = Design::from_toml_str(&bad, "t.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("sometimes"), "{e}");
    let short = text.replace(
        "[[[0, 0, 1], [1, 0, 1], [0, 1, 1]]]",
        "[[[0, 0, 1], [1, 0, 1]]]",
    );
    let e = Design::from_toml_str(&short, "t.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no_cut region 0") && e.contains("at least 3"),
        "{e}"
    );
}

#[test]
fn huge_bspline_counts_are_refused_before_any_allocation() {
    // 2^32 × 2^32 poles with 16 points: the default knots were built from the counts first.
    let e = err_toml(
        "[[piece]]\nname = \"big\"\n[piece.surface]\ntype = \"bspline\"\ndegree = [3, 3]\n\
         counts = [4294967296, 4294967296]\npoints = [[0,0,0],[0,1,0],[0,2,0],[0,3,0],[1,0,0],[1,1,0],\
         [1,2,0],[1,3,0],[2,0,0],[2,1,0],[2,2,0],[2,3,0],[3,0,0],[3,1,0],[3,2,0],[3,3,1]]\n",
    );
    assert!(
        e.contains("piece 0 'big'") && e.contains("control points"),
        "{e}"
    );
    let e = err_toml(
        "[[piece]]\nname = \"odd\"\n[piece.surface]\ntype = \"bspline\"\ndegree = [1, 1]\n\
         counts = [3, 3]\npoints = [[0,0,0],[0,1,0],[1,0,0],[1,1,0]]\n",
    );
    assert!(e.contains("need 9 points, the file gives 4"), "{e}");
    let e = err_toml(
        "[[piece]]\nname = \"deg\"\n[piece.surface]\ntype = \"bezier\"\ndegree = [4294967295, 1]\n\
         points = [[0,0,0],[0,1,0],[1,0,0],[1,1,0]]\n",
    );
    assert!(e.contains("degree 4294967295 is above"), "{e}");
    let e = err_toml(
        "[[piece]]\nname = \"q\"\nquantity = 4000000000\n[piece.surface]\ntype = \"sphere\"\ncenter = [0,0,0]\nradius = 1\n",
    );
    assert!(e.contains("quantity must be between 1 and"), "{e}");
}

#[test]
fn coordinates_beyond_the_sane_range_are_refused_in_mm() {
    let e = err_toml(
        "[[piece]]\nname = \"far\"\n[piece.surface]\ntype = \"bezier\"\ndegree = [1, 1]\n\
         points = [[0,0,0],[0,1,0],[1,0,0],[1e9,1,0]]\n",
    );
    assert!(
        e.contains("piece 0 'far'") && e.contains("point 3") && e.contains("beyond"),
        "{e}"
    );
    let e = err_toml(
        "[[piece]]\nname = \"huge\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0,0,0]\nradius = 1e308\n",
    );
    assert!(e.contains("sphere radius must be finite"), "{e}");
    // 900 m is fine in mm, not in metres
    let ok = "[[piece]]\nname = \"m\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0,0,900000]\nradius = 1\n";
    assert!(Design::from_toml_str(ok, "ok.toml").is_ok());
    let e = err_toml(&format!("units = \"m\"\n{ok}"));
    assert!(e.contains("beyond"), "{e}");
}

#[test]
fn grain_is_a_line_or_auto_and_material_properties_name_a_material() {
    let text = |grain: &str| {
        format!(
            "[[piece]]\nname = \"p\"\ngrain = {grain}\nmaterial = \"cotton, white\"\nmaterial_properties = \"woven-cotton\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\n"
        )
    };
    let d = Design::from_toml_str(&text("\"auto\""), "m.toml").unwrap();
    let p = &d.pieces[0];
    assert_eq!(p.grain, Some(crate::GrainDef::Auto));
    assert_eq!(p.material_properties.as_deref(), Some("woven-cotton"));
    let e = Design::from_toml_str(&text("\"sideways\""), "m.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("m.toml") && e.contains("\"auto\""), "{e}");
}
