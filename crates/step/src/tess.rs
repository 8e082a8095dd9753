//! Tessellation of chosen faces of a [`Model`], crack-free across shared edges.
//!
//! 1. Every edge bounding a chosen face is sampled once, from its start vertex to its end vertex,
//!    to the chordal tolerance; its end points are the model's vertices. Both faces of the edge
//!    use exactly these points, with the same vertex ids, so the shell welds without cracks or
//!    T-junctions, and every shared edge is one polyline on both sides.
//! 2. Each face's region is built in its surface's (u, v) by [`crate::trim`]: independent of
//!    where its loops start, through poles and along seams, with the points it adds (cut lines,
//!    poles) its own.
//! 3. An edge that runs through a pole gets a point there. Developable faces (plane aside:
//!    cylinder, cone, extrusion) are meshed along rulings (see [`flatcut_mesh::trimmed`]): a
//!    face's rulings are the u of its own edge samples and a chordal grid, taken for all faces
//!    before any crossing is put on an edge; then every ruling's crossings with its face's edges
//!    become points of those edges (for both faces), in one pass. A neighbour's crossing is a
//!    point of the face but not one of its rulings, so no point passes back and forth between
//!    faces, whatever their axes: two passes over the faces, whatever the model.
//! 4. Each face is triangulated by [`flatcut_mesh::tessellate_trimmed`] and oriented by its
//!    normal (the surface normal, reversed when the face's `same_sense` is false).
//! 5. Before anything is returned, [`crate::check`] compares every face's area on its trimmed
//!    domain (Green's theorem on the loops) with the area its triangles cover and with the
//!    triangles' own area, and every edge's polyline with its curve's length: a disagreement
//!    beyond 0.1 % is an error naming the face or edge.

use std::collections::BTreeMap;

use flatcut_geom::{DVec2, DVec3, Tolerances};
use flatcut_mesh::tessellate::TessOptions;
use flatcut_mesh::{TriMesh, TrimPoint, TrimmedFace, TrimmedMesh, tessellate_trimmed};
use flatcut_surface::curve::flatten_with_breaks;
use flatcut_surface::patch::AnalyticKind;
use flatcut_surface::{ParamCurve, ParamSurface};

use crate::StepError;
use crate::check::{self, AREA_REL};
use crate::geom::{Curve, Surface};
use crate::heal::Repair;
use crate::model::{EdgeGeometry, FaceGeometry, Model};
use crate::trim::{self, LoopPt, Origin, Samples, Seg, Trim, TrimInput};

/// Rounds of putting pole points on edges (each round only adds points; one is the rule).
pub const MAX_POLE_ROUNDS: usize = 4;
/// Bisection steps when locating a ruling's crossing on an edge curve.
const CROSSING_STEPS: usize = 80;
/// Relative size (of the parameter range) below which two rulings are one.
const RULING_SNAP_REL: f64 = 1e-9;
/// Relative size (of an edge's parameter range) below which two samples are one.
const SAME_SAMPLE_REL: f64 = 1e-9;
/// The area of [`face_area`] is integrated over loops sampled this finely (fraction of the
/// model's size), each segment along its edge's curve (a parabola through the curve's halfway
/// point): the error is then of the fourth order in the spacing, not the sag's `4 s / 3 r`.
const AREA_CHORD_REL: f64 = 1e-5;
/// A point whose whole circle of one parameter is shorter than this fraction of the model's
/// size (and than 1 µm) is a pole.
const POLE_REL: f64 = 1e-7;

/// The mesh of one face.
#[derive(Clone, Debug)]
pub struct FaceMesh {
    /// The face (index into [`crate::Model::faces`]).
    pub face: usize,
    /// Positions, triangles counter-clockwise about the face normal, `params` the (u, v).
    pub mesh: TriMesh,
    /// The shell vertex id of every vertex of `mesh`.
    pub global: Vec<u32>,
    /// Meshed along rulings (exactly developable).
    pub ruled: bool,
    /// The area of the region the mesh's loops bound (mm², Green's theorem on the chords
    /// between the edges' samples at the chordal tolerance): what the triangles are checked
    /// against. It falls short of the face's area by the chords' slivers (0.5 % on a 10 mm
    /// sphere corner at 0.1 mm); the face's area is [`face_area`].
    pub trim_area_mm2: f64,
    /// Lines (shell vertex ids) along which the face was cut open in (u, v) though no edge
    /// runs there: a piece is cut there again after welding.
    pub cuts: Vec<Vec<u32>>,
    /// What healing changed for this face (its edges' repairs included).
    pub repairs: Vec<Repair>,
}

/// An edge's points in the shell mesh, from its start vertex to its end vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeMesh {
    /// The edge (index into [`crate::Model::edges`]).
    pub edge: usize,
    /// Shell vertex ids along the edge, from its start vertex to its end vertex.
    pub vertices: Vec<u32>,
}

/// The tessellation of chosen faces: shell vertices shared by all faces, one mesh per face.
#[derive(Clone, Debug)]
pub struct Tessellation {
    /// Shell vertex positions (mm): model vertices first, then edge samples, then the points the
    /// faces added, then face interiors.
    pub positions: Vec<DVec3>,
    /// One mesh per chosen face, in the order the faces were asked for.
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

/// Samples the edge's curve from `t0` to `t1` within `tol`, ends at the exact vertices (a
/// degenerate edge: its vertex twice).
fn sample_edge(model: &Model, g: &EdgeGeometry, tol: f64) -> Samples {
    if g.degenerate {
        let p = model.vertices[g.start].point;
        return Samples {
            ts: vec![g.t0, g.t1],
            pts: vec![p, p],
        };
    }
    let (lo, hi) = (g.t0.min(g.t1), g.t0.max(g.t1));
    let mut inner = g.curve.breakpoints();
    if g.curve.is_periodic() {
        // Eighths of a turn of the conic's own angle: bisecting from them puts the samples at
        // dyadic fractions of a turn, whatever the edge's ends, so circles about one axis are
        // sampled at common angles and the rulings through one circle's points find points
        // on the next circle instead of adding their own (see `ruling_crossings`).
        // Grid points a round-off from an end are the end.
        let step = std::f64::consts::TAU / 8.0;
        let margin = 1e-9 * step;
        let mut k = (lo / step).floor() + 1.0;
        while k * step < hi - margin {
            if k * step > lo + margin {
                inner.push(k * step);
            }
            k += 1.0;
        }
    }
    inner.sort_by(f64::total_cmp);
    let mut breaks = vec![lo];
    breaks.extend(inner.into_iter().filter(|&b| b > lo && b < hi));
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

/// The pole tolerance of a model (mm).
fn pole_tol(model: &Model) -> f64 {
    (POLE_REL * model.size_mm).clamp(1e-9, 1e-3)
}

/// The region of face `index` from the current edge samples.
#[allow(clippy::too_many_arguments)]
fn face_trim(
    model: &Model,
    index: usize,
    g: &FaceGeometry,
    slot_of: &BTreeMap<usize, usize>,
    samples: &[Samples],
    ruled: bool,
    rulings: Option<&[f64]>,
    chord: f64,
) -> Result<Trim, StepError> {
    trim::build(&TrimInput {
        model,
        index,
        face: g,
        slot_of,
        samples,
        ruled,
        rulings,
        chord,
        heal: model.heal_mm,
        pole_tol: pole_tol(model),
    })
}

/// Loops oriented by their nesting: counter-clockwise at even depth, clockwise at odd — the
/// region the even–odd rule of the triangulation takes, as Green's theorem must see it.
fn oriented_by_nesting(loops: &[Vec<LoopPt>]) -> Vec<Vec<DVec2>> {
    let uv: Vec<Vec<DVec2>> = loops
        .iter()
        .map(|lp| lp.iter().map(|p| p.uv).collect())
        .collect();
    let reversed = reversed_by_nesting(&uv);
    uv.into_iter()
        .zip(reversed)
        .map(|(mut lp, r)| {
            if r {
                lp.reverse();
            }
            lp
        })
        .collect()
}

/// Which loops must be reversed to run counter-clockwise at even depth of nesting and
/// clockwise at odd.
fn reversed_by_nesting(uv: &[Vec<DVec2>]) -> Vec<bool> {
    let inside = |lp: &[DVec2], q: DVec2| {
        let mut c = false;
        for k in 0..lp.len() {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            if (a.y > q.y) != (b.y > q.y) && a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) > q.x {
                c = !c;
            }
        }
        c
    };
    let area = |lp: &[DVec2]| -> f64 {
        (0..lp.len())
            .map(|k| lp[k].perp_dot(lp[(k + 1) % lp.len()]))
            .sum::<f64>()
    };
    uv.iter()
        .enumerate()
        .map(|(i, lp)| {
            let probe = if lp.len() > 1 {
                0.5 * (lp[0] + lp[1])
            } else {
                lp[0]
            };
            let depth = uv
                .iter()
                .enumerate()
                .filter(|(j, other)| *j != i && inside(other, probe))
                .count();
            let ccw = area(lp) > 0.0;
            ccw != (depth % 2 == 0)
        })
        .collect()
}

/// The loops of a trimmed face with, between consecutive samples of an edge, the (u, v) of the
/// edge's curve halfway (marked `true`), for [`check::trim_area_curved`]. A halfway point the
/// surface does not reproduce within `tol`, or farther from the chord's middle than the chord
/// is long (next to a pole, where u is free), is left out: that segment stays straight.
fn curved_loops(
    model: &Model,
    s: &Surface,
    slot_of: &BTreeMap<usize, usize>,
    samples: &[Samples],
    loops: &[Vec<LoopPt>],
    tol: f64,
) -> Vec<Vec<(DVec2, bool)>> {
    let slot_edge: BTreeMap<usize, usize> = slot_of.iter().map(|(e, s)| (*s, *e)).collect();
    let halfway = |a: &LoopPt, b: &LoopPt| -> Option<DVec2> {
        let (slot, i, j) = trim::along_edge(model, slot_of, samples, a, b)?;
        let g = model.edges[*slot_edge.get(&slot)?].geometry.as_ref().ok()?;
        let t = 0.5 * (samples[slot].ts[i] + samples[slot].ts[j]);
        let p = g.curve.eval(t);
        let chord_mid = 0.5 * (a.uv + b.uv);
        let mut uv = s.param_of(p, Some(chord_mid));
        for (d, per) in s.periods().iter().enumerate() {
            if let Some(per) = per {
                uv[d] += per * ((chord_mid[d] - uv[d]) / per).round();
            }
        }
        let near = uv.distance(chord_mid) <= a.uv.distance(b.uv);
        let on = s.eval(uv.x, uv.y).distance(p) <= tol;
        (near && on).then_some(uv)
    };
    let uv: Vec<Vec<DVec2>> = loops
        .iter()
        .map(|lp| lp.iter().map(|p| p.uv).collect())
        .collect();
    loops
        .iter()
        .zip(reversed_by_nesting(&uv))
        .map(|(lp, rev)| {
            let n = lp.len();
            let mut out = Vec::with_capacity(2 * n);
            for k in 0..n {
                out.push((lp[k].uv, false));
                if n > 1
                    && let Some(m) = halfway(&lp[k], &lp[(k + 1) % n])
                {
                    out.push((m, true));
                }
            }
            if rev {
                out.reverse();
            }
            out
        })
        .collect()
}

/// The independent checks of one face (see [`crate::check`]): its triangles tile the region
/// its loops bound in (u, v), and their area agrees with the area of that region on the surface.
fn check_face(
    model: &Model,
    index: usize,
    s: &Surface,
    loops: &[Vec<DVec2>],
    trim_area: f64,
    tm: &TrimmedMesh,
    chord: f64,
) -> Result<(), StepError> {
    let region_uv: f64 = loops
        .iter()
        .map(|lp| {
            0.5 * (0..lp.len())
                .map(|k| lp[k].perp_dot(lp[(k + 1) % lp.len()]))
                .sum::<f64>()
        })
        .sum();
    let scale = loops
        .iter()
        .flatten()
        .fold(0.0f64, |a, p| a.max(p.abs().max_element()))
        .max(1.0);
    if (tm.cover_uv - region_uv).abs() > 1e-9 * region_uv.abs() + 1e-12 * scale * scale {
        return Err(face_err(
            model,
            index,
            format!(
                "its triangles cover {:.6} of its (u, v) domain's {region_uv:.6} ({:+.4} %): the face's region could not be built",
                tm.cover_uv,
                100.0 * (tm.cover_uv - region_uv) / region_uv.abs().max(f64::MIN_POSITIVE)
            ),
        ));
    }
    let flat = tm.mesh.area();
    let uv = tm.mesh.params.as_deref().unwrap_or(&[]);
    let allowance = AREA_REL + check::chordal_allowance(s, uv, chord);
    let tiny = 1e-9 * model.size_mm * model.size_mm;
    if (flat - trim_area).abs() > allowance * trim_area.abs() + tiny {
        return Err(face_err(
            model,
            index,
            format!(
                "its triangles have {flat:.4} mm², its trimmed domain {trim_area:.4} mm² ({:+.3} %, more than the {:.3} % the chordal tolerance allows)",
                100.0 * (flat - trim_area) / trim_area.abs().max(f64::MIN_POSITIVE),
                100.0 * allowance
            ),
        ));
    }
    Ok(())
}

/// The repairs of a face: its own, its edges', and those of its region.
fn face_repairs(model: &Model, index: usize, g: &FaceGeometry, t: &Trim) -> Vec<Repair> {
    let mut out = model.faces[index].repairs.clone();
    let mut seen = Vec::new();
    for u in g.bounds.iter().flat_map(|b| &b.uses) {
        if !seen.contains(&u.edge) {
            seen.push(u.edge);
            out.extend(model.edges[u.edge].repairs.iter().cloned());
        }
    }
    out.extend(t.repairs.iter().cloned());
    out
}

/// The rulings a developable face needs for the chordal tolerance `tol` and the normal's
/// largest turn `turn` (radians) across a strip, besides those through its loop points
/// (`have`, sorted): in every gap between those wider than the step the curvature allows, the
/// points of a fixed grid of that step or finer. The grid does not depend on where the face's
/// loops start in u (on a cylinder or a cone it is fractions of a turn from u = 0), so faces
/// about one axis share it.
fn chord_rulings(
    s: &Surface,
    loops: &[Vec<LoopPt>],
    have: &[f64],
    tol: f64,
    turn: f64,
) -> Vec<f64> {
    let Surface::Analytic(a) = s else {
        return Vec::new();
    };
    let (Some(&lo), Some(&hi)) = (have.first(), have.last()) else {
        return Vec::new();
    };
    let step_for = |radius: f64| {
        if radius > tol {
            (2.0 * (1.0 - tol / radius).acos()).min(turn)
        } else {
            f64::INFINITY
        }
    };
    let grid = |step: f64| -> Vec<f64> {
        if !(step.is_finite() && step > 0.0) {
            return Vec::new();
        }
        // A power of two of fractions of a turn, at least as fine as `step`: the grids of
        // faces about one axis, and the circles' samples (dyadic fractions of a turn, see
        // `sample_edge`), are then each other's subsets, so a stack of coaxial faces shares
        // its rulings instead of each adding its own between the others'.
        let n = (std::f64::consts::TAU / step).log2().ceil().exp2().max(8.0);
        if !(n.is_finite() && n >= 2.0) || (hi - lo) / step > 1e6 {
            return Vec::new();
        }
        let need = step;
        let step = std::f64::consts::TAU / n;
        let mut out = Vec::new();
        for w in have.windows(2) {
            if w[1] - w[0] <= need {
                continue;
            }
            let first = (w[0] / step).floor() as i64 + 1;
            let mut k = first;
            while (k as f64) * step < w[1] {
                out.push(k as f64 * step);
                k += 1;
            }
        }
        out
    };
    match &a.kind {
        AnalyticKind::Cylinder { radius } => grid(step_for(*radius)),
        AnalyticKind::Cone { .. } => {
            let rho = loops
                .iter()
                .flatten()
                .map(|p| {
                    let q = a.frame.local(p.pos);
                    q.x.hypot(q.y)
                })
                .fold(0.0, f64::max);
            grid(step_for(rho))
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

/// The rulings of a developable face: the u of its edge samples and those the tolerance needs.
/// Points the face added itself (cut lines, the runs along a pole, where every u is the same
/// point) are not rulings.
fn face_rulings(s: &Surface, loops: &[Vec<LoopPt>], tol: f64, turn: f64) -> (Vec<f64>, f64) {
    let mut us: Vec<f64> = Vec::new();
    for lp in loops {
        let n = lp.len();
        for (k, p) in lp.iter().enumerate() {
            let pole = n > 1
                && (lp[(k + 1) % n].origin == p.origin || lp[(k + n - 1) % n].origin == p.origin);
            if !pole && !matches!(p.origin, Origin::Extra(_)) {
                us.push(p.uv.x);
            }
        }
    }
    if us.is_empty() {
        us = loops.iter().flatten().map(|p| p.uv.x).collect();
    }
    let (lo, hi) = us
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &u| {
            (a.min(u), b.max(u))
        });
    let snap = RULING_SNAP_REL * (hi - lo).abs().max(f64::MIN_POSITIVE);
    let have = distinct(us, snap);
    let mut all = chord_rulings(s, loops, &have, tol, turn);
    all.extend(have);
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
    /// Tessellates the faces (indices into `model.faces`) to `tol.chord_mm`, and checks the
    /// result ([`crate::check`]).
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
        let chord = tol.chord_mm;
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
        let mut users: BTreeMap<usize, usize> = BTreeMap::new();
        for (i, g) in &geoms {
            for u in g.bounds.iter().flat_map(|b| &b.uses) {
                let n = slot_of.len();
                slot_of.entry(u.edge).or_insert(n);
                users.entry(u.edge).or_insert(*i);
            }
        }
        let mut slots: Vec<usize> = vec![0; slot_of.len()];
        for (&e, &s) in &slot_of {
            slots[s] = e;
        }
        let mut samples: Vec<Samples> = Vec::with_capacity(slots.len());
        for &e in &slots {
            let g = model.edges[e]
                .geometry
                .as_ref()
                .map_err(|err| face_err(model, users[&e], err.to_string()))?;
            samples.push(sample_edge(model, g, chord));
        }
        // Edges running through a pole get a point there (each round only adds such points;
        // a segment with its pole point asks for no other).
        let ruled: Vec<bool> = geoms
            .iter()
            .map(|(_, g)| g.surface.is_ruled_developable() && g.surface.name() != "plane")
            .collect();
        for _ in 0..MAX_POLE_ROUNDS {
            let mut changed = false;
            for (k, (i, g)) in geoms.iter().enumerate() {
                let t = face_trim(model, *i, g, &slot_of, &samples, ruled[k], None, chord)?;
                changed |= insert_samples(model, &slots, &mut samples, &t.wants);
            }
            if !changed {
                break;
            }
        }
        // The rulings of every developable face, from its own edge samples and the chordal
        // grid, all taken before any is put on an edge; then each ruling's crossings with its
        // face's edges are put on those edges, in one pass. A point a face gets from a
        // neighbour's ruling is not a ruling of its own (its strip's triangles take it as a
        // corner), so nothing passes back and forth between faces. A face too narrow for
        // such a point (its triangles, off the strip's plane, fail the face's check) takes the
        // points it got as rulings too, once, and all faces are meshed again: each face does
        // so at most once, so there are at most as many passes as developable faces, plus one.
        let mut rulings: Vec<Option<Vec<f64>>> = vec![None; geoms.len()];
        let mut takes_all = vec![false; geoms.len()];
        let mut pending: Vec<usize> = (0..geoms.len()).filter(|&k| ruled[k]).collect();
        let (positions, face_meshes, edges_out) = loop {
            let mut crossings: Vec<(usize, f64)> = Vec::new();
            for &k in &pending {
                let (i, g) = geoms[k];
                let t = face_trim(model, i, g, &slot_of, &samples, true, None, chord)?;
                let (own, snap) = face_rulings(&g.surface, &t.loops, chord, opts.max_normal_turn);
                crossings.extend(ruling_crossings(
                    model, g, &t.segs, &own, snap, &slots, &samples,
                ));
                rulings[k] = Some(own);
            }
            crossings.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
            crossings.dedup_by(|x, y| x.0 == y.0 && x.1 == y.1);
            insert_samples(model, &slots, &mut samples, &crossings);
            match mesh_faces(&Pass {
                model,
                geoms: &geoms,
                ruled: &ruled,
                rulings: &rulings,
                slots: &slots,
                slot_of: &slot_of,
                users: &users,
                samples: &samples,
                tol,
                opts,
            })? {
                Meshed::Done(p, f, e) => break (p, f, e),
                Meshed::Failed(k, err) => {
                    if takes_all[k] || !ruled[k] {
                        return Err(err);
                    }
                    takes_all[k] = true;
                    pending = vec![k];
                }
            }
        };
        let out = Tessellation {
            positions,
            faces: face_meshes,
            edges: edges_out,
        };
        for shell in model.shells.iter().filter(|sh| sh.closed) {
            if shell.faces.iter().all(|f| faces.contains(f)) {
                out.check_closed(model, shell)?;
            }
        }
        Ok(out)
    }

    /// One mesh of the faces (all when `faces` is `None`), welded at shared vertices, with only
    /// the vertices those faces use (in shell order).
    pub fn welded(&self, faces: Option<&[usize]>) -> TriMesh {
        self.welded_with_ids(faces).0
    }

    /// Open mesh edges of the welded closed shells whose faces are all tessellated here and
    /// whose topology closes them too (every model edge used twice; a file may flag an open
    /// shell closed): 0 for a crack-free tessellation.
    pub fn open_edges(&self, model: &Model) -> usize {
        let closed = |faces: &[usize]| {
            model.edges.iter().all(|e| {
                let uses = e.faces.iter().filter(|f| faces.contains(f)).count();
                uses == 0 || uses == 2
            })
        };
        model
            .shells
            .iter()
            .filter(|s| s.closed && s.faces.iter().all(|f| self.face(*f).is_some()))
            .filter(|s| closed(&s.faces))
            .map(|s| {
                let m = self.welded(Some(&s.faces));
                flatcut_mesh::Topology::build(&m).map_or(usize::MAX, |topo| {
                    topo.edges.values().filter(|e| e.is_boundary()).count()
                })
            })
            .sum()
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

    /// A closed shell's faces must weld into a closed, consistently oriented mesh: no edge open
    /// (an edge sampled differently on its two faces, a face missing a part) and none used
    /// twice the same way (a face that took the complement of its region). A check that shares
    /// nothing with the per-face ones: it sees the faces together.
    fn check_closed(&self, model: &Model, shell: &crate::model::Shell) -> Result<(), StepError> {
        let (mesh, new_id) = self.welded_with_ids(Some(&shell.faces));
        // Edges the file's own topology leaves free (one use in the shell: a shell flagged
        // closed that is not) may stay open; every other mesh edge must be shared.
        let mut free: std::collections::BTreeSet<(u32, u32)> = std::collections::BTreeSet::new();
        for e in &self.edges {
            let uses = model.edges[e.edge]
                .faces
                .iter()
                .filter(|f| shell.faces.contains(f))
                .count();
            if uses == 1 {
                for w in e.vertices.windows(2) {
                    let (a, b) = (new_id[w[0] as usize], new_id[w[1] as usize]);
                    free.insert((a.min(b), a.max(b)));
                }
            }
        }
        let refuse = |a: u32, b: u32, what: String| {
            let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            let at = 0.5 * (pa + pb);
            let faces: Vec<String> = self
                .faces
                .iter()
                .filter(|f| shell.faces.contains(&f.face))
                .filter(|f| {
                    let has = |p: DVec3| f.mesh.positions.iter().any(|q| q.distance(p) <= 1e-9);
                    has(pa) && has(pb)
                })
                .map(|f| format!("face {} (#{})", f.face, model.faces[f.face].entity))
                .collect();
            StepError::Entity {
                id: shell.entity,
                name: "CLOSED_SHELL".into(),
                message: format!(
                    "the tessellated faces do not close the shell: {what} at ({:.3}, {:.3}, {:.3}) mm{}",
                    at.x,
                    at.y,
                    at.z,
                    if faces.is_empty() {
                        String::new()
                    } else {
                        format!(", on {}", faces.join(" and "))
                    }
                ),
            }
        };
        let topo = match flatcut_mesh::Topology::build(&mesh) {
            Ok(t) => t,
            Err(flatcut_mesh::TopologyError::InconsistentOrientation { a, b, .. }) => {
                return Err(refuse(
                    a,
                    b,
                    "two faces run the same way along an edge".into(),
                ));
            }
            Err(flatcut_mesh::TopologyError::NonManifoldEdge { a, b, count }) => {
                return Err(refuse(a, b, format!("an edge bounds {count} triangles")));
            }
            Err(e) => {
                return Err(StepError::Entity {
                    id: shell.entity,
                    name: "CLOSED_SHELL".into(),
                    message: format!("the tessellated faces do not close the shell: {e}"),
                });
            }
        };
        let open: Vec<(u32, u32)> = topo
            .edges
            .iter()
            .filter(|(_, e)| e.is_boundary())
            .map(|(k, _)| *k)
            .filter(|&(a, b)| !free.contains(&(a.min(b), a.max(b))))
            .collect();
        if let Some(&(a, b)) = open.first() {
            let length: f64 = open
                .iter()
                .map(|&(a, b)| mesh.positions[a as usize].distance(mesh.positions[b as usize]))
                .sum();
            return Err(refuse(
                a,
                b,
                format!(
                    "{} edge(s) open, {length:.3} mm in all, the first",
                    open.len()
                ),
            ));
        }
        Ok(())
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
        let map = |ids: &[u32]| -> Vec<u32> { ids.iter().map(|&v| new_id[v as usize]).collect() };
        let mut seams: Vec<Vec<u32>> = self
            .edges
            .iter()
            .filter(|e| {
                let fs = &model.edges[e.edge].faces;
                fs.len() == 2 && fs[0] == fs[1] && faces.contains(&fs[0])
            })
            .map(|e| map(&e.vertices))
            .collect();
        for fm in self.faces.iter().filter(|f| faces.contains(&f.face)) {
            seams.extend(fm.cuts.iter().map(|c| map(c)));
        }
        flatcut_mesh::cut_to_disk(&mesh, &seams).unwrap_or(mesh)
    }
}

/// What meshing the faces from the edges' samples as they stand needs.
struct Pass<'a> {
    model: &'a Model,
    geoms: &'a [(usize, &'a FaceGeometry)],
    ruled: &'a [bool],
    rulings: &'a [Option<Vec<f64>>],
    slots: &'a [usize],
    slot_of: &'a BTreeMap<usize, usize>,
    users: &'a BTreeMap<usize, usize>,
    samples: &'a [Samples],
    tol: &'a Tolerances,
    opts: &'a TessOptions,
}

/// The meshes of a pass: shell positions, face meshes and edges, or the first face (index
/// into the pass's faces) that failed its check, with the error.
enum Meshed {
    Done(Vec<DVec3>, Vec<FaceMesh>, Vec<EdgeMesh>),
    Failed(usize, StepError),
}

/// Meshes every face of the pass from the edges' samples (see [`Tessellation::new`]).
fn mesh_faces(p: &Pass) -> Result<Meshed, StepError> {
    let Pass {
        model,
        ruled,
        rulings,
        slots,
        slot_of,
        users,
        samples,
        tol,
        opts,
        ..
    } = *p;
    let chord = tol.chord_mm;
    for (sl, &e) in slots.iter().enumerate() {
        if let Ok(g) = &model.edges[e].geometry
            && !g.degenerate
        {
            check::edge_length(g.curve.as_ref(), &samples[sl].ts, &samples[sl].pts, chord)
                .map_err(|m| {
                    face_err(
                        model,
                        users[&e],
                        format!("edge #{}: {m}", model.edges[e].entity),
                    )
                })?;
        }
    }
    // Shell vertex ids: model vertices, then edge samples in edge order.
    let mut positions: Vec<DVec3> = model.vertices.iter().map(|v| v.point).collect();
    let mut edges_out = Vec::new();
    let mut order: Vec<usize> = (0..slots.len()).collect();
    order.sort_by_key(|&s| slots[s]);
    let mut sample_id: Vec<Vec<u32>> = vec![Vec::new(); slots.len()];
    for &sl in &order {
        let g = model.edges[slots[sl]]
            .geometry
            .as_ref()
            .map_err(|e| face_err(model, users[&slots[sl]], e.to_string()))?;
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
        sample_id[sl] = ids;
    }
    // Faces.
    let mut face_meshes = Vec::with_capacity(p.geoms.len());
    for (k, (i, g)) in p.geoms.iter().enumerate() {
        // Own rulings a whole number of periods along too: the region's (u, v) may sit a
        // period from where the rulings were taken.
        let rulings = rulings[k]
            .as_deref()
            .map(|own| periodic_copies(&g.surface, own));
        let t = face_trim(
            model,
            *i,
            g,
            slot_of,
            samples,
            ruled[k],
            rulings.as_deref(),
            chord,
        )?;
        let first_extra = positions.len() as u32;
        positions.extend(t.extra.iter().copied());
        let id_of = |o: Origin| -> u32 {
            match o {
                Origin::Sample { slot, index } => sample_id[slot][index],
                Origin::Vertex(v) => v as u32,
                Origin::Extra(e) => first_extra + e as u32,
            }
        };
        let trim_pts: Vec<Vec<TrimPoint>> = t
            .loops
            .iter()
            .map(|lp| {
                lp.iter()
                    .map(|p| TrimPoint {
                        uv: p.uv,
                        pos: p.pos,
                        vertex: id_of(p.origin),
                    })
                    .collect()
            })
            .collect();
        let tm = tessellate_trimmed(
            &TrimmedFace {
                surface: g.surface.as_ref(),
                loops: &trim_pts,
                ruled: ruled[k],
                rulings: rulings.as_deref().unwrap_or(&[]),
            },
            tol,
            opts,
        )
        .map_err(|e| face_err(model, *i, e.to_string()))?;
        let oriented = oriented_by_nesting(&t.loops);
        let trim_area = check::trim_area(&g.surface, &oriented);
        if let Err(e) = check_face(model, *i, &g.surface, &oriented, trim_area, &tm, chord) {
            return Ok(Meshed::Failed(k, e));
        }
        let mut mesh = tm.mesh;
        if g.same_sense == t.flip {
            for tri in &mut mesh.triangles {
                tri.swap(1, 2);
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
            trim_area_mm2: trim_area,
            cuts: t
                .cuts
                .iter()
                .map(|c| c.iter().map(|&o| id_of(o)).collect())
                .collect(),
            repairs: face_repairs(model, *i, g, &t),
        });
    }
    Ok(Meshed::Done(positions, face_meshes, edges_out))
}

/// Adds samples at the curve parameters asked for (slot, t); true if any was added. A
/// parameter within [`SAME_SAMPLE_REL`] of the edge's range from a sample it has is that
/// sample (two faces about one axis find one ruling's crossing a rounding apart).
fn insert_samples(
    model: &Model,
    slots: &[usize],
    samples: &mut [Samples],
    wants: &[(usize, f64)],
) -> bool {
    let mut added = false;
    for &(slot, t) in wants {
        let Ok(eg) = &model.edges[slots[slot]].geometry else {
            continue;
        };
        let sm = &mut samples[slot];
        let increasing = sm.ts[sm.ts.len() - 1] > sm.ts[0];
        let pos = sm
            .ts
            .partition_point(|&x| if increasing { x < t } else { x > t });
        let same = SAME_SAMPLE_REL * (sm.ts[sm.ts.len() - 1] - sm.ts[0]).abs();
        if pos == 0
            || pos >= sm.ts.len()
            || (sm.ts[pos] - t).abs() <= same
            || (sm.ts[pos - 1] - t).abs() <= same
        {
            continue;
        }
        sm.ts.insert(pos, t);
        sm.pts.insert(pos, eg.curve.eval(t));
        added = true;
    }
    added
}

/// The points (slot, t) where the face's rulings cross its edge segments.
fn ruling_crossings(
    model: &Model,
    g: &FaceGeometry,
    segs: &[Seg],
    rulings: &[f64],
    snap: f64,
    slots: &[usize],
    samples: &[Samples],
) -> Vec<(usize, f64)> {
    let s = g.surface.as_ref();
    let mut out: Vec<(usize, f64)> = Vec::new();
    for sg in segs {
        let (ulo, uhi) = (sg.ua.min(sg.ub), sg.ua.max(sg.ub));
        let Ok(eg) = &model.edges[slots[sg.slot]].geometry else {
            continue;
        };
        let first = rulings.partition_point(|&r| r <= ulo + snap);
        for &r in rulings[first..].iter().take_while(|&&r| r < uhi - snap) {
            let ta = samples[sg.slot].ts[sg.i];
            let tb = samples[sg.slot].ts[sg.j];
            out.push((sg.slot, crossing(&eg.curve, s, (ta, sg.ua), (tb, sg.ub), r)));
        }
    }
    out
}

/// The rulings and their copies a whole period either way (a periodic u), sorted.
fn periodic_copies(s: &Surface, rulings: &[f64]) -> Vec<f64> {
    let Some(per) = s.periods()[0] else {
        return rulings.to_vec();
    };
    let mut out: Vec<f64> = (-2..=2)
        .flat_map(|k| rulings.iter().map(move |&r| r + k as f64 * per))
        .collect();
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}

/// The area of face `index` (mm²): the integral of |S_u × S_v| over the region its loops bound
/// (Green's theorem, [`check::trim_area_curved`]), with the loops sampled to `AREA_CHORD_REL` of
/// the model's size and followed along their edges' curves between the samples.
pub fn face_area(model: &Model, index: usize) -> Result<f64, StepError> {
    let g = model
        .face(index)
        .map_err(|e| face_err(model, index, e.to_string()))?;
    let tol = (AREA_CHORD_REL * model.size_mm).max(1e-9);
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
    let t = face_trim(model, index, g, &slot_of, &samples, false, None, tol)?;
    let loops = curved_loops(model, &g.surface, &slot_of, &samples, &t.loops, tol);
    Ok(check::trim_area_curved(&g.surface, &loops))
}
