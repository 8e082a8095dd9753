//! How the final map of a darted piece uses the material's give ([`DartFit`]).
//!
//! Within the limits a darted piece has many maps. The least-strained one (Duncan's δ2 within
//! the limits, the default) keeps the material as near its 3D size as the darts allow, so the
//! sewn part carries the least strain. The tight one spends the give the limits allow on
//! drawing every dart shut as far as it will go: the darts open least and take away the least
//! material, and the material sits at its limits around them, as a leather lasted over its form
//! or a prepreg draped onto its tool does. On a spherical cap of radius 50 mm and geodesic
//! radius 1 rad at ±3 %, the same darts open 41.2 mm in all least-strained and 34.6 mm tight
//! (four darts, 1,944 faces; three darts on the bench's 20k cap: 42.5 and 35.9 mm), against
//! the 32.4 mm the limits allow at the very least (`tests/opening.rs` derives that bound).
//!
//! The tight map is the least of δ2 plus a [`Pull`] of zero rest length between the two corners
//! of every dart's mouth, within the limits ([`closing`]). A pull's energy k·d² (d in mm) and
//! δ2's (a density times an area in mm²) scale alike with the piece, so its weight is a plain
//! number; at the first of [`CLOSE_WEIGHTS`] the limits, not the weight, stop the darts (the
//! 20k cap's open 35.9 mm at weights 10 and 100, 36.2 mm at 1, 39.2 mm at 0.1).
//!
//! A dart drawn shut can close past its mouth, its legs crossing, or have its legs pulled to
//! different lengths. The legs are kept from crossing by guards ([`Closing::guards`]). Where a
//! guard next to the point is on its boundary, the legs lie on one line there: the dart takes
//! nothing away from there on and is longer than the tight map needs, and the guard stops the
//! solver. The dart then ends where it was drawn shut ([`shut_points`]) and the piece is drawn
//! tight again (the bench's 140° cap at ±3 %: five darts 527.6 mm long instead of 539.2).
//! Where ending it there would break the limits, the dart is let go (its pull dropped) and the
//! others are drawn tight. Where the legs still part or cross, the next, weaker weight is tried
//! (the bench's toe holds its legs at 1, not at 10), and a piece none of them draws tight keeps
//! its least-strained map and says so.

use flatcut_flatten::nonlinear::newton::Pull;
use flatcut_geom::DVec2;

use crate::cut::Legs;
use crate::sewn::Closing;

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

/// Weights of the pulls that draw the darts shut (dimensionless; see the module docs), in the
/// order they are tried: the first whose map keeps every dart's legs paired and the outline
/// simple is kept.
pub const CLOSE_WEIGHTS: [f64; 3] = [10.0, 1.0, 0.1];

/// The closing of a tight map from the map `x`: one pull per dart between the two corners of its
/// mouth (the first vertices of its legs), and for every other pair of copies along the legs a
/// guard, the triangle of the dart's point and the two copies, which turns over when the legs
/// cross there. Pulling every pair of copies instead crossed the legs next to the point, where
/// they run close; the mouth's pull alone crossed them there too on a cap with three darts.
pub fn closing(legs: &[Legs], x: &[DVec2], weights: &[f64]) -> Closing {
    let mut out = Closing::default();
    for (l, &weight) in legs.iter().zip(weights) {
        let [a, b] = &l.sides;
        let (Some(&point), Some(&ma), Some(&mb)) = (a.last(), a.first(), b.first()) else {
            continue;
        };
        if ma != mb && weight > 0.0 {
            out.pulls.push(Pull {
                a: ma as usize,
                b: mb as usize,
                k: weight,
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

/// Below this sine of the angle that two copies of a leg vertex make at their dart's point, the
/// guard between them is on its boundary: the legs lie on one line there, and the tight map would
/// close the dart further if the guard let it.
pub const SHUT_SINE: f64 = 1e-6;
/// Two copies of a leg vertex closer than this fraction of their distance from the dart's point
/// (the angle, in radians, the dart opens there) are one point of the pattern: merging them
/// strains the faces next to them by about half of it.
pub const SHUT_ANGLE: f64 = 0.05;

/// Per dart, where a tight map `x` has drawn it shut: the index along its legs (mouth first) of
/// the farthest pair of copies from the point whose guard is on its boundary, every pair from
/// there to the point within [`SHUT_ANGLE`] (the legs may cross a little next to the point,
/// where their guards hold them as the first map had them); `None` where the dart is open up
/// to its point.
/// From there on the dart takes nothing away, and its guards stop the solver (a step along
/// them turns a guard over, so every step is cut to nothing): the dart is shorter than the
/// tight map needs, and ends there instead (`0`: at its mouth, so it is not needed at all).
pub fn shut_points(legs: &[Legs], x: &[DVec2]) -> Vec<Option<usize>> {
    legs.iter()
        .map(|l| {
            let [a, b] = &l.sides;
            let point = x[*a.last()? as usize];
            let mut shut = None;
            for i in (0..a.len().min(b.len()).saturating_sub(1)).rev() {
                let (p, q) = (x[a[i] as usize], x[b[i] as usize]);
                let (u, v) = (p - point, q - point);
                if p.distance(q) > SHUT_ANGLE * u.length().min(v.length()) {
                    break;
                }
                if on_one_line(u, v) {
                    shut = Some(i);
                }
            }
            shut
        })
        .collect()
}

/// Per dart, whether a guard of its legs is on its boundary in the map `x` (the two copies on
/// one line with the point): the solver can take no step that draws it further shut.
pub fn jammed(legs: &[Legs], x: &[DVec2]) -> Vec<bool> {
    legs.iter()
        .map(|l| {
            let [a, b] = &l.sides;
            let Some(&point) = a.last() else {
                return false;
            };
            let point = x[point as usize];
            a.iter()
                .zip(b)
                .rev()
                .skip(1)
                .any(|(&p, &q)| on_one_line(x[p as usize] - point, x[q as usize] - point))
        })
        .collect()
}

/// True when two copies, at `u` and `v` from their dart's point, lie on one line with it (within
/// [`SHUT_SINE`]): the guard through them is on its boundary.
fn on_one_line(u: DVec2, v: DVec2) -> bool {
    let scale = u.length() * v.length();
    scale > 0.0 && u.perp_dot(v).abs() <= SHUT_SINE * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dart whose legs lie on one line for their last two pairs before the point, each pair
    /// within the angle: it is shut from the farther of them; a pair apart by more than the
    /// angle, or at an angle of its own, is not.
    #[test]
    fn a_dart_drawn_shut_next_to_its_point_is_found() {
        let mut x: Vec<DVec2> = [(0.0, 0.0), (3.0, 0.6), (2.0, 0.0), (1.0, 0.0)]
            .into_iter()
            .chain([(3.0, -0.6), (2.004, 0.0), (1.002, 0.0)])
            .map(|(a, b)| DVec2::new(a, b))
            .collect();
        let legs = [Legs {
            sides: [vec![1, 2, 3, 0], vec![4, 5, 6, 0]],
        }];
        assert_eq!(shut_points(&legs, &x), vec![Some(1)]);
        assert_eq!(jammed(&legs, &x), vec![true]);
        // The farther pair apart by more than the angle: shut from the nearer one only.
        x[5].x = 2.0 * (1.0 + 1.5 * SHUT_ANGLE);
        assert_eq!(shut_points(&legs, &x), vec![Some(2)]);
        // The nearer pair at an angle (open) and the farther one beyond the angle: open.
        x[6].y = -1e-3;
        assert_eq!(shut_points(&legs, &x), vec![None]);
        // Not shut, but the farther pair still on one line with the point: stuck.
        assert_eq!(jammed(&legs, &x), vec![true]);
        x[5].y = 0.05;
        assert_eq!(jammed(&legs, &x), vec![false]);
        // The whole dart shut, the mouth's corners on one point.
        let shut: Vec<DVec2> = (0..7)
            .map(|i| DVec2::new([0.0, 3.0, 2.0, 1.0, 3.0, 2.0, 1.0][i], 0.0))
            .collect();
        assert_eq!(shut_points(&legs, &shut), vec![Some(0)]);
    }

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
            let c = closing(&[Legs { sides }], &x, &[2.0]);
            assert_eq!(c.pulls.len(), 1);
            let p = c.pulls[0];
            assert_eq!([p.a.min(p.b), p.a.max(p.b)], [1, 4]);
            assert_eq!(p.k, 2.0);
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
