//! What holds a dart's two legs together in a solve, made by the cut and the fit and used by the
//! solve (a module below all three): the pairs of edges that must keep equal 2D lengths
//! ([`EdgePairs`]) and the pulls and guards that draw the darts shut ([`Closing`]).

use flatcut_flatten::nonlinear::newton::Pull;
use flatcut_geom::DVec2;
use std::ops::Range;

/// Pairs of edges (vertex index pairs of the cut mesh) that must keep equal 2D lengths: the two
/// copies of one cut edge, one on each leg of a dart.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EdgePairs {
    /// Each pair: two edges as (from, to) vertex indices (0-based) of the cut mesh, one per
    /// leg, both directed from the mouth towards the point.
    pub pairs: Vec<[(usize, usize); 2]>,
    /// The pairs of each dart's legs: `pairs[legs[k]]` (a dart's legs are sewn as a whole).
    pub legs: Vec<Range<usize>>,
}

impl EdgePairs {
    /// The largest difference of a dart's two legs' 2D lengths (mm).
    pub fn worst_leg_mismatch(&self, x: &[DVec2]) -> f64 {
        self.worst_legs(x).map_or(0.0, |(_, d)| d)
    }

    /// The dart whose legs differ most in 2D length, and by how much (mm); `None` without darts.
    pub fn worst_legs(&self, x: &[DVec2]) -> Option<(usize, f64)> {
        self.legs
            .iter()
            .map(|r| {
                self.pairs[r.clone()]
                    .iter()
                    .map(|[(a, b), (c, d)]| x[*a].distance(x[*b]) - x[*c].distance(x[*d]))
                    .sum::<f64>()
                    .abs()
            })
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// What draws a piece's darts shut: pulls on the darts' mouths, and guards that keep their legs
/// from crossing. Empty for the least-strained fit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Closing {
    /// One pull per dart drawn shut.
    pub pulls: Vec<Pull>,
    /// Triangles (counter-clockwise in the map the closing is made for) that must not turn over.
    pub guards: Vec<[usize; 3]>,
}
