//! Vertices held in place by the projected Newton solver (`MapProblem::with_fixed`, a Dirichlet
//! problem; f1 relaxes an interior inside a kept outline with it): held vertices keep their
//! bits, and the free ones reach the minimiser the held ones leave them.

use flatcut_flatten::nonlinear::kernel::{SymDirichlet, rest_frames};
use flatcut_flatten::nonlinear::newton::{Budget, MapProblem, run};
use flatcut_flatten::{FlattenParams, Method, flatten, testmesh};
use flatcut_geom::DVec2;
use flatcut_mesh::Topology;

/// How close (mm) the interior must come back to the free optimum it was moved from.
const BACK_MM: f64 = 1e-6;

#[test]
fn held_vertices_keep_their_bits_and_the_rest_reach_the_optimum() {
    let mesh = testmesh::spherical_cap(50.0, 1.0, 12);
    let topo = Topology::build(&mesh).unwrap();
    let rest = rest_frames(&mesh).unwrap();
    let solve = |x: &[DVec2], held: Option<&[bool]>| {
        let mut problem = MapProblem::new(&rest, x.len(), SymDirichlet, None).unwrap();
        if let Some(h) = held {
            problem = problem.with_fixed(h);
        }
        run(problem, x, 100, 1e-15, 0.0, &Budget::none("test"))
            .unwrap()
            .0
    };
    // The free optimum, converged further than `flatten` takes it.
    let near = flatten(&mesh, &FlattenParams::new(Method::Isometric))
        .unwrap()
        .uv;
    let best = solve(&near, None).x;
    let n = best.len();
    let mut held = vec![false; n];
    for &v in &topo.boundary_loops[0] {
        held[v as usize] = true;
    }
    // The outline of the free optimum held: the optimum is the Dirichlet problem's too. The
    // interior starts moved off it (by up to 0.3 mm, within its 4 mm edges: flip-free).
    let start: Vec<DVec2> = best
        .iter()
        .enumerate()
        .map(|(v, &p)| {
            if held[v] {
                p
            } else {
                p + 0.3 * DVec2::new((v as f64 * 0.7).sin(), (v as f64 * 1.3).cos())
            }
        })
        .collect();
    let r = solve(&start, Some(&held));
    let mut worst = 0.0f64;
    for v in 0..n {
        if held[v] {
            assert_eq!(
                r.x[v].to_array().map(f64::to_bits),
                start[v].to_array().map(f64::to_bits)
            );
        } else {
            worst = worst.max(r.x[v].distance(best[v]));
        }
    }
    println!("{} steps, interior within {worst:.2e} mm", r.iterations);
    assert!(worst <= BACK_MM, "interior {worst:e} mm from the optimum");

    // A held outline scaled by 1.1: it stays put to the bit, and the interior is the
    // stretched optimum inside it, not the free one (whose outline is smaller).
    let scaled: Vec<DVec2> = best.iter().map(|&p| 1.1 * p).collect();
    let r = solve(&scaled, Some(&held));
    for v in (0..n).filter(|&v| held[v]) {
        assert_eq!(r.x[v], scaled[v]);
    }
    let moved = (0..n)
        .filter(|&v| !held[v])
        .map(|v| r.x[v].distance(scaled[v]))
        .fold(0.0, f64::max);
    assert!(moved > 1e-3, "the interior did not relax ({moved:e} mm)");
}
