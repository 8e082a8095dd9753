//! A scan's spikes removed, moving only what must move: an opt-in repair before a surface is cut
//! into parts within material limits.
//!
//! A map whose principal stretches lie within limits changes a corner's angle by at most a reach
//! (`flatcut_darts::cone::corner_reach`, 0.2003 rad at ±10 %), so an inside vertex whose angle
//! defect `|2π − Σ corner angles|` exceeds the reach times its number of corners lies inside no
//! part within the limits. A raw scan has such vertices where a triangle fan spikes out of the
//! surface; smoothing the whole scan moves millimetres everywhere and still leaves some. Here
//! only those vertices move:
//!
//! - A vertex beyond the bound is tried at two places: its projection onto the plane of its
//!   one-ring (through the ring's centroid, normal to the ring's vector area, Newell's method),
//!   and the ring's centroid (the umbrella). A move is taken when it lowers the excess beyond the
//!   bound summed over the vertex and its ring (the only vertices whose angles it changes); of
//!   the two, the lower excess wins, then the shorter move.
//! - Only where the vertex's own move leaves it beyond the bound are its ring's vertices tried,
//!   each the same way at its own ring, under the same rule; their moves are kept only when
//!   they bring the vertex within the bound (a ring raised part of the way up a spike would
//!   only widen it).
//! - A move is refused when it would take a vertex farther than `max_mm` from where it was in
//!   the input, or leave a face round it degenerate or flipped: every face of the moved vertex's
//!   star must face the way of its ring's vector area, which no move of the vertex changes.
//! - Rounds repeat over the vertices still beyond the bound, at most [`ROUNDS`] of them, each
//!   round the largest defect first (the lower index on a tie): the result is deterministic.
//!
//! Boundary vertices are never moved and never measured: their angles add up to whatever they
//! are on an outline (as the split's defects are 0 there), and they carry the piece's outline
//! and the seams sewn to it. A vertex is moved only when it is beyond the bound or in the ring
//! of one that is; a surface with no vertex beyond the bound comes back bit-identical.

use flatcut_geom::DVec3;

use crate::{Topology, TopologyError, TriMesh};

/// Most rounds over the vertices still beyond the bound.
pub const ROUNDS: usize = 8;

/// The smallest area of a face after a move, as a share of the squared mean edge length of the
/// moved vertex's star: below it the face counts as degenerate.
const DEGENERATE: f64 = 1e-6;

/// What [`despike`] changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Despiked {
    /// The vertices moved, ascending.
    pub moved: Vec<u32>,
    /// The largest distance a vertex moved from its input position (mm); 0 when none moved.
    pub max_mm: f64,
    /// The vertex that moved farthest and its input position; `None` when none moved.
    pub max_at: Option<(u32, DVec3)>,
    /// The inside vertices still beyond the bound after the repair, the largest defect first
    /// (the lower index on a tie): no move within the limits removed their spike.
    pub left: Vec<u32>,
}

/// Moves the inside vertices of `mesh` whose angle defect exceeds `reach` (radians, the most a
/// corner's angle may change) times their number of corners, and where needed their
/// neighbours, to remove the spikes (see the module doc); no vertex moves farther than
/// `max_mm` from its input position. Fails only where the mesh has no well-defined boundary
/// (non-manifold or inconsistently oriented).
pub fn despike(mesh: &mut TriMesh, reach: f64, max_mm: f64) -> Result<Despiked, TopologyError> {
    let topo = Topology::build(mesh)?;
    let n = mesh.positions.len();
    let mut rim = vec![false; n];
    for l in &topo.boundary_loops {
        for &v in l {
            rim[v as usize] = true;
        }
    }
    let star = stars(mesh);
    let input = mesh.positions.clone();
    let mut repair = Repair {
        mesh,
        star: &star,
        rim: &rim,
        input: &input,
        reach,
        max_mm,
    };
    for _ in 0..ROUNDS {
        let beyond = repair.beyond();
        let mut any = false;
        for v in beyond {
            if repair.excess(v) <= 0.0 {
                continue;
            }
            any |= repair.try_move(v);
            if repair.excess(v) > 0.0 {
                any |= repair.move_ring(v);
            }
        }
        if !any {
            break;
        }
    }
    let left = repair.beyond();
    let mut out = Despiked {
        left,
        ..Despiked::default()
    };
    for (v, (p, q)) in repair.mesh.positions.iter().zip(&input).enumerate() {
        if p == q {
            continue;
        }
        out.moved.push(v as u32);
        let d = p.distance(*q);
        if d > out.max_mm {
            out.max_mm = d;
            out.max_at = Some((v as u32, *q));
        }
    }
    Ok(out)
}

/// The faces round every vertex, ascending.
fn stars(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut star = vec![Vec::new(); mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            star[v as usize].push(t as u32);
        }
    }
    star
}

/// The state of one repair: the mesh being moved and what stays fixed while it moves.
struct Repair<'a> {
    mesh: &'a mut TriMesh,
    star: &'a [Vec<u32>],
    rim: &'a [bool],
    input: &'a [DVec3],
    reach: f64,
    max_mm: f64,
}

impl Repair<'_> {
    /// The sum of the corner angles at `v`.
    fn angle_sum(&self, v: u32) -> f64 {
        let p = &self.mesh.positions;
        self.star[v as usize]
            .iter()
            .map(|&t| {
                let tri = self.mesh.triangles[t as usize];
                let k = tri.iter().position(|&u| u == v).unwrap_or(0);
                let o = p[v as usize];
                (p[tri[(k + 1) % 3] as usize] - o).angle_between(p[tri[(k + 2) % 3] as usize] - o)
            })
            .sum()
    }

    /// How far the angle defect of `v` lies beyond what its corners can absorb (radians; 0 or
    /// less within the bound, and on the boundary).
    fn excess(&self, v: u32) -> f64 {
        if self.rim[v as usize] {
            return 0.0;
        }
        let defect = std::f64::consts::TAU - self.angle_sum(v);
        defect.abs() - self.reach * self.star[v as usize].len() as f64
    }

    /// The inside vertices beyond the bound, the largest defect first (the lower index on a tie).
    fn beyond(&self) -> Vec<u32> {
        let mut at: Vec<(u32, f64)> = (0..self.mesh.positions.len() as u32)
            .filter(|&v| !self.star[v as usize].is_empty())
            .map(|v| (v, self.excess(v)))
            .filter(|&(_, e)| e > 0.0)
            .collect();
        at.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        at.into_iter().map(|(v, _)| v).collect()
    }

    /// The vertices sharing a face with `v`, ascending.
    fn ring(&self, v: u32) -> Vec<u32> {
        let mut r: Vec<u32> = self.star[v as usize]
            .iter()
            .flat_map(|&t| self.mesh.triangles[t as usize])
            .filter(|&u| u != v)
            .collect();
        r.sort_unstable();
        r.dedup();
        r
    }

    /// The excess beyond the bound summed over `v` and its ring: what a move of `v` changes.
    fn local_excess(&self, v: u32, ring: &[u32]) -> f64 {
        std::iter::once(v)
            .chain(ring.iter().copied())
            .map(|u| self.excess(u).max(0.0))
            .sum()
    }

    /// The vector area of the star of `v` (twice the area, along the normal): that of its ring's
    /// polygon, the same wherever `v` is.
    fn star_area(&self, v: u32) -> DVec3 {
        let p = &self.mesh.positions;
        self.star[v as usize]
            .iter()
            .map(|&t| {
                let [a, b, c] = self.mesh.triangles[t as usize].map(|u| p[u as usize]);
                (b - a).cross(c - a)
            })
            .sum()
    }

    /// Whether every face round `v`, where it is now, faces the way of `up` and is no sliver.
    fn star_sound(&self, v: u32, up: DVec3) -> bool {
        let p = &self.mesh.positions;
        let (mut len2, mut edges) = (0.0, 0.0);
        for &t in &self.star[v as usize] {
            let [a, b, c] = self.mesh.triangles[t as usize].map(|u| p[u as usize]);
            len2 += (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
            edges += 3.0;
        }
        let least = DEGENERATE * len2 / edges;
        self.star[v as usize].iter().all(|&t| {
            let [a, b, c] = self.mesh.triangles[t as usize].map(|u| p[u as usize]);
            let n = (b - a).cross(c - a);
            n.length() > least && n.dot(up) > 0.0
        })
    }

    /// Moves the inside vertices of the ring of `v`, each as [`Self::try_move`] does, and keeps
    /// the moves only when they bring `v` within the bound; true when they do.
    fn move_ring(&mut self, v: u32) -> bool {
        let ring: Vec<u32> = self
            .ring(v)
            .into_iter()
            .filter(|&w| !self.rim[w as usize])
            .collect();
        let was: Vec<DVec3> = ring
            .iter()
            .map(|&w| self.mesh.positions[w as usize])
            .collect();
        let mut any = false;
        for &w in &ring {
            any |= self.try_move(w);
        }
        if any && self.excess(v) <= 0.0 {
            return true;
        }
        for (&w, p) in ring.iter().zip(was) {
            self.mesh.positions[w as usize] = p;
        }
        false
    }

    /// Moves `v` to the better of its two places (module doc) when that lowers the excess round
    /// it; true when it moved.
    fn try_move(&mut self, v: u32) -> bool {
        let ring = self.ring(v);
        if ring.is_empty() {
            return false;
        }
        let up = self.star_area(v);
        let Some(normal) = up.try_normalize() else {
            return false;
        };
        let pts: Vec<DVec3> = ring
            .iter()
            .map(|&u| self.mesh.positions[u as usize])
            .collect();
        let centroid = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        let here = self.mesh.positions[v as usize];
        let onto_plane = here - (here - centroid).dot(normal) * normal;
        let before = self.local_excess(v, &ring);
        let origin = self.input[v as usize];
        let mut best: Option<(f64, f64, DVec3)> = None;
        for to in [onto_plane, centroid] {
            let moved = to.distance(origin);
            if to == here || !to.is_finite() || moved > self.max_mm {
                continue;
            }
            self.mesh.positions[v as usize] = to;
            if self.star_sound(v, up) {
                let after = self.local_excess(v, &ring);
                let better = match best {
                    None => after < before,
                    Some((e, d, _)) => after < e || (after == e && moved < d),
                };
                if better {
                    best = Some((after, moved, to));
                }
            }
            self.mesh.positions[v as usize] = here;
        }
        match best {
            Some((_, _, to)) => {
                self.mesh.positions[v as usize] = to;
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_grid::grid_mesh;
    use crate::test_shapes::{star_shaped, turn};

    /// The reach at ±10 %: 2·asin(0.2 / 2.0).
    fn reach() -> f64 {
        2.0 * (0.2f64 / 2.0).asin()
    }

    /// A 6 × 6 flat grid of 10 mm cells in z = 0, node (3, 3) lifted `h` mm.
    fn spiked(h: f64) -> (TriMesh, usize) {
        let m = grid_mesh(6, 6, |i, j| {
            let z = if i == 3 && j == 3 { h } else { 0.0 };
            DVec3::new(10.0 * i as f64, 10.0 * j as f64, z)
        });
        (m, 3 * 7 + 3)
    }

    #[test]
    fn a_spike_on_a_plane_goes_back_onto_it_and_nothing_else_moves() {
        let (mut m, v) = spiked(30.0);
        let before = m.positions.clone();
        let r = despike(&mut m, reach(), 50.0).unwrap();
        assert_eq!(r.moved, vec![v as u32]);
        assert!(r.left.is_empty());
        assert!(m.positions[v].z.abs() < 1e-12, "z = {}", m.positions[v].z);
        // The plane projection: straight down, onto its place in the grid.
        assert!((m.positions[v] - DVec3::new(30.0, 30.0, 0.0)).length() < 1e-12);
        assert!((r.max_mm - 30.0).abs() < 1e-12);
        assert_eq!(r.max_at, Some((v as u32, before[v])));
        for (k, (p, q)) in m.positions.iter().zip(&before).enumerate() {
            if k != v {
                assert_eq!(p, q, "vertex {k} moved");
            }
        }
    }

    #[test]
    fn a_spike_beyond_the_largest_move_is_left_as_it_is() {
        let (mut m, v) = spiked(30.0);
        let before = m.clone();
        let r = despike(&mut m, reach(), 29.0).unwrap();
        assert!(r.moved.is_empty());
        assert_eq!(r.left, vec![v as u32]);
        assert_eq!(m, before);
    }

    #[test]
    fn a_sphere_has_nothing_beyond_reach_and_comes_back_bit_identical() {
        let mut m = star_shaped(3, turn(DVec3::Z, 0.0), |_| 100.0);
        let before = m.clone();
        let r = despike(&mut m, reach(), 2.0).unwrap();
        assert_eq!(r, Despiked::default());
        assert_eq!(m, before);
    }

    /// A fan of six faces round vertex 0, its ring a regular hexagon of radius 10 mm in z = 0
    /// (the outline: only the middle may move), the middle at `middle`.
    fn fan(middle: DVec3) -> TriMesh {
        let mut p = vec![middle];
        p.extend((0..6).map(|k| {
            let a = std::f64::consts::FRAC_PI_3 * k as f64;
            DVec3::new(10.0 * a.cos(), 10.0 * a.sin(), 0.0)
        }));
        let t = (0..6u32).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        TriMesh::new(p, t)
    }

    #[test]
    fn a_repair_that_would_fold_a_face_is_refused() {
        // The spike leans 12 mm along x, out over its ring (which reaches 10 mm): straight down
        // onto the plane it would lie outside its ring, a face folded over. The ring's centroid
        // is 32.3 mm away, beyond the largest move of 31 mm; the plane is within it (30 mm) but
        // folds, so nothing moves.
        let mut m = fan(DVec3::new(12.0, 0.0, 30.0));
        let before = m.clone();
        let r = despike(&mut m, reach(), 31.0).unwrap();
        assert!(r.moved.is_empty(), "moved {:?}", r.moved);
        assert_eq!(r.left, vec![0]);
        assert_eq!(m, before);
        // Given room, the centroid is taken: the middle of the hexagon, nothing folded.
        let r = despike(&mut m, reach(), 40.0).unwrap();
        assert_eq!(r.moved, vec![0]);
        assert!(r.left.is_empty());
        assert!(m.positions[0].length() < 1e-12);
        assert!((r.max_mm - (12f64.powi(2) + 30f64.powi(2)).sqrt()).abs() < 1e-12);
        for t in &m.triangles {
            let [a, b, c] = t.map(|u| m.positions[u as usize]);
            assert!((b - a).cross(c - a).z > 0.0);
        }
    }

    #[test]
    fn boundary_vertices_are_never_moved() {
        // The corner node lifted: beyond any bound measured against a full turn, but on the
        // outline, where no defect is measured.
        let mut m = grid_mesh(4, 4, |i, j| {
            let z = if i == 0 && j == 0 { 30.0 } else { 0.0 };
            DVec3::new(10.0 * i as f64, 10.0 * j as f64, z)
        });
        let before = m.clone();
        let r = despike(&mut m, reach(), 50.0).unwrap();
        assert_eq!(r, Despiked::default());
        assert_eq!(m, before);
    }
}
