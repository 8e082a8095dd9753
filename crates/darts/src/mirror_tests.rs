//! A plush body split as mirrored pairs, checked independently: every face of every piece within
//! the limits (its singular values computed here from the 3D triangle and the map), each right
//! piece's flat outline the left one's reflected, every seam (the ones across the mirror plane
//! too) of equal flat length on both sides edge by edge, and the pieces closing the surface.

use super::*;
use crate::limits::Band;
use crate::split::{SplitOptions, split_surface};
use flatcut_flatten::{FlattenParams, Method};
use flatcut_mesh::halve::half_of;
use flatcut_mesh::symmetry::{SymmetryOptions, find_mirror};
use flatcut_mesh::test_shapes::{plush, turn};

/// Singular values (σ1 ≥ σ2) of the map of triangle `t` and the sign of its orientation.
fn singular_values(mesh: &TriMesh, t: usize) -> (f64, f64, f64) {
    let x = mesh.flat.as_ref().unwrap();
    let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    let [p, q, r] = mesh.triangles[t].map(|v| x[v as usize]);
    let e1 = (b - a).normalize();
    let e2 = (b - a).cross(c - a).cross(e1).normalize();
    let u = nalgebra::Matrix2::new(
        (b - a).dot(e1),
        (c - a).dot(e1),
        (b - a).dot(e2),
        (c - a).dot(e2),
    );
    let w = nalgebra::Matrix2::new(q.x - p.x, r.x - p.x, q.y - p.y, r.y - p.y);
    let j = w * u.try_inverse().unwrap();
    let s = j.singular_values();
    (s[0].max(s[1]), s[0].min(s[1]), j.determinant())
}

#[test]
fn a_symmetric_body_comes_as_mirrored_pairs_within_the_limits_that_close_it() {
    let pct = 8.0;
    let body = plush(3, turn(DVec3::new(0.3, 0.7, 0.2), 0.41));
    let sym = find_mirror(&body, &SymmetryOptions::default()).unwrap();
    assert!(sym.accepted, "{sym:?}");
    let half = half_of(&body, &sym.plane).unwrap();
    let opts = SplitOptions {
        band: Band::from_pct(Some(pct), Some(pct)),
        max_pieces: 8,
        keep_out: None,
        visibility: Default::default(),
        time_limit: None,
        seam_allowance_mm: 0.0,
    };
    let first = split_surface(&half.mesh, &FlattenParams::new(Method::Isometric), &opts).unwrap();
    assert!(first.feasible);
    let on: Vec<DVec3> = half
        .mesh
        .positions
        .iter()
        .zip(&half.on_plane)
        .filter(|(_, o)| **o)
        .map(|(p, _)| *p)
        .collect();
    let n = first.pieces.len();
    let s = mirror_split(first, &sym.plane, &on, true).unwrap();
    assert_eq!(s.pieces.len(), 2 * n);
    // Limits, independently, on both sides; every face unflipped.
    let (hi, lo) = (1.0 + pct / 100.0 + 1e-9, 1.0 - pct / 100.0 - 1e-9);
    for (k, p) in s.pieces.iter().enumerate() {
        for t in 0..p.triangles.len() {
            let (s1, s2, det) = singular_values(p, t);
            assert!(
                s1 <= hi && s2 >= lo && det > 0.0,
                "piece {k} face {t}: {s1} {s2} {det}"
            );
        }
    }
    // Each right piece is the left one mirrored: its 3D vertices the reflections (or the same
    // points on the plane), its flat map the left one's reflected.
    for k in 0..n {
        let (l, r) = (&s.pieces[k], &s.pieces[k + n]);
        for v in 0..l.positions.len() {
            let d = sym.plane.reflect(l.positions[v]).distance(r.positions[v]);
            assert!(d < 1e-9 || l.positions[v] == r.positions[v], "{k}: {d}");
            let (a, b) = (l.flat.as_ref().unwrap()[v], r.flat.as_ref().unwrap()[v]);
            assert!((a.x + b.x).abs() < 1e-12 && (a.y - b.y).abs() < 1e-12);
        }
    }
    // Seams: some across the plane (a left piece to a right one), both sides of every seam of
    // equal flat length edge by edge.
    let refs: Vec<&TriMesh> = s.pieces.iter().collect();
    let across = s
        .seams
        .iter()
        .filter(|m| (m.sides[0].piece < n) != (m.sides[1].piece < n))
        .count();
    assert!(
        across >= 1,
        "{:?}",
        s.seams.iter().map(|m| &m.name).collect::<Vec<_>>()
    );
    for m in &s.seams {
        let [a, b] = [0, 1].map(|k| m.points_2d(k, &refs).unwrap());
        assert_eq!(a.len(), b.len(), "{}", m.name);
        for i in 1..a.len() {
            let (la, lb) = (a[i].distance(a[i - 1]), b[i].distance(b[i - 1]));
            assert!((la - lb).abs() < 0.1, "{}: edge {i}: {la} vs {lb}", m.name);
        }
    }
    // The pieces cover the body's area, half on each side (the cuts' lines embedded in the
    // surface move it by a few mm² of its 200,000).
    let area: f64 = s.pieces.iter().map(TriMesh::area).sum();
    let l: f64 = s.pieces[..n].iter().map(TriMesh::area).sum();
    assert!((2.0 * l - area).abs() < 1e-12 * area);
    assert!(
        (area - 2.0 * half.mesh.area()).abs() < 1e-4 * area,
        "{area}"
    );
    assert!(
        (area - body.area()).abs() < 2e-3 * area,
        "{area} vs {}",
        body.area()
    );
}

#[test]
fn a_piece_that_is_not_closed_again_is_refused() {
    // Half a body mirrored across a plane that is not its cut: the images do not meet it.
    let body = plush(2, turn(DVec3::new(0.3, 0.7, 0.2), 0.41));
    let plane = MirrorPlane::new(DVec3::ZERO, DVec3::X).unwrap();
    let half = half_of(&body, &plane).unwrap();
    let mut part = half.mesh.clone();
    part.flat = Some(vec![DVec2::ZERO; part.positions.len()]);
    let split = Split {
        pieces: vec![part],
        seams: Vec::new(),
        cuts: Vec::new(),
        excess: -1.0,
        feasible: true,
        worst_3d: DVec3::ZERO,
        timed_out: false,
        seams_apart: false,
        beyond_reach: Vec::new(),
    };
    let shifted = MirrorPlane::new(DVec3::new(1.0, 0.0, 0.0), DVec3::X).unwrap();
    let e = mirror_split(split, &shifted, &[], true).unwrap_err();
    assert!(e.to_string().contains("gap"), "{e}");
}
