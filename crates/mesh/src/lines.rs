//! Style lines embedded in a mesh: 3D polylines projected onto the surface and traced across its
//! triangles, every crossing with a mesh edge inserted as a vertex, so that each line runs
//! exactly along mesh edges (no zig-zag along the old edges) and the mesh can be split along it
//! ([`crate::regions`]).
//!
//! Tracing: each given point is projected onto the nearest point of the surface; between two
//! consecutive points the line follows the surface in the plane through the current vertex, the
//! next point and the surface normal, re-aimed at every crossed edge (a normal section of the
//! surface, as a designer's "curve on surface" between two picks). A crossing closer than
//! [`SNAP_REL`] of an edge's length to one of its ends goes through that vertex instead of
//! splitting the edge next to it (no sliver triangles), unless the line would then fold back onto
//! itself or run along the boundary or another line; every other crossing splits the edge.
//! New vertices lie on the old edges and faces; then the mesh around the lines is made
//! well-shaped again (`tidy`: short edges collapsed, edges flipped), moving the surface by far
//! less than its chordal tolerance and keeping every end and notch exactly.
//!
//! Notches are extra points of their line, inserted exactly where they project (never snapped to
//! a vertex), so both regions beside the line carry the notch at the same vertex.
//!
//! A line must end on the surface boundary or on another line (within [`END_REL`] of the part's
//! size; the end is moved onto it), or close on itself (last point = first point): lines ending
//! on other lines are traced after them.

use flatcut_geom::DVec3;

use crate::TriMesh;
use crate::nearest::closest_on_triangle;

/// A crossing within this fraction of an edge's length from one of its ends goes through that
/// end (a given point within this fraction of a triangle's shortest edge from a corner is that
/// corner): the line moves by at most a twentieth of a mesh edge (0.25 mm on the 5 mm edges of a
/// shoe upper at 0.4 mm chordal tolerance), and no triangle thinner than a twentieth of its
/// neighbours is made.
pub const SNAP_REL: f64 = 0.05;
/// A line end within this fraction of the mesh's bounding-box diagonal of the surface boundary
/// or of another line lies on it (and is moved onto it).
pub const END_REL: f64 = 0.01;
/// A given point farther than this fraction of the bounding-box diagonal from the surface is a
/// mistake in the design, not a point on the surface.
pub const OFF_SURFACE_REL: f64 = 0.02;
/// Relative distance (of the bounding-box diagonal) under which two points coincide: round-off
/// of points computed on the mesh.
const SAME_POINT_REL: f64 = 1e-9;

/// A line to embed: points near the surface, in order, and notch points on it.
#[derive(Clone, Debug, PartialEq)]
pub struct LineSpec {
    /// The line's points (mm) on or near the surface, in order; joined along the surface.
    pub points: Vec<DVec3>,
    /// Notch points (mm) on or near the line.
    pub notches: Vec<DVec3>,
}

/// A mesh with its lines as vertex paths.
#[derive(Clone, Debug)]
pub struct Embedded {
    /// The mesh, its triangles split along the lines (surface parameters are dropped: the new
    /// vertices have none).
    pub mesh: TriMesh,
    /// Per line, its vertices from its first point to its last; a closed line repeats its first
    /// vertex at the end.
    pub lines: Vec<Vec<u32>>,
    /// Per line, the vertex of each of its notches, in the order given.
    pub notches: Vec<Vec<u32>>,
}

/// Why a line cannot be embedded. `line` is the line's index in the input; points are 3D (mm).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LineError {
    #[error("line {line}: it needs at least two distinct points")]
    /// The line has fewer than two distinct points.
    TooShort {
        /// 0-based index of the line.
        line: usize,
    },
    #[error("line {line}: point {point} ({x:.2}, {y:.2}, {z:.2}) is {dist:.2} mm from the surface")]
    /// A point of the line lies too far from the surface.
    OffSurface {
        /// 0-based index of the line.
        line: usize,
        /// 0-based index of the point in the line.
        point: usize,
        /// x of the point (mm).
        x: f64,
        /// y of the point (mm).
        y: f64,
        /// z of the point (mm).
        z: f64,
        /// Its distance from the surface (mm).
        dist: f64,
    },
    #[error(
        "line {line}: notch {notch} ({x:.2}, {y:.2}, {z:.2}) is {dist:.2} mm from the line (at most {tol:.2} mm)"
    )]
    /// A notch lies too far from its line.
    NotchOffLine {
        /// 0-based index of the line.
        line: usize,
        /// 0-based index of the notch in the line.
        notch: usize,
        /// x of the notch (mm).
        x: f64,
        /// y of the notch (mm).
        y: f64,
        /// z of the notch (mm).
        z: f64,
        /// Its distance from the line (mm).
        dist: f64,
        /// The largest distance accepted (mm).
        tol: f64,
    },
    #[error(
        "line {line}: its {end} end ({x:.2}, {y:.2}, {z:.2}) is {dist:.2} mm from the surface boundary and from every other line (at most {tol:.2} mm): it does not close a region; end it on the boundary or on another line"
    )]
    /// An end of the line meets neither the boundary nor another line, so it closes no region.
    LooseEnd {
        /// 0-based index of the line.
        line: usize,
        /// Which end, "first" or "last".
        end: &'static str,
        /// x of the end (mm).
        x: f64,
        /// y of the end (mm).
        y: f64,
        /// z of the end (mm).
        z: f64,
        /// Its distance from the boundary and the other lines (mm).
        dist: f64,
        /// The largest distance accepted (mm).
        tol: f64,
    },
    #[error(
        "line {line} leaves the surface near ({x:.2}, {y:.2}, {z:.2}) on its way from point {from} to point {to}: give points along the surface there"
    )]
    /// The way between two points of the line leaves the surface.
    LeavesSurface {
        /// 0-based index of the line.
        line: usize,
        /// 0-based index of the point the way starts at.
        from: usize,
        /// 0-based index of the point it goes to.
        to: usize,
        /// x of where it leaves (mm).
        x: f64,
        /// y of where it leaves (mm).
        y: f64,
        /// z of where it leaves (mm).
        z: f64,
    },
    #[error(
        "line {line}: no way along the surface found from point {from} to point {to} (stopped near ({x:.2}, {y:.2}, {z:.2})): give points closer together"
    )]
    /// No way along the surface was found between two points of the line.
    Lost {
        /// 0-based index of the line.
        line: usize,
        /// 0-based index of the point the way starts at.
        from: usize,
        /// 0-based index of the point it goes to.
        to: usize,
        /// x of where the search stopped (mm).
        x: f64,
        /// y of where the search stopped (mm).
        y: f64,
        /// z of where the search stopped (mm).
        z: f64,
    },
}

/// Embeds the lines in the mesh (see the module documentation).
pub fn embed_lines(mesh: &TriMesh, specs: &[LineSpec]) -> Result<Embedded, LineError> {
    let mut ed = Edit::new(mesh);
    let diag = mesh.bbox().diagonal();
    let end_tol = END_REL * diag;
    // Project every point and check it is on the surface.
    let mut projected: Vec<Vec<Anchor>> = Vec::with_capacity(specs.len());
    for (k, s) in specs.iter().enumerate() {
        projected.push(anchors(&ed, k, s, diag)?);
    }
    ed.lines = vec![Vec::new(); specs.len()];
    let mut traced = vec![false; specs.len()];
    let mut notch_vertices: Vec<Vec<u32>> = vec![Vec::new(); specs.len()];
    // Trace lines whose ends lie on the boundary or on lines already traced; repeat until all
    // are traced or none can be.
    while traced.iter().any(|t| !t) {
        let mut progress = false;
        let mut first_loose: Option<LineError> = None;
        for k in 0..specs.len() {
            if traced[k] {
                continue;
            }
            match ends_of(&ed, k, &projected[k], end_tol) {
                Ok(ends) => {
                    let (path, notches) = trace(&mut ed, k, &projected[k], ends, diag)?;
                    ed.lines[k] = path;
                    notch_vertices[k] = notches;
                    traced[k] = true;
                    progress = true;
                }
                Err(e) => {
                    first_loose.get_or_insert(e);
                }
            }
        }
        if !progress {
            return Err(first_loose.expect("an untraced line failed its end check"));
        }
    }
    tidy::tidy(&mut ed, &notch_vertices, mesh.positions.len());
    let (pos, tris, map) = tidy::compact(&ed);
    let renumber = |l: &Vec<u32>| l.iter().map(|&v| map[v as usize]).collect();
    Ok(Embedded {
        mesh: TriMesh::new(pos, tris),
        lines: ed.lines.iter().map(renumber).collect(),
        notches: notch_vertices.iter().map(renumber).collect(),
    })
}

/// A point of a line on the surface: its projection, whether it is a notch (inserted exactly),
/// and its index among the given points (or notches) for messages.
#[derive(Clone, Copy, Debug)]
struct Anchor {
    p: DVec3,
    notch: Option<usize>,
    point: usize,
}

/// The line's points projected onto the surface, with the notches inserted in order along it.
fn anchors(ed: &Edit, line: usize, s: &LineSpec, diag: f64) -> Result<Vec<Anchor>, LineError> {
    let mut out: Vec<Anchor> = Vec::with_capacity(s.points.len() + s.notches.len());
    for (i, &p) in s.points.iter().enumerate() {
        let (q, d) = ed.nearest(p);
        if d.is_nan() || d > OFF_SURFACE_REL * diag {
            return Err(LineError::OffSurface {
                line,
                point: i,
                x: p.x,
                y: p.y,
                z: p.z,
                dist: d,
            });
        }
        if out
            .last()
            .is_none_or(|a: &Anchor| a.p.distance(q) > SAME_POINT_REL * diag)
        {
            out.push(Anchor {
                p: q,
                notch: None,
                point: i,
            });
        }
    }
    if out.len() < 2 {
        return Err(LineError::TooShort { line });
    }
    let tol = END_REL * diag;
    for (j, &n) in s.notches.iter().enumerate() {
        let (q, dist) = ed.nearest(n);
        // Where along the polyline of the projected points the notch falls.
        let mut best = (f64::INFINITY, 0usize, 0.0f64);
        for i in 0..out.len() - 1 {
            let (a, b) = (out[i].p, out[i + 1].p);
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 {
                ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = q.distance(a + ab * t);
            if d < best.0 {
                best = (d, i, t);
            }
        }
        // The polyline is a chord of the surface line, which sags below it on a curved
        // surface: allow a quarter of the chord besides the tolerance (the notch becomes a
        // point of the line, so the traced line goes through it).
        let (d, i, _) = best;
        if !(dist <= OFF_SURFACE_REL * diag && d <= tol.max(0.25 * chord_len(&out, i))) {
            return Err(LineError::NotchOffLine {
                line,
                notch: j,
                x: n.x,
                y: n.y,
                z: n.z,
                dist: d,
                tol,
            });
        }
        let same = SAME_POINT_REL * diag;
        if let Some(k) = [i, i + 1]
            .into_iter()
            .find(|&k| out[k].p.distance(q) <= same && out[k].notch.is_none())
        {
            out[k].notch = Some(j);
            continue;
        }
        let point = out[i].point;
        out.insert(
            i + 1,
            Anchor {
                p: q,
                notch: Some(j),
                point,
            },
        );
    }
    Ok(out)
}

fn chord_len(a: &[Anchor], i: usize) -> f64 {
    a[i].p.distance(a[i + 1].p)
}

/// Where a line starts and ends on the mesh.
#[derive(Clone, Copy, Debug)]
enum End {
    /// The line closes on itself.
    Closed,
    /// At this point of the boundary or of a traced line.
    At(DVec3),
}

/// The two ends of a line moved onto the boundary or a traced line, or the first end that is
/// on neither.
fn ends_of(ed: &Edit, line: usize, anchors: &[Anchor], tol: f64) -> Result<(End, End), LineError> {
    let (first, last) = (anchors[0].p, anchors[anchors.len() - 1].p);
    if anchors.len() >= 3 && first.distance(last) <= tol {
        return Ok((End::Closed, End::Closed));
    }
    let segs = ed.boundary_and_line_edges();
    let snap = |p: DVec3, end: &'static str| -> Result<End, LineError> {
        let mut best = (f64::INFINITY, 0u32, 0u32, 0.0);
        for &(a, b) in &segs {
            let (pa, pb) = (ed.pos[a as usize], ed.pos[b as usize]);
            let ab = pb - pa;
            let t = ((p - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            let d = p.distance(pa + ab * t);
            if d < best.0 {
                best = (d, a, b, t);
            }
        }
        if best.0 <= tol {
            let (pa, pb) = (ed.pos[best.1 as usize], ed.pos[best.2 as usize]);
            Ok(End::At(pa + (pb - pa) * best.3))
        } else {
            Err(LineError::LooseEnd {
                line,
                end,
                x: p.x,
                y: p.y,
                z: p.z,
                dist: best.0,
                tol,
            })
        }
    };
    Ok((snap(first, "first")?, snap(last, "last")?))
}

/// Traces one line: its path of vertices and the vertices of its notches.
fn trace(
    ed: &mut Edit,
    line: usize,
    anchors: &[Anchor],
    ends: (End, End),
    diag: f64,
) -> Result<(Vec<u32>, Vec<u32>), LineError> {
    let notch_count = anchors.iter().filter(|a| a.notch.is_some()).count();
    let mut notches = vec![u32::MAX; notch_count];
    let same = SAME_POINT_REL * diag;
    let start = match ends.0 {
        End::Closed => ed.insert_point(anchors[0].p, SNAP_REL, same),
        End::At(p) => ed.insert_point(p, SNAP_REL, same),
    };
    if let Some(j) = anchors[0].notch {
        notches[j] = start;
    }
    let mut path = vec![start];
    let n = anchors.len();
    for i in 1..n {
        let target = if i == n - 1 {
            match ends.1 {
                End::Closed => Target::Vertex(start),
                End::At(p) => Target::Point(p),
            }
        } else {
            Target::Point(anchors[i].p)
        };
        let exact = anchors[i].notch.is_some();
        let steps = ed.walk(&path, target, exact, same).map_err(|stop| {
            let p = ed.pos[stop.at as usize];
            let (from, to) = (anchors[i - 1].point, anchors[i].point);
            if stop.left_surface {
                LineError::LeavesSurface {
                    line,
                    from,
                    to,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                }
            } else {
                LineError::Lost {
                    line,
                    from,
                    to,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                }
            }
        })?;
        path.extend(steps);
        path.dedup();
        if let Some(j) = anchors[i].notch {
            notches[j] = *path.last().expect("non-empty");
        }
    }
    Ok((path, notches))
}

/// Where a walk goes.
#[derive(Clone, Copy, Debug)]
enum Target {
    /// A point on the surface.
    Point(DVec3),
    /// An existing vertex.
    Vertex(u32),
}

/// Where and why a walk stopped.
struct Stop {
    at: u32,
    left_surface: bool,
}

/// A triangle mesh under edit: triangles split in place, faces per vertex kept up to date, and
/// the traced lines updated when one of their edges is split.
struct Edit {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    vf: Vec<Vec<u32>>,
    lines: Vec<Vec<u32>>,
}

impl Edit {
    fn new(mesh: &TriMesh) -> Self {
        let mut vf = vec![Vec::new(); mesh.positions.len()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                vf[v as usize].push(f as u32);
            }
        }
        Self {
            pos: mesh.positions.clone(),
            tris: mesh.triangles.clone(),
            vf,
            lines: Vec::new(),
        }
    }

    /// The nearest surface point to `p` and its distance (brute force: the mesh changes
    /// between queries, and they are few).
    fn nearest(&self, p: DVec3) -> (DVec3, f64) {
        let mut best = (p, f64::INFINITY);
        for t in &self.tris {
            let [a, b, c] = t.map(|v| self.pos[v as usize]);
            let (q, _) = closest_on_triangle(p, a, b, c);
            let d = q.distance(p);
            if d < best.1 {
                best = (q, d);
            }
        }
        best
    }

    fn faces_of_edge(&self, a: u32, b: u32) -> Vec<u32> {
        self.vf[a as usize]
            .iter()
            .copied()
            .filter(|&f| self.tris[f as usize].contains(&b))
            .collect()
    }

    /// Boundary edges and edges of traced lines, each once.
    fn boundary_and_line_edges(&self) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for (f, t) in self.tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let shared = self.vf[a as usize]
                    .iter()
                    .any(|&g| g as usize != f && self.tris[g as usize].contains(&b));
                if !shared {
                    out.push((a, b));
                }
            }
        }
        for l in &self.lines {
            for w in l.windows(2) {
                out.push((w[0], w[1]));
            }
        }
        out
    }

    fn add_face(&mut self, t: [u32; 3]) -> u32 {
        let f = self.tris.len() as u32;
        self.tris.push(t);
        for v in t {
            self.vf[v as usize].push(f);
        }
        f
    }

    fn add_vertex(&mut self, p: DVec3) -> u32 {
        self.pos.push(p);
        self.vf.push(Vec::new());
        (self.pos.len() - 1) as u32
    }

    /// Replaces face `f` by `t` (updating the faces of the vertices that enter or leave it).
    fn set_face(&mut self, f: u32, t: [u32; 3]) {
        let old = self.tris[f as usize];
        for v in old {
            if !t.contains(&v) {
                self.vf[v as usize].retain(|&g| g != f);
            }
        }
        for v in t {
            if !old.contains(&v) {
                self.vf[v as usize].push(f);
            }
        }
        self.tris[f as usize] = t;
    }

    /// Splits edge (a, b) at `p` (on it): each triangle beside it becomes two. Lines running
    /// along the edge get the new vertex.
    fn split_edge(&mut self, a: u32, b: u32, p: DVec3) -> u32 {
        let v = self.add_vertex(p);
        for f in self.faces_of_edge(a, b) {
            let t = self.tris[f as usize];
            let k = (0..3)
                .find(|&k| {
                    let (x, y) = (t[k], t[(k + 1) % 3]);
                    (x, y) == (a, b) || (x, y) == (b, a)
                })
                .expect("the face holds the edge");
            let (x, y, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            self.set_face(f, [x, v, c]);
            self.add_face([v, y, c]);
        }
        for l in &mut self.lines {
            let mut i = 0;
            while i + 1 < l.len() {
                if (l[i], l[i + 1]) == (a, b) || (l[i], l[i + 1]) == (b, a) {
                    l.insert(i + 1, v);
                    i += 1;
                }
                i += 1;
            }
        }
        v
    }

    /// Removes face `f` (its slot stays, with no corners).
    fn remove_face(&mut self, f: u32) {
        for v in self.tris[f as usize] {
            self.vf[v as usize].retain(|&g| g != f);
        }
        self.tris[f as usize] = [u32::MAX; 3];
    }

    /// Splits face `f` at `p` (inside it) into three.
    fn split_face(&mut self, f: u32, p: DVec3) -> u32 {
        let v = self.add_vertex(p);
        let [a, b, c] = self.tris[f as usize];
        self.set_face(f, [a, b, v]);
        self.add_face([b, c, v]);
        self.add_face([c, a, v]);
        v
    }

    /// True when `v` is on the boundary (one of its edges has one triangle).
    fn on_boundary(&self, v: u32) -> bool {
        self.vf[v as usize].iter().any(|&f| {
            let t = self.tris[f as usize];
            let k = t.iter().position(|&x| x == v).expect("v is a corner");
            [t[(k + 1) % 3], t[(k + 2) % 3]]
                .into_iter()
                .any(|w| self.faces_of_edge(v, w).len() == 1)
        })
    }

    /// True when the line may not step from `v` to its neighbour `w` on its way: `w` is one of
    /// the line's own vertices (`visited`: going back through one would fold the line on
    /// itself), or a boundary vertex (the line touches the boundary only at its ends), or the
    /// edge v–w is an edge of another line (the line would run along it).
    fn blocked(&self, v: u32, w: u32, visited: &[u32]) -> bool {
        visited.contains(&w)
            || self.on_boundary(w)
            || self.lines.iter().any(|l| {
                l.windows(2)
                    .any(|e| (e[0], e[1]) == (v, w) || (e[0], e[1]) == (w, v))
            })
    }

    /// The vertex at parameter `t` of edge (a, b) (opposite `v` in a triangle): an end within
    /// [`SNAP_REL`] the line may step onto from `v` ([`Edit::blocked`]), else a new vertex
    /// splitting the edge; `None` when `t` is a blocked end itself.
    fn insert_on_edge(&mut self, v: u32, a: u32, b: u32, t: f64, visited: &[u32]) -> Option<u32> {
        const END: f64 = 1e-12;
        if t <= SNAP_REL && !self.blocked(v, a, visited) {
            Some(a)
        } else if t >= 1.0 - SNAP_REL && !self.blocked(v, b, visited) {
            Some(b)
        } else if t > END && t < 1.0 - END {
            let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
            Some(self.split_edge(a, b, pa + (pb - pa) * t))
        } else {
            None
        }
    }

    /// Inserts the surface point `p`, snapping to a corner within `snap` of the face's shortest
    /// edge and onto an edge within `snap` of its length; `same` is the distance at which
    /// points coincide (the least snap).
    fn insert_point(&mut self, p: DVec3, snap: f64, same: f64) -> u32 {
        let mut best = (f64::INFINITY, 0u32);
        for (f, t) in self.tris.iter().enumerate() {
            let [a, b, c] = t.map(|v| self.pos[v as usize]);
            let d = closest_on_triangle(p, a, b, c).0.distance(p);
            if d < best.0 {
                best = (d, f as u32);
            }
        }
        self.insert_in_face(best.1, p, snap, same, None)
    }

    /// Inserts `p` (on face `f`) as in [`Edit::insert_point`]; on a walk (`from` = the walk's
    /// vertex and the line so far), snapping to no corner the line may not step onto unless `p`
    /// is that corner.
    fn insert_in_face(
        &mut self,
        f: u32,
        p: DVec3,
        snap: f64,
        same: f64,
        from: Option<(u32, &[u32])>,
    ) -> u32 {
        let t = self.tris[f as usize];
        let c = t.map(|v| self.pos[v as usize]);
        let shortest = (0..3)
            .map(|k| c[k].distance(c[(k + 1) % 3]))
            .fold(f64::INFINITY, f64::min);
        if let Some(k) = (0..3).min_by(|&i, &j| c[i].distance(p).total_cmp(&c[j].distance(p)))
            && (c[k].distance(p) <= same
                || (c[k].distance(p) <= snap * shortest
                    && from
                        .is_none_or(|(v, visited)| t[k] == v || !self.blocked(v, t[k], visited))))
        {
            return t[k];
        }
        let on_edge = (0..3)
            .map(|k| {
                let (a, b) = (c[k], c[(k + 1) % 3]);
                let ab = b - a;
                let s = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                let q = a + ab * s;
                (q.distance(p) / (snap * ab.length()).max(same), k, q)
            })
            .min_by(|x, y| x.0.total_cmp(&y.0));
        match on_edge {
            Some((r, k, q)) if r <= 1.0 => self.split_edge(t[k], t[(k + 1) % 3], q),
            _ => self.split_face(f, p),
        }
    }

    /// Area-weighted normal of the faces around `v` (not normalised).
    fn vertex_normal(&self, v: u32) -> DVec3 {
        self.vf[v as usize]
            .iter()
            .map(|&f| {
                let [a, b, c] = self.tris[f as usize].map(|i| self.pos[i as usize]);
                (b - a).cross(c - a)
            })
            .sum()
    }

    /// Walks from the last vertex of `done` (the line so far) to the target along the surface,
    /// splitting the crossed edges and never stepping back onto a vertex of the line; returns
    /// the vertices passed, the last one at the target. An `exact` target point is inserted
    /// where it is (a notch), otherwise it snaps like any crossing.
    fn walk(
        &mut self,
        done: &[u32],
        target: Target,
        exact: bool,
        same: f64,
    ) -> Result<Vec<u32>, Stop> {
        let q = match target {
            Target::Point(p) => p,
            Target::Vertex(v) => self.pos[v as usize],
        };
        let snap = if exact { 0.0 } else { SNAP_REL };
        let mut v = *done.last().expect("a walk starts at a vertex");
        let mut path = Vec::new();
        // The line's vertices so far, which the walk must not step back onto.
        let mut visited = done.to_vec();
        let max_steps = self.tris.len() + 1000;
        for _ in 0..max_steps {
            if let Target::Vertex(w) = target
                && w == v
            {
                return Ok(path);
            }
            if self.pos[v as usize].distance(q) <= same {
                return Ok(path);
            }
            // The target in a face around v: insert it there (v is a corner of that face, so
            // the new vertex is joined to v by an edge).
            let star = self.vf[v as usize].clone();
            let here = star.iter().copied().find(|&f| {
                let [a, b, c] = self.tris[f as usize].map(|i| self.pos[i as usize]);
                closest_on_triangle(q, a, b, c).0.distance(q) <= same
            });
            if let Some(f) = here {
                let w = match target {
                    Target::Vertex(w) => {
                        if !self.tris[f as usize].contains(&w) {
                            return Err(Stop {
                                at: v,
                                left_surface: false,
                            });
                        }
                        w
                    }
                    Target::Point(p) => {
                        self.insert_in_face(f, p, snap, same, Some((v, visited.as_slice())))
                    }
                };
                if w != v {
                    path.push(w);
                }
                return Ok(path);
            }
            // Otherwise cross the edge opposite v that the plane through v, q and the normal
            // meets ahead of v.
            let pv = self.pos[v as usize];
            let n = self.vertex_normal(v);
            let d = q - pv;
            let plane = n.cross(d);
            let ahead = d - n * (d.dot(n) / n.length_squared().max(f64::MIN_POSITIVE));
            if !(plane.length() > 0.0 && ahead.length() > 0.0) {
                return Err(Stop {
                    at: v,
                    left_surface: false,
                });
            }
            let ahead = ahead.normalize();
            let mut best: Option<(f64, u32, u32, f64)> = None;
            for &f in &star {
                let t = self.tris[f as usize];
                let k = t.iter().position(|&x| x == v).expect("v is a corner");
                let (b, c) = (t[(k + 1) % 3], t[(k + 2) % 3]);
                let (pb, pc) = (self.pos[b as usize], self.pos[c as usize]);
                let (sb, sc) = (plane.dot(pb - pv), plane.dot(pc - pv));
                if sb * sc > 0.0 || (sb == 0.0 && sc == 0.0) {
                    continue;
                }
                let s = sb / (sb - sc);
                let x = pb + (pc - pb) * s;
                let dir = x - pv;
                let len = dir.length();
                if len.is_nan() || len <= 0.0 {
                    continue;
                }
                let cos = dir.normalize().dot(ahead);
                if cos > 0.0 && best.is_none_or(|bst| cos > bst.0) {
                    best = Some((cos, b, c, s));
                }
            }
            // No way ahead, or only across the boundary: the line would leave the surface (the
            // target is not on that boundary edge, or it would have been in the star).
            let Some((_, b, c, s)) = best.filter(|bst| self.faces_of_edge(bst.1, bst.2).len() > 1)
            else {
                return Err(Stop {
                    at: v,
                    left_surface: true,
                });
            };
            let Some(w) = self.insert_on_edge(v, b, c, s, &visited) else {
                return Err(Stop {
                    at: v,
                    left_surface: false,
                });
            };
            path.push(w);
            visited.push(w);
            v = w;
        }
        Err(Stop {
            at: v,
            left_surface: false,
        })
    }
}

#[cfg(test)]
mod tests;
mod tidy;
