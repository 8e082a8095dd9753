//! δ0 on pieces that are not convex, against answers known in closed form: exact unrollings of an
//! L-shaped cut of a cylinder and of a cone sector wider than 180° (δ0 = 0), a stretched L
//! (δ0 = ln a), and the theorem behind the exact figure checked pair by pair with geodesic
//! distances on the surface and inside the flat piece.

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{TriMesh, test_grid};
use flatcut_report::{Report, ReportOptions};

/// A deterministic offset in [−0.5, 0.5) for vertex (i, j), so the triangles are irregular.
fn jitter(i: usize, j: usize) -> f64 {
    ((i * 7 + j * 13) % 11) as f64 / 11.0 - 0.5
}

/// Quads between consecutive rulings `i` and `i + 1` at heights `j`, `j + 1`, for the cells that
/// `keep` keeps; diagonals alternate so the triangles are not all alike.
fn quads(nu: usize, nv: usize, keep: impl Fn(usize, usize) -> bool) -> Vec<[u32; 3]> {
    test_grid::grid_triangles(nu, nv, test_grid::Diagonal::Alternating, keep)
}

/// Drops the vertices no triangle uses (the L's missing corner), renumbering the rest.
fn compact(mut m: TriMesh) -> TriMesh {
    let mut new = vec![u32::MAX; m.positions.len()];
    let mut next = 0u32;
    for t in &mut m.triangles {
        for v in t.iter_mut() {
            if new[*v as usize] == u32::MAX {
                new[*v as usize] = next;
                next += 1;
            }
            *v = new[*v as usize];
        }
    }
    let mut pos = vec![DVec3::ZERO; next as usize];
    let mut flat = vec![DVec2::ZERO; next as usize];
    for (old, &n) in new.iter().enumerate() {
        if n != u32::MAX {
            pos[n as usize] = m.positions[old];
            if let Some(f) = &m.flat {
                flat[n as usize] = f[old];
            }
        }
    }
    m.flat = m.flat.is_some().then_some(flat);
    m.positions = pos;
    m
}

/// An L-shaped cut of a cylinder of radius `r` (300° of arc, 120 mm high, the quarter of larger
/// arc and height cut away) with its exact unrolling. The vertices lie on rulings, so every quad
/// between two rulings is a plane rectangle of the chord's width: the polyhedral surface is
/// developable exactly and the unrolling is an isometry of it.
fn cylinder_l(r: f64, nu: usize, nv: usize) -> TriMesh {
    let span = 300f64.to_radians();
    let dphi = span / nu as f64;
    let chord = 2.0 * r * (dphi / 2.0).sin();
    let mut p = Vec::new();
    let mut f = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            // Heights vary along each ruling (not across it): the quads stay plane.
            let z =
                120.0 * (j as f64 + 0.3 * jitter(0, j) * f64::from(j > 0 && j < nv)) / nv as f64;
            let phi = i as f64 * dphi;
            p.push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
            f.push(DVec2::new(i as f64 * chord, z));
        }
    }
    let mut m = TriMesh::new(p, quads(nu, nv, |i, j| i < nu / 2 || j < nv / 2));
    m.flat = Some(f);
    compact(m)
}

/// A cone sector (half-angle `beta`, slant 20..100 mm from the apex) around `span` of the axis,
/// with its exact unrolling: triangles between consecutive rulings lie in the plane of the two
/// rulings, so the unrolling lays each such strip flat at the angle between its rulings. The
/// slant positions vary from ruling to ruling (irregular triangles, still between two rulings).
fn cone_sector(beta: f64, span: f64, nu: usize, nv: usize) -> (TriMesh, f64) {
    let dir = |phi: f64| DVec3::new(beta.sin() * phi.cos(), beta.sin() * phi.sin(), beta.cos());
    let mut p = Vec::new();
    let mut f = Vec::new();
    let mut psi = vec![0.0];
    for i in 0..nu {
        let (a, b) = (
            dir(span * i as f64 / nu as f64),
            dir(span * (i + 1) as f64 / nu as f64),
        );
        psi.push(psi[i] + a.angle_between(b));
    }
    for j in 0..=nv {
        for (i, &ps) in psi.iter().enumerate() {
            let inner = j > 0 && j < nv;
            let s = 20.0 + 80.0 * (j as f64 + 0.4 * jitter(i, j) * f64::from(inner)) / nv as f64;
            p.push(dir(span * i as f64 / nu as f64) * s);
            f.push(DVec2::new(ps.cos(), ps.sin()) * s);
        }
    }
    // Angle along the rows and slant up the columns turn clockwise in the plane: the triangles
    // are reversed to be counter-clockwise there.
    let tris = quads(nu, nv, |_, _| true)
        .into_iter()
        .map(|[a, b, c]| [a, c, b]);
    let mut m = TriMesh::new(p, tris.collect());
    m.flat = Some(f);
    let developed = psi[nu];
    (m, developed)
}

/// A plane L (100 × 100 mm less the 50 × 50 mm top-right quarter) in z = 0, mapped by `map`.
fn plane_l(n: usize, map: impl Fn(DVec2) -> DVec2) -> TriMesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push(DVec3::new(
                100.0 * i as f64 / n as f64,
                100.0 * j as f64 / n as f64,
                0.0,
            ));
        }
    }
    let mut m = TriMesh::new(p, quads(n, n, |i, j| i < n / 2 || j < n / 2));
    m.flat = Some(m.positions.iter().map(|q| map(q.truncate())).collect());
    compact(m)
}

/// The flat piece as a surface of its own: its 2D positions at z = 0, the same triangles.
fn flat_surface(m: &TriMesh) -> TriMesh {
    let f = m.flat.as_ref().expect("a flattened mesh");
    TriMesh::new(
        f.iter().map(|q| q.extend(0.0)).collect(),
        m.triangles.clone(),
    )
}

/// The least and greatest ratio of intrinsic distance in the flat piece to geodesic distance on
/// the surface over the pairs (source, any vertex) of a few sources, both by the mesh crate's
/// geodesic distances; also the least ratio of the straight distance in the plane to the
/// surface's (Duncan's d_E, which a piece that is not convex makes smaller).
fn sampled_ratios(m: &TriMesh, sources: &[u32]) -> (f64, f64, f64) {
    let flat = flat_surface(m);
    let uv = m.flat.as_ref().unwrap();
    let (mut lo, mut hi, mut straight) = (f64::INFINITY, 0.0f64, f64::INFINITY);
    for &s in sources {
        let ds = flatcut_mesh::geodesic::distances_from(m, s);
        let df = flatcut_mesh::geodesic::distances_from(&flat, s);
        for v in 0..m.positions.len() {
            if ds[v] > 1.0 {
                lo = lo.min(df[v] / ds[v]);
                hi = hi.max(df[v] / ds[v]);
                straight = straight.min(uv[v].distance(uv[s as usize]) / ds[v]);
            }
        }
    }
    (lo, hi, straight)
}

fn report(m: &TriMesh) -> Report {
    flatcut_mesh::check_disk(m).expect("a disk");
    Report::compute("piece", m, &ReportOptions::default()).unwrap()
}

#[test]
fn the_exact_unrolling_of_an_l_cut_from_a_cylinder_has_no_global_distortion() {
    let m = cylinder_l(60.0, 60, 24);
    let r = report(&m);
    assert_eq!(r.flipped, 0);
    assert!(r.delta0.abs() < 1e-9, "δ0 {}", r.delta0);
    assert!(r.delta2_max < 1e-9, "δ2 max {}", r.delta2_max);
    assert_eq!(
        (r.delta0_method.as_str(), r.delta0_error_bound),
        ("exact", 0.0)
    );
    // Intrinsic distances agree pair by pair; the straight line across the L's notch is far
    // shorter than the surface's geodesic (what made the plane's d_E call this map distorted).
    let corner = m
        .positions
        .iter()
        .position(|p| p.z > 119.0 && p.y.abs() < 1e-9 && p.x > 0.0)
        .unwrap() as u32;
    let far = m
        .positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.z < 1e-9)
        .max_by(|a, b| {
            a.1.y
                .atan2(a.1.x)
                .rem_euclid(std::f64::consts::TAU)
                .total_cmp(&b.1.y.atan2(b.1.x).rem_euclid(std::f64::consts::TAU))
        })
        .unwrap()
        .0 as u32;
    let (lo, hi, straight) = sampled_ratios(&m, &[corner, far]);
    assert!(
        (lo - 1.0).abs() < 1e-9 && (hi - 1.0).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert!(straight < 0.9, "straight over geodesic {straight}");
}

#[test]
fn the_exact_unrolling_of_a_cone_sector_over_180_degrees_has_no_global_distortion() {
    // Half-angle 50°, 300° around the axis: the unrolled sector spans 230° (not convex).
    let (m, developed) = cone_sector(50f64.to_radians(), 300f64.to_radians(), 90, 16);
    assert!(developed > std::f64::consts::PI * 1.2, "{developed}");
    let r = report(&m);
    assert_eq!(r.flipped, 0);
    assert!(r.delta0.abs() < 1e-9, "δ0 {}", r.delta0);
    assert!(r.delta2_max < 1e-9, "δ2 max {}", r.delta2_max);
    // The two ends of the outer rim: the straight line between them crosses the sector's gap.
    let nu = 90;
    let rim = |i: usize| (16 * (nu + 1) + i) as u32;
    let (lo, hi, straight) = sampled_ratios(&m, &[rim(0), rim(nu), 0]);
    assert!(
        (lo - 1.0).abs() < 1e-9 && (hi - 1.0).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert!(straight < 0.7, "straight over geodesic {straight}");
}

#[test]
fn a_stretched_l_has_the_log_of_its_stretch() {
    // x' = a x on a plane L: every face has σ1 = a, σ2 = 1, so δ0 = ln a exactly, although the
    // straight distance across the notch is shorter than the path inside the L.
    let a = 1.3;
    let m = plane_l(20, |q| DVec2::new(a * q.x, q.y));
    let r = report(&m);
    assert!(
        (r.delta0 - a.ln()).abs() < 1e-12,
        "δ0 {} vs {}",
        r.delta0,
        a.ln()
    );
    assert!((r.delta0_s1 - 1.0).abs() < 1e-12 && (r.delta0_s2 - a).abs() < 1e-12);
    // Pair by pair (geodesics inside the L, which bend around its inner corner): every ratio
    // lies between s1 and s2, and the extremes are met (pairs along x and along y).
    let far = (m.positions.len() - 1) as u32;
    let (lo, hi, _) = sampled_ratios(&m, &[0, far, 10]);
    assert!(lo > 1.0 - 1e-9 && hi < a + 1e-9, "{lo} {hi}");
    assert!(
        (lo - 1.0).abs() < 1e-9 && (hi - a).abs() < 1e-9,
        "{lo} {hi}"
    );
}

#[test]
fn on_a_curved_map_every_pair_lies_within_the_faces_extremes() {
    // The cylinder L unrolled, then sheared and stretched: not an isometry, not convex.
    let mut m = cylinder_l(60.0, 40, 16);
    for q in m.flat.as_mut().unwrap() {
        *q = DVec2::new(1.1 * q.x + 0.2 * q.y, 0.95 * q.y);
    }
    let r = report(&m);
    let (lo, hi, _) = sampled_ratios(&m, &[0, 7, 200, (m.positions.len() - 1) as u32]);
    // The geodesic distances are upper bounds exact to ~1e-3 here; the faces' extremes bound
    // every pair of points, and a linear map's extremes are met by pairs along its axes.
    assert!(
        lo > r.delta0_s1 * (1.0 - 2e-3),
        "{lo} vs s1 {}",
        r.delta0_s1
    );
    assert!(
        hi < r.delta0_s2 * (1.0 + 2e-3),
        "{hi} vs s2 {}",
        r.delta0_s2
    );
    assert!(hi / lo > (r.delta0_s2 / r.delta0_s1).powf(0.8), "{lo} {hi}");
}
