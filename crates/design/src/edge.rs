//! Allowances by edge in a design: `[[part.edge]]` (a stretch of a part's outline, shared by the
//! pieces along it) and `[[piece.edge]]` (a stretch of one piece's outline), each with a name,
//! an allowance and a kind; and the stretches found on the meshes ([`OutlineEdge`]), which the
//! pattern turns into each piece's allowances.
//!
//! ```toml
//! [[part.edge]]
//! name = "featherline"
//! from = [-4, 0, 0]          # on the outline (within 1 % of the part's size: moved onto it)
//! to = [-4, 0, 0]            # from = to: the whole outline loop through that point
//! # via = [x, y, z]          # otherwise the way from `from` to `to` that passes nearest `via`
//! allowance_mm = 16          # always millimetres; absent: the piece's seam_allowance_mm
//! kind = "lasting"           # seam (default), hem, fold, lasting or raw (0 mm)
//! ```

use flatcut_geom::{DVec3, limits};
use flatcut_mesh::joins::{JoinError, boundary_vertex, stretch};
use flatcut_mesh::lines::END_REL;
use flatcut_mesh::{Topology, TriMesh};
use serde::Deserialize;

use crate::P3;
use crate::units::{Axes, map_point};

pub use flatcut_pattern::EdgeKind;

/// A named stretch of an outline with its own allowance, as the design file gives it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeDef {
    /// The edge's name, used in messages and on the pattern's allowance labels.
    pub name: String,
    /// Where the stretch starts: a point on (or within 1 % of the size of) the outline.
    pub from: P3,
    /// Where the stretch ends; equal to `from`, the whole outline loop through that point.
    pub to: P3,
    #[serde(default)]
    /// A point the stretch passes nearest, to choose between the two ways round from `from` to `to`
    /// (default: the shorter).
    pub via: Option<P3>,
    /// Allowance in mm whatever the file's units; absent: the piece's `seam_allowance_mm`.
    #[serde(default)]
    pub allowance_mm: Option<f64>,
    #[serde(default)]
    /// How the stretch is finished (seam, hem, fold, lasting or raw); default seam.
    pub kind: EdgeKind,
}

impl EdgeDef {
    /// Checks the edge (design units, `s` mm per unit); the message says what is wrong.
    pub(crate) fn check(&self, s: f64) -> Result<(), String> {
        let mut pts = vec![self.from, self.to];
        pts.extend(self.via);
        if pts.iter().flatten().any(|x| !limits::in_range(x * s)) {
            return Err(format!(
                "edge '{}': a point has a coordinate that is not finite or beyond ±{:e} mm",
                self.name,
                limits::MAX_COORD_MM
            ));
        }
        check_allowance(&format!("edge '{}'", self.name), self.allowance_mm)?;
        match (self.kind, self.allowance_mm) {
            (EdgeKind::Raw, Some(a)) if a > 0.0 => Err(format!(
                "edge '{}': a raw edge is cut on the line (0 mm), but allowance_mm = {a}",
                self.name
            )),
            (EdgeKind::Hem | EdgeKind::Fold | EdgeKind::Lasting, None) => Err(format!(
                "edge '{}': a {} edge needs its allowance_mm",
                self.name,
                self.kind.name()
            )),
            _ => Ok(()),
        }
    }

    pub(crate) fn map(&mut self, m: &Axes) {
        map_point(&mut self.from, m);
        map_point(&mut self.to, m);
        if let Some(v) = &mut self.via {
            map_point(v, m);
        }
    }
}

/// Refuses an allowance that is negative, not finite or beyond the coordinate range.
pub(crate) fn check_allowance(what: &str, a: Option<f64>) -> Result<(), String> {
    match a {
        Some(a) if !(a.is_finite() && a >= 0.0 && limits::in_range(a)) => Err(format!(
            "{what}: allowance must be finite, ≥ 0 and at most {:e} mm, got {a}",
            limits::MAX_COORD_MM
        )),
        _ => Ok(()),
    }
}

/// A stretch of a piece's outline with its own allowance: where it lies (3D points along the
/// outline, in order) and how it is finished. The pattern gives every outline edge of a piece
/// that lies on `points` this allowance.
#[derive(Clone, Debug, PartialEq)]
pub struct OutlineEdge {
    /// The edge's (or style line's, or seam's) name.
    pub name: String,
    /// How the stretch is finished (seam, hem, fold, lasting or raw).
    pub kind: EdgeKind,
    /// Allowance in mm; `None`: the piece's own.
    pub allowance_mm: Option<f64>,
    /// The stretch's points on the piece's 3D outline (mm), in order along it.
    pub points: Vec<DVec3>,
    /// The stretch is a whole loop of the outline.
    pub closed: bool,
}

/// Finds `edges` on the boundary of `mesh`: each end becomes a boundary vertex exactly where it
/// falls (within 1 % of the mesh's size), and the stretch between them (the whole loop when
/// both ends fall on one vertex) is the edge. Two edges that share a boundary edge overlap and
/// are refused. Errors: (the edge's name, what is wrong).
pub(crate) fn find(
    mesh: &mut TriMesh,
    edges: &[EdgeDef],
) -> Result<Vec<OutlineEdge>, (String, String)> {
    let mut found: Vec<(Vec<u32>, bool)> = Vec::with_capacity(edges.len());
    for e in edges {
        let fail = |x: JoinError| (e.name.clone(), x.to_string());
        let tol = END_REL * mesh.bbox().diagonal();
        let a = boundary_vertex(mesh, DVec3::from_array(e.from), tol, "`from`").map_err(fail)?;
        let b = boundary_vertex(mesh, DVec3::from_array(e.to), tol, "`to`").map_err(fail)?;
        found.push(if a == b {
            (whole_loop(mesh, a).map_err(fail)?, true)
        } else {
            (
                stretch(mesh, a, b, e.via.map(DVec3::from_array)).map_err(fail)?,
                false,
            )
        });
    }
    for j in 0..found.len() {
        for k in 0..j {
            if let Some(at) = shared_edge(&found[k], &found[j]) {
                let p = mesh.positions[at as usize];
                return Err((
                    edges[j].name.clone(),
                    format!(
                        "it overlaps edge '{}' (both hold the outline near ({:.2}, {:.2}, {:.2}))",
                        edges[k].name, p.x, p.y, p.z
                    ),
                ));
            }
        }
    }
    Ok(edges
        .iter()
        .zip(found)
        .map(|(e, (vs, closed))| OutlineEdge {
            name: e.name.clone(),
            kind: e.kind,
            allowance_mm: e.allowance_mm,
            points: vs.iter().map(|&v| mesh.positions[v as usize]).collect(),
            closed,
        })
        .collect())
}

/// The boundary loop through vertex `v`, starting there.
fn whole_loop(mesh: &TriMesh, v: u32) -> Result<Vec<u32>, JoinError> {
    let topo = Topology::build(mesh)?;
    let lp = topo
        .boundary_loops
        .iter()
        .find(|l| l.contains(&v))
        .ok_or(JoinError::DifferentLoops)?;
    let at = lp.iter().position(|&x| x == v).unwrap_or(0);
    Ok((0..lp.len()).map(|k| lp[(at + k) % lp.len()]).collect())
}

/// A vertex of a boundary edge two stretches share, if any.
fn shared_edge(a: &(Vec<u32>, bool), b: &(Vec<u32>, bool)) -> Option<u32> {
    let pairs = |(s, closed): &(Vec<u32>, bool)| -> Vec<(u32, u32)> {
        let n = s.len();
        let m = if *closed { n } else { n.saturating_sub(1) };
        (0..m)
            .map(|i| {
                let (x, y) = (s[i], s[(i + 1) % n]);
                (x.min(y), x.max(y))
            })
            .collect()
    };
    let pb = pairs(b);
    pairs(a).into_iter().find(|p| pb.contains(p)).map(|p| p.0)
}
