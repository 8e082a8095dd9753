//! The mesh around traced lines made well-shaped again. Tracing splits every crossed edge where
//! the line crosses it; where the line passes close to a vertex (but not within the snap
//! distance), or steps from a new vertex onto an old one a fraction of a millimetre away, it
//! leaves needle triangles and short zig-zags in the line. A flattening is free to distort such
//! tiny triangles (they weigh nothing in the energy), and a seam joining two pieces then carries
//! that distortion from one piece to the other (issue 15: a 19.5 % stretch on two 0.06 mm²
//! faces of the shoe's quarters, 1.5 % when flattened alone). So, after all lines are traced:
//!
//! * **collapses**: an edge shorter than [`COLLAPSE_REL`] of the mean length of its vertex's
//!   other edges loses that vertex to the edge's other end: a vertex off the lines (never one on
//!   the boundary unless it lies on a straight stretch of it), or a line vertex the tracing made,
//!   into its neighbour on the same line (never an end, a notch or a crossing of two lines);
//! * **flips**: an edge on no line and no boundary is flipped when that raises the smaller angle
//!   of its two triangles.
//!
//! Every change must raise the smallest angle of the triangles it touches and keep each new
//! triangle's normal within [`MAX_TURN_DEG`] of the ones it replaces, so the surface moves by
//! far less than the chordal tolerance it was tessellated to and no triangle folds. The lines
//! keep every vertex the user placed (ends and notches) exactly.

use flatcut_geom::DVec3;

use super::Edit;

/// An edge shorter than this fraction of the mean length of the other edges around the vertex it
/// removes is collapsed (a triangle with such an edge has an angle of at most ~14°).
pub const COLLAPSE_REL: f64 = 0.25;
/// Largest angle (degrees) between the normal of a triangle a change makes and the normals of
/// the triangles it replaces.
pub const MAX_TURN_DEG: f64 = 10.0;
/// Largest turn of the boundary (degrees) at a boundary vertex that may be removed (into its
/// neighbour along the boundary): the outline moves by less than 1 % of the collapsed edge.
const MAX_BOUNDARY_TURN_DEG: f64 = 1.0;
/// Smallest rise of the smallest angle (degrees) for a flip to be made: no flip back and forth.
const MIN_GAIN_DEG: f64 = 0.1;
/// Rounds of collapses and flips (each round visits every candidate once).
const MAX_ROUNDS: usize = 8;

/// Where a vertex stands with respect to the lines.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    /// On no line.
    Free,
    /// An inner vertex of one line (index into the line, position in it), made by the tracing.
    Inner(usize, usize),
    /// An end, a notch, a vertex on two lines or twice on one, or a vertex of the mesh the
    /// line went through: never removed.
    Kept,
}

/// Tidies the mesh around the lines (see the module documentation); `first_new` is the first
/// vertex the tracing added; `notches` are updated with the lines. Removed vertices keep their
/// slot with no face; [`compact`] renumbers.
pub(super) fn tidy(ed: &mut Edit, notches: &[Vec<u32>], first_new: usize) {
    let cos_turn = MAX_TURN_DEG.to_radians().cos();
    for _ in 0..MAX_ROUNDS {
        let collapsed = collapse_round(ed, notches, first_new, cos_turn);
        let flipped = flip_round(ed, first_new, cos_turn);
        if !collapsed && !flipped {
            break;
        }
    }
}

/// The vertices near the lines: every vertex the tracing made and their neighbours.
fn near_lines(ed: &Edit, first_new: usize) -> Vec<u32> {
    let mut mark = vec![false; ed.pos.len()];
    for v in first_new..ed.pos.len() {
        if ed.vf[v].is_empty() {
            continue;
        }
        mark[v] = true;
        for w in neighbours(ed, v as u32) {
            mark[w as usize] = true;
        }
    }
    (0..ed.pos.len() as u32)
        .filter(|&v| mark[v as usize])
        .collect()
}

fn neighbours(ed: &Edit, v: u32) -> Vec<u32> {
    let mut out: Vec<u32> = ed.vf[v as usize]
        .iter()
        .flat_map(|&f| ed.tris[f as usize])
        .filter(|&w| w != v)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

fn role(ed: &Edit, notches: &[Vec<u32>], first_new: usize, v: u32) -> Role {
    if notches.iter().any(|n| n.contains(&v)) {
        return Role::Kept;
    }
    let mut found = None;
    for (k, l) in ed.lines.iter().enumerate() {
        for (i, &w) in l.iter().enumerate() {
            if w != v {
                continue;
            }
            if found.is_some() || i == 0 || i + 1 == l.len() || (v as usize) < first_new {
                return Role::Kept;
            }
            found = Some((k, i));
        }
    }
    found.map_or(Role::Free, |(k, i)| Role::Inner(k, i))
}

fn normal(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a)
}

/// Smallest interior angle (radians) of a triangle; 0 for a degenerate one.
fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let corner = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, w) = (q - p, r - p);
        let d = u.length() * w.length();
        if d > 0.0 {
            (u.dot(w) / d).clamp(-1.0, 1.0).acos()
        } else {
            0.0
        }
    };
    corner(a, b, c).min(corner(b, c, a)).min(corner(c, a, b))
}

fn tri_min_angle(ed: &Edit, t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| ed.pos[v as usize]);
    min_angle(a, b, c)
}

/// True when the normal `n` of a new triangle is within the allowed turn of every old one.
fn keeps_normals(n: DVec3, old: &[DVec3], cos_turn: f64) -> bool {
    let ln = n.length();
    ln > 0.0
        && old
            .iter()
            .all(|o| o.length() > 0.0 && n.dot(*o) >= cos_turn * ln * o.length())
}

fn is_boundary_edge(ed: &Edit, a: u32, b: u32) -> bool {
    ed.faces_of_edge(a, b).len() == 1
}

/// The other ends of the boundary edges at `v`.
fn boundary_neighbours(ed: &Edit, v: u32) -> Vec<u32> {
    neighbours(ed, v)
        .into_iter()
        .filter(|&w| is_boundary_edge(ed, v, w))
        .collect()
}

/// One round of collapses, shortest edges first; true when any was made.
fn collapse_round(ed: &mut Edit, notches: &[Vec<u32>], first_new: usize, cos_turn: f64) -> bool {
    let mut cand: Vec<(f64, u32, u32)> = Vec::new();
    for w in near_lines(ed, first_new) {
        let nb = neighbours(ed, w);
        if nb.len() < 2 {
            continue;
        }
        let pw = ed.pos[w as usize];
        let total: f64 = nb.iter().map(|&u| pw.distance(ed.pos[u as usize])).sum();
        for &u in &nb {
            if (w as usize) < first_new && (u as usize) < first_new {
                continue;
            }
            let l = pw.distance(ed.pos[u as usize]);
            let others = (total - l) / (nb.len() - 1) as f64;
            if l < COLLAPSE_REL * others {
                cand.push((l, w, u));
            }
        }
    }
    cand.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    let mut any = false;
    for (_, w, u) in cand {
        if ed.vf[w as usize].is_empty() || ed.vf[u as usize].is_empty() {
            continue;
        }
        if ed.faces_of_edge(u, w).is_empty() {
            continue;
        }
        if try_collapse(ed, notches, first_new, w, u, cos_turn) {
            any = true;
        }
    }
    any
}

/// Removes `w` into `u` when the rules of the module documentation allow it.
fn try_collapse(
    ed: &mut Edit,
    notches: &[Vec<u32>],
    first_new: usize,
    w: u32,
    u: u32,
    cos_turn: f64,
) -> bool {
    let line_slot = match role(ed, notches, first_new, w) {
        Role::Kept => return false,
        Role::Free => None,
        Role::Inner(k, i) => {
            let l = &ed.lines[k];
            if l[i - 1] != u && l[i + 1] != u {
                return false;
            }
            Some((k, i))
        }
    };
    let shared = ed.faces_of_edge(u, w);
    let boundary_w = ed.on_boundary(w);
    if boundary_w {
        // Only along a straight stretch of the boundary, and never a line's vertex.
        if line_slot.is_some() || shared.len() != 1 {
            return false;
        }
        let bn = boundary_neighbours(ed, w);
        if bn.len() != 2 || !bn.contains(&u) {
            return false;
        }
        let pw = ed.pos[w as usize];
        let (d0, d1) = (pw - ed.pos[bn[0] as usize], ed.pos[bn[1] as usize] - pw);
        if d0.dot(d1) < MAX_BOUNDARY_TURN_DEG.to_radians().cos() * d0.length() * d1.length() {
            return false;
        }
    } else if ed.on_boundary(u) && shared.len() != 2 {
        return false;
    }
    // Link condition: the common neighbours of u and w are the far corners of their triangles.
    let far: Vec<u32> = shared
        .iter()
        .map(|&f| {
            *ed.tris[f as usize]
                .iter()
                .find(|&&x| x != u && x != w)
                .expect("a triangle has three corners")
        })
        .collect();
    let nu = neighbours(ed, u);
    let common = neighbours(ed, w)
        .into_iter()
        .filter(|x| nu.contains(x))
        .count();
    if common != far.len() {
        return false;
    }
    // Geometry: every moved triangle keeps its orientation and the worst angle rises.
    let star = ed.vf[w as usize].clone();
    let old_min = star
        .iter()
        .map(|&f| tri_min_angle(ed, ed.tris[f as usize]))
        .fold(f64::INFINITY, f64::min);
    let old_normals: Vec<DVec3> = star
        .iter()
        .map(|&f| {
            let [a, b, c] = ed.tris[f as usize].map(|v| ed.pos[v as usize]);
            normal(a, b, c)
        })
        .collect();
    let mut new_min = f64::INFINITY;
    for &f in &star {
        let t = ed.tris[f as usize];
        if t.contains(&u) {
            continue;
        }
        let nt = t.map(|x| if x == w { u } else { x });
        let [a, b, c] = nt.map(|v| ed.pos[v as usize]);
        if !keeps_normals(normal(a, b, c), &old_normals, cos_turn) {
            return false;
        }
        new_min = new_min.min(min_angle(a, b, c));
    }
    if new_min <= old_min {
        return false;
    }
    for &f in &star {
        let t = ed.tris[f as usize];
        if t.contains(&u) {
            ed.remove_face(f);
        } else {
            ed.set_face(f, t.map(|x| if x == w { u } else { x }));
        }
    }
    if let Some((k, i)) = line_slot {
        ed.lines[k].remove(i);
    }
    true
}

/// One round of flips; true when any was made.
fn flip_round(ed: &mut Edit, first_new: usize, cos_turn: f64) -> bool {
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for v in near_lines(ed, first_new) {
        for w in neighbours(ed, v) {
            edges.push((v.min(w), v.max(w)));
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let mut on_line: Vec<(u32, u32)> = ed
        .lines
        .iter()
        .flat_map(|l| l.windows(2).map(|e| (e[0].min(e[1]), e[0].max(e[1]))))
        .collect();
    on_line.sort_unstable();
    let min_gain = MIN_GAIN_DEG.to_radians();
    let mut any = false;
    for (a, b) in edges {
        if on_line.binary_search(&(a, b)).is_ok() {
            continue;
        }
        let fs = ed.faces_of_edge(a, b);
        if fs.len() != 2 {
            continue;
        }
        // Orient: f0 runs a → b, f1 runs b → a.
        let (f0, f1) = {
            let t = ed.tris[fs[0] as usize];
            let k = t.iter().position(|&x| x == a).expect("a is a corner");
            if t[(k + 1) % 3] == b {
                (fs[0], fs[1])
            } else {
                (fs[1], fs[0])
            }
        };
        let far = |f: u32| {
            *ed.tris[f as usize]
                .iter()
                .find(|&&x| x != a && x != b)
                .expect("a triangle has three corners")
        };
        let (c, d) = (far(f0), far(f1));
        if [a, b, c, d].iter().all(|&x| (x as usize) < first_new) {
            continue;
        }
        if c == d || neighbours(ed, c).contains(&d) {
            continue;
        }
        let (t0, t1) = ([a, b, c], [b, a, d]);
        let (n0, n1) = ([c, a, d], [d, b, c]);
        let old = tri_min_angle(ed, t0).min(tri_min_angle(ed, t1));
        let new = tri_min_angle(ed, n0).min(tri_min_angle(ed, n1));
        if new < old + min_gain {
            continue;
        }
        let nrm = |t: [u32; 3]| {
            let [p, q, r] = t.map(|v| ed.pos[v as usize]);
            normal(p, q, r)
        };
        let old_n = [nrm(t0), nrm(t1)];
        if !keeps_normals(old_n[0], &old_n[1..], cos_turn)
            || !keeps_normals(nrm(n0), &old_n, cos_turn)
            || !keeps_normals(nrm(n1), &old_n, cos_turn)
        {
            continue;
        }
        ed.set_face(f0, n0);
        ed.set_face(f1, n1);
        any = true;
    }
    any
}

/// The mesh without removed vertices and faces, and the old-to-new vertex numbering.
pub(super) fn compact(ed: &Edit) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<u32>) {
    let mut used = vec![false; ed.pos.len()];
    let tris: Vec<[u32; 3]> = ed
        .tris
        .iter()
        .filter(|t| t[0] != u32::MAX)
        .copied()
        .collect();
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut map = vec![u32::MAX; ed.pos.len()];
    let mut pos = Vec::with_capacity(ed.pos.len());
    for (v, p) in ed.pos.iter().enumerate() {
        if used[v] {
            map[v] = pos.len() as u32;
            pos.push(*p);
        }
    }
    let tris = tris
        .into_iter()
        .map(|t| t.map(|v| map[v as usize]))
        .collect();
    (pos, tris, map)
}
