//! Opening any surface into disks: the first cuts of a closed or open surface of any genus and
//! any number of boundary loops, before the limits ask for more ([`crate::split`]).
//!
//! 1. **Check.** The surface must be manifold (an edge of three triangles or a pinched vertex is
//!    refused naming it) and, where closed, must not pass through itself
//!    ([`flatcut_mesh::intersect`]): both would give pieces that no sewing can join.
//! 2. **Components.** Each connected part is opened on its own.
//! 3. **Handles and holes.** The cut graph of [`flatcut_mesh::cut_graph`]: the greedy system of
//!    shortest loops through the most hidden vertex (the edge lengths weighted by the seams'
//!    visibility, [`crate::seam_cost`]), joined to the boundary where there is one, then each of
//!    its paths tightened toward the geodesic of its class.
//! 4. **A sphere.** A closed surface of genus 0 has no handle: it is slit from its most hidden
//!    vertex to the vertex farthest from it (weighted), the seam a plush maker runs under a toy
//!    from its seat to the top of its head.
//!
//! Every cut's two sides are copies of the same vertices at the same coordinates, so the
//! opened disk's seams are found again by their coincident vertices
//! ([`flatcut_mesh::mating::coincident_seams`]) and sewn equal by the joint solve.

use flatcut_geom::DVec3;
use flatcut_mesh::cut_graph::{
    SurfaceType, cut_graph, farthest, opens_to_disk, shortest_path, surface_type, tighten,
};
use flatcut_mesh::regions::split_along_lines;
use flatcut_mesh::{Topology, TriMesh, check_disk, cut_along_seams};

use crate::DartError;
use crate::seam_cost::Visibility;

/// A surface opened into disks.
#[derive(Clone, Debug)]
pub struct Opened {
    /// One disk per connected part of the surface, in the order of their first triangles.
    pub pieces: Vec<TriMesh>,
    /// The 3D path of every opening cut.
    pub cuts: Vec<Vec<DVec3>>,
    /// The genus and boundary loops of every part, as it was before the cuts.
    pub parts: Vec<SurfaceType>,
}

/// Opens `mesh` into disks (see the module documentation); `visibility` weighs where the cuts
/// go (its per-vertex flags index `mesh`).
pub fn open_surface(mesh: &TriMesh, visibility: &Visibility) -> Result<Opened, DartError> {
    let mut bare = mesh.clone();
    bare.flat = None;
    let topo = Topology::build(&bare)?;
    if topo.boundary_loops.is_empty() {
        flatcut_mesh::intersect::check_no_self_intersection(&bare)
            .map_err(|e| DartError::Placement(e.to_string()))?;
    }
    let factors = visibility.vertex_factors(&bare);
    let regions = split_along_lines(&bare, &[]).map_err(|e| {
        DartError::Placement(format!("the surface cannot be split into its parts: {e}"))
    })?;
    let mut out = Opened {
        pieces: Vec::new(),
        cuts: Vec::new(),
        parts: Vec::new(),
    };
    for region in regions.regions {
        let part = region.mesh;
        let cost: Vec<f64> = region.origin.iter().map(|&o| factors[o as usize]).collect();
        let ptopo = Topology::build(&part)?;
        out.parts.push(surface_type(&part, &ptopo));
        if check_disk(&part).is_ok() {
            out.pieces.push(part);
            continue;
        }
        let paths = opening_paths(&part, &ptopo, &cost)?;
        let disk = cut_along_seams(&part, &paths)?;
        check_disk(&disk).map_err(|e| {
            DartError::Placement(format!("the opening cuts did not leave a disk: {e}"))
        })?;
        out.cuts.extend(
            paths
                .iter()
                .map(|p| p.iter().map(|&v| part.positions[v as usize]).collect()),
        );
        out.pieces.push(disk);
    }
    Ok(out)
}

/// The paths that open one connected part (not a disk) into a disk.
fn opening_paths(
    part: &TriMesh,
    topo: &Topology,
    cost: &[f64],
) -> Result<Vec<Vec<u32>>, DartError> {
    // The root: the most hidden vertex (the first on ties).
    let root = (0..part.positions.len())
        .min_by(|&a, &b| cost[a].total_cmp(&cost[b]))
        .unwrap_or(0) as u32;
    let mut paths = cut_graph(part, cost, root)?;
    if paths.is_empty() && topo.boundary_loops.is_empty() {
        let (far, _) = farthest(part, cost, &[root])
            .ok_or_else(|| DartError::Placement("the closed surface has one vertex".into()))?;
        let slit = shortest_path(part, cost, root, far)
            .ok_or_else(|| DartError::Placement("no path across the closed surface".into()))?;
        paths.push(slit);
    }
    let tight = tighten(part, &paths, cost);
    if opens_to_disk(part, &tight) {
        Ok(tight)
    } else if opens_to_disk(part, &paths) {
        Ok(paths)
    } else {
        Err(DartError::Placement(
            "the cut graph of the surface did not open it into a disk".into(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed slab with `holes` square holes through it in a row (genus = holes).
    pub(crate) fn slab_with_holes(holes: usize) -> TriMesh {
        // A (3·holes + 1) × 3 grid of unit cells; the cells (3k + 1 .. 3k + 2, 1) are holes.
        let (nx, ny) = (3 * holes + 1, 3);
        let hole = |i: usize, j: usize| j == 1 && i % 3 == 1;
        let mut p = Vec::new();
        let id = |i: usize, j: usize, top: bool| ((j * (nx + 1) + i) * 2 + usize::from(top)) as u32;
        for j in 0..=ny {
            for i in 0..=nx {
                p.push(DVec3::new(i as f64 * 10.0, j as f64 * 10.0, 0.0));
                p.push(DVec3::new(i as f64 * 10.0, j as f64 * 10.0, 5.0));
            }
        }
        let mut t = Vec::new();
        let mut quad = |a: u32, b: u32, c: u32, d: u32| {
            t.push([a, b, c]);
            t.push([a, c, d]);
        };
        for j in 0..ny {
            for i in 0..nx {
                if hole(i, j) {
                    continue;
                }
                quad(
                    id(i, j, true),
                    id(i + 1, j, true),
                    id(i + 1, j + 1, true),
                    id(i, j + 1, true),
                );
                quad(
                    id(i, j, false),
                    id(i, j + 1, false),
                    id(i + 1, j + 1, false),
                    id(i + 1, j, false),
                );
            }
        }
        // Walls along every edge between a solid cell and a hole or the outside.
        let solid = |i: isize, j: isize| {
            i >= 0
                && j >= 0
                && (i as usize) < nx
                && (j as usize) < ny
                && !hole(i as usize, j as usize)
        };
        for j in 0..ny as isize {
            for i in 0..nx as isize {
                if !solid(i, j) {
                    continue;
                }
                let (iu, ju) = (i as usize, j as usize);
                // Each side of the cell, counter-clockwise seen from above: its two corners.
                let sides = [
                    ((iu, ju), (iu + 1, ju), solid(i, j - 1)),
                    ((iu + 1, ju), (iu + 1, ju + 1), solid(i + 1, j)),
                    ((iu + 1, ju + 1), (iu, ju + 1), solid(i, j + 1)),
                    ((iu, ju + 1), (iu, ju), solid(i - 1, j)),
                ];
                for ((a, b), (c, d), neighbour) in sides {
                    if !neighbour {
                        quad(
                            id(a, b, false),
                            id(c, d, false),
                            id(c, d, true),
                            id(a, b, true),
                        );
                    }
                }
            }
        }
        TriMesh::new(p, t)
    }

    #[test]
    fn a_slab_with_three_holes_opens_into_one_disk() {
        let m = slab_with_holes(3);
        let topo = Topology::build(&m).unwrap();
        assert_eq!(
            surface_type(&m, &topo),
            SurfaceType {
                genus: 3,
                boundaries: 0
            }
        );
        let o = open_surface(&m, &Visibility::default()).unwrap();
        assert_eq!(o.pieces.len(), 1);
        check_disk(&o.pieces[0]).unwrap();
        assert!((o.pieces[0].area() - m.area()).abs() < 1e-9 * m.area());
        assert_eq!(o.parts[0].genus, 3);
    }

    #[test]
    fn a_closed_sphere_like_box_is_slit_from_its_hidden_side() {
        let m = slab_with_holes(0);
        let under = Visibility {
            hidden_dir: Some(-DVec3::Z),
            ..Default::default()
        };
        let o = open_surface(&m, &under).unwrap();
        assert_eq!(o.pieces.len(), 1);
        check_disk(&o.pieces[0]).unwrap();
        assert_eq!(o.cuts.len(), 1);
        // The slit starts on the underside (z = 0).
        assert!(o.cuts[0][0].z.min(o.cuts[0].last().unwrap().z) < 1e-9);
    }
}
