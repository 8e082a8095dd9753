//! The nonlinear flip-free methods against analytic truth: developable patches flatten with
//! zero isometric distortion, a spherical cap beats the conformal (stereographic) map in δ2,
//! no method ever returns an inverted triangle, boundary-isometric keeps boundary lengths, and
//! reruns are bit-identical.

use flatcut_flatten::{FlattenParams, Method, flatten};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{TriMesh, face_distortion, test_grid};

/// Grid over [0,1]² with `nu`×`nv` cells, mapped by `f`, alternate diagonals.
fn grid(nu: usize, nv: usize, f: impl Fn(f64, f64) -> DVec3) -> TriMesh {
    test_grid::grid_mesh_split(nu, nv, test_grid::Diagonal::Alternating, |i, j| {
        f(i as f64 / nu as f64, j as f64 / nv as f64)
    })
}

/// Cylinder patch, radius 30 mm, 200° of arc, height 50 mm.
fn cylinder() -> TriMesh {
    grid(24, 12, |u, v| {
        let th = u * 200f64.to_radians();
        DVec3::new(30.0 * th.cos(), 30.0 * th.sin(), 50.0 * v)
    })
}

/// Cone patch: half-angle 30°, slant 20..60 mm, 240° around the axis.
fn cone() -> TriMesh {
    let beta = 30f64.to_radians();
    grid(24, 10, |u, v| {
        let th = u * 240f64.to_radians();
        let s = 20.0 + 40.0 * v;
        DVec3::new(
            s * beta.sin() * th.cos(),
            s * beta.sin() * th.sin(),
            s * beta.cos(),
        )
    })
}

/// Spherical cap of radius `r` mm and geodesic radius `alpha`: an `n`×`n` grid of the square
/// mapped onto the unit disk (elliptical square-to-disk map), then by geodesic polar
/// coordinates (ρ = α·|p|) onto the sphere; the cap's centre is the pole (0, 0, r).
fn cap(r: f64, alpha: f64, n: usize) -> TriMesh {
    grid(n, n, |u, v| {
        let (x, y) = (2.0 * u - 1.0, 2.0 * v - 1.0);
        let (dx, dy) = (
            x * (1.0 - 0.5 * y * y).sqrt(),
            y * (1.0 - 0.5 * x * x).sqrt(),
        );
        let rho = alpha * (dx * dx + dy * dy).sqrt();
        let th = dy.atan2(dx);
        DVec3::new(
            r * rho.sin() * th.cos(),
            r * rho.sin() * th.sin(),
            r * rho.cos(),
        )
    })
}

fn mean_delta2(mesh: &TriMesh, uv: &[DVec2]) -> f64 {
    let mut s = 0.0;
    let mut a = 0.0;
    for t in 0..mesh.triangles.len() {
        let tri = mesh.triangles[t];
        let d = face_distortion(mesh.corners(t), tri.map(|v| uv[v as usize])).unwrap();
        let at = mesh.triangle_area(t);
        s += at * d.delta2();
        a += at;
    }
    s / a
}

fn assert_flip_free(mesh: &TriMesh, uv: &[DVec2]) {
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let d = face_distortion(mesh.corners(t), tri.map(|v| uv[v as usize])).unwrap();
        assert!(d.det > 0.0, "triangle {t} flipped (det {})", d.det);
    }
}

#[test]
fn isometric_flattens_developables_exactly() {
    for (name, mesh) in [("cylinder", cylinder()), ("cone", cone())] {
        let f = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
        let d2 = mean_delta2(&mesh, &f.uv);
        assert!(d2 < 1e-8, "{name}: mean δ2 = {d2:e}");
        assert_flip_free(&mesh, &f.uv);
        // True scale: the flat area is the 3D area.
        let fl = TriMesh {
            flat: Some(f.uv.clone()),
            ..mesh.clone()
        };
        let ratio = fl.flat_area().unwrap() / mesh.area();
        assert!((ratio - 1.0).abs() < 1e-6, "{name}: area ratio {ratio}");
    }
}

/// Stereographic projection of a cap centred on the +z pole of a sphere of radius `r`, scaled
/// to the 3D area (the exactly conformal map of the smooth cap).
fn stereographic(mesh: &TriMesh, r: f64) -> Vec<DVec2> {
    let mut uv: Vec<DVec2> = mesh
        .positions
        .iter()
        .map(|p| DVec2::new(p.x, p.y) * (2.0 / (1.0 + p.z / r)))
        .collect();
    let fl = TriMesh {
        flat: Some(uv.clone()),
        ..mesh.clone()
    };
    let k = (mesh.area() / fl.flat_area().unwrap()).sqrt();
    uv.iter_mut().for_each(|p| *p *= k);
    uv
}

#[test]
fn isometric_beats_stereographic_on_a_cap_and_nothing_flips() {
    let r = 100.0;
    let mesh = cap(r, std::f64::consts::FRAC_PI_4, 24);
    let st = mean_delta2(&mesh, &stereographic(&mesh, r));
    let iso = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
    let d_iso = mean_delta2(&mesh, &iso.uv);
    assert!(
        d_iso < 0.9 * st,
        "isometric δ2 {d_iso} vs stereographic {st}"
    );
    assert_flip_free(&mesh, &iso.uv);
    for m in [Method::Conformal, Method::BoundaryIsometric] {
        let f = flatten(&mesh, &FlattenParams::new(m)).unwrap();
        assert_flip_free(&mesh, &f.uv);
        assert!(f.uv.iter().all(|p| p.is_finite()));
    }
}

#[test]
fn conformal_is_more_conformal_than_isometric() {
    let mesh = cap(50.0, 1.0, 16);
    let mean_delta1 = |uv: &[DVec2]| {
        let mut s = 0.0;
        for t in 0..mesh.triangles.len() {
            let d = face_distortion(mesh.corners(t), mesh.triangles[t].map(|v| uv[v as usize]))
                .unwrap();
            s += mesh.triangle_area(t) * d.delta1();
        }
        s / mesh.area()
    };
    let c = flatten(&mesh, &FlattenParams::new(Method::Conformal)).unwrap();
    let i = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
    let (dc, di) = (mean_delta1(&c.uv), mean_delta1(&i.uv));
    assert!(dc < 0.5 * di, "conformal δ1 {dc} vs isometric {di}");
    // True area after the scale fix.
    let fl = TriMesh {
        flat: Some(c.uv.clone()),
        ..mesh.clone()
    };
    assert!((fl.flat_area().unwrap() / mesh.area() - 1.0).abs() < 1e-9);
}

fn boundary_rel_errors(mesh: &TriMesh, uv: &[DVec2]) -> f64 {
    let topo = flatcut_mesh::check_disk(mesh).unwrap();
    let lp = &topo.boundary_loops[0];
    let mut worst: f64 = 0.0;
    for i in 0..lp.len() {
        let (a, b) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
        let l3 = (mesh.positions[b] - mesh.positions[a]).length();
        let l2 = (uv[b] - uv[a]).length();
        worst = worst.max((l2 - l3).abs() / l3);
    }
    worst
}

#[test]
fn boundary_isometric_keeps_boundary_lengths() {
    let mesh = cylinder();
    let f = flatten(&mesh, &FlattenParams::new(Method::BoundaryIsometric)).unwrap();
    let e = boundary_rel_errors(&mesh, &f.uv);
    assert!(e <= 1e-9, "developable: boundary error {e:e}");
    assert_flip_free(&mesh, &f.uv);
    // Doubly curved: kept within the reported tolerance, or a warning says where not.
    let mesh = cap(40.0, 0.8, 12);
    let f = flatten(&mesh, &FlattenParams::new(Method::BoundaryIsometric)).unwrap();
    let e = boundary_rel_errors(&mesh, &f.uv);
    assert_flip_free(&mesh, &f.uv);
    assert!(
        e <= 1e-6 || !f.info.warnings.is_empty(),
        "cap: boundary error {e:e} without a warning"
    );
    let iso = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
    assert!(
        boundary_rel_errors(&mesh, &iso.uv) > e,
        "f1 must beat δ2 on the boundary"
    );
}

#[test]
fn reruns_are_bit_identical() {
    let mesh = cap(30.0, 1.2, 10);
    for m in [
        Method::Isometric,
        Method::Conformal,
        Method::BoundaryIsometric,
    ] {
        let a = flatten(&mesh, &FlattenParams::new(m)).unwrap();
        let b = flatten(&mesh, &FlattenParams::new(m)).unwrap();
        let bits = |f: &flatcut_flatten::Flattening| -> Vec<u64> {
            f.uv.iter()
                .flat_map(|p| [p.x.to_bits(), p.y.to_bits()])
                .collect()
        };
        assert_eq!(bits(&a), bits(&b), "{m}");
    }
}

#[test]
fn long_thin_strip_converges_flip_free() {
    // 400 mm × 4 mm strip bent on a cylinder: Tutte squeezes it onto a circle (extreme start).
    let mesh = grid(100, 1, |u, v| {
        let th = u * 2.0;
        DVec3::new(200.0 * th.cos(), 200.0 * th.sin(), 4.0 * v)
    });
    let f = flatten(&mesh, &FlattenParams::new(Method::Isometric)).unwrap();
    assert_flip_free(&mesh, &f.uv);
    let d2 = mean_delta2(&mesh, &f.uv);
    assert!(d2 < 1e-8, "strip δ2 {d2:e}");
}

#[test]
fn material_limits_are_honoured_or_reported() {
    let mesh = cap(50.0, 1.0, 12);
    let p = FlattenParams::new(Method::Isometric)
        .with_max_compress_pct(Some(0.0))
        .with_max_stretch_pct(Some(1.0));
    let f = flatten(&mesh, &p).unwrap();
    assert_flip_free(&mesh, &f.uv);
    // A cap cannot be flattened without compression or stretch above 1 %: expect a report.
    assert!(!f.info.warnings.is_empty());
    // Loose limits: nothing to report.
    let p = FlattenParams::new(Method::Isometric).with_max_stretch_pct(Some(50.0));
    let f = flatten(&mesh, &p).unwrap();
    assert!(f.info.warnings.is_empty(), "{:?}", f.info.warnings);
}
