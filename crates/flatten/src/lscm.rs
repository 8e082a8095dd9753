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

use crate::internal::InternalError;
use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use crate::ops::{QuadraticBuilder, corner_cotans, used_mask, uv_area};
use crate::ordering::{Graph, shared_dissection};
use crate::sparse::Ordering;
use crate::{FlattenError, FlattenInfo, Flattening, Method, Pin, Timings};
use rayon::prelude::*;
use std::time::{Duration, Instant};

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

/// [`solve_pinned`], with where its time went: the assembly of the matrix (cotangents, the
/// Dirichlet and boundary-area terms, their compression), the ordering and symbolic analysis,
/// the numeric factorisation and the solve, for `flatten --timings`.
fn solve_pinned_timed(
    mesh: &TriMesh,
    topo: &Topology,
    hard: &[(u32, DVec2)],
) -> Result<(Vec<DVec2>, Timings), FlattenError> {
    let started = Instant::now();
    let n = mesh.positions.len();
    let mut fixed = vec![false; 2 * n];
    for (v, used) in used_mask(mesh).into_iter().enumerate() {
        if !used {
            fixed[2 * v] = true;
            fixed[2 * v + 1] = true;
        }
    }
    for &(v, _) in hard {
        fixed[2 * v as usize] = true;
        fixed[2 * v as usize + 1] = true;
    }
    // The order depends on the mesh's graph alone: it is made on a thread of its own while the
    // matrix is assembled on this one (its time beyond the assembly's is the ordering's). Not
    // the other way round, nor both on rayon's threads: the assembly's buffers, freed before the
    // Newton solve a start map leads to, would then be held in another thread's heap, which
    // that solve does not reuse (34 MB more at the peak of a million-face isometric map).
    let dissect = || {
        (Ordering::for_nodes(n) == Ordering::NestedDissection).then(|| {
            let started = Instant::now();
            // The mesh's graph, pins included: the Newton solve this map starts orders the
            // same graph, and reuses this order.
            let order = shared_dissection(Graph::of_triangles(n, &mesh.triangles));
            (order, started.elapsed())
        })
    };
    let assemble = || {
        let started = Instant::now();
        let q = QuadraticBuilder::new(&fixed, 6 * mesh.triangles.len()).dofs_per_vertex(2);
        (conformal_terms(q, mesh, topo), started.elapsed())
    };
    let (order, (mut q, assembling)) = std::thread::scope(|s| {
        let order = s.spawn(dissect);
        let q = assemble();
        // A panic there is a bug, carried on here as if it were this thread's.
        let order = order
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e));
        (order, q)
    });
    let mut overhang = Duration::ZERO;
    if let Some((order, ordering)) = order {
        q = q.vertex_order(order);
        overhang = ordering.saturating_sub(assembling);
    }
    let sys = q.build("lscm")?;
    let built = started.elapsed();
    // The map's vector after the factorisation, the memory peak of a large map.
    let mut x = vec![0.0; 2 * n];
    for &(v, p) in hard {
        x[2 * v as usize] = p.x;
        x[2 * v as usize + 1] = p.y;
    }
    let mut fields = vec![x];
    sys.solve(&mut fields, None)?;
    let x = &fields[0];
    let solver = sys.timings();
    // The builder's own time: what the solver did not account for while building, but for
    // the ordering's overhang.
    let timings = Timings {
        assembly: built.saturating_sub(solver.ordering + solver.factorisation + overhang),
        ordering: solver.ordering + overhang,
        ..solver
    };
    Ok((
        (0..n).map(|v| DVec2::new(x[2 * v], x[2 * v + 1])).collect(),
        timings,
    ))
}

/// Adds the conformal energy of `mesh` to `q` (u and v of vertex `v` are dofs 2v and 2v + 1):
/// the cotangent Dirichlet energy of both coordinates and minus the signed area, which the
/// boundary loops of `topo` give alone (the interior edges' contributions cancel exactly).
fn conformal_terms(mut q: QuadraticBuilder, mesh: &TriMesh, topo: &Topology) -> QuadraticBuilder {
    let cot = corner_cotans(&mesh.positions, &mesh.triangles);
    for (tri, c) in mesh.triangles.iter().zip(&cot) {
        for k in 0..3 {
            let (a, b) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            // Dirichlet energy ¼ Σ cot (u_a − u_b)² = ½ Σ (cot/2)(u_a − u_b)², both coordinates.
            let w = 0.5 * c[k];
            q.add_edge(2 * a, 2 * b, w);
            q.add_edge(2 * a + 1, 2 * b + 1, w);
        }
    }
    drop(cot);
    for lp in &topo.boundary_loops {
        for i in 0..lp.len() {
            let (a, b) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
            // Minus the signed area ½ (x_a y_b − x_b y_a) of the boundary edge a → b.
            q.add(2 * a, 2 * b + 1, -0.5);
            q.add(2 * b, 2 * a + 1, 0.5);
        }
    }
    q
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
