//! Least-squares conformal maps (Lévy et al. 2002) with a free boundary, at true scale.
//!
//! The energy is the conformal energy `E_C = Σ_T A_T (½‖J‖²_F − det J) = E_Dirichlet − Area`
//! (Desbrun et al. 2002 / Mullen et al. 2008 form of LSCM: per triangle it equals
//! `½ A_T (σ1 − σ2)²`, zero exactly for a similarity). It is a positive semi-definite quadratic
//! form whose null space is the similarities of the plane, so two pinned vertices give a unique
//! minimizer, independent (up to a similarity) of which two vertices are pinned.
//!
//! **Scale.** Without user pins the two farthest-apart boundary vertices are pinned, and the
//! result is then scaled uniformly so that **its total area equals the 3D area** (conformal maps
//! are scale-free; area matching is the least-squares choice for `log(σ1σ2)` and keeps a
//! planar input exactly at scale). With one user pin the same map is translated onto the pin;
//! with two or more user pins the pins are hard constraints and fix the scale themselves.

use crate::beside::beside;
use crate::internal::InternalError;
use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use crate::ops::{laplacian_terms, triangle_cotans, used_mask, uv_area, vertex_triangles};
use crate::ordering::{Graph, shared_dissection_of};
use crate::sparse::hermitian::HermitianSolver;
use crate::sparse::{Ordering, SymPattern};
use crate::{FlattenError, FlattenInfo, Flattening, Method, Pin, Timings};
use faer::c64;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Solves LSCM on the disk `mesh` (topology from `check_disk`) with the (validated) `pins`.
pub fn lscm(mesh: &TriMesh, topo: &Topology, pins: &[Pin]) -> Result<Flattening, FlattenError> {
    let (uv, timings) = conformal_map(mesh, topo, pins)?;
    let mut warnings = Vec::new();
    let flips = crate::ops::count_flips(&mesh.triangles, &uv);
    if flips > 0 {
        warnings.push(format!(
            "lscm: {flips} triangle(s) flipped (first: {}); the isometric method is flip-free",
            crate::ops::first_flip(&mesh.triangles, &uv).unwrap_or(0)
        ));
    }
    let energy = conformal_energy(mesh, &uv) / mesh.area();
    Ok(Flattening {
        uv,
        info: FlattenInfo {
            iterations: 1,
            final_energy: energy,
            warnings,
            timings,
            ..Default::default()
        },
    })
}

/// The map of [`lscm`] and where its time went, without the report of its flips and energy
/// (a start map's caller checks its own, and needs no energy: a pass over every face).
pub fn conformal_map(
    mesh: &TriMesh,
    topo: &Topology,
    pins: &[Pin],
) -> Result<(Vec<DVec2>, Timings), FlattenError> {
    let hard: Vec<(u32, DVec2)> = if pins.len() >= 2 {
        pins.iter().map(|p| (p.vertex, p.position)).collect()
    } else {
        let (a, b) = farthest_boundary_pair(mesh, topo)?;
        let d = (mesh.positions[b as usize] - mesh.positions[a as usize]).length();
        vec![(a, DVec2::ZERO), (b, DVec2::new(d, 0.0))]
    };
    let (mut uv, timings) = solve_pinned_timed(mesh, topo, &hard)?;
    if pins.len() < 2 {
        let a2 = uv_area(&mesh.triangles, &uv);
        if a2.is_nan() || a2 <= 0.0 || a2.is_infinite() {
            return Err(FlattenError::NoConvergence {
                method: Method::Lscm,
                reason: format!("the conformal map has non-positive total area {a2:.3e} mm²"),
            });
        }
        let s = (mesh.area() / a2).sqrt();
        uv.iter_mut().for_each(|p| *p *= s);
        if let Some(p) = pins.first() {
            let shift = p.position - uv[p.vertex as usize];
            uv.iter_mut().for_each(|q| *q += shift);
        }
    }
    Ok((uv, timings))
}

/// The LSCM minimizer with the vertices of `hard` held at their positions (at least two
/// distinct vertices). Vertices used by no triangle are put at the origin.
///
/// The area term is assembled from the boundary loops only (the interior edges' contributions
/// cancel exactly), which keeps the x–y coupling off the interior and halves the matrix.
pub fn solve_pinned(
    mesh: &TriMesh,
    topo: &Topology,
    hard: &[(u32, DVec2)],
) -> Result<Vec<DVec2>, FlattenError> {
    solve_pinned_timed(mesh, topo, hard).map(|(uv, _)| uv)
}

/// [`solve_pinned`], with where its time went: the ordering and symbolic analysis, the assembly
/// of the matrix beyond it (cotangents, the Dirichlet and boundary-area terms), the numeric
/// factorisation and the solve, for `flatten --timings`.
///
/// The energy's real matrix over the u and v of the vertices is `[[L, M], [Mᵀ, L]]` (`L` the
/// Dirichlet energy of each coordinate, `M` the boundary's signed area between u and v,
/// antisymmetric): the realification of the Hermitian `H = L − i M` acting on `z = u + i v`.
/// The map is solved as `H z = b`, one complex unknown per free vertex
/// ([`HermitianSolver`]): half the unknowns of the real system to order and analyse, and a
/// factor with fewer values and flops (a million-face toe's: 29.3M complex values against 73.6M
/// real, 1.4 CPU s against 2.2). Every pin holds both coordinates of its vertex, so every
/// unknown is complex.
///
/// The pattern of the matrix depends only on the mesh's graph and the pinned vertices, never on
/// the coordinates: this thread makes it and analyses it (its order and symbolic
/// factorisation, [`analyse`]) while another one assembles the values ([`ConformalValues`]),
/// which are then put straight into the factor's order. The factor, and the map, are the same
/// bits with any number of threads. Everything the map keeps or frees is made on this thread
/// (the other one fills it): the Newton solve a start map leads to reuses this thread's freed
/// memory, not another thread's.
fn solve_pinned_timed(
    mesh: &TriMesh,
    topo: &Topology,
    hard: &[(u32, DVec2)],
) -> Result<(Vec<DVec2>, Timings), FlattenError> {
    let started = Instant::now();
    let n = mesh.positions.len();
    let free_index = free_vertices(mesh, hard);
    if free_index.iter().all(|&k| k == FIXED) {
        return Err(FlattenError::Internal(InternalError::EveryUnknownFixed {
            stage: "lscm",
        }));
    }
    let area = AreaTerms::of(topo);
    // The mesh's graph, pins included (the Newton solve this map may start orders the same
    // graph, and reuses the order), made on a thread of its own, as the order is: the graph
    // outlives the map in the order's memo, and the room its making frees (28 MB at a million
    // faces) is not left among this thread's memory.
    let (graph, (ptr, tris)) = beside(
        || Arc::new(Graph::of_triangles(n, &mesh.triangles)),
        || vertex_triangles(n, &mesh.triangles),
    );
    // Each triangle's cotangents where they are needed (a triangle's thrice, not held: 24 MB at
    // a million faces).
    let cot = |t: usize| triangle_cotans(&mesh.positions, mesh.triangles[t]);
    let mut values = ConformalValues::zeroed(&graph);
    let ((), (analysis, analysing)) = beside(
        || values.fill(&mesh.triangles, &graph, (&ptr, &tris), cot),
        || {
            let started = Instant::now();
            let analysis = analyse(&graph, &free_index, &area);
            (analysis, started.elapsed())
        },
    );
    drop((ptr, tris));
    let (mut solver, free) = analysis?;
    let matrix = solver.values_of(|i, j| values.entry(&graph, &area, free[i], free[j]));
    // The held vertices where they are held (those no triangle uses at the origin), and the
    // right-hand side: minus the couplings of the free vertices to them.
    let mut uv = vec![DVec2::ZERO; n];
    for &(v, p) in hard {
        uv[v as usize] = p;
    }
    let mut z = vec![c64::new(0.0, 0.0); free.len()];
    for held in (0..n as u32).filter(|&v| free_index[v as usize] == FIXED) {
        let at = c64::new(uv[held as usize].x, uv[held as usize].y);
        for &a in graph.neighbours(held) {
            let k = free_index[a as usize];
            if k != FIXED {
                z[k as usize] -= values.entry(&graph, &area, a, held) * at;
            }
        }
    }
    drop((values, graph));
    let built = started.elapsed();
    solver.factor(matrix)?;
    solver.solve_in_place(&mut z)?;
    for (&v, z) in free.iter().zip(&z) {
        uv[v as usize] = DVec2::new(z.re, z.im);
    }
    // The assembly ran beside the analysis: what it took beyond it, the set-up, the values'
    // gathering and the right-hand side are the assembly's time.
    let timings = Timings {
        assembly: built.saturating_sub(analysing),
        ordering: analysing,
        ..solver.timings()
    };
    Ok((uv, timings))
}

/// The number of an unknown held at its value: a vertex that is not one of the map's unknowns.
const FIXED: u32 = u32::MAX;

/// The unknown of each vertex, the free vertices numbered in increasing order, [`FIXED`] for a
/// vertex in `hard` and for one no triangle uses.
fn free_vertices(mesh: &TriMesh, hard: &[(u32, DVec2)]) -> Vec<u32> {
    let mut free = used_mask(mesh);
    for &(v, _) in hard {
        free[v as usize] = false;
    }
    let mut next = 0;
    free.iter()
        .map(|&f| {
            if f {
                next += 1;
                next - 1
            } else {
                FIXED
            }
        })
        .collect()
}

/// The pattern of the free block of the conformal energy's Hermitian matrix and its solver
/// (ordering and symbolic factorisation, no values), with the vertex of each of its unknowns.
/// Nested dissection orders the mesh's `graph` ([`shared_dissection_of`]), which the Newton
/// solve a start map leads to shares.
fn analyse(
    graph: &Arc<Graph>,
    free_index: &[u32],
    area: &AreaTerms,
) -> Result<(HermitianSolver, Vec<u32>), FlattenError> {
    let n = graph.len();
    let (order, pattern) = beside(
        || {
            (Ordering::for_nodes(n) == Ordering::NestedDissection)
                .then(|| shared_dissection_of(Arc::clone(graph)))
        },
        || conformal_pattern(graph, free_index, area),
    );
    let (pattern, free) = pattern?;
    let mut pattern = pattern.with_nodes(free.clone(), n)?;
    if let Some(d) = order {
        pattern = pattern.with_node_order(d)?;
    }
    let solver = HermitianSolver::new(&pattern, "lscm")?;
    Ok((solver, free))
}

/// The lower triangle of the free block of the conformal energy's Hermitian matrix, made from
/// the mesh's graph: the diagonal and every edge between two free vertices (the Dirichlet
/// energy couples every edge, the area the boundary edges, which are edges of the graph). With
/// the vertex of each unknown (unknowns numbered by `free_index`).
fn conformal_pattern(
    graph: &Graph,
    free_index: &[u32],
    area: &AreaTerms,
) -> Result<(SymPattern, Vec<u32>), FlattenError> {
    // Every boundary edge is an edge of the graph, or its term would be dropped.
    if let Some(&((x, y), _)) = area
        .terms
        .iter()
        .find(|((x, y), _)| graph.neighbours(*x).binary_search(y).is_err())
    {
        return Err(FlattenError::Solver {
            stage: "lscm",
            reason: format!("the boundary edge {x}–{y} is not an edge of the mesh's triangles"),
        });
    }
    let free: Vec<u32> = (0..free_index.len() as u32)
        .filter(|&v| free_index[v as usize] != FIXED)
        .collect();
    let mut col_ptr = Vec::with_capacity(free.len() + 1);
    let mut row_idx = Vec::with_capacity(free.len() + graph.n_neighbours() / 2);
    col_ptr.push(0);
    for &c in &free {
        row_idx.push(free_index[c as usize] as usize);
        let below = graph.neighbours(c).iter().filter(|&&a| a > c);
        row_idx.extend(
            below
                .map(|&a| free_index[a as usize])
                .filter(|&k| k != FIXED)
                .map(|k| k as usize),
        );
        col_ptr.push(row_idx.len());
    }
    let pattern = SymPattern::from_lower_csc(free.len(), col_ptr, row_idx, "lscm")?;
    Ok((pattern, free))
}

/// Adds the conformal energy's terms to `add` (u and v of vertex `v` are dofs 2v and 2v + 1), in
/// the order their sums are made: the cotangent Dirichlet energy of both coordinates of each
/// triangle whose vertices `at` accepts, then minus the signed area of each boundary edge whose
/// ends it accepts (the boundary loops of `topo` give the area alone: the interior edges'
/// contributions cancel exactly). `cot(t)` gives the corner cotangents of triangle `t`
/// ([`triangle_cotans`]). The matrix made of these triplets is the one [`ConformalValues`] and
/// [`AreaTerms`] give entry by entry (the tests' reference).
#[cfg(test)]
fn conformal_terms(
    mesh: &TriMesh,
    topo: &Topology,
    cot: impl Fn(usize) -> [f64; 3],
    at: impl Fn(&[u32]) -> bool,
    add: &mut impl FnMut(usize, usize, f64),
) {
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if at(tri) {
            dirichlet_terms(*tri, cot(t), add);
        }
    }
    for lp in &topo.boundary_loops {
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            if at(&[a, b]) {
                area_terms(a, b, add);
            }
        }
    }
}

/// The Dirichlet energy ¼ Σ cot (u_a − u_b)² = ½ Σ (cot/2)(u_a − u_b)² of both coordinates on
/// one triangle with corner cotangents `cot` ([`laplacian_terms`] of each edge, u then v).
fn dirichlet_terms(tri: [u32; 3], cot: [f64; 3], add: &mut impl FnMut(usize, usize, f64)) {
    for k in 0..3 {
        let (a, b) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
        let w = 0.5 * cot[k];
        laplacian_terms(2 * a, 2 * b, w, add);
        laplacian_terms(2 * a + 1, 2 * b + 1, w, add);
    }
}

/// Minus the signed area ½ (x_a y_b − x_b y_a) of the boundary edge a → b.
fn area_terms(a: u32, b: u32, add: &mut impl FnMut(usize, usize, f64)) {
    let (a, b) = (a as usize, b as usize);
    add(2 * a, 2 * b + 1, -0.5);
    add(2 * b, 2 * a + 1, 0.5);
}

/// The u–v entries of the conformal energy's matrix: `((x, y), q)` for the entry between u of
/// vertex `x` and v of vertex `y`, sorted, the terms at one entry summed in their order.
struct AreaTerms {
    terms: Vec<((u32, u32), f64)>,
}

impl AreaTerms {
    fn of(topo: &Topology) -> Self {
        let mut terms = Vec::new();
        for lp in &topo.boundary_loops {
            for i in 0..lp.len() {
                area_terms(lp[i], lp[(i + 1) % lp.len()], &mut |i, j, q| {
                    // Each term is between a u (even dof) and a v (odd).
                    let (u, v) = if i.is_multiple_of(2) { (i, j) } else { (j, i) };
                    terms.push(((u as u32 / 2, v as u32 / 2), q));
                });
            }
        }
        // Stable: the terms at one entry stay in their order.
        terms.sort_by_key(|&(at, _)| at);
        let mut merged: Vec<((u32, u32), f64)> = Vec::with_capacity(terms.len());
        for (at, q) in terms {
            match merged.last_mut() {
                Some((last, s)) if *last == at => *s += q,
                _ => merged.push((at, q)),
            }
        }
        Self { terms: merged }
    }

    /// The entry between u of `x` and v of `y`, if a boundary edge joins them.
    fn get(&self, x: u32, y: u32) -> Option<f64> {
        let k = self
            .terms
            .binary_search_by_key(&(x, y), |&(at, _)| at)
            .ok()?;
        Some(self.terms[k].1)
    }
}

/// The Dirichlet part of the conformal energy's matrix, vertex by vertex (u's and v's are the
/// same): the diagonal, and the entry of each edge beside the mesh's graph's neighbour lists.
/// Each entry is summed as the triplets of [`conformal_terms`] are (in the order of the
/// triangles), so the matrix is the same bits; the vertices are summed in parallel.
struct ConformalValues {
    diag: Vec<f64>,
    /// The entry of vertex `v` and its `k`-th neighbour at `graph.first_neighbour(v) + k`.
    edge: Vec<f64>,
}

/// Vertices per task of [`ConformalValues::fill`].
const VALUES_BLOCK: usize = 4096;

impl ConformalValues {
    /// Room for the entries of the mesh with `graph`, zero.
    fn zeroed(graph: &Graph) -> Self {
        Self {
            diag: vec![0.0; graph.len()],
            edge: vec![0.0; graph.n_neighbours()],
        }
    }

    /// The entries of the mesh with `triangles`, its `graph`, the triangles at each vertex
    /// ([`vertex_triangles`]) and the corner cotangents of each (`cot`), blocks of vertices in
    /// parallel.
    fn fill(
        &mut self,
        triangles: &[[u32; 3]],
        graph: &Graph,
        (ptr, tris): (&[usize], &[u32]),
        cot: impl Fn(usize) -> [f64; 3] + Sync,
    ) {
        let n = graph.len();
        let mut blocks = Vec::with_capacity(n.div_ceil(VALUES_BLOCK));
        let (mut diag, mut edge) = (self.diag.as_mut_slice(), self.edge.as_mut_slice());
        for first in (0..n).step_by(VALUES_BLOCK) {
            let end = (first + VALUES_BLOCK).min(n);
            let entries = graph.first_neighbour(end as u32) - graph.first_neighbour(first as u32);
            let (d, d_rest) = std::mem::take(&mut diag).split_at_mut(end - first);
            let (e, e_rest) = std::mem::take(&mut edge).split_at_mut(entries);
            blocks.push((first..end, d, e));
            (diag, edge) = (d_rest, e_rest);
        }
        blocks.into_par_iter().for_each(|(vertices, diag, edge)| {
            let base = graph.first_neighbour(vertices.start as u32);
            let mut sums: Vec<Option<f64>> = Vec::new();
            for v in vertices.clone() {
                let nb = graph.neighbours(v as u32);
                sums.clear();
                sums.resize(nb.len(), None);
                let mut d = 0.0;
                for &t in &tris[ptr[v]..ptr[v + 1]] {
                    let t = t as usize;
                    dirichlet_terms(triangles[t], cot(t), &mut |i, j, w| {
                        // u's terms: v's are the same.
                        if i % 2 != 0 || j % 2 != 0 {
                            return;
                        }
                        let (a, b) = (i / 2, j / 2);
                        if a == v && b == v {
                            d += w;
                        } else if a == v || b == v {
                            let other = (a + b - v) as u32;
                            if let Ok(k) = nb.binary_search(&other) {
                                // The first term as it is, as a sum of triplets starts.
                                sums[k] = Some(sums[k].map_or(w, |s| s + w));
                            }
                        }
                    });
                }
                diag[v - vertices.start] = d;
                let at = graph.first_neighbour(v as u32) - base;
                for (e, s) in edge[at..at + nb.len()].iter_mut().zip(&sums) {
                    *e = s.unwrap_or(0.0);
                }
            }
        });
    }

    /// The Hermitian matrix's entry in the row of vertex `a` and the column of vertex `b`:
    /// `L − i M` ([`solve_pinned_timed`]), `M` the area's entry between u of `a` and v of `b`
    /// ([`AreaTerms`]). NaN, which the factorisation refuses, for two vertices no edge joins.
    fn entry(&self, graph: &Graph, area: &AreaTerms, a: u32, b: u32) -> c64 {
        if a == b {
            return c64::new(self.diag[a as usize], 0.0);
        }
        let re = match graph.neighbours(a).binary_search(&b) {
            Ok(k) => self.edge[graph.first_neighbour(a) + k],
            Err(_) => f64::NAN,
        };
        c64::new(re, area.get(a, b).map_or(0.0, |m| -m))
    }
}

/// Triangles per block of the energy's parallel sum: fixed, so the partial sums, and the
/// total's bits, are the same with any number of threads.
const ENERGY_BLOCK: usize = 4096;

/// `Σ_T A_T (½‖J‖² − det J) = Σ_T ½ A_T (σ1 − σ2)²` of the map `uv`: summed block by block in
/// parallel, the blocks' sums added in order.
pub fn conformal_energy(mesh: &TriMesh, uv: &[DVec2]) -> f64 {
    let term = |t: usize| {
        let tri = mesh.triangles[t];
        let d = flatcut_mesh::face_distortion(mesh.corners(t), tri.map(|v| uv[v as usize]))?;
        let s2 = if d.det < 0.0 { -d.sigma2 } else { d.sigma2 };
        Some(0.5 * mesh.triangle_area(t) * (d.sigma1 - s2).powi(2))
    };
    let blocks = mesh.triangles.len().div_ceil(ENERGY_BLOCK);
    let partial: Vec<f64> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            let end = ((b + 1) * ENERGY_BLOCK).min(mesh.triangles.len());
            (b * ENERGY_BLOCK..end).filter_map(term).sum()
        })
        .collect();
    partial.iter().sum()
}

/// Two boundary vertices far apart (the double sweep: the farthest from the first boundary
/// vertex, then the farthest from that one), distinct.
pub fn farthest_boundary_pair(mesh: &TriMesh, topo: &Topology) -> Result<(u32, u32), FlattenError> {
    let lp = topo
        .boundary_loops
        .first()
        .ok_or(FlattenError::Internal(InternalError::LscmNoBoundary))?;
    let far = |from: u32| {
        let p = mesh.positions[from as usize];
        let mut best = (from, -1.0);
        for &v in lp {
            let d = (mesh.positions[v as usize] - p).length_squared();
            if d > best.1 {
                best = (v, d);
            }
        }
        best.0
    };
    let a = far(lp[0]);
    let b = far(a);
    if a == b {
        return Err(FlattenError::Internal(InternalError::LscmSingleVertex));
    }
    Ok((a.min(b), a.max(b)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::{QuadraticBuilder, corner_cotans};
    use crate::testmesh::{saddle, spherical_cap};
    use std::collections::BTreeMap;

    /// A cap with two pins inside its boundary's reach, a third inside, and a vertex no
    /// triangle uses, with its topology and the pins.
    fn pinned_cap() -> (TriMesh, Topology, Vec<(u32, DVec2)>) {
        let mut mesh = spherical_cap(40.0, 1.1, 24);
        let topo = flatcut_mesh::check_disk(&mesh).unwrap();
        mesh.positions.push(flatcut_geom::DVec3::new(1e3, 0.0, 0.0));
        let (a, b) = farthest_boundary_pair(&mesh, &topo).unwrap();
        let hard = vec![(a, DVec2::ZERO), (b, DVec2::new(70.0, 0.0)), (7, DVec2::Y)];
        (mesh, topo, hard)
    }

    /// A saddle pinned at two vertices of its boundary.
    fn pinned_saddle() -> (TriMesh, Topology, Vec<(u32, DVec2)>) {
        let mesh = saddle(50.0, 30);
        let topo = flatcut_mesh::check_disk(&mesh).unwrap();
        (mesh, topo, vec![(0, DVec2::ZERO), (5, DVec2::X)])
    }

    /// Which dofs of the real system are held (u of vertex `v` is dof 2v, its v 2v + 1): both of
    /// every vertex the map holds.
    fn fixed_dofs(mesh: &TriMesh, hard: &[(u32, DVec2)]) -> Vec<bool> {
        free_vertices(mesh, hard)
            .iter()
            .flat_map(|&k| [k == FIXED; 2])
            .collect()
    }

    /// The real matrix of the free u's and v's as the triplets of every term give it, lower
    /// triangle by (row dof, column dof), and the builder that holds its couplings.
    fn triplet_matrix(
        mesh: &TriMesh,
        topo: &Topology,
        hard: &[(u32, DVec2)],
    ) -> BTreeMap<(u32, u32), f64> {
        let fixed = fixed_dofs(mesh, hard);
        let mut q = QuadraticBuilder::new(&fixed, 6 * mesh.triangles.len());
        let cot = corner_cotans(&mesh.positions, &mesh.triangles);
        conformal_terms(mesh, topo, |t| cot[t], |_| true, &mut |i, j, w| {
            q.add(i, j, w)
        });
        let free: Vec<u32> = (0..fixed.len() as u32)
            .filter(|&d| !fixed[d as usize])
            .collect();
        let (pattern, values) = q.into_triplet_matrix("test").unwrap();
        let (col_ptr, row_idx) = pattern.csc();
        let mut entries = BTreeMap::new();
        for c in 0..free.len() {
            for k in col_ptr[c]..col_ptr[c + 1] {
                entries.insert((free[row_idx[k]], free[c]), values[k]);
            }
        }
        entries
    }

    /// The map of the real system of u's and v's assembled from triplets, solved by the real
    /// solver (the map's solve before it was made complex).
    fn real_map(mesh: &TriMesh, topo: &Topology, hard: &[(u32, DVec2)]) -> Vec<DVec2> {
        let n = mesh.positions.len();
        let fixed = fixed_dofs(mesh, hard);
        let mut q = QuadraticBuilder::new(&fixed, 6 * mesh.triangles.len());
        let cot = corner_cotans(&mesh.positions, &mesh.triangles);
        conformal_terms(mesh, topo, |t| cot[t], |_| true, &mut |i, j, w| {
            q.add(i, j, w)
        });
        let sys = q.build("test").unwrap();
        let mut x = vec![0.0; 2 * n];
        for &(v, p) in hard {
            x[2 * v as usize] = p.x;
            x[2 * v as usize + 1] = p.y;
        }
        let mut fields = vec![x];
        sys.solve(&mut fields, None).unwrap();
        (0..n)
            .map(|v| DVec2::new(fields[0][2 * v], fields[0][2 * v + 1]))
            .collect()
    }

    #[test]
    fn the_hermitian_matrix_is_the_real_triplets_matrix_made_complex_bit_for_bit() {
        for (mesh, topo, hard) in [pinned_cap(), pinned_saddle()] {
            let want = triplet_matrix(&mesh, &topo, &hard);
            let n = mesh.positions.len();
            let free_index = free_vertices(&mesh, &hard);
            let graph = Graph::of_triangles(n, &mesh.triangles);
            let area = AreaTerms::of(&topo);
            let (pattern, free) = conformal_pattern(&graph, &free_index, &area).unwrap();
            let (ptr, tris) = vertex_triangles(n, &mesh.triangles);
            let cot = corner_cotans(&mesh.positions, &mesh.triangles);
            let mut values = ConformalValues::zeroed(&graph);
            values.fill(&mesh.triangles, &graph, (&ptr, &tris), |t| cot[t]);
            // Each entry of the Hermitian pattern, written as the real 2 × 2 block
            // [[Re, −Im], [Im, Re]] over (u, v), is the real matrix's (zero where it has none).
            let (col_ptr, row_idx) = pattern.csc();
            let mut seen = 0;
            for c in 0..free.len() {
                for k in col_ptr[c]..col_ptr[c + 1] {
                    let (x, y) = (free[row_idx[k]], free[c]);
                    let h = values.entry(&graph, &area, x, y);
                    let block = [[h.re, -h.im], [h.im, h.re]];
                    for (f, row) in block.iter().enumerate() {
                        for (g, &got) in row.iter().enumerate() {
                            let (r, s) = (2 * x + f as u32, 2 * y + g as u32);
                            if r < s {
                                continue;
                            }
                            match want.get(&(r, s)) {
                                Some(w) => {
                                    seen += 1;
                                    assert_eq!(
                                        got.to_bits(),
                                        w.to_bits(),
                                        "({r}, {s}): {got} against {w}"
                                    );
                                }
                                None => assert_eq!(got, 0.0, "({r}, {s}) is no entry"),
                            }
                        }
                    }
                }
            }
            assert_eq!(
                seen,
                want.len(),
                "every real entry is in the Hermitian pattern"
            );
        }
    }

    #[test]
    fn the_complex_map_is_the_real_map_with_any_threads() {
        for (mesh, topo, hard) in [pinned_cap(), pinned_saddle()] {
            let want = real_map(&mesh, &topo, &hard);
            let scale = want
                .iter()
                .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
            let mut maps = Vec::new();
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                maps.push(pool.install(|| solve_pinned(&mesh, &topo, &hard)).unwrap());
            }
            for (v, (got, want)) in maps[0].iter().zip(&want).enumerate() {
                let err = (*got - *want).abs().max_element();
                assert!(err <= 1e-9 * scale, "vertex {v}: {got} against {want}");
            }
            for (a, b) in maps[0].iter().zip(&maps[1]) {
                assert_eq!(a.x.to_bits(), b.x.to_bits());
                assert_eq!(a.y.to_bits(), b.y.to_bits());
            }
            // The pins hold, and a vertex no triangle uses is at the origin.
            for &(v, p) in &hard {
                assert_eq!(maps[0][v as usize], p);
            }
            if mesh.positions.len()
                > mesh
                    .triangles
                    .iter()
                    .flatten()
                    .max()
                    .map_or(0, |&v| v as usize + 1)
            {
                assert_eq!(*maps[0].last().unwrap(), DVec2::ZERO);
            }
        }
    }

    #[test]
    fn every_unknown_fixed_is_an_error() {
        let mesh = crate::testmesh::skew_triangle();
        let topo = flatcut_mesh::check_disk(&mesh).unwrap();
        let hard: Vec<(u32, DVec2)> = (0..3).map(|v| (v, DVec2::splat(v as f64))).collect();
        assert!(matches!(
            solve_pinned(&mesh, &topo, &hard),
            Err(FlattenError::Internal(
                InternalError::EveryUnknownFixed { .. }
            ))
        ));
    }
}
