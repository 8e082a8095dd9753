//! Triangle meshes in millimetres: the indexed [`TriMesh`], readers (OBJ, STL, PLY) and writers (OBJ, STL),
//! topology (edges, boundary loops, components, manifold checks), tessellation of parametric
//! surfaces and of trimmed faces (CAD models) to a chordal tolerance, geodesic distances, and the per-triangle distortion kernel
//! shared by the flattener and the report.
//!
//! **Architecture invariant:** this crate knows 3D surfaces and 2D maps of them, but nothing of
//! patterns, sheets or machines.
#![warn(missing_docs)]

pub mod cut_graph;
pub mod decimal;
pub mod despike;
pub mod disk;
pub mod distortion;
pub mod geodesic;
pub mod grain_strain;
pub mod grid;
pub mod halve;
pub mod intersect;
pub mod io;
pub mod joins;
pub mod lines;
pub mod mating;
pub mod nearest;
pub mod regions;
pub mod seams;
pub mod stats;
pub mod symmetry;
pub mod tessellate;
/// The geometry testkit: grid meshes for tests (feature `testkit`), not part of the public API.
#[cfg(any(test, feature = "testkit"))]
#[doc(hidden)]
pub mod test_grid;
/// Closed test shapes (feature `testkit`), not part of the public API.
#[cfg(any(test, feature = "testkit"))]
#[doc(hidden)]
pub mod test_shapes;
pub mod topology;
pub mod trimesh;
pub mod trimmed;
pub mod weld;

pub use disk::cut_to_disk;
pub use distortion::{FaceDistortion, face_distortion};
pub use io::{MeshIoError, read_mesh, write_obj};
pub use seams::{cut_along_seams, seam_from_points};
pub use stats::MeshStats;
pub use tessellate::{TessError, tessellate, tessellate_model, tessellate_patches};
pub use topology::{Topology, TopologyError, check_disk};
pub use trimesh::TriMesh;
pub use trimmed::{TrimError, TrimPoint, TrimmedFace, TrimmedMesh, tessellate_trimmed};
