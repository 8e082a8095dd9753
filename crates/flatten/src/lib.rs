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
//! **Architecture invariants:** deterministic (bit-identical output for the same input: sequential
//! faer, no hash-map iteration, no threads whose scheduling changes results); never returns a
//! flipped triangle from a method documented flip-free; never rescales the result.

pub mod method;
pub mod nonlinear;
pub mod params;

pub use method::Method;
pub use params::{FlattenError, FlattenInfo, FlattenParams, Flattening, Pin};

use flatcut_mesh::{TriMesh, check_disk};

/// Flattens a disk-topology mesh with the method and constraints in `params`.
pub fn flatten(mesh: &TriMesh, params: &FlattenParams) -> Result<Flattening, FlattenError> {
    let topo = check_disk(mesh)?;
    match params.method {
        Method::Isometric | Method::Conformal | Method::Minmax | Method::BoundaryIsometric => {
            nonlinear::solve(mesh, &topo, params)
        }
        m => Err(FlattenError::Internal(format!(
            "method {m} is not available in this build"
        ))),
    }
}
