//! The bundled example designs in `patterns/`: every one loads, builds and tessellates, and each
//! shows the property it was made for (analytic area, developability, a disk after its seams).

use std::path::{Path, PathBuf};

use flatcut_design::{Design, PieceDef, PieceGeometry, SurfaceDef};
use flatcut_geom::{DVec3, Tolerances, num};
use flatcut_mesh::{TriMesh, check_disk};
use flatcut_surface::diffgeom::developability;

/// Chordal tolerance of the tessellations (mm): coarse enough to keep the suite fast, fine
/// enough that the inscribed mesh area is within 0.1 % of the surface area on these radii.
const CHORD_MM: f64 = 0.1;
/// Relative tolerance on areas against analytic values: the inscribed mesh loses about
/// (2/3)·chord/radius of the area (0.13 % on the sleeve, Ø 110 mm).
const AREA_REL: f64 = 5e-3;
/// Scaled Gaussian curvature below which a patch counts as developable (rounding level).
const DEVELOPABLE_MAX: f64 = 1e-6;
/// Scaled Gaussian curvature above which a patch is clearly doubly curved.
const DOUBLY_CURVED_MIN: f64 = 1e-2;
/// Samples per direction of the developability check.
const DEV_SAMPLES: usize = 24;

fn dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../patterns")
        .join(name)
}

fn load(name: &str, file: &str) -> Design {
    let path = dir(name).join(file);
    Design::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn tol() -> Tolerances {
    Tolerances::DEFAULT.with_chord_mm(CHORD_MM)
}

/// The piece cut along its seams, checked finite.
fn mesh(name: &str, p: &PieceDef) -> TriMesh {
    let m = p
        .mesh(&dir(name), &tol())
        .unwrap_or_else(|e| panic!("{name}/{}: {e}", p.name));
    assert!(!m.triangles.is_empty(), "{name}/{}: empty mesh", p.name);
    assert!(
        m.positions.iter().all(|q| q.is_finite()),
        "{name}/{}: non-finite vertex",
        p.name
    );
    m
}

fn patches(name: &str, p: &PieceDef) -> Vec<std::sync::Arc<dyn flatcut_surface::ParamSurface>> {
    match p.build(&dir(name)).unwrap() {
        PieceGeometry::Patches(v) => v,
        _ => panic!("{name}/{}: expected patches", p.name),
    }
}

/// Largest scaled |K| over the piece's patches.
fn max_scaled_k(name: &str, p: &PieceDef) -> f64 {
    patches(name, p)
        .iter()
        .map(|s| {
            let r = developability(s.as_ref(), DEV_SAMPLES);
            assert!(r.max_scaled_k.is_finite());
            r.max_scaled_k
        })
        .fold(0.0, f64::max)
}

fn assert_area(what: &str, got: f64, want: f64) {
    let rel = (got - want).abs() / want;
    assert!(
        rel < AREA_REL,
        "{what}: area {got:.1} mm² vs analytic {want:.1} mm² (rel {rel:.2e})"
    );
}

/// Asserts the piece is a single disk after its seams and returns its boundary length.
fn assert_disk(what: &str, m: &TriMesh) -> f64 {
    let topo = check_disk(m).unwrap_or_else(|e| panic!("{what}: not a disk: {e}"));
    assert_eq!(topo.boundary_loops.len(), 1, "{what}");
    let b = &topo.boundary_loops[0];
    (0..b.len())
        .map(|k| m.positions[b[k] as usize].distance(m.positions[b[(k + 1) % b.len()] as usize]))
        .sum()
}

fn nearest_vertex_distance(m: &TriMesh, p: DVec3) -> f64 {
    m.positions
        .iter()
        .map(|q| q.distance(p))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn every_pattern_folder_has_a_design_and_notes() {
    let root = dir("");
    let mut names: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        // patterns/golden holds the blessed outputs of the end-to-end tests, not a design.
        .filter(|n| n != "golden")
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "helmet",
            "hull",
            "kayak",
            "lampshade",
            "sail",
            "shoe",
            "sleeve",
            "teapot"
        ]
    );
    for n in &names {
        assert!(dir(n).join("design.toml").is_file(), "{n}/design.toml");
        assert!(dir(n).join("NOTES.md").is_file(), "{n}/NOTES.md");
        let d = load(n, "design.toml");
        assert!(!d.pieces.is_empty() || !d.parts.is_empty(), "{n}");
    }
    assert!(root.join("README.md").is_file());
}

#[test]
fn lampshade_is_an_exact_frustum_and_a_disk() {
    let d = load("lampshade", "design.toml");
    assert_eq!(d.pieces.len(), 1);
    let p = &d.pieces[0];
    assert_eq!(p.quantity, 1);
    let m = mesh("lampshade", p);
    let (r0, r1, h) = (150.0f64, 80.0f64, 200.0f64);
    let slant = ((r0 - r1).powi(2) + h * h).sqrt();
    assert_area(
        "lampshade",
        m.area(),
        std::f64::consts::PI * (r0 + r1) * slant,
    );
    assert!(max_scaled_k("lampshade", p) < DEVELOPABLE_MAX);
    // Open along its parameter seam: one boundary of length 2π(R + r) + 2·slant.
    let len = assert_disk("lampshade", &m);
    let want = 2.0 * std::f64::consts::PI * (r0 + r1) + 2.0 * slant;
    assert!(
        (len - want).abs() / want < AREA_REL,
        "boundary {len} vs {want}"
    );
}

#[test]
fn sleeve_is_a_cylinder_cut_open_by_its_underarm_seam() {
    let d = load("sleeve", "design.toml");
    assert_eq!(d.pieces.len(), 1);
    let p = &d.pieces[0];
    assert_eq!(p.quantity, 2);
    assert_eq!(p.seam_allowance_mm, Some(10.0));
    assert!(matches!(&p.surface, SurfaceDef::Patches { patches } if patches.len() == 2));
    let (r, l) = (55.0f64, 500.0f64);
    // Without the seam the two halves weld into a closed tube: two boundary loops (the cuffs).
    let closed = PieceDef {
        seams: Vec::new(),
        ..p.clone()
    };
    let tube = mesh("sleeve", &closed);
    let topo = flatcut_mesh::Topology::build(&tube).unwrap();
    assert_eq!(topo.component_count, 1, "halves welded into one tube");
    assert_eq!(topo.boundary_loops.len(), 2, "a tube has two cuffs");
    assert!(check_disk(&tube).is_err());
    let m = mesh("sleeve", p);
    assert_area("sleeve", m.area(), 2.0 * std::f64::consts::PI * r * l);
    assert!(max_scaled_k("sleeve", p) < DEVELOPABLE_MAX);
    let len = assert_disk("sleeve", &m);
    let want = 2.0 * (2.0 * std::f64::consts::PI * r) + 2.0 * l;
    assert!(
        (len - want).abs() / want < AREA_REL,
        "boundary {len} vs {want}"
    );
}

#[test]
fn sail_panel_is_a_cone_between_its_battens() {
    let d = load("sail", "design.toml");
    let p = &d.pieces[0];
    assert_eq!((d.pieces.len(), p.quantity), (1, 1));
    let m = mesh("sail", p);
    let theta = 2.0 * 11.936621f64.to_radians();
    assert_area("sail", m.area(), 0.5 * theta * (6000.0 + 5900.0) * 400.0);
    assert!(max_scaled_k("sail", p) < DEVELOPABLE_MAX);
    assert_disk("sail", &m);
}

#[test]
fn hull_plate_is_the_conic_development_of_its_chines() {
    let d = load("hull", "design.toml");
    let p = &d.pieces[0];
    // Port and starboard: one as drawn and one mirrored.
    assert_eq!((d.pieces.len(), p.quantity, p.mirrored), (1, 1, 1));
    assert_eq!(
        p.pair_labels(),
        ["PORT".to_string(), "STARBOARD".to_string()]
    );
    // The construction of patterns/hull/make.py: sheer = A + K (chine − A).
    let chine = [
        DVec3::new(0.0, 520.0, 0.0),
        DVec3::new(700.0, 640.0, -60.0),
        DVec3::new(1500.0, 560.0, 20.0),
        DVec3::new(2050.0, 60.0, 260.0),
    ];
    let (apex, k) = (DVec3::new(900.0, -1400.0, -2200.0), 1.18);
    let bez = |t: f64| {
        let s = 1.0 - t;
        chine[0] * s * s * s
            + chine[1] * 3.0 * s * s * t
            + chine[2] * 3.0 * s * t * t
            + chine[3] * t * t * t
    };
    let dbez = |t: f64| {
        let s = 1.0 - t;
        (chine[1] - chine[0]) * 3.0 * s * s
            + (chine[2] - chine[1]) * 6.0 * s * t
            + (chine[3] - chine[2]) * 3.0 * t * t
    };
    let integral = num::integrate(|t| dbez(t).cross(bez(t) - apex).length(), 0.0, 1.0, 1e-9);
    let want = (k - 1.0f64).abs() * (1.0 + k) / 2.0 * integral;
    let m = mesh("hull", p);
    eprintln!("hull plate area {:.0} mm² (analytic {want:.0})", m.area());
    assert_area("hull", m.area(), want);
    assert!(max_scaled_k("hull", p) < DEVELOPABLE_MAX);
    assert_disk("hull", &m);
    let bb = m.bbox();
    assert!(
        (2000.0..2600.0).contains(&(bb.max.x - bb.min.x)),
        "plate ~2 m long"
    );
}

#[test]
fn helmet_is_doubly_curved_and_darts_keep_it_a_disk() {
    let d = load("helmet", "design.toml");
    assert_eq!(d.pieces.len(), 2);
    let cap = mesh("helmet", &d.pieces[0]);
    let darted = mesh("helmet", &d.pieces[1]);
    for (p, m) in d.pieces.iter().zip([&cap, &darted]) {
        assert!(max_scaled_k("helmet", p) > DOUBLY_CURVED_MIN, "{}", p.name);
        let bb = m.bbox();
        let size = bb.max - bb.min;
        // The spline lies inside its net, so the rim falls a little inside the 240 × 200 ellipse.
        assert!((size.x - 240.0).abs() < 4.0, "length {}", size.x);
        assert!((size.y - 200.0).abs() < 4.0, "width {}", size.y);
        assert!((size.z - 110.0).abs() < 0.5, "height {}", size.z);
    }
    let rim = assert_disk("cap", &cap);
    let rim_darted = assert_disk("cap with darts", &darted);
    // Four darts half-way up the dome add two sides each to the outline.
    assert!(rim_darted > rim + 4.0 * 2.0 * 50.0, "{rim_darted} vs {rim}");
    assert_eq!(darted.triangles.len(), cap.triangles.len());
    // Between the rim ellipse's flat area and the half-ellipsoid's (Thomsen's formula, ±1 %).
    let (a, b, c, q) = (120.0f64, 100.0f64, 110.0f64, 1.6075f64);
    let half_ellipsoid = 2.0
        * std::f64::consts::PI
        * (((a * b).powf(q) + (a * c).powf(q) + (b * c).powf(q)) / 3.0).powf(1.0 / q);
    let area = cap.area();
    eprintln!("helmet cap area {area:.0} mm², half-ellipsoid {half_ellipsoid:.0} mm²");
    assert!(
        area > std::f64::consts::PI * a * b && area < 1.02 * half_ellipsoid,
        "area {area} vs half-ellipsoid {half_ellipsoid}"
    );
}

#[test]
fn shoe_upper_is_one_surface_cut_into_four_pieces_by_its_style_lines() {
    let d = load("shoe", "design.toml");
    assert!(d.pieces.is_empty());
    assert_eq!(d.parts.len(), 1);
    let part = &d.parts[0];
    let lines: Vec<&str> = part.lines.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(lines, ["toe-cap", "vamp-lateral", "vamp-medial", "back"]);
    let a = d.assemble(&dir("shoe"), &tol()).unwrap();
    let names: Vec<&str> = a.pieces.iter().map(|p| p.def.name.as_str()).collect();
    assert_eq!(
        names,
        ["toe cap", "vamp", "lateral quarter", "medial quarter"]
    );
    for p in &a.pieces {
        // A pair of shoes: each piece as drawn (left) and mirrored (right).
        assert_eq!((p.def.quantity, p.def.mirrored), (1, 1), "{}", p.def.name);
        assert_eq!(p.def.material.as_deref(), Some("leather"));
        assert_eq!(p.def.seam_allowance_mm, Some(8.0));
        assert!(p.def.grain.is_some());
        assert_disk(&p.def.name, &p.mesh);
    }
    // The upper is doubly curved, and the pieces cover it (up to the tidying of the mesh around
    // the style lines: 0.11 mm² of 39,792 mm², far below the tessellation's own area error).
    let upper = PieceDef {
        name: "upper".into(),
        ..a.pieces[0].def.clone()
    };
    assert!(max_scaled_k("shoe", &upper) > DOUBLY_CURVED_MIN);
    let whole = mesh("shoe", &upper);
    let sum: f64 = a.pieces.iter().map(|p| p.mesh.area()).sum();
    assert!(
        (sum - whole.area()).abs() < 1e-5 * whole.area(),
        "{sum} vs {}",
        whole.area()
    );
    // Four mating seams between the right pieces, both sides at the same 3D points.
    let mut seams: Vec<(String, [&str; 2], usize)> = a
        .seams
        .iter()
        .map(|s| {
            let mut pieces = [0, 1].map(|k| names[s.sides[k].piece]);
            pieces.sort_unstable();
            (s.name.clone(), pieces, s.notches.len())
        })
        .collect();
    seams.sort();
    assert_eq!(
        seams,
        [
            ("back".to_string(), ["lateral quarter", "medial quarter"], 2),
            ("toe-cap".to_string(), ["toe cap", "vamp"], 3),
            ("vamp-lateral".to_string(), ["lateral quarter", "vamp"], 3),
            ("vamp-medial".to_string(), ["medial quarter", "vamp"], 3),
        ]
    );
    for s in &a.seams {
        let pts = |k: usize| -> Vec<DVec3> {
            let side = &s.sides[k];
            side.vertices
                .iter()
                .map(|&v| a.pieces[side.piece].mesh.positions[v as usize])
                .collect()
        };
        assert_eq!(pts(0), pts(1), "{}", s.name);
        // Each notch is exactly at its 3D point.
        let line = part.lines.iter().find(|l| l.name == s.name).unwrap();
        for (n, want) in s.notches.iter().zip(&line.notches) {
            let got = pts(0)[n.index];
            assert!(
                nearest_vertex_distance(&whole, DVec3::from_array(*want)) < 5.0
                    && got.distance(DVec3::from_array(*want)) < CHORD_MM + 1e-3,
                "{}: notch {} at {got}",
                s.name,
                n.name
            );
        }
    }
    // A size-42 last: ~270 mm long overall, ~100 mm wide across the vamp.
    let bb = whole.bbox();
    let length = bb.max.x - bb.min.x;
    assert!((255.0..285.0).contains(&length), "length {length}");
    let width = bb.max.y - bb.min.y;
    assert!((90.0..110.0).contains(&width), "width {width}");
}

/// Boundary curves of a bicubic patch as control-point rows (u = 0, u = 1, v = 0, v = 1).
fn edges(pts: &[[f64; 3]]) -> [[[f64; 3]; 4]; 4] {
    let at = |i: usize, j: usize| pts[4 * i + j];
    [
        [at(0, 0), at(0, 1), at(0, 2), at(0, 3)],
        [at(3, 0), at(3, 1), at(3, 2), at(3, 3)],
        [at(0, 0), at(1, 0), at(2, 0), at(3, 0)],
        [at(0, 3), at(1, 3), at(2, 3), at(3, 3)],
    ]
}

#[test]
fn teapot_has_32_bicubic_patches_sharing_exact_edges() {
    let d = load("teapot", "design.toml");
    assert_eq!(d.pieces.len(), 1);
    let p = &d.pieces[0];
    let SurfaceDef::Patches { patches: defs } = &p.surface else {
        panic!("teapot is a patch list")
    };
    assert_eq!(defs.len(), 32);
    let nets: Vec<Vec<[f64; 3]>> = defs
        .iter()
        .map(|s| match s {
            SurfaceDef::Bezier { degree, points } => {
                assert_eq!(*degree, [3, 3]);
                points.clone()
            }
            other => panic!("not a bicubic Bézier: {other:?}"),
        })
        .collect();
    // The data set lists 306 control points, 16 of which repeat others (the bottom's outer ring
    // repeats the body's lowest ring): 290 distinct. Inches converted to mm: 80 mm tall.
    let mut distinct: Vec<[u64; 3]> = nets
        .iter()
        .flatten()
        .map(|q| q.map(|x| x.to_bits()))
        .collect();
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(distinct.len(), 290);
    let zmax = nets.iter().flatten().map(|q| q[2]).fold(f64::MIN, f64::max);
    assert!((zmax - 3.15 * 25.4).abs() < 1e-9);
    // Crack-free data: count boundary curves that another patch repeats exactly (either way).
    let mut shared = 0;
    for a in 0..nets.len() {
        for b in a + 1..nets.len() {
            for ea in edges(&nets[a]) {
                for eb in edges(&nets[b]) {
                    let mut rev = eb;
                    rev.reverse();
                    if (ea == eb || ea == rev) && ea[0] != ea[3] {
                        shared += 1;
                    }
                }
            }
        }
    }
    // See patterns/teapot/NOTES.md for which curves these are.
    assert_eq!(shared, TEAPOT_SHARED_EDGES, "shared boundary curves");
    assert_eq!(patches("teapot", p).len(), 32);
    for s in patches("teapot", p) {
        let dom = s.domain();
        for i in 0..=8 {
            for j in 0..=8 {
                let u = dom.u.0 + (dom.u.1 - dom.u.0) * i as f64 / 8.0;
                let v = dom.v.0 + (dom.v.1 - dom.v.0) * j as f64 / 8.0;
                assert!(s.eval(u, v).is_finite());
            }
        }
    }
}

/// Boundary curves repeated exactly by a neighbour in the data set (measured: rim, body and
/// bottom rings and their side joins, handle and spout halves, lid and knob rings).
const TEAPOT_SHARED_EDGES: usize = 52;

#[test]
fn teapot_pot_tessellates_crack_free() {
    // Rim, body and bottom: 16 patches, four of them meeting at the bottom centre on collapsed
    // sides. Welded it is one cup (one component, one boundary: the rim's inner edge at radius
    // 1.4 in).
    let d = load("teapot", "body.toml");
    let p = &d.pieces[0];
    let refs = patches("teapot", p);
    let surfs: Vec<&dyn flatcut_surface::ParamSurface> = refs.iter().map(|s| s.as_ref()).collect();
    let whole = flatcut_mesh::tessellate_patches(&surfs, &tol()).unwrap();
    let topo = flatcut_mesh::Topology::build(&whole).unwrap();
    assert_eq!(topo.component_count, 1, "one cup");
    assert_eq!(
        topo.boundary_loops.len(),
        1,
        "only the rim's inner edge is open"
    );
    let lp = &topo.boundary_loops[0];
    for &v in lp {
        let q = whole.positions[v as usize];
        assert!(
            (q.z - 2.4 * 25.4).abs() < 1e-6,
            "boundary vertex off the rim: {q}"
        );
    }
    assert!(
        whole.vertex_count() < 100_000,
        "{} vertices",
        whole.vertex_count()
    );
}
