//! Where a flat piece overlaps itself: a boundary loop of its map crossing itself. A map with no
//! inverted triangle (the limits' excess counts one as infinite) whose outline is a simple
//! polygon is one-to-one on a disk, so this check and the limits together prove that a flat
//! piece can be cut from the material as it is drawn.

use flatcut_geom::DVec2;
use flatcut_geom::polygon::first_self_intersection;
use flatcut_mesh::{Topology, TriMesh};

use crate::DartError;

/// The boundary vertex of `mesh` nearest the first place where a flat boundary loop (the map
/// `x`) crosses itself, or `None` when every loop is simple.
pub fn outline_crossing(mesh: &TriMesh, x: &[DVec2]) -> Result<Option<u32>, DartError> {
    let topo = Topology::build(mesh)?;
    for l in &topo.boundary_loops {
        let pts: Vec<DVec2> = l.iter().map(|&v| x[v as usize]).collect();
        if let Some((_, _, p)) = first_self_intersection(&pts) {
            let nearest = l.iter().copied().min_by(|&a, &b| {
                x[a as usize]
                    .distance_squared(p)
                    .total_cmp(&x[b as usize].distance_squared(p))
            });
            return Ok(nearest);
        }
    }
    Ok(None)
}
