//! Reference surfaces with known flattenings, built in code (mm): spherical caps, exactly
//! developable cylinder and cone patches, a saddle and a jittered planar grid. Used by the
//! tests and benchmarks of the flattener and handy for demonstrations.
//!
//! The cylinder and cone patches are triangulated on their rulings so that every quad is
//! planar: the polyhedral surface is then *exactly* developable (zero angle defect up to
//! round-off), unlike a generic triangulation of the smooth surface.

use std::f64::consts::TAU;

use flatcut_mesh::test_grid::Diagonal;

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;

/// One scalene triangle tilted out of every coordinate plane, for per-triangle energy tests.
pub fn skew_triangle() -> TriMesh {
    TriMesh::new(
        vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.3, 0.1),
            DVec3::new(0.4, 1.7, -0.2),
        ],
        vec![[0, 1, 2]],
    )
}

/// A spherical cap of sphere radius `radius` and geodesic radius `alpha` (radians, < π),
/// centred on the +z pole, with `rings` concentric rings (ring k has 6k vertices, all
/// rings start at longitude 0). Triangles are counter-clockwise seen from outside.
pub fn spherical_cap(radius: f64, alpha: f64, rings: usize) -> TriMesh {
    let rings = rings.max(1);
    let mut pos = vec![DVec3::new(0.0, 0.0, radius)];
    let mut ring_start = vec![0usize];
    let mut ring_phi: Vec<Vec<f64>> = vec![vec![0.0]];
    for k in 1..=rings {
        let rho = alpha * k as f64 / rings as f64;
        let m = 6 * k;
        ring_start.push(pos.len());
        let mut phis = Vec::with_capacity(m);
        for j in 0..m {
            let phi = TAU * j as f64 / m as f64;
            phis.push(phi);
            pos.push(radius * DVec3::new(rho.sin() * phi.cos(), rho.sin() * phi.sin(), rho.cos()));
        }
        ring_phi.push(phis);
    }
    let mut tris = Vec::new();
    for k in 1..=rings {
        let (a0, b0) = (ring_start[k - 1], ring_start[k]);
        let (ma, mb) = (ring_phi[k - 1].len(), ring_phi[k].len());
        if ma == 1 {
            for j in 0..mb {
                tris.push([a0 as u32, (b0 + j) as u32, (b0 + (j + 1) % mb) as u32]);
            }
            continue;
        }
        zip_rings(&mut tris, a0, &ring_phi[k - 1], b0, &ring_phi[k]);
    }
    TriMesh::new(pos, tris)
}

/// Triangulates the band between an inner ring (first vertex `a0`, longitudes `pa`) and an
/// outer ring (`b0`, `pb`), both counter-clockwise and starting at longitude 0.
fn zip_rings(tris: &mut Vec<[u32; 3]>, a0: usize, pa: &[f64], b0: usize, pb: &[f64]) {
    let (ma, mb) = (pa.len(), pb.len());
    let next = |p: &[f64], i: usize| if i + 1 < p.len() { p[i + 1] } else { TAU };
    let (mut i, mut j) = (0usize, 0usize);
    while i < ma || j < mb {
        let advance_a = j == mb || (i < ma && next(pa, i) <= next(pb, j));
        let ai = (a0 + i % ma) as u32;
        let bj = (b0 + j % mb) as u32;
        if advance_a {
            tris.push([ai, bj, (a0 + (i + 1) % ma) as u32]);
            i += 1;
        } else {
            tris.push([ai, bj, (b0 + (j + 1) % mb) as u32]);
            j += 1;
        }
    }
}

/// A cylinder patch of radius `radius`, angular span `span` (radians) and height `height`,
/// `nu × nv` planar rectangles each split in two (diagonals alternate). Exactly developable:
/// its development is a `radius·span × height` rectangle.
pub fn cylinder_patch(radius: f64, span: f64, height: f64, nu: usize, nv: usize) -> TriMesh {
    grid_surface(nu, nv, |s, t| {
        let th = span * s;
        DVec3::new(radius * th.cos(), radius * th.sin(), height * t)
    })
}

/// A patch of the cone with apex at the origin, axis +z and half-angle `half_angle`, between
/// distances `t0 < t1` from the apex along the rulings and over the angular span `span`
/// (radians around the axis). Planar trapezoids split in two: exactly developable.
pub fn cone_patch(half_angle: f64, t0: f64, t1: f64, span: f64, nu: usize, nv: usize) -> TriMesh {
    let (sb, cb) = half_angle.sin_cos();
    grid_surface(nu, nv, |s, t| {
        let th = span * s;
        let d = t0 + (t1 - t0) * t;
        d * DVec3::new(sb * th.cos(), sb * th.sin(), cb)
    })
}

/// The saddle `z = (x² − y²)/(2c)` over the square of side `size` centred at the origin, with
/// `c = size` (Gaussian curvature about −1/c² at the centre), `n × n` cells.
pub fn saddle(size: f64, n: usize) -> TriMesh {
    saddle_of_radius(size, size, n)
}

/// The saddle `z = (x² − y²)/(2c)` over the square of side `size` centred at the origin, with
/// `n × n` cells: Gaussian curvature about −1/c² at the centre. The bench's saddle is
/// `c = size / 2`.
pub fn saddle_of_radius(size: f64, c: f64, n: usize) -> TriMesh {
    grid_surface(n, n, |s, t| {
        let x = size * (s - 0.5);
        let y = size * (t - 0.5);
        DVec3::new(x, y, (x * x - y * y) / (2.0 * c))
    })
}

/// A planar `n × n` grid of side `size` whose interior vertices are jittered (by up to 30 % of a
/// cell, deterministically), rotated into a tilted plane and translated: flat input that every
/// method must reproduce up to a rigid motion. Returns the mesh and the 2D coordinates of its
/// vertices in the plane (the exact development).
pub fn jittered_plane(size: f64, n: usize) -> (TriMesh, Vec<DVec2>) {
    let h = size / n as f64;
    let mut flat = Vec::new();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = move || {
        // SplitMix64: a fixed, portable sequence.
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for j in 0..=n {
        for i in 0..=n {
            let mut p = DVec2::new(i as f64 * h, j as f64 * h);
            if i > 0 && j > 0 && i < n && j < n {
                p += 0.6 * h * DVec2::new(rnd(), rnd());
            }
            flat.push(p);
        }
    }
    let ex = DVec3::new(2.0, 1.0, 2.0) / 3.0;
    let ey = DVec3::new(-1.0, 2.0, 0.0).normalize();
    let ey = (ey - ex * ex.dot(ey)).normalize();
    let o = DVec3::new(10.0, -20.0, 5.0);
    let pos = flat.iter().map(|p| o + ex * p.x + ey * p.y).collect();
    (TriMesh::new(pos, grid_triangles(n, n)), flat)
}

fn grid_surface(nu: usize, nv: usize, f: impl Fn(f64, f64) -> DVec3) -> TriMesh {
    let (nu, nv) = (nu.max(1), nv.max(1));
    let pos = flatcut_mesh::test_grid::grid_points(nu, nv, |i, j| {
        f(i as f64 / nu as f64, j as f64 / nv as f64)
    });
    TriMesh::new(pos, grid_triangles(nu, nv))
}

/// Triangles of an `nu × nv` vertex grid (row-major, `nu + 1` vertices per row), counter-
/// clockwise in the parameter plane, with alternating diagonals (the geometry testkit's).
fn grid_triangles(nu: usize, nv: usize) -> Vec<[u32; 3]> {
    flatcut_mesh::test_grid::grid_triangles(nu, nv, Diagonal::Alternating, |_, _| true)
}

/// `mesh` with slivers: every `every`-th interior edge (in the order of first appearance, one
/// per triangle pair at most) is split at a point a fraction `t` of its length from one end, so
/// each split leaves two triangles whose smallest angle is a fraction of a degree — the shape of
/// scanned meshes, on an otherwise regular surface. The new vertex lies on the old edge, so the
/// surface is unchanged.
pub fn slivered(mesh: &TriMesh, every: usize, t: f64) -> TriMesh {
    let mut pos = mesh.positions.clone();
    let mut tris = mesh.triangles.clone();
    // Interior edges with their two triangles, in order of first appearance.
    let mut seen: Vec<((u32, u32), usize)> = Vec::new();
    let mut pairs: Vec<((u32, u32), usize, usize)> = Vec::new();
    for (f, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            match seen.binary_search_by_key(&key, |e| e.0) {
                Ok(i) => pairs.push((key, seen[i].1, f)),
                Err(i) => seen.insert(i, (key, f)),
            }
        }
    }
    pairs.sort_by_key(|p| p.1.min(p.2));
    let mut touched = vec![false; tris.len()];
    for (k, &((a, b), f0, f1)) in pairs.iter().enumerate() {
        if k % every.max(1) != 0 || touched[f0] || touched[f1] {
            continue;
        }
        let m = pos.len() as u32;
        pos.push(pos[a as usize] * (1.0 - t) + pos[b as usize] * t);
        for f in [f0, f1] {
            let tri = tris[f];
            let c = (0..3).find(|&j| tri[j] != a && tri[j] != b).unwrap_or(0);
            let (apex, x, y) = (tri[c], tri[(c + 1) % 3], tri[(c + 2) % 3]);
            // (apex, x, y) becomes (apex, x, m) and (apex, m, y): same orientation.
            tris[f] = [apex, x, m];
            tris.push([apex, m, y]);
            touched[f] = true;
            touched.push(true);
        }
    }
    TriMesh::new(pos, tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_mesh::check_disk;

    #[test]
    fn test_surfaces_are_disks() {
        let cap = spherical_cap(100.0, 1.0, 8);
        assert_eq!(cap.triangle_count(), 6 * 8 * 8);
        for m in [
            cap,
            cylinder_patch(50.0, 2.0, 60.0, 6, 4),
            cone_patch(0.5, 20.0, 80.0, 2.5, 6, 4),
            saddle(80.0, 5),
            jittered_plane(50.0, 6).0,
        ] {
            let topo = check_disk(&m).unwrap();
            assert_eq!(topo.boundary_loops.len(), 1);
        }
    }
}
