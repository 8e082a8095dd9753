//! The nonlinear, flip-free methods: isometric (δ2), conformal (δ1), min-max (δ0) and
//! boundary-isometric (Duncan's f1), with material stretch limits.

use flatcut_mesh::{Topology, TriMesh};

use crate::{FlattenError, FlattenParams, Flattening};

/// Solves one of the nonlinear methods (`Isometric`, `Conformal`, `Minmax`, `BoundaryIsometric`).
pub fn solve(
    mesh: &TriMesh,
    topo: &Topology,
    params: &FlattenParams,
) -> Result<Flattening, FlattenError> {
    let _ = (mesh, topo);
    Err(FlattenError::Internal(format!(
        "method {} is not available in this build",
        params.method
    )))
}
