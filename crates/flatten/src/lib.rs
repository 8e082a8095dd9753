//! Minimum-distortion flattening of a disk-topology triangle mesh to the plane, at true scale.
//!
//! Entry point: [`flatten`] with [`FlattenParams`]; the result is a [`Flattening`] (a 2D position
//! per vertex in mm, never rescaled) with a [`FlattenInfo`], or a [`FlattenError`] that says what
//! is wrong with the input or why the method refused.
//!
//! Methods ([`Method`]): Duncan's isometric δ2 (symmetric Dirichlet, flip-free), conformal δ1
//! (flip-free), LSCM, conformal with an isometric boundary (Duncan's f2), ARAP, exact developable
//! unfolding, min-max global distortion δ0, and boundary-isometric (Duncan's f1).
//!
//! **Architecture invariants:** deterministic (bit-identical output for the same input, with any
//! number of threads: sequential faer, no hash-map iteration; the nonlinear methods assemble in
//! parallel with rayon over fixed blocks whose partial sums are combined in a fixed order);
//! never returns a flipped triangle from a method documented flip-free; never rescales the
//! result. Long solves report progress, honour a time limit and can be cancelled
//! ([`FlattenParams::time_limit`], [`FlattenHooks`]).
//!
//! ## How it works
//!
//! (The crate's map is in ARCHITECTURE.md; this is the detail behind it.)
//!
//! `flatten(mesh, params) -> Flattening`. Linear methods (LSCM, ARAP, conformal with isometric
//! boundary, developable unfolding) on faer's sparse Cholesky with a reused symbolic factorisation
//! (AMD ordering; from 150k vertices our nested dissection of the vertex graph, `ordering.rs`, with
//! LSCM's u and v one complex unknown per vertex, `sparse/hermitian.rs`, the order made once
//! per graph and shared by the LSCM start and the Newton solves after it; 32-bit indices); nonlinear flip-free methods (isometric δ2, conformal δ1, min-max δ0,
//! boundary-isometric f1, orthotropic) as argmin solvers whose heavy steps are our own sparse
//! Newton/local-global iterations. The projected Newton (`nonlinear/newton.rs`) evaluates triangles
//! in parallel (rayon, fixed blocks scattered in triangle order), mirrors indefinite Hessian modes
//! while steps run into inversions, extends full steps while the energy falls, uses the unprojected
//! Hessian near convergence when it is positive definite, and in the tail takes chord steps (the
//! last factorisation reused for the new gradient), ending on one when it shows the next step would
//! gain less than the tolerance. Edge lengths held as constraints (f1's boundary) take their
//! multipliers along with every step (the SQP step of the augmented Lagrangian), and the solve does
//! not stop while they still close in; vertices can be held in place (`MapProblem::with_fixed`:
//! f1's interior inside a kept outline where a free one would crimp), pulled together (`Pull`, zero
//! rest length) and kept from turning over in triangles of their own (`MapProblem::with_guards`):
//! the darts' tight fit. The sparse Cholesky is always supernodal and sequential (the second
//! core gets whole tasks instead: an isometric map's Newton analysis is made beside its LSCM
//! start, `nonlinear::solve`, and LSCM's own analysis, whose pattern it makes from the mesh's
//! graph, beside the assembly of its values, `lscm.rs`); from 40M (about 300k faces) the factor is single precision and each solve is
//! refined to double precision by conjugate gradients (`refine.rs`), a Newton direction far from the
//! minimum only to its forcing term (inexact Newton, `nonlinear/newton.rs`). Long solves report progress
//! and honour a time limit and a cancel flag (`FlattenParams::time_limit`, `FlattenHooks`). Every
//! stage of a flattening (a method's own solve, the limits, the joint solve's seams, the darts, the
//! split) draws on one `budget::Budget`: `max_iters` and `time_limit` cap the stage over all its
//! solves, work computed ahead on the other core is taken only where the cap would not have cut it
//! short (so the counts and the bits are those of the sequential run), and each stage's count is in
//! `FlattenInfo::stages`; `timings` says where a solve's time went (start map, ordering, assembly,
//! factorisation, solves, line search). `assembly` flattens the pieces joined by mating seams as
//! one problem (δ2 plus an augmented Lagrangian that keeps each pair of sewn edges equally long);
//! `limits` makes material limits constraints of the solve (a feasibility penalty, then a
//! logarithmic barrier) or reports where they cannot be met. `nonlinear/orthotropic` is the one
//! energy that is not a function of the singular values (the Green strain in each triangle's grain
//! frame weighted by the material's stiffness; its 4×4 Hessian projected by a symmetric
//! eigen-decomposition), so the Newton solver takes any per-triangle energy (`kernel::TriEnergy`,
//! every isotropic energy one); `nonlinear/grain` takes the warp as a straight line of the pattern
//! pulled back through the isometric map, and searches the grain's angle for `grain = "auto"` (its
//! samples solved side by side, compared in order); `anisotropy` holds the material numbers it
//! takes. `testmesh` (generated surfaces) is test support behind the `test-support` feature;
//! `examples/flatten_bench.rs` is the benchmark driver (`tools/flatten/bench.py` runs it against
//! libigl's SLIM).

#![warn(missing_docs)]

pub mod anisotropy;
pub mod arap;
pub mod assembly;
pub(crate) mod beside;
pub mod budget;
pub mod conformal_boundary;
pub mod developable;
pub mod internal;
pub mod limits;
pub mod lscm;
pub mod marks;
pub mod method;
pub mod nonlinear;
pub(crate) mod ops;
pub(crate) mod ordering;
pub mod params;
pub(crate) mod refine;
pub(crate) mod sparse;
/// Generated test surfaces (caps, cylinders, cones, saddles): for this crate's tests, benches
/// and examples only (feature `test-support`), not part of the public API.
#[cfg(any(test, feature = "test-support"))]
#[doc(hidden)]
pub mod testmesh;
pub mod timings;
pub mod tutte;
pub mod warm;

pub use budget::{Budget, StageCount};
pub use internal::InternalError;
pub use method::Method;
pub use params::{
    FlattenError, FlattenHooks, FlattenInfo, FlattenParams, FlattenProgress, Flattening, Pin,
    ProgressFn,
};
pub use timings::Timings;
pub use warm::flatten_assembly_from;

use flatcut_mesh::{TriMesh, check_disk};

/// Two pins closer than this fraction of the mesh's bounding-box diagonal count as the same
/// point: pinning two different vertices there would force a degenerate map.
const PIN_COINCIDENT_REL: f64 = 1e-9;

/// Flattens a disk-topology mesh with the method and constraints in `params`.
///
/// Two 10 mm squares at a right angle (a sheet folded along x = 10) unfold to a 20 × 10 mm
/// rectangle, every edge its own length:
///
/// ```
/// use flatcut_flatten::{FlattenParams, Method, flatten};
/// use flatcut_geom::DVec3;
/// use flatcut_mesh::TriMesh;
///
/// let p = [(0., 0., 0.), (10., 0., 0.), (10., 10., 0.), (0., 10., 0.), (10., 0., 10.), (10., 10., 10.)]
///     .map(|(x, y, z)| DVec3::new(x, y, z))
///     .to_vec();
/// let mesh = TriMesh::new(p, vec![[0, 1, 2], [0, 2, 3], [2, 1, 4], [2, 4, 5]]);
/// let flat = flatten(&mesh, &FlattenParams::new(Method::Isometric))?;
/// for t in &mesh.triangles {
///     for k in 0..3 {
///         let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
///         let (l3, l2) = (mesh.positions[a].distance(mesh.positions[b]), flat.uv[a].distance(flat.uv[b]));
///         assert!((l3 - l2).abs() < 1e-6, "{l3} vs {l2}");
///     }
/// }
/// # Ok::<(), flatcut_flatten::FlattenError>(())
/// ```
pub fn flatten(mesh: &TriMesh, params: &FlattenParams) -> Result<Flattening, FlattenError> {
    let mut topo = check_disk(mesh)?;
    validate_pins(mesh, &params.pins)?;
    if matches!(params.method, Method::Isometric | Method::Lscm) {
        // Their start maps read the outline alone (LSCM's pins and area term, Tutte's circle):
        // the edge map and the components (42 MB at a million faces) are dropped before their
        // factorisations, the memory peak of a large map.
        topo.edges = Default::default();
        topo.component_of_triangle = Vec::new();
    }
    match params.method {
        Method::Isometric
        | Method::Conformal
        | Method::Minmax
        | Method::BoundaryIsometric
        | Method::Orthotropic => nonlinear::solve(mesh, &topo, params),
        Method::Lscm => lscm::lscm(mesh, &topo, &params.pins),
        Method::ConformalBoundary => conformal_boundary::conformal_boundary(mesh, &topo, params),
        Method::Developable => developable::developable(mesh, &topo, params),
        Method::Arap => arap::arap(mesh, &topo, params),
    }
}

/// Checks that every pin names a vertex used by the mesh, at a finite position, that no vertex
/// is pinned twice and that no two pinned vertices share a position.
pub fn validate_pins(mesh: &TriMesh, pins: &[Pin]) -> Result<(), FlattenError> {
    let used = ops::used_mask(mesh);
    let diag = mesh.bbox().diagonal();
    for (index, p) in pins.iter().enumerate() {
        let v = p.vertex as usize;
        if v >= mesh.positions.len() {
            return Err(FlattenError::BadPin {
                index,
                reason: format!(
                    "vertex {} does not exist (the mesh has {} vertices)",
                    p.vertex,
                    mesh.positions.len()
                ),
            });
        }
        if !used[v] {
            return Err(FlattenError::BadPin {
                index,
                reason: format!("vertex {} belongs to no triangle", p.vertex),
            });
        }
        if !flatcut_geom::finite2(p.position) {
            return Err(FlattenError::BadPin {
                index,
                reason: format!(
                    "the position of vertex {} is not finite ({}, {})",
                    p.vertex, p.position.x, p.position.y
                ),
            });
        }
        for (j, q) in pins[..index].iter().enumerate() {
            if q.vertex == p.vertex {
                return Err(FlattenError::BadPin {
                    index,
                    reason: format!("vertex {} is already pinned by pin {j}", p.vertex),
                });
            }
            if (q.position - p.position).length() <= PIN_COINCIDENT_REL * diag {
                return Err(FlattenError::BadPin {
                    index,
                    reason: format!(
                        "vertex {} is pinned at the same point as vertex {} (pin {j})",
                        p.vertex, q.vertex
                    ),
                });
            }
        }
    }
    Ok(())
}
