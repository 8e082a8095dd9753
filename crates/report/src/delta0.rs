//! Duncan's global distortion δ0 = log(s2/s1) (thesis Def. 6.7–6.10): s1 and s2 are the least and
//! the greatest ratio of two points' distance in the flat piece to their distance on the surface.
//!
//! Both distances are intrinsic: on the surface the geodesic distance (the shortest path over the
//! surface), in the flat piece the shortest path inside the piece, which is straight only where
//! the piece is convex. Duncan writes the plane's distance d_E; for a convex piece the two agree.
//! For a piece that is not convex (an unrolled cone is an annular sector, a cut may leave an L)
//! the cloth's distances are the ones inside it: a straight line across a notch is no distance of
//! the material, and measured that way an exact unrolling would count as distorted.
//!
//! With intrinsic distances on both sides δ0 is computed exactly, in one pass over the faces. The
//! surface is the mesh (a polyhedral surface) and the flat piece is the same triangles at their 2D
//! positions; the map f between them is linear on each face, with principal stretches σ1 ≥ σ2.
//! Then
//!
//!   s2 = max over faces of σ1,   s1 = min over faces of σ2.
//!
//! *Proof.* A path γ on the surface maps face by face to a path f∘γ in the piece at most
//! max σ1 times as long, and the distance in the piece is at most the length of f∘γ; taking the
//! infimum over γ, d_F(f(p), f(q)) ≤ max σ1 · d_S(p, q). The same argument for f⁻¹ (on each face
//! the inverse linear map, whose largest stretch is 1/σ2) gives d_S ≤ d_F / min σ2. Both bounds
//! are attained: two points inside the face of the largest σ1 (the smallest σ2), apart along that
//! face's principal direction, are joined by the straight segment in the face and by its image in
//! the piece, and no path is shorter than the straight chord, so their ratio is that σ exactly. ∎
//!
//! So the figure is exact for the mesh as given (the only error is the floating-point rounding of
//! each face's singular values, far below 1e-12), costs O(faces), and no geodesic needs to be
//! computed; `delta0_method` says `exact` and `delta0_error_bound` is 0. A flipped or collapsed
//! face folds the piece over itself: δ0 is +∞ (s1 = 0), as for any folded map. The independent
//! check of the theorem (geodesic distances on the surface and in the flat piece, pair by pair)
//! is in the tests.

use crate::face::FaceMeasure;

/// How δ0 was obtained (the JSON's `delta0_method`): exactly, from the faces' extreme stretches.
pub const METHOD_EXACT: &str = "exact";

/// δ0 with its two extreme distance ratios.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Delta0 {
    /// log(s2 / s1); +∞ for a folded piece.
    pub delta0: f64,
    /// The least ratio of intrinsic distances, flat over surface (the smallest σ2).
    pub s1: f64,
    /// The greatest ratio (the largest σ1).
    pub s2: f64,
    /// `METHOD_EXACT`.
    pub method: &'static str,
    /// A bound on |δ0 − the exact figure of the mesh's map| (0: exact).
    pub error_bound: f64,
}

/// δ0 of a map from its faces' measures (see the module documentation).
pub fn delta0(faces: &[FaceMeasure]) -> Delta0 {
    let mut s1 = f64::INFINITY;
    let mut s2: f64 = 0.0;
    let mut folded = false;
    for f in faces {
        folded |= f.flipped;
        s1 = s1.min(f.mu2.sqrt());
        s2 = s2.max(f.mu1.sqrt());
    }
    if folded || faces.is_empty() {
        s1 = 0.0;
    }
    Delta0 {
        delta0: if s1 > 0.0 {
            (s2 / s1).ln()
        } else {
            f64::INFINITY
        },
        s1,
        s2,
        method: METHOD_EXACT,
        error_bound: 0.0,
    }
}
