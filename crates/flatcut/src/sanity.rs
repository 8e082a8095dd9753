//! Whether a flattened piece is sane: every face's singular values (its stretch factors) within
//! [[`SANE_MIN`], [`SANE_MAX`]]. A map outside them is not a pattern but a solver that lost its
//! piece (a seam forced twice as long as its edge, a face squashed into a sliver): it is named
//! with its piece and where it sits, and the command exits with the limits' code, never 0.

use flatcut_geom::DVec3;
use flatcut_mesh::distortion::face_distortion;

use crate::flat::Flat;

/// The smallest singular value a sane face may have (shrunk to a tenth).
pub const SANE_MIN: f64 = 0.1;
/// The largest (stretched tenfold).
pub const SANE_MAX: f64 = 10.0;

/// A piece whose map leaves the sane range.
#[derive(Clone, Debug, PartialEq)]
pub struct Insane {
    /// The piece's name.
    pub piece: String,
    /// Faces outside the range.
    pub faces: usize,
    /// The worst singular value (the one farthest outside, in ratio).
    pub sigma: f64,
    /// Where the worst face is, in 3D.
    pub at: DVec3,
}

impl std::fmt::Display for Insane {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {} face(s) flattened beyond the sane range [{SANE_MIN}, {SANE_MAX}] of stretch factors, the worst by {:.4} at 3D ({:.1}, {:.1}, {:.1}): the joint solve could not keep the piece sane",
            self.piece, self.faces, self.sigma, self.at.x, self.at.y, self.at.z
        )
    }
}

/// The pieces whose maps leave the sane range (see the module documentation).
pub fn insane(flats: &[Flat]) -> Vec<Insane> {
    let mut out = Vec::new();
    for f in flats {
        let m = &f.mesh;
        let Some(uv) = m.flat.as_deref() else {
            continue;
        };
        let mut faces = 0;
        let mut worst: Option<(f64, f64, DVec3)> = None;
        for t in &m.triangles {
            let p = t.map(|v| m.positions[v as usize]);
            let q = t.map(|v| uv[v as usize]);
            let Some(d) = face_distortion(p, q) else {
                continue;
            };
            // How far outside, as a ratio (1 inside).
            let off = (d.sigma1 / SANE_MAX).max(SANE_MIN / d.sigma2.max(f64::MIN_POSITIVE));
            if off > 1.0 {
                faces += 1;
                let sigma = if d.sigma1 > SANE_MAX {
                    d.sigma1
                } else {
                    d.sigma2
                };
                if worst.is_none_or(|w| off > w.0) {
                    worst = Some((off, sigma, (p[0] + p[1] + p[2]) / 3.0));
                }
            }
        }
        if let Some((_, sigma, at)) = worst {
            out.push(Insane {
                piece: f.name.clone(),
                faces,
                sigma,
                at,
            });
        }
    }
    out
}
