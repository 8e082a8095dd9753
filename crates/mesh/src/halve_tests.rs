//! The half of a plush body cut at its mirror plane: on its side, its cut on the plane, half
//! the area, and closed again by its mirror image.

use super::*;
use crate::Topology;
use crate::test_shapes::{plush, turn};
use crate::weld::weld_points;

fn body() -> TriMesh {
    plush(3, turn(DVec3::new(0.3, 0.7, 0.2), 0.41))
}

fn across_x() -> MirrorPlane {
    MirrorPlane::new(DVec3::ZERO, DVec3::X).unwrap()
}

#[test]
fn the_half_lies_on_its_side_with_its_cut_on_the_plane() {
    let m = body();
    let h = half_of(&m, &across_x()).unwrap();
    assert_eq!(h.on_plane.len(), h.mesh.positions.len());
    for (p, &on) in h.mesh.positions.iter().zip(&h.on_plane) {
        if on {
            assert!(p.x.abs() < 1e-12, "{p}");
        } else {
            assert!(p.x > 0.0, "{p}");
        }
    }
    let topo = crate::check_disk(&h.mesh).unwrap();
    for v in &topo.boundary_loops[0] {
        assert!(h.on_plane[*v as usize]);
    }
    // Half the area, to the chordal error of the cut triangles.
    let (half, whole) = (h.mesh.area(), m.area());
    assert!(
        (2.0 * half - whole).abs() < 2e-3 * whole,
        "{half} of {whole}"
    );
    // Vertices moved onto the plane moved by at most the snap (a twentieth of an edge).
    assert!(h.snapped_mm < 1.0, "{}", h.snapped_mm);
}

#[test]
fn the_half_and_its_mirror_image_close_the_surface() {
    let h = half_of(&body(), &across_x()).unwrap();
    let plane = across_x();
    let n = h.mesh.positions.len() as u32;
    let mut points = h.mesh.positions.clone();
    points.extend(
        h.mesh.positions.iter().zip(&h.on_plane).map(
            |(&p, &on)| {
                if on { p } else { plane.reflect(p) }
            },
        ),
    );
    let mut tris = h.mesh.triangles.clone();
    tris.extend(
        h.mesh
            .triangles
            .iter()
            .map(|t| [t[0] + n, t[2] + n, t[1] + n]),
    );
    let (p, map) = weld_points(&points, 0.0);
    let closed = TriMesh::new(p, tris.iter().map(|t| t.map(|v| map[v as usize])).collect());
    let topo = Topology::build(&closed).unwrap();
    assert!(topo.boundary_loops.is_empty());
    assert_eq!(topo.component_count, 1);
    let euler =
        closed.positions.len() as i64 - topo.edge_count() as i64 + closed.triangles.len() as i64;
    assert_eq!(euler, 2);
}

#[test]
fn a_plane_that_misses_the_surface_is_refused() {
    let far = MirrorPlane::new(DVec3::new(500.0, 0.0, 0.0), DVec3::X).unwrap();
    assert_eq!(half_of(&body(), &far).unwrap_err(), HalveError::NoCrossing);
    assert_eq!(
        half_of(&TriMesh::default(), &across_x()).unwrap_err(),
        HalveError::NoCrossing
    );
}
