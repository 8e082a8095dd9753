//! Tessellation of chosen faces of a [`Model`], crack-free across shared edges.
//!
//! 1. Every edge bounding a chosen face is sampled once, from its start vertex to its end vertex,
//!    to the chordal tolerance; its end points are the model's vertices. Both faces of the edge
//!    use exactly these points, with the same vertex ids, so the shell welds without cracks or
//!    T-junctions.
//! 2. Each face's loops are mapped to its surface's (u, v): by the analytic surfaces' inverse, or
//!    for spline patches by Newton projection ([`crate::geom::PROJECT_ACCURACY`]) started from the
//!    file's `PCURVE` at the same curve parameter when there is one, else from the previous loop
//!    point. A loop point farther than [`TRIM_GAP_MM`] from the surface makes the face unusable
//!    (the edge is not on the face). Periodic parameters are unwrapped along each loop, holes are
//!    moved to the outer loop's period, and a side of the domain that collapses to one point (a
//!    pole) becomes a run of loop points sharing that point's vertex.
//! 3. Developable faces (plane aside: cylinder, cone, extrusion) are meshed along rulings (see
//!    [`flatcut_mesh::trimmed`]); each ruling that crosses an edge puts a point on that edge (for
//!    both faces), repeated until no face needs another point (at most [`MAX_RULING_ROUNDS`]).
//! 4. Each face is triangulated by [`flatcut_mesh::tessellate_trimmed`] and oriented by its
//!    normal (the surface normal, reversed when the face's `same_sense` is false).

use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};

use flatcut_geom::{DVec2, DVec3, Tolerances};
use flatcut_mesh::tessellate::TessOptions;
use flatcut_mesh::{TriMesh, TrimPoint, TrimmedFace, tessellate_trimmed, trimmed_area};
use flatcut_surface::curve::flatten_with_breaks;
use flatcut_surface::patch::AnalyticKind;
use flatcut_surface::{ParamCurve, ParamSurface};

use crate::StepError;
use crate::geom::{Curve, Surface};
use crate::model::{EdgeGeometry, FaceGeometry, Model};

/// A loop point farther than this from the face's surface (mm) means the edge does not lie on
/// the face: CAD files keep edges within micrometres of their faces.
pub const TRIM_GAP_MM: f64 = 0.1;
/// Rounds of putting ruling crossings on edges (each round only adds points).
pub const MAX_RULING_ROUNDS: usize = 8;
/// Angular step of the points of a pole run on a curved face (radians of the collapsed
/// parameter): 64 per turn.
const POLE_STEP: f64 = PI / 32.0;
/// Bisection steps when locating a ruling's crossing on an edge curve.
const CROSSING_STEPS: usize = 80;
/// Relative size (of the parameter range) below which two rulings are one.
const RULING_SNAP_REL: f64 = 1e-9;
/// Relative accuracy per triangle of the area quadrature.
const AREA_REL: f64 = 1e-10;
/// Chordal tolerance (fraction of the model's size) of the triangles the area is integrated on.
const AREA_MESH_REL: f64 = 1e-3;
/// The area is integrated over loops sampled this finely (fraction of the face's size): the
/// sliver between a chord and its curve is then ~1e-6 of the area.
const AREA_CHORD_REL: f64 = 1e-5;

/// The samples of one edge from its start vertex to its end vertex.
#[derive(Clone, Debug)]
struct Samples {
    ts: Vec<f64>,
    pts: Vec<DVec3>,
}

/// Where a loop point comes from: edge sample `index` of edge slot `slot`, or a vertex of a
/// pole run.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Origin {
    Sample { slot: usize, index: usize },
    Pole { vertex: usize },
}

#[derive(Clone, Copy, Debug)]
struct LoopPt {
    uv: DVec2,
    pos: DVec3,
    origin: Origin,
    /// The model vertex this point is, if any.
    vertex: Option<usize>,
}

/// A segment of a loop along one edge: samples `i` → `j` of edge slot `slot`, at `ua` → `ub`
/// (the u of both ends on the face, after the loop's period alignment).
#[derive(Clone, Copy, Debug)]
struct Seg {
    lp: usize,
    slot: usize,
    i: usize,
    j: usize,
    ua: f64,
    ub: f64,
}

/// The (u, v) loops of a face and the edge segments they run along.
struct Loops {
    loops: Vec<Vec<LoopPt>>,
    segs: Vec<Seg>,
}

/// The mesh of one face.
#[derive(Clone, Debug)]
pub struct FaceMesh {
    pub face: usize,
    /// Positions, triangles counter-clockwise about the face normal, `params` the (u, v).
    pub mesh: TriMesh,
    /// The shell vertex id of every vertex of `mesh`.
    pub global: Vec<u32>,
    /// Meshed along rulings (exactly developable).
    pub ruled: bool,
}

/// An edge's points in the shell mesh, from its start vertex to its end vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeMesh {
    pub edge: usize,
    pub vertices: Vec<u32>,
}

/// The tessellation of chosen faces: shell vertices shared by all faces, one mesh per face.
#[derive(Clone, Debug)]
pub struct Tessellation {
    /// Shell vertex positions (mm): model vertices first, then edge samples, then face interiors.
    pub positions: Vec<DVec3>,
    pub faces: Vec<FaceMesh>,
    /// The edges bounding the faces, in edge order.
    pub edges: Vec<EdgeMesh>,
}

fn face_err(model: &Model, index: usize, message: impl Into<String>) -> StepError {
    StepError::Face {
        index,
        entity: model.faces[index].entity,
        message: message.into(),
    }
}

/// Samples the edge's curve from `t0` to `t1` within `tol`, ends at the exact vertices.
fn sample_edge(model: &Model, g: &EdgeGeometry, tol: f64) -> Samples {
    let (lo, hi) = (g.t0.min(g.t1), g.t0.max(g.t1));
    let mut breaks = vec![lo];
    breaks.extend(
        g.curve
            .breakpoints()
            .into_iter()
            .filter(|&b| b > lo && b < hi),
    );
    breaks.push(hi);
    let mut s: Vec<(f64, DVec3)> = flatten_with_breaks(g.curve.as_ref(), tol, &breaks);
    if g.t1 < g.t0 {
        s.reverse();
    }
    let n = s.len();
    s[0].1 = model.vertices[g.start].point;
    s[n - 1].1 = model.vertices[g.end].point;
    Samples {
        ts: s.iter().map(|x| x.0).collect(),
        pts: s.iter().map(|x| x.1).collect(),
    }
}

/// Shape of a face's parameter space: which directions are periodic angles.
fn periodic(s: &Surface) -> (bool, bool) {
    match s {
        Surface::Analytic(a) => a.periodic(),
        Surface::Spline(_) => (false, false),
    }
}

/// The pcurve of `edge` on the face's surface to start projections from: for a seam (two
/// pcurves on one surface) the one continuing from `prev`.
fn pick_pcurve(
    g: &EdgeGeometry,
    surface_entity: u64,
    t_first: f64,
    prev: Option<DVec2>,
) -> Option<&Curve> {
    let mut best: Option<(&Curve, f64)> = None;
    for p in g
        .pcurves
        .iter()
        .filter(|p| p.surface_entity == surface_entity)
    {
        let d = prev.map_or(0.0, |q| p.curve.eval(t_first).truncate().distance(q));
        if best.is_none_or(|b| d < b.1) {
            best = Some((p.curve.as_ref(), d));
        }
    }
    best.map(|b| b.0)
}

/// Builds the (u, v) loops of a face from the current edge samples.
fn face_loops(
    model: &Model,
    index: usize,
    f: &FaceGeometry,
    slot_of: &BTreeMap<usize, usize>,
    samples: &[Samples],
    rulings: Option<&[f64]>,
) -> Result<Loops, StepError> {
    let s = f.surface.as_ref();
    let mut loops: Vec<Vec<LoopPt>> = Vec::new();
    let mut segs: Vec<Seg> = Vec::new();
    for b in &f.bounds {
        if b.uses.is_empty() {
            continue;
        }
        let mut lp: Vec<LoopPt> = Vec::new();
        for u in &b.uses {
            let g = model.edges[u.edge]
                .geometry
                .as_ref()
                .map_err(|e| face_err(model, index, e.to_string()))?;
            let slot = slot_of[&u.edge];
            let sm = &samples[slot];
            let n = sm.pts.len();
            let order: Vec<usize> = if u.forward {
                (0..n).collect()
            } else {
                (0..n).rev().collect()
            };
            let prev = lp.last().map(|p| p.uv);
            let mut prev_sample: Option<(usize, f64)> = None;
            let pc = match s {
                Surface::Spline(_) => pick_pcurve(g, f.surface_entity, sm.ts[order[0]], prev),
                Surface::Analytic(_) => None,
            };
            for k in order {
                let p = sm.pts[k];
                let last = lp.last().map(|q| q.uv);
                let hint = match pc {
                    Some(c) => Some(c.eval(sm.ts[k]).truncate()),
                    None => last,
                };
                let mut uv = s.param_of(p, hint);
                // Angles continue from the previous point (a pcurve may sit a period away).
                if let (Some(l), (pu, pv)) = (last, periodic(s)) {
                    if pu {
                        uv.x = flatcut_surface::patch::analytic::unwrap_angle(uv.x, l.x);
                    }
                    if pv {
                        uv.y = flatcut_surface::patch::analytic::unwrap_angle(uv.y, l.y);
                    }
                }
                let gap = s.eval(uv.x, uv.y).distance(p);
                if gap.is_nan() || gap > TRIM_GAP_MM {
                    return Err(face_err(
                        model,
                        index,
                        format!(
                            "edge #{} is {gap:.3} mm from the face's surface (more than {TRIM_GAP_MM} mm)",
                            model.edges[u.edge].entity
                        ),
                    ));
                }
                let vertex = if k == 0 {
                    Some(g.start)
                } else if k == n - 1 {
                    Some(g.end)
                } else {
                    None
                };
                let pt = LoopPt {
                    uv,
                    pos: p,
                    origin: Origin::Sample { slot, index: k },
                    vertex,
                };
                if let Some((i, ua)) = prev_sample {
                    segs.push(Seg {
                        lp: loops.len(),
                        slot,
                        i,
                        j: k,
                        ua,
                        ub: uv.x,
                    });
                }
                prev_sample = Some((k, uv.x));
                if let Some(q) = lp.last()
                    && q.vertex.is_some()
                    && q.vertex == vertex
                    && q.uv.distance(uv) <= 1e-12 * (1.0 + uv.length())
                {
                    continue;
                }
                lp.push(pt);
            }
        }
        // Closing: a last point equal to the first is dropped.
        if lp.len() > 1 {
            let (a, z) = (lp[0], lp[lp.len() - 1]);
            if a.vertex.is_some()
                && a.vertex == z.vertex
                && a.uv.distance(z.uv) <= 1e-12 * (1.0 + a.uv.length())
            {
                lp.pop();
            }
        }
        loops.push(fill_poles(lp, rulings));
    }
    align_periods(s, &mut loops, &mut segs);
    check_closure(model, index, s, &loops)?;
    Ok(Loops { loops, segs })
}

/// Inserts the run of points of a pole between consecutive loop points that are the same model
/// vertex at different (u, v): on every ruling for a ruled face, else every [`POLE_STEP`].
fn fill_poles(lp: Vec<LoopPt>, rulings: Option<&[f64]>) -> Vec<LoopPt> {
    let n = lp.len();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (a, b) = (lp[k], lp[(k + 1) % n]);
        out.push(a);
        let same = a.vertex.is_some() && a.vertex == b.vertex;
        if !same || a.uv.distance(b.uv) <= 1e-9 * (1.0 + a.uv.length()) {
            continue;
        }
        let vertex = a.vertex.unwrap_or(0);
        let mut ts: Vec<f64> = match rulings {
            Some(r) => {
                let (u0, u1) = (a.uv.x.min(b.uv.x), a.uv.x.max(b.uv.x));
                r.iter()
                    .filter(|&&u| u > u0 && u < u1)
                    .map(|&u| (u - a.uv.x) / (b.uv.x - a.uv.x))
                    .collect()
            }
            None => {
                let d = (b.uv - a.uv).abs().max_element();
                let m = (d / POLE_STEP).ceil().max(1.0) as usize;
                (1..m).map(|i| i as f64 / m as f64).collect()
            }
        };
        ts.sort_by(f64::total_cmp);
        for t in ts {
            let uv = a.uv + (b.uv - a.uv) * t;
            out.push(LoopPt {
                uv,
                pos: a.pos,
                origin: Origin::Pole { vertex },
                vertex: Some(vertex),
            });
        }
    }
    out
}

fn signed_area(lp: &[LoopPt]) -> f64 {
    let n = lp.len();
    (0..n)
        .map(|k| lp[k].uv.perp_dot(lp[(k + 1) % n].uv))
        .sum::<f64>()
        * 0.5
}

/// Moves the loops other than the outer (largest) one by whole periods into its range.
fn align_periods(s: &Surface, loops: &mut [Vec<LoopPt>], segs: &mut [Seg]) {
    let (pu, pv) = periodic(s);
    if !(pu || pv) || loops.len() < 2 {
        return;
    }
    let outer = (0..loops.len())
        .max_by(|&a, &b| {
            signed_area(&loops[a])
                .abs()
                .total_cmp(&signed_area(&loops[b]).abs())
        })
        .unwrap_or(0);
    let mid = |lp: &[LoopPt]| {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in lp {
            lo = lo.min(p.uv);
            hi = hi.max(p.uv);
        }
        0.5 * (lo + hi)
    };
    let c = mid(&loops[outer]);
    for (i, lp) in loops.iter_mut().enumerate() {
        if i == outer {
            continue;
        }
        let m = mid(lp);
        let shift = DVec2::new(
            if pu {
                TAU * ((c.x - m.x) / TAU).round()
            } else {
                0.0
            },
            if pv {
                TAU * ((c.y - m.y) / TAU).round()
            } else {
                0.0
            },
        );
        for p in lp.iter_mut() {
            p.uv += shift;
        }
        for sg in segs.iter_mut().filter(|sg| sg.lp == i) {
            sg.ua += shift.x;
            sg.ub += shift.x;
        }
    }
}

/// A loop whose (u, v) does not close (it winds once around a periodic direction: a band face
/// with no seam edge) cannot be triangulated in the parameter plane.
fn check_closure(
    model: &Model,
    index: usize,
    s: &Surface,
    loops: &[Vec<LoopPt>],
) -> Result<(), StepError> {
    let (pu, pv) = periodic(s);
    for lp in loops {
        let (a, z) = (lp[0].uv, lp[lp.len() - 1].uv);
        let d = (a - z).abs();
        if (pu && d.x > PI) || (pv && d.y > PI) {
            return Err(face_err(
                model,
                index,
                "a loop winds around the periodic surface without a seam edge: not supported",
            ));
        }
    }
    Ok(())
}

/// The u-step between rulings that keeps a developable face within `tol`, if it has one.
fn chord_rulings(s: &Surface, loops: &[Vec<LoopPt>], tol: f64) -> Vec<f64> {
    let Surface::Analytic(a) = s else {
        return Vec::new();
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in loops.iter().flatten() {
        lo = lo.min(p.uv.x);
        hi = hi.max(p.uv.x);
    }
    let step_for = |radius: f64| {
        if radius > tol {
            2.0 * (1.0 - tol / radius).acos()
        } else {
            f64::INFINITY
        }
    };
    let uniform = |step: f64| -> Vec<f64> {
        if !(step.is_finite() && step > 0.0) {
            return Vec::new();
        }
        let n = ((hi - lo) / step).ceil();
        if !(n.is_finite() && n >= 2.0) {
            return Vec::new();
        }
        (1..n as usize)
            .map(|i| lo + (hi - lo) * i as f64 / n)
            .collect()
    };
    match &a.kind {
        AnalyticKind::Cylinder { radius } => uniform(step_for(*radius)),
        AnalyticKind::Cone { .. } => {
            let rho = loops
                .iter()
                .flatten()
                .map(|p| {
                    let q = a.frame.local(p.pos);
                    q.x.hypot(q.y)
                })
                .fold(0.0, f64::max);
            uniform(step_for(rho))
        }
        AnalyticKind::Extrusion { curve, .. } => {
            flatten_with_breaks(curve.as_ref(), tol, &[lo, hi])
                .into_iter()
                .map(|x| x.0)
                .filter(|&t| t > lo && t < hi)
                .collect()
        }
        _ => Vec::new(),
    }
}

/// Sorted distinct values, merged within `snap`.
fn distinct(mut v: Vec<f64>, snap: f64) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::with_capacity(v.len());
    for x in v {
        if out.last().is_none_or(|&l| x - l > snap) {
            out.push(x);
        }
    }
    out
}

/// The rulings of a developable face: the u of its loop points and those the tolerance needs.
fn face_rulings(s: &Surface, loops: &[Vec<LoopPt>], tol: f64) -> (Vec<f64>, f64) {
    let us: Vec<f64> = loops.iter().flatten().map(|p| p.uv.x).collect();
    let (lo, hi) = us
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &u| {
            (a.min(u), b.max(u))
        });
    let snap = RULING_SNAP_REL * (hi - lo).abs().max(f64::MIN_POSITIVE);
    let mut all = us;
    all.extend(chord_rulings(s, loops, tol));
    (distinct(all, snap), snap)
}

/// The parameter on the edge's curve between `ta` and `tb` where the face's u reaches `r`
/// (bisection on the unwrapped u, which is monotone over one chordal sample).
fn crossing(curve: &Curve, s: &Surface, (ta, ua): (f64, f64), (tb, ub): (f64, f64), r: f64) -> f64 {
    let (mut a, mut b) = (ta, tb);
    let (mut fa, fb) = (ua - r, ub - r);
    if fa * fb > 0.0 {
        return ta + (tb - ta) * (r - ua) / (ub - ua);
    }
    for _ in 0..CROSSING_STEPS {
        let m = 0.5 * (a + b);
        let um = s.param_of(curve.eval(m), Some(DVec2::new(ua, 0.0))).x;
        let fm = um - r;
        if fm == 0.0 {
            return m;
        }
        if (fm < 0.0) == (fa < 0.0) {
            a = m;
            fa = fm;
        } else {
            b = m;
        }
        if a == b {
            break;
        }
    }
    0.5 * (a + b)
}

impl Tessellation {
    /// Tessellates the faces (indices into `model.faces`) to `tol.chord_mm`.
    pub fn new(
        model: &Model,
        faces: &[usize],
        tol: &Tolerances,
        opts: &TessOptions,
    ) -> Result<Tessellation, StepError> {
        if !(tol.chord_mm.is_finite() && tol.chord_mm > 0.0) {
            return Err(StepError::Face {
                index: 0,
                entity: 0,
                message: format!("chordal tolerance must be > 0 mm, got {}", tol.chord_mm),
            });
        }
        let mut geoms: Vec<(usize, &FaceGeometry)> = Vec::with_capacity(faces.len());
        for &i in faces {
            let g = model.face(i).map_err(|e| match e {
                StepError::NoSuchFace { .. } => e,
                e => face_err(model, i, e.to_string()),
            })?;
            geoms.push((i, g));
        }
        // Edges of the faces, sampled once.
        let mut slot_of: BTreeMap<usize, usize> = BTreeMap::new();
        for (_, g) in &geoms {
            for u in g.bounds.iter().flat_map(|b| &b.uses) {
                let n = slot_of.len();
                slot_of.entry(u.edge).or_insert(n);
            }
        }
        let mut slots: Vec<usize> = vec![0; slot_of.len()];
        for (&e, &s) in &slot_of {
            slots[s] = e;
        }
        let mut samples: Vec<Samples> = Vec::with_capacity(slots.len());
        for &e in &slots {
            let g = model.edges[e].geometry.as_ref().map_err(|err| {
                let f = model.edges[e].faces.first().copied().unwrap_or(0);
                face_err(model, f, err.to_string())
            })?;
            samples.push(sample_edge(model, g, tol.chord_mm));
        }
        // Rulings of the developable faces put points on their edges.
        let ruled: Vec<bool> = geoms
            .iter()
            .map(|(_, g)| g.surface.is_ruled_developable() && g.surface.name() != "plane")
            .collect();
        for _ in 0..MAX_RULING_ROUNDS {
            let mut changed = false;
            for (k, (i, g)) in geoms.iter().enumerate() {
                if !ruled[k] {
                    continue;
                }
                let fl = face_loops(model, *i, g, &slot_of, &samples, None)?;
                let (rulings, snap) = face_rulings(&g.surface, &fl.loops, tol.chord_mm);
                changed |=
                    split_at_rulings(model, g, &fl.segs, &rulings, snap, &slots, &mut samples);
            }
            if !changed {
                break;
            }
        }
        // Shell vertex ids: model vertices, then edge samples in edge order.
        let mut positions: Vec<DVec3> = model.vertices.iter().map(|v| v.point).collect();
        let mut sample_id: Vec<Vec<u32>> = Vec::with_capacity(samples.len());
        let mut edges_out = Vec::new();
        let mut order: Vec<usize> = (0..slots.len()).collect();
        order.sort_by_key(|&s| slots[s]);
        let mut ids_of_slot: Vec<Vec<u32>> = vec![Vec::new(); slots.len()];
        for &sl in &order {
            let g = model.edges[slots[sl]]
                .geometry
                .as_ref()
                .map_err(|e| face_err(model, 0, e.to_string()))?;
            let n = samples[sl].pts.len();
            let mut ids = Vec::with_capacity(n);
            ids.push(g.start as u32);
            for k in 1..n - 1 {
                positions.push(samples[sl].pts[k]);
                ids.push((positions.len() - 1) as u32);
            }
            ids.push(g.end as u32);
            edges_out.push(EdgeMesh {
                edge: slots[sl],
                vertices: ids.clone(),
            });
            ids_of_slot[sl] = ids;
        }
        sample_id.extend(ids_of_slot);
        // Faces.
        let mut face_meshes = Vec::with_capacity(geoms.len());
        for (k, (i, g)) in geoms.iter().enumerate() {
            let rulings = if ruled[k] {
                let fl = face_loops(model, *i, g, &slot_of, &samples, None)?;
                Some(face_rulings(&g.surface, &fl.loops, tol.chord_mm).0)
            } else {
                None
            };
            let loops = face_loops(model, *i, g, &slot_of, &samples, rulings.as_deref())?.loops;
            let trim: Vec<Vec<TrimPoint>> = loops
                .iter()
                .map(|lp| {
                    lp.iter()
                        .map(|p| TrimPoint {
                            uv: p.uv,
                            pos: p.pos,
                            vertex: match p.origin {
                                Origin::Sample { slot, index } => sample_id[slot][index],
                                Origin::Pole { vertex } => vertex as u32,
                            },
                        })
                        .collect()
                })
                .collect();
            let tm = tessellate_trimmed(
                &TrimmedFace {
                    surface: g.surface.as_ref(),
                    loops: &trim,
                    ruled: ruled[k],
                },
                tol,
                opts,
            )
            .map_err(|e| face_err(model, *i, e.to_string()))?;
            let mut mesh = tm.mesh;
            if !g.same_sense {
                for t in &mut mesh.triangles {
                    t.swap(1, 2);
                }
            }
            let global: Vec<u32> = tm
                .vertex
                .iter()
                .zip(&mesh.positions)
                .map(|(id, p)| match id {
                    Some(v) => *v,
                    None => {
                        positions.push(*p);
                        (positions.len() - 1) as u32
                    }
                })
                .collect();
            face_meshes.push(FaceMesh {
                face: *i,
                mesh,
                global,
                ruled: ruled[k],
            });
        }
        Ok(Tessellation {
            positions,
            faces: face_meshes,
            edges: edges_out,
        })
    }

    /// One mesh of the faces (all when `faces` is `None`), welded at shared vertices, with only
    /// the vertices those faces use (in shell order).
    pub fn welded(&self, faces: Option<&[usize]>) -> TriMesh {
        self.welded_with_ids(faces).0
    }

    /// [`Self::welded`] and the index in it of every shell vertex (`u32::MAX` if unused).
    fn welded_with_ids(&self, faces: Option<&[usize]>) -> (TriMesh, Vec<u32>) {
        let chosen: Vec<&FaceMesh> = self
            .faces
            .iter()
            .filter(|f| faces.is_none_or(|s| s.contains(&f.face)))
            .collect();
        let mut used = vec![false; self.positions.len()];
        for f in &chosen {
            for &g in &f.global {
                used[g as usize] = true;
            }
        }
        let mut new_id = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::new();
        for (i, &u) in used.iter().enumerate() {
            if u {
                new_id[i] = positions.len() as u32;
                positions.push(self.positions[i]);
            }
        }
        let mut triangles = Vec::new();
        for f in &chosen {
            for t in &f.mesh.triangles {
                let g = t.map(|v| new_id[f.global[v as usize] as usize]);
                if g[0] != g[1] && g[1] != g[2] && g[2] != g[0] {
                    triangles.push(g);
                }
            }
        }
        (TriMesh::new(positions, triangles), new_id)
    }

    /// The mesh of one face, by face index.
    pub fn face(&self, face: usize) -> Option<&FaceMesh> {
        self.faces.iter().find(|f| f.face == face)
    }

    /// The points of an edge (mm), from its start vertex to its end vertex, if the edge bounds
    /// one of the tessellated faces: the polyline both its faces share.
    pub fn edge_polyline(&self, edge: usize) -> Option<Vec<DVec3>> {
        let e = self.edges.iter().find(|e| e.edge == edge)?;
        Some(
            e.vertices
                .iter()
                .map(|&v| self.positions[v as usize])
                .collect(),
        )
    }

    /// The mesh of a piece made of the faces: a single face as meshed (cut at its own seam,
    /// with (u, v)), several welded at their shared edges and cut open again along the seams of
    /// periodic faces; then holes are cut to the outer boundary, so the piece is a disk when it
    /// can be (see [`flatcut_mesh::cut_to_disk`]; otherwise it is returned uncut and a
    /// flattening reports why).
    pub fn piece_mesh(&self, model: &Model, faces: &[usize]) -> TriMesh {
        if let [f] = faces
            && let Some(fm) = self.face(*f)
        {
            return flatcut_mesh::cut_to_disk(&fm.mesh, &[]).unwrap_or_else(|_| fm.mesh.clone());
        }
        let (mesh, new_id) = self.welded_with_ids(Some(faces));
        let seams: Vec<Vec<u32>> = self
            .edges
            .iter()
            .filter(|e| {
                let fs = &model.edges[e.edge].faces;
                fs.len() == 2 && fs[0] == fs[1] && faces.contains(&fs[0])
            })
            .map(|e| e.vertices.iter().map(|&v| new_id[v as usize]).collect())
            .collect();
        flatcut_mesh::cut_to_disk(&mesh, &seams).unwrap_or(mesh)
    }
}

/// Puts a point on every edge segment of the face that a ruling crosses; true if any was added.
fn split_at_rulings(
    model: &Model,
    g: &FaceGeometry,
    segs: &[Seg],
    rulings: &[f64],
    snap: f64,
    slots: &[usize],
    samples: &mut [Samples],
) -> bool {
    let s = g.surface.as_ref();
    let mut inserts: Vec<(usize, f64)> = Vec::new();
    for sg in segs {
        let (ulo, uhi) = (sg.ua.min(sg.ub), sg.ua.max(sg.ub));
        let Ok(eg) = &model.edges[slots[sg.slot]].geometry else {
            continue;
        };
        for &r in rulings {
            if r > ulo + snap && r < uhi - snap {
                let ta = samples[sg.slot].ts[sg.i];
                let tb = samples[sg.slot].ts[sg.j];
                let t = crossing(&eg.curve, s, (ta, sg.ua), (tb, sg.ub), r);
                inserts.push((sg.slot, t));
            }
        }
    }
    if inserts.is_empty() {
        return false;
    }
    inserts.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
    inserts.dedup_by(|x, y| x.0 == y.0 && x.1 == y.1);
    let mut added = false;
    for (slot, t) in inserts {
        let Ok(eg) = &model.edges[slots[slot]].geometry else {
            continue;
        };
        let sm = &mut samples[slot];
        let increasing = sm.ts[sm.ts.len() - 1] > sm.ts[0];
        let pos = sm
            .ts
            .partition_point(|&x| if increasing { x < t } else { x > t });
        if pos == 0 || pos >= sm.ts.len() || sm.ts[pos] == t || sm.ts[pos - 1] == t {
            continue;
        }
        sm.ts.insert(pos, t);
        sm.pts.insert(pos, eg.curve.eval(t));
        added = true;
    }
    added
}

/// The area of face `index` (mm²): the integral of |S_u × S_v| over the region its loops bound,
/// with the loops sampled to [`AREA_CHORD_REL`] of the model's size.
pub fn face_area(model: &Model, index: usize) -> Result<f64, StepError> {
    let g = model
        .face(index)
        .map_err(|e| face_err(model, index, e.to_string()))?;
    let size = model.vertex_bbox().diagonal().max(f64::MIN_POSITIVE);
    let tol = (AREA_CHORD_REL * size).max(1e-9);
    let mut slot_of = BTreeMap::new();
    let mut samples = Vec::new();
    for u in g.bounds.iter().flat_map(|b| &b.uses) {
        if slot_of.contains_key(&u.edge) {
            continue;
        }
        let eg = model.edges[u.edge]
            .geometry
            .as_ref()
            .map_err(|e| face_err(model, index, e.to_string()))?;
        slot_of.insert(u.edge, samples.len());
        samples.push(sample_edge(model, eg, tol));
    }
    let loops = face_loops(model, index, g, &slot_of, &samples, None)?.loops;
    // Every point its own id: the quadrature runs in (u, v), where a pole run is a side of the
    // domain, not one point.
    let mut next = 0u32;
    let trim: Vec<Vec<TrimPoint>> = loops
        .iter()
        .map(|lp| {
            lp.iter()
                .map(|p| {
                    next += 1;
                    TrimPoint {
                        uv: p.uv,
                        pos: p.pos,
                        vertex: next,
                    }
                })
                .collect()
        })
        .collect();
    trimmed_area(g.surface.as_ref(), &trim, AREA_MESH_REL * size, AREA_REL)
        .map_err(|e| face_err(model, index, e.to_string()))
}
