//! Closed test shapes (testkit, not part of the public API): a torus, star-shaped surfaces over
//! an icosphere, and a plush-like body symmetric across the plane x = 0, whose triangulation can be
//! turned so that it is not itself symmetric.

use flatcut_geom::{DMat3, DVec3};
use std::collections::BTreeMap;

use crate::TriMesh;

/// A torus of radii `r1` (to the tube's centre) and `r2` (the tube's), `n` × `m` quads of two
/// triangles, facing out.
pub fn torus(r1: f64, r2: f64, n: usize, m: usize) -> TriMesh {
    use std::f64::consts::TAU;
    let mut positions = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (TAU * i as f64 / n as f64, TAU * j as f64 / m as f64);
            let r = r1 + r2 * v.cos();
            positions.push(DVec3::new(r * u.cos(), r * u.sin(), r2 * v.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % n) * m + j % m) as u32;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(positions, triangles)
}

/// The icosphere of `levels` subdivisions (20·4^levels faces, outward, counter-clockwise), its
/// directions turned by `turn`, each vertex at `radius(direction)` along its direction.
pub fn star_shaped(levels: usize, turn: DMat3, radius: impl Fn(DVec3) -> f64) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|c| DVec3::from_array(*c).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        let mut next = Vec::with_capacity(4 * f.len());
        for [a, b, c] in f {
            let mut m = |x: u32, y: u32| {
                *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    p.push((p[x as usize] + p[y as usize]).normalize());
                    (p.len() - 1) as u32
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    let positions = p
        .into_iter()
        .map(|d| {
            let d = (turn * d).normalize();
            d * radius(d)
        })
        .collect();
    TriMesh::new(positions, f)
}

/// A rotation by `angle` (radians) about `axis`.
pub fn turn(axis: DVec3, angle: f64) -> DMat3 {
    DMat3::from_axis_angle(axis.normalize(), angle)
}

/// The radius of the plush body along unit direction `d`: an ellipsoid of semi-axes 70, 50 and
/// 90 mm (x, y, z) with a bump (an ear) toward each direction of `ears`.
pub fn plush_radius(d: DVec3, ears: &[DVec3]) -> f64 {
    let e = 1.0 / ((d.x / 70.0).powi(2) + (d.y / 50.0).powi(2) + (d.z / 90.0).powi(2)).sqrt();
    let bumps: f64 = ears
        .iter()
        .map(|&c| 0.35 * (-(d - c.normalize()).length_squared() / 0.12).exp())
        .sum();
    e * (1.0 + bumps)
}

/// The ears of the symmetric plush: one each side of x = 0, up and to the front.
pub fn plush_ears() -> [DVec3; 2] {
    [DVec3::new(0.55, 0.25, 0.8), DVec3::new(-0.55, 0.25, 0.8)]
}

/// The plush body with both ears (symmetric across x = 0), its triangulation turned by `turn`.
pub fn plush(levels: usize, turn: DMat3) -> TriMesh {
    let ears = plush_ears();
    star_shaped(levels, turn, |d| plush_radius(d, &ears))
}
