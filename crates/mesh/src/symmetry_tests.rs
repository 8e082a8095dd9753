//! The mirror plane against analytic truth: a plush body symmetric across x = 0 by
//! construction, triangulated unsymmetrically, in its own pose and in another one.

use super::*;
use crate::test_shapes::{plush, plush_ears, plush_radius, star_shaped, turn};
use flatcut_geom::DMat3;

/// A turn of the triangulation that leaves it symmetric about no coordinate plane.
fn skew() -> DMat3 {
    turn(DVec3::new(0.3, 0.7, 0.2), 0.41)
}

/// The angle (degrees) between the found plane's normal and `n`, either way round, and the
/// distance of `p` from the found plane.
fn plane_error(s: &Symmetry, n: DVec3, p: DVec3) -> (f64, f64) {
    let a = s
        .plane
        .normal
        .dot(n.normalize())
        .abs()
        .min(1.0)
        .acos()
        .to_degrees();
    (a, s.plane.distance(p).abs())
}

#[test]
fn the_plane_of_a_symmetric_body_is_found_though_its_triangles_are_not_symmetric() {
    let m = plush(3, skew());
    // The triangulation itself is not symmetric: some vertex's mirror image is no vertex.
    let far = m
        .positions
        .iter()
        .map(|p| {
            let q = DVec3::new(-p.x, p.y, p.z);
            m.positions
                .iter()
                .map(|r| r.distance(q))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    assert!(far > 1.0, "{far}");
    let s = find_mirror(&m, &SymmetryOptions::default()).unwrap();
    let (deg, off) = plane_error(&s, DVec3::X, DVec3::ZERO);
    assert!(s.accepted, "{s:?}");
    assert!(deg < 0.1 && off < 0.05, "{deg}° {off} mm: {s:?}");
    // The deviation is the chordal error of 1,280 faces on a 250 mm body: under 2 mm at worst,
    // a quarter of a millimetre in the mean.
    assert!(s.max_mm < 2.0 && s.rms_mm < 0.3, "{s:?}");
}

#[test]
fn the_plane_is_found_in_any_pose() {
    let m = plush(3, skew());
    let r = turn(DVec3::new(-0.4, 0.2, 0.9), 1.1);
    let shift = DVec3::new(310.0, -45.0, 120.0);
    let posed = TriMesh::new(
        m.positions.iter().map(|&p| r * p + shift).collect(),
        m.triangles.clone(),
    );
    let s = find_mirror(&posed, &SymmetryOptions::default()).unwrap();
    let (deg, off) = plane_error(&s, r * DVec3::X, shift);
    assert!(s.accepted, "{s:?}");
    assert!(deg < 0.1 && off < 0.05, "{deg}° {off} mm: {s:?}");
}

#[test]
fn a_body_with_one_ear_has_no_mirror_plane() {
    let ear = [plush_ears()[0]];
    let m = star_shaped(3, skew(), |d| plush_radius(d, &ear));
    let s = find_mirror(&m, &SymmetryOptions::default()).unwrap();
    assert!(!s.accepted, "{s:?}");
    // The ear stands some 20 mm off the body where its mirror image has none.
    assert!(s.max_mm > 10.0, "{s:?}");
}

#[test]
fn a_named_axis_is_held_and_refused_when_the_body_is_not_symmetric_across_it() {
    let m = plush(3, skew());
    let across_x = SymmetryOptions {
        normal: Some(DVec3::X),
        ..SymmetryOptions::default()
    };
    assert!(find_mirror(&m, &across_x).unwrap().accepted);
    // Both ears lean to +y: the body is not symmetric across y = 0.
    let across_y = SymmetryOptions {
        normal: Some(DVec3::Y),
        ..SymmetryOptions::default()
    };
    let s = find_mirror(&m, &across_y).unwrap();
    assert!(!s.accepted && s.max_mm > 5.0, "{s:?}");
}

#[test]
fn a_mesh_without_area_has_no_plane() {
    assert!(find_mirror(&TriMesh::default(), &SymmetryOptions::default()).is_none());
    let flat = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0], vec![[0, 1, 2]]);
    assert!(find_mirror(&flat, &SymmetryOptions::default()).is_none());
    let nan = TriMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 1.0, 0.0)],
        vec![[0, 1, 2]],
    );
    assert!(find_mirror(&nan, &SymmetryOptions::default()).is_none());
}

#[test]
fn the_reflection_maps_the_plane_to_itself() {
    let p = MirrorPlane::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.0, 2.0, 0.0)).unwrap();
    let q = DVec3::new(4.0, 7.0, -1.0);
    assert!((p.reflect(q) - DVec3::new(4.0, -3.0, -1.0)).length() < 1e-12);
    assert!(p.distance(p.project(q)).abs() < 1e-12);
    assert!(MirrorPlane::new(DVec3::ZERO, DVec3::ZERO).is_none());
}

/// A plane given whole is measured where it is: the posed body's analytic plane (through a
/// point off its centroid, its normal not unit) is accepted and kept exactly; the same plane
/// moved 10 mm, or turned 5°, is refused, the body then some 20 mm (twice the move) from its
/// mirror image.
#[test]
fn a_given_plane_is_measured_as_it_is() {
    let m = plush(3, skew());
    let r = turn(DVec3::new(-0.4, 0.2, 0.9), 1.1);
    let shift = DVec3::new(310.0, -45.0, 120.0);
    let posed = TriMesh::new(
        m.positions.iter().map(|&p| r * p + shift).collect(),
        m.triangles.clone(),
    );
    // A point of the plane x = 0 (before the pose) far from the centroid.
    let point = r * DVec3::new(0.0, 80.0, -60.0) + shift;
    let plane = MirrorPlane::new(point, 3.0 * (r * DVec3::X)).unwrap();
    let s = mirror_across(&posed, plane, DEFAULT_TOLERANCE).unwrap();
    assert!(s.accepted, "{s:?}");
    assert_eq!(s.plane, plane);
    assert!(s.max_mm < 2.0 && s.rms_mm < 0.3, "{s:?}");
    let moved = MirrorPlane::new(point + 10.0 * plane.normal, plane.normal).unwrap();
    let s = mirror_across(&posed, moved, DEFAULT_TOLERANCE).unwrap();
    assert!(!s.accepted && s.max_mm > 15.0 && s.max_mm < 21.0, "{s:?}");
    let tilted = r * turn(DVec3::Z, 5f64.to_radians()) * DVec3::X;
    let s = mirror_across(
        &posed,
        MirrorPlane::new(point, tilted).unwrap(),
        DEFAULT_TOLERANCE,
    )
    .unwrap();
    assert!(!s.accepted, "{s:?}");
    assert!(mirror_across(&TriMesh::default(), plane, DEFAULT_TOLERANCE).is_none());
    for bad in [DVec3::ZERO, DVec3::new(f64::NAN, 1.0, 0.0)] {
        assert!(MirrorPlane::new(DVec3::ZERO, bad).is_none());
    }
    assert!(MirrorPlane::new(DVec3::splat(f64::INFINITY), DVec3::X).is_none());
}
