//! A grain line for a piece whose grain is a direction rather than a drawn line: the thread
//! direction a material's flattening chose (`grain = "auto"`) or fixed along the map's axis.

use flatcut_geom::DVec2;

use crate::poly;

/// The share of the chord the drawn grain line covers, centred on the chord: long enough to
/// lay a rule along, short of the sew line at both ends.
const CHORD_SHARE: f64 = 0.7;

/// Parallel chords tried when the piece's centroid is outside it (a crescent, an L).
const SCAN_CHORDS: usize = 32;

/// The grain line of `outline` along `dir`: the middle `CHORD_SHARE` of the chord along
/// `dir` through the area centroid, or, when the centroid is outside the piece, of the longest
/// of `SCAN_CHORDS` parallel chords. `None` for a degenerate outline or direction.
pub fn grain_line_along(outline: &[DVec2], dir: DVec2) -> Option<(DVec2, DVec2)> {
    let d = dir.try_normalize()?;
    if outline.len() < 3 {
        return None;
    }
    let chord = |p: DVec2| -> Option<(DVec2, DVec2)> {
        let ahead = poly::ray_hit(outline, p, d)?;
        let behind = poly::ray_hit(outline, p, -d)?;
        Some((p - d * behind, p + d * ahead))
    };
    let centre = flatcut_geom::polygon::area_centroid(outline)?;
    let (a, b) = if poly::contains(outline, centre) {
        chord(centre)?
    } else {
        let n = d.perp();
        let (lo, hi) = outline
            .iter()
            .map(|p| p.dot(n))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| {
                (l.min(s), h.max(s))
            });
        // Points on the line through `centre` along `n`, one per chord offset; each chord is
        // taken from the inside point nearest to `centre` along it.
        (0..SCAN_CHORDS)
            .filter_map(|k| {
                let s = lo + (hi - lo) * (k as f64 + 0.5) / SCAN_CHORDS as f64;
                let base = centre + n * (s - centre.dot(n));
                inside_on_line(outline, base, d).and_then(chord)
            })
            .max_by(|x, y| x.0.distance(x.1).total_cmp(&y.0.distance(y.1)))?
    };
    let (mid, half) = ((a + b) * 0.5, (b - a) * 0.5 * CHORD_SHARE);
    (half.length() > 0.0).then(|| (mid - half, mid + half))
}

/// A point inside `outline` on the line `base + s·d`: the midpoint of the first span the line
/// spends inside, found from its crossings with the outline.
fn inside_on_line(outline: &[DVec2], base: DVec2, d: DVec2) -> Option<DVec2> {
    let n = outline.len();
    let mut s: Vec<f64> = (0..n)
        .filter_map(|i| {
            let (a, b) = (outline[i], outline[(i + 1) % n]);
            let e = b - a;
            let den = d.perp_dot(e);
            if den.abs() < 1e-15 {
                return None;
            }
            let qp = a - base;
            let u = qp.perp_dot(d) / den;
            (0.0..1.0).contains(&u).then(|| qp.perp_dot(e) / den)
        })
        .collect();
    s.sort_by(f64::total_cmp);
    s.windows(2)
        .map(|w| base + d * (0.5 * (w[0] + w[1])))
        .find(|&p| poly::contains(outline, p))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn a_rectangles_grain_runs_through_its_centre_over_most_of_its_length() {
        let r = [v(0., 0.), v(200., 0.), v(200., 100.), v(0., 100.)];
        let (a, b) = grain_line_along(&r, DVec2::X).unwrap();
        assert!((a - v(30., 50.)).length() < 1e-9 && (b - v(170., 50.)).length() < 1e-9);
        let (a, b) = grain_line_along(&r, v(0., -3.)).unwrap();
        assert!((a - v(100., 85.)).length() < 1e-9 && (b - v(100., 15.)).length() < 1e-9);
    }

    #[test]
    fn a_crescents_grain_lies_inside_it() {
        // A C shape: its centroid is in the mouth, outside the piece.
        let c = [
            v(0., 0.),
            v(100., 0.),
            v(100., 20.),
            v(20., 20.),
            v(20., 80.),
            v(100., 80.),
            v(100., 100.),
            v(0., 100.),
        ];
        for dir in [DVec2::X, DVec2::Y] {
            let (a, b) = grain_line_along(&c, dir).unwrap();
            for k in 0..=20 {
                let p = a.lerp(b, k as f64 / 20.0);
                assert!(poly::contains(&c, p), "{dir}: {p} outside");
            }
            assert!(a.distance(b) > 0.6 * 100.0, "{dir}: {}", a.distance(b));
        }
    }

    #[test]
    fn no_grain_line_without_a_direction_or_an_outline() {
        let r = [v(0., 0.), v(1., 0.), v(1., 1.)];
        assert_eq!(grain_line_along(&r, DVec2::ZERO), None);
        assert_eq!(grain_line_along(&r[..2], DVec2::X), None);
    }
}
