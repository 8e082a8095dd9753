//! Triangles a Newton problem keeps from turning over without an energy of their own
//! (`MapProblem::with_guards`; the darts keep a dart's legs from crossing with them): the step
//! bound stops where a guard would turn over, as it does for the mesh's own triangles.

use flatcut_flatten::nonlinear::kernel::{SymDirichlet, rest_frames};
use flatcut_flatten::nonlinear::newton::MapProblem;
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;

#[test]
fn a_guard_bounds_the_step_where_it_would_turn_over() {
    // Two separate unit triangles; the second moves as a whole, so none of the mesh's own
    // triangles ever turns over.
    let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
    let mesh = TriMesh::new(
        vec![
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(0.0, 1.0),
            p(3.0, -1.0),
            p(3.0, 1.0),
            p(4.0, 0.0),
        ],
        vec![[0, 1, 2], [3, 5, 4]],
    );
    let rest = rest_frames(&mesh).unwrap();
    let x: Vec<DVec2> = mesh.positions.iter().map(|q| q.truncate()).collect();
    // The second triangle slides left by 4 per unit step: its edge 3–4 (x = 3) passes the first
    // triangle's corner 1 (x = 1) at t = 0.5.
    let d: Vec<DVec2> = (0..6)
        .map(|v| {
            if v >= 3 {
                DVec2::new(-4.0, 0.0)
            } else {
                DVec2::ZERO
            }
        })
        .collect();
    let free = MapProblem::new(&rest, 6, SymDirichlet, None).unwrap();
    assert_eq!(free.max_step(&x, &d), f64::INFINITY);
    // Corner 1 to the left of 3→4 seen as the triangle (1, 3, 4): counter-clockwise.
    assert!((x[3] - x[1]).perp_dot(x[4] - x[1]) > 0.0);
    let guarded = MapProblem::new(&rest, 6, SymDirichlet, None)
        .unwrap()
        .with_guards(vec![[1, 3, 4]]);
    let t = guarded.max_step(&x, &d);
    assert!((t - 0.5).abs() < 1e-12, "step bound {t}");
}
