//! Which of a design's edges each stretch of a flattened piece's outline is: an edge of the
//! outline (a pair of boundary vertices) belongs to the design's [`OutlineEdge`] whose 3D
//! polyline holds both its ends and its middle. The design's stretches and the piece's mesh
//! share their vertices' coordinates exactly (vertices inserted later lie on the old edges), so
//! the test is to round-off. Consecutive outline edges of one design edge become one
//! [`EdgeAllowance`] of the pattern piece.

use flatcut_design::OutlineEdge;
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_pattern::EdgeAllowance;

/// How far (relative to the mesh's size) a point may lie off a design edge's polyline and
/// still be on it: round-off, far below any mesh edge.
const ON_EDGE_REL: f64 = 1e-7;

/// For each outline edge (vertex `ids[i]` to `ids[i + 1]` of `mesh`), the design edge it lies
/// on (index into `edges`; the first that holds it).
pub fn classify(ids: &[u32], mesh: &TriMesh, edges: &[OutlineEdge]) -> Vec<Option<usize>> {
    let n = ids.len();
    if edges.is_empty() || n == 0 {
        return vec![None; n];
    }
    let tol = ON_EDGE_REL * mesh.bbox().diagonal().max(1.0);
    let pos = |v: u32| mesh.positions.get(v as usize).copied();
    (0..n)
        .map(|i| {
            let (p, q) = (pos(ids[i])?, pos(ids[(i + 1) % n])?);
            let mid = 0.5 * (p + q);
            edges
                .iter()
                .position(|e| [p, q, mid].iter().all(|x| near(e, *x, tol)))
        })
        .collect()
}

/// Whether `x` lies within `tol` of the edge's polyline.
fn near(e: &OutlineEdge, x: DVec3, tol: f64) -> bool {
    let n = e.points.len();
    let m = if e.closed { n } else { n.saturating_sub(1) };
    (0..m).any(|i| {
        let (a, b) = (e.points[i], e.points[(i + 1) % n]);
        let ab = b - a;
        let t = if ab.length_squared() > 0.0 {
            ((x - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + ab * t).distance(x) <= tol
    })
}

/// The pattern's named stretches: each run of consecutive outline edges of one design edge
/// (`classes[i]`, the edge outline vertex `i` starts), from its first vertex to its last; one
/// design edge round the whole outline is a stretch from vertex 0 to vertex 0.
pub fn stretches(classes: &[Option<usize>], edges: &[OutlineEdge]) -> Vec<EdgeAllowance> {
    let n = classes.len();
    let make = |k: usize, from: usize, to: usize| {
        let e = &edges[k];
        EdgeAllowance {
            name: e.name.clone(),
            kind: e.kind,
            width: e.allowance_mm,
            from,
            to,
        }
    };
    let Some(start) = (0..n).find(|&i| classes[i] != classes[(i + n - 1) % n]) else {
        return match classes.first().copied().flatten() {
            Some(k) => vec![make(k, 0, 0)],
            None => Vec::new(),
        };
    };
    let mut out = Vec::new();
    let mut i = start;
    loop {
        let (from, class) = (i, classes[i]);
        loop {
            i = (i + 1) % n;
            if i == start || classes[i] != class {
                break;
            }
        }
        if let Some(k) = class {
            out.push(make(k, from, i));
        }
        if i == start {
            return out;
        }
    }
}

/// The middle of a flattened outline (its area centroid) and the piece's length direction
/// there: the grain where there is one, else the longer side of its smallest bounding box.
pub fn centre_line(outline: &[DVec2], grain: Option<DVec2>) -> (DVec2, DVec2) {
    let centre = flatcut_geom::polygon::area_centroid(outline)
        .unwrap_or_else(|| outline.iter().copied().sum::<DVec2>() / outline.len().max(1) as f64);
    let dir = grain
        .filter(|d| d.length() > 0.0)
        .unwrap_or_else(|| DVec2::from_angle(-flatcut_pattern::piece::orientation(outline, None)));
    (centre, dir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_pattern::EdgeKind;

    fn edge(name: &str, pts: &[[f64; 3]], closed: bool) -> OutlineEdge {
        OutlineEdge {
            name: name.into(),
            kind: EdgeKind::Seam,
            allowance_mm: Some(5.0),
            points: pts.iter().map(|p| DVec3::from_array(*p)).collect(),
            closed,
        }
    }

    #[test]
    fn outline_edges_on_a_design_edge_are_its_stretch() {
        // a square's outline, its bottom side named (the vertex at x = 5 inserted later)
        let mesh = TriMesh {
            positions: [[0., 0.], [5., 0.], [10., 0.], [10., 10.], [0., 10.]]
                .iter()
                .map(|p| DVec3::new(p[0], p[1], 0.0))
                .collect(),
            ..Default::default()
        };
        let edges = [edge("hem", &[[0., 0., 0.], [10., 0., 0.]], false)];
        let classes = classify(&[0, 1, 2, 3, 4], &mesh, &edges);
        assert_eq!(classes, [Some(0), Some(0), None, None, None]);
        let s = stretches(&classes, &edges);
        assert_eq!(s.len(), 1);
        assert_eq!((s[0].from, s[0].to, s[0].name.as_str()), (0, 2, "hem"));
        // a closed design edge round the whole outline
        let all = [edge(
            "rim",
            &[[0., 0., 0.], [10., 0., 0.], [10., 10., 0.], [0., 10., 0.]],
            true,
        )];
        let classes = classify(&[0, 1, 2, 3, 4], &mesh, &all);
        assert!(classes.iter().all(|c| *c == Some(0)));
        let s = stretches(&classes, &all);
        assert_eq!((s.len(), s[0].from, s[0].to), (1, 0, 0));
    }
}
