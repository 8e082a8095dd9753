//! The report against answers known in closed form: identity, uniform scale, shear, a fold, and
//! Duncan's δ0 of the azimuthal equidistant map of a spherical cap (Milnor's optimum,
//! δ0 = log(α / sin α)).

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_report::{
    Column, Measure, Report, ReportOptions, heatmap_svg, html_report, render_png,
};

fn grid(n: usize, size: f64) -> TriMesh {
    flatcut_mesh::test_grid::grid_mesh(n, n, |i, j| {
        DVec3::new(i as f64 * size / n as f64, j as f64 * size / n as f64, 0.0)
    })
}

fn with_map(mut m: TriMesh, f: impl Fn(DVec3) -> DVec2) -> TriMesh {
    m.flat = Some(m.positions.iter().map(|p| f(*p)).collect());
    m
}

#[test]
fn identity_of_a_planar_piece_is_all_zero() {
    let m = with_map(grid(8, 100.0), |p| DVec2::new(p.x, p.y));
    let r = Report::compute("flat", &m, &ReportOptions::default()).unwrap();
    assert_eq!(r.flipped, 0);
    for v in [
        r.delta0,
        r.delta1_max,
        r.delta2_max,
        r.stretch_max_pct,
        r.compress_max_pct,
        r.boundary_length_error,
    ] {
        assert!(v.abs() < 1e-9, "{v}");
    }
    assert!((r.area_mean - 1.0).abs() < 1e-12 && (r.area_3d_mm2 - 10_000.0).abs() < 1e-6);
}

#[test]
fn uniform_scale_is_conformal_with_mu_equal_s_squared() {
    let s = 1.25;
    let m = with_map(grid(6, 50.0), |p| DVec2::new(p.x, p.y) * s);
    let r = Report::compute("scaled", &m, &ReportOptions::default()).unwrap();
    for f in &r.per_face {
        assert!((f.mu1 - s * s).abs() < 1e-12 && (f.mu2 - s * s).abs() < 1e-12);
    }
    assert!(r.delta1_max.abs() < 1e-9);
    let d2 = 0.5 * (2.0 * s * s + 2.0 / (s * s) - 4.0);
    assert!((r.delta2_mean - d2).abs() < 1e-12 && (r.delta2_max - d2).abs() < 1e-12);
    assert!((r.stretch_max_pct - 25.0).abs() < 1e-9);
    assert!((r.area_mean - s * s).abs() < 1e-12);
    // Every pair of points is scaled by s: δ0 = 0.
    assert!(r.delta0.abs() < 1e-9, "{}", r.delta0);
    assert!((r.boundary_length_error - 0.25).abs() < 1e-12);
}

#[test]
fn shear_has_its_singular_values() {
    // x' = x + k y, y' = y: singular values sqrt((2 + k² ± k sqrt(4 + k²)) / 2).
    let k = 0.5f64;
    let m = with_map(grid(5, 40.0), |p| DVec2::new(p.x + k * p.y, p.y));
    let r = Report::compute("shear", &m, &ReportOptions::default()).unwrap();
    let mu1 = (2.0 + k * k + k * (4.0 + k * k).sqrt()) / 2.0;
    let mu2 = (2.0 + k * k - k * (4.0 + k * k).sqrt()) / 2.0;
    assert!((mu1 * mu2 - 1.0).abs() < 1e-12, "a shear keeps area");
    for f in &r.per_face {
        assert!((f.mu1 - mu1).abs() < 1e-12 && (f.mu2 - mu2).abs() < 1e-12);
        assert!((f.delta1 - (mu1 / mu2).ln()).abs() < 1e-12);
        assert!((f.area_ratio - 1.0).abs() < 1e-12);
    }
}

#[test]
fn a_fold_is_counted_as_flipped_never_hidden() {
    // Mirror the right half of the grid over x = 20: those faces fold back.
    let m = with_map(grid(8, 40.0), |p| {
        DVec2::new(if p.x > 20.0 { 40.0 - p.x } else { p.x }, p.y)
    });
    let r = Report::compute("fold", &m, &ReportOptions::default()).unwrap();
    assert_eq!(r.flipped, 64);
    assert!(r.delta2_max.is_infinite() && r.delta0.is_infinite());
    assert!(!r.within_limits());
}

/// A spherical cap of geodesic radius `alpha` on a sphere of radius `radius` mm, in rings.
fn cap(alpha: f64, radius: f64, rings: usize) -> TriMesh {
    let mut p = vec![DVec3::new(0.0, 0.0, radius)];
    let mut polar = vec![(0.0, 0.0)];
    let mut ring_start = vec![0usize];
    for k in 1..=rings {
        ring_start.push(p.len());
        let rho = alpha * k as f64 / rings as f64;
        let count = 6 * k;
        for i in 0..count {
            let th = std::f64::consts::TAU * i as f64 / count as f64;
            p.push(radius * DVec3::new(rho.sin() * th.cos(), rho.sin() * th.sin(), rho.cos()));
            polar.push((rho, th));
        }
    }
    let mut t = Vec::new();
    for k in 1..=rings {
        let (inner_n, outer_n) = (if k == 1 { 1 } else { 6 * (k - 1) }, 6 * k);
        let (a0, b0) = (ring_start[k - 1], ring_start[k]);
        // Walk both rings by angle, emitting triangles (a standard ring zipper).
        // The centre is a single vertex: its ring gets only outer steps.
        let (mut i, mut j) = (usize::from(inner_n == 1), 0usize);
        while i < inner_n || j < outer_n {
            let ai = (a0 + i % inner_n) as u32;
            let bj = (b0 + j % outer_n) as u32;
            let take_outer = if i >= inner_n {
                true
            } else if j >= outer_n {
                false
            } else {
                (j + 1) as f64 / outer_n as f64 <= (i + 1) as f64 / inner_n as f64
            };
            if take_outer {
                t.push([ai, bj, (b0 + (j + 1) % outer_n) as u32]);
                j += 1;
            } else {
                t.push([ai, bj, (a0 + (i + 1) % inner_n) as u32]);
                i += 1;
            }
        }
    }
    let mut m = TriMesh::new(p, t);
    m.flat = Some(
        polar
            .iter()
            .map(|&(rho, th)| DVec2::new(th.cos(), th.sin()) * (radius * rho))
            .collect(),
    );
    m
}

#[test]
fn azimuthal_equidistant_map_of_a_cap_has_milnors_delta0() {
    for alpha in [std::f64::consts::FRAC_PI_4, std::f64::consts::FRAC_PI_3] {
        let m = cap(alpha, 100.0, 40);
        flatcut_mesh::check_disk(&m).expect("the cap is a disk");
        let r = Report::compute("cap", &m, &ReportOptions::default()).unwrap();
        let want = (alpha / alpha.sin()).ln();
        assert_eq!(r.flipped, 0);
        assert!(
            (r.delta0 - want).abs() < 0.03 * want,
            "alpha {alpha}: delta0 {} vs {want}",
            r.delta0
        );
        assert_eq!(
            (r.delta0_method.as_str(), r.delta0_error_bound),
            ("exact", 0.0)
        );
    }
}

#[test]
fn limits_list_the_regions_beyond_them_with_location() {
    // Stretch 10 % in x on the right half only.
    let m = with_map(grid(10, 100.0), |p| {
        DVec2::new(
            if p.x > 50.0 {
                50.0 + (p.x - 50.0) * 1.1
            } else {
                p.x
            },
            p.y,
        )
    });
    let opts = ReportOptions::default().with_limit_stretch_pct(Some(3.0));
    let r = Report::compute("half", &m, &opts).unwrap();
    assert_eq!(r.regions.len(), 1);
    let reg = &r.regions[0];
    assert_eq!(reg.kind, "stretch");
    assert!((reg.worst_pct - 10.0).abs() < 1e-9);
    assert!((reg.area_mm2 - 5000.0).abs() < 1e-6);
    assert!((reg.centroid_3d[0] - 75.0).abs() < 1e-9 && (reg.centroid_3d[1] - 50.0).abs() < 1e-9);
    assert!(!r.within_limits());
    let ok = Report::compute(
        "half",
        &m,
        &ReportOptions::default().with_limit_stretch_pct(Some(12.0)),
    )
    .unwrap();
    assert!(ok.within_limits());
}

#[test]
fn a_region_on_a_curved_piece_is_located_on_its_surface() {
    // A half-cylinder of radius 50 (the grid's x bent round the y axis), unrolled with a stretch
    // that grows along the arc: s' = s + k s². Nearly every face is over 1 %; the region's
    // centroid sits inside the cylinder, far off its surface, while the worst face is the last
    // column at the far end of the arc (θ = π, x = −R).
    let (r, n, k) = (50.0, 20, 0.001);
    let theta = |x: f64| std::f64::consts::PI * x / 100.0;
    let mut m = grid(n, 100.0);
    let arc: Vec<f64> = m.positions.iter().map(|p| r * theta(p.x)).collect();
    let ys: Vec<f64> = m.positions.iter().map(|p| p.y).collect();
    m.flat = Some(
        arc.iter()
            .zip(&ys)
            .map(|(&s, &y)| DVec2::new(s + k * s * s, y))
            .collect(),
    );
    for p in &mut m.positions {
        let t = theta(p.x);
        *p = DVec3::new(r * t.cos(), p.y, r * t.sin());
    }
    let opts = ReportOptions::default().with_limit_stretch_pct(Some(1.0));
    let rep = Report::compute("arc", &m, &opts).unwrap();
    let reg = &rep.regions[0];
    let from_axis = |p: [f64; 3]| p[0].hypot(p[2]);
    assert!(
        from_axis(reg.centroid_3d) < 0.8 * r,
        "{:?}",
        reg.centroid_3d
    );
    // The worst face's centroid is on a chord of the circle: between R cos(Δθ/2) and R.
    let half_step = std::f64::consts::PI / n as f64 / 2.0;
    let d = from_axis(reg.worst_at_3d);
    assert!(d > r * half_step.cos() * 0.999 && d <= r, "{d}");
    assert!(
        reg.worst_at_3d[0] < -r * (2.0 * half_step).cos(),
        "{:?}",
        reg.worst_at_3d
    );
    // In the flat map too: the last column, s from 47.5π to 50π mm before the stretch.
    let s_end = 50.0 * std::f64::consts::PI;
    let last = s_end * (1.0 - 1.0 / n as f64);
    assert!(
        reg.worst_at_2d[0] > last + k * last * last,
        "{:?}",
        reg.worst_at_2d
    );
    assert!(reg.worst_at_2d[0] < s_end + k * s_end * s_end);
}

#[test]
fn hot_spots_show_where_the_distortion_concentrates_without_limits() {
    // x' = x + k x²: the stretch grows to the right; on each column of cells the secant slope
    // is 1 + k (x_i + x_{i+1}), so the last column (x 95..100) is the 1 % worst at 19.5 %.
    let k = 0.001;
    let m = with_map(grid(20, 100.0), |p| DVec2::new(p.x + k * p.x * p.x, p.y));
    let r = Report::compute("graded", &m, &ReportOptions::default()).unwrap();
    assert!(r.regions.is_empty() && r.within_limits(), "no limit asked");
    assert_eq!(r.hot_spots.len(), 1, "{:?}", r.hot_spots);
    let h = &r.hot_spots[0];
    assert_eq!(h.kind, "stretch");
    assert!((h.worst_pct - 19.5).abs() < 1e-9, "{}", h.worst_pct);
    assert!((h.area_mm2 - 500.0).abs() < 1e-9);
    assert!((h.centroid_3d[0] - 97.5).abs() < 1e-9 && (h.centroid_3d[1] - 50.0).abs() < 1e-9);
    let col = Column {
        title: "graded".into(),
        mesh: &m,
        report: &r,
    };
    let html = html_report(&[col], Measure::Stretch, false);
    assert!(
        html.contains("Worst regions") && html.contains("19.50"),
        "HTML lists the hot spot"
    );
    // an isometry has none
    let id = with_map(grid(8, 100.0), |p| DVec2::new(p.x, p.y));
    let r = Report::compute("flat", &id, &ReportOptions::default()).unwrap();
    assert!(r.hot_spots.is_empty());
}

#[test]
fn json_has_the_stable_keys() {
    let m = with_map(grid(4, 10.0), |p| DVec2::new(p.x, p.y));
    let r = Report::compute("k", &m, &ReportOptions::default()).unwrap();
    let v = serde_json::to_value(&r).unwrap();
    for key in [
        "faces",
        "flipped",
        "area_3d_mm2",
        "area_2d_mm2",
        "delta0",
        "delta0_method",
        "delta0_error_bound",
        "delta1_mean",
        "delta1_max",
        "delta1_p90",
        "delta2_mean",
        "delta2_max",
        "delta2_p90",
        "area_mean",
        "stretch_max_pct",
        "compress_max_pct",
        "boundary_length_error",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
}

#[test]
fn per_face_rows_carry_each_face_with_its_centroid_and_measures() {
    // A stretch of 1.5 along x only: μ1 = 2.25, μ2 = 1 on every face, stretch 50 %.
    let m = with_map(grid(3, 30.0), |p| DVec2::new(1.5 * p.x, p.y));
    let r = Report::compute("x", &m, &ReportOptions::default()).unwrap();
    let v = serde_json::to_value(flatcut_report::with_faces(&r, &m)).unwrap();
    assert_eq!(v["faces"], 18, "the report's own keys stay");
    let rows = v["per_face"].as_array().unwrap();
    assert_eq!(rows.len(), 18);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row["face"], k);
        let t = m.triangles[k];
        let c =
            (m.positions[t[0] as usize] + m.positions[t[1] as usize] + m.positions[t[2] as usize])
                / 3.0;
        for (i, x) in c.to_array().iter().enumerate() {
            assert!((row["centroid_3d"][i].as_f64().unwrap() - x).abs() < 1e-12);
        }
        assert!((row["mu1"].as_f64().unwrap() - 2.25).abs() < 1e-12);
        assert!((row["mu2"].as_f64().unwrap() - 1.0).abs() < 1e-12);
        assert!((row["stretch_pct"].as_f64().unwrap() - 50.0).abs() < 1e-9);
        assert!((row["area_3d_mm2"].as_f64().unwrap() - 50.0).abs() < 1e-9);
        assert_eq!(row["flipped"], false);
    }
}

#[test]
fn pictures_are_true_scale_deterministic_and_the_png_shows_the_legend() {
    let a = with_map(grid(10, 100.0), |p| {
        DVec2::new(
            if p.x > 50.0 {
                50.0 + (p.x - 50.0) * 1.1
            } else {
                p.x
            },
            p.y,
        )
    });
    let b = with_map(grid(10, 100.0), |p| DVec2::new(p.x, p.y));
    let ra = Report::compute("a", &a, &ReportOptions::default()).unwrap();
    let rb = Report::compute("b", &b, &ReportOptions::default()).unwrap();
    let cols = [
        Column {
            title: "A".into(),
            mesh: &a,
            report: &ra,
        },
        Column {
            title: "B".into(),
            mesh: &b,
            report: &rb,
        },
    ];
    let svg = heatmap_svg(&cols, Measure::Stretch, true);
    assert_eq!(svg, heatmap_svg(&cols, Measure::Stretch, true));
    assert!(svg.contains("mm\"") && svg.contains("viewBox=\"0 0 "));
    // Two columns of at least the piece width side by side.
    let w: f64 = svg
        .split("viewBox=\"0 0 ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(w >= 2.0 * 105.0, "width {w}");
    let png = render_png(&svg, Some(800)).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // The legend (stroke-font text and colour bar) is drawn: dark pixels below the pieces.
    let html = html_report(&cols, Measure::Stretch, false);
    assert!(
        html.starts_with("<!DOCTYPE html>")
            && html.contains("<svg")
            && !html.contains("src=\"http")
    );
}
