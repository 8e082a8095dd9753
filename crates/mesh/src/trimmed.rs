//! Tessellation of trimmed faces: a parametric surface restricted to the region its trim loops
//! bound in (u, v) — the faces of CAD models (STEP).
//!
//! The loops are given as points with their (u, v), their exact 3D position and the caller's
//! vertex id; the caller samples each edge curve once, so two faces sharing an edge get the same
//! points and the same ids, and the shell welds crack-free. Boundary points are never moved and
//! boundary segments never split here.
//!
//! Two methods:
//! - **General** ([`TrimmedFace::ruled`] false): a constrained Delaunay triangulation (spade) of
//!   the loops in the (u, v) plane scaled by the surface's mean speeds `|S_u|`, `|S_v|` (so the
//!   Delaunay criterion sees roughly the surface metric), whose inside triangles (even–odd rule
//!   across the constraint edges) are refined until each meets the chordal tolerance: deviation
//!   at the centroid and at the midpoints of its interior edges (the surface point at the
//!   interpolated (u, v) against the triangle point), and a normal turn of at most
//!   [`crate::tessellate::MAX_NORMAL_TURN`] across it. A bad triangle gets a vertex at its
//!   circumcentre (Delaunay refinement, which keeps triangles well shaped) or, where that falls
//!   outside the face or on a boundary, at its centroid.
//! - **Ruled** (true; the developable surfaces, whose lines `u = const` are straight and along
//!   which the surface is flat): each ruling's stretches inside the face are constraints of the
//!   triangulation (with points along them so triangles are not needles), so every triangle
//!   lies between two neighbouring rulings; one with its corners on those two rulings lies in
//!   the strip's plane, and a mesh whose rulings all end at loop points is exactly developable
//!   (it unfolds with zero distortion). The rulings are given by the caller (by default the
//!   distinct `u` of the loop points): it puts a loop point wherever one of its rulings crosses
//!   the boundary, and adds rulings where the surface needs them for the chordal tolerance. A
//!   loop point off the rulings (a neighbour's, on a shared edge) is a corner of the triangles
//!   of its strip; a ruling that crosses a segment with no loop point there ends at its last
//!   point inside, and the triangulation closes the gap.
//!
//! Consecutive loop points with the same vertex id (a pole: a side of the parameter domain that
//! collapses to one point, as at a cone's apex) become one vertex; triangles with two corners
//! there are dropped.

use std::collections::{BTreeSet, VecDeque};

use flatcut_geom::{DVec2, DVec3, Tolerances};
use flatcut_surface::ParamSurface;
use spade::Triangulation as _;
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{ConstrainedDelaunayTriangulation, HasPosition, Point2, PositionInTriangulation};

use crate::TriMesh;
use crate::tessellate::TessOptions;

/// Refinement rounds before giving up (each round refines every bad triangle once; the number of
/// triangles grows geometrically, so 64 rounds is far beyond any tolerance reachable in f64).
const MAX_ROUNDS: usize = 64;
/// Triangles whose longest 3D edge is below this fraction of the chordal tolerance are not split
/// further (round-off level; stops refinement at singular points).
const MIN_EDGE_OVER_CHORD: f64 = 1e-3;
/// A refined vertex closer than this fraction of its triangle's shortest edge (in the scaled
/// plane) to the triangle's boundary is moved to the centroid instead (no slivers).
const MIN_INSET: f64 = 0.05;
/// Sample grid per side for the speeds and curvatures that scale the plane.
const SPEED_SAMPLES: usize = 9;
/// Largest ratio of wanted triangle lengths along u and along v (see [`plane_scale`]): long
/// thin triangles follow a fillet, but never needles.
const MAX_ANISOTROPY: f64 = 6.0;
/// Points along a ruling are at most this many widths of the face's widest strip apart (ruled
/// method).
const RULING_ASPECT: f64 = 6.0;
/// Two rulings closer than this fraction of the u range are one ruling (ruled method).
const RULING_SNAP_REL: f64 = 1e-9;
/// A point of a trim loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrimPoint {
    /// Parameters on the face's surface.
    pub uv: DVec2,
    /// Exact 3D position (mm): the point of the edge curve, shared with the neighbouring face.
    pub pos: DVec3,
    /// The caller's vertex id: equal ids are one vertex of the shell.
    pub vertex: u32,
}

/// A trimmed face: the surface and its closed trim loops (last point not repeated).
#[derive(Clone, Copy, Debug)]
pub struct TrimmedFace<'a> {
    /// The face's surface.
    pub surface: &'a dyn ParamSurface,
    /// The trim loops in (u, v), closed (last point not repeated): the outer loop and its holes.
    pub loops: &'a [Vec<TrimPoint>],
    /// The surface is developable with straight, flat lines `u = const`: mesh along them.
    pub ruled: bool,
    /// The u of the rulings to mesh along (ruled faces); empty: the distinct u of the loop
    /// points.
    pub rulings: &'a [f64],
}

/// The mesh of one face: positions, triangles counter-clockwise in (u, v), `params` the (u, v)
/// of every vertex; `vertex[i]` is the caller's id of a boundary vertex, `None` inside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrimmedMesh {
    /// The mesh: positions (mm), triangles counter-clockwise in (u, v), `params` the (u, v).
    pub mesh: TriMesh,
    /// Per vertex of `mesh`, the caller's id for a boundary vertex, `None` inside.
    pub vertex: Vec<Option<u32>>,
    /// The area in (u, v) of the triangulation's triangles, each with its own corners' (u, v)
    /// (a pole is one vertex of the mesh but a run of points in (u, v)), triangles collapsed at
    /// a pole included: equal to the area the loops bound when the triangles tile the region
    /// the loops bound (the caller compares).
    pub cover_uv: f64,
}

/// Why a trimmed face could not be tessellated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TrimError {
    #[error("chordal tolerance must be finite and > 0 mm, got {0}")]
    /// The chordal tolerance given is not finite and positive.
    BadTolerance(f64),
    #[error("trim loop {index} has fewer than 2 distinct points")]
    /// A trim loop has fewer than two distinct points.
    ShortLoop {
        /// 0-based index of the loop.
        index: usize,
    },
    #[error("trim loop {index} has a non-finite (u, v) or point")]
    /// A trim loop has a NaN or infinite coordinate.
    NonFinite {
        /// 0-based index of the loop.
        index: usize,
    },
    #[error("trim loop {index} has (u, v) = ({u}, {v}), beyond the triangulator's range (±3.2e60)")]
    /// A trim loop's (u, v) is beyond the triangulator's range.
    OutOfRange {
        /// 0-based index of the loop.
        index: usize,
        /// The u given.
        u: f64,
        /// The v given.
        v: f64,
    },
    #[error("the surface is not finite at (u, v) = ({u}, {v})")]
    /// The surface evaluates to a NaN or infinite point.
    SurfaceNonFinite {
        /// Parameter u of the point.
        u: f64,
        /// Parameter v of the point.
        v: f64,
    },
    #[error(
        "the trim loops cross each other in (u, v) near ({u:.6}, {v:.6}): the face's boundary is not a valid region"
    )]
    /// Trim loops cross each other.
    LoopsCross {
        /// Parameter u near the crossing.
        u: f64,
        /// Parameter v near the crossing.
        v: f64,
    },
    #[error(
        "the trim loops run twice along one segment near ({u:.6}, {v:.6}) in (u, v): the face's boundary is not a valid region"
    )]
    /// Trim loops run twice along one segment.
    LoopsOverlap {
        /// Parameter u near the overlap.
        u: f64,
        /// Parameter v near the overlap.
        v: f64,
    },
    #[error(
        "the face needs more than {limit} vertices at chordal tolerance {chord_mm} mm; raise the tolerance"
    )]
    /// The tolerance calls for more vertices than the limit.
    TooManyVertices {
        /// The vertex limit.
        limit: usize,
        /// The chordal tolerance asked for (mm).
        chord_mm: f64,
    },
}

/// Working-plane vertex of the triangulation: scaled (u, v) and the local vertex index.
#[derive(Clone, Copy, Debug)]
struct Vx {
    pos: Point2<f64>,
    local: u32,
}

/// Marks a vertex spade inserted itself (never: we insert all vertices) or not yet indexed.
const UNSET: u32 = u32::MAX;

impl HasPosition for Vx {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

impl From<Point2<f64>> for Vx {
    fn from(pos: Point2<f64>) -> Self {
        Self { pos, local: UNSET }
    }
}

type Cdt = ConstrainedDelaunayTriangulation<Vx>;

/// Local vertices under construction: (u, v), 3D point, caller id.
#[derive(Default)]
struct Verts {
    uv: Vec<DVec2>,
    pos: Vec<DVec3>,
    id: Vec<Option<u32>>,
}

impl Verts {
    fn push(&mut self, uv: DVec2, pos: DVec3, id: Option<u32>) -> u32 {
        self.uv.push(uv);
        self.pos.push(pos);
        self.id.push(id);
        (self.uv.len() - 1) as u32
    }
}

/// `x`, or 0 where spade would reject it as too small (below its `MIN_ALLOWED_VALUE`, 2^-142
/// ≈ 1.8e-43): a CAD system's rounding noise, e.g. (u, v) = (−100, 1.8e-45) on a plane whose
/// axes are written with components of 1e-17.
fn tiny0(x: f64) -> f64 {
    if x.abs() < spade::MIN_ALLOWED_VALUE {
        0.0
    } else {
        x
    }
}

/// Validates the loops and turns each into local vertex indices (consecutive points with the
/// same id share one vertex); returns, per loop, `(local index, (u, v))` for every point.
fn loop_vertices(
    loops: &[Vec<TrimPoint>],
    verts: &mut Verts,
) -> Result<Vec<Vec<(u32, DVec2)>>, TrimError> {
    let mut out = Vec::with_capacity(loops.len());
    for (index, lp) in loops.iter().enumerate() {
        if lp
            .iter()
            .any(|p| !(flatcut_geom::finite2(p.uv) && flatcut_geom::finite3(p.pos)))
        {
            return Err(TrimError::NonFinite { index });
        }
        let mut pts: Vec<(u32, DVec2)> = Vec::with_capacity(lp.len());
        for (k, p) in lp.iter().enumerate() {
            if let Some(&(_, last_uv)) = pts.last()
                && last_uv == p.uv
            {
                continue;
            }
            let same_as_prev = k > 0 && lp[k - 1].vertex == p.vertex;
            let local = if same_as_prev {
                pts.last()
                    .map_or_else(|| verts.push(p.uv, p.pos, Some(p.vertex)), |&(l, _)| l)
            } else {
                verts.push(p.uv, p.pos, Some(p.vertex))
            };
            pts.push((local, p.uv));
        }
        // The loop closes on itself: a last point equal to the first is dropped, and a last run
        // with the first point's id joins the first vertex.
        while pts.len() > 1 && pts[pts.len() - 1].1 == pts[0].1 {
            pts.pop();
        }
        if let (Some(first), Some(last)) = (lp.first(), lp.last())
            && lp.len() > 1
            && first.vertex == last.vertex
        {
            let l0 = pts[0].0;
            let mut k = pts.len();
            while k > 1 && verts.id[pts[k - 1].0 as usize] == Some(first.vertex) {
                pts[k - 1].0 = l0;
                k -= 1;
            }
        }
        let distinct = {
            let mut ls: Vec<u32> = pts.iter().map(|p| p.0).collect();
            ls.sort_unstable();
            ls.dedup();
            ls.len()
        };
        if pts.len() < 3 || distinct < 2 {
            return Err(TrimError::ShortLoop { index });
        }
        out.push(pts);
    }
    Ok(out)
}

/// The scale of the working plane: `(s_u, s_v)` such that a unit step in the scaled plane is
/// about one wanted triangle edge in either direction. An edge along u may be as long as the
/// chordal tolerance (`√(8 tol / κ_u)` for the normal curvature κ_u along u) and the normal-turn
/// limit (`θ / κ_u`) allow; the scale is the mean of `|S_u|` divided by that length (with the
/// box's 3D size as the longest edge), likewise for v, and the ratio of the two directions'
/// densities is kept within [`MAX_ANISOTROPY`]. So a fillet, curved across and nearly straight
/// along, gets long thin triangles along it, as the tolerance allows; a plane gets the isotropic
/// scaling of its speeds.
fn plane_scale(s: &dyn ParamSurface, lo: DVec2, hi: DVec2, tol: f64, max_turn: f64) -> DVec2 {
    let mut speed = DVec2::ZERO;
    let mut density = DVec2::ZERO;
    let mut size = flatcut_geom::Aabb3::EMPTY;
    let mut n = 0usize;
    let mut samples = Vec::with_capacity(SPEED_SAMPLES * SPEED_SAMPLES);
    for i in 0..SPEED_SAMPLES {
        for j in 0..SPEED_SAMPLES {
            let t = DVec2::new(
                (i as f64 + 0.5) / SPEED_SAMPLES as f64,
                (j as f64 + 0.5) / SPEED_SAMPLES as f64,
            );
            let uv = lo + (hi - lo) * t;
            let d = s.deriv2(uv.x, uv.y);
            size.add(d.p);
            samples.push(d);
        }
    }
    let diag = size.diagonal();
    let want = |kappa: f64| -> f64 {
        let k = kappa.abs();
        (8.0 * tol / k).sqrt().min(max_turn / k)
    };
    for d in &samples {
        let (e, g) = (d.su.length(), d.sv.length());
        let Some(nrm) = d.su.cross(d.sv).try_normalize() else {
            continue;
        };
        if !(e.is_finite() && g.is_finite() && e > 0.0 && g > 0.0) {
            continue;
        }
        let ku = d.suu.dot(nrm) / (e * e);
        let kv = d.svv.dot(nrm) / (g * g);
        let lu = want(ku).min(diag);
        let lv = want(kv).min(diag);
        if !(lu > 0.0 && lv > 0.0) {
            continue;
        }
        speed += DVec2::new(e, g);
        density += DVec2::new(e / lu, g / lv);
        n += 1;
    }
    if n == 0 || !(speed.x > 0.0 && speed.y > 0.0) {
        return DVec2::ONE;
    }
    // Density per unit parameter; its ratio to the speeds' ratio is the anisotropy.
    let iso = speed / n as f64;
    let dens = density / n as f64;
    let r = ((dens.x / iso.x) / (dens.y / iso.y)).clamp(1.0 / MAX_ANISOTROPY, MAX_ANISOTROPY);
    if !r.is_finite() {
        return iso;
    }
    DVec2::new(iso.x * r.sqrt(), iso.y / r.sqrt())
}

fn bounds(loops: &[Vec<(u32, DVec2)>]) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in loops.iter().flatten() {
        lo = lo.min(p.1);
        hi = hi.max(p.1);
    }
    (lo, hi)
}

/// The constrained triangulation of the loops in the plane scaled by `scale`; returns the CDT and
/// the CDT vertex of every local vertex inserted so far.
fn loops_cdt(
    loops: &[Vec<(u32, DVec2)>],
    scale: DVec2,
    nverts: usize,
) -> Result<(Cdt, Vec<Option<FixedVertexHandle>>), TrimError> {
    let mut cdt = Cdt::new();
    let mut handle: Vec<Option<FixedVertexHandle>> = vec![None; nverts];
    // One CDT vertex per loop point: pole runs share a local vertex but keep their own (u, v).
    let mut loop_handles: Vec<Vec<FixedVertexHandle>> = Vec::with_capacity(loops.len());
    for (index, lp) in loops.iter().enumerate() {
        let mut hs = Vec::with_capacity(lp.len());
        for &(local, uv) in lp {
            let w = uv * scale;
            let h = cdt
                .insert(Vx {
                    pos: Point2::new(tiny0(w.x), tiny0(w.y)),
                    local,
                })
                .map_err(|_| TrimError::OutOfRange {
                    index,
                    u: uv.x,
                    v: uv.y,
                })?;
            handle[local as usize].get_or_insert(h);
            hs.push(h);
        }
        loop_handles.push(hs);
    }
    for (lp, hs) in loops.iter().zip(&loop_handles) {
        for k in 0..hs.len() {
            let (a, b) = (hs[k], hs[(k + 1) % hs.len()]);
            if a == b {
                continue;
            }
            if cdt.exists_constraint(a, b) {
                // Two loop segments along one line: the loops run back over themselves.
                let uv = 0.5 * (lp[k].1 + lp[(k + 1) % lp.len()].1);
                return Err(TrimError::LoopsOverlap { u: uv.x, v: uv.y });
            }
            if cdt.try_add_constraint(a, b).is_empty() {
                let uv = 0.5 * (lp[k].1 + lp[(k + 1) % lp.len()].1);
                return Err(TrimError::LoopsCross { u: uv.x, v: uv.y });
            }
        }
    }
    Ok((cdt, handle))
}

/// Inside flags of the CDT's inner faces: even–odd parity of constraint edges crossed from the
/// outer face (breadth first, in face-index order, so deterministic).
fn inside_faces(cdt: &Cdt) -> Vec<bool> {
    inside_faces_except(cdt, &BTreeSet::new())
}

/// [`inside_faces`] counting only the constraint edges that are not `inner` (pairs of CDT
/// vertex indices, smaller first): constraints inside the face, not on its boundary.
fn inside_faces_except(cdt: &Cdt, inner: &BTreeSet<(usize, usize)>) -> Vec<bool> {
    let boundary = |e: spade::handles::UndirectedEdgeHandle<'_, Vx, (), spade::CdtEdge<()>, ()>| {
        let [a, b] = e.vertices().map(|v| v.fix().index());
        cdt.is_constraint_edge(e.fix()) && !inner.contains(&(a.min(b), a.max(b)))
    };
    let n = cdt.num_inner_faces() + 1;
    let mut parity: Vec<Option<bool>> = vec![None; n];
    let mut queue: VecDeque<FixedFaceHandle<InnerTag>> = VecDeque::new();
    for e in cdt.convex_hull() {
        // The hull edge has the outer face on its left; its reverse has an inner face.
        if let Some(f) = e.rev().face().as_inner() {
            let inside = boundary(e.as_undirected());
            let idx = f.fix().index();
            if parity[idx].is_none() {
                parity[idx] = Some(inside);
                queue.push_back(f.fix());
            }
        }
    }
    while let Some(f) = queue.pop_front() {
        let here = parity[f.index()].unwrap_or(false);
        for e in cdt.face(f).adjacent_edges() {
            if let Some(g) = e.rev().face().as_inner() {
                let idx = g.fix().index();
                if parity[idx].is_none() {
                    let crosses = boundary(e.as_undirected());
                    parity[idx] = Some(here ^ crosses);
                    queue.push_back(g.fix());
                }
            }
        }
    }
    parity.into_iter().map(|p| p.unwrap_or(false)).collect()
}

/// Whether the triangle `[a, b, c]` (local vertices, at parameters `uv` — the triangle's own
/// corners: a pole vertex has a different (u, v) in each triangle) needs refining, from its
/// deviation from the surface and the turn of the normal across it.
#[allow(clippy::too_many_arguments)]
fn needs_refining(
    s: &dyn ParamSurface,
    verts: &Verts,
    normals: &[Option<DVec3>],
    tri: [u32; 3],
    uv: [DVec2; 3],
    boundary_edge: [bool; 3],
    tol: f64,
    min_edge: f64,
    max_turn_cos: f64,
) -> bool {
    let p = tri.map(|i| verts.pos[i as usize]);
    let longest = (p[1] - p[0])
        .length()
        .max((p[2] - p[1]).length())
        .max((p[0] - p[2]).length());
    if longest.is_nan() || longest < min_edge {
        return false;
    }
    let dev = |w: [f64; 3]| {
        let q = uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
        let lin = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
        s.eval(q.x, q.y).distance(lin)
    };
    if dev([1.0 / 3.0; 3]) > tol {
        return true;
    }
    for k in 0..3 {
        if boundary_edge[k] {
            continue;
        }
        let mut w = [0.0; 3];
        w[k] = 0.5;
        w[(k + 1) % 3] = 0.5;
        if dev(w) > tol {
            return true;
        }
    }
    let n = tri.map(|i| normals[i as usize]);
    for k in 0..3 {
        if let (Some(a), Some(b)) = (n[k], n[(k + 1) % 3])
            && a.dot(b) < max_turn_cos
        {
            return true;
        }
    }
    false
}

fn unit_normal(s: &dyn ParamSurface, uv: DVec2) -> Option<DVec3> {
    let (_, su, sv) = s.deriv1(uv.x, uv.y);
    su.cross(sv).try_normalize()
}

/// Tessellates a trimmed face to the chordal tolerance `tol.chord_mm`.
pub fn tessellate_trimmed(
    face: &TrimmedFace,
    tol: &Tolerances,
    opts: &TessOptions,
) -> Result<TrimmedMesh, TrimError> {
    if !(tol.chord_mm.is_finite() && tol.chord_mm > 0.0) {
        return Err(TrimError::BadTolerance(tol.chord_mm));
    }
    let mut verts = Verts::default();
    let loops = loop_vertices(face.loops, &mut verts)?;
    let mut cover = 0.0;
    let triangles = if face.ruled {
        ruled_mesh(
            face.surface,
            &loops,
            face.rulings,
            &mut verts,
            tol,
            opts,
            &mut cover,
        )?
    } else {
        cdt_mesh(face.surface, &loops, &mut verts, tol, opts, &mut cover)?
    };
    let mut mesh = TriMesh::new(verts.pos, triangles);
    mesh.params = Some(verts.uv);
    Ok(TrimmedMesh {
        mesh,
        vertex: verts.id,
        cover_uv: cover,
    })
}

/// The general method: CDT of the loops, refined to the tolerance.
fn cdt_mesh(
    s: &dyn ParamSurface,
    loops: &[Vec<(u32, DVec2)>],
    verts: &mut Verts,
    tol: &Tolerances,
    opts: &TessOptions,
    cover: &mut f64,
) -> Result<Vec<[u32; 3]>, TrimError> {
    let (lo, hi) = bounds(loops);
    let scale = plane_scale(s, lo, hi, tol.chord_mm, opts.max_normal_turn);
    let (mut cdt, _) = loops_cdt(loops, scale, verts.uv.len())?;
    let mut normals: Vec<Option<DVec3>> = verts.uv.iter().map(|&uv| unit_normal(s, uv)).collect();
    let min_edge = (MIN_EDGE_OVER_CHORD * tol.chord_mm).max(4.0 * tol.weld_mm);
    let max_turn_cos = opts.max_normal_turn.cos();
    // A triangle's test depends on its corners alone, and every triangle an insertion makes has
    // the new vertex as a corner: a round tests the triangles with a corner inserted by the
    // round before, and those found bad then (by their triangulation vertices, sorted) whose
    // point could not go in; the others were found fine already.
    let mut new_from = 0usize;
    let mut bad: BTreeSet<[usize; 3]> = BTreeSet::new();
    for _ in 0..MAX_ROUNDS {
        let inside = inside_faces(&cdt);
        let was_bad = std::mem::take(&mut bad);
        // (preferred point, fallback: the bad triangle's centroid, a vertex of the bad triangle
        // to start locating from), scaled plane.
        let mut todo: Vec<(DVec2, DVec2, FixedVertexHandle)> = Vec::new();
        for f in cdt.inner_faces() {
            if !inside[f.fix().index()] {
                continue;
            }
            let vs = f.vertices();
            let tri = vs.map(|v| v.data().local);
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
                continue;
            }
            let mut key = vs.map(|v| v.fix().index());
            key.sort_unstable();
            if key[2] < new_from && !was_bad.contains(&key) {
                continue;
            }
            let edges = f.adjacent_edges();
            // adjacent_edges()[k] runs from vertex k to vertex k + 1.
            let boundary = edges.map(|e| e.is_constraint_edge());
            let uv = f.positions().map(|p| DVec2::new(p.x, p.y) / scale);
            if !needs_refining(
                s,
                verts,
                &normals,
                tri,
                uv,
                boundary,
                tol.chord_mm,
                min_edge,
                max_turn_cos,
            ) {
                continue;
            }
            bad.insert(key);
            let [a, b, c] = f.positions().map(|p| DVec2::new(p.x, p.y));
            let hint = vs[0].fix();
            todo.push((
                refinement_point(&cdt, &inside, f.fix()),
                (a + b + c) / 3.0,
                hint,
            ));
        }
        if todo.is_empty() {
            break;
        }
        let before = verts.uv.len();
        new_from = cdt.num_vertices();
        for (first, fallback, hint) in todo {
            // Points of one round can crowd each other (neighbouring triangles on one circle
            // share their circumcentre): each goes in only with clearance in the triangulation
            // as it stands, else its triangle's centroid, else not at all this round.
            let Some(w) = [first, fallback]
                .into_iter()
                .find(|&w| clear(&cdt, w, hint))
            else {
                continue;
            };
            let uv = w / scale;
            let p = s.eval(uv.x, uv.y);
            if !flatcut_geom::finite3(p) {
                return Err(TrimError::SurfaceNonFinite { u: uv.x, v: uv.y });
            }
            if verts.uv.len() >= opts.max_vertices {
                return Err(TrimError::TooManyVertices {
                    limit: opts.max_vertices,
                    chord_mm: tol.chord_mm,
                });
            }
            let local = verts.uv.len() as u32;
            let pos = Point2::new(tiny0(w.x), tiny0(w.y));
            cdt.insert_with_hint(Vx { pos, local }, hint)
                .map_err(|_| TrimError::SurfaceNonFinite { u: uv.x, v: uv.y })?;
            verts.push(uv, p, None);
            normals.push(unit_normal(s, uv));
        }
        if verts.uv.len() == before {
            break;
        }
    }
    let inside = inside_faces(&cdt);
    Ok(inside_triangles(&cdt, &inside, scale, cover))
}

/// True when `w` lies strictly inside a face of the triangulation, at least [`MIN_INSET`] of
/// that face's shortest side away from its sides (located walking from `hint`).
fn clear(cdt: &Cdt, w: DVec2, hint: FixedVertexHandle) -> bool {
    if !flatcut_geom::finite2(w) {
        return false;
    }
    match cdt.locate_with_hint(Point2::new(tiny0(w.x), tiny0(w.y)), hint) {
        PositionInTriangulation::OnFace(g) => {
            let [p, q, r] = cdt.face(g).positions().map(|p| DVec2::new(p.x, p.y));
            let shortest = (q - p).length().min((r - q).length()).min((p - r).length());
            let inset = [(p, q), (q, r), (r, p)]
                .iter()
                .map(|&(x, y)| dist_to_segment(w, x, y))
                .fold(f64::INFINITY, f64::min);
            inset > MIN_INSET * shortest
        }
        _ => false,
    }
}

/// Where to refine the inner face `f`: its circumcentre when that lies strictly inside an inside
/// face and away from that face's sides, else its centroid (scaled plane coordinates).
fn refinement_point(cdt: &Cdt, inside: &[bool], f: FixedFaceHandle<InnerTag>) -> DVec2 {
    let face = cdt.face(f);
    let [a, b, c] = face.positions().map(|p| DVec2::new(p.x, p.y));
    let centroid = (a + b + c) / 3.0;
    let cc = face.circumcenter();
    let ccv = DVec2::new(cc.x, cc.y);
    if !flatcut_geom::finite2(ccv) {
        return centroid;
    }
    match cdt.locate_with_hint(cc, face.vertices()[0].fix()) {
        PositionInTriangulation::OnFace(g) if inside[g.index()] => {
            let [p, q, r] = cdt.face(g).positions().map(|p| DVec2::new(p.x, p.y));
            let shortest = (q - p).length().min((r - q).length()).min((p - r).length());
            let inset = [(p, q), (q, r), (r, p)]
                .iter()
                .map(|&(x, y)| dist_to_segment(ccv, x, y))
                .fold(f64::INFINITY, f64::min);
            // Do not cross a boundary to get there: the segment from the centroid must not cut a
            // constraint edge (checked cheaply: the circumcentre's face must be reachable, which
            // for a Delaunay face holds unless a constraint is in between).
            if inset > MIN_INSET * shortest && !crosses_constraint(cdt, centroid, ccv) {
                ccv
            } else {
                centroid
            }
        }
        _ => centroid,
    }
}

fn crosses_constraint(cdt: &Cdt, from: DVec2, to: DVec2) -> bool {
    let (a, b) = (Point2::new(from.x, from.y), Point2::new(to.x, to.y));
    spade::LineIntersectionIterator::new(cdt, a, b).any(|i| match i {
        spade::Intersection::EdgeIntersection(e) => e.is_constraint_edge(),
        spade::Intersection::EdgeOverlap(e) => e.is_constraint_edge(),
        _ => false,
    })
}

fn dist_to_segment(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return q.distance(a);
    }
    let t = ((q - a).dot(ab) / l2).clamp(0.0, 1.0);
    q.distance(a + ab * t)
}

/// Even–odd test of a point against the loops (segments between consecutive points).
fn inside_loops(loops: &[Vec<(u32, DVec2)>], q: DVec2) -> bool {
    let mut inside = false;
    for lp in loops {
        for k in 0..lp.len() {
            let (a, b) = (lp[k].1, lp[(k + 1) % lp.len()].1);
            if (a.y > q.y) != (b.y > q.y) {
                let x = a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > q.x {
                    inside = !inside;
                }
            }
        }
    }
    inside
}

/// The ruled method (see the module documentation).
fn ruled_mesh(
    s: &dyn ParamSurface,
    loops: &[Vec<(u32, DVec2)>],
    given: &[f64],
    verts: &mut Verts,
    tol: &Tolerances,
    opts: &TessOptions,
    cover: &mut f64,
) -> Result<Vec<[u32; 3]>, TrimError> {
    let (lo, hi) = bounds(loops);
    let snap = RULING_SNAP_REL * (hi.x - lo.x).abs().max(f64::MIN_POSITIVE);
    let rulings: Vec<f64> = ruling_values(loops, given, snap)
        .into_iter()
        .filter(|&r| r >= lo.x - snap && r <= hi.x + snap)
        .collect();
    let scale = plane_scale(s, lo, hi, tol.chord_mm, opts.max_normal_turn);
    let (mut cdt, _) = loops_cdt(loops, scale, verts.uv.len())?;
    // Loop points on each ruling, and the loop segments running along one.
    let ruling_of = |u: f64| -> Option<usize> {
        let k = rulings.partition_point(|&r| r < u - snap);
        (k < rulings.len() && (rulings[k] - u).abs() <= snap).then_some(k)
    };
    let nr = rulings.len();
    // (v, the loop point's local vertex and exact (u, v), if a loop point is there).
    type OnRuling = (f64, Option<(u32, DVec2)>);
    let mut on_ruling: Vec<Vec<OnRuling>> = vec![Vec::new(); nr];
    let mut along: BTreeSet<(u32, u32)> = BTreeSet::new();
    for lp in loops {
        for k in 0..lp.len() {
            let (la, a) = lp[k];
            let (lb, b) = lp[(k + 1) % lp.len()];
            let (ra, rb) = (ruling_of(a.x), ruling_of(b.x));
            if let Some(r) = ra {
                on_ruling[r].push((a.y, Some((la, a))));
            }
            if ra.is_some() && ra == rb {
                along.insert((la.min(lb), la.max(lb)));
            }
            // Where the segment crosses rulings between its ends (no loop point there: the
            // ruling ends short of the boundary, the triangulation closes the gap).
            let (u0, u1) = (a.x.min(b.x), a.x.max(b.x));
            let first = rulings.partition_point(|&r| r <= u0 + snap);
            for r in first..nr {
                if rulings[r] >= u1 - snap {
                    break;
                }
                let t = (rulings[r] - a.x) / (b.x - a.x);
                on_ruling[r].push((a.y + t * (b.y - a.y), None));
            }
        }
    }
    // Along each ruling, its stretches inside the face: points at the spacing that keeps the
    // widest strips' triangles from being needles (the points add no accuracy: a strip is
    // flat), each stretch a constraint from end to end, so every triangle away from the
    // boundary has its corners on two neighbouring rulings.
    let vmid = 0.5 * (lo.y + hi.y);
    let widest = rulings
        .windows(2)
        .map(|w| s.eval(w[0], vmid).distance(s.eval(w[1], vmid)))
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max);
    let spacing = (RULING_ASPECT * widest).max(tol.chord_mm);
    let mut inner: BTreeSet<(usize, usize)> = BTreeSet::new();
    let mut hint: Option<FixedVertexHandle> = None;
    for (r, pts) in on_ruling.iter_mut().enumerate() {
        let u = rulings[r];
        pts.sort_by(|x, y| {
            x.0.total_cmp(&y.0)
                .then(x.1.map(|p| p.0).cmp(&y.1.map(|p| p.0)))
        });
        pts.dedup_by(|x, y| x.0 == y.0 && x.1.map(|p| p.0) == y.1.map(|p| p.0));
        for w in pts.windows(2) {
            let ((v0, l0), (v1, l1)) = (w[0], w[1]);
            if v1 - v0 <= 0.0 {
                continue;
            }
            if let (Some((a, _)), Some((b, _))) = (l0, l1)
                && (a == b || along.contains(&(a.min(b), a.max(b))))
            {
                continue;
            }
            if !inside_loops(loops, DVec2::new(u, 0.5 * (v0 + v1))) {
                continue;
            }
            let len = s.eval(u, v0).distance(s.eval(u, v1));
            let n = (len / spacing).ceil().max(1.0);
            if !n.is_finite() || verts.uv.len() + n as usize >= opts.max_vertices {
                return Err(TrimError::TooManyVertices {
                    limit: opts.max_vertices,
                    chord_mm: tol.chord_mm,
                });
            }
            // The stretch's vertices: its ends where they are loop points, and the points
            // between.
            let mut chain: Vec<FixedVertexHandle> = Vec::new();
            let locate = |cdt: &Cdt, uv: DVec2, hint: Option<FixedVertexHandle>| {
                let w = uv * scale;
                let p = Point2::new(tiny0(w.x), tiny0(w.y));
                match hint {
                    Some(h) => cdt.locate_with_hint(p, h),
                    None => cdt.locate(p),
                }
            };
            if let Some((_, uv)) = l0
                && let PositionInTriangulation::OnVertex(h) = locate(&cdt, uv, hint)
            {
                chain.push(h);
            }
            for m in 1..n as usize {
                let v = v0 + (v1 - v0) * m as f64 / n;
                let p = s.eval(u, v);
                if !flatcut_geom::finite3(p) {
                    return Err(TrimError::SurfaceNonFinite { u, v });
                }
                // Only inside a triangle or on an edge inside the face: never on the boundary.
                match locate(&cdt, DVec2::new(u, v), hint) {
                    PositionInTriangulation::OnFace(_) => {}
                    PositionInTriangulation::OnEdge(e)
                        if !cdt.is_constraint_edge(e.as_undirected()) => {}
                    _ => continue,
                }
                let w = DVec2::new(u, v) * scale;
                let local = verts.push(DVec2::new(u, v), p, None);
                let vx = Vx {
                    pos: Point2::new(tiny0(w.x), tiny0(w.y)),
                    local,
                };
                let h = match hint {
                    Some(h) => cdt.insert_with_hint(vx, h),
                    None => cdt.insert(vx),
                }
                .map_err(|_| TrimError::SurfaceNonFinite { u, v })?;
                chain.push(h);
                hint = Some(h);
            }
            if let Some((_, uv)) = l1
                && let PositionInTriangulation::OnVertex(h) = locate(&cdt, uv, hint)
            {
                chain.push(h);
            }
            for c in chain.windows(2) {
                if c[0] == c[1] || cdt.exists_constraint(c[0], c[1]) {
                    continue;
                }
                // A stretch that would cross the boundary (round-off at a tangency) is left
                // to the triangulation.
                if cdt.can_add_constraint(c[0], c[1]) {
                    cdt.add_constraint(c[0], c[1]);
                    inner.insert((
                        c[0].index().min(c[1].index()),
                        c[0].index().max(c[1].index()),
                    ));
                }
            }
        }
    }
    let inside = inside_faces_except(&cdt, &inner);
    Ok(inside_triangles(&cdt, &inside, scale, cover))
}

/// The rulings of a ruled face: those given, or (none given) the distinct u of its loop
/// points, merged within `snap`.
fn ruling_values(loops: &[Vec<(u32, DVec2)>], given: &[f64], snap: f64) -> Vec<f64> {
    let mut us: Vec<f64> = if given.is_empty() {
        loops.iter().flatten().map(|p| p.1.x).collect()
    } else {
        given.to_vec()
    };
    us.sort_by(f64::total_cmp);
    let mut rulings: Vec<f64> = Vec::new();
    for u in us {
        if rulings.last().is_none_or(|&r| u - r > snap) {
            rulings.push(u);
        }
    }
    rulings
}

/// The triangles of `cdt` inside the face (`inside`, per face) as local vertex indices, those
/// collapsed onto one vertex left out; adds their (u, v) area, unscaled by `scale`, to `cover`.
fn inside_triangles(cdt: &Cdt, inside: &[bool], scale: DVec2, cover: &mut f64) -> Vec<[u32; 3]> {
    let mut tris = Vec::new();
    for f in cdt.inner_faces() {
        if !inside[f.fix().index()] {
            continue;
        }
        *cover += uv_area(f.positions().map(|p| DVec2::new(p.x, p.y) / scale));
        let t = f.vertices().map(|v| v.data().local);
        if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
            tris.push(t);
        }
    }
    tris
}

/// The signed area of a (u, v) triangle.
fn uv_area(t: [DVec2; 3]) -> f64 {
    0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check_disk;
    use flatcut_surface::curve::Frame;
    use flatcut_surface::patch::Analytic;
    use std::f64::consts::{PI, TAU};

    /// A loop of points sampled on the surface along a closed (u, v) polyline, with ids from
    /// `next` on.
    fn sample_loop(
        s: &dyn ParamSurface,
        corners: &[DVec2],
        per_side: usize,
        next: &mut u32,
    ) -> Vec<TrimPoint> {
        let mut out = Vec::new();
        for k in 0..corners.len() {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            for m in 0..per_side {
                let uv = a + (b - a) * (m as f64 / per_side as f64);
                out.push(TrimPoint {
                    uv,
                    pos: s.eval(uv.x, uv.y),
                    vertex: *next,
                });
                *next += 1;
            }
        }
        out
    }

    fn sphere() -> Analytic {
        Analytic::sphere(Frame::WORLD, 40.0).unwrap()
    }

    /// Largest distance from the triangles (centroids, edge midpoints) to the sphere of radius
    /// 40 about the origin: | |p| − R |, exact.
    fn sphere_deviation(m: &TrimmedMesh) -> f64 {
        let mut worst: f64 = 0.0;
        for t in &m.mesh.triangles {
            for w in [
                [1.0 / 3.0; 3],
                [0.5, 0.5, 0.0],
                [0.0, 0.5, 0.5],
                [0.5, 0.0, 0.5],
            ] {
                let lin = m.mesh.positions[t[0] as usize] * w[0]
                    + m.mesh.positions[t[1] as usize] * w[1]
                    + m.mesh.positions[t[2] as usize] * w[2];
                worst = worst.max((lin.length() - 40.0).abs());
            }
        }
        worst
    }

    #[test]
    fn sphere_patch_with_a_hole_meets_the_tolerance_and_keeps_its_boundary() {
        let s = sphere();
        let mut id = 0;
        let outer = sample_loop(
            &s,
            &[
                DVec2::new(0.2, -0.6),
                DVec2::new(2.0, -0.6),
                DVec2::new(2.0, 0.8),
                DVec2::new(0.2, 0.8),
            ],
            // 4 mm chords at most: their sagitta on the 40 mm sphere is below 0.05 mm.
            30,
            &mut id,
        );
        let mut hole: Vec<TrimPoint> = (0..24)
            .map(|k| {
                let a = TAU * k as f64 / 24.0;
                let uv = DVec2::new(1.1 + 0.3 * a.cos(), 0.1 + 0.25 * a.sin());
                id += 1;
                TrimPoint {
                    uv,
                    pos: s.eval(uv.x, uv.y),
                    vertex: id,
                }
            })
            .collect();
        hole.reverse();
        let loops = vec![outer.clone(), hole.clone()];
        let tol = Tolerances::DEFAULT.with_chord_mm(0.05);
        let m = tessellate_trimmed(
            &TrimmedFace {
                surface: &s,
                loops: &loops,
                ruled: false,
                rulings: &[],
            },
            &tol,
            &TessOptions::DEFAULT,
        )
        .unwrap();
        let dev = sphere_deviation(&m);
        assert!(dev <= 0.05, "deviation {dev}");
        // Every loop point is a vertex, with its id; boundary = the loops.
        for p in outer.iter().chain(&hole) {
            assert!(m.vertex.contains(&Some(p.vertex)));
        }
        let topo = crate::Topology::build(&m.mesh).unwrap();
        assert_eq!(topo.boundary_loops.len(), 2);
        let bnd: usize = topo.boundary_loops.iter().map(|l| l.len()).sum();
        assert_eq!(bnd, outer.len() + hole.len());
        // Area against the exact spherical zone minus the (approximately elliptical) hole.
        let exact_outer = 40.0f64.powi(2) * 1.8 * (0.8f64.sin() - (-0.6f64).sin());
        assert!(m.mesh.area() < exact_outer);
    }

    #[test]
    fn the_triangles_tile_the_loops_region() {
        let s = sphere();
        let mut id = 0;
        let lp = sample_loop(
            &s,
            &[
                DVec2::new(0.0, -0.3),
                DVec2::new(1.5, -0.3),
                DVec2::new(1.5, 1.1),
                DVec2::new(0.0, 1.1),
            ],
            8,
            &mut id,
        );
        let m = tessellate_trimmed(
            &TrimmedFace {
                surface: &s,
                loops: &[lp],
                ruled: false,
                rulings: &[],
            },
            &Tolerances::DEFAULT.with_chord_mm(0.01),
            &TessOptions::DEFAULT,
        )
        .unwrap();
        let want = 1.5 * 1.4;
        assert!(
            (m.cover_uv - want).abs() < 1e-12 * want,
            "{} vs {want}",
            m.cover_uv
        );
    }

    #[test]
    fn a_loop_that_runs_back_over_itself_is_an_error() {
        let s = Analytic::plane(Frame::WORLD);
        let pts = [
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (10.0, 0.0),
            (0.0, 10.0),
        ];
        let e = plane_face(&s, &[plane_loop(&s, &pts, 0)]).unwrap_err();
        assert!(matches!(e, TrimError::LoopsOverlap { .. }), "{e}");
    }

    #[test]
    fn ruled_cylinder_face_is_exactly_developable() {
        let s = Analytic::cylinder(Frame::WORLD, 30.0).unwrap();
        // A face under a sloping cut: bottom at v = 0, top v = 40 + 10 sin u, u in [0, 2]. Loop
        // points on the rulings u_k on both bottom and top.
        let n = 20;
        let mut id = 0;
        let mut lp = Vec::new();
        for k in 0..=n {
            let u = 2.0 * k as f64 / n as f64;
            let uv = DVec2::new(u, 0.0);
            lp.push(TrimPoint {
                uv,
                pos: s.eval(uv.x, uv.y),
                vertex: id,
            });
            id += 1;
        }
        for k in (0..=n).rev() {
            let u = 2.0 * k as f64 / n as f64;
            let uv = DVec2::new(u, 40.0 + 10.0 * u.sin());
            lp.push(TrimPoint {
                uv,
                pos: s.eval(uv.x, uv.y),
                vertex: id,
            });
            id += 1;
        }
        let m = tessellate_trimmed(
            &TrimmedFace {
                surface: &s,
                loops: &[lp],
                ruled: true,
                rulings: &[],
            },
            &Tolerances::DEFAULT,
            &TessOptions::DEFAULT,
        )
        .unwrap();
        let topo = check_disk(&m.mesh).unwrap();
        assert_eq!(topo.boundary_loops.len(), 1);
        // Exactly developable: the angles around every interior vertex sum to 2π.
        let bnd = crate::stats::boundary_vertices(&m.mesh);
        let mut sum = vec![0.0; m.mesh.positions.len()];
        for (t, tri) in m.mesh.triangles.iter().enumerate() {
            let p = m.mesh.corners(t);
            for k in 0..3 {
                sum[tri[k] as usize] +=
                    (p[(k + 1) % 3] - p[k]).angle_between(p[(k + 2) % 3] - p[k]);
            }
        }
        let interior: Vec<f64> = (0..sum.len())
            .filter(|&v| !bnd[v])
            .map(|v| (sum[v] - TAU).abs())
            .collect();
        assert!(!interior.is_empty());
        assert!(
            interior.iter().all(|d| *d < 1e-12),
            "{:?}",
            interior.iter().cloned().fold(0.0, f64::max)
        );
        // Orientation: counter-clockwise in (u, v).
        let uv = m.mesh.params.as_ref().unwrap();
        for t in &m.mesh.triangles {
            let (a, b, c) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            assert!((b - a).perp_dot(c - a) > 0.0);
        }
        // The area of the strips equals the polygon area in the unrolled plane.
        let unrolled: f64 = 30.0 * 2.0 * 40.0 + 30.0 * 10.0 * (1.0 - 2.0f64.cos());
        assert!((m.mesh.area() - unrolled).abs() < 0.02 * unrolled);
        let _ = PI;
    }

    #[test]
    fn crossing_loops_are_an_error() {
        let s = Analytic::plane(Frame::WORLD);
        let a = plane_loop(&s, &[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)], 0);
        let b = plane_loop(
            &s,
            &[(5.0, 5.0), (15.0, 5.0), (15.0, 15.0), (5.0, 15.0)],
            10,
        );
        let e = plane_face(&s, &[a, b]).unwrap_err();
        assert!(matches!(e, TrimError::LoopsCross { .. }), "{e}");
    }

    /// A loop on a plane through the given (u, v) points, one vertex each from `first`.
    fn plane_loop(s: &Analytic, pts: &[(f64, f64)], first: u32) -> Vec<TrimPoint> {
        pts.iter()
            .enumerate()
            .map(|(k, &(u, v))| TrimPoint {
                uv: DVec2::new(u, v),
                pos: s.eval(u, v),
                vertex: first + k as u32,
            })
            .collect()
    }

    /// The untrimmed-plane tessellation of `loops` at the default tolerances.
    fn plane_face(s: &Analytic, loops: &[Vec<TrimPoint>]) -> Result<TrimmedMesh, TrimError> {
        tessellate_trimmed(
            &TrimmedFace {
                surface: s,
                loops,
                ruled: false,
                rulings: &[],
            },
            &Tolerances::DEFAULT,
            &TessOptions::DEFAULT,
        )
    }

    #[test]
    fn rounding_noise_below_the_triangulators_range_is_zero() {
        // HiCAD writes plane axes with components of 1e-17 and 1e-33: a corner lands at
        // v = 1.8e-45, below spade's smallest accepted magnitude (2^-142).
        let s = Analytic::plane(Frame::WORLD);
        let corners = [
            (-100.0, 1.7789921910373654e-45),
            (0.0, 0.0),
            (0.0, 100.0),
            (-100.0, 100.0),
        ];
        let m = plane_face(&s, &[plane_loop(&s, &corners, 0)]).unwrap();
        assert!((m.cover_uv - 1e4).abs() < 1e-9, "{}", m.cover_uv);
    }

    #[test]
    fn a_loop_beyond_the_triangulators_range_is_named() {
        let s = Analytic::plane(Frame::WORLD);
        let corners = [(0.0, 0.0), (1e61, 0.0), (1e61, 1e61), (0.0, 1e61)];
        let e = plane_face(&s, &[plane_loop(&s, &corners, 0)]).unwrap_err();
        assert!(matches!(e, TrimError::OutOfRange { index: 0, .. }), "{e}");
    }
}
