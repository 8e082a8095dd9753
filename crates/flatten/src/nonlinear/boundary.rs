//! Boundary-isometric flattening (Duncan's f1, issue 10): every boundary edge keeps its 3D
//! length, the interior minimises Duncan's pointwise deviation Σ(λi − 1)² (λi = σi², the
//! Green–Lagrange strain norm).
//!
//! Method: start from the isometric (δ2) map, which is flip-free and already close; then an
//! augmented Lagrangian on the boundary lengths (c_e = (|e|² − L²)/L² = 0), each inner problem
//! solved by the flip-free projected Newton of [`super::newton`], multipliers updated
//! λ ← λ + w c and the weight raised ×10 while the violation does not shrink fast enough.
//! Where the lengths cannot all be kept without a fold, the line search stops at the fold and
//! the closest flip-free map is returned with a warning naming the worst edges.

use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use super::kernel::{GreenStrain, RestTri, SymDirichlet};
use super::newton::{EdgeTerms, MapProblem, run};
use super::{ABS_DECREMENT_PER_AREA, mean_density, newton_solve, total_area};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method};

/// Target relative boundary-length error.
pub const BOUNDARY_REL_TOLERANCE: f64 = 1e-10;
/// Outer augmented-Lagrangian iterations.
const MAX_OUTER: usize = 12;
/// Initial penalty weight (relative to the strain density).
const INITIAL_WEIGHT: f64 = 10.0;
/// Weight growth when the violation shrank by less than [`REQUIRED_SHRINK`].
const WEIGHT_GROWTH: f64 = 10.0;
const REQUIRED_SHRINK: f64 = 0.25;
/// Relative length error above which an edge is reported as not kept.
const REPORT_REL_ERROR: f64 = 1e-6;

/// Largest relative boundary-length error |ℓ − L|/L and its edge.
pub fn max_boundary_error(edges: &[(usize, usize, f64)], x: &[DVec2]) -> (f64, usize) {
    let mut worst = (0.0, 0);
    for (k, &(a, b, l)) in edges.iter().enumerate() {
        let r = ((x[b] - x[a]).length() - l).abs() / l;
        if r > worst.0 {
            worst = (r, k);
        }
    }
    worst
}

/// Boundary edges of the (single) boundary loop with their 3D lengths.
pub fn boundary_edges(mesh: &TriMesh, topo: &Topology) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    for lp in &topo.boundary_loops {
        for i in 0..lp.len() {
            let (a, b) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
            out.push((a, b, (mesh.positions[b] - mesh.positions[a]).length()));
        }
    }
    out
}

/// Duncan's f1.
pub fn boundary_isometric(
    mesh: &TriMesh,
    topo: &Topology,
    rest: &[RestTri],
    params: &FlattenParams,
) -> Result<Flattening, FlattenError> {
    let n = mesh.positions.len();
    let method = Method::BoundaryIsometric;
    let x0 = super::init::tutte(mesh, topo)?;
    let iso = newton_solve(rest, n, SymDirichlet, &x0, params, method)?;
    let mut iterations = iso.iterations;
    let mut x = iso.x;
    let edges = boundary_edges(mesh, topo);
    let mut terms = EdgeTerms {
        lambda: vec![0.0; edges.len()],
        edges: edges.clone(),
        weight: INITIAL_WEIGHT,
    };
    let abs = ABS_DECREMENT_PER_AREA * total_area(rest);
    let mut viol = max_boundary_error(&edges, &x).0;
    for _ in 0..MAX_OUTER {
        if viol <= BOUNDARY_REL_TOLERANCE {
            break;
        }
        let problem =
            MapProblem::new(rest, n, GreenStrain, Some(terms.clone())).map_err(|reason| {
                FlattenError::Solver {
                    stage: "boundary-isometric",
                    reason,
                }
            })?;
        let (r, p) = run(problem, &x, params.max_iters, params.rel_tolerance, abs)
            .map_err(|reason| FlattenError::NoConvergence { method, reason })?;
        iterations += r.iterations;
        x = r.x;
        let Some(t) = p.edges else { break };
        terms = t;
        for k in 0..terms.edges.len() {
            terms.lambda[k] += terms.weight * terms.constraint(k, &x);
        }
        let v = max_boundary_error(&edges, &x).0;
        if v > REQUIRED_SHRINK * viol {
            terms.weight *= WEIGHT_GROWTH;
        }
        viol = v;
    }
    let mut warnings = Vec::new();
    if viol > REPORT_REL_ERROR {
        let mut errs: Vec<(f64, usize)> = edges
            .iter()
            .enumerate()
            .map(|(k, &(a, b, l))| (((x[b] - x[a]).length() - l).abs() / l, k))
            .collect();
        errs.sort_by(|p, q| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)));
        let worst: Vec<String> = errs
            .iter()
            .take(3)
            .map(|&(r, k)| format!("{}–{} ({:.2e})", edges[k].0, edges[k].1, r))
            .collect();
        warnings.push(format!(
            "boundary lengths cannot all be kept without a fold: largest relative length error {viol:.2e}; worst edges {}",
            worst.join(", ")
        ));
    }
    Ok(Flattening {
        info: FlattenInfo {
            iterations,
            final_energy: mean_density(rest, &x, &GreenStrain),
            warnings,
        },
        uv: x,
    })
}
