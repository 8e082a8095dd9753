//! Nearest points on a triangle mesh: a small bounding-volume hierarchy over the triangles
//! (median split, best-first search) and the closest point on one triangle.
//!
//! Written here rather than taken from a collision crate: it is some 150 lines, needs no
//! dependency, and is exact (it returns the true nearest point, not an approximation), which
//! the parry-style crates would also give but at the cost of a second vector type and a large
//! dependency. Every "which point of the surface is this 3D point" question of the workspace
//! (marks carried into the plane, style lines projected onto the surface) is answered here.

use flatcut_geom::{Aabb3, DVec3};

/// Maximum triangles per leaf of the hierarchy.
const LEAF_SIZE: usize = 4;

#[derive(Debug)]
enum Node {
    Leaf {
        bbox: Aabb3,
        tris: Vec<u32>,
    },
    Inner {
        bbox: Aabb3,
        left: usize,
        right: usize,
    },
}

impl Node {
    fn bbox(&self) -> &Aabb3 {
        match self {
            Node::Leaf { bbox, .. } | Node::Inner { bbox, .. } => bbox,
        }
    }
}

/// A bounding-volume hierarchy over triangles for nearest-point queries. It stores triangle
/// indices only: queries take the same positions and triangles it was built from.
#[derive(Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
}

impl Bvh {
    /// Builds the hierarchy over `tris` (indices into `pos`).
    pub fn new(pos: &[DVec3], tris: &[[u32; 3]]) -> Self {
        let mut ids: Vec<u32> = (0..tris.len() as u32).collect();
        let centroids: Vec<DVec3> = tris
            .iter()
            .map(|t| (pos[t[0] as usize] + pos[t[1] as usize] + pos[t[2] as usize]) / 3.0)
            .collect();
        let mut nodes = Vec::new();
        build(&mut nodes, pos, tris, &centroids, &mut ids);
        Self { nodes }
    }

    /// Nearest triangle to `p`: `(triangle, barycentric coordinates, distance)`.
    pub fn nearest(
        &self,
        pos: &[DVec3],
        tris: &[[u32; 3]],
        p: DVec3,
    ) -> Option<(usize, DVec3, f64)> {
        let mut best: Option<(usize, DVec3, f64)> = None;
        let mut best_d2 = f64::INFINITY;
        // The root is the last node pushed by `build`.
        let mut stack = vec![self.nodes.len().checked_sub(1)?];
        while let Some(i) = stack.pop() {
            if box_dist2(self.nodes[i].bbox(), p) >= best_d2 {
                continue;
            }
            match &self.nodes[i] {
                Node::Leaf { tris: ts, .. } => {
                    for &t in ts {
                        let tri = tris[t as usize];
                        let (q, b) = closest_on_triangle(
                            p,
                            pos[tri[0] as usize],
                            pos[tri[1] as usize],
                            pos[tri[2] as usize],
                        );
                        let d2 = (q - p).length_squared();
                        if d2 < best_d2 {
                            best_d2 = d2;
                            best = Some((t as usize, b, d2.sqrt()));
                        }
                    }
                }
                Node::Inner { left, right, .. } => {
                    // Visit the nearer child first (pushed last).
                    let (dl, dr) = (
                        box_dist2(self.nodes[*left].bbox(), p),
                        box_dist2(self.nodes[*right].bbox(), p),
                    );
                    if dl <= dr {
                        stack.push(*right);
                        stack.push(*left);
                    } else {
                        stack.push(*left);
                        stack.push(*right);
                    }
                }
            }
        }
        best
    }
}

fn build(
    nodes: &mut Vec<Node>,
    pos: &[DVec3],
    tris: &[[u32; 3]],
    centroids: &[DVec3],
    ids: &mut [u32],
) -> usize {
    let bbox = ids
        .iter()
        .flat_map(|&t| tris[t as usize].map(|v| pos[v as usize]))
        .fold(Aabb3::EMPTY, |mut b, p| {
            b.add(p);
            b
        });
    if ids.len() <= LEAF_SIZE {
        nodes.push(Node::Leaf {
            bbox,
            tris: ids.to_vec(),
        });
        return nodes.len() - 1;
    }
    let cb = Aabb3::from_points(ids.iter().map(|&t| centroids[t as usize]));
    let ext = cb.size();
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = ids.len() / 2;
    ids.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis]
            .total_cmp(&centroids[b as usize][axis])
            .then(a.cmp(&b))
    });
    let (l, r) = ids.split_at_mut(mid);
    let left = build(nodes, pos, tris, centroids, l);
    let right = build(nodes, pos, tris, centroids, r);
    nodes.push(Node::Inner { bbox, left, right });
    nodes.len() - 1
}

fn box_dist2(b: &Aabb3, p: DVec3) -> f64 {
    let d = (b.min - p).max(p - b.max).max(DVec3::ZERO);
    d.length_squared()
}

/// Closest point to `p` on triangle `(a, b, c)` and its barycentric coordinates (Ericson,
/// Real-Time Collision Detection, §5.1.5).
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, DVec3) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, DVec3::X);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, DVec3::Y);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, DVec3::new(1.0 - v, v, 0.0));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, DVec3::Z);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, DVec3::new(1.0 - w, 0.0, w));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, DVec3::new(0.0, 1.0 - w, w));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, DVec3::new(1.0 - v - w, v, w))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let (q, w) = closest_on_triangle(DVec3::new(0.25, 0.25, 3.0), a, b, c);
        assert!((q - DVec3::new(0.25, 0.25, 0.0)).length() < 1e-15);
        assert!((w - DVec3::new(0.5, 0.25, 0.25)).length() < 1e-15);
        let (q, _) = closest_on_triangle(DVec3::new(2.0, 2.0, 0.0), a, b, c);
        assert!((q - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
        let (q, w) = closest_on_triangle(DVec3::new(-1.0, -1.0, 0.0), a, b, c);
        assert_eq!((q, w), (a, DVec3::X));
    }
}
