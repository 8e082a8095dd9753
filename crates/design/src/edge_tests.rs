//! Tests of allowances by edge and of grading: edges found on a part's outline and shared by the
//! pieces along them, style lines' allowances and laps on both sides, sizes scaled about the
//! origin, and the bad input each refuses by name.

use super::*;
use flatcut_geom::{DVec3, Tolerances};
use std::path::Path;

const TOL: Tolerances = Tolerances::DEFAULT.with_chord_mm(0.5);

/// A flat 200 × 100 mm sheet cut by a line at x = 100 into a left and a right piece, with `extra`
/// (TOML) added to its part and `line` to its line.
fn sheet(line: &str, extra: &str) -> String {
    format!(
        r#"
[[part]]
name = "sheet"
[part.surface]
type = "bezier"
degree = [1, 1]
points = [[0, 0, 0], [0, 100, 0], [200, 0, 0], [200, 100, 0]]
[[part.line]]
name = "middle"
points = [[100, 0, 0], [100, 100, 0]]
{line}
{extra}
[[part.piece]]
name = "left"
at = [50, 50, 0]
seam_allowance_mm = 8
[[part.piece]]
name = "right"
at = [150, 50, 0]
"#
    )
}

fn assemble(text: &str) -> Result<Assembly, DesignError> {
    Design::from_toml_str(text, "t.toml")?.assemble(Path::new("."), &TOL)
}

fn edges<'a>(a: &'a Assembly, piece: &str) -> Vec<&'a OutlineEdge> {
    let p = a.pieces.iter().find(|p| p.def.name == piece).unwrap();
    p.def.outline_edges.iter().collect()
}

#[test]
fn a_part_edge_is_found_on_the_outline_and_shared_by_the_pieces_along_it() {
    let text = sheet(
        "",
        "[[part.edge]]\nname = \"hem\"\nfrom = [0, 0, 0]\nto = [200, 0, 0]\nallowance_mm = 30\nkind = \"hem\"\n",
    );
    let a = assemble(&text).unwrap();
    for piece in ["left", "right"] {
        let e = edges(&a, piece);
        // the hem, and the line's seam side (the pieces' own allowance)
        let hem = e.iter().find(|e| e.name == "hem").unwrap();
        assert_eq!(
            (hem.kind, hem.allowance_mm, hem.closed),
            (EdgeKind::Hem, Some(30.0), false)
        );
        // the whole bottom side, from x = 0 to x = 200 at y = 0
        assert!(hem.points.iter().all(|p| p.y.abs() < 1e-9));
        assert_eq!(hem.points.first().unwrap().x, 0.0);
        assert_eq!(hem.points.last().unwrap().x, 200.0);
        let line = e.iter().find(|e| e.name == "middle").unwrap();
        assert_eq!((line.kind, line.allowance_mm), (EdgeKind::Seam, None));
        assert!(line.points.iter().all(|p| (p.x - 100.0).abs() < 1e-9));
    }
    // from = to: the whole loop through that point
    let text = sheet(
        "",
        "[[part.edge]]\nname = \"rim\"\nfrom = [0, 0, 0]\nto = [0, 0, 0]\nallowance_mm = 5\nkind = \"fold\"\n",
    );
    let a = assemble(&text).unwrap();
    let rim = edges(&a, "left")
        .into_iter()
        .find(|e| e.name == "rim")
        .unwrap();
    assert!(rim.closed);
    let len: f64 = (0..rim.points.len())
        .map(|i| rim.points[i].distance(rim.points[(i + 1) % rim.points.len()]))
        .sum();
    assert!((len - 600.0).abs() < 1e-9, "{len}");
}

#[test]
fn a_lapped_line_cuts_the_top_piece_raw_and_gives_the_other_the_underlay() {
    let a = assemble(&sheet("lap = \"right\"\nunderlay_mm = 9", "")).unwrap();
    let side = |piece: &str| {
        let e = edges(&a, piece);
        let m = e.iter().find(|e| e.name == "middle").unwrap();
        (m.kind, m.allowance_mm)
    };
    assert_eq!(side("right"), (EdgeKind::Raw, Some(0.0)));
    assert_eq!(side("left"), (EdgeKind::Seam, Some(9.0)));
    let a = assemble(&sheet("lap = \"left\"", "")).unwrap();
    let e = edges(&a, "right");
    let m = e.iter().find(|e| e.name == "middle").unwrap();
    assert_eq!(m.allowance_mm, Some(LineDef::UNDERLAY_MM));
    let a = assemble(&sheet("allowance_mm = 4", "")).unwrap();
    for piece in ["left", "right"] {
        let e = edges(&a, piece);
        assert_eq!(
            e.iter().find(|e| e.name == "middle").unwrap().allowance_mm,
            Some(4.0)
        );
    }
}

fn err(text: &str) -> String {
    assemble(text).unwrap_err().to_string()
}

#[test]
fn bad_edges_and_laps_are_refused_naming_file_part_and_edge() {
    let edge = |from: &str, to: &str, more: &str| {
        format!(
            "[[part.edge]]\nname = \"hem\"\nfrom = {from}\nto = {to}\nallowance_mm = 30\nkind = \"hem\"\n{more}"
        )
    };
    let e = err(&sheet("", &edge("[0, 50, 40]", "[200, 0, 0]", "")));
    assert!(
        e.starts_with("t.toml: part 0 'sheet': edge 'hem': `from`"),
        "{e}"
    );
    assert!(e.contains("from the boundary"), "{e}");
    let overlap = format!(
        "{}[[part.edge]]\nname = \"side\"\nfrom = [150, 0, 0]\nto = [200, 100, 0]\nallowance_mm = 12\n",
        edge("[0, 0, 0]", "[200, 0, 0]", "")
    );
    let e = err(&sheet("", &overlap));
    assert!(e.contains("edge 'side': it overlaps edge 'hem'"), "{e}");
    let e = err(&sheet("lap = \"elsewhere\"", ""));
    assert!(
        e.contains("line 0 'middle': lap = \"elsewhere\" names no piece"),
        "{e}"
    );
    let e = err(&sheet("lap = \"left\"\nallowance_mm = 3", ""));
    assert!(e.contains("give `allowance_mm` or `lap`"), "{e}");
    let e = err(&sheet("underlay_mm = 3", ""));
    assert!(e.contains("`underlay_mm` needs `lap`"), "{e}");
    let e = err(&sheet(
        "",
        "[[part.edge]]\nname = \"x\"\nfrom = [0, 0, 0]\nto = [9, 0, 0]\nkind = \"lasting\"\n",
    ));
    assert!(
        e.contains("edge 'x': a lasting edge needs its allowance_mm"),
        "{e}"
    );
    let e = err(&sheet(
        "",
        "[[part.edge]]\nname = \"x\"\nfrom = [0, 0, 0]\nto = [9, 0, 0]\nkind = \"raw\"\nallowance_mm = 2\n",
    ));
    assert!(e.contains("a raw edge is cut on the line"), "{e}");
}

#[test]
fn a_lap_naming_a_piece_not_beside_the_line_is_refused() {
    // a third piece, "strip", beyond a second line: the middle line has left and right beside it
    let text = sheet("lap = \"strip\"", "")
        .replace(
            "[[part.piece]]\nname = \"left\"",
            "[[part.line]]\nname = \"edge-line\"\npoints = [[180, 0, 0], [180, 100, 0]]\n[[part.piece]]\nname = \"strip\"\nat = [190, 50, 0]\n[[part.piece]]\nname = \"left\"",
        );
    let e = err(&text);
    assert!(
        e.contains("line 'middle': lap = \"strip\" is not beside the line")
            && e.contains("'left'")
            && e.contains("'right'"),
        "{e}"
    );
}

fn graded(sizes: &str) -> String {
    format!(
        "{}\n[grading]\nbase = \"M\"\norigin = [100, 0, 0]\n{sizes}",
        sheet("", "")
    )
}

#[test]
fn sizes_are_the_design_scaled_about_the_origin_per_axis() {
    let text = graded(
        "[[grading.size]]\nname = \"S\"\nscale = [0.9, 0.8, 1]\n[[grading.size]]\nname = \"M\"\n",
    );
    let d = Design::from_toml_str(&text, "t.toml").unwrap();
    let sizes = d.sizes(Path::new(".")).unwrap();
    let names: Vec<_> = sizes.iter().map(|s| s.size.clone().unwrap()).collect();
    assert_eq!(names, ["S", "M"]);
    let s = &sizes[0].design;
    // x scaled by 0.9 about x = 100, y by 0.8 about 0
    assert_eq!(s.parts[0].lines[0].points[1], [100.0, 80.0, 0.0]);
    assert_eq!(s.parts[0].pieces[0].at, [55.0, 40.0, 0.0]);
    assert!(s.grading.is_none() && sizes[1].design.grading.is_none());
    assert_eq!(sizes[1].design.parts, d.parts);
    let a = s.assemble(Path::new("."), &TOL).unwrap();
    let bb = a.pieces[0].mesh.bbox();
    assert!(
        (bb.min.x - 10.0).abs() < 1e-9 && (bb.max.y - 80.0).abs() < 1e-9,
        "{bb:?}"
    );
    // a design without grading is its one unnamed size
    let plain = Design::from_toml_str(&sheet("", ""), "t.toml").unwrap();
    let one = plain.sizes(Path::new(".")).unwrap();
    assert_eq!((one.len(), one[0].size.clone()), (1, None));
}

#[test]
fn bad_gradings_are_refused_naming_the_size() {
    let e = |sizes: &str| {
        Design::from_toml_str(&graded(sizes), "t.toml")
            .and_then(|d| d.sizes(Path::new(".")))
            .unwrap_err()
            .to_string()
    };
    let m = "[[grading.size]]\nname = \"M\"\n";
    let x = e(&format!(
        "{m}[[grading.size]]\nname = \"S\"\nscale = [1, -0.5, 1]\n"
    ));
    assert!(x.starts_with("t.toml: [grading] size 'S': scale"), "{x}");
    assert!(x.contains("finite and > 0, got -0.5"), "{x}");
    let x = e(&format!(
        "{m}[[grading.size]]\nname = \"S\"\nscale = [0, 1, 1]\n"
    ));
    assert!(x.contains("size 'S'") && x.contains("got 0"), "{x}");
    let x = e("[[grading.size]]\nname = \"S\"\nscale = [1, 1, 1]\n");
    assert!(x.contains("base = \"M\" is none of the sizes (S)"), "{x}");
    let x = e(&format!("{m}[[grading.size]]\nname = \"S\"\n"));
    assert!(x.contains("size 'S': give `scale"), "{x}");
    let x = e(&format!(
        "{m}[[grading.size]]\nname = \"M\"\nscale = [1, 1, 1]\n"
    ));
    assert!(x.contains("two sizes have this name"), "{x}");
    // a size's own design must have the base's lines
    let dir = tempfile::tempdir().unwrap();
    let own = sheet("", "").replace(
        "[[part.line]]\nname = \"middle\"",
        "[[part.line]]\nname = \"centre\"",
    );
    std::fs::write(dir.path().join("s.toml"), own).unwrap();
    let d = Design::from_toml_str(
        &graded(&format!(
            "{m}[[grading.size]]\nname = \"S\"\ndesign = \"s.toml\"\n"
        )),
        "t.toml",
    )
    .unwrap();
    let x = d.sizes(dir.path()).unwrap_err().to_string();
    assert!(
        x.starts_with("t.toml: [grading] size 'S': ")
            && x.contains(
                "s.toml: part 'sheet': it has no line 'middle', which the base design has"
            ),
        "{x}"
    );
    // a sphere cannot be scaled differently per axis
    let ball = "[[piece]]\nname = \"ball\"\n[piece.surface]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 10\n[grading]\nbase = \"M\"\norigin = [0, 0, 0]\n[[grading.size]]\nname = \"M\"\n[[grading.size]]\nname = \"L\"\nscale = [1.1, 1, 1]\n";
    let x = Design::from_toml_str(ball, "b.toml")
        .unwrap()
        .sizes(Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(
        x.contains("size 'L': piece 'ball': a sphere stays a sphere only"),
        "{x}"
    );
    let _ = DVec3::ZERO;
}

#[test]
fn a_size_of_its_own_design_is_read_in_its_own_units_with_the_base_names() {
    // size L: the sheet 1.2 times as long and 1.1 times as wide, written in cm, its line and
    // pieces where the grade puts them
    let dir = tempfile::tempdir().unwrap();
    let own = r#"
units = "cm"
[[part]]
name = "sheet"
[part.surface]
type = "bezier"
degree = [1, 1]
points = [[0, 0, 0], [0, 11, 0], [24, 0, 0], [24, 11, 0]]
[[part.line]]
name = "middle"
points = [[12, 0, 0], [12, 11, 0]]
[[part.piece]]
name = "left"
at = [6, 5.5, 0]
seam_allowance_mm = 8
[[part.piece]]
name = "right"
at = [18, 5.5, 0]
"#;
    std::fs::write(dir.path().join("l.toml"), own).unwrap();
    let text = graded(
        "[[grading.size]]\nname = \"M\"\n[[grading.size]]\nname = \"L\"\ndesign = \"l.toml\"\n",
    );
    let d = Design::from_toml_str(&text, "t.toml").unwrap();
    let sizes = d.sizes(dir.path()).unwrap();
    let names: Vec<_> = sizes.iter().map(|s| s.size.clone().unwrap()).collect();
    assert_eq!(names, ["M", "L"]);
    let l = &sizes[1];
    assert_eq!(l.dir, dir.path());
    assert!(l.design.grading.is_none());
    // in mm, as every design is once loaded
    assert_eq!(l.design.parts[0].lines[0].points[1], [120.0, 110.0, 0.0]);
    let a = l.design.assemble(&l.dir, &TOL).unwrap();
    let got: Vec<_> = a.pieces.iter().map(|p| p.def.name.as_str()).collect();
    assert_eq!(got, ["left", "right"]);
    let bb = a.pieces[0].mesh.bbox();
    assert!(
        bb.min.x.abs() < 1e-9 && (bb.max.x - 120.0).abs() < 1e-9 && (bb.max.y - 110.0).abs() < 1e-9,
        "{bb:?}"
    );
    assert_eq!(a.seams.len(), 1);
    // the base size is the design itself
    assert_eq!(sizes[0].design.parts, d.parts);
}
