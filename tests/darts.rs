//! Automatic darts end to end on the bench meshes (../shared/bench/make_meshes.py, scaled to
//! 100 mm): `flatcut flatten --darts auto` brings the shoe toe and a spherical cap within the
//! limits asked. Every check reads the flat OBJ and measures it here, independently of the
//! solver and of the report: each face's singular values within the limits and no flip, each
//! dart's two legs walked along the flat outline (their lengths as reported and within 0.1 mm of
//! each other), no two darts sharing a vertex, the outline simple, and no dart entering a
//! `no_cut` region. Limits no dart can meet (0 % on a sphere) exit 3 and say what was reached.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use clap::Parser as _;
use flatcut::geom::{DVec2, DVec3};

use crate::dxf::python_with;
use crate::pipeline::{root, run_cli};

/// Scale of the bench meshes (unit size) to mm.
const SCALE_MM: f64 = 100.0;
/// Pattern makers' tolerance on a dart's two legs in the flat piece (mm).
const LEG_MATCH_MM: f64 = 0.1;
/// Slack on the limits for rounding in the OBJ's printed coordinates.
const LIMIT_SLACK: f64 = 1e-6;

/// The 2k bench meshes, made once per run by the bench's generator (numpy), scaled to mm.
fn bench_mesh(name: &str) -> Option<PathBuf> {
    static DIR: OnceLock<Option<PathBuf>> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let script = root().join("../shared/bench/make_meshes.py");
        if !script.exists() {
            eprintln!(
                "SKIPPED: {} not found (../shared beside the repository)",
                script.display()
            );
            return None;
        }
        let py = python_with("numpy")?;
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("darts-bench");
        let ok = Command::new(py)
            .arg(&script)
            .args(["--sizes", "2k", "--out"])
            .arg(&dir)
            .output()
            .is_ok_and(|o| o.status.success());
        assert!(ok, "the bench mesh generator failed");
        Some(dir)
    });
    let dir = dir.as_ref()?;
    let scaled = dir.join(format!("{name}_mm.obj"));
    if !scaled.exists() {
        let text = std::fs::read_to_string(dir.join(format!("{name}.obj"))).unwrap();
        let mut out = String::new();
        for line in text.lines() {
            match line.strip_prefix("v ") {
                Some(rest) => {
                    let c: Vec<f64> = rest
                        .split_whitespace()
                        .map(|x| x.parse::<f64>().unwrap() * SCALE_MM)
                        .collect();
                    out.push_str(&format!("v {} {} {}\n", c[0], c[1], c[2]));
                }
                None => {
                    out.push_str(line);
                    out.push('\n');
                }
            }
        }
        std::fs::write(&scaled, out).unwrap();
    }
    Some(scaled)
}

/// A mesh as read from an OBJ: 3D positions, per-vertex UV when given, triangles.
pub(crate) struct Obj {
    pub(crate) v: Vec<DVec3>,
    pub(crate) vt: Vec<DVec2>,
    /// Per face: (vertex, uv) indices of its corners.
    pub(crate) f: Vec<[(usize, usize); 3]>,
}

pub(crate) fn read_obj(path: &Path) -> Obj {
    let text = std::fs::read_to_string(path).unwrap();
    let (mut v, mut vt, mut f) = (Vec::new(), Vec::new(), Vec::new());
    let nums = |s: &str| -> Vec<f64> { s.split_whitespace().map(|x| x.parse().unwrap()).collect() };
    for line in text.lines() {
        if let Some(r) = line.strip_prefix("v ") {
            let c = nums(r);
            v.push(DVec3::new(c[0], c[1], c[2]));
        } else if let Some(r) = line.strip_prefix("vt ") {
            let c = nums(r);
            vt.push(DVec2::new(c[0], c[1]));
        } else if let Some(r) = line.strip_prefix("f ") {
            let c: Vec<(usize, usize)> = r
                .split_whitespace()
                .map(|t| {
                    let mut it = t.split('/');
                    let a: usize = it.next().unwrap().parse().unwrap();
                    let b = it.next().and_then(|s| s.parse().ok()).unwrap_or(a);
                    (a - 1, b - 1)
                })
                .collect();
            assert_eq!(c.len(), 3, "triangles only: {line}");
            f.push([c[0], c[1], c[2]]);
        }
    }
    Obj { v, vt, f }
}

/// Singular values (s1 ≥ s2) and determinant sign of the map of one face from its 3D triangle to
/// its flat triangle, by the closed form of a 2×2 matrix.
fn face_sv(o: &Obj, t: &[(usize, usize); 3]) -> (f64, f64, f64) {
    let [a, b, c, d] = face_jacobian(o, t);
    let t2 = a * a + b * b + c * c + d * d;
    let det = a * d - b * c;
    let root = (t2 * t2 - 4.0 * det * det).max(0.0).sqrt();
    (
        ((t2 + root) / 2.0).sqrt(),
        ((t2 - root) / 2.0).max(0.0).sqrt(),
        det,
    )
}

/// The map of one face, 3D (its own frame) to the plane, as [a, b, c, d] = [[a, b], [c, d]].
fn face_jacobian(o: &Obj, t: &[(usize, usize); 3]) -> [f64; 4] {
    let [p0, p1, p2] = t.map(|c| o.v[c.0]);
    let [q0, q1, q2] = t.map(|c| o.vt[c.1]);
    let (e1, e2) = (p1 - p0, p2 - p0);
    let x = e1.normalize();
    let y = e1.cross(e2).cross(e1).normalize();
    // P: the 3D edges in the triangle's own frame (columns); Q: the flat edges.
    let (p11, p12, p22) = (e1.length(), e2.dot(x), e2.dot(y));
    let (f1, f2) = (q1 - q0, q2 - q0);
    // J = Q P⁻¹ with P = [[p11, p12], [0, p22]].
    let a = f1.x / p11;
    let c = f1.y / p11;
    let b = (f2.x - a * p12) / p22;
    let d = (f2.y - c * p12) / p22;
    [a, b, c, d]
}

/// Worst stretch and compression (percent) of the threads of a woven or knitted material cut
/// with its warp along the pattern's x axis: warp, weft and bias, over the faces. A thread along
/// the flat direction `u` lies on the surface along J⁻¹u, so it is stretched by 1/|J⁻¹u|.
fn measured_threads(o: &Obj) -> [(f64, f64); 3] {
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let dirs = [
        [DVec2::X].to_vec(),
        [DVec2::Y].to_vec(),
        [DVec2::new(r, r), DVec2::new(r, -r)].to_vec(),
    ];
    dirs.map(|ds| {
        let (mut most, mut least) = (f64::MIN, f64::MAX);
        for t in &o.f {
            let [a, b, c, d] = face_jacobian(o, t);
            let det = a * d - b * c;
            assert!(det > 0.0, "a flipped or degenerate face in the flat map");
            for u in &ds {
                // J⁻¹u = adj(J) u / det.
                let v = DVec2::new(d * u.x - b * u.y, -c * u.x + a * u.y) / det;
                let s = 1.0 / v.length();
                (most, least) = (most.max(s), least.min(s));
            }
        }
        ((most - 1.0) * 100.0, (1.0 - least) * 100.0)
    })
}

/// The material's limits as the report states them: (stretch, compression) percent along,
/// across and on the bias.
fn reported_thread_limits(r: &serde_json::Value) -> [(f64, f64); 3] {
    ["along", "across", "bias"].map(|d| {
        let get = |k: &str| r[format!("{k}_{d}")].as_f64().unwrap();
        (get("limit_stretch_pct"), get("limit_compress_pct"))
    })
}

/// Every thread within the material's limits (measured here, and as the report says).
fn assert_threads_within(o: &Obj, r: &serde_json::Value) {
    assert_eq!(r["faces_over_material_limits"], 0, "{r}");
    let limits = reported_thread_limits(r);
    for (k, (got, lim)) in measured_threads(o).iter().zip(limits).enumerate() {
        let name = ["along", "across", "bias"][k];
        assert!(
            got.0 <= lim.0 + LIMIT_SLACK,
            "{name}: stretch {:.4}% beyond {}%",
            got.0,
            lim.0
        );
        assert!(
            got.1 <= lim.1 + LIMIT_SLACK,
            "{name}: compression {:.4}% beyond {}%",
            got.1,
            lim.1
        );
    }
}

/// Worst stretch and compression (percent) over the faces; panics on a flipped face.
pub(crate) fn measured_limits(o: &Obj) -> (f64, f64) {
    let svs: Vec<(f64, f64, f64)> = o.f.iter().map(|t| face_sv(o, t)).collect();
    let sign = svs[0].2.signum();
    assert!(
        svs.iter().all(|s| s.2 * sign > 0.0),
        "a flipped or degenerate face in the flat map"
    );
    let s1 = svs.iter().map(|s| s.0).fold(f64::MIN, f64::max);
    let s2 = svs.iter().map(|s| s.1).fold(f64::MAX, f64::min);
    ((s1 - 1.0) * 100.0, (1.0 - s2) * 100.0)
}

/// The outline of the flat mesh: next vertex along each boundary edge (face orientation).
pub(crate) fn boundary_next(o: &Obj) -> std::collections::BTreeMap<usize, usize> {
    let mut directed = std::collections::BTreeSet::new();
    for t in &o.f {
        for k in 0..3 {
            directed.insert((t[k].0, t[(k + 1) % 3].0));
        }
    }
    directed
        .iter()
        .filter(|(a, b)| !directed.contains(&(*b, *a)))
        .map(|&(a, b)| (a, b))
        .collect()
}

/// A dart as the report states it.
struct ReportedDart {
    start: DVec3,
    apex: DVec3,
    length_3d: f64,
    legs: [f64; 2],
}

fn reported_darts(report: &serde_json::Value) -> Vec<ReportedDart> {
    let p = |v: &serde_json::Value| {
        DVec3::new(
            v[0].as_f64().unwrap(),
            v[1].as_f64().unwrap(),
            v[2].as_f64().unwrap(),
        )
    };
    report["darts"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|d| ReportedDart {
                    start: p(&d["start_3d"]),
                    apex: p(&d["apex_3d"]),
                    length_3d: d["length_3d_mm"].as_f64().unwrap(),
                    legs: [
                        d["leg_2d_mm"][0].as_f64().unwrap(),
                        d["leg_2d_mm"][1].as_f64().unwrap(),
                    ],
                })
                .collect()
        })
        .unwrap_or_default()
}

/// One leg walked along the flat outline from the dart's point to its mouth: its vertices, its
/// 2D length and its 3D length.
struct Leg {
    verts: Vec<usize>,
    len_2d: f64,
    len_3d: f64,
}

/// Each dart's two legs, found on the flat outline: the outline vertex at the dart's point, then
/// both ways along the outline to the first vertex at its mouth.
fn walk_legs(o: &Obj, d: &ReportedDart) -> [Leg; 2] {
    const AT: f64 = 1e-5;
    let next = boundary_next(o);
    let prev: std::collections::BTreeMap<usize, usize> =
        next.iter().map(|(&a, &b)| (b, a)).collect();
    let apexes: Vec<usize> = next
        .keys()
        .copied()
        .filter(|&v| o.v[v].distance(d.apex) < AT)
        .collect();
    assert_eq!(
        apexes.len(),
        1,
        "one outline vertex at the dart's point {:?}",
        d.apex
    );
    let uv = |v: usize| o.vt[v];
    let walk = |step: &std::collections::BTreeMap<usize, usize>| {
        let mut verts = vec![apexes[0]];
        let (mut len_2d, mut len_3d) = (0.0, 0.0);
        loop {
            let here = *verts.last().unwrap();
            let there = step[&here];
            len_2d += uv(here).distance(uv(there));
            len_3d += o.v[here].distance(o.v[there]);
            verts.push(there);
            if o.v[there].distance(d.start) < AT {
                break;
            }
            assert!(
                verts.len() <= next.len(),
                "the dart's mouth is not on the outline"
            );
        }
        Leg {
            verts,
            len_2d,
            len_3d,
        }
    };
    [walk(&next), walk(&prev)]
}

fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (orient(a, b, c), orient(a, b, d));
    let (d3, d4) = (orient(c, d, a), orient(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// The flat outline as a polygon does not cross itself.
fn assert_outline_simple(o: &Obj) {
    let next = boundary_next(o);
    let start = *next.keys().next().unwrap();
    let mut ring = vec![start];
    while next[ring.last().unwrap()] != start {
        ring.push(next[ring.last().unwrap()]);
        assert!(ring.len() <= next.len(), "the outline is not one loop");
    }
    assert_eq!(ring.len(), next.len(), "the flat piece has one outline");
    let p: Vec<DVec2> = ring.iter().map(|&v| o.vt[v]).collect();
    let n = p.len();
    for i in 0..n {
        for j in i + 2..n {
            if (j + 1) % n == i {
                continue;
            }
            assert!(
                !segments_cross(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]),
                "the flat outline crosses itself near {:?}",
                p[i]
            );
        }
    }
}

/// What one `flatten --darts auto` run gave, measured from its files.
struct Darted {
    stretch_pct: f64,
    compress_pct: f64,
    legs: Vec<[Leg; 2]>,
    darts: Vec<ReportedDart>,
}

/// Checks a darted flat OBJ and its report against each other and the limits.
fn check_darted(input: &Path, flat: &Path, report: &Path, stretch: f64, compress: f64) -> Darted {
    let o = read_obj(flat);
    assert_eq!(o.v.len(), o.vt.len(), "one UV per vertex");
    let (s, c) = measured_limits(&o);
    assert!(
        s <= stretch + LIMIT_SLACK,
        "stretch {s:.4}% beyond {stretch}%"
    );
    assert!(
        c <= compress + LIMIT_SLACK,
        "compression {c:.4}% beyond {compress}%"
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    let darts = reported_darts(&r);
    assert!(!darts.is_empty(), "darts were needed and none is reported");
    // The input's outline: every dart leaves it, and its point lies inside the piece.
    let inp = read_obj(input);
    let rim: Vec<DVec3> = boundary_next(&inp).keys().map(|&v| inp.v[v]).collect();
    let to_rim = |p: DVec3| rim.iter().map(|q| q.distance(p)).fold(f64::MAX, f64::min);
    let mut legs = Vec::new();
    for d in &darts {
        assert!(
            to_rim(d.start) < 1e-5,
            "a dart's mouth {:?} is off the outline",
            d.start
        );
        assert!(
            to_rim(d.apex) > 1.0,
            "a dart's point {:?} is on the outline",
            d.apex
        );
        let l = walk_legs(&o, d);
        for (k, leg) in l.iter().enumerate() {
            assert!(
                (leg.len_2d - d.legs[k]).abs() < 1e-4 || (leg.len_2d - d.legs[1 - k]).abs() < 1e-4,
                "leg measured {} mm, reported {:?}",
                leg.len_2d,
                d.legs
            );
            assert!(
                (leg.len_3d - d.length_3d).abs() < 1e-4,
                "leg 3D {} vs {}",
                leg.len_3d,
                d.length_3d
            );
        }
        assert!(
            (l[0].len_2d - l[1].len_2d).abs() <= LEG_MATCH_MM,
            "legs {} and {} mm differ by more than {LEG_MATCH_MM} mm",
            l[0].len_2d,
            l[1].len_2d
        );
        // The two legs are one cut: the same 3D points, point to mouth.
        assert_eq!(l[0].verts.len(), l[1].verts.len());
        for (a, b) in l[0].verts.iter().zip(&l[1].verts) {
            assert!(o.v[*a].distance(o.v[*b]) < 1e-5, "the legs part in 3D");
        }
        legs.push(l);
    }
    // No two darts share a vertex (they would cross or touch).
    for i in 0..legs.len() {
        for j in i + 1..legs.len() {
            let pts = |l: &[Leg; 2]| -> Vec<DVec3> { l[0].verts.iter().map(|&v| o.v[v]).collect() };
            for p in pts(&legs[i]) {
                for q in pts(&legs[j]) {
                    assert!(p.distance(q) > 1e-5, "darts {i} and {j} meet at {p:?}");
                }
            }
        }
    }
    assert_outline_simple(&o);
    Darted {
        stretch_pct: s,
        compress_pct: c,
        legs,
        darts,
    }
}

/// `flatten --darts auto` at 5 % stretch and 2 % compression (the shoe's leather); the flat
/// OBJ and the report.
fn flatten_darts(input: &Path, out: &Path, extra: &[&str]) -> (PathBuf, PathBuf) {
    flatten_darts_within(input, out, ("5", "2"), extra)
}

/// `flatten --darts auto` within `(stretch, compress)` percent, which must succeed.
fn flatten_darts_within(
    input: &Path,
    out: &Path,
    (stretch, compress): (&str, &str),
    extra: &[&str],
) -> (PathBuf, PathBuf) {
    let mut args = vec!["--max-stretch", stretch, "--max-compress", compress];
    args.extend_from_slice(extra);
    flatten_darted(input, out, &args)
}

/// `flatten --darts auto` with `args` (the limits among them), which must succeed; the flat OBJ
/// and the report.
fn flatten_darted(input: &Path, out: &Path, args: &[&str]) -> (PathBuf, PathBuf) {
    let flat = out.join("flat.obj");
    let report = out.join("r.json");
    let mut all = vec![
        "flatten",
        input.to_str().unwrap(),
        "--darts",
        "auto",
        "-o",
        flat.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    let code = run_cli(&all);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    (flat, report)
}

#[test]
fn darts_bring_the_shoe_toe_within_five_percent_stretch_and_two_compression() {
    let Some(toe) = bench_mesh("toe_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (flat, report) = flatten_darts(&toe, dir.path(), &[]);
    let d = check_darted(&toe, &flat, &report, 5.0, 2.0);
    // Without darts the toe is far beyond (47 % stretch): the darts did the work.
    assert!(d.stretch_pct <= 5.0 + LIMIT_SLACK && d.compress_pct <= 2.0 + LIMIT_SLACK);
    assert!(d.darts.len() <= 24);
}

/// The total width of the darts' mouths in the flat piece, measured on its outline: the
/// distance between the mouth ends of each dart's two legs.
fn mouths_mm(o: &Obj, legs: &[[Leg; 2]]) -> f64 {
    legs.iter()
        .map(|[a, b]| {
            let (ma, mb) = (a.verts.last().unwrap(), b.verts.last().unwrap());
            o.vt[*ma].distance(o.vt[*mb])
        })
        .sum()
}

/// `mesh` darted at ±3 % with `--dart-fit fit`, checked by `check_darted`, and the total width
/// of its darts' mouths (mm).
fn darted_with_fit(mesh: &Path, fit: &str) -> (Darted, f64) {
    let dir = tempfile::tempdir().unwrap();
    let (flat, report) = flatten_darts_within(mesh, dir.path(), ("3", "3"), &["--dart-fit", fit]);
    let d = check_darted(mesh, &flat, &report, 3.0, 3.0);
    let width = mouths_mm(&read_obj(&flat), &d.legs);
    (d, width)
}

#[test]
fn a_tight_fit_draws_the_same_darts_narrower_within_the_limits() {
    // `--dart-fit tight` spends the give of ±3 % on closing the darts: the same darts (mouths,
    // points, lengths), every face still within the limits and the legs meeting (measured on the
    // OBJ by `check_darted`), the mouths narrower.
    let Some(cap) = bench_mesh("sphcap_a100_2k") else {
        return;
    };
    let (loose, loose_mm) = darted_with_fit(&cap, "least-strain");
    let (tight, tight_mm) = darted_with_fit(&cap, "tight");
    println!("mouths: least strain {loose_mm:.2} mm, tight {tight_mm:.2} mm");
    assert_eq!(loose.darts.len(), tight.darts.len());
    for (a, b) in loose.darts.iter().zip(&tight.darts) {
        assert!(a.start.distance(b.start) < 1e-6 && a.apex.distance(b.apex) < 1e-6);
        assert!((a.length_3d - b.length_3d).abs() < 1e-6);
    }
    assert!(
        tight_mm < 0.95 * loose_mm,
        "tight {tight_mm} mm, least strain {loose_mm} mm"
    );
}

#[test]
fn a_tight_fit_ends_a_dart_where_it_draws_it_shut() {
    // On the 140° cap at ±3 % the tight map draws darts shut before their points. Those darts
    // end there, the piece is cut again and drawn tight again: the same mouths, every dart no
    // longer and some shorter, the mouths narrower, and the limits and legs still held (checked
    // on the OBJ by `check_darted`). Before, the tight fit gave way to the least-strained map
    // here (the guards next to a dart's point stopped the solver, its legs 0.2 mm apart).
    let Some(cap) = bench_mesh("sphcap_a140_2k") else {
        return;
    };
    let (loose, loose_mm) = darted_with_fit(&cap, "least-strain");
    let (tight, tight_mm) = darted_with_fit(&cap, "tight");
    let length = |d: &Darted| d.darts.iter().map(|d| d.length_3d).sum::<f64>();
    let (ll, tl) = (length(&loose), length(&tight));
    println!(
        "least strain: {ll:.1} mm of darts, mouths {loose_mm:.2} mm; tight: {tl:.1} mm, {tight_mm:.2} mm"
    );
    assert_eq!(loose.darts.len(), tight.darts.len());
    for (a, b) in loose.darts.iter().zip(&tight.darts) {
        assert!(a.start.distance(b.start) < 1e-6, "a dart moved its mouth");
        assert!(b.length_3d <= a.length_3d + 1e-6, "a tight dart is longer");
    }
    assert!(
        tl < 0.98 * ll,
        "darts {tl} mm tight, {ll} mm least-strained"
    );
    assert!(
        tight_mm < 0.97 * loose_mm,
        "tight {tight_mm} mm, least strain {loose_mm} mm"
    );
}

#[test]
fn darts_for_a_material_hold_its_limits_in_every_direction() {
    // `--material` alone gives the limits, each thread its own: leather takes 3 % along the
    // backbone but 6 % across it, so it needs fewer and shorter darts than its tightest limits
    // (3 % / 0.5 %, held on the principal stretches when the run names them) would.
    let Some(cap) = bench_mesh("sphcap_a100_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (flat, report) = flatten_darted(&cap, dir.path(), &["--material", "leather"]);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let limits = reported_thread_limits(&r);
    // The limits are on the threads: a principal stretch between them may go beyond each.
    let threads = check_darted(&cap, &flat, &report, f64::INFINITY, f64::INFINITY);
    assert_threads_within(&read_obj(&flat), &r);
    let o = read_obj(&flat);
    let across = measured_threads(&o)[1].0;
    assert!(
        across > limits[0].0,
        "the weft takes more than the warp may: {across}%"
    );

    let tight_dir = dir.path().join("tight");
    std::fs::create_dir_all(&tight_dir).unwrap();
    let (tf, tr) = flatten_darted(
        &cap,
        &tight_dir,
        &[
            "--material",
            "leather",
            "--max-stretch",
            "3",
            "--max-compress",
            "0.5",
        ],
    );
    let tight = check_darted(&cap, &tf, &tr, 3.0, 0.5);
    let total = |d: &Darted| d.darts.iter().map(|d| d.length_3d).sum::<f64>();
    assert!(
        threads.darts.len() <= tight.darts.len() && total(&threads) < total(&tight),
        "per thread: {} darts, {:.1} mm; tightest on the principal stretches: {} darts, {:.1} mm",
        threads.darts.len(),
        total(&threads),
        tight.darts.len(),
        total(&tight)
    );
}

#[test]
fn darts_per_thread_keep_the_warp_on_the_designs_grain_line() {
    // The thread limits turn with the map: the darted piece must still put the warp along the
    // grain line the design draws on the surface, here 30° off the x axis.
    let Some(cap) = bench_mesh("sphcap_a100_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(&cap, dir.path().join("cap.obj")).unwrap();
    let g = DVec3::new(30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0);
    let (a, b) = (-50.0 * g + 100.0 * DVec3::Z, 50.0 * g + 100.0 * DVec3::Z);
    let design = dir.path().join("cap.toml");
    std::fs::write(
        &design,
        format!(
            "[[piece]]\nname = \"cap\"\ndarts = \"auto\"\nmaterial_properties = \"woven-cotton\"\ngrain = [[{}, {}, {}], [{}, {}, {}]]\n[piece.surface]\ntype = \"mesh\"\nfile = \"cap.obj\"\n",
            a.x, a.y, a.z, b.x, b.y, b.z
        ),
    )
    .unwrap();
    let flat = dir.path().join("flat.obj");
    let report = dir.path().join("r.json");
    let code = run_cli(&[
        "flatten",
        design.to_str().unwrap(),
        "-o",
        flat.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let r = if r.is_array() { r[0].clone() } else { r };
    assert!(!reported_darts(&r).is_empty(), "the cap needs a dart: {r}");
    let o = read_obj(&flat);
    assert_threads_within(&o, &r);
    // Around the pole, the image of the grain line's direction runs along the pattern's warp
    // (+x): F a for a the line's direction in each face's frame.
    let mut worst: f64 = 0.0;
    for t in &o.f {
        let [p0, p1, p2] = t.map(|c| o.v[c.0]);
        if ((p0 + p1 + p2) / 3.0 - 100.0 * DVec3::Z).length() > 10.0 {
            continue;
        }
        let (e1, e2) = (p1 - p0, p2 - p0);
        let x = e1.normalize();
        let y = e1.cross(e2).cross(e1).normalize();
        let [ja, jb, jc, jd] = face_jacobian(&o, t);
        let (ax, ay) = (g.dot(x), g.dot(y));
        let image = DVec2::new(ja * ax + jb * ay, jc * ax + jd * ay);
        worst = worst.max(image.y.atan2(image.x).abs().to_degrees());
    }
    assert!(worst < 1.0, "the warp runs {worst:.2}° off the grain line");
}

#[test]
fn a_woven_dome_takes_its_curvature_on_the_bias_and_needs_fewer_darts() {
    // Woven cotton hardly stretches along its threads (2 %, 3 %) but shears freely (15 % on the
    // bias): darts for its thread limits leave the dome's curvature to the bias, where darts for
    // its tightest limits cut it away.
    let Some(cap) = bench_mesh("sphcap_a100_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (flat, report) = flatten_darted(&cap, dir.path(), &["--material", "woven-cotton"]);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let o = read_obj(&flat);
    assert_threads_within(&o, &r);
    let threads = measured_threads(&o);
    assert!(
        threads[2].0 > 10.0,
        "the bias takes the strain: {:?}",
        threads
    );
    assert!(r["bias_strain_share"].as_f64().unwrap() > 0.8, "{r}");
    let darts = reported_darts(&r);
    let tight_dir = dir.path().join("tight");
    std::fs::create_dir_all(&tight_dir).unwrap();
    let (_, tr) = flatten_darted(
        &cap,
        &tight_dir,
        &[
            "--material",
            "woven-cotton",
            "--max-stretch",
            "2",
            "--max-compress",
            "1",
        ],
    );
    let tr: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&tr).unwrap()).unwrap();
    let tight = reported_darts(&tr);
    assert!(
        darts.len() * 3 <= tight.len(),
        "{} darts per thread against {} for the tightest limits",
        darts.len(),
        tight.len()
    );
}

#[test]
fn darts_per_thread_are_the_fewest_that_hold_and_their_legs_meet() {
    // Canvas holds its threads to 1.5–2 % but its bias to 8 %: a count estimated for the
    // tightest limits is far too many (on the toe it went down from there to 18 darts,
    // 2,265 mm, where 17 broke the limits, while 4 hold). Held at the bias limit, a dart's
    // flanks press on its legs along different threads: they must still meet within 0.1 mm
    // (3 darts on the woven hemisphere held the limits with legs 0.4 mm apart, 2.7 mm on
    // another tessellation of it; 4 keep them equal).
    for (mesh, material) in [("toe_2k", "canvas"), ("hemisphere_2k", "woven-cotton")] {
        let Some(input) = bench_mesh(mesh) else {
            return;
        };
        let dir = tempfile::tempdir().unwrap();
        let (flat, report) = flatten_darted(&input, dir.path(), &["--material", material]);
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let o = read_obj(&flat);
        assert_threads_within(&o, &r);
        assert_outline_simple(&o);
        let darts = reported_darts(&r);
        let k = darts.len();
        assert!((1..=6).contains(&k), "{mesh}: {k} darts");
        // Measured along the flat outline, not taken from the report.
        for d in &darts {
            let [a, b] = walk_legs(&o, d);
            assert!(
                (a.len_2d - b.len_2d).abs() <= 0.1,
                "{mesh}: legs {} and {} mm",
                a.len_2d,
                b.len_2d
            );
        }
        // One dart fewer does not hold: with at most k − 1 darts the run ends with exit 3.
        let fewer = (k - 1).to_string();
        let out = dir.path().join("fewer.obj");
        let args = [
            "flatcut",
            "flatten",
            input.to_str().unwrap(),
            "--darts",
            "auto",
            "--material",
            material,
            "--max-darts",
            &fewer,
            "-o",
            out.to_str().unwrap(),
        ];
        let cli = flatcut_cli::Cli::try_parse_from(args).expect("valid arguments");
        let code = flatcut_cli::exit_code(flatcut_cli::run(cli));
        assert_eq!(
            format!("{code:?}"),
            format!(
                "{:?}",
                std::process::ExitCode::from(flatcut_cli::EXIT_LIMIT)
            ),
            "{mesh}: {fewer} darts held"
        );
    }
}

#[test]
fn darts_bring_a_spherical_cap_within_the_limits_and_keep_out_of_a_no_cut_region() {
    let Some(cap) = bench_mesh("sphcap_a100_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (flat, report) = flatten_darts(&cap, dir.path(), &[]);
    let free = check_darted(&cap, &flat, &report, 5.0, 2.0);
    // A cap is symmetric about its pole: the darts are alike and all point at it.
    for d in &free.darts {
        let radial = (d.start - d.apex).normalize();
        assert!(d.start.z < d.apex.z, "a dart points away from the pole");
        assert!(radial.z < 0.0);
    }

    // A no_cut square on the surface around the middle of the first dart: darts go elsewhere.
    let first = &free.legs[0][0];
    let o = read_obj(&flat);
    let mid = o.v[first.verts[first.verts.len() / 2]];
    let n = mid.normalize();
    let u = n.cross(DVec3::Z).normalize();
    let w = n.cross(u);
    const HALF: f64 = 15.0;
    let corner = |a: f64, b: f64| (mid + u * a + w * b).normalize() * SCALE_MM;
    let square = [
        corner(-HALF, -HALF),
        corner(HALF, -HALF),
        corner(HALF, HALF),
        corner(-HALF, HALF),
    ];
    let pts: Vec<String> = square
        .iter()
        .map(|p| format!("[{}, {}, {}]", p.x, p.y, p.z))
        .collect();
    let design = dir.path().join("cap.toml");
    std::fs::copy(&cap, dir.path().join("cap.obj")).unwrap();
    std::fs::write(
        &design,
        format!(
            "[[piece]]\nname = \"cap\"\ndarts = \"auto\"\nno_cut = [[{}]]\n[piece.surface]\ntype = \"mesh\"\nfile = \"cap.obj\"\n",
            pts.join(", ")
        ),
    )
    .unwrap();
    let kept = dir.path().join("kept");
    std::fs::create_dir_all(&kept).unwrap();
    let (flat2, report2) = flatten_darts(&design, &kept, &[]);
    let d2 = check_darted(&cap, &flat2, &report2, 5.0, 2.0);
    // In the square's tangent frame no dart segment enters the square.
    let o2 = read_obj(&flat2);
    let local = |p: DVec3| DVec2::new((p - mid).dot(u), (p - mid).dot(w));
    let inside = |q: DVec2| q.x.abs() < HALF && q.y.abs() < HALF;
    let sq: Vec<DVec2> = [(-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF)]
        .iter()
        .map(|&(a, b)| DVec2::new(a, b))
        .collect();
    for l in &d2.legs {
        for s in l[0].verts.windows(2) {
            let (p, q) = (o2.v[s[0]], o2.v[s[1]]);
            if p.dot(n) <= 0.0 || q.dot(n) <= 0.0 {
                continue;
            }
            let (a, b) = (local(p), local(q));
            assert!(
                !inside(a) && !inside(b),
                "a dart enters the no_cut region at {p:?}"
            );
            for k in 0..4 {
                assert!(
                    !segments_cross(a, b, sq[k], sq[(k + 1) % 4]),
                    "a dart crosses the no_cut region's edge near {p:?}"
                );
            }
        }
    }
}

/// The shoe toe at ±3 %: the fewest darts that hold the limits (6) include two short ones that the
/// final map closes past their mouths, so its flat outline would overlap itself there. That is
/// no pattern: the search goes on to more darts, each needed less, and the piece written is
/// within the limits with a simple outline and matched legs.
#[test]
fn darts_that_would_close_past_their_mouths_give_way_to_more_darts() {
    let Some(toe) = bench_mesh("toe_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (flat, report) = flatten_darts_within(&toe, dir.path(), ("3", "3"), &[]);
    let d = check_darted(&toe, &flat, &report, 3.0, 3.0);
    assert!(d.darts.len() > 6, "{} darts", d.darts.len());
}

#[test]
fn limits_no_dart_can_meet_exit_3_and_say_what_was_reached() {
    let Some(cap) = bench_mesh("sphcap_a100_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat.obj");
    let args = [
        "flatcut",
        "flatten",
        cap.to_str().unwrap(),
        "--max-stretch",
        "0",
        "--max-compress",
        "0",
        "--darts",
        "auto",
        "-o",
        flat.to_str().unwrap(),
    ];
    let cli = flatcut_cli::Cli::try_parse_from(args).expect("valid arguments");
    let result = flatcut_cli::run(cli);
    let text = match &result {
        Ok(code) => panic!("a sphere cannot lie flat within 0 %, yet the run ended {code:?}"),
        Err(e) => format!("{e:#}"),
    };
    assert!(
        text.contains("cannot be met")
            && text.contains("reached")
            && text.contains("beyond the limits"),
        "{text}"
    );
    assert_eq!(
        format!("{:?}", flatcut_cli::exit_code(result)),
        format!(
            "{:?}",
            std::process::ExitCode::from(flatcut_cli::EXIT_LIMIT)
        )
    );
    assert!(
        !flat.exists(),
        "no flat OBJ is written when the limits are not met"
    );
}

/// The parts `<stem>-1.obj`, `<stem>-2.obj`, … a split wrote into `dir`, in order.
pub(crate) fn split_parts(dir: &Path, stem: &str) -> Vec<Obj> {
    (1..)
        .map(|k| dir.join(format!("{stem}-{k}.obj")))
        .take_while(|p| p.exists())
        .map(|p| read_obj(&p))
        .collect()
}

/// The flat position of vertex `v` (its first corner's UV).
fn flat_at(o: &Obj, v: usize) -> DVec2 {
    o.f.iter()
        .flatten()
        .find(|c| c.0 == v)
        .map(|c| o.vt[c.1])
        .unwrap()
}

/// When outline edge `(u, w)` of `a` is sewn to `b` (an outline edge of `b` runs between the
/// same two 3D points the other way), its flat length in `a` and in `b`.
/// The flat lengths of outline edge `u`→`w` of `a` and of the outline edge of `b` sewn to it:
/// the one between vertices at the same two 3D points, running the other way (on `b = a`, a
/// seam of the part with itself, one of the other copies of those points).
pub(crate) fn sewn_lengths(a: &Obj, (u, w): (usize, usize), b: &Obj) -> Option<(f64, f64)> {
    let at = |p: DVec3| -> Vec<usize> { (0..b.v.len()).filter(|&i| b.v[i] == p).collect() };
    let next = boundary_next(b);
    let (xs, ys) = (at(a.v[u]), at(a.v[w]));
    let (x, y) = xs
        .iter()
        .flat_map(|&x| ys.iter().map(move |&y| (x, y)))
        .find(|&(x, y)| next.get(&y) == Some(&x))?;
    Some((
        flat_at(a, u).distance(flat_at(a, w)),
        flat_at(b, x).distance(flat_at(b, y)),
    ))
}

/// The bench's saddle at 3 %/3 %: no dart can help (its flat piece is too short at the rim), and
/// the error says so and names `--split auto`; with `--split auto` it is cut in parts, each
/// within the limits as measured here from its OBJ, sewn along seams whose coincident edges
/// have equal flat lengths (read from the two OBJs), with balance notches at equal offsets on
/// both sides (report).
#[test]
fn a_saddle_no_dart_can_help_is_split_into_parts_that_sew_together() {
    let Some(saddle) = bench_mesh("saddle_2k") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat.obj");
    let report = dir.path().join("flat.json");
    let mut args = vec![
        "flatcut",
        "flatten",
        saddle.to_str().unwrap(),
        "--max-stretch",
        "3",
        "--max-compress",
        "3",
        "--darts",
        "auto",
        "-o",
        flat.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    let darts_only = flatcut_cli::run(flatcut_cli::Cli::try_parse_from(&args).unwrap());
    let text = format!("{:#}", darts_only.expect_err("no dart can help a saddle"));
    assert!(
        text.contains("no dart can help") && text.contains("--split auto"),
        "{text}"
    );
    args.extend(["--split", "auto"]);
    let code = flatcut_cli::run(flatcut_cli::Cli::try_parse_from(&args).unwrap()).unwrap();
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let parts = split_parts(dir.path(), "flat-saddle_2k_mm");
    assert!(
        parts.len() >= 2,
        "{:?}",
        std::fs::read_dir(dir.path()).unwrap().collect::<Vec<_>>()
    );
    for (k, o) in parts.iter().enumerate() {
        let (s, c) = measured_limits(o);
        assert!(
            s <= 3.0 + LIMIT_SLACK && c <= 3.0 + LIMIT_SLACK,
            "part {k}: {s} % / {c} %"
        );
    }
    // Edges on both sides of a seam: the same two 3D points, the same flat length.
    let mut sewn = 0;
    for i in 0..parts.len() {
        for j in i + 1..parts.len() {
            for (&u, &w) in &boundary_next(&parts[i]) {
                if let Some((la, lb)) = sewn_lengths(&parts[i], (u, w), &parts[j]) {
                    assert!((la - lb).abs() < 1e-5, "parts {i}/{j}: {la} vs {lb}");
                    sewn += 1;
                }
            }
        }
    }
    assert!(sewn > 10, "{sewn} sewn edges");
    let reports: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let seam = &reports[0]["mating_seams"][0];
    assert!(seam["mismatch_mm"].as_f64().unwrap() < 1e-6, "{seam}");
    let notches = seam["notches"].as_array().unwrap();
    assert_eq!(notches.len(), 2, "{seam}");
    for n in notches {
        let o = &n["offset_mm"];
        assert!(
            (o[0].as_f64().unwrap() - o[1].as_f64().unwrap()).abs() < 1e-6,
            "{n}"
        );
    }
}

#[test]
fn split_without_limits_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat.obj");
    let design = root().join("crates/design/examples/cylinder.toml");
    let cli = flatcut_cli::Cli::try_parse_from([
        "flatcut",
        "flatten",
        design.to_str().unwrap(),
        "--split",
        "auto",
        "-o",
        flat.to_str().unwrap(),
    ])
    .unwrap();
    let text = format!("{:#}", flatcut_cli::run(cli).expect_err("refused"));
    assert!(text.contains("--split auto needs --max-stretch"), "{text}");
    assert!(text.contains("or --material"), "{text}");
    assert!(!flat.exists());
}

/// A UV sphere of radius `r` (closed: no boundary) as OBJ text.
pub(crate) fn ball_obj(r: f64, rings: usize, segments: usize) -> String {
    use std::f64::consts::PI;
    let mut s = format!("v 0 0 {r}\n");
    for i in 1..rings {
        let th = PI * i as f64 / rings as f64;
        for j in 0..segments {
            let ph = 2.0 * PI * j as f64 / segments as f64;
            s.push_str(&format!(
                "v {} {} {}\n",
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos()
            ));
        }
    }
    s.push_str(&format!("v 0 0 {}\n", -r));
    let (m, last) = (segments, 1 + (rings - 1) * segments);
    for j in 0..m {
        s.push_str(&format!("f 1 {} {}\n", 2 + j, 2 + (j + 1) % m));
    }
    for i in 0..rings - 2 {
        for j in 0..m {
            let (a, b) = (1 + i * m + j, 1 + i * m + (j + 1) % m);
            let (c, d) = (a + m, b + m);
            s.push_str(&format!("f {} {} {}\n", a + 1, c + 1, d + 1));
            s.push_str(&format!("f {} {} {}\n", a + 1, d + 1, b + 1));
        }
    }
    let base = 1 + (rings - 2) * m;
    for j in 0..m {
        s.push_str(&format!(
            "f {} {} {}\n",
            base + j + 1,
            last + 1,
            base + (j + 1) % m + 1
        ));
    }
    s
}

/// A closed ball cannot be flattened at all until it is cut open: with `--split auto` it is
/// opened and split into parts, each within the limits as measured here, that cover the ball
/// once (their areas add up to its area) and close it again: every outline edge of every part
/// is sewn to an outline edge (of another part, or of the same part where the opening slit's
/// two sides both lie on it) at the same two 3D points, at the same flat length.
#[test]
fn a_closed_ball_is_opened_and_split_into_parts_that_close_it_again() {
    let dir = tempfile::tempdir().unwrap();
    let ball = dir.path().join("ball.obj");
    std::fs::write(&ball, ball_obj(60.0, 16, 32)).unwrap();
    let flat = dir.path().join("flat.obj");
    let cli = flatcut_cli::Cli::try_parse_from([
        "flatcut",
        "flatten",
        ball.to_str().unwrap(),
        "--max-stretch",
        "8",
        "--max-compress",
        "8",
        "--split",
        "auto",
        "-o",
        flat.to_str().unwrap(),
    ])
    .unwrap();
    let code = flatcut_cli::run(cli).unwrap();
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let parts = split_parts(dir.path(), "flat-ball");
    assert!(parts.len() >= 2, "{} parts", parts.len());
    let area3 = |o: &Obj| -> f64 {
        o.f.iter()
            .map(|t| {
                let [a, b, c] = t.map(|x| o.v[x.0]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    };
    let whole = read_obj(&ball);
    let total: f64 = parts.iter().map(area3).sum();
    // The cuts' cleanup moves vertices along the cuts by far less than the chordal tolerance
    // (0.1 mm over some 1,000 mm of cuts would be 100 mm²): the area moves by under 1e-4 of it
    // (0.47 mm² of 44,876 mm² here).
    assert!(
        (total - area3(&whole)).abs() < 1e-4 * total,
        "{total} vs {}",
        area3(&whole)
    );
    for (i, a) in parts.iter().enumerate() {
        let (s, c) = measured_limits(a);
        assert!(
            s <= 8.0 + LIMIT_SLACK && c <= 8.0 + LIMIT_SLACK,
            "part {i}: {s} % / {c} %"
        );
        for (&u, &w) in &boundary_next(a) {
            let sewn = parts
                .iter()
                .any(|b| sewn_lengths(a, (u, w), b).is_some_and(|(la, lb)| (la - lb).abs() < 1e-5));
            assert!(
                sewn,
                "part {i}: outline edge {} – {} is sewn to nothing",
                a.v[u], a.v[w]
            );
        }
    }
}
