//! Tests of the linear flattening methods (lscm, conformal-boundary, arap, developable) against
//! analytic truth on surfaces built in code.

use flatcut_flatten::{FlattenError, FlattenParams, Flattening, Method, Pin, flatten, testmesh};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{TopologyError, TriMesh, face_distortion};

/// Area-weighted means of log(σ1/σ2), δ2 and the number of flipped triangles.
struct Score {
    conf: f64,
    delta2_mean: f64,
    delta2_integral: f64,
    flips: usize,
}

fn score(mesh: &TriMesh, uv: &[DVec2]) -> Score {
    let (mut conf, mut d2, mut area, mut flips) = (0.0, 0.0, 0.0, 0);
    for t in 0..mesh.triangles.len() {
        let tri = mesh.triangles[t];
        let d = face_distortion(mesh.corners(t), tri.map(|v| uv[v as usize])).unwrap();
        let a = mesh.triangle_area(t);
        if d.flipped() {
            flips += 1;
        }
        conf += a * (d.sigma1 / d.sigma2).ln();
        d2 += a * d.delta2();
        area += a;
    }
    Score {
        conf: conf / area,
        delta2_mean: d2 / area,
        delta2_integral: d2,
        flips,
    }
}

/// Largest relative edge-length error of the map.
fn max_rel_edge_error(mesh: &TriMesh, uv: &[DVec2]) -> f64 {
    let mut e: f64 = 0.0;
    for tri in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            let l3 = (mesh.positions[a] - mesh.positions[b]).length();
            let l2 = (uv[a] - uv[b]).length();
            e = e.max((l2 - l3).abs() / l3);
        }
    }
    e
}

/// Largest distance between `uv` and `flat` after the best rigid motion (2D Kabsch).
fn rigid_residual(uv: &[DVec2], flat: &[DVec2]) -> f64 {
    let n = uv.len() as f64;
    let cu = uv.iter().copied().sum::<DVec2>() / n;
    let cf = flat.iter().copied().sum::<DVec2>() / n;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (p, q) in flat.iter().zip(uv) {
        let (a, b) = (*p - cf, *q - cu);
        sxx += a.dot(b);
        sxy += a.perp_dot(b);
    }
    let th = sxy.atan2(sxx);
    let r = DVec2::from_angle(th);
    flat.iter()
        .zip(uv)
        .map(|(p, q)| (r.rotate(*p - cf) + cu - *q).length())
        .fold(0.0, f64::max)
}

fn run(mesh: &TriMesh, m: Method) -> Flattening {
    flatten(mesh, &FlattenParams::new(m)).unwrap_or_else(|e| panic!("{m}: {e}"))
}

#[test]
fn lscm_reproduces_a_plane_at_scale() {
    let (mesh, flat) = testmesh::jittered_plane(60.0, 12);
    let f = run(&mesh, Method::Lscm);
    assert!(rigid_residual(&f.uv, &flat) < 1e-9 * 60.0);
    assert!(f.info.final_energy < 1e-20);
}

#[test]
fn lscm_says_where_its_time_went() {
    // One ordering, one numeric factorisation, one solve: the parts `flatten --timings` prints.
    let mesh = testmesh::spherical_cap(30.0, 1.0, 24);
    let t = run(&mesh, Method::Lscm).info.timings;
    assert_eq!(t.factorisations, 1, "{t}");
    assert!(t.ordering > std::time::Duration::ZERO, "{t}");
    assert!(t.factorisation > std::time::Duration::ZERO, "{t}");
    assert!(t.solve > std::time::Duration::ZERO, "{t}");
    assert!(t.assembly > std::time::Duration::ZERO, "{t}");
    assert_eq!(t.line_search, std::time::Duration::ZERO, "{t}");
}

#[test]
fn lscm_on_a_cap_matches_the_stereographic_floor() {
    // Sphere radius 100 mm, geodesic radius 1.0 rad.
    let r = 100.0;
    let mesh = testmesh::spherical_cap(r, 1.0, 16);
    let f = run(&mesh, Method::Lscm);
    let s = score(&mesh, &f.uv);
    assert_eq!(s.flips, 0);
    // The stereographic projection from the antipode is exactly conformal on the sphere; on
    // the chord triangles it is the discrete floor LSCM must reach (its own energy is lower).
    let stereo: Vec<DVec2> = mesh
        .positions
        .iter()
        .map(|p| DVec2::new(p.x, p.y) * (2.0 * r / (r + p.z)))
        .collect();
    let s0 = score(&mesh, &stereo);
    assert!(s0.conf > 1e-3, "floor {}", s0.conf);
    assert!(
        s.conf <= 1.02 * s0.conf,
        "lscm {} vs stereographic {}",
        s.conf,
        s0.conf
    );
    // True scale: same total area as the surface.
    let a2: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            0.5 * (f.uv[t[1] as usize] - f.uv[t[0] as usize])
                .perp_dot(f.uv[t[2] as usize] - f.uv[t[0] as usize])
        })
        .sum();
    assert!((a2 / mesh.area() - 1.0).abs() < 1e-12);
}

#[test]
fn lscm_is_exact_on_developable_patches() {
    for mesh in [
        testmesh::cylinder_patch(40.0, 2.5, 70.0, 20, 8),
        testmesh::cone_patch(0.6, 30.0, 90.0, 2.0, 16, 8),
    ] {
        let f = run(&mesh, Method::Lscm);
        let s = score(&mesh, &f.uv);
        assert!(
            s.conf < 1e-9 && s.delta2_mean < 1e-12,
            "{} {}",
            s.conf,
            s.delta2_mean
        );
        assert!(max_rel_edge_error(&mesh, &f.uv) < 1e-8);
    }
}

#[test]
fn lscm_honours_pins() {
    let mesh = testmesh::saddle(80.0, 10);
    let pins = vec![
        Pin {
            vertex: 0,
            position: DVec2::new(5.0, 5.0),
        },
        Pin {
            vertex: 10,
            position: DVec2::new(90.0, 5.0),
        },
        Pin {
            vertex: 120,
            position: DVec2::new(90.0, 90.0),
        },
    ];
    let f = flatten(
        &mesh,
        &FlattenParams::new(Method::Lscm).with_pins(pins.clone()),
    )
    .unwrap();
    for p in &pins {
        assert_eq!(f.uv[p.vertex as usize], p.position);
    }
    // One pin: the free map, translated onto it.
    let f1 = flatten(
        &mesh,
        &FlattenParams::new(Method::Lscm).with_pins(pins[..1].to_vec()),
    )
    .unwrap();
    let f0 = run(&mesh, Method::Lscm);
    assert!((f1.uv[0] - pins[0].position).length() < 1e-12);
    let d = f1.uv[0] - f0.uv[0];
    assert!(
        f1.uv
            .iter()
            .zip(&f0.uv)
            .all(|(a, b)| (*a - *b - d).length() < 1e-9)
    );
}

#[test]
fn bad_pins_are_refused() {
    let mesh = testmesh::saddle(80.0, 4);
    let p = |vertex, x: f64| Pin {
        vertex,
        position: DVec2::new(x, 0.0),
    };
    for (pins, index) in [
        (vec![p(0, 0.0), p(999, 1.0)], 1),
        (vec![p(0, 0.0), p(0, 1.0)], 1),
        (vec![p(0, 0.0), p(3, 0.0)], 1),
        (vec![p(0, f64::NAN)], 0),
    ] {
        let e = flatten(&mesh, &FlattenParams::new(Method::Lscm).with_pins(pins)).unwrap_err();
        assert!(
            matches!(e, FlattenError::BadPin { index: i, .. } if i == index),
            "{e}"
        );
    }
}

#[test]
fn bad_input_gives_the_right_topology_error() {
    let cap = testmesh::spherical_cap(50.0, 1.0, 4);
    // Closed: glue a second cap mirrored onto the first's boundary (a sphere-like closed mesh).
    let closed = {
        let mut m = cap.clone();
        let n = m.positions.len() as u32;
        let ring = 6 * 4;
        let first_ring = n - ring;
        m.positions.push(DVec3::new(0.0, 0.0, -50.0));
        for j in 0..ring {
            m.triangles
                .push([n, first_ring + (j + 1) % ring, first_ring + j]);
        }
        m
    };
    let two = {
        let mut m = cap.clone();
        let n = m.positions.len() as u32;
        m.positions.extend(
            cap.positions
                .iter()
                .map(|p| *p + DVec3::new(500.0, 0.0, 0.0)),
        );
        m.triangles
            .extend(cap.triangles.iter().map(|t| t.map(|v| v + n)));
        m
    };
    let mut nan = cap.clone();
    nan.positions[3].y = f64::NAN;
    let mut nonmanifold = cap.clone();
    let k = nonmanifold.positions.len() as u32;
    nonmanifold.positions.push(DVec3::new(0.0, 0.0, 200.0));
    let t0 = nonmanifold.triangles[0];
    nonmanifold.triangles.push([t0[0], t0[1], k]);
    for m in Method::ALL {
        let p = FlattenParams::new(m);
        assert!(matches!(
            flatten(&closed, &p),
            Err(FlattenError::Topology(TopologyError::NoBoundary))
        ));
        assert!(matches!(
            flatten(&two, &p),
            Err(FlattenError::Topology(TopologyError::SeveralComponents {
                count: 2
            }))
        ));
        assert!(matches!(
            flatten(&nan, &p),
            Err(FlattenError::Topology(TopologyError::NonFinite {
                vertex: 3
            }))
        ));
        assert!(matches!(
            flatten(&nonmanifold, &p),
            Err(FlattenError::Topology(
                TopologyError::NonManifoldEdge { .. }
                    | TopologyError::InconsistentOrientation { .. }
            ))
        ));
    }
}

#[test]
fn linear_methods_are_deterministic() {
    let mesh = testmesh::spherical_cap(80.0, 1.2, 10);
    for m in [Method::Lscm, Method::ConformalBoundary, Method::Arap] {
        let a = run(&mesh, m);
        let b = run(&mesh, m);
        assert!(
            a.uv.iter()
                .zip(&b.uv)
                .all(|(p, q)| p.x.to_bits() == q.x.to_bits() && p.y.to_bits() == q.y.to_bits())
        );
    }
}

#[test]
fn developable_unfolds_cylinders_and_cones_exactly() {
    for (mesh, chords) in [
        (
            testmesh::cylinder_patch(40.0, 2.5, 70.0, 40, 12),
            Some(40usize),
        ),
        (testmesh::cone_patch(0.6, 30.0, 90.0, 2.0, 30, 10), None),
    ] {
        let f = run(&mesh, Method::Developable);
        let s = score(&mesh, &f.uv);
        assert_eq!(s.flips, 0);
        assert!(s.delta2_mean < 1e-8, "{}", s.delta2_mean);
        let e = max_rel_edge_error(&mesh, &f.uv);
        assert!(e <= 1e-9, "{e}");
        if let Some(nu) = chords {
            // The cylinder patch's rulings stay parallel and its bottom chords collinear: the
            // bottom corners (vertices 0 and nu) end up the sum of the chord lengths apart.
            let expected = nu as f64 * 2.0 * 40.0 * (2.5 / (2.0 * nu as f64)).sin();
            let d = (f.uv[nu] - f.uv[0]).length();
            assert!((d / expected - 1.0).abs() < 1e-12, "{d} vs {expected}");
        }
    }
}

#[test]
fn developable_refuses_a_cap_and_names_the_vertex() {
    let mesh = testmesh::spherical_cap(100.0, 1.0, 6);
    match flatten(&mesh, &FlattenParams::new(Method::Developable)) {
        Err(FlattenError::NotDevelopable {
            max_abs_k,
            angle_defect,
            vertex,
            ..
        }) => {
            // K = 1/R² = 1e-4 /mm² on the sphere; the discrete estimate is within 20 %.
            assert!((max_abs_k / 1e-4 - 1.0).abs() < 0.2, "{max_abs_k}");
            assert!(angle_defect > 0.0);
            assert!((vertex as usize) < mesh.positions.len());
        }
        other => panic!("expected NotDevelopable, got {other:?}"),
    }
}

#[test]
fn developable_reproduces_a_plane() {
    let (mesh, flat) = testmesh::jittered_plane(60.0, 12);
    let f = run(&mesh, Method::Developable);
    assert!(rigid_residual(&f.uv, &flat) < 1e-9 * 60.0);
}

#[test]
fn conformal_boundary_matches_tv43_on_a_spherical_cap() {
    // TV43: alpha = pi/4 on the unit sphere: image disc of radius sin(alpha), integrated
    // delta2 = 0.064297741135 (scaled by R^2 for a sphere of radius R).
    let r = 100.0;
    let alpha = std::f64::consts::FRAC_PI_4;
    let mesh = testmesh::spherical_cap(r, alpha, 24);
    let f = run(&mesh, Method::ConformalBoundary);
    let s = score(&mesh, &f.uv);
    assert_eq!(s.flips, 0);
    let expected = 0.064297741135 * r * r;
    assert!(
        (s.delta2_integral / expected - 1.0).abs() < 0.03,
        "integrated delta2 {} vs {}",
        s.delta2_integral,
        expected
    );
    // Conformal up to discretisation.
    assert!(s.conf < 0.01, "{}", s.conf);
    // Boundary: isometric (each boundary edge keeps its length) and on a circle of radius
    // R sin(alpha) around the image of the pole (vertex 0).
    let ring = 6 * 24;
    let n = mesh.positions.len();
    for j in 0..ring {
        let (a, b) = (n - ring + j, n - ring + (j + 1) % ring);
        let l3 = (mesh.positions[a] - mesh.positions[b]).length();
        let l2 = (f.uv[a] - f.uv[b]).length();
        assert!(
            (l2 / l3 - 1.0).abs() < 0.01,
            "boundary edge {j}: {l2} vs {l3}"
        );
        let rho = (f.uv[a] - f.uv[0]).length();
        assert!((rho / (r * alpha.sin()) - 1.0).abs() < 0.01, "{rho}");
    }
    // sigma at the pole: cos^2(alpha/2) (TV43), measured on the fan around vertex 0.
    let fan: Vec<usize> = (0..6).collect();
    for t in fan {
        let tri = mesh.triangles[t];
        let d = face_distortion(mesh.corners(t), tri.map(|v| f.uv[v as usize])).unwrap();
        let sigma = (d.sigma1 * d.sigma2).sqrt();
        assert!(
            (sigma / (alpha / 2.0).cos().powi(2) - 1.0).abs() < 0.02,
            "{sigma}"
        );
    }
}

#[test]
fn conformal_boundary_reproduces_a_plane() {
    let (mesh, flat) = testmesh::jittered_plane(60.0, 12);
    let f = run(&mesh, Method::ConformalBoundary);
    assert!(
        rigid_residual(&f.uv, &flat) < 1e-9 * 60.0,
        "{}",
        rigid_residual(&f.uv, &flat)
    );
}

#[test]
fn arap_reproduces_a_plane() {
    let (mesh, flat) = testmesh::jittered_plane(60.0, 12);
    let f = run(&mesh, Method::Arap);
    assert!(
        rigid_residual(&f.uv, &flat) < 1e-8 * 60.0,
        "{}",
        rigid_residual(&f.uv, &flat)
    );
}

#[test]
fn arap_is_flip_free_and_more_isometric_than_lscm() {
    for mesh in [
        testmesh::spherical_cap(100.0, 1.4, 14),
        testmesh::saddle(80.0, 14),
    ] {
        let f = run(&mesh, Method::Arap);
        let s = score(&mesh, &f.uv);
        assert_eq!(s.flips, 0);
        let l = score(&mesh, &run(&mesh, Method::Lscm).uv);
        assert!(
            s.delta2_mean < l.delta2_mean,
            "arap {} vs lscm {}",
            s.delta2_mean,
            l.delta2_mean
        );
        assert!(f.info.iterations >= 1);
    }
    // Developable: ARAP reaches the isometry (libigl's ARAP stalls at conf 0.39 there).
    for mesh in [
        testmesh::cylinder_patch(40.0, 2.5, 70.0, 30, 10),
        testmesh::cone_patch(0.6, 30.0, 90.0, 2.0, 24, 8),
    ] {
        let s = score(&mesh, &run(&mesh, Method::Arap).uv);
        assert!(s.delta2_mean < 1e-8 && s.flips == 0, "{}", s.delta2_mean);
    }
}

#[test]
fn arap_honours_pins() {
    let mesh = testmesh::spherical_cap(100.0, 1.0, 10);
    let pins = vec![
        Pin {
            vertex: 0,
            position: DVec2::new(0.0, 0.0),
        },
        Pin {
            vertex: 200,
            position: DVec2::new(60.0, 20.0),
        },
    ];
    let f = flatten(
        &mesh,
        &FlattenParams::new(Method::Arap).with_pins(pins.clone()),
    )
    .unwrap();
    for p in &pins {
        assert_eq!(f.uv[p.vertex as usize], p.position);
    }
    assert_eq!(score(&mesh, &f.uv).flips, 0);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(12))]

    /// Moving and scaling the surface rigidly in 3D changes nothing but the scale of the
    /// pattern: the distortion of every method is invariant and no triangle flips.
    #[test]
    fn methods_are_invariant_under_3d_similarities(
        ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in 0.1f64..1.0,
        angle in 0.0f64..std::f64::consts::TAU, scale in 0.2f64..5.0,
        tx in -100.0f64..100.0, ty in -100.0f64..100.0,
    ) {
        let base = testmesh::spherical_cap(50.0, 1.1, 6);
        let rot = flatcut_geom::DMat3::from_axis_angle(DVec3::new(ax, ay, az).normalize(), angle);
        let mut moved = base.clone();
        for p in &mut moved.positions {
            *p = rot * *p * scale + DVec3::new(tx, ty, 7.0);
        }
        for m in [Method::Lscm, Method::Arap, Method::ConformalBoundary] {
            let a = score(&base, &run(&base, m).uv);
            let fb = run(&moved, m);
            let b = score(&moved, &fb.uv);
            proptest::prop_assert!((a.conf - b.conf).abs() < 1e-7, "{m}: {} vs {}", a.conf, b.conf);
            proptest::prop_assert!((a.delta2_mean - b.delta2_mean).abs() < 1e-7);
            proptest::prop_assert_eq!(b.flips, 0);
        }
    }
}
