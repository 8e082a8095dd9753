//! Discrete differential operators on a triangle mesh: corner angles, cotangent weights,
//! angle defects, and Laplace problems with Dirichlet data (the building block of Tutte,
//! harmonic extension, the Yamabe solve and the ARAP global step).

use crate::internal::InternalError;
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{Topology, TriMesh};

use crate::FlattenError;
use crate::sparse::{SpdSolver, SymPattern, SymTriplets};
use rayon::prelude::*;

/// Interior angle at each corner of each triangle (radians), corner `k` at `triangles[t][k]`.
pub fn corner_angles(mesh: &TriMesh) -> Vec<[f64; 3]> {
    mesh.triangles
        .iter()
        .enumerate()
        .map(|(t, _)| {
            let p = mesh.corners(t);
            std::array::from_fn(|k| {
                let a = p[(k + 1) % 3] - p[k];
                let b = p[(k + 2) % 3] - p[k];
                // atan2(|a×b|, a·b) is accurate for all angles, unlike acos of the cosine.
                a.cross(b).length().atan2(a.dot(b))
            })
        })
        .collect()
}

/// Interior angle at each corner of each triangle of the flat map `uv` (radians), as
/// [`corner_angles`] gives them on the surface.
pub fn flat_corner_angles(triangles: &[[u32; 3]], uv: &[DVec2]) -> Vec<[f64; 3]> {
    triangles
        .iter()
        .map(|tri| {
            let p = tri.map(|v| uv[v as usize]);
            std::array::from_fn(|k| {
                let a = p[(k + 1) % 3] - p[k];
                let b = p[(k + 2) % 3] - p[k];
                a.perp_dot(b).abs().atan2(a.dot(b))
            })
        })
        .collect()
}

/// Cotangent of the angle at each corner: `cot[t][k]` weights the edge opposite corner `k`,
/// i.e. the edge `(triangles[t][k+1], triangles[t][k+2])`. Computed in parallel, each
/// triangle's by itself ([`triangle_cotans`]): the same bits with any number of threads.
pub fn corner_cotans(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    triangles
        .par_iter()
        .map(|&tri| triangle_cotans(positions, tri))
        .collect()
}

/// The cotangents of the corners of one triangle, as [`corner_cotans`] gives them.
pub fn triangle_cotans(positions: &[DVec3], tri: [u32; 3]) -> [f64; 3] {
    let p = tri.map(|v| positions[v as usize]);
    std::array::from_fn(|k| {
        let a = p[(k + 1) % 3] - p[k];
        let b = p[(k + 2) % 3] - p[k];
        a.dot(b) / a.cross(b).length()
    })
}

/// Which vertices lie on the boundary (`true`) of a mesh with topology `topo`.
pub fn boundary_mask(n: usize, topo: &Topology) -> Vec<bool> {
    let mut b = vec![false; n];
    for lp in &topo.boundary_loops {
        for &v in lp {
            b[v as usize] = true;
        }
    }
    b
}

/// The triangles at each vertex, in increasing index, in compressed form: those of vertex `v`
/// are `tris[ptr[v]..ptr[v + 1]]` (a triangle that names a vertex twice is listed once).
pub fn vertex_triangles(n: usize, triangles: &[[u32; 3]]) -> (Vec<usize>, Vec<u32>) {
    let mut ptr = vec![0usize; n + 1];
    let distinct = |tri: &[u32; 3], k: usize| tri[..k].iter().all(|&w| w != tri[k]);
    for tri in triangles {
        for k in 0..3 {
            if distinct(tri, k) {
                ptr[tri[k] as usize + 1] += 1;
            }
        }
    }
    for v in 0..n {
        ptr[v + 1] += ptr[v];
    }
    let mut tris = vec![0u32; ptr[n]];
    // Filled by each vertex's offset, moved along and then back.
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            if distinct(tri, k) {
                let v = tri[k] as usize;
                tris[ptr[v]] = t as u32;
                ptr[v] += 1;
            }
        }
    }
    for v in (1..=n).rev() {
        ptr[v] = ptr[v - 1];
    }
    ptr[0] = 0;
    (ptr, tris)
}

/// The terms `add(i, i, w)`, `add(j, j, w)`, `add(i, j, −w)` of the Laplacian energy
/// `w (x_i − x_j)²/2`, in this order (the order their sums are made in).
pub fn laplacian_terms(i: usize, j: usize, w: f64, add: &mut impl FnMut(usize, usize, f64)) {
    add(i, i, w);
    add(j, j, w);
    add(i, j, -w);
}

/// Which vertices are used by at least one triangle.
pub fn used_mask(mesh: &TriMesh) -> Vec<bool> {
    let mut u = vec![false; mesh.positions.len()];
    for tri in &mesh.triangles {
        for &v in tri {
            u[v as usize] = true;
        }
    }
    u
}

/// Angle sum at each vertex (radians).
pub fn angle_sums(mesh: &TriMesh, angles: &[[f64; 3]]) -> Vec<f64> {
    let mut s = vec![0.0; mesh.positions.len()];
    for (tri, a) in mesh.triangles.iter().zip(angles) {
        for k in 0..3 {
            s[tri[k] as usize] += a[k];
        }
    }
    s
}

/// Twice the signed area of the 2D triangle `(a, b, c)` (positive when counter-clockwise).
pub fn orient2(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Index of the first triangle whose image in `uv` is flipped or degenerate, if any.
pub fn first_flip(triangles: &[[u32; 3]], uv: &[DVec2]) -> Option<usize> {
    triangles.iter().position(|t| {
        let o = orient2(uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
        o.is_nan() || o <= 0.0
    })
}

/// Number of triangles whose image in `uv` is flipped or degenerate (counted in parallel).
pub fn count_flips(triangles: &[[u32; 3]], uv: &[DVec2]) -> usize {
    triangles
        .par_iter()
        .filter(|t| {
            let o = orient2(uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            o.is_nan() || o <= 0.0
        })
        .count()
}

/// Signed area of the image of the mesh in `uv`.
pub fn uv_area(triangles: &[[u32; 3]], uv: &[DVec2]) -> f64 {
    triangles
        .iter()
        .map(|t| 0.5 * orient2(uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]))
        .sum()
}

/// A quadratic energy `½ xᵀ Q x − bᵀ x` over degrees of freedom, some of which are held at
/// given values. [`QuadraticBuilder`] accumulates `Q`; the free block `Q_ff` must be positive
/// definite. Solving gives `Q_ff x_f = b_f − Q_fc x_c`.
#[derive(Debug)]
pub struct Reduced {
    /// Dof of each free unknown.
    free: Vec<u32>,
    /// `(free row, fixed dof, Q entry)`: couplings moved to the right-hand side.
    coupling: Vec<(usize, u32, f64)>,
    solver: SpdSolver,
}

/// Accumulates the symmetric matrix `Q` of a [`Reduced`] problem.
#[derive(Debug)]
pub struct QuadraticBuilder {
    free_index: Vec<usize>,
    free: Vec<u32>,
    coupling: Vec<(usize, u32, f64)>,
    /// Off-diagonal entries of `Q_ff`.
    triplets: SymTriplets,
    /// Diagonal of `Q_ff`, summed as it comes: a third of the entries of a Laplacian, which
    /// would otherwise each be a triplet.
    diag: Vec<f64>,
}

impl QuadraticBuilder {
    /// A builder over `fixed.len()` dofs; `fixed[i]` marks the dofs with given values;
    /// `capacity` off-diagonal entries are reserved.
    pub fn new(fixed: &[bool], capacity: usize) -> Self {
        let mut free_index = vec![usize::MAX; fixed.len()];
        let mut free = Vec::new();
        for (i, &f) in fixed.iter().enumerate() {
            if !f {
                free_index[i] = free.len();
                free.push(i as u32);
            }
        }
        let triplets = SymTriplets::with_capacity(free.len(), capacity + free.len());
        Self {
            diag: vec![0.0; free.len()],
            free_index,
            free,
            coupling: Vec::new(),
            triplets,
        }
    }

    /// Adds `v` to `Q[i][j]` and, when `i ≠ j`, to `Q[j][i]`.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        match (self.free_index[i], self.free_index[j]) {
            (usize::MAX, usize::MAX) => {}
            (fi, usize::MAX) => self.coupling.push((fi, j as u32, v)),
            (usize::MAX, fj) => self.coupling.push((fj, i as u32, v)),
            (fi, fj) if fi == fj => self.diag[fi] += v,
            (fi, fj) => self.triplets.add(fi, fj, v),
        }
    }

    /// Adds the Laplacian term `w (x_i − x_j)²/2` to the energy.
    pub fn add_edge(&mut self, i: usize, j: usize, w: f64) {
        laplacian_terms(i, j, w, &mut |i, j, v| self.add(i, j, v));
    }

    /// `Q_ff` in compressed-column form (lower triangle), its diagonal added last, as
    /// [`QuadraticBuilder::build`] factors it.
    #[cfg(test)]
    pub fn into_triplet_matrix(
        mut self,
        stage: &'static str,
    ) -> Result<(SymPattern, Vec<f64>), FlattenError> {
        for (i, &d) in self.diag.iter().enumerate() {
            self.triplets.add(i, i, d);
        }
        SymPattern::compress(self.triplets, stage)
    }

    /// Factors `Q_ff`.
    pub fn build(mut self, stage: &'static str) -> Result<Reduced, FlattenError> {
        for (i, &d) in self.diag.iter().enumerate() {
            self.triplets.add(i, i, d);
        }
        if self.free.is_empty() {
            return Err(FlattenError::Internal(InternalError::EveryUnknownFixed {
                stage,
            }));
        }
        // The nodes of the ordering are the dofs, the fixed ones too.
        let n_nodes = self.free_index.len();
        // Done with before the factorisation, the memory peak.
        drop(std::mem::take(&mut self.diag));
        drop(std::mem::take(&mut self.free_index));
        let node_of = self.free.clone();
        let (pattern, values) = SymPattern::compress(self.triplets, stage)?;
        let pattern = pattern.with_nodes(node_of, n_nodes)?;
        let mut solver = SpdSolver::new(&pattern, stage)?;
        let values = solver.gather(&pattern, &values)?;
        drop(pattern);
        solver.factor(values)?;
        Ok(Reduced {
            free: self.free,
            coupling: self.coupling,
            solver,
        })
    }
}

impl Reduced {
    /// Minimizes for several fields at once: `values[c]` holds the values of field `c` at the
    /// fixed dofs (free entries are overwritten with the solution); `source[c]`, when given, is
    /// the linear term `b` (read at free dofs).
    pub fn solve(
        &self,
        values: &mut [Vec<f64>],
        source: Option<&[Vec<f64>]>,
    ) -> Result<(), FlattenError> {
        let m = self.free.len();
        let k = values.len();
        let mut rhs = vec![0.0; m * k];
        for c in 0..k {
            let col = &mut rhs[c * m..(c + 1) * m];
            if let Some(s) = source {
                for (i, &v) in self.free.iter().enumerate() {
                    col[i] = s[c][v as usize];
                }
            }
            for &(i, v, q) in &self.coupling {
                col[i] -= q * values[c][v as usize];
            }
        }
        self.solver.solve_many_in_place(&mut rhs, k)?;
        for c in 0..k {
            for (i, &v) in self.free.iter().enumerate() {
                values[c][v as usize] = rhs[c * m + i];
            }
        }
        Ok(())
    }
}

/// The Laplace problem `Σ w (x_a − x_b)²/2 → min` with the weights given per triangle corner
/// (the weight of the edge opposite the corner, as for cotangent weights) and the vertices
/// `fixed` held at given values.
pub fn laplace(
    triangles: &[[u32; 3]],
    corner_weights: &[[f64; 3]],
    fixed: &[bool],
    stage: &'static str,
) -> Result<Reduced, FlattenError> {
    let mut b = QuadraticBuilder::new(fixed, 3 * triangles.len());
    for (tri, w) in triangles.iter().zip(corner_weights) {
        for k in 0..3 {
            b.add_edge(tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize, w[k]);
        }
    }
    b.build(stage)
}

/// Moves `uv` by the rigid motion (rotation and translation, no mirror, no scale) that best fits
/// the pinned vertices to their positions in the least-squares sense. Returns the largest
/// remaining distance of a pinned vertex from its pin (0 for at most one pin).
pub fn fit_rigid_to_pins(uv: &mut [DVec2], pins: &[crate::Pin]) -> f64 {
    if pins.is_empty() {
        return 0.0;
    }
    let k = pins.len() as f64;
    let cs = pins.iter().map(|p| uv[p.vertex as usize]).sum::<DVec2>() / k;
    let cd = pins.iter().map(|p| p.position).sum::<DVec2>() / k;
    let (mut c, mut s) = (0.0, 0.0);
    for p in pins {
        let (a, b) = (uv[p.vertex as usize] - cs, p.position - cd);
        c += a.dot(b);
        s += a.perp_dot(b);
    }
    let rot = if pins.len() >= 2 && (c != 0.0 || s != 0.0) {
        DVec2::from_angle(s.atan2(c))
    } else {
        DVec2::X
    };
    uv.iter_mut().for_each(|q| *q = rot.rotate(*q - cs) + cd);
    pins.iter()
        .map(|p| (uv[p.vertex as usize] - p.position).length())
        .fold(0.0, f64::max)
}

/// Area-weighted mean of Duncan's δ2 of the map `uv` (∞ if a triangle is flipped or degenerate).
pub fn mean_delta2(mesh: &TriMesh, uv: &[DVec2]) -> f64 {
    let mut s = 0.0;
    for t in 0..mesh.triangles.len() {
        let tri = mesh.triangles[t];
        match flatcut_mesh::face_distortion(mesh.corners(t), tri.map(|v| uv[v as usize])) {
            Some(d) if !d.flipped() => s += mesh.triangle_area(t) * d.delta2(),
            _ => return f64::INFINITY,
        }
    }
    s / mesh.area()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_triangles_at_each_vertex_are_listed_once_in_increasing_order() {
        // Two triangles sharing the edge 1–2, a third naming vertex 3 twice, vertex 5 unused.
        let tris = [[0, 1, 2], [2, 1, 3], [3, 4, 3]];
        let (ptr, at) = vertex_triangles(6, &tris);
        let of = |v: usize| &at[ptr[v]..ptr[v + 1]];
        assert_eq!(of(0), &[0]);
        assert_eq!(of(1), &[0, 1]);
        assert_eq!(of(2), &[0, 1]);
        assert_eq!(of(3), &[1, 2]);
        assert_eq!(of(4), &[2]);
        assert!(of(5).is_empty());
    }

    #[test]
    fn angles_and_cotans_of_a_right_triangle() {
        let m = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, 2.0, 0.0)],
            vec![[0, 1, 2]],
        );
        let a = corner_angles(&m)[0];
        assert!((a[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((a.iter().sum::<f64>() - std::f64::consts::PI).abs() < 1e-15);
        let c = corner_cotans(&m.positions, &m.triangles)[0];
        assert!(c[0].abs() < 1e-15);
        assert!((c[1] - 0.5).abs() < 1e-14 && (c[2] - 2.0).abs() < 1e-14);
    }
}
