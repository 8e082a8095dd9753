//! Tests of parts, style lines, joins and pairs: pieces from regions, seams named after their
//! lines, and errors that say where.

use super::*;
use flatcut_geom::{DVec3, Tolerances};
use std::path::Path;

const TOL: Tolerances = Tolerances::DEFAULT.with_chord_mm(0.2);

/// A gently curved 200 × 100 mm sheet (a bicubic Bézier, z up to 20 mm) as a part with the
/// given lines and pieces (TOML fragments).
fn sheet(lines: &str, pieces: &str) -> String {
    format!(
        r#"
[[part]]
name = "sheet"
[part.surface]
type = "bezier"
degree = [1, 2]
points = [[0, 0, 0], [0, 50, 20], [0, 100, 0], [200, 0, 0], [200, 50, 20], [200, 100, 0]]
{lines}
{pieces}
"#
    )
}

/// The height of the sheet above (x, y): 20·4t(1 − t)·(1/2)… the Bézier in y, linear in x.
fn z(y: f64) -> f64 {
    let t = y / 100.0;
    2.0 * t * (1.0 - t) * 20.0
}

fn on(x: f64, y: f64) -> String {
    format!("[{x}, {y}, {}]", z(y))
}

fn assemble(text: &str) -> Result<Assembly, DesignError> {
    Design::from_toml_str(text, "t.toml")?.assemble(Path::new("."), &TOL)
}

#[test]
fn a_line_across_a_part_makes_two_pieces_and_a_seam_named_after_it() {
    let text = sheet(
        &format!(
            "[[part.line]]\nname = \"yoke\"\npoints = [{}, {}, {}]\nnotches = [{}]\n",
            on(80.0, 0.0),
            on(95.0, 50.0),
            on(110.0, 100.0),
            on(88.0, 27.0)
        ),
        &format!(
            "[[part.piece]]\nname = \"front\"\nat = {}\npairs = 1\n[[part.piece]]\nname = \"back\"\nat = {}\nquantity = 3\n",
            on(40.0, 50.0),
            on(160.0, 50.0)
        ),
    );
    let a = assemble(&text).unwrap();
    let names: Vec<&str> = a.pieces.iter().map(|p| p.def.name.as_str()).collect();
    assert_eq!(names, ["front", "back"]);
    let (front, back) = (&a.pieces[0], &a.pieces[1]);
    assert_eq!((front.def.quantity, front.def.mirrored), (1, 1));
    assert_eq!((back.def.quantity, back.def.mirrored), (3, 0));
    assert_eq!(front.part.as_deref(), Some("sheet"));
    // The front is the part of the sheet with x < ~95.
    assert!(front.mesh.positions.iter().all(|p| p.x < 111.0));
    assert!(back.mesh.positions.iter().all(|p| p.x > 79.0));
    assert_eq!(a.seams.len(), 1);
    let s = &a.seams[0];
    assert_eq!(s.name, "yoke");
    let mut sides: Vec<usize> = s.sides.iter().map(|x| x.piece).collect();
    sides.sort_unstable();
    assert_eq!(sides, [0, 1]);
    let pts = |k: usize| -> Vec<DVec3> {
        let side = &s.sides[k];
        side.vertices
            .iter()
            .map(|&v| a.pieces[side.piece].mesh.positions[v as usize])
            .collect()
    };
    assert_eq!(pts(0), pts(1), "identical coordinates on both sides");
    assert_eq!(s.notches.len(), 1);
    assert_eq!(s.notches[0].name, "yoke 1");
    let n = pts(0)[s.notches[0].index];
    assert!(n.distance(DVec3::new(88.0, 27.0, z(27.0))) < 0.05, "{n}");
    // The two pieces cover the sheet.
    let whole = Design::from_toml_str(&text, "t.toml").unwrap().parts[0]
        .surface_piece()
        .mesh(Path::new("."), &TOL)
        .unwrap();
    // (up to the tidying of the mesh around the line, which changes the area by 1.2e-5 here:
    // far less than the tessellation's own area error, ~1e-3 at this chordal tolerance).
    let sum: f64 = a.pieces.iter().map(|p| p.mesh.area()).sum();
    assert!(
        (sum - whole.area()).abs() < 1e-4 * whole.area(),
        "{sum} vs {}",
        whole.area()
    );
}

#[test]
fn a_region_no_piece_names_is_an_error_that_says_where() {
    let text = sheet(
        &format!(
            "[[part.line]]\nname = \"yoke\"\npoints = [{}, {}]\n",
            on(100.0, 0.0),
            on(100.0, 100.0)
        ),
        &format!(
            "[[part.piece]]\nname = \"front\"\nat = {}\n",
            on(40.0, 50.0)
        ),
    );
    let e = assemble(&text).unwrap_err().to_string();
    assert!(
        e.contains("part 0 'sheet'") && e.contains("is named by no [[part.piece]]"),
        "{e}"
    );
    assert!(e.contains("near (1") && e.contains("line(s) yoke"), "{e}");
}

#[test]
fn two_pieces_in_one_region_or_a_loose_line_are_errors() {
    let both = format!(
        "[[part.piece]]\nname = \"a\"\nat = {}\n[[part.piece]]\nname = \"b\"\nat = {}\n",
        on(40.0, 50.0),
        on(60.0, 50.0)
    );
    let e = assemble(&sheet("", &both)).unwrap_err().to_string();
    assert!(
        e.contains("pieces 0 'a' and 1 'b' name the same region"),
        "{e}"
    );
    let loose = format!(
        "[[part.line]]\nname = \"dart\"\npoints = [{}, {}]\n",
        on(100.0, 0.0),
        on(100.0, 60.0)
    );
    let e = assemble(&sheet(&loose, &both)).unwrap_err().to_string();
    assert!(
        e.contains("line 0 'dart'") && e.contains("does not close a region"),
        "{e}"
    );
    let off = "[[part.piece]]\nname = \"a\"\nat = [40, 50, 90]\n".to_string();
    let e = assemble(&sheet("", &off)).unwrap_err().to_string();
    assert!(e.contains("`at` (40.00, 50.00, 90.00) is"), "{e}");
}

#[test]
fn pairs_and_quantity_are_exclusive_and_labels_need_pairs() {
    let p = |extra: &str| {
        format!(
            "[[piece]]\nname = \"p\"\n{extra}\n[piece.surface]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 5\n"
        )
    };
    let e = Design::from_toml_str(&p("quantity = 2\npairs = 1"), "p.toml").unwrap_err();
    assert!(
        e.to_string().contains("give quantity or pairs, not both"),
        "{e}"
    );
    let e = Design::from_toml_str(&p("pair_labels = [\"A\", \"B\"]"), "p.toml").unwrap_err();
    assert!(e.to_string().contains("pair_labels needs pairs"), "{e}");
    let d = Design::from_toml_str(
        &p("pairs = 2\npair_labels = [\"PORT\", \"STBD\"]"),
        "p.toml",
    )
    .unwrap();
    let q = &d.pieces[0];
    assert_eq!((q.quantity, q.mirrored), (2, 2));
    assert_eq!(q.pair_labels(), ["PORT".to_string(), "STBD".to_string()]);
}

#[test]
fn a_join_between_two_pieces_gives_both_edges_matching_vertices_and_notches() {
    // Two flat strips meeting along y = 50: 100 mm in 4 and in 7 segments (different meshes).
    let strip = |name: &str, y0: f64, y1: f64| {
        format!(
            "[[piece]]\nname = \"{name}\"\n[piece.surface]\ntype = \"bezier\"\ndegree = [1, 1]\npoints = [[0, {y0}, 0], [0, {y1}, 0], [100, {y0}, 0], [100, {y1}, 0]]\n"
        )
    };
    let text = format!(
        "{}{}[[join]]\nname = \"side\"\na = {{ piece = \"lower\", from = [0, 50, 0], to = [100, 50, 0] }}\nb = {{ piece = \"upper\", from = [0, 50, 0], to = [100, 50, 0] }}\nnotches = [[37.5, 50, 0]]\n",
        strip("lower", 0.0, 50.0),
        strip("upper", 50.0, 80.0)
    );
    let a = assemble(&text).unwrap();
    let s = &a.seams[0];
    assert_eq!(
        (s.name.as_str(), s.sides[0].piece, s.sides[1].piece),
        ("side", 0, 1)
    );
    let xs = |k: usize| -> Vec<f64> {
        let side = &s.sides[k];
        side.vertices
            .iter()
            .map(|&v| a.pieces[side.piece].mesh.positions[v as usize].x)
            .collect()
    };
    let (xa, xb) = (xs(0), xs(1));
    assert_eq!(xa.len(), xb.len());
    for (p, q) in xa.iter().zip(&xb) {
        assert!((p - q).abs() < 1e-9, "{xa:?} vs {xb:?}");
    }
    assert_eq!((xa[0], xa[xa.len() - 1]), (0.0, 100.0));
    assert_eq!(s.notches.len(), 1);
    assert!((xa[s.notches[0].index] - 37.5).abs() < 1e-9);
    for p in &a.pieces {
        flatcut_mesh::check_disk(&p.mesh).unwrap();
    }
    let bad = text.replace("piece = \"upper\"", "piece = \"uper\"");
    let e = assemble(&bad).unwrap_err().to_string();
    assert!(
        e.contains("join 0 'side': there is no piece named 'uper'"),
        "{e}"
    );
}

#[test]
fn notch_marks_become_boundary_vertices_exactly_where_they_are() {
    let text = "[[piece]]\nname = \"p\"\nmarks = [{name = \"n\", kind = \"notch\", points = [[33.3, 0, 0]]}]\n[piece.surface]\ntype = \"bezier\"\ndegree = [1, 1]\npoints = [[0, 0, 0], [0, 50, 0], [100, 0, 0], [100, 50, 0]]\n";
    let a = assemble(text).unwrap();
    let p = &a.pieces[0];
    assert_eq!(p.notch_marks.len(), 1);
    let (name, v) = &p.notch_marks[0];
    assert_eq!(name, "n");
    assert!(p.mesh.positions[*v as usize].distance(DVec3::new(33.3, 0.0, 0.0)) < 1e-9);
    flatcut_mesh::check_disk(&p.mesh).unwrap();
}

#[test]
fn a_line_named_by_a_step_edge_needs_a_step_surface_and_no_points() {
    let piece = format!("[[part.piece]]\nname = \"all\"\nat = {}\n", on(40.0, 50.0));
    let text = sheet("[[part.line]]\nname = \"keel\"\nedge = 12\n", &piece);
    let e = Design::from_toml_str(&text, "t.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`edge` names an edge of a STEP model"), "{e}");
    let both = format!(
        "[[part.line]]\nname = \"keel\"\nedge = 12\npoints = [{}, {}]\n",
        on(80.0, 0.0),
        on(80.0, 100.0)
    );
    let e = Design::from_toml_str(&sheet(&both, &piece), "t.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("either `points` or `edge`"), "{e}");
}
