//! Tests of line embedding on planes and cylinders, where the traced line is known exactly.

use super::*;
use crate::regions::split_along_lines;
use crate::{Topology, check_disk};

/// An n × n grid of `size` mm squares in the plane z = 0, jittered so that lines do not run
/// through vertices by accident; triangles CCW from +z.
fn plane(n: usize, size: f64) -> TriMesh {
    crate::test_grid::grid_mesh(n, n, |i, j| {
        let inner = i > 0 && i < n && j > 0 && j < n;
        let jit = if inner {
            0.17 * ((i * 7 + j * 13) as f64).sin()
        } else {
            0.0
        };
        DVec3::new((i as f64 + jit) * size, (j as f64 - 0.6 * jit) * size, 0.0)
    })
}

/// Half a cylinder of radius `r` around the z axis (y ≥ 0), height `h`, `nu` × `nv` quads.
fn half_cylinder(r: f64, h: f64, nu: usize, nv: usize) -> TriMesh {
    // Outward normal: the quad (i, j) → (i+1, j) → (i+1, j+1) runs CCW seen from outside.
    crate::test_grid::grid_mesh(nu, nv, |i, j| {
        let a = std::f64::consts::PI * i as f64 / nu as f64;
        DVec3::new(r * a.cos(), r * a.sin(), h * j as f64 / nv as f64)
    })
}

fn spec(points: &[[f64; 3]], notches: &[[f64; 3]]) -> LineSpec {
    LineSpec {
        points: points.iter().map(|p| DVec3::from_array(*p)).collect(),
        notches: notches.iter().map(|p| DVec3::from_array(*p)).collect(),
    }
}

/// Largest distance of the line's vertices from the segment a–b.
fn off_segment(m: &TriMesh, line: &[u32], a: DVec3, b: DVec3) -> f64 {
    line.iter()
        .map(|&v| {
            let p = m.positions[v as usize];
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            p.distance(a + ab * t)
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_straight_line_across_a_plane_runs_along_new_edges_and_splits_it_in_two() {
    let m = plane(10, 10.0);
    let (a, b) = (DVec3::new(0.0, 23.0, 0.0), DVec3::new(100.0, 71.0, 0.0));
    let e = embed_lines(&m, &[spec(&[a.to_array(), b.to_array()], &[])]).unwrap();
    let line = &e.lines[0];
    // Every crossing snapped or split: the vertices lie within a tenth of an edge of the line,
    // consecutive ones are joined by an edge, and it runs from boundary to boundary.
    assert!(off_segment(&e.mesh, line, a, b) <= 2.0);
    let topo = Topology::build(&e.mesh).unwrap();
    for w in line.windows(2) {
        assert!(topo.edges.contains_key(&(w[0].min(w[1]), w[0].max(w[1]))));
    }
    assert!((e.mesh.area() - m.area()).abs() < 1e-9);
    let s = split_along_lines(&e.mesh, &e.lines).unwrap();
    assert_eq!(s.regions.len(), 2);
    assert_eq!(s.seams.len(), 1);
    let area: f64 = s.regions.iter().map(|r| r.mesh.area()).sum();
    assert!((area - m.area()).abs() < 1e-9);
    // Both sides carry the same vertices at the same coordinates.
    let seam = &s.seams[0];
    let coords = |k: usize| -> Vec<DVec3> {
        let r = &s.regions[seam.sides[k].piece];
        seam.sides[k]
            .vertices
            .iter()
            .map(|&v| r.mesh.positions[v as usize])
            .collect()
    };
    assert_eq!(coords(0), coords(1));
    assert_eq!(coords(0).len(), line.len());
    for r in &s.regions {
        check_disk(&r.mesh).unwrap();
    }
}

#[test]
fn a_line_between_two_points_of_a_cylinder_follows_its_circle() {
    // Two points at the same height: the normal section through them is the circle z = 40.
    let (r, h) = (50.0, 100.0);
    let m = half_cylinder(r, h, 40, 10);
    let e = embed_lines(
        &m,
        &[spec(
            &[[r, 0.0, 43.0], [0.0, r, 43.0], [-r, 0.0, 43.0]],
            &[],
        )],
    )
    .unwrap();
    let edge = h / 10.0;
    for &v in &e.lines[0] {
        let p = e.mesh.positions[v as usize];
        assert!((p.z - 43.0).abs() <= SNAP_REL * edge + 1e-9, "z = {}", p.z);
    }
    let s = split_along_lines(&e.mesh, &e.lines).unwrap();
    assert_eq!(s.regions.len(), 2);
    // The line crosses every vertical edge once: no zig-zag back and forth.
    assert!(e.lines[0].len() <= 2 * 40 + 2, "{}", e.lines[0].len());
}

#[test]
fn notches_are_line_vertices_exactly_where_given() {
    let m = plane(8, 10.0);
    let notches = [[30.0, 41.7, 0.0], [61.3, 41.7, 0.0]];
    let e = embed_lines(
        &m,
        &[spec(&[[0.0, 41.7, 0.0], [80.0, 41.7, 0.0]], &notches)],
    )
    .unwrap();
    for (k, n) in notches.iter().enumerate() {
        let v = e.notches[0][k];
        assert!(e.lines[0].contains(&v));
        assert!(e.mesh.positions[v as usize].distance(DVec3::from_array(*n)) < 1e-9);
    }
    let i0 = e.lines[0]
        .iter()
        .position(|&v| v == e.notches[0][0])
        .unwrap();
    let i1 = e.lines[0]
        .iter()
        .position(|&v| v == e.notches[0][1])
        .unwrap();
    assert!(i0 < i1, "notches in line order");
}

#[test]
fn a_line_may_end_on_another_line() {
    let m = plane(8, 10.0);
    let across = spec(&[[0.0, 40.0, 0.0], [80.0, 40.0, 0.0]], &[]);
    // Given first, it ends 0.4 mm short of the line across: traced after it, onto it.
    let up = spec(&[[37.0, 80.0, 0.0], [37.0, 40.4, 0.0]], &[]);
    let e = embed_lines(&m, &[up, across]).unwrap();
    let end = *e.lines[0].last().unwrap();
    assert!(e.lines[1].contains(&end));
    let s = split_along_lines(&e.mesh, &e.lines).unwrap();
    assert_eq!(s.regions.len(), 3);
    // The line across is two seams (its regions differ left and right of the junction).
    assert_eq!(s.seams.len(), 3);
}

#[test]
fn a_closed_line_cuts_out_the_region_inside() {
    let m = plane(10, 10.0);
    let sq = [
        [30.0, 30.0, 0.0],
        [70.0, 31.0, 0.0],
        [69.0, 72.0, 0.0],
        [31.0, 70.0, 0.0],
        [30.0, 30.0, 0.0],
    ];
    let e = embed_lines(&m, &[spec(&sq, &[])]).unwrap();
    let l = &e.lines[0];
    assert_eq!(l.first(), l.last());
    let s = split_along_lines(&e.mesh, &e.lines).unwrap();
    assert_eq!(s.regions.len(), 2);
    assert_eq!(s.seams.len(), 1);
    let inner = s
        .regions
        .iter()
        .map(|r| r.mesh.area())
        .fold(f64::INFINITY, f64::min);
    // The quadrilateral's area by the shoelace formula.
    let shoelace: f64 = (0..4)
        .map(|k| sq[k][0] * sq[k + 1][1] - sq[k + 1][0] * sq[k][1])
        .sum::<f64>()
        * 0.5;
    assert!(
        (inner - shoelace).abs() < 0.03 * shoelace,
        "{inner} vs {shoelace}"
    );
}

#[test]
fn a_loose_end_is_an_error_that_says_where() {
    let m = plane(8, 10.0);
    let err = embed_lines(&m, &[spec(&[[0.0, 40.0, 0.0], [50.0, 40.0, 0.0]], &[])]).unwrap_err();
    match err {
        LineError::LooseEnd { line, end, x, .. } => {
            assert_eq!((line, end), (0, "last"));
            assert!((x - 50.0).abs() < 1e-9);
        }
        e => panic!("{e}"),
    }
    let err = embed_lines(&m, &[spec(&[[0.0, 40.0, 0.0], [80.0, 40.0, 30.0]], &[])]).unwrap_err();
    assert!(
        matches!(err, LineError::OffSurface { point: 1, .. }),
        "{err}"
    );
}

/// Smallest angle (degrees) of the triangles with a corner on one of the lines.
fn min_angle_beside(e: &Embedded) -> f64 {
    e.mesh
        .triangles
        .iter()
        .filter(|t| t.iter().any(|v| e.lines.iter().any(|l| l.contains(v))))
        .map(|t| {
            let p = t.map(|v| e.mesh.positions[v as usize]);
            (0..3)
                .map(|k| {
                    (p[(k + 1) % 3] - p[k])
                        .angle_between(p[(k + 2) % 3] - p[k])
                        .to_degrees()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn lines_passing_close_to_vertices_leave_no_sliver_triangles() {
    // Lines across a jittered grid at many heights and slopes pass at every distance from its
    // vertices, just outside the snap distance too; the grid's own triangles have 25° or more.
    // Traced without the tidying, these lines leave triangles of 0.06° beside them; with it, the
    // worst is a line crossing an edge 11 % from the boundary (6°), which no collapse or flip
    // improves without moving the boundary or the line by more than the snap distance.
    let m = plane(10, 10.0);
    let mut worst = f64::INFINITY;
    for k in 0..40 {
        let y0 = 12.0 + 1.83 * k as f64;
        let y1 = 88.0 - 1.91 * k as f64;
        let (a, b) = (DVec3::new(0.0, y0, 0.0), DVec3::new(100.0, y1, 0.0));
        let notch = a.lerp(b, 0.37);
        let e = embed_lines(
            &m,
            &[spec(&[a.to_array(), b.to_array()], &[notch.to_array()])],
        )
        .unwrap();
        // The plane stays the plane, the line stays on its segment (within the snap distance)
        // and the notch stays exactly where it was given.
        assert!((e.mesh.area() - m.area()).abs() < 1e-9);
        assert!(off_segment(&e.mesh, &e.lines[0], a, b) <= SNAP_REL * 10.0 * 1.5);
        assert!(e.mesh.positions[e.notches[0][0] as usize].distance(notch) < 1e-12);
        let s = split_along_lines(&e.mesh, &e.lines).unwrap();
        assert_eq!(s.regions.len(), 2);
        worst = worst.min(min_angle_beside(&e));
    }
    eprintln!("smallest angle beside a line: {worst:.2}°");
    assert!(worst >= 5.0, "{worst:.2}°");
}
