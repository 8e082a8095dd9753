//! How the final map of a darted piece uses the material's give ([`DartFit`]).
//!
//! Within the limits a darted piece has many maps. The least-strained one (Duncan's δ2 within
//! the limits, the default) keeps the material as near its 3D size as the darts allow, so the
//! sewn part carries the least strain. The tight one spends the give the limits allow on
//! drawing every dart shut as far as it will go: the darts open least and take away the least
//! material, and the material sits at its limits around them, as a leather lasted over its form
//! or a prepreg draped onto its tool does. On a spherical cap of radius 50 mm and geodesic
//! radius 1 rad at ±3 %, the same darts open 41.2 mm in all least-strained and 35.3 mm tight
//! (four darts, 1,944 faces; three darts on the bench's 20k cap: 42.5 and 35.9 mm), against
//! the 32.4 mm the limits allow at the very least (`tests/opening.rs` derives that bound).
//!
//! The tight map is the least of δ2 plus a [`Pull`] of zero rest length between the two corners
//! of every dart's mouth, within the limits ([`closing`]). A pull's energy k·d² (d in mm) and
//! δ2's (a density times an area in mm²) scale alike with the piece, so the weight
//! [`CLOSE_WEIGHT`] is a plain number; at it the limits, not the weight, stop the darts (the
//! 20k cap's open 35.9 mm at weights 10 and 100, 36.2 mm at 1, 39.2 mm at 0.1).
//!
//! A dart drawn shut can close past its mouth, its legs crossing, or have its legs pulled to
//! different lengths; the legs are kept from crossing by guards ([`Closing::guards`]), and a
//! tight map whose legs still part or cross is not kept: the piece keeps its least-strained
//! map and says so (the bench's 20k toe at ±3 %: legs 0.37 mm apart).

use flatcut_flatten::nonlinear::newton::Pull;
use flatcut_geom::DVec2;

use crate::cut::Legs;

/// How the final map of a darted piece uses the material's give.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DartFit {
    /// The least-strained map within the limits (Duncan's δ2).
    #[default]
    LeastStrain,
    /// The darts drawn shut as far as the limits let them.
    Tight,
}

impl DartFit {
    /// The command-line names.
    pub fn name(self) -> &'static str {
        match self {
            DartFit::LeastStrain => "least-strain",
            DartFit::Tight => "tight",
        }
    }

    /// Parses a command-line name.
    pub fn from_name(s: &str) -> Option<Self> {
        [DartFit::LeastStrain, DartFit::Tight]
            .into_iter()
            .find(|f| f.name() == s)
    }
}

/// Weight of a pull that draws a dart shut (dimensionless; see the module docs).
pub const CLOSE_WEIGHT: f64 = 10.0;

/// What draws a piece's darts shut: pulls on the darts' mouths, and guards that keep their legs
/// from crossing. Empty for the least-strained fit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Closing {
    pub pulls: Vec<Pull>,
    /// Triangles (counter-clockwise in the map the closing is made for) that must not turn over.
    pub guards: Vec<[usize; 3]>,
}

/// The closing of a tight map from the map `x`: one pull per dart between the two corners of its
/// mouth (the first vertices of its legs), and for every other pair of copies along the legs a
/// guard, the triangle of the dart's point and the two copies, which turns over when the legs
/// cross there. Pulling every pair of copies instead crossed the legs next to the point, where
/// they run close; the mouth's pull alone crossed them there too on a cap with three darts.
pub fn closing(legs: &[Legs], x: &[DVec2]) -> Closing {
    let mut out = Closing::default();
    for l in legs {
        let [a, b] = &l.sides;
        let (Some(&point), Some(&ma), Some(&mb)) = (a.last(), a.first(), b.first()) else {
            continue;
        };
        if ma != mb {
            out.pulls.push(Pull {
                a: ma as usize,
                b: mb as usize,
                k: CLOSE_WEIGHT,
            });
        }
        for (&p, &q) in a.iter().zip(b) {
            let v = [point as usize, p as usize, q as usize];
            if p == q || v[0] == v[1] || v[0] == v[2] {
                continue;
            }
            let turn = (x[v[1]] - x[v[0]]).perp_dot(x[v[2]] - x[v[0]]);
            if turn > 0.0 {
                out.guards.push(v);
            } else if turn < 0.0 {
                out.guards.push([v[0], v[2], v[1]]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dart along −x from its mouth (x = 3) to its point (the origin): one pull between the
    /// mouth's corners, a guard for every other pair of copies, each counter-clockwise in the
    /// map whichever side its legs lie on, none at the point.
    #[test]
    fn a_tight_closing_pulls_the_mouth_and_guards_the_legs() {
        // Vertex 0 is the point; 1–3 one leg (y > 0), 4–6 the other (y < 0), mouth first.
        let x: Vec<DVec2> = [(0.0, 0.0), (3.0, 0.6), (2.0, 0.4), (1.0, 0.2)]
            .into_iter()
            .chain([(3.0, -0.6), (2.0, -0.4), (1.0, -0.2)])
            .map(|(a, b)| DVec2::new(a, b))
            .collect();
        for sides in [
            [vec![1, 2, 3, 0], vec![4, 5, 6, 0]],
            [vec![4, 5, 6, 0], vec![1, 2, 3, 0]],
        ] {
            let c = closing(&[Legs { sides }], &x);
            assert_eq!(c.pulls.len(), 1);
            let p = c.pulls[0];
            assert_eq!([p.a.min(p.b), p.a.max(p.b)], [1, 4]);
            assert_eq!(c.guards.len(), 3);
            for g in &c.guards {
                assert_eq!(g[0], 0);
                assert!(
                    (x[g[1]] - x[g[0]]).perp_dot(x[g[2]] - x[g[0]]) > 0.0,
                    "{g:?}"
                );
            }
        }
    }
}
