//! A surface cut along a plane, its half on the plane normal's side kept: the first step of a
//! mirrored layout ([`crate::symmetry`]), whose other half is this one's mirror image.
//!
//! Every edge that crosses the plane gets a new vertex on it (shared by the two triangles of the
//! edge), and the triangles on the kept side are cut there (a triangle becomes one or two). A
//! vertex closer to the plane than [`SNAP`] of the mean edge length is moved onto it rather than
//! leaving a sliver beside it; one that touches the plane without the surface crossing it there
//! stays on its side. The vertices on the plane are projected onto it and flagged: the mirror
//! image shares them, and they are the seam between the halves.

use flatcut_geom::DVec3;
use std::collections::BTreeMap;

use crate::TriMesh;
use crate::symmetry::MirrorPlane;

/// Vertices closer to the plane than this share of the mean edge length are moved onto it.
pub const SNAP: f64 = 0.05;

/// One half of a surface.
#[derive(Clone, Debug)]
pub struct Half {
    /// The half on the plane normal's side, its boundary on the plane (where the surface was
    /// closed).
    pub mesh: TriMesh,
    /// Per vertex of `mesh`: true when it lies on the plane (shared with the mirror image).
    pub on_plane: Vec<bool>,
    /// Largest distance a vertex was moved to put it on the plane (mm).
    pub snapped_mm: f64,
}

/// Why a surface has no half along a plane.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HalveError {
    /// Nothing of the surface lies on the plane normal's side, or nothing on the other.
    #[error("the plane does not cross the surface")]
    NoCrossing,
    /// A face lies in the plane itself.
    #[error("face {face} lies in the mirror plane")]
    FaceInPlane {
        /// The face (0-based).
        face: usize,
    },
    /// A vertex on the plane is inside the kept half, not on its cut: mirrored it would pinch
    /// the surface.
    #[error("the surface touches the mirror plane at ({:.2}, {:.2}, {:.2}) without crossing it", .at.x, .at.y, .at.z)]
    Touches {
        /// Where (mm).
        at: DVec3,
    },
}

/// The half of `mesh` on `plane`'s normal side (see the module documentation).
pub fn half_of(mesh: &TriMesh, plane: &MirrorPlane) -> Result<Half, HalveError> {
    let side = sides(mesh, plane);
    let (pos, neg) = (side.contains(&1), side.contains(&-1));
    if !(pos && neg) {
        return Err(HalveError::NoCrossing);
    }
    let mut positions: Vec<DVec3> = Vec::new();
    let mut on_plane: Vec<bool> = Vec::new();
    let mut snapped_mm = 0.0f64;
    // Kept vertices of `mesh`, and the vertices made on crossing edges.
    let mut kept: BTreeMap<u32, u32> = BTreeMap::new();
    let mut crossings: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    let mut vertex = |v: u32, positions: &mut Vec<DVec3>, on_plane: &mut Vec<bool>| -> u32 {
        *kept.entry(v).or_insert_with(|| {
            let p = mesh.positions[v as usize];
            let on = side[v as usize] == 0;
            if on {
                snapped_mm = snapped_mm.max(plane.distance(p).abs());
            }
            positions.push(if on { plane.project(p) } else { p });
            on_plane.push(on);
            (positions.len() - 1) as u32
        })
    };
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for (f, tri) in mesh.triangles.iter().enumerate() {
        let s = tri.map(|v| side[v as usize]);
        if s.iter().all(|&x| x == 0) {
            return Err(HalveError::FaceInPlane { face: f });
        }
        if !s.contains(&1) {
            continue;
        }
        // The triangle's part on the kept side, in its winding.
        let mut poly: Vec<u32> = Vec::with_capacity(4);
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            if s[i] >= 0 {
                poly.push(vertex(a, &mut positions, &mut on_plane));
            }
            if s[i] * s[(i + 1) % 3] < 0 {
                let key = (a.min(b), a.max(b));
                let id = *crossings.entry(key).or_insert_with(|| {
                    let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                    let (da, db) = (plane.distance(pa), plane.distance(pb));
                    positions.push(plane.project(pa.lerp(pb, da / (da - db))));
                    on_plane.push(true);
                    (positions.len() - 1) as u32
                });
                poly.push(id);
            }
        }
        triangulate(&poly, &positions, &mut triangles);
    }
    let out = TriMesh::new(positions, triangles);
    check_on_cut(&out, &on_plane)?;
    Ok(Half {
        mesh: out,
        on_plane,
        snapped_mm,
    })
}

/// The side of every vertex: 1 on the normal's side, −1 on the other, 0 on the plane (within
/// [`SNAP`] of the mean edge length, and with neighbours on both sides).
fn sides(mesh: &TriMesh, plane: &MirrorPlane) -> Vec<i8> {
    let mut edges = 0.0;
    for t in &mesh.triangles {
        for i in 0..3 {
            edges +=
                mesh.positions[t[i] as usize].distance(mesh.positions[t[(i + 1) % 3] as usize]);
        }
    }
    let snap = SNAP * edges / (3 * mesh.triangles.len()).max(1) as f64;
    let d: Vec<f64> = mesh.positions.iter().map(|&p| plane.distance(p)).collect();
    let sign = |x: f64| -> i8 { if x > 0.0 { 1 } else { -1 } };
    let mut side: Vec<i8> = d
        .iter()
        .map(|&x| if x.abs() <= snap { 0 } else { sign(x) })
        .collect();
    // A vertex near the plane where the surface does not cross it stays on its side.
    let mut seen = vec![[false; 2]; mesh.positions.len()];
    for t in &mesh.triangles {
        for i in 0..3 {
            for j in 0..3 {
                match side[t[j] as usize] {
                    1 => seen[t[i] as usize][0] = true,
                    -1 => seen[t[i] as usize][1] = true,
                    _ => {}
                }
            }
        }
    }
    for (v, s) in side.iter_mut().enumerate() {
        if *s == 0 && !(seen[v][0] && seen[v][1]) {
            *s = if seen[v][1] { -1 } else { sign(d[v]) };
        }
    }
    side
}

/// Triangles of the convex polygon `poly` (3 or 4 vertices), a quad cut along its shorter
/// diagonal.
fn triangulate(poly: &[u32], positions: &[DVec3], out: &mut Vec<[u32; 3]>) {
    match *poly {
        [a, b, c] => out.push([a, b, c]),
        [a, b, c, d] => {
            let p = |v: u32| positions[v as usize];
            if p(a).distance(p(c)) <= p(b).distance(p(d)) {
                out.extend([[a, b, c], [a, c, d]]);
            } else {
                out.extend([[a, b, d], [b, c, d]]);
            }
        }
        _ => {}
    }
}

/// Every vertex on the plane must be on the half's boundary (its cut); one inside would pinch
/// the surface once mirrored.
fn check_on_cut(half: &TriMesh, on_plane: &[bool]) -> Result<(), HalveError> {
    let mut boundary = vec![false; half.positions.len()];
    let mut count: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for t in &half.triangles {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &count {
        if n == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    match (0..half.positions.len()).find(|&v| on_plane[v] && !boundary[v]) {
        Some(v) => Err(HalveError::Touches {
            at: half.positions[v],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
#[path = "halve_tests.rs"]
mod tests;
