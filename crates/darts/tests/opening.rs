//! The darts' total opening on a spherical cap against the analytic bound.
//!
//! A cap of geodesic radius α on a sphere of radius R, flattened with every face's stretch
//! within [1 − c, 1 + s]: each radial geodesic (length Rα) is at least R·α(1 − c) long in the
//! flat piece, so the flat rim lies at least that far from the flat centre and, the darts being
//! cut out of it, the flat rim with the darts closed must go round that centre: its length plus
//! the darts' openings is at least 2πRα(1 − c). The rim itself (3D length 2πR sin α) is at most
//! (1 + s)·2πR sin α long in the flat piece. So the darts must open at least
//!
//!   W = 2πR (α(1 − c) − (1 + s) sin α)
//!
//! at the rim (for α where this is positive). The bound is met with equality only by a map that
//! compresses every radial line by c all the way from the centre and stretches the whole rim by
//! s; the darts end short of the centre and the band-held δ2 map does not use the whole band
//! everywhere, so the darts open more. Measured (R = 50 mm, α = 1 rad, 3 %/3 %): 4 darts,
//! 41.2 mm against W = 32.4 mm, 1.27 W — outside the 20 % the darts issue aims for. The test
//! holds the bound (no placement may open less: that would break the limits somewhere) and the
//! measured 1.27 with a little room, as a guard against the placement getting worse, and checks
//! that one dart fewer was tried and broke the limits.

use flatcut_darts::{DartOptions, place};
use flatcut_flatten::testmesh::spherical_cap;
use flatcut_flatten::{FlattenParams, Method, flatten};

#[test]
fn total_opening_on_a_spherical_cap_holds_the_analytic_bound() {
    let (r, alpha, pct) = (50.0, 1.0f64, 3.0);
    let mesh = spherical_cap(r, alpha, 18);
    let x0 = flatten(&mesh, &FlattenParams::new(Method::Isometric))
        .unwrap()
        .uv;
    let d = place(&mesh, &x0, &DartOptions::new(Some(pct), Some(pct))).unwrap();
    let (s, c) = (pct / 100.0, pct / 100.0);
    let bound = std::f64::consts::TAU * r * (alpha * (1.0 - c) - (1.0 + s) * alpha.sin());
    let total: f64 = d.darts.iter().map(|d| d.opening_mm).sum();
    eprintln!(
        "{} darts, total opening {total:.2} mm, bound {bound:.2} mm, ratio {:.3}",
        d.darts.len(),
        total / bound
    );
    assert!(bound > 0.0);
    // Openings are chords of the flat rim (radius ≈ 48 mm, mouths ≈ 10 mm): 0.2 % under arcs.
    assert!(
        total >= 0.99 * bound,
        "total {total} below the bound {bound}"
    );
    assert!(total <= 1.3 * bound, "total {total}, bound {bound}");
    // The fewest darts the placement rule allows: the count below was tried and broke the limits
    // (no count below the result held), so no dart is cut that the limits do not need.
    let k = d.darts.len();
    eprintln!("attempts: {:?}", d.attempts);
    assert!(
        k == 1 || d.attempts.iter().any(|a| a.darts == k - 1 && !a.feasible),
        "{k} darts, attempts {:?}",
        d.attempts
    );
    assert!(
        d.attempts
            .iter()
            .filter(|a| a.darts < k)
            .all(|a| !a.feasible),
        "{:?}",
        d.attempts
    );
}
