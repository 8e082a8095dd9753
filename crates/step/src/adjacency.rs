//! Which faces meet: the edges shared by two faces, and the groups of faces that meet smoothly
//! (tangent-continuously) — a layup ply or an upholstery panel that a CAD model splits into
//! several faces is one piece.

use flatcut_geom::{DVec2, DVec3};
use flatcut_surface::{ParamCurve, ParamSurface};

use crate::model::{FaceGeometry, Model};

/// Two faces meet smoothly when their normals differ by less than this along their whole common
/// edge (radians; 1°). Fillets and G1 blends meet within round-off; a crease of a degree is a
/// design feature.
pub const SMOOTH_MAX_ANGLE: f64 = std::f64::consts::PI / 180.0;
/// Points of a shared edge at which the normals are compared.
const SMOOTH_SAMPLES: usize = 9;

impl Model {
    /// The edges between two different faces, as `(edge, face a, face b)`, in edge order: the
    /// face adjacency of the model.
    pub fn adjacency(&self) -> Vec<(usize, usize, usize)> {
        self.edges
            .iter()
            .enumerate()
            .filter_map(|(e, edge)| match edge.faces.as_slice() {
                [a, b] if a != b => Some((e, *a, *b)),
                _ => None,
            })
            .collect()
    }

    /// The faces (a subset of the model's) grouped by smooth meetings: two faces of the subset
    /// sharing an edge are in one group when their normals agree within [`SMOOTH_MAX_ANGLE`] at
    /// every sampled point of the edge. Groups are listed by their lowest face, faces ascending.
    /// Faces that cannot be read are groups of their own.
    pub fn smooth_groups(&self, faces: &[usize]) -> Vec<Vec<usize>> {
        let mut sel: Vec<usize> = faces.to_vec();
        sel.sort_unstable();
        sel.dedup();
        let pos = |f: usize| sel.binary_search(&f).ok();
        let mut parent: Vec<usize> = (0..sel.len()).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for (e, a, b) in self.adjacency() {
            let (Some(ka), Some(kb)) = (pos(a), pos(b)) else {
                continue;
            };
            // Bodies sewn together meet at a seam, never in one piece.
            if self.faces[a].shell != self.faces[b].shell {
                continue;
            }
            if self.meet_smoothly(e, a, b) {
                let (ra, rb) = (find(&mut parent, ka), find(&mut parent, kb));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut groups: Vec<Vec<usize>> = vec![Vec::new(); sel.len()];
        for k in 0..sel.len() {
            let r = find(&mut parent, k);
            groups[r].push(sel[k]);
        }
        groups.retain(|g| !g.is_empty());
        groups
    }

    fn meet_smoothly(&self, edge: usize, a: usize, b: usize) -> bool {
        let (Ok(eg), Ok(fa), Ok(fb)) = (&self.edges[edge].geometry, self.face(a), self.face(b))
        else {
            return false;
        };
        (1..=SMOOTH_SAMPLES).all(|k| {
            let t = eg.t0 + (eg.t1 - eg.t0) * k as f64 / (SMOOTH_SAMPLES + 1) as f64;
            let p = eg.curve.eval(t);
            let gap = self.heal_mm;
            match (normal_at(eg, fa, p, t, gap), normal_at(eg, fb, p, t, gap)) {
                (Some(na), Some(nb)) => na.angle_between(nb) < SMOOTH_MAX_ANGLE,
                // A singular point (a pole) says nothing either way.
                _ => true,
            }
        })
    }
}

/// The face's outward normal at the point `p` of one of its edges (curve parameter `t`), when the
/// edge lies within `gap` mm of the face's surface there.
fn normal_at(
    eg: &crate::model::EdgeGeometry,
    f: &FaceGeometry,
    p: DVec3,
    t: f64,
    gap: f64,
) -> Option<DVec3> {
    let hint: Option<DVec2> = eg
        .pcurves
        .iter()
        .find(|pc| pc.surface_entity == f.surface_entity)
        .map(|pc| f.surface.from_file(pc.curve.eval(t).truncate()));
    let uv = f.surface.param_of(p, hint);
    if f.surface.eval(uv.x, uv.y).distance(p) > gap {
        return None;
    }
    let (_, su, sv) = f.surface.deriv1(uv.x, uv.y);
    let n = su.cross(sv).try_normalize()?;
    Some(if f.same_sense { n } else { -n })
}
