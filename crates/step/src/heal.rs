//! Repairs of imperfect files, as OpenCASCADE's ShapeFix makes them, each within a limit the
//! user can set ([`HealOptions`]) and each reported per face: vertices off their edge's curve,
//! edges off their face's surface (the shared edge points are kept, the face's tolerance grows),
//! gaps between consecutive edges of a loop (the ends joined), edges listed out of order or with
//! the wrong orientation flag (the loop re-chained by its vertices), and p-curves that disagree
//! with their edge's 3D curve (the 3D curve is used). Beyond the limit the file is refused,
//! naming the entity.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::edge_use::EdgeUse;

/// The default healing limit as a fraction of the model's size (the diagonal of its vertices'
/// bounding box): 0.2 % — a 0.4 mm gap on a 200 mm part is a sloppy file, a 4 mm one is a
/// different shape.
pub const DEFAULT_HEAL_REL: f64 = 2e-3;
/// A defect smaller than this is not reported (mm): files carry round-off of the order of their
/// stated uncertainty, far below this.
pub const REPORT_MM: f64 = 1e-3;

/// How far the reader may move or bridge geometry to heal a file.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HealOptions {
    /// The largest defect healed (mm); `None`: [`DEFAULT_HEAL_REL`] of the model's size.
    pub limit_mm: Option<f64>,
}

impl HealOptions {
    /// The limit for a model of the given size (mm).
    pub fn limit_for(&self, size_mm: f64) -> f64 {
        self.limit_mm
            .unwrap_or(DEFAULT_HEAL_REL * size_mm)
            .max(REPORT_MM)
    }
}

/// What was wrong and has been repaired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RepairKind {
    /// A vertex lies off its edge's curve: the edge runs between the curve's nearest points.
    VertexOffCurve,
    /// An edge lies off the face's surface: its points are kept (shared with the other face),
    /// the face's local tolerance grows to the distance.
    EdgeOffSurface,
    /// Consecutive edges of a loop do not meet: the ends are joined.
    Gap,
    /// A loop's edges are listed out of order or with wrong orientation flags: it is chained by
    /// its vertices.
    LoopOrder,
    /// A face's orientation disagrees with its neighbours' in the shell: it is reversed.
    Orientation,
    /// A p-curve disagrees with its edge's 3D curve: the 3D curve is used.
    Pcurve,
    /// Two vertices at (nearly) one point, used by consecutive edges: merged.
    VertexMerge,
    /// An edge used out and back by consecutive uses of a loop, turning where the surface has
    /// no pole: a slit of zero width inside the face (an internal edge), dropped from the loop.
    Slit,
    /// A free edge of one shell runs along a free edge of another: sewn into one edge, a seam
    /// between the bodies.
    Sewn,
}

/// One repair, on the entity it concerns.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Repair {
    /// What was repaired.
    pub kind: RepairKind,
    /// The instance repaired (`#id`).
    pub entity: u64,
    /// The size of the defect (mm).
    pub mm: f64,
    /// The repair in words, for the report.
    pub message: String,
}

impl Repair {
    /// A repair of `kind` on instance `entity`, of a defect `mm` long.
    pub fn new(kind: RepairKind, entity: u64, mm: f64, message: impl Into<String>) -> Self {
        Self {
            kind,
            entity,
            mm,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Repair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "#{}: {}", self.entity, self.message)
    }
}

impl crate::Model {
    /// Heals the model within `self.heal_mm`: vertices off their curves (reported, or the edge
    /// refused beyond the limit), vertices of consecutive edges that do not meet (merged), free
    /// edges of different shells along one curve (sewn, [`crate::sew`]), and loops running the
    /// same way as their neighbours' along their shared edges (reversed).
    pub(crate) fn heal(&mut self) {
        self.vertices_off_curves();
        self.merge_gaps();
        self.sew_shells();
        self.orient_loops();
    }

    fn vertices_off_curves(&mut self) {
        let limit = self.heal_mm;
        for e in &mut self.edges {
            let Ok(g) = &e.geometry else { continue };
            let d = g.off_curve_mm;
            if d > limit {
                e.geometry = Err(crate::StepError::entity(
                    e.entity,
                    "EDGE_CURVE",
                    format!(
                        "its vertices lie {d:.3} mm from its {} (more than the healing limit, {limit:.3} mm; see --heal-tolerance)",
                        g.curve.name()
                    ),
                ));
            } else if d > REPORT_MM {
                e.repairs.push(Repair::new(
                    RepairKind::VertexOffCurve,
                    e.entity,
                    d,
                    format!(
                        "its vertices lie up to {d:.4} mm from its {}: the edge runs between the curve's points nearest them",
                        g.curve.name()
                    ),
                ));
            }
        }
    }

    /// Merges the end vertex of each edge of a loop with the start vertex of the next where they
    /// are different vertices within the healing limit.
    fn merge_gaps(&mut self) {
        let mut parent: Vec<usize> = (0..self.vertices.len()).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut merged: Vec<(usize, Repair)> = Vec::new();
        for (fi, f) in self.faces.iter().enumerate() {
            let Ok(g) = &f.geometry else { continue };
            for b in &g.bounds {
                let uses = chain_uses(self, &b.uses);
                let n = uses.len();
                for k in 0..n {
                    let (Some(a), Some(c)) = (
                        end_vertex(self, uses[k], true),
                        end_vertex(self, uses[(k + 1) % n], false),
                    ) else {
                        continue;
                    };
                    let (ra, rc) = (find(&mut parent, a), find(&mut parent, c));
                    if ra == rc {
                        continue;
                    }
                    let d = self.vertices[a].point.distance(self.vertices[c].point);
                    if d <= self.heal_mm {
                        parent[ra.max(rc)] = ra.min(rc);
                        merged.push((
                            fi,
                            Repair::new(
                                if d > REPORT_MM {
                                    RepairKind::Gap
                                } else {
                                    RepairKind::VertexMerge
                                },
                                self.vertices[c].entity,
                                d,
                                format!(
                                    "consecutive edges of loop #{} end at vertices #{} and #{}, {d:.4} mm apart: merged",
                                    b.entity, self.vertices[a].entity, self.vertices[c].entity
                                ),
                            ),
                        ));
                    }
                }
            }
        }
        if merged.is_empty() {
            return;
        }
        for e in &mut self.edges {
            if let Ok(g) = &mut e.geometry {
                g.start = find(&mut parent, g.start);
                g.end = find(&mut parent, g.end);
            }
        }
        for (fi, r) in merged {
            self.faces[fi].repairs.push(r);
        }
    }

    /// Reverses the loops that run the same way as their neighbours' along most of their shared
    /// edges (in an oriented shell two faces traverse their common edge in opposite senses),
    /// when the neighbours agree with the rest of the shell.
    fn orient_loops(&mut self) {
        // (face, bound) of every use of every edge, with its direction.
        let mut uses: Vec<Vec<(usize, usize, bool)>> = vec![Vec::new(); self.edges.len()];
        for (fi, f) in self.faces.iter().enumerate() {
            let Ok(g) = &f.geometry else { continue };
            for (bi, b) in g.bounds.iter().enumerate() {
                for u in &b.uses {
                    uses[u.edge].push((fi, bi, u.forward));
                }
            }
        }
        // Net disagreement of each loop: edges shared with another face traversed the same way,
        // minus those traversed the other way.
        let net = |uses: &[Vec<(usize, usize, bool)>]| -> BTreeMap<(usize, usize), i64> {
            let mut out: BTreeMap<(usize, usize), i64> = BTreeMap::new();
            for us in uses {
                if let [a, b] = us.as_slice()
                    && a.0 != b.0
                {
                    let same = if a.2 == b.2 { 1 } else { -1 };
                    *out.entry((a.0, a.1)).or_default() += same;
                    *out.entry((b.0, b.1)).or_default() += same;
                }
            }
            out
        };
        for _ in 0..self.faces.len() {
            let scores = net(&uses);
            // A loop that disagrees with its neighbours while they agree with theirs.
            let pick = scores.iter().filter(|(_, s)| **s > 0).find(|(k, s)| {
                uses.iter().all(|us| match us.as_slice() {
                    [a, b] if a.0 != b.0 && a.2 == b.2 => {
                        let other = if (a.0, a.1) == **k {
                            (b.0, b.1)
                        } else if (b.0, b.1) == **k {
                            (a.0, a.1)
                        } else {
                            return true;
                        };
                        scores.get(&other).copied().unwrap_or(0) < **s
                    }
                    _ => true,
                })
            });
            let Some((&(fi, bi), &s)) = pick else { break };
            let f = &mut self.faces[fi];
            let Ok(g) = &mut f.geometry else { break };
            let b = &mut g.bounds[bi];
            b.uses.reverse();
            for u in &mut b.uses {
                u.forward = !u.forward;
            }
            f.repairs.push(Repair::new(
                RepairKind::Orientation,
                b.entity,
                0.0,
                format!(
                    "the loop runs the same way as its neighbours along its shared edges (by {s}): reversed"
                ),
            ));
            for us in &mut uses {
                for x in us.iter_mut() {
                    if (x.0, x.1) == (fi, bi) {
                        x.2 = !x.2;
                    }
                }
            }
        }
    }
}

/// The vertex at which a use ends (`at_end`) or starts.
fn end_vertex(m: &crate::Model, u: EdgeUse, at_end: bool) -> Option<usize> {
    let g = m.edges[u.edge].geometry.as_ref().ok()?;
    Some(if u.forward == at_end { g.end } else { g.start })
}

/// A loop's uses chained by their vertices: each next use is the unused one starting nearest
/// where the previous ends (the same vertex first, then the nearest point, flipped if its end
/// is nearer), so out-of-order lists and wrong flags chain as the geometry says.
pub(crate) fn chain_uses(m: &crate::Model, uses: &[EdgeUse]) -> Vec<EdgeUse> {
    let n = uses.len();
    if n < 2 {
        return uses.to_vec();
    }
    let chained = (0..n).all(|k| {
        end_vertex(m, uses[k], true).is_some()
            && end_vertex(m, uses[k], true) == end_vertex(m, uses[(k + 1) % n], false)
    });
    if chained {
        return uses.to_vec();
    }
    let pos = |v: Option<usize>| v.map(|v| m.vertices[v].point);
    let mut left: Vec<usize> = (1..n).collect();
    let mut out = vec![uses[0]];
    while !left.is_empty() {
        let cur = *out.last().unwrap_or(&uses[0]);
        let end = end_vertex(m, cur, true);
        let mut best: Option<(f64, usize, bool)> = None;
        for (p, &k) in left.iter().enumerate() {
            for flip in [false, true] {
                let s = end_vertex(m, uses[k], flip);
                let d = if s.is_some() && s == end {
                    -1.0
                } else {
                    match (pos(s), pos(end)) {
                        (Some(a), Some(b)) => a.distance(b),
                        _ => f64::INFINITY,
                    }
                };
                // The file's flag first at equal distance.
                let d = d + if flip { 1e-300 } else { 0.0 };
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, p, flip));
                }
            }
        }
        let (_, p, flip) = best.unwrap_or((0.0, 0, false));
        let k = left.remove(p);
        let mut u = uses[k];
        if flip {
            u.forward = !u.forward;
        }
        out.push(u);
    }
    out
}
