//! Adaptive tessellation of parametric surfaces to a chordal tolerance.
//!
//! Algorithm: a coarse initial triangulation of each parameter domain, sized from the surface's
//! 3D extent in u and in v (so a long thin strip starts with long thin cells in parameter space
//! and near-isotropic triangles in 3D), refined by **longest-edge bisection** (Rivara) where the
//! edge length is measured in 3D, so the refinement follows the metric of the surface, not the
//! parameterisation. Longest-edge bisection keeps the smallest angle bounded below by a fixed
//! fraction of the initial one, so triangles stay well shaped; a conformity closure removes every
//! hanging node after each round.
//!
//! Refinement criterion (per triangle, in mm): for a surface that is locally quadratic over the
//! triangle, the deviation between the triangle and the surface at barycentric point λ is
//! Σ_{i<j} λ_i λ_j d_ij where d_ij/4 is the deviation at the midpoint of edge ij. Since
//! Σ λ_i λ_j ≤ 1/3, the maximum deviation is at most 4/3 of the largest edge-midpoint deviation;
//! we refine while max(centroid deviation, 4/3 · max midpoint deviation) exceeds the chordal
//! tolerance, and while the surface normal turns by more than [`MAX_NORMAL_TURN`] over a triangle
//! (so no feature is missed by a coarse sample). The deviation is measured between the triangle
//! point and the surface point at the same interpolated (u, v), which bounds the Hausdorff
//! distance in both directions.
//!
//! Multi-patch models are tessellated jointly: corners on shared boundaries are welded across
//! patches within `Tolerances::weld_mm`, a boundary vertex of one patch lying on a boundary edge
//! of another splits that edge at the same vertex (its parameters in the other patch are found by
//! projection), and every later split of a shared edge is one shared vertex. The result has no
//! cracks and no T-junctions even when the two patches parameterise their common edge at
//! different speeds. Within one patch, vertices are never welded (a closed cylinder stays cut at
//! its parameter seam, which is where a flattening needs it cut anyway).
//!
//! Poles: a domain side that collapses to one point (the teapot's lid top and bottom centre, a
//! sphere's poles) is one vertex from the start, the half-cells at it are dropped, and every
//! edge from it is split on the meridian of its other end, so the pole is an ordinary fan
//! vertex and no zero-area triangle is ever made there. Across patches, coincident boundary
//! vertices are welded only where a side of one patch leaves the point along a side of the
//! other: patches that merely touch at a point (the teapot's handle on the body) stay separate
//! manifold components.
//!
//! Hand-written rather than `spade`: a constrained Delaunay refinement works in the parameter
//! plane, where the metric of the surface is lost; bisection in the surface metric is what keeps
//! 3D triangles well shaped on strongly anisotropic parameterisations.

use std::collections::BTreeMap;

use flatcut_geom::num::{GoldenStop, golden_section_min};
use flatcut_geom::{DVec2, DVec3, Tolerances};
use flatcut_surface::{DomainKind, ParamSurface};

use crate::TriMesh;

/// Largest turn of the surface normal across one triangle (radians): 20° guarantees the
/// quadratic error model behind the chordal test holds before the test is trusted.
pub const MAX_NORMAL_TURN: f64 = 20.0 * std::f64::consts::PI / 180.0;
/// Default cap on the number of vertices, to fail cleanly instead of exhausting memory.
pub const DEFAULT_MAX_VERTICES: usize = 2_000_000;
/// Cells along the longer parameter direction of the initial grid.
const INIT_CELLS_LONG: usize = 8;
/// Minimum cells along either direction (4 cells resolve a closed direction without
/// degenerate triangles).
const INIT_CELLS_MIN: usize = 4;
/// Samples per direction used to measure the patch extent for the initial grid.
const EXTENT_SAMPLES: usize = 16;
/// Triangles whose longest edge is below this fraction of the chordal tolerance are not split
/// further: the deviation of such a triangle is below round-off of a sane surface, and this stops
/// refinement at parametric singularities.
const MIN_EDGE_OVER_CHORD: f64 = 1e-3;
/// Triangles whose longest edge is below this multiple of the weld tolerance are not split
/// either: the output collapses edges up to the weld tolerance, and a split this close to it would
/// leave edges that collapse into non-manifold fans (at the poles of collapsed patch sides).
const MIN_EDGE_OVER_WELD: f64 = 4.0;
/// |su × sv| below this fraction of max(|su|², |sv|²) is a degenerate point (a pole): the
/// cross product is then rounding noise (≈ 1e-16 relative at the teapot's lid and bottom
/// centres), far below this, while a genuine normal near the pole is ≳ 1e-6 relative.
const DEGENERATE_NORMAL_REL: f64 = 1e-10;
/// Parameter step (fraction of the domain) of the probes that tell which sides of two patches
/// leave a shared point in the same direction.
const PROBE_STEP: f64 = 1.0 / 64.0;
/// Two probes match when their directions from the shared point differ by less than this
/// (cosine of 5°). A side both patches share leaves in the same direction whatever the speeds
/// of the two parameterisations (the chord over one probe step of a side turning 90° across
/// the patch is within 1° of the tangent), while distinct sides meeting at a corner are as far
/// apart as the corner's angle, and a corner of 5° is a degenerate patch.
const PROBE_MATCH_COS: f64 = 0.996_194_698_091_745_5;
/// Parameter tolerance of the projection of a shared vertex onto another patch's boundary edge.
const PROJECT_T_TOL: f64 = 1e-13;

/// Why a surface could not be tessellated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TessError {
    #[error("chordal tolerance must be finite and > 0 mm, got {0}")]
    /// The chordal tolerance given is not finite and positive.
    BadTolerance(f64),
    #[error("no surface to tessellate")]
    /// There is no patch to tessellate.
    NoPatches,
    #[error("patch {patch} evaluates to a non-finite point at (u, v) = ({u}, {v})")]
    /// A patch evaluates to a NaN or infinite point.
    NonFinite {
        /// 0-based index of the patch.
        patch: usize,
        /// Parameter u of the point.
        u: f64,
        /// Parameter v of the point.
        v: f64,
    },
    #[error("patch {patch} has an empty or non-finite parameter domain")]
    /// A patch's parameter domain is empty or not finite.
    BadDomain {
        /// 0-based index of the patch.
        patch: usize,
    },
    #[error(
        "tessellation needs more than {limit} vertices at chordal tolerance {chord_mm} mm; raise the tolerance"
    )]
    /// The tolerance calls for more vertices than the limit.
    TooManyVertices {
        /// The vertex limit ([`TessOptions::max_vertices`]).
        limit: usize,
        /// The chordal tolerance asked for (mm).
        chord_mm: f64,
    },
    /// A face of a trimmed (CAD) model could not be tessellated; the message names it.
    #[error("{0}")]
    Face(String),
}

/// Options of the tessellator beyond the tolerances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TessOptions {
    /// Give up with [`TessError::TooManyVertices`] beyond this many vertices.
    pub max_vertices: usize,
    /// Largest normal turn across a triangle in radians.
    pub max_normal_turn: f64,
}

impl TessOptions {
    /// The default limits: [`DEFAULT_MAX_VERTICES`] and [`MAX_NORMAL_TURN`].
    pub const DEFAULT: Self = Self {
        max_vertices: DEFAULT_MAX_VERTICES,
        max_normal_turn: MAX_NORMAL_TURN,
    };

    /// These options with a vertex limit of `n`.
    pub const fn with_max_vertices(mut self, n: usize) -> Self {
        self.max_vertices = n;
        self
    }

    /// These options with a largest normal turn of `a` radians.
    pub const fn with_max_normal_turn(mut self, a: f64) -> Self {
        self.max_normal_turn = a;
        self
    }
}

impl Default for TessOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Tessellates one patch: positions, (u, v) per vertex in `params`, Hausdorff distance to the
/// surface ≤ `tol.chord_mm`.
pub fn tessellate(surface: &dyn ParamSurface, tol: &Tolerances) -> Result<TriMesh, TessError> {
    let mut m = tessellate_with(&[surface], tol, &TessOptions::DEFAULT)?;
    m.patch_of_vertex = None;
    Ok(m)
}

/// Tessellates a multi-patch model into one crack-free mesh; `patch_of_vertex` and `params` give
/// each vertex's (first) patch and its parameters there.
pub fn tessellate_patches(
    surfaces: &[&dyn ParamSurface],
    tol: &Tolerances,
) -> Result<TriMesh, TessError> {
    tessellate_with(surfaces, tol, &TessOptions::DEFAULT)
}

/// Tessellates the patches of a multi-patch model into one crack-free mesh, welding shared
/// sides within the larger of `tol.weld_mm` and the model's own weld tolerance.
pub fn tessellate_model(
    model: &flatcut_surface::patch::Model,
    tol: &Tolerances,
) -> Result<TriMesh, TessError> {
    let refs: Vec<&dyn ParamSurface> = model.patches().iter().map(|p| p.as_ref()).collect();
    let tol = tol.with_weld_mm(tol.weld_mm.max(model.weld_mm()));
    tessellate_patches(&refs, &tol)
}

/// A short step from a boundary vertex along a side of its patch.
#[derive(Clone, Copy, Debug)]
struct Probe {
    /// Unit direction from the vertex to the step's point.
    dir: DVec3,
    point: DVec3,
    patch: u32,
    /// Parameters of the vertex and of the step's point.
    from: DVec2,
    to: DVec2,
}

#[derive(Clone, Copy, Debug)]
struct Tri {
    v: [u32; 3],
    uv: [DVec2; 3],
    patch: u32,
    alive: bool,
    checked: bool,
}

struct Builder<'a> {
    surfs: &'a [&'a dyn ParamSurface],
    pos: Vec<DVec3>,
    /// First patch and parameters of each vertex.
    home: Vec<(u32, DVec2)>,
    /// Boundary vertices per patch, flag.
    on_boundary: Vec<bool>,
    tris: Vec<Tri>,
    /// Edge (lo, hi) -> split vertex and the patch that created it.
    split: BTreeMap<(u32, u32), (u32, u32)>,
    /// Alive triangles on each edge (lo, hi).
    edge_tris: BTreeMap<(u32, u32), Vec<u32>>,
    /// Triangles to check for hanging vertices in the conformity closure.
    work: Vec<u32>,
    opts: TessOptions,
    chord: f64,
    /// Weld tolerance: edges this short are collapsed in the output.
    weld: f64,
    /// Per patch, which domain sides are collapsed to a point (a pole), in the order
    /// u = lo, u = hi, v = lo, v = hi.
    collapsed: Vec<[bool; 4]>,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

fn domain_ok(s: &dyn ParamSurface) -> bool {
    let d = s.domain();
    d.u.0.is_finite()
        && d.u.1.is_finite()
        && d.v.0.is_finite()
        && d.v.1.is_finite()
        && d.u.1 > d.u.0
        && d.v.1 > d.v.0
}

impl Builder<'_> {
    /// Which sides of the patch's domain collapse to one point within the weld tolerance: the
    /// side is sampled at [`EXTENT_SAMPLES`] + 1 points. Triangular domains are not checked
    /// (none of the supported triangular patches has a collapsed side).
    fn find_collapsed_sides(&self, patch: u32) -> Result<[bool; 4], TessError> {
        let s = self.surfs[patch as usize];
        if s.domain_kind() != DomainKind::Rectangle {
            return Ok([false; 4]);
        }
        let d = s.domain();
        let mut out = [false; 4];
        for (side, flag) in out.iter_mut().enumerate() {
            let at = |t: f64| match side {
                0 => DVec2::new(d.u.0, d.v.0 + (d.v.1 - d.v.0) * t),
                1 => DVec2::new(d.u.1, d.v.0 + (d.v.1 - d.v.0) * t),
                2 => DVec2::new(d.u.0 + (d.u.1 - d.u.0) * t, d.v.0),
                _ => DVec2::new(d.u.0 + (d.u.1 - d.u.0) * t, d.v.1),
            };
            let first = self.eval(patch, at(0.0))?;
            let mut spread: f64 = 0.0;
            for i in 1..=EXTENT_SAMPLES {
                let p = self.eval(patch, at(i as f64 / EXTENT_SAMPLES as f64))?;
                spread = spread.max(p.distance(first));
            }
            *flag = spread <= self.weld;
        }
        Ok(out)
    }

    /// The parameters of a corner at `uv` as seen from the other end `other` of an edge. On a
    /// collapsed side (a pole) the coordinate along the side is arbitrary: every value names the
    /// same point. The pole's parameters towards `other` are the ones on the iso-line through
    /// `other` (the meridian), so every edge from the pole is a meridian in the parameter plane
    /// and its splits land on the meridian whichever triangle makes them.
    fn toward(&self, patch: u32, uv: DVec2, other: DVec2) -> DVec2 {
        let c = self.collapsed[patch as usize];
        let d = self.surfs[patch as usize].domain();
        if c[0] && uv.x == d.u.0 && other.x != d.u.0 {
            DVec2::new(d.u.0, other.y)
        } else if c[1] && uv.x == d.u.1 && other.x != d.u.1 {
            DVec2::new(d.u.1, other.y)
        } else if c[2] && uv.y == d.v.0 && other.y != d.v.0 {
            DVec2::new(other.x, d.v.0)
        } else if c[3] && uv.y == d.v.1 && other.y != d.v.1 {
            DVec2::new(other.x, d.v.1)
        } else {
            uv
        }
    }

    /// Parameters of the two ends of edge a–b, each pole end moved onto the other end's
    /// meridian (see [`Self::toward`]).
    fn edge_uvs(&self, patch: u32, ua: DVec2, ub: DVec2) -> (DVec2, DVec2) {
        let ua2 = self.toward(patch, ua, ub);
        (ua2, self.toward(patch, ub, ua2))
    }

    /// The parameters of a triangle's corners with each pole corner moved onto the mean
    /// meridian of the two other corners (so the centroid lies inside the wedge of the fan).
    fn corner_uvs(&self, patch: u32, uv: [DVec2; 3]) -> [DVec2; 3] {
        let mut out = uv;
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            out[k] = self.toward(patch, uv[k], 0.5 * (uv[i] + uv[j]));
        }
        out
    }

    fn eval(&self, patch: u32, uv: DVec2) -> Result<DVec3, TessError> {
        let p = self.surfs[patch as usize].eval(uv.x, uv.y);
        if flatcut_geom::finite3(p) {
            Ok(p)
        } else {
            Err(TessError::NonFinite {
                patch: patch as usize,
                u: uv.x,
                v: uv.y,
            })
        }
    }

    fn add_vertex(
        &mut self,
        p: DVec3,
        patch: u32,
        uv: DVec2,
        boundary: bool,
    ) -> Result<u32, TessError> {
        if self.pos.len() >= self.opts.max_vertices {
            return Err(TessError::TooManyVertices {
                limit: self.opts.max_vertices,
                chord_mm: self.chord,
            });
        }
        self.pos.push(p);
        self.home.push((patch, uv));
        self.on_boundary.push(boundary);
        Ok((self.pos.len() - 1) as u32)
    }

    fn on_domain_boundary(&self, patch: u32, uv: DVec2) -> bool {
        let s = self.surfs[patch as usize];
        let d = s.domain();
        // Exact comparisons: boundary parameters are produced by averaging two boundary values of
        // the same coordinate, which is exact for the constant coordinate.
        match s.domain_kind() {
            DomainKind::Rectangle => {
                uv.x == d.u.0 || uv.x == d.u.1 || uv.y == d.v.0 || uv.y == d.v.1
            }
            DomainKind::Triangle => uv.x == 0.0 || uv.y == 0.0 || uv.x + uv.y == 1.0,
        }
    }

    /// Initial triangulation of one patch.
    fn init_patch(&mut self, patch: u32) -> Result<(), TessError> {
        let s = self.surfs[patch as usize];
        let d = s.domain();
        match s.domain_kind() {
            DomainKind::Rectangle => {
                let n = EXTENT_SAMPLES;
                let mut grid = Vec::with_capacity((n + 1) * (n + 1));
                for j in 0..=n {
                    for i in 0..=n {
                        let uv = DVec2::new(
                            d.u.0 + (d.u.1 - d.u.0) * i as f64 / n as f64,
                            d.v.0 + (d.v.1 - d.v.0) * j as f64 / n as f64,
                        );
                        grid.push(self.eval(patch, uv)?);
                    }
                }
                let at = |i: usize, j: usize| grid[j * (n + 1) + i];
                let lu = (0..=n)
                    .map(|j| (0..n).map(|i| at(i, j).distance(at(i + 1, j))).sum::<f64>())
                    .fold(0.0, f64::max);
                let lv = (0..=n)
                    .map(|i| (0..n).map(|j| at(i, j).distance(at(i, j + 1))).sum::<f64>())
                    .fold(0.0, f64::max);
                let h = lu.max(lv) / INIT_CELLS_LONG as f64;
                let cells = |l: f64| -> usize {
                    if h > 0.0 {
                        ((l / h).ceil() as usize).clamp(INIT_CELLS_MIN, INIT_CELLS_LONG)
                    } else {
                        INIT_CELLS_MIN
                    }
                };
                let (nu, nv) = (cells(lu), cells(lv));
                let collapsed = self.collapsed[patch as usize];
                let mut pole_id: [Option<u32>; 4] = [None; 4];
                let mut ids = Vec::with_capacity((nu + 1) * (nv + 1));
                let mut uvs = Vec::with_capacity((nu + 1) * (nv + 1));
                for j in 0..=nv {
                    for i in 0..=nu {
                        let u = if i == nu {
                            d.u.1
                        } else {
                            d.u.0 + (d.u.1 - d.u.0) * i as f64 / nu as f64
                        };
                        let v = if j == nv {
                            d.v.1
                        } else {
                            d.v.0 + (d.v.1 - d.v.0) * j as f64 / nv as f64
                        };
                        let uv = DVec2::new(u, v);
                        let p = self.eval(patch, uv)?;
                        let b = i == 0 || j == 0 || i == nu || j == nv;
                        // All grid points of a collapsed side are one vertex (the pole): the
                        // fan around it then has no zero-area triangles to fold over later.
                        let on_sides = [i == 0, i == nu, j == 0, j == nv];
                        let pole = (0..4)
                            .filter(|&k| collapsed[k] && on_sides[k])
                            .find_map(|k| pole_id[k]);
                        let v = match pole {
                            Some(v) => v,
                            None => self.add_vertex(p, patch, uv, b)?,
                        };
                        for k in 0..4 {
                            if collapsed[k] && on_sides[k] {
                                pole_id[k] = Some(v);
                            }
                        }
                        ids.push(v);
                        uvs.push(uv);
                    }
                }
                let id = |i: usize, j: usize| j * (nu + 1) + i;
                for j in 0..nv {
                    for i in 0..nu {
                        let (a, b, c, e) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                        // Alternate diagonals so the initial mesh has no directional bias.
                        let quads = if (i + j) % 2 == 0 {
                            [[a, b, c], [a, c, e]]
                        } else {
                            [[a, b, e], [b, c, e]]
                        };
                        for q in quads {
                            let v = q.map(|k| ids[k]);
                            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                                // Half of a cell at a pole: a segment, not a triangle.
                                continue;
                            }
                            self.tris.push(Tri {
                                v,
                                uv: q.map(|k| uvs[k]),
                                patch,
                                alive: true,
                                checked: false,
                            });
                        }
                    }
                }
            }
            DomainKind::Triangle => {
                let k = INIT_CELLS_MIN;
                let mut ids = BTreeMap::new();
                let mut uvs = BTreeMap::new();
                for j in 0..=k {
                    for i in 0..=(k - j) {
                        let uv = DVec2::new(i as f64 / k as f64, j as f64 / k as f64);
                        let uv = if i + j == k {
                            DVec2::new(uv.x, 1.0 - uv.x)
                        } else {
                            uv
                        };
                        let p = self.eval(patch, uv)?;
                        let b = i == 0 || j == 0 || i + j == k;
                        ids.insert((i, j), self.add_vertex(p, patch, uv, b)?);
                        uvs.insert((i, j), uv);
                    }
                }
                for j in 0..k {
                    for i in 0..(k - j) {
                        let mut tri_list = vec![[(i, j), (i + 1, j), (i, j + 1)]];
                        if i + j + 1 < k {
                            tri_list.push([(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
                        }
                        for t in tri_list {
                            self.tris.push(Tri {
                                v: t.map(|c| ids[&c]),
                                uv: t.map(|c| uvs[&c]),
                                patch,
                                alive: true,
                                checked: false,
                            });
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Parameters in `patch` of the point on the segment uv_a..uv_b closest to `target`.
    fn project_on_edge(&self, patch: u32, uv_a: DVec2, uv_b: DVec2, target: DVec3) -> DVec2 {
        let s = self.surfs[patch as usize];
        let f = |t: f64| eval_at(s, uv_a.lerp(uv_b, t)).distance_squared(target);
        // The distance along a short boundary arc to a point on it is unimodal.
        let m = golden_section_min(f, 0.0, 1.0, GoldenStop::Width(PROJECT_T_TOL));
        uv_a.lerp(uv_b, 0.5 * (m.lo + m.hi))
    }

    /// Bisects triangle `t` at its edge `k` (from corner k to k+1), creating or reusing the split
    /// vertex.
    fn bisect(&mut self, t: usize, k: usize) -> Result<(), TessError> {
        let tri = self.tris[t];
        let (a, b, c) = (tri.v[k], tri.v[(k + 1) % 3], tri.v[(k + 2) % 3]);
        let (ua, ub) = self.edge_uvs(tri.patch, tri.uv[k], tri.uv[(k + 1) % 3]);
        let uc = tri.uv[(k + 2) % 3];
        let (m, um) = match self.split.get(&key(a, b)).copied() {
            Some((m, creator)) if creator == tri.patch && self.home[m as usize].0 == tri.patch => {
                (m, 0.5 * (ua + ub))
            }
            Some((m, _)) => {
                let um = self.project_on_edge(tri.patch, ua, ub, self.pos[m as usize]);
                (m, um)
            }
            None => {
                let um = 0.5 * (ua + ub);
                let p = self.eval(tri.patch, um)?;
                let boundary = self.on_domain_boundary(tri.patch, um);
                let m = self.add_vertex(p, tri.patch, um, boundary)?;
                self.split.insert(key(a, b), (m, tri.patch));
                (m, um)
            }
        };
        self.tris[t].alive = false;
        self.unindex(t as u32);
        for (v, uv) in [([a, m, c], [ua, um, uc]), ([m, b, c], [um, ub, uc])] {
            self.tris.push(Tri {
                v,
                uv,
                patch: tri.patch,
                alive: true,
                checked: false,
            });
            let id = (self.tris.len() - 1) as u32;
            self.index(id);
            self.work.push(id);
        }
        // The neighbours across the split edge now have a hanging vertex.
        self.wake_edge(key(a, b));
        Ok(())
    }

    fn index(&mut self, t: u32) {
        let v = self.tris[t as usize].v;
        for k in 0..3 {
            self.edge_tris
                .entry(key(v[k], v[(k + 1) % 3]))
                .or_default()
                .push(t);
        }
    }

    fn unindex(&mut self, t: u32) {
        let v = self.tris[t as usize].v;
        for k in 0..3 {
            if let Some(l) = self.edge_tris.get_mut(&key(v[k], v[(k + 1) % 3])) {
                l.retain(|&x| x != t);
            }
        }
    }

    /// Rebuilds the edge index from the alive triangles (after vertices were renumbered).
    fn reindex(&mut self) {
        self.edge_tris.clear();
        for t in 0..self.tris.len() as u32 {
            if self.tris[t as usize].alive {
                self.index(t);
            }
        }
    }

    /// Queues the alive triangles on an edge for the closure.
    fn wake_edge(&mut self, e: (u32, u32)) {
        if let Some(l) = self.edge_tris.get(&e) {
            self.work.extend_from_slice(l);
        }
    }

    /// Index (0..3) of the longest edge of triangle `t` in 3D, ties broken by vertex ids so that
    /// every triangle sharing an edge ranks it identically.
    fn longest_edge(&self, t: usize) -> usize {
        let v = self.tris[t].v;
        let rank = |k: usize| {
            let (a, b) = key(v[k], v[(k + 1) % 3]);
            (self.pos[a as usize].distance(self.pos[b as usize]), a, b)
        };
        let mut best = 0;
        for k in 1..3 {
            let (l, a, b) = rank(k);
            let (lb, ab, bb) = rank(best);
            if l > lb || (l == lb && (a, b) > (ab, bb)) {
                best = k;
            }
        }
        best
    }

    /// Bisects every triangle that has a split edge until the triangulation is conforming.
    /// Works from the queue of triangles touched by splits, so each round costs in proportion to
    /// the triangles it changes.
    fn close(&mut self) -> Result<(), TessError> {
        while let Some(t) = self.work.pop() {
            let t = t as usize;
            if !self.tris[t].alive {
                continue;
            }
            let v = self.tris[t].v;
            let hanging = (0..3).any(|k| self.split.contains_key(&key(v[k], v[(k + 1) % 3])));
            if hanging {
                let k = self.longest_edge(t);
                self.bisect(t, k)?;
            }
        }
        Ok(())
    }

    /// Unit directions from vertex `v` to points a short step along every side of its patch's domain that passes
    /// through it, both ways: from its own parameters and from every domain corner at the same
    /// point (a pole stands for a whole side, so both its end corners' sides leave it). Steps
    /// that stay within `weld` of the vertex (along a collapsed side) are left out.
    fn side_probes(&self, v: u32, weld: f64) -> Vec<Probe> {
        let (patch, uv) = self.home[v as usize];
        let s = self.surfs[patch as usize];
        let d = s.domain();
        let here = self.pos[v as usize];
        let mut starts = vec![uv];
        if s.domain_kind() == DomainKind::Rectangle {
            for c in [
                DVec2::new(d.u.0, d.v.0),
                DVec2::new(d.u.1, d.v.0),
                DVec2::new(d.u.0, d.v.1),
                DVec2::new(d.u.1, d.v.1),
            ] {
                if c != uv && eval_at(s, c).distance(here) <= weld {
                    starts.push(c);
                }
            }
        }
        let mut out = Vec::new();
        for q in starts {
            for (axis, (lo, hi)) in [(0, d.u), (1, d.v)] {
                // Only along a side: the other coordinate sits on its bound.
                let (x, other, (olo, ohi)) = if axis == 0 {
                    (q.x, q.y, d.v)
                } else {
                    (q.y, q.x, d.u)
                };
                if other != olo && other != ohi {
                    continue;
                }
                let step = (hi - lo) * PROBE_STEP;
                for x in [x + step, x - step] {
                    if x < lo || x > hi {
                        continue;
                    }
                    let r = if axis == 0 {
                        DVec2::new(x, q.y)
                    } else {
                        DVec2::new(q.x, x)
                    };
                    let p = eval_at(s, r);
                    if p.distance(here) > weld {
                        out.push(Probe {
                            dir: (p - here).normalize(),
                            point: p,
                            patch,
                            from: q,
                            to: r,
                        });
                    }
                }
            }
        }
        out
    }

    /// Welds initial boundary vertices of different patches and splits boundary edges at foreign
    /// boundary vertices lying on them, until the patches meet edge to edge.
    fn conform_patches(&mut self, weld: f64) -> Result<(), TessError> {
        // 1. Weld coincident boundary vertices across patches.
        let bverts: Vec<u32> = (0..self.pos.len() as u32)
            .filter(|&v| self.on_boundary[v as usize])
            .collect();
        let pts: Vec<DVec3> = bverts.iter().map(|&v| self.pos[v as usize]).collect();
        let (reps, remap) = crate::weld::weld_points(&pts, weld);
        // `remap` numbers clusters, not input points: a cluster stands for its first member.
        // (Indexing `bverts` by the cluster number welded a third patch's corners to unrelated
        // vertices of the second, and the closure then chased those vertices without end.)
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); reps.len()];
        for (i, &r) in remap.iter().enumerate() {
            members[r as usize].push(bverts[i]);
        }
        // Within a cluster, weld only vertices whose patches share a side there (a side of one
        // leaves the point in the same direction as a side of the other), and never two
        // vertices of one patch: patches that merely touch at a point (the teapot's handle
        // ends on a body corner) stay apart, so every vertex keeps one fan, and a closed
        // patch's parameter seam stays open.
        let mut rep: Vec<u32> = (0..self.pos.len() as u32).collect();
        for m in &members {
            if m.len() < 2 {
                continue;
            }
            let patch = |v: u32| self.home[v as usize].0;
            let probes: Vec<Vec<Probe>> = m.iter().map(|&v| self.side_probes(v, weld)).collect();
            // Classes by index into `m`, with the patches each holds.
            let mut class: Vec<usize> = (0..m.len()).collect();
            let mut patches: Vec<Vec<u32>> = m.iter().map(|&v| vec![patch(v)]).collect();
            for j in 1..m.len() {
                for i in 0..j {
                    let (ci, cj) = (class[i], class[j]);
                    if ci == cj || patches[ci].iter().any(|p| patches[cj].contains(p)) {
                        continue;
                    }
                    // Same direction, and the nearer of the two probe points lies on the other's
                    // stretch of side (a side of another patch merely tangent there, like the
                    // handle's end on the body's ring, leaves it at second order). Checking
                    // within one step keeps the projection on a monotone arc.
                    let on_side = |a: &Probe, b: &Probe| {
                        let uv = self.project_on_edge(b.patch, b.from, b.to, a.point);
                        eval_at(self.surfs[b.patch as usize], uv).distance(a.point) <= weld
                    };
                    let linked = probes[j].iter().any(|a| {
                        probes[i].iter().any(|b| {
                            a.dir.dot(b.dir) >= PROBE_MATCH_COS && (on_side(a, b) || on_side(b, a))
                        })
                    });
                    if linked {
                        let (keep, gone) = (ci.min(cj), ci.max(cj));
                        for c in class.iter_mut() {
                            if *c == gone {
                                *c = keep;
                            }
                        }
                        let moved = std::mem::take(&mut patches[gone]);
                        patches[keep].extend(moved);
                    }
                }
            }
            for (k, &v) in m.iter().enumerate() {
                rep[v as usize] = m[class[k]];
            }
        }
        for t in 0..self.tris.len() {
            let v = self.tris[t].v.map(|v| rep[v as usize]);
            self.tris[t].v = v;
            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                self.tris[t].alive = false;
            }
        }
        self.reindex();
        // 2. Split boundary edges at foreign boundary vertices (T-junctions), repeatedly.
        loop {
            let mut registered = false;
            let live: Vec<usize> = (0..self.tris.len())
                .filter(|&t| self.tris[t].alive)
                .collect();
            let bset: Vec<u32> = (0..self.pos.len() as u32)
                .filter(|&v| {
                    self.on_boundary[v as usize] && rep.get(v as usize).is_none_or(|&r| r == v)
                })
                .collect();
            for &t in &live {
                let tri = self.tris[t];
                for k in 0..3 {
                    let (a, b) = (tri.v[k], tri.v[(k + 1) % 3]);
                    let (ua, ub) = self.edge_uvs(tri.patch, tri.uv[k], tri.uv[(k + 1) % 3]);
                    if !self.on_domain_boundary(tri.patch, ua)
                        || !self.on_domain_boundary(tri.patch, ub)
                        || self.split.contains_key(&key(a, b))
                    {
                        continue;
                    }
                    let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
                    let ab = pb - pa;
                    let len2 = ab.length_squared();
                    if len2 == 0.0 {
                        continue;
                    }
                    let mut best: Option<(f64, u32)> = None;
                    for &c in &bset {
                        if c == a || c == b || self.home[c as usize].0 == tri.patch {
                            continue;
                        }
                        let pc = self.pos[c as usize];
                        let s = (pc - pa).dot(ab) / len2;
                        if !(s > 0.0 && s < 1.0) {
                            continue;
                        }
                        // Cheap filter: the point must be near the chord (within the sag).
                        if (pa + ab * s).distance(pc) > 0.5 * len2.sqrt() {
                            continue;
                        }
                        let um = self.project_on_edge(tri.patch, ua, ub, pc);
                        if eval_at(self.surfs[tri.patch as usize], um).distance(pc) <= weld {
                            let score = (s - 0.5).abs();
                            if best.is_none_or(|(bs, _)| score < bs) {
                                best = Some((score, c));
                            }
                        }
                    }
                    if let Some((_, c)) = best {
                        self.split.insert(key(a, b), (c, self.home[c as usize].0));
                        self.wake_edge(key(a, b));
                        registered = true;
                    }
                }
            }
            if !registered {
                return Ok(());
            }
            self.close()?;
        }
    }

    /// Whether triangle `t` must be refined.
    fn needs_split(&self, t: usize) -> Result<bool, TessError> {
        let tri = self.tris[t];
        let p = tri.v.map(|v| self.pos[v as usize]);
        let longest = (0..3)
            .map(|k| p[k].distance(p[(k + 1) % 3]))
            .fold(0.0, f64::max);
        if longest < (MIN_EDGE_OVER_CHORD * self.chord).max(MIN_EDGE_OVER_WELD * self.weld) {
            return Ok(false);
        }
        let s = self.surfs[tri.patch as usize];
        let mut dev: f64 = 0.0;
        for k in 0..3 {
            let (ua, ub) = self.edge_uvs(tri.patch, tri.uv[k], tri.uv[(k + 1) % 3]);
            let q = self.eval(tri.patch, 0.5 * (ua + ub))?;
            dev = dev.max(q.distance(0.5 * (p[k] + p[(k + 1) % 3])));
        }
        let cuv = self.corner_uvs(tri.patch, tri.uv);
        let uc = (cuv[0] + cuv[1] + cuv[2]) / 3.0;
        let qc = self.eval(tri.patch, uc)?;
        let dev = (4.0 / 3.0 * dev).max(qc.distance((p[0] + p[1] + p[2]) / 3.0));
        if dev > self.chord {
            return Ok(true);
        }
        // Normal turn between the corners and the centroid.
        // At a collapsed side (a pole) one tangent vanishes and su × sv is round-off whose
        // direction is arbitrary: such a point has no normal to compare, only the chordal test.
        let normal = |uv: DVec2| {
            let (_, su, sv) = s.deriv1(uv.x, uv.y);
            let n = su.cross(sv);
            let scale = su.length_squared().max(sv.length_squared());
            if n.length() <= DEGENERATE_NORMAL_REL * scale {
                None
            } else {
                n.try_normalize()
            }
        };
        let nc = normal(uc);
        if let Some(nc) = nc {
            let cos_max = self.opts.max_normal_turn.cos();
            for k in 0..3 {
                if let Some(nk) = normal(tri.uv[k])
                    && nk.dot(nc) < cos_max
                {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    fn refine(&mut self) -> Result<(), TessError> {
        // Triangles below `start` are dead or already passed the test: triangles are immutable
        // and new ones are appended, so each round only looks at the new ones.
        let mut start = 0;
        loop {
            let mut marked = Vec::new();
            let end = self.tris.len();
            for t in start..end {
                if self.tris[t].alive && !self.tris[t].checked {
                    if self.needs_split(t)? {
                        marked.push(t);
                    } else {
                        self.tris[t].checked = true;
                    }
                }
            }
            start = end;
            if marked.is_empty() {
                return Ok(());
            }
            for t in marked {
                if self.tris[t].alive {
                    let k = self.longest_edge(t);
                    self.bisect(t, k)?;
                }
            }
            self.close()?;
        }
    }
}

/// Evaluation at a parameter point given as a vector.
fn eval_at(s: &dyn ParamSurface, uv: DVec2) -> DVec3 {
    s.eval(uv.x, uv.y)
}

/// [`tessellate_patches`] with explicit options.
pub fn tessellate_with(
    surfaces: &[&dyn ParamSurface],
    tol: &Tolerances,
    opts: &TessOptions,
) -> Result<TriMesh, TessError> {
    if !(tol.chord_mm.is_finite() && tol.chord_mm > 0.0) {
        return Err(TessError::BadTolerance(tol.chord_mm));
    }
    if surfaces.is_empty() {
        return Err(TessError::NoPatches);
    }
    for (i, s) in surfaces.iter().enumerate() {
        if !domain_ok(*s) {
            return Err(TessError::BadDomain { patch: i });
        }
    }
    let mut b = Builder {
        surfs: surfaces,
        pos: Vec::new(),
        home: Vec::new(),
        on_boundary: Vec::new(),
        tris: Vec::new(),
        split: BTreeMap::new(),
        edge_tris: BTreeMap::new(),
        work: Vec::new(),
        opts: *opts,
        chord: tol.chord_mm,
        weld: tol.weld_mm,
        collapsed: Vec::new(),
    };
    for p in 0..surfaces.len() as u32 {
        let c = b.find_collapsed_sides(p)?;
        b.collapsed.push(c);
        b.init_patch(p)?;
    }
    b.reindex();
    if surfaces.len() > 1 {
        b.conform_patches(tol.weld_mm)?;
    }
    b.refine()?;
    // Compact: keep used vertices in creation order.
    let mut new_id = vec![u32::MAX; b.pos.len()];
    let mut positions = Vec::new();
    let mut params = Vec::new();
    let mut patch_of_vertex = Vec::new();
    let mut triangles = Vec::new();
    for t in b.tris.iter().filter(|t| t.alive) {
        for &v in &t.v {
            if new_id[v as usize] == u32::MAX {
                new_id[v as usize] = 0;
            }
        }
    }
    for v in 0..b.pos.len() {
        if new_id[v] == 0 {
            new_id[v] = positions.len() as u32;
            positions.push(b.pos[v]);
            params.push(b.home[v].1);
            patch_of_vertex.push(b.home[v].0);
        }
    }
    for t in b.tris.iter().filter(|t| t.alive) {
        triangles.push(t.v.map(|v| new_id[v as usize]));
    }
    // Collapsed domain sides (sphere poles, cone apex) become single vertices; parameter seams
    // (coincident but not joined by an edge) stay open.
    Ok(TriMesh {
        positions,
        triangles,
        params: Some(params),
        patch_of_vertex: Some(patch_of_vertex),
        flat: None,
    }
    .collapsed_short_edges(tol.weld_mm))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Topology;
    use flatcut_surface::{Domain2, SurfaceDerivs};
    use std::f64::consts::PI;

    /// Sphere of radius r: u = longitude in [u0, u1], v = colatitude in [v0, v1].
    #[derive(Debug)]
    struct Sphere {
        r: f64,
        dom: Domain2,
    }
    /// Cylinder radius r along z: u = angle, v = height.
    #[derive(Debug)]
    struct Cylinder {
        r: f64,
        dom: Domain2,
    }
    /// Graph z = a·x·y over a rectangle, with an optional reparameterisation x = x0 + w·u^q.
    #[derive(Debug)]
    struct Saddle {
        a: f64,
        x0: f64,
        w: f64,
        q: i32,
        h: f64,
        qv: i32,
    }
    /// A curved triangular patch: barycentric map onto a paraboloid cap.
    #[derive(Debug)]
    struct TriCap {
        size: f64,
        k: f64,
    }

    fn num_derivs(s: &dyn Fn(f64, f64) -> DVec3, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let h = 1e-6;
        (
            s(u, v),
            (s(u + h, v) - s(u - h, v)) / (2.0 * h),
            (s(u, v + h) - s(u, v - h)) / (2.0 * h),
        )
    }

    macro_rules! impl_surface {
        ($t:ty, $dom:expr, $kind:expr, $f:expr) => {
            impl ParamSurface for $t {
                fn domain(&self) -> Domain2 {
                    ($dom)(self)
                }
                fn domain_kind(&self) -> DomainKind {
                    $kind
                }
                fn eval(&self, u: f64, v: f64) -> DVec3 {
                    ($f)(self, u, v)
                }
                fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
                    num_derivs(&|u, v| ($f)(self, u, v), u, v)
                }
                fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
                    let (p, su, sv) = self.deriv1(u, v);
                    SurfaceDerivs {
                        p,
                        su,
                        sv,
                        ..Default::default()
                    }
                }
            }
        };
    }

    impl_surface!(
        Sphere,
        |s: &Sphere| s.dom,
        DomainKind::Rectangle,
        |s: &Sphere, u: f64, v: f64| {
            DVec3::new(v.sin() * u.cos(), v.sin() * u.sin(), v.cos()) * s.r
        }
    );
    impl_surface!(
        Cylinder,
        |s: &Cylinder| s.dom,
        DomainKind::Rectangle,
        |s: &Cylinder, u: f64, v: f64| { DVec3::new(s.r * u.cos(), s.r * u.sin(), v) }
    );
    impl_surface!(
        Saddle,
        |_: &Saddle| Domain2::UNIT,
        DomainKind::Rectangle,
        |s: &Saddle, u: f64, v: f64| {
            let x = s.x0 + s.w * u.powi(s.q);
            let y = s.h * v.powi(s.qv);
            DVec3::new(x, y, s.a * x * y)
        }
    );
    impl_surface!(
        TriCap,
        |_: &TriCap| Domain2::UNIT,
        DomainKind::Triangle,
        |s: &TriCap, u: f64, v: f64| {
            let x = s.size * (u + 0.5 * v);
            let y = s.size * v * 0.866;
            DVec3::new(x, y, s.k * (x * x + y * y))
        }
    );

    /// Largest deviation between each triangle and the surface at the same interpolated (u, v),
    /// sampled on a barycentric grid of `n` steps.
    fn mesh_to_surface(m: &TriMesh, surfs: &[&dyn ParamSurface], n: usize) -> f64 {
        let params = m.params.as_ref().unwrap();
        let patch = m.patch_of_vertex.clone();
        let mut worst: f64 = 0.0;
        for (ti, t) in m.triangles.iter().enumerate() {
            // Use the patch of a vertex whose home patch is shared by all three (single patch).
            let p = patch.as_ref().map(|pv| pv[t[0] as usize]).unwrap_or(0);
            if patch
                .as_ref()
                .is_some_and(|pv| t.iter().any(|&v| pv[v as usize] != p))
            {
                continue;
            }
            let c = m.corners(ti);
            let uv = t.map(|v| params[v as usize]);
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
                    let l = [1.0 - a - b, a, b];
                    let q = c[0] * l[0] + c[1] * l[1] + c[2] * l[2];
                    let w = uv[0] * l[0] + uv[1] * l[1] + uv[2] * l[2];
                    worst = worst.max(surfs[p as usize].eval(w.x, w.y).distance(q));
                }
            }
        }
        worst
    }

    fn point_triangle_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
        // Ericson, Real-Time Collision Detection §5.1.5.
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(ap), ac.dot(ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return p.distance(a);
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        if d3 >= 0.0 && d4 <= d3 {
            return p.distance(b);
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return p.distance(a + ab * (d1 / (d1 - d3)));
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return p.distance(c);
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return p.distance(a + ac * (d2 / (d2 - d6)));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
        }
        let denom = 1.0 / (va + vb + vc);
        p.distance(a + ab * (vb * denom) + ac * (vc * denom))
    }

    /// Largest distance from surface samples (a regular grid in the domain) to the mesh.
    fn surface_to_mesh(m: &TriMesh, s: &dyn ParamSurface, n: usize) -> f64 {
        let d = s.domain();
        let mut worst: f64 = 0.0;
        for i in 0..=n {
            for j in 0..=n {
                let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
                if s.domain_kind() == DomainKind::Triangle && a + b > 1.0 {
                    continue;
                }
                let p = s.eval(d.u.0 + a * (d.u.1 - d.u.0), d.v.0 + b * (d.v.1 - d.v.0));
                let best = (0..m.triangles.len())
                    .map(|t| point_triangle_distance(p, m.corners(t)))
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(best);
            }
        }
        worst
    }

    /// Largest ratio of longest edge to the height onto it (1.15 for equilateral triangles).
    fn worst_aspect(m: &TriMesh) -> f64 {
        (0..m.triangles.len())
            .map(|t| {
                let c = m.corners(t);
                let l = (0..3)
                    .map(|k| c[k].distance(c[(k + 1) % 3]))
                    .fold(0.0, f64::max);
                let area = m.triangle_area(t);
                if area > 0.0 {
                    l * l / (2.0 * area)
                } else {
                    f64::INFINITY
                }
            })
            .fold(0.0, f64::max)
    }

    fn sphere_cap() -> Sphere {
        Sphere {
            r: 100.0,
            dom: Domain2 {
                u: (0.0, 2.0 * PI),
                v: (0.3, 1.4),
            },
        }
    }

    #[test]
    fn sphere_zone_meets_chordal_tolerance_both_ways() {
        let s = sphere_cap();
        let tol = Tolerances::DEFAULT.with_chord_mm(0.2);
        let m = tessellate(&s, &tol).unwrap();
        let d1 = mesh_to_surface(&m, &[&s], 6);
        assert!(d1 <= 0.2, "mesh->surface {d1}");
        let d2 = surface_to_mesh(&m, &s, 40);
        assert!(d2 <= 0.2, "surface->mesh {d2}");
        // Not wastefully fine either: the worst deviation uses a good part of the budget.
        assert!(d1 > 0.05, "over-refined: {d1}");
        assert!(worst_aspect(&m) < 8.0, "aspect {}", worst_aspect(&m));
        // Area converges to the zone area 2πr²(cos v0 − cos v1).
        let exact = 2.0 * PI * 100.0f64.powi(2) * (0.3f64.cos() - 1.4f64.cos());
        assert!((m.area() - exact).abs() / exact < 1e-2);
        assert!(m.patch_of_vertex.is_none());
    }

    #[test]
    fn vertex_count_scales_inversely_with_tolerance() {
        let s = sphere_cap();
        let n1 = tessellate(&s, &Tolerances::DEFAULT.with_chord_mm(0.4))
            .unwrap()
            .vertex_count();
        let n2 = tessellate(&s, &Tolerances::DEFAULT.with_chord_mm(0.1))
            .unwrap()
            .vertex_count();
        // Vertex density ∝ 1/tol on a surface of constant curvature: 4x here, allow 2.5..6.
        let r = n2 as f64 / n1 as f64;
        assert!((2.5..6.0).contains(&r), "{n1} -> {n2}");
    }

    #[test]
    fn anisotropic_cylinder_is_refined_around_not_along() {
        // Long thin cylinder: curvature only around; triangles follow the metric.
        let s = Cylinder {
            r: 20.0,
            dom: Domain2 {
                u: (0.0, 2.0 * PI),
                v: (0.0, 500.0),
            },
        };
        let m = tessellate(&s, &Tolerances::DEFAULT.with_chord_mm(0.05)).unwrap();
        assert!(mesh_to_surface(&m, &[&s], 5) <= 0.05);
        assert!(worst_aspect(&m) < 40.0, "aspect {}", worst_aspect(&m));
        // Around: 2π·20 / (2·sqrt(2·20·0.05)) ≈ 45 segments are enough; we should be near it.
        let ring = m
            .params
            .as_ref()
            .unwrap()
            .iter()
            .filter(|p| p.y == 0.0)
            .count();
        assert!(
            (40..200).contains(&ring),
            "{ring} vertices on the bottom ring"
        );
        // Within one patch the parameter seam stays open: the sleeve is a disk.
        let topo = Topology::build(&m).unwrap();
        assert_eq!(topo.boundary_loops.len(), 1);
    }

    #[test]
    fn flat_patch_needs_no_refinement_and_triangle_domain_works() {
        let s = Saddle {
            a: 0.0,
            x0: 0.0,
            w: 100.0,
            q: 1,
            h: 100.0,
            qv: 1,
        };
        let m = tessellate(&s, &Tolerances::DEFAULT).unwrap();
        assert_eq!(m.vertex_count(), 81, "initial 8x8 grid only");
        let t = TriCap {
            size: 80.0,
            k: 0.01,
        };
        let tol = Tolerances::DEFAULT.with_chord_mm(0.05);
        let m = tessellate(&t, &tol).unwrap();
        assert!(
            m.params
                .as_ref()
                .unwrap()
                .iter()
                .all(|p| p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0 + 1e-15)
        );
        assert!(mesh_to_surface(&m, &[&t], 5) <= 0.05);
        assert!(surface_to_mesh(&m, &t, 25) <= 0.05);
        crate::check_disk(&m).unwrap();
    }

    #[test]
    fn two_patches_with_different_edge_speeds_are_crack_free() {
        // Saddle split at x = 50; the right half is parameterised x = 50 + 50 u², so its left
        // edge (u = 0) is sampled at a different speed than the left half's right edge.
        let a = Saddle {
            a: 0.004,
            x0: 0.0,
            w: 50.0,
            q: 1,
            h: 100.0,
            qv: 1,
        };
        let b = Saddle {
            a: 0.004,
            x0: 50.0,
            w: 50.0,
            q: 2,
            h: 100.0,
            qv: 1,
        };
        let tol = Tolerances::DEFAULT.with_chord_mm(0.02);
        let surfs: [&dyn ParamSurface; 2] = [&a, &b];
        let m = tessellate_patches(&surfs, &tol).unwrap();
        let topo = crate::check_disk(&m).unwrap();
        // One boundary loop = no crack along x = 50; its length is the outer perimeter.
        let lp = &topo.boundary_loops[0];
        let per: f64 = (0..lp.len())
            .map(|i| {
                m.positions[lp[i] as usize].distance(m.positions[lp[(i + 1) % lp.len()] as usize])
            })
            .sum();
        // Edges y = 100 and x = 100 are straight lines rising 0.4 mm per mm.
        let exact = 200.0 + 200.0 * 1.16f64.sqrt();
        assert!((per - exact).abs() < 1e-9, "perimeter {per} vs {exact}");
        let pv = m.patch_of_vertex.as_ref().unwrap();
        assert!(pv.contains(&0) && pv.contains(&1));
        assert!(mesh_to_surface(&m, &surfs, 4) <= 0.02);
    }

    #[test]
    fn t_junctions_between_patches_are_resolved() {
        // The right half runs along the shared edge x = 50 as y = 100 v², so none of its initial
        // samples there (except the ends) coincide with the left half's: every one is a
        // T-junction until the boundary edges are split at the foreign vertices.
        let a = Saddle {
            a: 0.004,
            x0: 0.0,
            w: 50.0,
            q: 1,
            h: 100.0,
            qv: 1,
        };
        let b = Saddle {
            a: 0.004,
            x0: 50.0,
            w: 50.0,
            q: 1,
            h: 100.0,
            qv: 2,
        };
        let tol = Tolerances::DEFAULT.with_chord_mm(0.05);
        let surfs: [&dyn ParamSurface; 2] = [&a, &b];
        let m = tessellate_patches(&surfs, &tol).unwrap();
        let topo = crate::check_disk(&m).unwrap();
        assert_eq!(topo.boundary_loops.len(), 1);
        // No boundary edge runs along the interior line x = 50 (0 < y < 100).
        let lp = &topo.boundary_loops[0];
        for i in 0..lp.len() {
            let (p, q) = (
                m.positions[lp[i] as usize],
                m.positions[lp[(i + 1) % lp.len()] as usize],
            );
            let on_seam = |r: DVec3| (r.x - 50.0).abs() < 1e-9 && r.y > 1e-9 && r.y < 100.0 - 1e-9;
            assert!(!(on_seam(p) && on_seam(q)), "crack at {p} - {q}");
        }
        assert!(mesh_to_surface(&m, &surfs, 4) <= 0.05);
    }

    #[test]
    fn closed_cylinder_from_two_halves_welds_into_a_tube() {
        let a = Cylinder {
            r: 30.0,
            dom: Domain2 {
                u: (0.0, PI),
                v: (0.0, 80.0),
            },
        };
        let b = Cylinder {
            r: 30.0,
            dom: Domain2 {
                u: (PI, 2.0 * PI),
                v: (0.0, 80.0),
            },
        };
        let m = tessellate_patches(&[&a, &b], &Tolerances::DEFAULT.with_chord_mm(0.1)).unwrap();
        let topo = Topology::build(&m).unwrap();
        assert_eq!(topo.boundary_loops.len(), 2, "a tube has two rims");
        assert_eq!(topo.component_count, 1);
    }

    #[test]
    fn model_of_two_half_cylinders_is_one_tube() {
        use std::sync::Arc;
        let a: Arc<dyn ParamSurface> = Arc::new(Cylinder {
            r: 30.0,
            dom: Domain2 {
                u: (0.0, PI),
                v: (0.0, 80.0),
            },
        });
        let b: Arc<dyn ParamSurface> = Arc::new(Cylinder {
            r: 30.0,
            dom: Domain2 {
                u: (PI, 2.0 * PI),
                v: (0.0, 80.0),
            },
        });
        let model = flatcut_surface::patch::Model::new(vec![a, b], 1e-6).unwrap();
        let m = tessellate_model(&model, &Tolerances::DEFAULT.with_chord_mm(0.1)).unwrap();
        let topo = Topology::build(&m).unwrap();
        assert_eq!((topo.boundary_loops.len(), topo.component_count), (2, 1));
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let s = sphere_cap();
        assert_eq!(
            tessellate(&s, &Tolerances::DEFAULT.with_chord_mm(0.0)).unwrap_err(),
            TessError::BadTolerance(0.0)
        );
        assert_eq!(
            tessellate_patches(&[], &Tolerances::DEFAULT).unwrap_err(),
            TessError::NoPatches
        );
        let bad = Sphere {
            r: f64::NAN,
            dom: Domain2::UNIT,
        };
        assert!(matches!(
            tessellate(&bad, &Tolerances::DEFAULT),
            Err(TessError::NonFinite { patch: 0, .. })
        ));
        let e = tessellate_with(
            &[&s],
            &Tolerances::DEFAULT.with_chord_mm(1e-4),
            &TessOptions::DEFAULT.with_max_vertices(1000),
        );
        assert!(matches!(
            e,
            Err(TessError::TooManyVertices { limit: 1000, .. })
        ));
    }

    #[test]
    fn full_sphere_poles_collapse_and_the_seam_stays_open() {
        let s = Sphere {
            r: 50.0,
            dom: Domain2 {
                u: (0.0, 2.0 * PI),
                v: (0.0, PI),
            },
        };
        let m = tessellate(&s, &Tolerances::DEFAULT.with_chord_mm(0.1)).unwrap();
        // A disk: the two poles are single vertices on the boundary (the meridian seam, twice).
        let topo = crate::check_disk(&m).unwrap();
        let poles = m.positions.iter().filter(|p| p.x.hypot(p.y) < 1e-9).count();
        assert_eq!(poles, 2);
        let exact = 4.0 * PI * 2500.0;
        assert!((m.area() - exact).abs() / exact < 5e-3);
        assert_eq!(topo.boundary_loops.len(), 1);
    }

    /// Rim patch `k` (0..4) of Newell's teapot in mm: patch 0 rotated by k quarter turns.
    fn teapot_rim(k: usize) -> flatcut_surface::patch::BezierPatch {
        const RIM: [[f64; 3]; 16] = [
            [1.4, 0.0, 2.4],
            [1.4, -0.784, 2.4],
            [0.784, -1.4, 2.4],
            [0.0, -1.4, 2.4],
            [1.3375, 0.0, 2.53125],
            [1.3375, -0.749, 2.53125],
            [0.749, -1.3375, 2.53125],
            [0.0, -1.3375, 2.53125],
            [1.4375, 0.0, 2.53125],
            [1.4375, -0.805, 2.53125],
            [0.805, -1.4375, 2.53125],
            [0.0, -1.4375, 2.53125],
            [1.5, 0.0, 2.4],
            [1.5, -0.84, 2.4],
            [0.84, -1.5, 2.4],
            [0.0, -1.5, 2.4],
        ];
        let pts = RIM
            .iter()
            .map(|&[x, y, z]| {
                let (mut x, mut y) = (x, y);
                for _ in 0..k {
                    (x, y) = (y, -x);
                }
                DVec3::new(x, y, z) * 25.4
            })
            .collect();
        flatcut_surface::patch::BezierPatch::new(3, 3, pts).unwrap()
    }

    #[test]
    fn ring_of_four_patches_is_one_annulus() {
        // Three or more patches meeting corner to corner: the corner weld must pick the vertex
        // of the cluster, not the cluster's number (which once sent the closure into an endless
        // chase and this ring past 2 000 000 vertices).
        let rim: Vec<_> = (0..4).map(teapot_rim).collect();
        let surfs: Vec<&dyn ParamSurface> = rim.iter().map(|s| s as &dyn ParamSurface).collect();
        let tol = Tolerances::DEFAULT.with_chord_mm(0.1);
        let opts = TessOptions::DEFAULT.with_max_vertices(50_000);
        let m = tessellate_with(&surfs, &tol, &opts).unwrap();
        let topo = Topology::build(&m).unwrap();
        assert_eq!(topo.component_count, 1);
        assert_eq!(
            topo.boundary_loops.len(),
            2,
            "inner and outer edge of the rim"
        );
        // Each loop is a whole circle (radius 1.4 in and 1.5 in, to the Bézier arc error of the
        // data): no crack runs along a side.
        let mut radii: Vec<f64> = topo
            .boundary_loops
            .iter()
            .map(|lp| {
                let r = lp
                    .iter()
                    .map(|&v| m.positions[v as usize].truncate().length());
                let (lo, hi) = r.fold((f64::MAX, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
                assert!(hi - lo < 0.5, "loop radius spread {lo}..{hi}");
                hi
            })
            .collect();
        radii.sort_by(f64::total_cmp);
        assert!((radii[0] - 1.4 * 25.4).abs() < 0.5 && (radii[1] - 1.5 * 25.4).abs() < 0.5);
        assert!(mesh_to_surface(&m, &surfs, 3) <= 0.1);
    }

    #[test]
    fn output_is_deterministic() {
        let s = sphere_cap();
        let tol = Tolerances::DEFAULT.with_chord_mm(0.3);
        assert_eq!(tessellate(&s, &tol).unwrap(), tessellate(&s, &tol).unwrap());
    }
}
