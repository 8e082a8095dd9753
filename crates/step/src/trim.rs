//! The trimmed region of a face in its surface's (u, v): closed loops of points, each the point
//! of an edge sample (shared with the face across the edge), a point added on a cut line, or a
//! pole — built so that the region does not depend on where a loop starts, in which order its
//! edges are listed or how its flags are set.
//!
//! 1. Each loop is chained by its vertices: edges listed out of order or with a wrong
//!    orientation flag are put in order ([`crate::heal`] reports it).
//! 2. Each edge is mapped to (u, v) on its own, continuously along the edge (a pole's free
//!    parameter taken from its neighbours on the edge); an edge that runs through a pole is
//!    split there (the caller adds a sample at the pole).
//! 3. The edges are joined in the loop, each moved by whole periods to meet the previous one.
//!    Where two edges meet at a pole, the move is free: the loop runs along the pole's line, and
//!    the moves are chosen so the loop closes, with the orientation ISO 10303-42 gives it (the
//!    face on the left of its loops seen from the face's normal) — a seam edge used twice is
//!    then one period apart, whichever use comes first.
//! 4. A loop that winds once around a periodic surface (no seam edge: a band or a cap) is cut
//!    open along a line of constant u to the other loop or to the pole, the line sampled once
//!    and used on both of its sides.
//! 5. The other loops are moved by periods to lie inside the outer one.
//!
//! A face whose region cannot be built this way is refused, naming it.

use std::collections::BTreeMap;
use std::f64::consts::PI;

use flatcut_geom::{DVec2, DVec3};
use flatcut_surface::{ParamCurve, ParamSurface};

use crate::StepError;
use crate::edge_use::EdgeUse;
use crate::geom::{Curve, Surface};
use crate::heal::{Repair, RepairKind};
use crate::model::{Bound, EdgeGeometry, FaceGeometry, Model};

/// Angular step of the points of a pole run on a curved face (radians of the free parameter):
/// 64 per turn.
const POLE_STEP: f64 = PI / 32.0;
/// Most pole junctions whose moves are searched jointly in one loop (3 choices each).
const MAX_FREE_JUNCTIONS: usize = 7;
/// Candidate starts of a cut line tried before a face is refused.
const CUT_CANDIDATES: usize = 48;
/// Relative size (of a period) below which two parameters are one.
const SAME_PARAM_REL: f64 = 1e-9;

/// The samples of one edge from its start vertex to its end vertex (shared by its faces).
#[derive(Clone, Debug)]
pub(crate) struct Samples {
    pub ts: Vec<f64>,
    pub pts: Vec<DVec3>,
}

/// Where a loop point comes from: edge sample `index` of edge slot `slot`, a model vertex on no
/// edge of the face (a `VERTEX_LOOP`'s apex), or point `k` the face added (cut line, pole).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Origin {
    Sample { slot: usize, index: usize },
    Vertex(usize),
    Extra(usize),
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct LoopPt {
    pub uv: DVec2,
    pub pos: DVec3,
    pub origin: Origin,
    /// The edge slot the loop runs along from this point to the next, if it runs along one.
    pub along: Option<usize>,
}

/// A segment of a loop along one edge: samples `i` → `j` of edge slot `slot`, at `ua` → `ub`
/// (the u of both ends on the face, after the loop's moves).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Seg {
    pub slot: usize,
    pub i: usize,
    pub j: usize,
    pub ua: f64,
    pub ub: f64,
}

/// The region of a face: its loops, the edge segments they run along, the points it added.
#[derive(Clone, Debug, Default)]
pub(crate) struct Trim {
    pub loops: Vec<Vec<LoopPt>>,
    pub segs: Vec<Seg>,
    /// Positions of the points the face added (`Origin::Extra`).
    pub extra: Vec<DVec3>,
    /// Lines along which the face was cut open to be a region of the plane (each as its points,
    /// both sides being the same points): the piece is cut there again after welding.
    pub cuts: Vec<Vec<Origin>>,
    pub repairs: Vec<Repair>,
    /// Samples the face needs on its edges (where an edge runs through a pole): (slot, t).
    pub wants: Vec<(usize, f64)>,
    /// The face's normal is the opposite of what its `same_sense` says: its loops agree with
    /// the neighbours' (each shared edge used once each way) but run the wrong way round on its
    /// surface, so the flag is the one in error.
    pub flip: bool,
}

/// What building a face's region needs.
pub(crate) struct TrimInput<'a> {
    pub model: &'a Model,
    pub index: usize,
    pub face: &'a FaceGeometry,
    pub slot_of: &'a BTreeMap<usize, usize>,
    pub samples: &'a [Samples],
    /// The face is meshed along its rulings (lines of constant u): a line cutting it open must
    /// run along one, so the points of its two sides are the same.
    pub ruled: bool,
    /// The rulings of a ruled face, once its edges carry them: pole runs put their points on
    /// them, and a band's cut line must be found on one.
    pub rulings: Option<&'a [f64]>,
    /// Chordal tolerance for the points of cut lines (mm).
    pub chord: f64,
    /// The healing limit (mm).
    pub heal: f64,
    /// A point whose whole circle of one parameter is shorter than this is a pole (mm).
    pub pole_tol: f64,
}

impl TrimInput<'_> {
    fn err(&self, message: impl Into<String>) -> StepError {
        StepError::Face {
            index: self.index,
            entity: self.model.faces[self.index].entity,
            message: message.into(),
        }
    }

    fn surface(&self) -> &Surface {
        self.face.surface.as_ref()
    }

    fn geometry(&self, edge: usize) -> Result<&EdgeGeometry, StepError> {
        self.model.edges[edge]
            .geometry
            .as_ref()
            .map_err(|e| self.err(e.to_string()))
    }
}

/// A run of one edge in a loop, in (u, v) before the loop's moves, in the loop's direction.
#[derive(Clone, Debug)]
struct Part {
    /// The edge's instance number (for messages).
    edge: u64,
    pts: Vec<LoopPt>,
    /// The free direction at the start and at the end (the point is a pole).
    free_start: Option<usize>,
    free_end: Option<usize>,
}

/// The region of face `inp.index`.
pub(crate) fn build(inp: &TrimInput) -> Result<Trim, StepError> {
    let s = inp.surface();
    let periods = s.periods();
    let sigma = if inp.face.same_sense { 1.0 } else { -1.0 };
    let mut trim = Trim::default();
    let mut cache: BTreeMap<usize, Vec<DVec2>> = BTreeMap::new();
    let mut placed: Vec<(Vec<LoopPt>, [i64; 2])> = Vec::new();
    for b in &inp.face.bounds {
        if b.uses.is_empty() {
            continue;
        }
        let uses = chain(inp, b, &mut trim.repairs)?;
        let mut parts: Vec<Part> = Vec::new();
        for u in &uses {
            edge_parts(inp, *u, &mut cache, &mut parts, &mut trim)?;
        }
        if parts.is_empty() {
            continue;
        }
        let (lp, winding) = join(inp, &parts, periods, sigma)?;
        placed.push((lp, winding));
    }
    if placed.is_empty() && inp.face.bounds.iter().any(|b| !b.uses.is_empty()) {
        return Err(
            inp.err("every loop of the face is a slit (edges out and back): it bounds no region")
        );
    }
    if placed.is_empty() {
        let lp = whole_surface(inp, &[], &mut trim)?;
        placed.push((lp, [0, 0]));
    }
    let mut loops = close_windings(inp, placed, periods, sigma, &mut trim)?;
    if !loops.iter().any(|lp| signed_area(lp) * sigma > 0.0) {
        outer_for_holes(inp, &mut loops, sigma, &mut trim)?;
    }
    let loops = place_loops(loops, periods);
    trim.loops = loops
        .into_iter()
        .map(|lp| fill_poles(lp, inp.rulings))
        .collect();
    trim.segs = segments(inp, &trim.loops);
    trim.repairs.sort_by(|a, b| {
        (a.entity, a.kind as u8)
            .cmp(&(b.entity, b.kind as u8))
            .then(b.mm.total_cmp(&a.mm))
    });
    trim.repairs
        .dedup_by(|a, b| a.entity == b.entity && a.kind == b.kind);
    Ok(trim)
}

/// The loop's edge uses chained by their vertices ([`crate::heal::chain_uses`]); a change of
/// the file's order or flags is reported.
fn chain(inp: &TrimInput, b: &Bound, repairs: &mut Vec<Repair>) -> Result<Vec<EdgeUse>, StepError> {
    for u in &b.uses {
        inp.geometry(u.edge)?;
    }
    let out = crate::heal::chain_uses(inp.model, &b.uses);
    if out != b.uses {
        repairs.push(Repair::new(
            RepairKind::LoopOrder,
            b.entity,
            0.0,
            "the loop's edges are out of order or flagged the wrong way: chained by their vertices",
        ));
    }
    Ok(without_slits(inp, out, repairs))
}

/// The loop without its slits: an edge used out and back by consecutive uses (cyclically),
/// turning at a point that is not a pole, bounds nothing — the face lies on both sides of it
/// (an internal edge, as some systems write where a face was split and merged again). Both uses
/// are dropped, repeatedly, so a loop made only of slits becomes empty. An edge out to a pole
/// and back (a sphere's seam where no pole edge is written) is kept: the pole closes the region.
fn without_slits(
    inp: &TrimInput,
    mut uses: Vec<EdgeUse>,
    repairs: &mut Vec<Repair>,
) -> Vec<EdgeUse> {
    let s = inp.surface();
    loop {
        let n = uses.len();
        let slit = (0..n).find(|&k| {
            let (a, b) = (uses[k], uses[(k + 1) % n]);
            if n < 2 || a.edge != b.edge || a.forward == b.forward {
                return false;
            }
            let Ok(g) = inp.geometry(a.edge) else {
                return false;
            };
            let turn = if a.forward { g.end } else { g.start };
            let p = inp.model.vertices[turn].point;
            s.free_direction(s.param_of(p, None), inp.pole_tol)
                .is_none()
        });
        let Some(k) = slit else {
            return uses;
        };
        let edge = uses[k].edge;
        repairs.push(Repair::new(
            RepairKind::Slit,
            inp.model.edges[edge].entity,
            0.0,
            "the loop runs out and back along this edge (a slit inside the face): dropped from the loop",
        ));
        let next = (k + 1) % n;
        let (hi, lo) = (k.max(next), k.min(next));
        uses.remove(hi);
        uses.remove(lo);
    }
}

/// The (u, v) of an edge's samples on the face, continuous along the edge, from its start.
fn edge_uv(inp: &TrimInput, slot: usize, g: &EdgeGeometry) -> Vec<DVec2> {
    let s = inp.surface();
    let sm = &inp.samples[slot];
    let pc = match s {
        Surface::Spline(_) => pcurve(g, inp.face.surface_entity),
        Surface::Analytic(_) => None,
    };
    let mut out: Vec<DVec2> = Vec::with_capacity(sm.pts.len());
    for (k, p) in sm.pts.iter().enumerate() {
        let hint = match (pc, out.last()) {
            (Some(c), _) => Some(s.from_file(c.eval(sm.ts[k]).truncate())),
            (None, last) => last.copied(),
        };
        let mut uv = s.param_of(*p, hint);
        // A pcurve may sit a period away from the previous point: continue from it.
        if let Some(l) = out.last() {
            for (d, per) in s.periods().iter().enumerate() {
                if let Some(per) = per {
                    uv[d] += per * ((l[d] - uv[d]) / per).round();
                }
            }
        }
        out.push(uv);
    }
    out
}

/// The pcurve of `g` on the surface (the first, for a seam: continuity fixes the period).
fn pcurve(g: &EdgeGeometry, surface_entity: u64) -> Option<&Curve> {
    g.pcurves
        .iter()
        .find(|p| p.surface_entity == surface_entity)
        .map(|p| p.curve.as_ref())
}

/// Appends the parts of one edge use: the edge's points in (u, v) in the use's direction, split
/// where the edge runs through a pole.
fn edge_parts(
    inp: &TrimInput,
    u: EdgeUse,
    cache: &mut BTreeMap<usize, Vec<DVec2>>,
    parts: &mut Vec<Part>,
    trim: &mut Trim,
) -> Result<(), StepError> {
    let g = inp.geometry(u.edge)?;
    let s = inp.surface();
    let slot = inp.slot_of[&u.edge];
    let sm = &inp.samples[slot];
    let n = sm.pts.len();
    if g.degenerate {
        // A degenerate edge (at a pole): the loop runs along the pole there; nothing to add.
        return Ok(());
    }
    let uvs = match cache.get(&slot) {
        Some(v) => v.clone(),
        None => {
            let v = edge_uv(inp, slot, g);
            // The distance of the edge from the surface: healed within the limit.
            let gap = v
                .iter()
                .zip(&sm.pts)
                .map(|(w, p)| s.eval(w.x, w.y).distance(*p))
                .fold(
                    0.0,
                    |a: f64, x| if x.is_nan() { f64::INFINITY } else { a.max(x) },
                );
            let entity = inp.model.edges[u.edge].entity;
            if gap > inp.heal {
                return Err(inp.err(format!(
                    "edge #{entity} is {gap:.3} mm from the face's surface (more than the healing limit, {:.3} mm; see --heal-tolerance)",
                    inp.heal
                )));
            }
            if gap > crate::heal::REPORT_MM {
                trim.repairs.push(Repair::new(
                    RepairKind::EdgeOffSurface,
                    entity,
                    gap,
                    format!(
                        "the edge lies up to {gap:.4} mm off the face's surface: its points are kept, the face's tolerance grown to {gap:.4} mm"
                    ),
                ));
            }
            cache.insert(slot, v.clone());
            v
        }
    };
    // Points in the edge's direction, with the free direction of each.
    let free: Vec<Option<usize>> = uvs
        .iter()
        .map(|w| s.free_direction(*w, inp.pole_tol))
        .collect();
    let mut uvs = uvs;
    // A pole point takes its free parameter from its neighbours on the edge; where they differ
    // the edge runs through the pole and is split there.
    let mut splits: Vec<usize> = Vec::new();
    let mut k = 0;
    while k < n {
        let Some(d) = free[k] else {
            k += 1;
            continue;
        };
        let run_end = (k..n).find(|&j| free[j].is_none()).unwrap_or(n);
        let before = (k > 0).then(|| uvs[k - 1][d]);
        let after = (run_end < n).then(|| uvs[run_end][d]);
        match (before, after) {
            (Some(a), Some(b)) if (a - b).abs() > 1e-9 * (1.0 + a.abs()) => {
                for j in k..run_end {
                    uvs[j][d] = a;
                }
                splits.push(run_end - 1);
            }
            (Some(a), _) | (None, Some(a)) => {
                for j in k..run_end {
                    uvs[j][d] = a;
                }
            }
            (None, None) => {}
        }
        k = run_end;
    }
    // An edge that passes a pole between two samples: ask for a sample there.
    want_pole_samples(inp, slot, g, &uvs, &free, trim);
    // The ends are the model's vertices (shared with the next edge of the loop).
    let pts: Vec<LoopPt> = (0..n)
        .map(|k| LoopPt {
            uv: uvs[k],
            pos: sm.pts[k],
            origin: if k == 0 {
                Origin::Vertex(g.start)
            } else if k == n - 1 {
                Origin::Vertex(g.end)
            } else {
                Origin::Sample { slot, index: k }
            },
            along: Some(slot),
        })
        .collect();
    let mut cuts: Vec<usize> = vec![0];
    cuts.extend(splits.iter().copied());
    cuts.push(n - 1);
    let mut runs: Vec<Part> = Vec::new();
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let mut seg: Vec<LoopPt> = pts[a..=b].to_vec();
        // Beyond a split, the pole point takes the parameter of the side it starts.
        if a > 0
            && b > a
            && let Some(d) = free[a]
        {
            seg[0].uv[d] = pts[a + 1].uv[d];
        }
        runs.push(Part {
            edge: inp.model.edges[u.edge].entity,
            pts: seg,
            free_start: free[a],
            free_end: free[b],
        });
    }
    if !u.forward {
        runs.reverse();
        for r in &mut runs {
            r.pts.reverse();
            std::mem::swap(&mut r.free_start, &mut r.free_end);
        }
    }
    // A part's last point leads on to the next part, not along this edge.
    for r in &mut runs {
        if let Some(last) = r.pts.last_mut() {
            last.along = None;
        }
    }
    parts.extend(runs);
    Ok(())
}

/// Where consecutive samples of an edge jump by more than a quarter turn in a periodic
/// parameter next to a pole, the edge crosses the pole between them: asks for a sample at the
/// curve's point nearest the pole.
fn want_pole_samples(
    inp: &TrimInput,
    slot: usize,
    g: &EdgeGeometry,
    uvs: &[DVec2],
    free: &[Option<usize>],
    trim: &mut Trim,
) {
    let s = inp.surface();
    let Some(per) = s.periods()[0] else { return };
    let sm = &inp.samples[slot];
    for k in 0..uvs.len().saturating_sub(1) {
        if free[k].is_some() || free[k + 1].is_some() {
            continue;
        }
        if (uvs[k + 1].x - uvs[k].x).abs() < 0.25 * per {
            continue;
        }
        let v = 0.5 * (uvs[k].y + uvs[k + 1].y);
        let Some(pv) = s
            .pole_beyond(v, true, inp.pole_tol)
            .into_iter()
            .chain(s.pole_beyond(v, false, inp.pole_tol))
            .min_by(|a, b| (a - v).abs().total_cmp(&(b - v).abs()))
        else {
            continue;
        };
        let pole = s.eval(uvs[k].x, pv);
        let (mut a, mut b) = (sm.ts[k], sm.ts[k + 1]);
        // Golden-section search of the distance to the pole on (a, b).
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let c = b - gr * (b - a);
            let d = a + gr * (b - a);
            if g.curve.eval(c).distance(pole) < g.curve.eval(d).distance(pole) {
                b = d;
            } else {
                a = c;
            }
        }
        let t = 0.5 * (a + b);
        if g.curve.eval(t).distance(pole) <= inp.pole_tol.max(1e-6) {
            trim.wants.push((slot, t));
        }
    }
}

/// Joins the parts of a loop into one closed loop in the parameter plane (moving each by whole
/// periods; at poles choosing the move that closes the loop the right way round); returns the
/// loop and its winding (in periods, per direction: not zero for a loop that goes around).
fn join(
    inp: &TrimInput,
    parts: &[Part],
    periods: [Option<f64>; 2],
    sigma: f64,
) -> Result<(Vec<LoopPt>, [i64; 2]), StepError> {
    let n = parts.len();
    // The free direction at each junction (end of part k → start of part k + 1).
    let free: Vec<Option<usize>> = (0..n)
        .map(|k| parts[k].free_end.or(parts[(k + 1) % n].free_start))
        .collect();
    let step = |from: DVec2, to: DVec2, d: usize| -> i64 {
        periods[d].map_or(0, |p| ((from[d] - to[d]) / p).round() as i64)
    };
    // Consecutive edges must meet (the reader merged the vertices of gaps within the limit).
    for k in 0..n {
        let (a, b) = (&parts[k], &parts[(k + 1) % n]);
        let (Some(end), Some(start)) = (a.pts.last(), b.pts.first()) else {
            continue;
        };
        let gap = end.pos.distance(start.pos);
        if gap > inp.heal {
            return Err(inp.err(format!(
                "a gap of {gap:.3} mm between consecutive edges #{} and #{} of a loop (more than the healing limit, {:.3} mm; see --heal-tolerance)",
                a.edge, b.edge, inp.heal
            )));
        }
    }
    let free_js: Vec<usize> = (0..n).filter(|&k| free[k].is_some()).collect();
    // Candidate moves at the free junctions: the nearest period and one either side.
    let choices: Vec<Vec<i64>> = free_js
        .iter()
        .map(|&k| {
            let d = free[k].unwrap_or(0);
            if periods[d].is_none() {
                vec![0]
            } else {
                vec![-1, 0, 1]
            }
        })
        .collect();
    let combos: usize = if free_js.len() > MAX_FREE_JUNCTIONS {
        1
    } else {
        choices.iter().map(Vec::len).product()
    };
    let mut best: Option<(Vec<LoopPt>, [i64; 2], (u8, u8, f64))> = None;
    for c in 0..combos {
        // Decode combination c into one choice per free junction.
        let mut pick: BTreeMap<usize, i64> = BTreeMap::new();
        let mut rest = c;
        for (i, &k) in free_js.iter().enumerate() {
            let ch = &choices[i];
            let off = if combos == 1 { 0 } else { ch[rest % ch.len()] };
            rest /= ch.len().max(1);
            pick.insert(k, off);
        }
        let mut lp: Vec<LoopPt> = Vec::new();
        let mut shift = [0i64; 2];
        let mut run_len = 0.0;
        for k in 0..n {
            let part = &parts[k];
            let mv = |p: &LoopPt| {
                let mut q = *p;
                for d in 0..2 {
                    if let Some(per) = periods[d] {
                        q.uv[d] += per * shift[d] as f64;
                    }
                }
                q
            };
            for (i, p) in part.pts.iter().enumerate() {
                let q = mv(p);
                if i == 0
                    && let Some(last) = lp.last_mut()
                    && last.origin == q.origin
                    && free[(k + n - 1) % n].is_none()
                {
                    last.along = q.along;
                    continue;
                }
                lp.push(q);
            }
            // The move of the next part.
            let next = &parts[(k + 1) % n];
            let end = lp.last().map(|p| p.uv).unwrap_or_default();
            let start = next.pts[0].uv;
            let mut new_shift = shift;
            for (d, ns) in new_shift.iter_mut().enumerate() {
                let base = step(end, start + per_shift(periods, shift, d), d);
                *ns = shift[d] + base;
            }
            if let Some(d) = free[k] {
                new_shift[d] += pick.get(&k).copied().unwrap_or(0);
                let to = start[d] + periods[d].unwrap_or(0.0) * new_shift[d] as f64;
                run_len += (to - end[d]).abs();
            }
            shift = new_shift;
        }
        // `shift` is now the move of part 0 after going once around: the winding.
        let winding = shift;
        // Drop the repeated first point of a closed loop; of a loop going around, the first
        // point again a period along (the loop's next point after its last).
        if lp.len() > 1 && free[n - 1].is_none() {
            let (a, z) = (lp[0], lp[lp.len() - 1]);
            let again =
                a.uv + (0..2).fold(DVec2::ZERO, |acc, d| acc + per_shift(periods, winding, d));
            if a.origin == z.origin
                && (winding == [0, 0] || z.uv.distance(again) <= 1e-9 * (1.0 + again.length()))
            {
                lp.pop();
            }
        }
        let area = signed_area(&lp);
        let degenerate = area.abs() <= 1e-12 * (1.0 + bbox_area(&lp));
        let score = (
            u8::from(winding != [0, 0]),
            u8::from(degenerate) * 2 + u8::from(area * sigma < 0.0 && !free_js.is_empty()),
            run_len,
        );
        if best.as_ref().is_none_or(|b| {
            (score.0, score.1)
                .cmp(&(b.2.0, b.2.1))
                .then(score.2.total_cmp(&b.2.2))
                .is_lt()
        }) {
            best = Some((lp, winding, score));
        }
    }
    let (lp, winding, _) = best.ok_or_else(|| inp.err("a loop has no points"))?;
    if lp.len() < 2 {
        return Err(inp.err("a loop has fewer than 2 distinct points"));
    }
    Ok((lp, winding))
}

/// The (u, v) move of `shift` periods, in direction `d` only.
fn per_shift(periods: [Option<f64>; 2], shift: [i64; 2], d: usize) -> DVec2 {
    let mut out = DVec2::ZERO;
    if let Some(p) = periods[d] {
        out[d] = p * shift[d] as f64;
    }
    out
}

pub(crate) fn signed_area(lp: &[LoopPt]) -> f64 {
    let n = lp.len();
    (0..n)
        .map(|k| lp[k].uv.perp_dot(lp[(k + 1) % n].uv))
        .sum::<f64>()
        * 0.5
}

fn bbox(lp: &[LoopPt]) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in lp {
        lo = lo.min(p.uv);
        hi = hi.max(p.uv);
    }
    (lo, hi)
}

fn bbox_area(lp: &[LoopPt]) -> f64 {
    let (lo, hi) = bbox(lp);
    let d = hi - lo;
    (d.x * d.y).abs()
}

/// Loops that wind around a periodic direction (no seam edge) made closed: one winding loop
/// is cut along a line of constant u to the pole its region reaches (a cap), two winding the
/// opposite ways are joined by a line between them (a band). Others are returned as they are.
fn close_windings(
    inp: &TrimInput,
    loops: Vec<(Vec<LoopPt>, [i64; 2])>,
    periods: [Option<f64>; 2],
    sigma: f64,
    trim: &mut Trim,
) -> Result<Vec<Vec<LoopPt>>, StepError> {
    let (winding, closed): (Vec<_>, Vec<_>) = loops.into_iter().partition(|(_, w)| *w != [0, 0]);
    let mut closed: Vec<Vec<LoopPt>> = closed.into_iter().map(|(l, _)| l).collect();
    if winding.is_empty() {
        return Ok(closed);
    }
    let name = inp.surface().name();
    let unsupported = || {
        inp.err(format!(
            "its loops wind around the {name} in a way that bounds no region flatcut can build ({} loop(s) going around)",
            winding.len()
        ))
    };
    // Every winding loop goes once around u (and not around v).
    if winding.iter().any(|(_, w)| w[1] != 0 || w[0].abs() != 1) {
        return Err(unsupported());
    }
    let Some(per) = periods[0] else {
        return Err(unsupported());
    };
    match winding.len() {
        1 => {
            let (lp, w) = &winding[0];
            let up = (w[0] > 0) == (sigma > 0.0);
            let main = cap(inp, lp, w[0], up, per, &mut closed, trim)?;
            closed.insert(0, main);
            Ok(closed)
        }
        2 if winding[0].1[0] != winding[1].1[0] => {
            // The loop whose region lies above it (east-going with the face on its left) is the
            // lower one.
            let (mut lower, mut upper) = (&winding[0], &winding[1]);
            if (lower.1[0] > 0) != (sigma > 0.0) {
                std::mem::swap(&mut lower, &mut upper);
            }
            let mid =
                |lp: &[LoopPt]| lp.iter().map(|p| p.uv.y).sum::<f64>() / lp.len().max(1) as f64;
            if mid(&lower.0) > mid(&upper.0) {
                trim.repairs.push(Repair::new(
                    RepairKind::Orientation,
                    inp.model.faces[inp.index].entity,
                    0.0,
                    "the face's loops are oriented as if it were the outside of the band they bound: the band between them is used",
                ));
                std::mem::swap(&mut lower, &mut upper);
            }
            let main = band(inp, &lower.0, lower.1[0], &upper.0, per, &closed, trim)?;
            closed.insert(0, main);
            Ok(closed)
        }
        _ => Err(unsupported()),
    }
}

/// The points of the straight (u, v) segment from `a` to `b` on the surface, within the chordal
/// tolerance, ends excluded; added to the face's points.
fn cut_points(inp: &TrimInput, a: DVec2, b: DVec2, trim: &mut Trim) -> Vec<(DVec2, usize)> {
    let s = inp.surface();
    #[derive(Debug)]
    struct Line<'s> {
        s: &'s Surface,
        a: DVec2,
        b: DVec2,
    }
    impl ParamCurve for Line<'_> {
        fn domain(&self) -> (f64, f64) {
            (0.0, 1.0)
        }
        fn eval(&self, t: f64) -> DVec3 {
            let q = self.a + (self.b - self.a) * t;
            self.s.eval(q.x, q.y)
        }
        fn deriv(&self, t: f64, k: usize) -> DVec3 {
            let q = self.a + (self.b - self.a) * t;
            let d = self.b - self.a;
            match k {
                0 => self.s.eval(q.x, q.y),
                1 => {
                    let (_, su, sv) = self.s.deriv1(q.x, q.y);
                    su * d.x + sv * d.y
                }
                _ => {
                    let dd = self.s.deriv2(q.x, q.y);
                    dd.suu * (d.x * d.x) + dd.suv * (2.0 * d.x * d.y) + dd.svv * (d.y * d.y)
                }
            }
        }
    }
    let line = Line { s, a, b };
    let pts = flatcut_surface::curve::flatten_with_breaks(&line, inp.chord, &[0.0, 1.0]);
    let mut out = Vec::new();
    for (t, p) in pts.iter().skip(1).take(pts.len().saturating_sub(2)) {
        trim.extra.push(*p);
        out.push((a + (b - a) * *t, trim.extra.len() - 1));
    }
    out
}

/// A polyline of the parameter plane (closed: its last point joins its first).
struct Poly {
    pts: Vec<DVec2>,
    closed: bool,
}

/// The polylines a cut line must not cross: each winding loop unrolled once from its first
/// point (open), and every loop, a few periods either way.
fn obstacles(winding: &[(&[LoopPt], i64)], closed: &[Vec<LoopPt>], per: f64) -> Vec<Poly> {
    let mut out = Vec::new();
    for k in -2..=2 {
        let sh = DVec2::new(per * k as f64, 0.0);
        for (lp, w) in winding {
            let mut pts: Vec<DVec2> = lp.iter().map(|p| p.uv + sh).collect();
            if let Some(first) = lp.first() {
                pts.push(first.uv + sh + DVec2::new(per * *w as f64, 0.0));
            }
            out.push(Poly { pts, closed: false });
        }
        for lp in closed {
            out.push(Poly {
                pts: lp.iter().map(|p| p.uv + sh).collect(),
                closed: true,
            });
        }
    }
    out
}

/// Whether the segment (a, b) crosses any segment of the polylines properly (segments that
/// only touch its end points aside).
fn crosses(a: DVec2, b: DVec2, polys: &[Poly]) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let eps = 1e-12 * (1.0 + a.length() + b.length());
    for poly in polys {
        let n = poly.pts.len();
        let segs = if poly.closed { n } else { n.saturating_sub(1) };
        for k in 0..segs {
            let (c, d) = (poly.pts[k], poly.pts[(k + 1) % n]);
            if [c, d]
                .iter()
                .any(|x| x.distance(a) <= eps || x.distance(b) <= eps)
            {
                continue;
            }
            let (o1, o2) = (orient(a, b, c), orient(a, b, d));
            let (o3, o4) = (orient(c, d, a), orient(c, d, b));
            if o1 * o2 <= 0.0 && o3 * o4 <= 0.0 && (o1 != 0.0 || o2 != 0.0) {
                return true;
            }
        }
    }
    false
}

/// Moves a closed loop by whole periods in u so that its u range lies within (lo, lo + per);
/// false when it is wider than that window there.
fn fit_between(lp: &mut [LoopPt], lo: f64, per: f64) -> bool {
    let (a, b) = bbox(lp);
    let k = ((lo - a.x) / per).ceil();
    let shift = per * k;
    if a.x + shift <= lo || b.x + shift >= lo + per {
        return false;
    }
    for p in lp.iter_mut() {
        p.uv.x += shift;
    }
    true
}

/// The loop once around from point `start`, its points past the end moved by `wrap` in u (the
/// loop's winding), ending on the start's copy.
fn around_from(lp: &[LoopPt], start: usize, wrap: f64) -> Vec<LoopPt> {
    let n = lp.len();
    (0..=n)
        .map(|k| {
            let mut p = lp[(start + k) % n];
            if start + k >= n {
                p.uv.x += wrap;
            }
            if k == n {
                p.along = None;
            }
            p
        })
        .collect()
}

/// The points of a cut line moved by `shift` in (u, v), forwards or backwards.
fn line_points(trim: &Trim, line: &[(DVec2, usize)], shift: DVec2, backwards: bool) -> Vec<LoopPt> {
    let pt = |&(q, e): &(DVec2, usize)| LoopPt {
        uv: q + shift,
        pos: trim.extra[e],
        origin: Origin::Extra(e),
        along: None,
    };
    if backwards {
        line.iter().rev().map(pt).collect()
    } else {
        line.iter().map(pt).collect()
    }
}

/// Records a cut line from `from` through the line's points to `to`.
fn record_cut(trim: &mut Trim, from: Origin, line: &[(DVec2, usize)], to: Origin) {
    let mut cut = vec![from];
    cut.extend(line.iter().map(|&(_, e)| Origin::Extra(e)));
    cut.push(to);
    trim.cuts.push(cut);
}

/// A cap: the winding loop `lp` (going `w` = ±1 times around u) closed through the pole on its
/// region's side by a cut line at the u of one of its points.
fn cap(
    inp: &TrimInput,
    lp: &[LoopPt],
    w: i64,
    up: bool,
    per: f64,
    holes: &mut [Vec<LoopPt>],
    trim: &mut Trim,
) -> Result<Vec<LoopPt>, StepError> {
    let s = inp.surface();
    let extreme = if up {
        lp.iter().map(|p| p.uv.y).fold(f64::NEG_INFINITY, f64::max)
    } else {
        lp.iter().map(|p| p.uv.y).fold(f64::INFINITY, f64::min)
    };
    let Some(pole_v) = s.pole_beyond(extreme, up, inp.pole_tol) else {
        return Err(inp.err(format!(
            "a loop winds once around the {} and nothing closes the region on its {} side (no seam edge and no pole)",
            s.name(),
            if up { "upper" } else { "lower" }
        )));
    };
    // Anchor candidates: the points nearest the pole first.
    let mut order: Vec<usize> = (0..lp.len()).collect();
    order.sort_by(|&a, &b| {
        let (x, y) = (lp[a].uv.y, lp[b].uv.y);
        if up { y.total_cmp(&x) } else { x.total_cmp(&y) }
    });
    for &ai in order.iter().take(CUT_CANDIDATES) {
        let a = lp[ai].uv;
        // The holes must fit beside the cut line, and the line must not cross the loop.
        let mut moved: Vec<Vec<LoopPt>> = holes.to_vec();
        if !moved.iter_mut().all(|h| fit_between(h, a.x, per)) {
            continue;
        }
        let top = DVec2::new(a.x, pole_v);
        if crosses(a, top, &obstacles(&[(lp, w)], &moved, per)) {
            continue;
        }
        holes.clone_from_slice(&moved);
        let wp = per * w as f64;
        // Around once from the anchor.
        let mut out = around_from(lp, ai, wp);
        // Up the cut line at u + w·per, along the pole, and down at u.
        let line = cut_points(inp, a, top, trim);
        let pole_pos = s.eval(a.x, pole_v);
        let pole_origin = vertex_at(inp, pole_pos).unwrap_or_else(|| {
            trim.extra.push(pole_pos);
            Origin::Extra(trim.extra.len() - 1)
        });
        out.extend(line_points(trim, &line, DVec2::new(wp, 0.0), false));
        for uv in [top + DVec2::new(wp, 0.0), top] {
            out.push(LoopPt {
                uv,
                pos: pole_pos,
                origin: pole_origin,
                along: None,
            });
        }
        out.extend(line_points(trim, &line, DVec2::ZERO, true));
        record_cut(trim, lp[ai].origin, &line, pole_origin);
        // The anchor's copy a period on closes the loop against the first point: drop it.
        return Ok(dedup_closing(out));
    }
    Err(inp.err(format!(
        "a loop winds once around the {} and no line from it to the pole clears the face's other loops",
        s.name()
    )))
}

/// Loops that are all holes (the face on their outside): on a closed surface (a sphere, a torus,
/// a closed patch) the face is the whole surface but the holes, its cut lines placed clear of
/// them; on an open surface the loops are oriented the wrong way round, and the largest is
/// reversed to be the outer one (reported).
fn outer_for_holes(
    inp: &TrimInput,
    loops: &mut Vec<Vec<LoopPt>>,
    sigma: f64,
    trim: &mut Trim,
) -> Result<(), StepError> {
    let closed = whole_surface_closes(inp);
    if closed {
        let outer = whole_surface(inp, loops, trim)?;
        loops.insert(0, outer);
        return Ok(());
    }
    let Some(k) = (0..loops.len()).max_by(|&a, &b| {
        signed_area(&loops[a])
            .abs()
            .total_cmp(&signed_area(&loops[b]).abs())
    }) else {
        return Ok(());
    };
    if signed_area(&loops[k]) * sigma == 0.0 {
        return Err(inp.err("its outer loop bounds no area"));
    }
    let face = &inp.model.faces[inp.index];
    if shares_edges(inp) {
        trim.flip = true;
        trim.repairs.push(Repair::new(
            RepairKind::Orientation,
            face.entity,
            0.0,
            "the face's loops run the wrong way round on its surface but agree with its neighbours': its normal is the opposite of its same_sense flag",
        ));
        return Ok(());
    }
    reverse_loop(&mut loops[k]);
    trim.repairs.push(Repair::new(
        RepairKind::Orientation,
        face.entity,
        0.0,
        "the face's outer loop runs the wrong way round (the face on its outside, on a surface that does not close): reversed",
    ));
    Ok(())
}

/// Whether the surface closes on itself so that a face may be all of it but holes: periodic in
/// u and either periodic in v or closed at a pole at both ends.
/// True when an edge of the face's loops is used by another face too: the loops' directions
/// are then fixed by the shell (the reader oriented them against their neighbours').
fn shares_edges(inp: &TrimInput) -> bool {
    inp.face.bounds.iter().flat_map(|b| &b.uses).any(|u| {
        inp.model.edges[u.edge]
            .faces
            .iter()
            .any(|&f| f != inp.index)
    })
}

fn whole_surface_closes(inp: &TrimInput) -> bool {
    let s = inp.surface();
    let d = s.domain();
    match s.periods() {
        [Some(_), Some(_)] => true,
        [Some(_), None] => {
            let v_mid = 0.5 * (d.v.0 + d.v.1);
            s.pole_beyond(v_mid, false, inp.pole_tol).is_some()
                && s.pole_beyond(v_mid, true, inp.pole_tol).is_some()
        }
        _ => false,
    }
}

/// A loop run the other way, each point still leading along the edge it led along.
fn reverse_loop(lp: &mut [LoopPt]) {
    let n = lp.len();
    let along: Vec<Option<usize>> = (0..n).map(|k| lp[k].along).collect();
    lp.reverse();
    // After reversing, point k (was n-1-k) leads to the point that was n-2-k, along what the
    // point n-2-k led along before.
    for k in 0..n {
        let was_next = (2 * n - 2 - k) % n;
        lp[k].along = along[was_next];
    }
}

/// Where along a periodic direction `d` a cut line clears the holes: the middle of the widest
/// gap between their extents (taken modulo the period), else the domain's start.
fn clear_cut(holes: &[Vec<LoopPt>], d: usize, per: f64, start: f64) -> f64 {
    let mut spans: Vec<(f64, f64)> = holes
        .iter()
        .map(|h| {
            let lo = h.iter().map(|p| p.uv[d]).fold(f64::INFINITY, f64::min);
            let hi = h.iter().map(|p| p.uv[d]).fold(f64::NEG_INFINITY, f64::max);
            let s = start + (lo - start).rem_euclid(per);
            (s, s + (hi - lo))
        })
        .collect();
    if spans.is_empty() {
        return start;
    }
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Merge, then find the widest gap (around the period).
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (a, b) in spans {
        match merged.last_mut() {
            Some(m) if a <= m.1 => m.1 = m.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    let mut best = (f64::NEG_INFINITY, start);
    for k in 0..merged.len() {
        let end = merged[k].1;
        let next = if k + 1 < merged.len() {
            merged[k + 1].0
        } else {
            merged[0].0 + per
        };
        if next - end > best.0 {
            best = (next - end, 0.5 * (end + next));
        }
    }
    best.1
}

/// A model vertex at this point (a `VERTEX_LOOP`'s apex), if one is there.
fn vertex_at(inp: &TrimInput, p: DVec3) -> Option<Origin> {
    inp.face
        .bounds
        .iter()
        .filter_map(|b| b.vertex)
        .find(|&v| inp.model.vertices[v].point.distance(p) <= inp.pole_tol.max(1e-9))
        .map(Origin::Vertex)
}

/// The loop of a face with no loops: the whole of a closed surface (a sphere, a torus, a closed
/// patch), its domain bounded by cut lines (one set of points on both sides) and poles.
fn whole_surface(
    inp: &TrimInput,
    holes: &[Vec<LoopPt>],
    trim: &mut Trim,
) -> Result<Vec<LoopPt>, StepError> {
    let s = inp.surface();
    let d = s.domain();
    let [pu, pv] = s.periods();
    let v_mid = 0.5 * (d.v.0 + d.v.1);
    let Some(pu) = pu else {
        return Err(inp.err(format!(
            "the face has no loops and its {} does not close on itself: it has no boundary",
            s.name()
        )));
    };
    let corner = |trim: &mut Trim, uv: DVec2| {
        trim.extra.push(s.eval(uv.x, uv.y));
        Origin::Extra(trim.extra.len() - 1)
    };
    let pt = |trim: &Trim, uv: DVec2, origin: Origin| LoopPt {
        uv,
        pos: match origin {
            Origin::Extra(e) => trim.extra[e],
            _ => s.eval(uv.x, uv.y),
        },
        origin,
        along: None,
    };
    let u0 = clear_cut(holes, 0, pu, d.u.0);
    let mut out = Vec::new();
    match pv {
        // A torus: the rectangle of both periods, its opposite sides one set of points.
        Some(pv) => {
            let v0 = clear_cut(holes, 1, pv, d.v.0);
            let c = corner(trim, DVec2::new(u0, v0));
            let bottom = cut_points(inp, DVec2::new(u0, v0), DVec2::new(u0 + pu, v0), trim);
            let side = cut_points(inp, DVec2::new(u0, v0), DVec2::new(u0, v0 + pv), trim);
            out.push(pt(trim, DVec2::new(u0, v0), c));
            out.extend(line_points(trim, &bottom, DVec2::ZERO, false));
            out.push(pt(trim, DVec2::new(u0 + pu, v0), c));
            out.extend(line_points(trim, &side, DVec2::new(pu, 0.0), false));
            out.push(pt(trim, DVec2::new(u0 + pu, v0 + pv), c));
            out.extend(line_points(trim, &bottom, DVec2::new(0.0, pv), true));
            out.push(pt(trim, DVec2::new(u0, v0 + pv), c));
            out.extend(line_points(trim, &side, DVec2::ZERO, true));
            record_cut(trim, c, &bottom, c);
            record_cut(trim, c, &side, c);
        }
        // A sphere: between its poles, cut along one meridian.
        None => {
            let (Some(south), Some(north)) = (
                s.pole_beyond(v_mid, false, inp.pole_tol),
                s.pole_beyond(v_mid, true, inp.pole_tol),
            ) else {
                return Err(inp.err(format!(
                    "the face has no loops and its {} is open at a pole: it has no boundary",
                    s.name()
                )));
            };
            let (a, b) = (DVec2::new(u0, south), DVec2::new(u0, north));
            let ps = corner(trim, a);
            let pn = corner(trim, b);
            let line = cut_points(inp, a, b, trim);
            out.push(pt(trim, a, ps));
            out.push(pt(trim, a + DVec2::new(pu, 0.0), ps));
            out.extend(line_points(trim, &line, DVec2::new(pu, 0.0), false));
            out.push(pt(trim, b + DVec2::new(pu, 0.0), pn));
            out.push(pt(trim, b, pn));
            out.extend(line_points(trim, &line, DVec2::ZERO, true));
            record_cut(trim, ps, &line, pn);
        }
    }
    Ok(out)
}

/// Drops a last point that repeats the first one's origin and (u, v).
fn dedup_closing(mut lp: Vec<LoopPt>) -> Vec<LoopPt> {
    while lp.len() > 1 {
        let (a, z) = (lp[0], lp[lp.len() - 1]);
        if a.origin == z.origin && a.uv.distance(z.uv) <= 1e-12 * (1.0 + a.uv.length()) {
            lp.pop();
        } else {
            break;
        }
    }
    lp
}

/// A band: the loops `lower` (going `w` = ±1 times around u, the region on its upper side) and
/// `upper` (the other way) joined by a cut line between a point of each.
///
/// On a ruled face the line runs along a ruling, between points of the two loops at one u: a
/// line off the rulings would be split where it crosses each, at u on one side and at u + one
/// period on the other, so its two sides would not share their points. Each ruling through a
/// point of one loop crosses the other loop at an edge sample once the caller has put the
/// face's rulings on its edges; until then (`inp.rulings` unset) any clear line will do.
fn band(
    inp: &TrimInput,
    lower: &[LoopPt],
    w: i64,
    upper: &[LoopPt],
    per: f64,
    holes: &[Vec<LoopPt>],
    trim: &mut Trim,
) -> Result<Vec<LoopPt>, StepError> {
    let wp = per * w as f64;
    // Anchor candidates on the lower loop: its highest points first; on the upper loop, the
    // points nearest the anchor (a period either way).
    let mut order: Vec<usize> = (0..lower.len()).collect();
    order.sort_by(|&a, &b| lower[b].uv.y.total_cmp(&lower[a].uv.y));
    let refs = obstacles(&[(lower, w), (upper, -w)], holes, per);
    let same_u = SAME_PARAM_REL * per;
    let find = |along_ruling: bool, anchors: usize| -> Option<(usize, usize, f64)> {
        for &ai in order.iter().take(anchors) {
            let a = lower[ai].uv;
            let mut near: Vec<(f64, usize, f64)> = upper
                .iter()
                .enumerate()
                .map(|(k, q)| {
                    let sh = per * ((a.x - q.uv.x) / per).round();
                    (q.uv.x + sh - a.x, k, sh)
                })
                .filter(|&(du, _, _)| !along_ruling || du.abs() <= same_u)
                .map(|(_, k, sh)| {
                    let b = upper[k].uv + DVec2::new(sh, 0.0);
                    (b.distance(a), k, sh)
                })
                .collect();
            near.sort_by(|x, y| x.0.total_cmp(&y.0));
            for &(_, bi, sh) in near.iter().take(CUT_CANDIDATES) {
                let b = upper[bi].uv + DVec2::new(sh, 0.0);
                if !crosses(a, b, &refs) {
                    return Some((ai, bi, sh));
                }
            }
        }
        None
    };
    let found = if inp.ruled {
        find(true, order.len()).or_else(|| {
            inp.rulings
                .is_none()
                .then(|| find(false, CUT_CANDIDATES))
                .flatten()
        })
    } else {
        find(false, CUT_CANDIDATES)
    };
    let Some((ai, bi, sh)) = found else {
        return Err(inp.err(format!(
            "its two loops wind around the {} and no {} between them clears the face's other loops",
            inp.surface().name(),
            if inp.ruled { "ruling" } else { "line" }
        )));
    };
    let (a, b) = (lower[ai].uv, upper[bi].uv + DVec2::new(sh, 0.0));
    // A ruling is straight: its ends are all its points.
    let line = if inp.ruled {
        Vec::new()
    } else {
        cut_points(inp, a, b, trim)
    };
    let mut out = around_from(lower, ai, wp);
    out.extend(line_points(trim, &line, DVec2::new(wp, 0.0), false));
    // Around the upper loop once from its point (going the other way round).
    let m = upper.len();
    for k in 0..=m {
        let mut p = upper[(bi + k) % m];
        p.uv.x += sh + wp;
        if bi + k >= m {
            p.uv.x -= wp;
        }
        if k == m {
            p.along = None;
        }
        out.push(p);
    }
    out.extend(line_points(trim, &line, DVec2::ZERO, true));
    record_cut(trim, lower[ai].origin, &line, upper[bi].origin);
    Ok(dedup_closing(out))
}

/// Even–odd test of a point against a closed loop.
fn inside(lp: &[LoopPt], q: DVec2) -> bool {
    let mut c = false;
    let n = lp.len();
    for k in 0..n {
        let (a, b) = (lp[k].uv, lp[(k + 1) % n].uv);
        if (a.y > q.y) != (b.y > q.y) {
            let x = a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if x > q.x {
                c = !c;
            }
        }
    }
    c
}

/// Moves every loop but the outer one (the largest) by whole periods to lie inside it (the move
/// that puts a point of the loop inside, else the one nearest its middle).
fn place_loops(mut loops: Vec<Vec<LoopPt>>, periods: [Option<f64>; 2]) -> Vec<Vec<LoopPt>> {
    if loops.len() < 2 || periods.iter().all(Option::is_none) {
        return loops;
    }
    let outer = (0..loops.len())
        .max_by(|&a, &b| {
            signed_area(&loops[a])
                .abs()
                .total_cmp(&signed_area(&loops[b]).abs())
        })
        .unwrap_or(0);
    let (olo, ohi) = bbox(&loops[outer]);
    let omid = 0.5 * (olo + ohi);
    let reach = |d: usize| -> Vec<i64> {
        if periods[d].is_some() {
            (-2..=2).collect()
        } else {
            vec![0]
        }
    };
    for i in 0..loops.len() {
        if i == outer {
            continue;
        }
        let lp = &loops[i];
        // A probe just inside the loop's first segment's middle is on the loop: use its middle.
        let probe = 0.5 * (lp[0].uv + lp[1 % lp.len()].uv);
        let (lo, hi) = bbox(lp);
        let mid = 0.5 * (lo + hi);
        let mut best: Option<(bool, f64, DVec2)> = None;
        for ku in reach(0) {
            for kv in reach(1) {
                let sh = DVec2::new(
                    periods[0].unwrap_or(0.0) * ku as f64,
                    periods[1].unwrap_or(0.0) * kv as f64,
                );
                let inside_outer = inside(&loops[outer], probe + sh);
                let dist = (mid + sh).distance(omid);
                let better = best
                    .as_ref()
                    .is_none_or(|b| (inside_outer && !b.0) || (inside_outer == b.0 && dist < b.1));
                if better {
                    best = Some((inside_outer, dist, sh));
                }
            }
        }
        if let Some((_, _, sh)) = best {
            for p in loops[i].iter_mut() {
                p.uv += sh;
            }
        }
    }
    loops
}

/// Inserts the points of a pole run between consecutive loop points that are one pole point at
/// different (u, v): on every ruling for a ruled face, else every [`POLE_STEP`].
fn fill_poles(lp: Vec<LoopPt>, rulings: Option<&[f64]>) -> Vec<LoopPt> {
    let n = lp.len();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (a, b) = (lp[k], lp[(k + 1) % n]);
        out.push(a);
        if a.origin != b.origin || a.uv.distance(b.uv) <= SAME_PARAM_REL * (1.0 + a.uv.length()) {
            continue;
        }
        let d = (b.uv - a.uv).abs();
        let dir = usize::from(d.y > d.x);
        let mut ts: Vec<f64> = match rulings {
            Some(r) if dir == 0 => {
                let (u0, u1) = (a.uv.x.min(b.uv.x), a.uv.x.max(b.uv.x));
                r.iter()
                    .filter(|&&u| u > u0 && u < u1)
                    .map(|&u| (u - a.uv.x) / (b.uv.x - a.uv.x))
                    .collect()
            }
            _ => {
                let m = (d[dir] / POLE_STEP).ceil().max(1.0) as usize;
                (1..m).map(|i| i as f64 / m as f64).collect()
            }
        };
        ts.sort_by(f64::total_cmp);
        for t in ts {
            out.push(LoopPt {
                uv: a.uv + (b.uv - a.uv) * t,
                pos: a.pos,
                origin: a.origin,
                along: None,
            });
        }
    }
    out
}

/// The sample indices point origin `o` may be on edge slot `slot` (a closed edge's vertex is
/// both ends).
fn index_on(
    model: &Model,
    slot_of: &BTreeMap<usize, usize>,
    samples: &[Samples],
    o: Origin,
    slot: usize,
) -> Vec<usize> {
    match o {
        Origin::Sample { slot: s, index } if s == slot => vec![index],
        Origin::Vertex(v) => {
            let Some((e, _)) = slot_of.iter().find(|(_, s)| **s == slot) else {
                return Vec::new();
            };
            let Ok(g) = model.edges[*e].geometry.as_ref() else {
                return Vec::new();
            };
            let n = samples[slot].pts.len();
            let mut out = Vec::new();
            if v == g.start {
                out.push(0);
            }
            if v == g.end {
                out.push(n - 1);
            }
            out
        }
        _ => Vec::new(),
    }
}

/// The edge samples a loop runs between from point `a` to the next point `b`: (slot, i, j)
/// when they are consecutive samples of the edge `a` runs along.
pub(crate) fn along_edge(
    model: &Model,
    slot_of: &BTreeMap<usize, usize>,
    samples: &[Samples],
    a: &LoopPt,
    b: &LoopPt,
) -> Option<(usize, usize, usize)> {
    let slot = a.along?;
    let ia = index_on(model, slot_of, samples, a.origin, slot);
    let ib = index_on(model, slot_of, samples, b.origin, slot);
    ia.iter()
        .flat_map(|&i| ib.iter().map(move |&j| (i, j)))
        .find(|(i, j)| i.abs_diff(*j) == 1)
        .map(|(i, j)| (slot, i, j))
}

/// The segments of the loops along edges: consecutive points that are consecutive samples of
/// one edge (its ends being its vertices).
fn segments(inp: &TrimInput, loops: &[Vec<LoopPt>]) -> Vec<Seg> {
    let mut out = Vec::new();
    for lp in loops {
        let n = lp.len();
        for k in 0..n {
            let (a, b) = (lp[k], lp[(k + 1) % n]);
            if let Some((slot, i, j)) = along_edge(inp.model, inp.slot_of, inp.samples, &a, &b) {
                out.push(Seg {
                    slot,
                    i,
                    j,
                    ua: a.uv.x,
                    ub: b.uv.x,
                });
            }
        }
    }
    out
}
