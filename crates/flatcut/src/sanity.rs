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

/// How far inside the sane range a piece's report must put its extremes for its faces not to be
/// scanned again: a thousandth of the range, far beyond the rounding of the report's percentages.
const REPORT_MARGIN: f64 = 1e-3;

/// True when the piece's report proves every face sane: no flipped face, finite means (a face
/// whose singular values are not numbers makes them NaN) and the largest stretch
/// `(σ1 − 1)·100` and compression `(1 − σ2)·100` of its faces inside the range by
/// [`REPORT_MARGIN`]. The report measured the same faces of the same map.
fn sane_by_report(f: &Flat) -> bool {
    let r = &f.report;
    let inside = |pct: f64, limit_pct: f64| pct < limit_pct * (1.0 - REPORT_MARGIN);
    r.faces == f.mesh.triangles.len()
        && r.flipped == 0
        && r.delta2_mean.is_finite()
        && r.area_mean.is_finite()
        && inside(r.stretch_max_pct, (SANE_MAX - 1.0) * 100.0)
        && inside(r.compress_max_pct, (1.0 - SANE_MIN) * 100.0)
}

/// The pieces whose maps leave the sane range (see the module documentation). A piece whose
/// report already proves it sane is not scanned face by face again.
pub fn insane(flats: &[Flat]) -> Vec<Insane> {
    let mut out = Vec::new();
    for f in flats {
        if !sane_by_report(f)
            && let Some(i) = scan(f)
        {
            out.push(i);
        }
    }
    out
}

/// The piece's faces outside the sane range, face by face; `None` when there is none.
fn scan(f: &Flat) -> Option<Insane> {
    let m = &f.mesh;
    let uv = m.flat.as_deref()?;
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
    worst.map(|(_, sigma, at)| Insane {
        piece: f.name.clone(),
        faces,
        sigma,
        at,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec2;
    use flatcut_report::{Report, ReportOptions};

    /// A flat 60 × 60 mm grid piece whose map scales x by `sx` up to `x = split` (and keeps the
    /// lengths beyond) and y by `sy` everywhere, reported as `flatten` reports it.
    fn piece(name: &str, sx: f64, sy: f64, split: f64) -> Flat {
        let mut mesh = flatcut_mesh::test_grid::grid_mesh(6, 6, |i, j| {
            DVec3::new(i as f64 * 10.0, j as f64 * 10.0, 0.0)
        });
        let uv = mesh
            .positions
            .iter()
            .map(|p| {
                let x = if p.x <= split {
                    p.x * sx
                } else {
                    split * sx + (p.x - split)
                };
                DVec2::new(x, p.y * sy)
            })
            .collect();
        mesh.flat = Some(uv);
        let report = Report::compute(name, &mesh, &ReportOptions::default()).unwrap();
        Flat {
            name: name.into(),
            def: None,
            mesh,
            report,
            quantity: 1,
            mirrored: 0,
            notches: Vec::new(),
            info: None,
            darts: Vec::new(),
            grain: None,
            grain_dir: None,
            times: Default::default(),
            despike: None,
        }
    }

    #[test]
    fn a_piece_is_judged_as_by_the_scan_of_its_faces() {
        let pieces = [
            // Sane with room: the report proves it, no face is scanned.
            (piece("sane", 3.0, 0.5, 60.0), true),
            // Stretched twentyfold on a strip: insane.
            (piece("stretched", 20.0, 1.0, 20.0), false),
            // Squashed to a twentieth across: insane.
            (piece("squashed", 1.0, 0.05, 60.0), false),
            // Inside the range, but closer to its end than the report's margin: scanned, sane.
            (piece("close", SANE_MAX * (1.0 - 1e-5), 1.0, 60.0), false),
            // Mirrored: the report counts every face flipped, the scan finds them sane.
            (piece("mirrored", -1.0, 1.0, 60.0), false),
        ];
        for (p, by_report) in &pieces {
            assert_eq!(sane_by_report(p), *by_report, "{}", p.name);
            assert_eq!(
                insane(std::slice::from_ref(p)),
                scan(p).into_iter().collect::<Vec<_>>()
            );
        }
        let all: Vec<Flat> = pieces.iter().map(|(p, _)| p.clone()).collect();
        let found = insane(&all);
        let names: Vec<&str> = found.iter().map(|i| i.piece.as_str()).collect();
        assert_eq!(names, ["stretched", "squashed"]);
        assert_eq!(found[0].faces, 2 * 6 * 2);
        assert!((found[0].sigma - 20.0).abs() < 1e-9);
        assert_eq!(found[1].faces, 6 * 6 * 2);
        assert!((found[1].sigma - 0.05).abs() < 1e-9);
    }
}
