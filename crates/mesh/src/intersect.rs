//! Self-intersection: whether two triangles of a mesh that share no vertex pass through each
//! other. A closed surface that does cannot be the skin of anything: its pieces would overlap
//! where they are sewn.
//!
//! Candidate pairs come from a uniform grid of cells about twice the mean edge long (each
//! triangle entered into the cells its box covers, a pair tested once, in the first cell both
//! share); a pair is tested by the separating axis theorem over the two normals, the nine edge
//! cross products and, for coplanar pairs, the six in-plane edge normals. Overlaps thinner than
//! [`TOUCH_REL`] of the pair's size count as touching, not crossing.

use std::collections::BTreeMap;

use flatcut_geom::DVec3;

use crate::TriMesh;

/// Overlap (relative to the larger triangle's longest edge) below which two triangles touch
/// rather than cross: round-off of coordinates written to a file.
pub const TOUCH_REL: f64 = 1e-9;
/// Cells a triangle may be entered into at most (a huge triangle among small ones is tested
/// against the triangles of its first cells only beyond this; such meshes are rare and the
/// bound keeps the memory linear).
const MAX_CELLS_PER_TRIANGLE: usize = 4096;

/// Two triangles that pass through each other, and a point near where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "the surface passes through itself: triangles {first} and {second} intersect near ({:.2}, {:.2}, {:.2})",
    at.x, at.y, at.z
)]
pub struct SelfIntersection {
    /// 0-based index in `TriMesh::triangles` of one triangle; always less than `second`.
    pub first: usize,
    /// 0-based index of the other triangle.
    pub second: usize,
    /// The mean of the two triangles' six corners (mm): a point near the crossing, for the
    /// message, not on it.
    pub at: DVec3,
}

/// Fails with the first intersecting pair (smallest first triangle, then second).
pub fn check_no_self_intersection(mesh: &TriMesh) -> Result<(), SelfIntersection> {
    let nt = mesh.triangles.len();
    if nt < 2 {
        return Ok(());
    }
    let corners = |t: usize| mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    let mean_edge = (0..nt)
        .map(|t| {
            let [a, b, c] = corners(t);
            a.distance(b) + b.distance(c) + c.distance(a)
        })
        .sum::<f64>()
        / (3 * nt) as f64;
    let cell = 2.0 * mean_edge.max(f64::MIN_POSITIVE);
    let bb = mesh.bbox();
    let index = |p: DVec3| {
        let c = ((p - bb.min) / cell).floor();
        (c.x as i32, c.y as i32, c.z as i32)
    };
    let mut cells: BTreeMap<(i32, i32, i32), Vec<u32>> = BTreeMap::new();
    for t in 0..nt {
        let [a, b, c] = corners(t);
        let (lo, hi) = (index(a.min(b).min(c)), index(a.max(b).max(c)));
        let count = |a: i32, b: i32| (b - a + 1) as f64;
        if count(lo.0, hi.0) * count(lo.1, hi.1) * count(lo.2, hi.2) > MAX_CELLS_PER_TRIANGLE as f64
        {
            cells.entry(lo).or_default().push(t as u32);
            continue;
        }
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                for z in lo.2..=hi.2 {
                    cells.entry((x, y, z)).or_default().push(t as u32);
                }
            }
        }
    }
    let mut first: Option<(usize, usize)> = None;
    for members in cells.values() {
        for (i, &s) in members.iter().enumerate() {
            for &t in &members[i + 1..] {
                let (s, t) = (s.min(t) as usize, s.max(t) as usize);
                if first.is_some_and(|f| (s, t) >= f) {
                    continue;
                }
                let (ts, tt) = (mesh.triangles[s], mesh.triangles[t]);
                if ts.iter().any(|v| tt.contains(v)) {
                    continue;
                }
                if crosses(corners(s), corners(t)) {
                    first = Some((s, t));
                }
            }
        }
    }
    match first {
        None => Ok(()),
        Some((s, t)) => Err(SelfIntersection {
            first: s,
            second: t,
            at: (corners(s).iter().sum::<DVec3>() + corners(t).iter().sum::<DVec3>()) / 6.0,
        }),
    }
}

/// True when the two triangles overlap by more than [`TOUCH_REL`] of their size along every
/// separating axis candidate.
pub fn crosses(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    let size = p
        .iter()
        .chain(q.iter())
        .flat_map(|a| p.iter().chain(q.iter()).map(move |b| a.distance(*b)))
        .fold(0.0, f64::max);
    let tol = TOUCH_REL * size;
    let ep = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let eq = [q[1] - q[0], q[2] - q[1], q[0] - q[2]];
    let (np, nq) = (ep[0].cross(ep[1]), eq[0].cross(eq[1]));
    let mut axes: Vec<DVec3> = vec![np, nq];
    for a in ep {
        for b in eq {
            axes.push(a.cross(b));
        }
    }
    for e in ep {
        axes.push(np.cross(e));
    }
    for e in eq {
        axes.push(nq.cross(e));
    }
    for axis in axes {
        let Some(n) = axis.try_normalize() else {
            continue;
        };
        let (a0, a1) = span(&p, n);
        let (b0, b1) = span(&q, n);
        if a1 - b0 <= tol || b1 - a0 <= tol {
            return false;
        }
    }
    true
}

fn span(t: &[DVec3; 3], n: DVec3) -> (f64, f64) {
    let d = t.map(|v| v.dot(n));
    (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_triangles_are_found_and_touching_ones_are_not() {
        let p = [DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 2.0];
        // Pierces p's interior.
        let q = [
            DVec3::new(0.5, 0.5, -1.0),
            DVec3::new(0.5, 0.5, 1.0),
            DVec3::new(3.0, 3.0, 1.0),
        ];
        assert!(crosses(p, q));
        // Above p, parallel.
        let r = p.map(|v| v + DVec3::Z);
        assert!(!crosses(p, r));
        // Meets p along its edge only (a fold along a shared line, no crossing).
        let s = [DVec3::ZERO, DVec3::X * 2.0, DVec3::new(1.0, 0.0, 1.0)];
        assert!(!crosses(p, s));
    }

    #[test]
    fn a_tetrahedron_is_clean_and_two_pierced_ones_are_not() {
        let tet = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        );
        check_no_self_intersection(&tet).unwrap();
        let mut two = tet.clone();
        let off = DVec3::new(0.2, 0.2, 0.2);
        two.positions.extend(tet.positions.iter().map(|p| *p + off));
        two.triangles
            .extend(tet.triangles.iter().map(|t| t.map(|v| v + 4)));
        let e = check_no_self_intersection(&two).unwrap_err();
        assert!(e.first < 4 && e.second >= 4, "{e}");
        assert!(e.to_string().contains("passes through itself"));
    }
}
