//! `flatten --despike`: a scan's spikes moved back into its surface before the split, checked
//! from the files written. A ball with one face raised into a spike is refused at ±10 % without
//! it (the message names the remedy), refused with it when the spike needs a longer move than
//! `--despike-max-mm` allows, and split within the limits (every face measured here by its
//! singular values) once the spike may move as far as it must: the parts then cover exactly the
//! ball without the spike (the spike's three faces lie in the plane of the face they replaced),
//! and the report says what moved, how far and from where.

use flatcut::geom::DVec3;
use flatcut::mesh::TriMesh;
use flatcut_mesh::test_shapes::star_shaped;

use crate::darts::{measured_limits, split_parts};
use crate::genus::{flatten, obj_text};

/// The 320-face ball of radius 100 mm with its first face raised into a spike: three faces round
/// a point 25 mm out from the face's centroid; the ball, the spiked ball, the spike's tip and its
/// distance from the face's plane.
fn spiked_ball() -> (TriMesh, TriMesh, DVec3, f64) {
    let ball = star_shaped(2, flatcut::geom::DMat3::IDENTITY, |_| 100.0);
    let mut spiked = ball.clone();
    let [a, b, c] = spiked.triangles[0].map(|v| spiked.positions[v as usize]);
    let mid = (a + b + c) / 3.0;
    let top = mid + mid.normalize() * 25.0;
    let normal = (b - a).cross(c - a).normalize();
    let height = (top - mid).dot(normal).abs();
    let [ia, ib, ic] = spiked.triangles[0];
    let s = spiked.positions.len() as u32;
    spiked.positions.push(top);
    spiked.triangles[0] = [ia, ib, s];
    spiked.triangles.push([ib, ic, s]);
    spiked.triangles.push([ic, ia, s]);
    (ball, spiked, top, height)
}

/// ±10 % in at most four parts: the ball without the spike takes four here, the spiked one
/// (whose spike needs a seam through it) more.
const LIMITS: &[&str] = &[
    "--max-stretch",
    "10",
    "--max-compress",
    "10",
    "--split",
    "auto",
    "--max-pieces",
    "4",
];

#[test]
fn a_spiked_ball_is_refused_without_despike_and_split_within_the_limits_with_it() {
    let (ball, spiked, top, height) = spiked_ball();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("spiked.obj");
    std::fs::write(&file, obj_text(&spiked, 6)).unwrap();

    // Without --despike: refused, the spike named and the remedy given; nothing written.
    let plain = dir.path().join("plain");
    std::fs::create_dir(&plain).unwrap();
    let text = flatten(&file, &plain, LIMITS).unwrap_err();
    assert!(
        text.contains("1 vertices of the surface have more angle defect")
            && text.contains("--despike"),
        "{text}"
    );
    assert_eq!(std::fs::read_dir(&plain).unwrap().count(), 0);

    // With --despike but a largest move shorter than the spike: left, and refused as before.
    let short = dir.path().join("short");
    std::fs::create_dir(&short).unwrap();
    let mut args = LIMITS.to_vec();
    args.push("--despike");
    let text = flatten(&file, &short, &args).unwrap_err();
    assert!(
        text.contains("1 vertices of the surface have more angle defect")
            && text.contains("--despike moved 0 vertices, at most 0.000 mm, and left 1"),
        "{text}"
    );

    // Room to move it: split within the limits.
    let moved = dir.path().join("moved");
    std::fs::create_dir(&moved).unwrap();
    args.extend(["--despike-max-mm", "30"]);
    let code = flatten(&file, &moved, &args).unwrap();
    assert_eq!(code, format!("{:?}", std::process::ExitCode::SUCCESS));
    let parts = split_parts(&moved, "flat-spiked");
    assert!(
        !parts.is_empty() && parts.len() <= 4,
        "{} parts",
        parts.len()
    );
    for (i, p) in parts.iter().enumerate() {
        let (s, c) = measured_limits(p);
        assert!(
            s <= 10.0 + 1e-6 && c <= 10.0 + 1e-6,
            "part {i}: {s} % / {c} %"
        );
    }
    // The spike lies in its face's plane: the parts cover the ball without it, not the spiked
    // ball (0.4 % more).
    let covered: f64 = parts
        .iter()
        .map(|o| {
            o.f.iter()
                .map(|t| {
                    let [a, b, c] = t.map(|x| o.v[x.0]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum::<f64>()
        })
        .sum();
    assert!(
        (covered - ball.area()).abs() < 1e-4 * ball.area(),
        "{covered} vs {} (spiked {})",
        ball.area(),
        spiked.area()
    );
    assert!(spiked.area() - ball.area() > 1e-3 * ball.area());
    // The report of every part says what moved: one vertex, its height over the face, from the
    // spike's tip, none left.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(moved.join("flat.json")).unwrap()).unwrap();
    let reports = json.as_array().map_or(vec![&json], |a| a.iter().collect());
    for r in reports {
        let d = &r["despike"];
        assert_eq!(d["moved"], 1, "{d}");
        assert_eq!(d["left"], 0, "{d}");
        let max = d["max_mm"].as_f64().unwrap();
        assert!((max - height).abs() < 1e-5, "{max} vs {height}");
        let at: Vec<f64> = d["at"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert!(
            DVec3::from_slice(&at).distance(top) < 1e-5,
            "{at:?} vs {top}"
        );
    }
}

/// Without `--despike` the report has no `despike` key; with it on a ball that has no spike,
/// nothing moves (the report says so) and the parts are those of the run without it, byte for
/// byte.
#[test]
fn despike_moves_nothing_on_a_ball_without_spikes() {
    let (ball, _, _, _) = spiked_ball();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ball.obj");
    std::fs::write(&file, obj_text(&ball, 6)).unwrap();
    // The limits without the cap on the parts.
    let limits = &LIMITS[..6];
    let (plain, with) = (dir.path().join("plain"), dir.path().join("with"));
    std::fs::create_dir(&plain).unwrap();
    std::fs::create_dir(&with).unwrap();
    flatten(&file, &plain, limits).unwrap();
    let mut args = limits.to_vec();
    args.push("--despike");
    flatten(&file, &with, &args).unwrap();
    let report = std::fs::read_to_string(plain.join("flat.json")).unwrap();
    assert!(!report.contains("despike"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(with.join("flat.json")).unwrap()).unwrap();
    let first = json.as_array().map_or(&json, |a| &a[0]);
    assert_eq!(first["despike"]["moved"], 0);
    assert_eq!(first["despike"]["left"], 0);
    let mut k = 1;
    while plain.join(format!("flat-ball-{k}.obj")).exists() {
        let name = format!("flat-ball-{k}.obj");
        assert_eq!(
            std::fs::read(plain.join(&name)).unwrap(),
            std::fs::read(with.join(&name)).unwrap(),
            "{name}"
        );
        k += 1;
    }
    assert!(k > 1);
}
