//! Darts as drawn: `flatcut pattern --darts auto` on a spherical cap writes a DXF whose darts,
//! read back with the project's own AAMA reader, are there as the pattern maker expects: each
//! dart is one open sew line (its two legs, of equal length within 0.1 mm as drawn, smooth), its
//! drill mark sits inside the piece the default 5 mm short of the point where the legs meet, and
//! its mouth is trued: folded toward its pressed leg, the cap lands on that side's sew line.

use std::f64::consts::TAU;

use flatcut::geom::DVec2;
use flatcut::pattern::StrokeKind;

use crate::pipeline::run_cli;

/// A spherical cap (sphere radius `r`, geodesic radius `alpha`, `rings` rings of 6k vertices)
/// as OBJ text.
fn cap_obj(r: f64, alpha: f64, rings: usize) -> String {
    let mut out = format!("v 0 0 {r}\n");
    let mut start = vec![1usize];
    for k in 1..=rings {
        start.push(start[k - 1] + if k == 1 { 1 } else { 6 * (k - 1) });
        let rho = alpha * k as f64 / rings as f64;
        for j in 0..6 * k {
            let phi = TAU * j as f64 / (6 * k) as f64;
            out.push_str(&format!(
                "v {} {} {}\n",
                r * rho.sin() * phi.cos(),
                r * rho.sin() * phi.sin(),
                r * rho.cos()
            ));
        }
    }
    // Ring k has 6k vertices; sector s of ring k−1 (k−1 vertices) and of ring k (k vertices).
    for k in 1..=rings {
        let (a0, b0) = (start[k - 1], start[k]);
        let (ma, mb) = (if k == 1 { 1 } else { 6 * (k - 1) }, 6 * k);
        let (mut i, mut j) = (0usize, 0usize);
        while i < ma || j < mb {
            let next = |n: usize, m: usize| (n + 1) as f64 / m as f64;
            let advance_a = ma > 1 && (j == mb || (i < ma && next(i, ma) <= next(j, mb)));
            let ai = a0 + i % ma;
            let bj = b0 + j % mb;
            if advance_a {
                out.push_str(&format!("f {ai} {bj} {}\n", a0 + (i + 1) % ma));
                i += 1;
            } else {
                out.push_str(&format!("f {ai} {bj} {}\n", b0 + (j + 1) % mb));
                j += 1;
                if ma == 1 && j == mb {
                    i = ma;
                }
            }
        }
    }
    out
}

#[test]
fn darts_in_the_dxf_are_sew_legs_meeting_near_a_drill_mark() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("cap.obj");
    std::fs::write(&obj, cap_obj(50.0, 1.0, 12)).unwrap();
    let (svg, dxf) = (dir.path().join("p.svg"), dir.path().join("p.dxf"));
    let code = run_cli(&[
        "pattern",
        obj.to_str().unwrap(),
        "-o",
        svg.to_str().unwrap(),
        "--dxf",
        dxf.to_str().unwrap(),
        "--max-stretch",
        "3",
        "--max-compress",
        "3",
        "--darts",
        "auto",
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let n = darts_read_back(&dxf);
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.contains("<svg"), "an SVG is written");
    eprintln!("{n} darts' drill marks read back from the DXF");
}

#[test]
fn a_flat_obj_keeps_its_darts_for_the_pattern() {
    // `flatten --darts auto` writes each dart's sew line into the OBJ (`g dart-k`, `l`), so the
    // pattern drawn from that file has the darts as the one drawn from the mesh: sew lines of
    // equal legs, drill marks, the mouths bridged by the cut line. Before, the pattern of the
    // flat OBJ took the darts for notches cut into the outline and refused the piece (its seam
    // allowance crossed each dart).
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("cap.obj");
    std::fs::write(&obj, cap_obj(50.0, 1.0, 12)).unwrap();
    let flat = dir.path().join("flat").join("cap.obj");
    std::fs::create_dir_all(flat.parent().unwrap()).unwrap();
    let limits = ["--max-stretch", "3", "--max-compress", "3"];
    let ok = format!("{:?}", std::process::ExitCode::SUCCESS);
    let mut args = vec![
        "flatten",
        obj.to_str().unwrap(),
        "-o",
        flat.to_str().unwrap(),
    ];
    args.extend(limits);
    args.extend(["--darts", "auto"]);
    assert_eq!(format!("{:?}", run_cli(&args)), ok);
    let dxf_of = |input: &std::path::Path, name: &str, darted: bool| {
        let (svg, dxf) = (
            dir.path().join(format!("{name}.svg")),
            dir.path().join(format!("{name}.dxf")),
        );
        let mut args = vec![
            "pattern",
            input.to_str().unwrap(),
            "-o",
            svg.to_str().unwrap(),
            "--dxf",
            dxf.to_str().unwrap(),
        ];
        if darted {
            args.extend(limits);
            args.extend(["--darts", "auto"]);
        }
        assert_eq!(format!("{:?}", run_cli(&args)), ok, "pattern of {name}");
        dxf
    };
    let from_flat = darts_read_back(&dxf_of(&flat, "from_flat", false));
    let from_mesh = darts_read_back(&dxf_of(&obj, "from_mesh", true));
    assert!(from_flat > 0);
    assert_eq!(from_flat, from_mesh);
}

/// Reads the DXF back with the project's AAMA reader and checks its darts: one open sew line per
/// drill mark, each drill mark inside the one piece about 5 mm short of its sew line's point,
/// the two legs within 0.1 mm. Returns how many darts.
fn darts_read_back(dxf: &std::path::Path) -> usize {
    let text = std::fs::read_to_string(dxf).unwrap();
    let d = flatcut::pattern::dxf_read::read_dxf(&text, 0.01)
        .unwrap()
        .drawing;
    let of = |k: StrokeKind| d.strokes.iter().filter(move |s| s.kind == k);
    let drills: Vec<DVec2> = of(StrokeKind::Drill)
        .map(|s| s.points.iter().copied().sum::<DVec2>() / s.points.len() as f64)
        .collect();
    assert!(!drills.is_empty(), "no drill marks read back");
    // A dart's sew line is one open polyline: one leg from the mouth to the point, the other
    // back to the other side of the mouth.
    let darts: Vec<&Vec<DVec2>> = of(StrokeKind::Sew)
        .filter(|s| !s.closed)
        .map(|s| &s.points)
        .collect();
    assert_eq!(darts.len(), drills.len(), "one sew line per drill mark");
    let boundary: Vec<&Vec<DVec2>> = of(StrokeKind::Boundary).map(|s| &s.points).collect();
    assert_eq!(boundary.len(), 1, "one piece");
    let length = |p: &[DVec2]| p.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
    for (i, p) in drills.iter().enumerate() {
        assert!(
            inside(boundary[0], *p),
            "drill {i} at {p} is outside the piece"
        );
        // The sew line whose point (the vertex farthest from its mouth) is nearest this drill.
        let (apex_d, legs) = darts
            .iter()
            .map(|line| {
                let mouth = 0.5 * (line[0] + line[line.len() - 1]);
                let k = (0..line.len())
                    .max_by(|&a, &b| line[a].distance(mouth).total_cmp(&line[b].distance(mouth)))
                    .unwrap();
                (
                    line[k].distance(*p),
                    [length(&line[..=k]), length(&line[k..])],
                )
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        // The drill mark sits the default 5 mm short of the point (along the dart's middle).
        assert!(
            (apex_d - 5.0).abs() < 1.0,
            "drill {i}: {apex_d} mm from the point"
        );
        assert!(
            (legs[0] - legs[1]).abs() < 0.1,
            "dart {i}: legs {legs:?} differ by more than 0.1 mm"
        );
    }
    drills.len()
}

/// Point in polygon (even-odd).
fn inside(poly: &[DVec2], p: DVec2) -> bool {
    let mut c = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            c = !c;
        }
    }
    c
}

#[test]
fn a_hemispheres_darts_have_smooth_legs_and_caps_that_fold_onto_the_pressed_side() {
    // A hemisphere of radius 50 mm at 2k faces, darted to ±3 %.
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("hemisphere.obj");
    std::fs::write(&obj, cap_obj(50.0, std::f64::consts::FRAC_PI_2, 18)).unwrap();
    let (svg, dxf) = (dir.path().join("p.svg"), dir.path().join("p.dxf"));
    let code = run_cli(&[
        "pattern",
        obj.to_str().unwrap(),
        "-o",
        svg.to_str().unwrap(),
        "--dxf",
        dxf.to_str().unwrap(),
        "--max-stretch",
        "3",
        "--max-compress",
        "3",
        "--darts",
        "auto",
    ]);
    assert_eq!(
        format!("{code:?}"),
        format!("{:?}", std::process::ExitCode::SUCCESS)
    );
    let n = darts_read_back(&dxf);
    let text = std::fs::read_to_string(&dxf).unwrap();
    let d = flatcut::pattern::dxf_read::read_dxf(&text, 0.005)
        .unwrap()
        .drawing;
    let sew = d
        .strokes
        .iter()
        .find(|s| s.kind == StrokeKind::Sew && s.closed)
        .map(|s| s.points.clone())
        .unwrap();
    let darts: Vec<&Vec<DVec2>> = d
        .strokes
        .iter()
        .filter(|s| s.kind == StrokeKind::Sew && !s.closed)
        .map(|s| &s.points)
        .collect();
    assert_eq!(darts.len(), n);
    let dist_to = |poly: &[DVec2], q: DVec2, closed: bool| {
        let m = if closed { poly.len() } else { poly.len() - 1 };
        (0..m)
            .map(|i| seg_dist(poly[i], poly[(i + 1) % poly.len()], q))
            .fold(f64::INFINITY, f64::min)
    };
    let mut worst_kink = 0.0f64;
    for (k, line) in darts.iter().enumerate() {
        let (m0, m1) = (line[0], line[line.len() - 1]);
        let mouth = 0.5 * (m0 + m1);
        let a = (0..line.len())
            .max_by(|&x, &y| line[x].distance(mouth).total_cmp(&line[y].distance(mouth)))
            .unwrap();
        let apex = line[a];
        // Legs smooth: no point of a leg stands off the chord of its neighbours by more than a
        // smooth curve flattened within the 0.02 mm chord tolerance does (the legs drawn
        // through the mesh's crossings stood off by up to 0.53 mm here).
        for leg in [&line[..=a], &line[a..]] {
            for w in leg.windows(3) {
                worst_kink = worst_kink.max(seg_dist(w[0], w[2], w[1]));
            }
        }
        // The cap: the sew line between the two mouths (the short way round), sampled.
        let at = |q: DVec2| {
            (0..sew.len())
                .min_by(|&x, &y| sew[x].distance(q).total_cmp(&sew[y].distance(q)))
                .unwrap()
        };
        let (i0, i1) = (at(m0), at(m1));
        let ahead = (i1 + sew.len() - i0) % sew.len();
        let idx: Vec<usize> = if ahead <= sew.len() / 2 {
            (0..=ahead).map(|j| (i0 + j) % sew.len()).collect()
        } else {
            (0..=sew.len() - ahead)
                .map(|j| (i0 + sew.len() - j) % sew.len())
                .collect()
        };
        let cap: Vec<DVec2> = idx
            .windows(2)
            .flat_map(|w| {
                let (a, b) = (sew[w[0]], sew[w[1]]);
                let steps = (a.distance(b) / 0.2).ceil().max(1.0) as usize;
                (0..steps).map(move |j| a.lerp(b, j as f64 / steps as f64))
            })
            .collect();
        let rise = cap.iter().map(|p| seg_dist(m0, m1, *p)).fold(0.0, f64::max);
        // Folded toward one leg, the cap's half next to it lands on that side's sew line
        // (within the fit's tolerance: the sew line is fitted to 0.1 mm).
        let folds = [m0, m1].map(|ms| {
            let u = (ms - apex).normalize();
            let other = if ms == m0 { m1 } else { m0 };
            cap.iter()
                .filter(|p| p.distance(ms) < p.distance(other))
                .map(|p| {
                    let r = apex + 2.0 * (*p - apex).dot(u) * u - (*p - apex);
                    dist_to(&sew, r, true)
                })
                .fold(0.0, f64::max)
        });
        let fold = folds[0].min(folds[1]);
        eprintln!(
            "dart {k}: mouth {:.2} mm, cap rises {rise:.3} mm, folded {fold:.3} mm off the pressed side",
            m0.distance(m1)
        );
        assert!(
            fold < 0.12,
            "dart {k}: folded, the cap is {fold} mm off the pressed side"
        );
    }
    eprintln!("{n} darts; legs stand off their neighbours' chords by at most {worst_kink:.4} mm");
    assert!(worst_kink < 0.1, "{worst_kink}");
}

/// Distance from `q` to the segment `a`–`b`.
fn seg_dist(a: DVec2, b: DVec2, q: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t).distance(q)
}
