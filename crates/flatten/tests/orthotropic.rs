//! The orthotropic method against analytic truth: a cylinder is developable whichever way its
//! grain runs, so it flattens exactly with the grain along or across its axis; on a spherical
//! cap a woven material (low shear stiffness) keeps its threads and shears, so the bias takes a
//! larger share of the strain than with the isotropic energy; `grain = "auto"` finds the grain
//! a developable surface's limits prefer; every result is flip-free and bit-identical on rerun.

use flatcut_flatten::anisotropy::{Anisotropy, ByDirection, DirectionalLimits, Grain, Stiffness};
use flatcut_flatten::testmesh::{cylinder_patch, spherical_cap};
use flatcut_flatten::{FlattenParams, Method, flatten};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::grain_strain::grain_strain;
use flatcut_mesh::{TriMesh, face_distortion};

const WOVEN: Stiffness = Stiffness {
    along: 1.0,
    across: 0.8,
    shear: 0.02,
};

fn params(stiffness: Stiffness, grain: Grain, limits: Option<DirectionalLimits>) -> FlattenParams {
    FlattenParams::new(Method::Orthotropic).with_anisotropy(Some(Anisotropy {
        stiffness,
        limits,
        grain,
    }))
}

fn tri2(uv: &[DVec2], t: [u32; 3]) -> [DVec2; 3] {
    t.map(|v| uv[v as usize])
}

/// Largest δ2 and whether any triangle is flipped.
fn worst_delta2(mesh: &TriMesh, uv: &[DVec2]) -> (f64, bool) {
    let mut worst = 0f64;
    let mut flipped = false;
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let d = face_distortion(mesh.corners(t), tri2(uv, *tri)).unwrap();
        flipped |= d.flipped();
        worst = worst.max(d.delta2());
    }
    (worst, flipped)
}

/// Area-weighted share of the squared Green strain that is shear in the grain frame (+x).
fn bias_share(mesh: &TriMesh, uv: &[DVec2]) -> f64 {
    let (mut s, mut t) = (0.0, 0.0);
    for (k, tri) in mesh.triangles.iter().enumerate() {
        let c = mesh.corners(k);
        let a = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length();
        let g = grain_strain(c, tri2(uv, *tri), DVec2::X).unwrap();
        let (sh, all) = g.bias_share_parts();
        s += a * sh;
        t += a * all;
    }
    s / t
}

/// The cylinder of the isometric tests: radius 30 mm, 120° of arc, height 50 mm, axis z.
fn cylinder() -> TriMesh {
    cylinder_patch(30.0, 120f64.to_radians(), 50.0, 24, 12)
}

#[test]
fn a_cylinder_flattens_exactly_with_the_grain_along_or_across_its_axis() {
    let mesh = cylinder();
    // Drawn at the middle of the arc (60°), half way up; across: the circumferential direction.
    let (s, c) = 60f64.to_radians().sin_cos();
    let at = DVec3::new(30.0 * c, 30.0 * s, 25.0);
    let across = 10.0 * DVec3::new(-s, c, 0.0);
    for (name, dir) in [("along", 10.0 * DVec3::Z), ("across", across)] {
        let f = flatten(&mesh, &params(WOVEN, Grain::Line([at, at + dir]), None)).unwrap();
        let (d2, flipped) = worst_delta2(&mesh, &f.uv);
        assert!(!flipped, "{name}: flipped");
        assert!(d2 < 1e-10, "{name}: δ2 = {d2:e}");
        // The grain runs along +x in the result: a ruling (along z) maps to ±x when the grain
        // is along the axis, to ±y when it is across.
        let ruling = f.uv[12 * 25 + 5] - f.uv[5];
        let along_x = ruling.x.abs() / ruling.length();
        let want = if name == "along" { 1.0 } else { 0.0 };
        assert!((along_x - want).abs() < 1e-6, "{name}: ruling {ruling:?}");
        // Every thread keeps its length.
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let g = grain_strain(mesh.corners(t), tri2(&f.uv, *tri), DVec2::X).unwrap();
            for s in [g.along, g.across, g.bias_max, g.bias_min] {
                assert!((s - 1.0).abs() < 1e-6, "{name}: triangle {t}: {g:?}");
            }
        }
    }
}

#[test]
fn on_a_spherical_cap_a_woven_material_takes_its_strain_on_the_bias() {
    let mesh = spherical_cap(50.0, 0.7, 14);
    let pole = DVec3::new(0.0, 0.0, 50.0);
    let grain = Grain::Line([pole, pole + 10.0 * DVec3::X]);
    let iso = flatten(&mesh, &params(Stiffness::ISOTROPIC, grain, None)).unwrap();
    let woven = flatten(&mesh, &params(WOVEN, grain, None)).unwrap();
    for f in [&iso, &woven] {
        assert!(!worst_delta2(&mesh, &f.uv).1, "flipped");
    }
    let (si, sw) = (bias_share(&mesh, &iso.uv), bias_share(&mesh, &woven.uv));
    eprintln!("bias share of the squared strain: isotropic {si:.3}, woven {sw:.3}");
    assert!(sw > si + 0.2, "isotropic {si}, woven {sw}");
    // The threads themselves stretch less in the woven flattening.
    let worst_thread = |uv: &[DVec2]| {
        mesh.triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let g = grain_strain(mesh.corners(t), tri2(uv, *tri), DVec2::X).unwrap();
                (g.along - 1.0).abs().max((g.across - 1.0).abs())
            })
            .fold(0.0, f64::max)
    };
    let (ti, tw) = (worst_thread(&iso.uv), worst_thread(&woven.uv));
    eprintln!(
        "worst thread strain: isotropic {:.2} %, woven {:.2} %",
        ti * 100.0,
        tw * 100.0
    );
    assert!(tw < ti, "isotropic {ti}, woven {tw}");
}

#[test]
fn auto_grain_on_an_elliptic_bowl_finds_the_direction_its_limits_prefer_and_is_deterministic() {
    // A spherical cap's strain is symmetric about its axis, but an elliptic bowl's is not:
    // with a tight warp limit the grain's angle matters. The chosen grain's excess is no worse
    // than that of any fixed grain tried here.
    let cap = spherical_cap(50.0, 0.5, 10);
    let mesh = TriMesh::new(
        cap.positions
            .iter()
            .map(|p| DVec3::new(p.x * 1.6, p.y, p.z))
            .collect(),
        cap.triangles.clone(),
    );
    let limits = DirectionalLimits {
        stretch_pct: ByDirection {
            along: 0.3,
            across: 4.0,
            bias: 10.0,
        },
        compress_pct: ByDirection {
            along: 0.3,
            across: 4.0,
            bias: 10.0,
        },
    };
    let p = params(WOVEN, Grain::Auto, Some(limits));
    let a = flatten(&mesh, &p).unwrap();
    let b = flatten(&mesh, &p).unwrap();
    assert_eq!(a.uv, b.uv, "not deterministic");
    let excess = |uv: &[DVec2]| {
        mesh.triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let g = grain_strain(mesh.corners(t), tri2(uv, *tri), DVec2::X).unwrap();
                g.excess(&limits)
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let auto = excess(&a.uv);
    let mut worst_fixed = f64::NEG_INFINITY;
    for deg in [0.0f64, 45.0, 90.0, 135.0] {
        let r = deg.to_radians();
        let f = flatten(
            &mesh,
            &params(
                WOVEN,
                Grain::Line([
                    DVec3::new(0.0, 0.0, 50.0),
                    DVec3::new(10.0 * r.cos(), 10.0 * r.sin(), 50.0),
                ]),
                Some(limits),
            ),
        )
        .unwrap();
        let fixed = excess(&f.uv);
        eprintln!("grain {deg}°: excess {fixed:.3} (auto {auto:.3})");
        assert!(auto <= fixed + 0.01, "{deg}°: fixed {fixed}, auto {auto}");
        worst_fixed = worst_fixed.max(fixed);
    }
    // The grain's angle matters on this bowl (so the search had something to find).
    assert!(worst_fixed > auto + 0.1, "worst {worst_fixed}, auto {auto}");
}

#[test]
fn without_a_material_the_method_says_so() {
    let e = flatten(&cylinder(), &FlattenParams::new(Method::Orthotropic)).unwrap_err();
    assert!(e.to_string().contains("needs a material"), "{e}");
}
