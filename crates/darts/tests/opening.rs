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
//! s: a map that spends all the give the limits allow on closing the darts. The tight fit
//! ([`DartFit::Tight`]) is that map for the darts placed; it opens them 1.07 W (R = 50 mm,
//! α = 1 rad, 3 %/3 %: 4 darts, 34.6 mm against W = 32.4 mm), within the 20 % asked, the rest
//! being what four darts that end short of the centre cost over a continuum of them. The
//! default, least-strained fit leaves the material nearer its 3D size and opens the same darts
//! more (1.27 W, 41.2 mm): held with a little room, as a guard. Both must stay above the bound
//! (no map may open less: it would break the limits somewhere), and one dart fewer must have
//! been tried and broken the limits.

use flatcut_darts::{DartFit, DartOptions, LEG_MATCH_MM, place};
use flatcut_flatten::testmesh::spherical_cap;
use flatcut_flatten::{FlattenParams, Method, flatten};
use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;

/// Largest total opening of the tight fit over the bound: the 20 %.
const TIGHT_OVER_BOUND: f64 = 1.2;
/// Largest total opening of the least-strained fit over the bound (measured 1.27).
const LEAST_STRAIN_OVER_BOUND: f64 = 1.3;

/// Limits of the tests (percent, both ways).
const PCT: f64 = 3.0;

/// The cap of the tests (radius 50 mm, geodesic radius 1 rad, 1,944 faces), its isometric map,
/// and the bound W (mm) at [`PCT`].
fn cap() -> (TriMesh, Vec<DVec2>, f64) {
    cap_of(1.0, 18)
}

/// A cap of radius 50 mm and geodesic radius `alpha` (rad) with `rings` rings of faces, its
/// isometric map and the bound W (mm) at [`PCT`].
fn cap_of(alpha: f64, rings: usize) -> (TriMesh, Vec<DVec2>, f64) {
    let r = 50.0;
    let mesh = spherical_cap(r, alpha, rings);
    let x0 = flatten(&mesh, &FlattenParams::new(Method::Isometric))
        .unwrap()
        .uv;
    let (s, c) = (PCT / 100.0, PCT / 100.0);
    let bound = std::f64::consts::TAU * r * (alpha * (1.0 - c) - (1.0 + s) * alpha.sin());
    (mesh, x0, bound)
}

#[test]
fn a_tight_fit_opens_the_darts_within_20_percent_of_the_analytic_bound() {
    let (mesh, x0, bound) = cap();
    let opts = DartOptions::new(Some(PCT), Some(PCT));
    let loose = place(&mesh, &x0, &opts).unwrap();
    let tight = place(&mesh, &x0, &opts.clone().with_fit(DartFit::Tight)).unwrap();
    let total = |d: &flatcut_darts::Darted| d.darts.iter().map(|d| d.opening_mm).sum::<f64>();
    let (lt, tt) = (total(&loose), total(&tight));
    eprintln!(
        "{} darts: least strain {lt:.2} mm ({:.3} W), tight {tt:.2} mm ({:.3} W), W {bound:.2} mm",
        tight.darts.len(),
        lt / bound,
        tt / bound
    );
    // The fit changes the final map only: the same darts.
    assert_eq!(tight.darts.len(), loose.darts.len());
    for (a, b) in tight.darts.iter().zip(&loose.darts) {
        assert_eq!(a.path, b.path);
    }
    assert_eq!(tight.fit, DartFit::Tight, "the tight map was not kept");
    assert!(tight.feasible && tight.excess <= 0.0, "{}", tight.excess);
    for d in &tight.darts {
        let [a, b] = d.leg_2d_mm;
        assert!((a - b).abs() <= LEG_MATCH_MM, "legs {a} / {b}");
    }
    assert!(tt >= 0.99 * bound, "tight {tt} below the bound {bound}");
    assert!(tt <= TIGHT_OVER_BOUND * bound, "tight {tt}, bound {bound}");
    assert!(tt < lt, "tight {tt} not below least strain {lt}");
}

#[test]
fn total_opening_on_a_spherical_cap_holds_the_analytic_bound() {
    let (mesh, x0, bound) = cap();
    let d = place(&mesh, &x0, &DartOptions::new(Some(PCT), Some(PCT))).unwrap();
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
    assert!(
        total <= LEAST_STRAIN_OVER_BOUND * bound,
        "total {total}, bound {bound}"
    );
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

/// Deeper caps, 70° to 90° (the bench's 140° cap is the first): the tight fit holds the bound
/// there too, within the limits with the legs paired, and its darts are no longer than the
/// least-strained fit's. On the 80° cap it draws darts shut before their points and ends them
/// there: 269.6 mm of darts instead of 273.3, opening 1.089 W (1.099 W, the darts as placed,
/// without the shortening).
#[test]
fn a_tight_fit_holds_the_bound_on_deeper_caps() {
    let total = |d: &flatcut_darts::Darted| d.darts.iter().map(|d| d.opening_mm).sum::<f64>();
    let length = |d: &flatcut_darts::Darted| d.darts.iter().map(|d| d.length_3d_mm).sum::<f64>();
    for (alpha, rings) in [(1.2217, 18), (1.4, 24), (std::f64::consts::FRAC_PI_2, 24)] {
        let (mesh, x0, bound) = cap_of(alpha, rings);
        let opts = DartOptions::new(Some(PCT), Some(PCT));
        let loose = place(&mesh, &x0, &opts).unwrap();
        let tight = place(&mesh, &x0, &opts.clone().with_fit(DartFit::Tight)).unwrap();
        let (lt, tt) = (total(&loose), total(&tight));
        let (ll, tl) = (length(&loose), length(&tight));
        eprintln!(
            "α {alpha}: {} darts, least strain {lt:.2} mm ({:.3} W) {ll:.1} mm long, tight {tt:.2} mm ({:.3} W) {tl:.1} mm long, W {bound:.2} mm",
            tight.darts.len(),
            lt / bound,
            tt / bound
        );
        assert_eq!(
            tight.fit,
            DartFit::Tight,
            "α {alpha}: the tight map was not kept"
        );
        assert!(
            tight.feasible && tight.excess <= 0.0,
            "α {alpha}: {}",
            tight.excess
        );
        for d in &tight.darts {
            let [a, b] = d.leg_2d_mm;
            assert!((a - b).abs() <= LEG_MATCH_MM, "α {alpha}: legs {a} / {b}");
        }
        assert!(
            tt >= 0.99 * bound,
            "α {alpha}: tight {tt} below the bound {bound}"
        );
        assert!(
            tt <= TIGHT_OVER_BOUND * bound,
            "α {alpha}: tight {tt}, bound {bound}"
        );
        assert!(tt < lt, "α {alpha}: tight {tt} not below least strain {lt}");
        assert!(
            tl <= ll + 1e-9,
            "α {alpha}: tight darts {tl} mm, least strain {ll} mm"
        );
        if alpha == 1.4 {
            assert!(
                tl < ll - 0.5,
                "α {alpha}: no dart was shortened ({tl} / {ll} mm)"
            );
        }
    }
}
