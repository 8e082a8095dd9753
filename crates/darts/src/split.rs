//! Splitting seams: a piece cut right through into pieces that are sewn back together, for where
//! no dart can bring it within its limits. A dart takes a wedge out; where the flat piece is too
//! short rather than too long (a saddle's rim, the flare of a collar) a wedge only makes it worse,
//! and the pattern maker splits the piece instead (OptCuts' setting: cuts that end on the outline
//! at both ends).
//!
//! Method, greedy as a pattern maker adds seams, worst place first:
//! 1. **Candidates.** In the piece's current flat map, straight chords of the flat outline through
//!    the face of largest limit excess and through the piece's middle, in [`DIRECTIONS`]
//!    directions each. A chord is carried onto the surface (its points found in the flat
//!    triangles and lifted to 3D, then traced along the surface as a style line,
//!    [`flatcut_mesh::lines`]), so the cut is a smooth line the sewer can follow.
//! 2. **Choice.** A chord that splits the piece into two disks, neither smaller than
//!    [`MIN_AREA_SHARE`] of it, is scored by the larger of the two halves' limit excess, each half
//!    flattened on its own (isometric, without limits). The lowest score wins, the shorter cut on
//!    a tie.
//! 3. **All pieces together.** The pieces are flattened together, the two sides of every seam
//!    kept at equal lengths edge by edge and the limits held ([`flatcut_flatten::assembly`]); while
//!    a piece is still beyond the limits and fewer than `max_pieces` exist, the worst is split
//!    again.
//!
//! A closed surface (a ball, a cushion) cannot be flattened at all: [`split_closed`] first cuts
//! it open along its middle section ([`opening_loop`]) into two disks and goes on from those.
//! New parts are judged flattened on their own with the limits held; all parts are flattened
//! together only when they look done (step 3 is then the proof, or it sends the loop on).
//!
//! The seams between the final pieces are found by their coincident vertices
//! ([`flatcut_mesh::mating::coincident_seams`]): a cut's vertices are copied to both of its sides
//! with the same coordinates, and a cut ends at an outline vertex, so it adds no vertex to one
//! side of an earlier seam that the other side lacks.
//!
//! Why chords of the flat map rather than OptCuts' joint optimisation of cuts and map: a few
//! candidates, each judged by the flattener itself, give seams a pattern maker would draw (smooth,
//! across the strain) at the cost of a handful of solves per cut, and the limit solve of the
//! assembled pieces is the proof that the limits hold.

use flatcut_flatten::assembly::flatten_assembly;
use flatcut_flatten::nonlinear::kernel::rest_frames;
use flatcut_flatten::{FlattenParams, Method};
use flatcut_geom::{DVec2, DVec3, polygon};
use flatcut_mesh::lines::{LineSpec, embed_lines};
use flatcut_mesh::mating::{MatingSeam, coincident_seams};
use flatcut_mesh::regions::split_along_lines;
use flatcut_mesh::{Topology, TriMesh, check_disk};

use crate::limits::{Band, Limits, face_excess};
use crate::{DartError, KeepOut};

/// How far inside the limits (log strain, 0.001 % of stretch) the assembled parts are held: the
/// flattener's limits land on their bound, and a map written to a file (to a micrometre) and
/// checked independently must still be within it.
const HELD_INSIDE: f64 = 1e-5;
/// Directions of the chords tried through each centre, evenly over a half turn.
pub const DIRECTIONS: usize = 8;
/// Points of a chord lifted to the surface between its ends (the trace joins them along it).
const CHORD_SAMPLES: usize = 16;
/// Neither side of a cut may be smaller than this share of the piece's area: a sliver cut off
/// the rim relieves nothing and is a piece no one wants to sew.
pub const MIN_AREA_SHARE: f64 = 0.05;

/// What to split for.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitOptions {
    /// The limits every face must meet.
    pub band: Band,
    /// Most pieces the piece may become.
    pub max_pieces: usize,
    /// Vertices of the piece no cut may pass (no_cut regions, marks), as for darts; `None`: none.
    pub keep_out: Option<KeepOut>,
}

impl SplitOptions {
    pub const DEFAULT_MAX_PIECES: usize = 8;
}

/// A piece split into pieces.
#[derive(Clone, Debug)]
pub struct Split {
    /// The pieces, each flattened (`flat` set), the first containing the original's first face.
    pub pieces: Vec<TriMesh>,
    /// The seams between them (sides index `pieces`), named `"<a>/<b>"` after the pieces' numbers
    /// (1-based).
    pub seams: Vec<MatingSeam>,
    /// The 3D path of every cut, in the order made.
    pub cuts: Vec<Vec<DVec3>>,
    /// Largest limit excess over every piece's faces (log strain; negative within the limits).
    pub excess: f64,
    pub feasible: bool,
    /// Where the largest excess is (3D).
    pub worst_3d: DVec3,
}

impl Split {
    /// Total 3D length of the cuts (mm): the seams to sew.
    pub fn total_cut_mm(&self) -> f64 {
        self.cuts.iter().map(|c| polyline_length(c)).sum()
    }
}

/// Splits `mesh` (flattened as `x0`) until every piece is within the limits of `opts` or it has
/// `opts.max_pieces` pieces; `params` flattens the pieces (their method is taken as isometric,
/// the one that holds seams and limits together). A result that is not `feasible` says how far
/// beyond the limits the best split reached.
pub fn split(
    mesh: &TriMesh,
    x0: &[DVec2],
    params: &FlattenParams,
    opts: &SplitOptions,
) -> Result<Split, DartError> {
    let mut first = mesh.clone();
    first.flat = Some(x0.to_vec());
    split_on(mesh, vec![first], Vec::new(), params, opts)
}

/// Splits a closed surface (no boundary, such as a ball or a cushion): it is first cut open
/// along [`opening_loop`] into two disks, flattened together, and then split as [`split`]
/// does. The opening cut is the first of the result's `cuts`.
pub fn split_closed(
    mesh: &TriMesh,
    params: &FlattenParams,
    opts: &SplitOptions,
) -> Result<Split, DartError> {
    let (a, b, path) = open(mesh)?;
    let mut pieces = vec![a, b];
    flatten_together(&mut pieces, &held_params(params, opts))?;
    split_on(mesh, pieces, vec![path], params, opts)
}

/// A closed surface cut open along [`opening_loop`]: its two halves (disks) and the cut.
pub fn open(mesh: &TriMesh) -> Result<(TriMesh, TriMesh, Vec<DVec3>), DartError> {
    let loop3 = opening_loop(mesh).ok_or_else(|| {
        DartError::Placement(
            "the closed surface has no section through its middle to open it along".into(),
        )
    })?;
    let mut bare = mesh.clone();
    bare.flat = None;
    cut_in_two(&bare, loop3, mesh.area()).ok_or_else(|| {
        DartError::Placement(
            "cutting the closed surface along its middle section did not give two disks (is it a sphere-like surface, genus 0?)".into(),
        )
    })
}

/// The flattening parameters that hold the limits of `opts` (a little inside them).
fn held_params(params: &FlattenParams, opts: &SplitOptions) -> FlattenParams {
    // Inside by the margin, or by half a side narrower than it (a 0 % limit stays 0 %).
    let inside = Band {
        ln_s: (opts.band.ln_s - HELD_INSIDE).max(0.5 * opts.band.ln_s),
        ln_c: (opts.band.ln_c + HELD_INSIDE).min(0.5 * opts.band.ln_c),
    };
    isometric(params)
        .with_max_stretch_pct(stretch_pct(inside))
        .with_max_compress_pct(compress_pct(inside))
}

/// The greedy loop of the module documentation from `pieces` (each flattened), the cuts made
/// so far being `cuts`; `mesh` is the piece the keep-out of `opts` is indexed by.
fn split_on(
    mesh: &TriMesh,
    mut pieces: Vec<TriMesh>,
    mut cuts: Vec<Vec<DVec3>>,
    params: &FlattenParams,
    opts: &SplitOptions,
) -> Result<Split, DartError> {
    let held = held_params(params, opts);
    let guard = Guard::new(mesh, opts.keep_out.as_ref());
    // New parts are judged flattened on their own with the limits held; the parts are flattened
    // together (seams equal) only when that says they are done, and split further if the seams
    // then push one beyond the limits.
    let mut together = pieces.len() == 1;
    loop {
        let (w, excess, face) = worst(&pieces, opts.band)?;
        let full = pieces.len() >= opts.max_pieces.max(1);
        if (excess <= 0.0 || full) && !together {
            flatten_together(&mut pieces, &held)?;
            together = true;
            continue;
        }
        let next = if excess <= 0.0 || full {
            None
        } else {
            best_cut(&pieces[w], face, opts.band, params, &guard)?
        };
        let Some((a, b, cut)) = next else {
            if !together {
                flatten_together(&mut pieces, &held)?;
                together = true;
                continue;
            }
            let seams = seams_of(&pieces);
            return Ok(Split {
                worst_3d: centroid(&pieces[w], face),
                pieces,
                seams,
                cuts,
                excess,
                feasible: excess <= 0.0,
            });
        };
        let mut parts = [a, b];
        for p in &mut parts {
            let f = flatcut_flatten::flatten(p, &held).map_err(DartError::Flatten)?;
            p.flat = Some(f.uv);
        }
        let [a, b] = parts;
        pieces[w] = a;
        pieces.push(b);
        cuts.push(cut);
        together = false;
    }
}

/// `params` with the isometric method (no material's grain): the one that holds seams and limits
/// together.
fn isometric(params: &FlattenParams) -> FlattenParams {
    let mut p = params.clone().with_anisotropy(None);
    p.method = Method::Isometric;
    p
}

/// The band's stretch limit in percent, `None` when open.
fn stretch_pct(b: Band) -> Option<f64> {
    b.ln_s.is_finite().then(|| (b.ln_s.exp() - 1.0) * 100.0)
}

/// The band's compression limit in percent, `None` when open.
fn compress_pct(b: Band) -> Option<f64> {
    b.ln_c.is_finite().then(|| (1.0 - b.ln_c.exp()) * 100.0)
}

/// The piece, its largest face excess and that face.
fn worst(pieces: &[TriMesh], band: Band) -> Result<(usize, f64, usize), DartError> {
    let mut best = (0, f64::NEG_INFINITY, 0);
    for (k, p) in pieces.iter().enumerate() {
        let x = p
            .flat
            .as_deref()
            .ok_or_else(|| DartError::Internal("a split piece has no map".into()))?;
        let rest =
            rest_frames(p).map_err(|t| DartError::Internal(format!("degenerate face {t}")))?;
        for (t, e) in face_excess(&rest, x, &Limits::Band(band))
            .into_iter()
            .enumerate()
        {
            if e > best.1 {
                best = (k, e, t);
            }
        }
    }
    Ok(best)
}

/// The seams between the pieces, named by the pieces' 1-based numbers.
fn seams_of(pieces: &[TriMesh]) -> Vec<MatingSeam> {
    let refs: Vec<&TriMesh> = pieces.iter().collect();
    let names: Vec<String> = (1..=pieces.len()).map(|k| k.to_string()).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    coincident_seams(&refs, &names)
}

/// Flattens the pieces together: seams at equal lengths, the limits of `params` held.
fn flatten_together(pieces: &mut [TriMesh], params: &FlattenParams) -> Result<(), DartError> {
    let seams = seams_of(pieces);
    let flats = {
        let refs: Vec<&TriMesh> = pieces.iter().collect();
        flatten_assembly(&refs, &seams, params).map_err(|e| DartError::Solver(e.to_string()))?
    };
    for (p, f) in pieces.iter_mut().zip(flats) {
        p.flat = Some(f.uv);
    }
    Ok(())
}

/// The best cut of `piece` (see the module documentation): its two sides (unflattened maps are
/// replaced by each side's own) and the cut's 3D path. `None` when no chord splits the piece.
fn best_cut(
    piece: &TriMesh,
    worst_face: usize,
    band: Band,
    params: &FlattenParams,
    guard: &Guard,
) -> Result<Option<(TriMesh, TriMesh, Vec<DVec3>)>, DartError> {
    let x = piece
        .flat
        .as_deref()
        .ok_or_else(|| DartError::Internal("a split piece has no map".into()))?;
    let topo = Topology::build(piece)?;
    let Some(rim) = topo.boundary_loops.iter().max_by_key(|l| l.len()) else {
        return Ok(None);
    };
    let outline: Vec<DVec2> = rim.iter().map(|&v| x[v as usize]).collect();
    let rim3: Vec<DVec3> = rim.iter().map(|&v| piece.positions[v as usize]).collect();
    let free = isometric(params)
        .with_max_stretch_pct(None)
        .with_max_compress_pct(None);
    let area = piece.area();
    let tri = piece.triangles[worst_face];
    let mut centres = vec![tri.iter().map(|&v| x[v as usize]).sum::<DVec2>() / 3.0];
    centres.extend(polygon::area_centroid(&outline).filter(|&c| polygon::contains(&outline, c)));
    let mut bare = piece.clone();
    bare.flat = None;
    let mut best: Option<(f64, f64, TriMesh, TriMesh, Vec<DVec3>)> = None;
    for &c in &centres {
        for k in 0..DIRECTIONS {
            let d = DVec2::from_angle(std::f64::consts::PI * k as f64 / DIRECTIONS as f64);
            let Some(points) = chord_on_surface(piece, x, &outline, &rim3, c, d) else {
                continue;
            };
            let Some((a, b, path)) = cut_in_two(&bare, points, area) else {
                continue;
            };
            if guard.blocks(&path) {
                continue;
            }
            let mut sides = [a, b];
            let (Some(sa), Some(sb)) = (
                alone_excess(&mut sides[0], &free, band),
                alone_excess(&mut sides[1], &free, band),
            ) else {
                continue;
            };
            let score = sa.max(sb);
            let length = polyline_length(&path);
            let better = best
                .as_ref()
                .is_none_or(|(s, l, ..)| score < *s || (score == *s && length < *l));
            if score.is_finite() && better {
                let [a, b] = sides;
                best = Some((score, length, a, b, path));
            }
        }
    }
    Ok(best.map(|(_, _, a, b, path)| (a, b, path)))
}

/// Where a closed surface is cut open: its section by the plane through its centroid that
/// holds its two longest directions (normal to the direction of least spread of its vertices),
/// the longest loop of that section, as points on the surface (closed: the last is the first).
/// The seam round a cushion's edge, a ball's equator, a sausage's length.
pub fn opening_loop(mesh: &TriMesh) -> Option<Vec<DVec3>> {
    let n = mesh.positions.len() as f64;
    let c = mesh.positions.iter().sum::<DVec3>() / n;
    let cov = mesh
        .positions
        .iter()
        .fold(flatcut_geom::DMat3::ZERO, |m, p| {
            let d = *p - c;
            m + flatcut_geom::DMat3::from_cols(d * d.x, d * d.y, d * d.z)
        });
    let normal = least_spread(cov)?;
    // Signed distances, with vertices on the plane moved to its positive side so that every
    // crossing lies inside an edge.
    let side: Vec<f64> = mesh
        .positions
        .iter()
        .map(|p| {
            let s = (*p - c).dot(normal);
            if s == 0.0 { f64::MIN_POSITIVE } else { s }
        })
        .collect();
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut next: std::collections::BTreeMap<(u32, u32), Vec<(u32, u32)>> = Default::default();
    for t in &mesh.triangles {
        let crossed: Vec<(u32, u32)> = (0..3)
            .map(|k| (t[k], t[(k + 1) % 3]))
            .filter(|&(a, b)| (side[a as usize] > 0.0) != (side[b as usize] > 0.0))
            .map(|(a, b)| key(a, b))
            .collect();
        if let [e, f] = crossed[..] {
            next.entry(e).or_default().push(f);
            next.entry(f).or_default().push(e);
        }
    }
    let at = |(a, b): (u32, u32)| {
        let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let (sa, sb) = (side[a as usize], side[b as usize]);
        pa.lerp(pb, sa / (sa - sb))
    };
    let mut seen = std::collections::BTreeSet::new();
    let mut best: Vec<DVec3> = Vec::new();
    for &start in next.keys() {
        if seen.contains(&start) {
            continue;
        }
        let (mut prev, mut cur) = (start, start);
        let mut pts = Vec::new();
        loop {
            seen.insert(cur);
            pts.push(at(cur));
            let Some(&n) = next[&cur].iter().find(|&&e| e != prev) else {
                break;
            };
            (prev, cur) = (cur, n);
            if cur == start {
                let closes = pts.len() >= 3;
                if closes && polyline_length(&pts) > polyline_length(&best) {
                    pts.push(pts[0]);
                    best = pts;
                }
                break;
            }
            if seen.contains(&cur) {
                break;
            }
        }
    }
    // At most OPENING_POINTS points: the trace joins them along the surface.
    if best.len() > OPENING_POINTS {
        let step = best.len() as f64 / OPENING_POINTS as f64;
        let last = best[best.len() - 1];
        best = (0..OPENING_POINTS)
            .map(|k| best[(k as f64 * step) as usize])
            .chain(std::iter::once(last))
            .collect();
    }
    (best.len() >= 4).then_some(best)
}

/// Points of an opening loop given to the trace.
const OPENING_POINTS: usize = 64;

/// The unit eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3×3
/// matrix: power iteration on its shifted complement (`tr·I − M`, whose largest eigenvalue is
/// M's smallest), deterministic from a fixed start.
fn least_spread(m: flatcut_geom::DMat3) -> Option<DVec3> {
    let tr = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    let shifted = flatcut_geom::DMat3::from_diagonal(DVec3::splat(tr)) - m;
    let mut v = DVec3::new(0.577, 0.5773, 0.5774).normalize();
    for _ in 0..200 {
        v = (shifted * v).try_normalize()?;
    }
    Some(v)
}

/// The keep-out of the piece being split, in 3D: the parts are new meshes, so a cut is checked
/// against the original piece's vertices, a path point taking the flag of its nearest one.
struct Guard {
    positions: Vec<DVec3>,
    blocked: Vec<bool>,
}

impl Guard {
    fn new(mesh: &TriMesh, keep_out: Option<&KeepOut>) -> Self {
        Self {
            positions: mesh.positions.clone(),
            blocked: keep_out.map_or_else(Vec::new, |k| k.blocked.clone()),
        }
    }

    /// True when some point of the cut lies at a blocked vertex's place.
    fn blocks(&self, path: &[DVec3]) -> bool {
        if !self.blocked.iter().any(|&b| b) {
            return false;
        }
        path.iter().any(|&p| {
            let v = flatcut_mesh::seams::nearest_vertex(&self.positions, p) as usize;
            self.blocked.get(v).copied().unwrap_or(false)
        })
    }
}

/// The largest face excess of `side` flattened on its own with `free` (its map is kept);
/// `None` when it cannot be flattened.
fn alone_excess(side: &mut TriMesh, free: &FlattenParams, band: Band) -> Option<f64> {
    let f = flatcut_flatten::flatten(side, free).ok()?;
    let rest = rest_frames(side).ok()?;
    let e = face_excess(&rest, &f.uv, &Limits::Band(band))
        .into_iter()
        .fold(f64::NEG_INFINITY, f64::max);
    side.flat = Some(f.uv);
    Some(e)
}

/// The chord of the flat outline through `c` along `d`, as points on the surface: its two ends on
/// the 3D outline and the points between found in the flat triangles. `None` when the chord does
/// not cross the outline on both sides.
fn chord_on_surface(
    piece: &TriMesh,
    x: &[DVec2],
    outline: &[DVec2],
    rim3: &[DVec3],
    c: DVec2,
    d: DVec2,
) -> Option<Vec<DVec3>> {
    let ha = polygon::ray_hit(outline, c, d)?;
    let hb = polygon::ray_hit(outline, c, -d)?;
    // A cut ends at an outline vertex, never inside an outline edge: a new vertex there would be
    // on this part's side of a seam only, and its neighbour's side would no longer match it
    // vertex for vertex.
    let n = rim3.len();
    let on_rim = |h: polygon::RayHit| rim3[(h.edge + usize::from(h.u > 0.5)) % n];
    let (a3, b3) = (on_rim(ha), on_rim(hb));
    let (a2, b2) = (c + d * ha.t, c - d * hb.t);
    let mut points = vec![a3];
    points.extend(
        (1..CHORD_SAMPLES)
            .filter_map(|j| lift(piece, x, a2.lerp(b2, j as f64 / CHORD_SAMPLES as f64))),
    );
    points.push(b3);
    Some(points)
}

/// The piece cut along the surface line through `points` into exactly two disks, neither under
/// [`MIN_AREA_SHARE`] of `area`, and the cut's 3D path.
fn cut_in_two(
    bare: &TriMesh,
    points: Vec<DVec3>,
    area: f64,
) -> Option<(TriMesh, TriMesh, Vec<DVec3>)> {
    let spec = LineSpec {
        points,
        notches: Vec::new(),
    };
    let e = embed_lines(bare, std::slice::from_ref(&spec)).ok()?;
    let s = split_along_lines(&e.mesh, &e.lines).ok()?;
    let [a, b] = <[_; 2]>::try_from(s.regions).ok()?;
    for r in [&a, &b] {
        check_disk(&r.mesh).ok()?;
        if r.mesh.area() < MIN_AREA_SHARE * area {
            return None;
        }
    }
    let path = e.lines[0]
        .iter()
        .map(|&v| e.mesh.positions[v as usize])
        .collect();
    Some((a.mesh, b.mesh, path))
}

/// The surface point whose flat image is `p`, found in the flat triangle containing it.
fn lift(mesh: &TriMesh, x: &[DVec2], p: DVec2) -> Option<DVec3> {
    mesh.triangles.iter().find_map(|t| {
        let [a, b, c] = t.map(|v| x[v as usize]);
        let den = (b - a).perp_dot(c - a);
        if den.abs() < f64::MIN_POSITIVE {
            return None;
        }
        let wb = (p - a).perp_dot(c - a) / den;
        let wc = (b - a).perp_dot(p - a) / den;
        let wa = 1.0 - wb - wc;
        let inside = [wa, wb, wc].iter().all(|&w| w >= -1e-12);
        inside.then(|| {
            let [pa, pb, pc] = t.map(|v| mesh.positions[v as usize]);
            pa * wa + pb * wb + pc * wc
        })
    })
}

fn polyline_length(p: &[DVec3]) -> f64 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}

fn centroid(mesh: &TriMesh, t: usize) -> DVec3 {
    mesh.corners(t).iter().sum::<DVec3>() / 3.0
}
