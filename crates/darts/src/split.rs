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
//! The seams between the final pieces are found by their coincident vertices
//! ([`flatcut_mesh::mating::coincident_seams`]): a cut's vertices are copied to both of its sides
//! with the same coordinates, and a later cut moves no vertex of an earlier one.
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

use crate::limits::{Band, face_excess};
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
    // Inside by the margin, or by half a side narrower than it (a 0 % limit stays 0 %).
    let inside = Band {
        ln_s: (opts.band.ln_s - HELD_INSIDE).max(0.5 * opts.band.ln_s),
        ln_c: (opts.band.ln_c + HELD_INSIDE).min(0.5 * opts.band.ln_c),
    };
    let held = isometric(params)
        .with_max_stretch_pct(stretch_pct(inside))
        .with_max_compress_pct(compress_pct(inside));
    let guard = Guard::new(mesh, opts.keep_out.as_ref());
    let mut first = mesh.clone();
    first.flat = Some(x0.to_vec());
    let mut pieces = vec![first];
    let mut cuts = Vec::new();
    loop {
        let (w, excess, face) = worst(&pieces, opts.band)?;
        let done = excess <= 0.0 || pieces.len() >= opts.max_pieces.max(1);
        let next = if done {
            None
        } else {
            best_cut(&pieces[w], face, opts.band, params, &guard)?
        };
        let Some((a, b, cut)) = next else {
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
        pieces[w] = a;
        pieces.push(b);
        cuts.push(cut);
        flatten_together(&mut pieces, &held)?;
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
        for (t, e) in face_excess(&rest, x, band).into_iter().enumerate() {
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
            let mut score = f64::NEG_INFINITY;
            let mut sides = [a, b];
            for side in &mut sides {
                let Ok(f) = flatcut_flatten::flatten(side, &free) else {
                    score = f64::INFINITY;
                    break;
                };
                let rest = rest_frames(side)
                    .map_err(|t| DartError::Internal(format!("degenerate face {t}")))?;
                score = score.max(
                    face_excess(&rest, &f.uv, band)
                        .into_iter()
                        .fold(f64::NEG_INFINITY, f64::max),
                );
                side.flat = Some(f.uv);
            }
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
    let n = rim3.len();
    let on_rim = |h: polygon::RayHit| rim3[h.edge].lerp(rim3[(h.edge + 1) % n], h.u);
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
