//! Marks between the surface and its flattening: 3D points and polylines (notches, darts,
//! grain lines, logos drawn on the model) carried into the plane, and 2D points carried back
//! onto the surface, by barycentric coordinates in the nearest triangle.
//!
//! Nearest-triangle queries use the mesh crate's bounding-volume hierarchy
//! ([`flatcut_mesh::nearest`]).

use flatcut_geom::{Aabb3, DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_mesh::nearest::Bvh;

/// A 3D point farther from the surface than this fraction of the mesh's bounding-box diagonal
/// is not a mark on the surface (a mark 1 % of the part size away is a mistake, not round-off
/// or tessellation error).
pub const MAX_OFFSET_REL: f64 = 1e-2;

/// A 2D point outside the flat piece by more than this fraction of the piece's diagonal is
/// outside it (only round-off of points on the cut line is tolerated).
pub const OUTSIDE_REL: f64 = 1e-9;

/// Carries 3D points on (or within [`MAX_OFFSET_REL`] of) the surface into the plane of the
/// flattening `uv` (one 2D position per mesh vertex). `None` for a non-finite point, a point
/// too far from the surface, or a `uv` whose length does not match the mesh.
pub fn to_plane(mesh: &TriMesh, uv: &[DVec2], points: &[DVec3]) -> Vec<Option<DVec2>> {
    let pts: Vec<(DVec3, bool)> = points.iter().map(|&p| (p, true)).collect();
    carry(mesh, uv, &pts)
}

/// Carries each point by its nearest surface point; points flagged `true` must lie within
/// [`MAX_OFFSET_REL`] of the surface, the others are projected however far they are.
fn carry(mesh: &TriMesh, uv: &[DVec2], points: &[(DVec3, bool)]) -> Vec<Option<DVec2>> {
    if uv.len() != mesh.positions.len() || mesh.triangles.is_empty() {
        return vec![None; points.len()];
    }
    let bvh = Bvh::new(&mesh.positions, &mesh.triangles);
    let limit = MAX_OFFSET_REL * mesh.bbox().diagonal();
    points
        .iter()
        .map(|&(p, checked)| {
            if !flatcut_geom::finite3(p) {
                return None;
            }
            let (t, b, d) = bvh.nearest(&mesh.positions, &mesh.triangles, p)?;
            if checked && d > limit {
                return None;
            }
            let tri = mesh.triangles[t];
            Some(uv[tri[0] as usize] * b.x + uv[tri[1] as usize] * b.y + uv[tri[2] as usize] * b.z)
        })
        .collect()
}

/// Carries a 3D polyline drawn on the surface into the plane, first subdividing each segment
/// so that no piece is longer than `max_step` mm (the image of a straight 3D segment is
/// curved in the plane). The given points must lie on the surface as for [`to_plane`]; the
/// samples between them lie on the straight chord, which cuts through a curved surface, and
/// are carried by their nearest surface point (the chord projected onto the surface, as CAD's
/// "project curve" does). Points that cannot be carried are `None`.
pub fn polyline_to_plane(
    mesh: &TriMesh,
    uv: &[DVec2],
    points: &[DVec3],
    max_step: f64,
) -> Vec<Option<DVec2>> {
    let mut dense = Vec::new();
    for (i, &p) in points.iter().enumerate() {
        if i > 0 {
            let q = points[i - 1];
            let len = (p - q).length();
            let k = if max_step > 0.0 && len.is_finite() {
                ((len / max_step).ceil() as usize).clamp(1, 1 << 20)
            } else {
                1
            };
            for j in 1..k {
                dense.push((q.lerp(p, j as f64 / k as f64), false));
            }
        }
        dense.push((p, true));
    }
    carry(mesh, uv, &dense)
}

/// Carries 2D points of the flattening `uv` back onto the surface. `None` for a non-finite
/// point or a point outside the flat piece (by more than [`OUTSIDE_REL`] of its diagonal).
/// Where the flattening overlaps itself the nearest triangle found first wins.
pub fn to_surface(mesh: &TriMesh, uv: &[DVec2], points: &[DVec2]) -> Vec<Option<DVec3>> {
    if uv.len() != mesh.positions.len() || mesh.triangles.is_empty() {
        return vec![None; points.len()];
    }
    let flat: Vec<DVec3> = uv.iter().map(|q| q.extend(0.0)).collect();
    let bvh = Bvh::new(&flat, &mesh.triangles);
    let limit = OUTSIDE_REL * Aabb3::from_points(flat.iter().copied()).diagonal();
    points
        .iter()
        .map(|&q| {
            if !flatcut_geom::finite2(q) {
                return None;
            }
            let (t, b, d) = bvh.nearest(&flat, &mesh.triangles, q.extend(0.0))?;
            if d > limit {
                return None;
            }
            let tri = mesh.triangles[t];
            Some(
                mesh.positions[tri[0] as usize] * b.x
                    + mesh.positions[tri[1] as usize] * b.y
                    + mesh.positions[tri[2] as usize] * b.z,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FlattenParams, Method, flatten, testmesh};
    use flatcut_mesh::nearest::closest_on_triangle;

    #[test]
    fn marks_round_trip_and_match_brute_force() {
        let mesh = testmesh::spherical_cap(100.0, 1.2, 10);
        let f = flatten(&mesh, &FlattenParams::new(Method::Lscm)).unwrap();
        // Points on the surface: barycentric combinations inside triangles.
        let pts: Vec<DVec3> = (0..mesh.triangles.len())
            .step_by(7)
            .map(|t| {
                let p = mesh.corners(t);
                0.2 * p[0] + 0.3 * p[1] + 0.5 * p[2]
            })
            .collect();
        let flat = to_plane(&mesh, &f.uv, &pts);
        for (k, t) in (0..mesh.triangles.len()).step_by(7).enumerate() {
            let tri = mesh.triangles[t];
            let want = 0.2 * f.uv[tri[0] as usize]
                + 0.3 * f.uv[tri[1] as usize]
                + 0.5 * f.uv[tri[2] as usize];
            assert!((flat[k].unwrap() - want).length() < 1e-9);
        }
        let back = to_surface(
            &mesh,
            &f.uv,
            &flat.iter().map(|q| q.unwrap()).collect::<Vec<_>>(),
        );
        for (p, q) in pts.iter().zip(&back) {
            assert!((*p - q.unwrap()).length() < 1e-9);
        }
        // Off-surface, outside, NaN.
        let out = to_plane(&mesh, &f.uv, &[DVec3::new(0.0, 0.0, 500.0), DVec3::NAN]);
        assert_eq!(out, vec![None, None]);
        let out = to_surface(&mesh, &f.uv, &[DVec2::new(1e4, 0.0), DVec2::NAN]);
        assert_eq!(out, vec![None, None]);
        // Slightly above the surface: projected to the nearest point (BVH = brute force).
        let bvh = Bvh::new(&mesh.positions, &mesh.triangles);
        for k in 0..50 {
            let p = DVec3::new(
                (k as f64 * 7.3).sin() * 60.0,
                (k as f64 * 3.1).cos() * 60.0,
                80.0 + k as f64 * 0.2,
            );
            let (_, _, d) = bvh.nearest(&mesh.positions, &mesh.triangles, p).unwrap();
            let brute = (0..mesh.triangles.len())
                .map(|t| {
                    let c = mesh.corners(t);
                    (closest_on_triangle(p, c[0], c[1], c[2]).0 - p).length()
                })
                .fold(f64::INFINITY, f64::min);
            assert!((d - brute).abs() < 1e-12);
        }
    }

    #[test]
    fn a_chord_across_a_curved_surface_is_projected_onto_it() {
        // Quarter cylinder, radius 50: the chord between the ends of the quarter circle at
        // height 50 sags 14.6 mm below the surface (far beyond MAX_OFFSET_REL), yet projected
        // onto the surface it is that circle, which develops into a straight line as long as
        // the facets' polygon.
        let (r, nu) = (50.0, 64);
        let mesh = testmesh::cylinder_patch(r, std::f64::consts::FRAC_PI_2, 100.0, nu, 8);
        let f = flatten(&mesh, &FlattenParams::new(Method::Developable)).unwrap();
        let (a, b) = (DVec3::new(r, 0.0, 50.0), DVec3::new(0.0, r, 50.0));
        let line: Vec<DVec2> = polyline_to_plane(&mesh, &f.uv, &[a, b], 1.0)
            .into_iter()
            .map(|q| q.expect("every sample is carried"))
            .collect();
        let len: f64 = line.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        let arc = nu as f64 * 2.0 * r * (std::f64::consts::FRAC_PI_4 / nu as f64).sin();
        assert!((len - arc).abs() < 1e-6, "{len} vs {arc}");
        let d = (line[line.len() - 1] - line[0]).normalize();
        for q in &line {
            assert!(
                (*q - line[0]).perp_dot(d).abs() < 1e-9,
                "straight in the plane"
            );
        }
        // a given point off the surface is still refused
        let off = DVec3::new(0.0, r + 5.0, 50.0);
        let q = polyline_to_plane(&mesh, &f.uv, &[a, off], 1.0);
        assert!(q[0].is_some() && q.last().unwrap().is_none());
    }

    #[test]
    fn polylines_are_densified() {
        let (mesh, _) = testmesh::jittered_plane(60.0, 6);
        let f = flatten(&mesh, &FlattenParams::new(Method::Lscm)).unwrap();
        let a = mesh.positions[8];
        let b = mesh.positions[40];
        let line = polyline_to_plane(&mesh, &f.uv, &[a, b], 1.0);
        let n = ((b - a).length() / 1.0).ceil() as usize + 1;
        assert_eq!(line.len(), n);
        // Planar: the image of the straight segment is straight and of the same length.
        let p: Vec<DVec2> = line.into_iter().map(|q| q.unwrap()).collect();
        let len: f64 = p.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        assert!((len - (b - a).length()).abs() < 1e-9);
    }
}
