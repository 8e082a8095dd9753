//! Sewing of separate shells along edges that coincide: a model built of several sheet bodies
//! (one per panel, or a surface model exported face by face) has each body's border as free
//! edges — used by one face only — and where two bodies meet, two such edges run along the same
//! curve. They are made one edge, used by a face of each body, as OpenCASCADE's
//! `BRepBuilderAPI_Sewing` does within its tolerance: the tessellation then samples the edge
//! once for both faces and the pieces meet along a mating seam instead of two unsewn borders.
//!
//! Two free edges are sewn when they belong to different shells, their end vertices coincide
//! (either way round) and points along the two curves coincide, all within the healing limit.
//! Only free edges are candidates: an edge a body already shares is never taken from it.

use std::collections::BTreeMap;

use flatcut_geom::DVec3;
use flatcut_surface::ParamCurve;
use flatcut_surface::curve::nearest_from_samples;

use crate::heal::{Repair, RepairKind};
use crate::model::{EdgeGeometry, Model};

/// Interior points compared along two candidate edges.
const SEW_SAMPLES: usize = 7;
/// How exactly a point is projected onto the other edge's curve (mm).
const SEW_ACCURACY_MM: f64 = 1e-6;

/// A free edge: its index, its shell, and its geometry's end points.
struct Free {
    edge: usize,
    shell: usize,
    ends: [DVec3; 2],
}

impl Model {
    /// Sews free edges of different shells that run along one curve (see the module's doc);
    /// every sewing is reported on the faces it joins.
    pub(crate) fn sew_shells(&mut self) {
        let tol = self.heal_mm;
        let free: Vec<Free> = self
            .edges
            .iter()
            .enumerate()
            .filter_map(|(e, edge)| {
                let [f] = edge.faces.as_slice() else {
                    return None;
                };
                let g = edge.geometry.as_ref().ok()?;
                if g.degenerate {
                    return None;
                }
                Some(Free {
                    edge: e,
                    shell: self.faces[*f].shell,
                    ends: [self.vertices[g.start].point, self.vertices[g.end].point],
                })
            })
            .collect();
        if free.len() < 2 {
            return;
        }
        // Candidates by a grid of the start points (cells of the tolerance): an end within the
        // tolerance of another lies in the same or a neighbouring cell.
        let cell =
            |p: DVec3| -> [i64; 3] { (p / tol.max(1e-9)).floor().to_array().map(|x| x as i64) };
        let mut grid: BTreeMap<[i64; 3], Vec<usize>> = BTreeMap::new();
        for (k, f) in free.iter().enumerate() {
            for end in f.ends {
                grid.entry(cell(end)).or_default().push(k);
            }
        }
        let mut taken = vec![false; free.len()];
        let mut sewn: Vec<(usize, usize, bool, f64)> = Vec::new();
        for (k, a) in free.iter().enumerate() {
            if taken[k] {
                continue;
            }
            let c = cell(a.ends[0]);
            let mut near: Vec<usize> = Vec::new();
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(ks) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            near.extend(ks.iter().copied().filter(|&j| j > k));
                        }
                    }
                }
            }
            near.sort_unstable();
            near.dedup();
            let best = near
                .into_iter()
                .filter(|&j| !taken[j] && free[j].shell != a.shell)
                .filter_map(|j| {
                    let b = &free[j];
                    let forward = a.ends[0].distance(b.ends[0]) <= tol
                        && a.ends[1].distance(b.ends[1]) <= tol;
                    let backward = a.ends[0].distance(b.ends[1]) <= tol
                        && a.ends[1].distance(b.ends[0]) <= tol;
                    let same = if forward {
                        true
                    } else if backward {
                        false
                    } else {
                        return None;
                    };
                    let gap = self.curve_gap(a.edge, b.edge, same)?;
                    (gap <= tol).then_some((j, same, gap))
                })
                .min_by(|x, y| x.2.total_cmp(&y.2));
            if let Some((j, same, gap)) = best {
                taken[k] = true;
                taken[j] = true;
                sewn.push((a.edge, free[j].edge, same, gap));
            }
        }
        for (keep, drop, same, gap) in sewn {
            self.sew(keep, drop, same, gap);
        }
    }

    /// The largest distance from points along edge `b` to edge `a`'s curve (mm), `b` running
    /// the same way as `a` when `same`; `None` when either has no geometry.
    fn curve_gap(&self, a: usize, b: usize, same: bool) -> Option<f64> {
        let (ga, gb) = (
            self.edges[a].geometry.as_ref().ok()?,
            self.edges[b].geometry.as_ref().ok()?,
        );
        let along = |g: &EdgeGeometry, s: f64| g.curve.eval(g.t0 + (g.t1 - g.t0) * s);
        // Points at equal fractions of the parameter need not be near each other (the curves
        // may be parametrised differently): each point of b is projected onto a's curve,
        // within a's range.
        let (lo, hi) = (ga.t0.min(ga.t1), ga.t0.max(ga.t1));
        let ts: Vec<f64> = (0..=8 * SEW_SAMPLES)
            .map(|k| lo + (hi - lo) * k as f64 / (8 * SEW_SAMPLES) as f64)
            .collect();
        let mut worst: f64 = 0.0;
        for k in 1..=SEW_SAMPLES {
            let s = k as f64 / (SEW_SAMPLES + 1) as f64;
            let p = along(gb, if same { s } else { 1.0 - s });
            let (_, d) = nearest_from_samples(ga.curve.as_ref(), p, SEW_ACCURACY_MM, &ts);
            worst = worst.max(d);
        }
        Some(worst)
    }

    /// Makes edge `drop` the edge `keep`: every use of `drop` becomes a use of `keep` (the other
    /// way round unless `same`), its vertices are `keep`'s, and both faces report the sewing.
    fn sew(&mut self, keep: usize, drop: usize, same: bool, gap: f64) {
        let (Ok(gk), Ok(gd)) = (&self.edges[keep].geometry, &self.edges[drop].geometry) else {
            return;
        };
        let (ks, ke) = (gk.start, gk.end);
        let (ds, de) = (gd.start, gd.end);
        let (to_s, to_e) = if same { (ks, ke) } else { (ke, ks) };
        let remap = |v: usize| {
            if v == ds {
                to_s
            } else if v == de {
                to_e
            } else {
                v
            }
        };
        for e in &mut self.edges {
            if let Ok(g) = &mut e.geometry {
                g.start = remap(g.start);
                g.end = remap(g.end);
            }
        }
        let faces = std::mem::take(&mut self.edges[drop].faces);
        let message = format!(
            "edge #{} of another body runs along edge #{} (within {gap:.4} mm): sewn into one, a seam between the bodies",
            self.edges[drop].entity, self.edges[keep].entity
        );
        for &f in &faces {
            if let Ok(g) = &mut self.faces[f].geometry {
                for u in g.bounds.iter_mut().flat_map(|b| b.uses.iter_mut()) {
                    if u.edge == drop {
                        u.edge = keep;
                        u.forward = u.forward == same;
                    }
                }
            }
        }
        let keep_faces = self.edges[keep].faces.clone();
        for &f in keep_faces.iter().chain(&faces) {
            self.faces[f].repairs.push(Repair::new(
                RepairKind::Sewn,
                self.edges[drop].entity,
                gap,
                message.clone(),
            ));
        }
        self.edges[keep].faces.extend(faces);
        self.edges[drop].sewn_into = Some(keep);
    }
}
