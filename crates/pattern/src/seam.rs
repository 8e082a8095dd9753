//! Seam allowance: the cut line is the sew line pushed outward by a width per boundary edge,
//! with pattern-maker corner styles.
//!
//! Construction: the allowance region is the union of the sew polygon, one strip per sew edge
//! (the edge swept outward by its width) and one corner patch per convex vertex whose shape
//! is the corner style. The union is computed by `geo`'s boolean operations (i_overlay, integer
//! robust), which resolves every overlap a concave outline or a narrow neck produces, without
//! the cusp/loop trimming a hand-rolled offset needs. The per-edge construction is what lets the
//! width change from seam to seam (0 on a fold) — a uniform offset engine cannot. The call is
//! guarded with `catch_unwind`, and the result is validated independently: one closed simple
//! ring, no trapped holes, every sew point inside, and no cut point closer to a sew edge than
//! that edge's width.

use crate::poly;
use flatcut_geom::DVec2;
use geo::{Coord, LineString, Polygon};

/// How the allowance is closed at a convex corner of the sew line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CornerStyle {
    /// The two cut lines are extended until they meet (up to the mitre limit, then squared).
    #[default]
    Mitred,
    /// The corner is cut square to the bisector at the larger width from the sew corner.
    Squared,
    /// The allowance of the incoming seam ends on the mirror image of the outgoing sew line
    /// (as it lies when the allowance is folded back along the incoming seam), so the folded
    /// allowance matches the neighbouring seam: Seamly2D's "by first edge symmetry".
    Reflected,
}

/// A mitre longer than this many widths is squared off instead (the usual CAD mitre limit; a
/// 4× mitre is reached at a turn of about 150°).
pub const DEFAULT_MITRE_LIMIT: f64 = 4.0;
/// Holes in the allowance region smaller than this (mm²) are numerical slivers, not trapped
/// material.
const HOLE_AREA_EPS: f64 = 1e-3;
/// Corner patches of vertices turning less than this (radians) are skipped for equal widths:
/// the neighbouring strips already overlap within this chord sagitta.
const TURN_EPS: f64 = 1e-9;

/// Result of the offset: the cut ring (CCW, no repeated end point).
#[derive(Clone, Debug)]
pub struct SeamResult {
    pub cut: Vec<DVec2>,
}

/// Reason an allowance could not be built (mapped to `PatternError` by the caller).
#[derive(Clone, Debug)]
pub enum SeamFailure {
    TooLarge(String),
    Engine(String),
}

fn right_normal(d: DVec2) -> DVec2 {
    DVec2::new(d.y, -d.x)
}

fn line_intersect(a: DVec2, da: DVec2, b: DVec2, db: DVec2) -> Option<DVec2> {
    let den = da.perp_dot(db);
    if den.abs() < 1e-12 {
        return None;
    }
    let t = (b - a).perp_dot(db) / den;
    Some(a + da * t)
}

fn push_ccw(out: &mut Vec<Vec<DVec2>>, ring: Vec<DVec2>) {
    let a = poly::signed_area(&ring);
    if a.abs() < 1e-12 {
        return;
    }
    let mut r = ring;
    if a < 0.0 {
        r.reverse();
    }
    out.push(r);
}

/// Builds the cut line of a CCW simple sew polygon `sew` with width `widths[i]` on edge
/// `i` (vertex i → i+1).
pub fn allowance(
    sew: &[DVec2],
    widths: &[f64],
    style: CornerStyle,
    mitre_limit: f64,
    tol: f64,
) -> Result<SeamResult, SeamFailure> {
    let n = sew.len();
    let dir: Vec<DVec2> = (0..n)
        .map(|i| (sew[(i + 1) % n] - sew[i]).normalize_or_zero())
        .collect();
    let mut parts: Vec<Vec<DVec2>> = vec![sew.to_vec()];
    for i in 0..n {
        let w = widths[i];
        if w <= 0.0 || dir[i] == DVec2::ZERO {
            continue;
        }
        let o = right_normal(dir[i]) * w;
        let (a, b) = (sew[i], sew[(i + 1) % n]);
        push_ccw(&mut parts, vec![a, b, b + o, a + o]);
    }
    for i in 0..n {
        let ip = (i + n - 1) % n;
        let (dp, dn) = (dir[ip], dir[i]);
        let (wp, wn) = (widths[ip], widths[i]);
        if (wp <= 0.0 && wn <= 0.0) || dp == DVec2::ZERO || dn == DVec2::ZERO {
            continue;
        }
        let v = sew[i];
        let turn = dp.perp_dot(dn);
        let a = v + right_normal(dp) * wp;
        let b = v + right_normal(dn) * wn;
        if turn <= TURN_EPS && (wp - wn).abs() <= 1e-12 {
            continue; // concave or straight with equal widths: the strips overlap
        }
        if turn <= TURN_EPS {
            push_ccw(&mut parts, vec![v, a, b]);
            continue;
        }
        let wmax = wp.max(wn);
        let mitre = line_intersect(a, dp, b, dn);
        let squared = |parts: &mut Vec<Vec<DVec2>>| {
            // cut perpendicular to the outward bisector at distance wmax from v
            let bis = (right_normal(dp) + right_normal(dn)).normalize_or_zero();
            let q = v + bis * wmax;
            let perp = DVec2::new(-bis.y, bis.x);
            let pa = line_intersect(a, dp, q, perp).unwrap_or(a);
            let pb = line_intersect(b, dn, q, perp).unwrap_or(b);
            push_ccw(parts, vec![v, a, pa, pb, b]);
        };
        match style {
            CornerStyle::Mitred => match mitre {
                Some(m) if m.distance(v) <= mitre_limit * wmax => {
                    push_ccw(&mut parts, vec![v, a, m, b])
                }
                _ => squared(&mut parts),
            },
            CornerStyle::Squared => match mitre {
                Some(m) if m.distance(v) <= wmax * (1.0 + 1e-9) => {
                    push_ccw(&mut parts, vec![v, a, m, b])
                }
                _ => squared(&mut parts),
            },
            CornerStyle::Reflected => {
                // mirror of the outgoing sew direction about the incoming sew line
                let r = 2.0 * dn.dot(dp) * dp - dn;
                let p1 = line_intersect(a, dp, v, r).filter(|p| (*p - a).dot(dp) >= 0.0);
                match p1 {
                    Some(p1) if p1.distance(v) <= mitre_limit * wmax => {
                        let p2 = line_intersect(b, dn, v, r)
                            .filter(|p| {
                                (*p - b).dot(dn) <= 0.0 && p.distance(v) <= mitre_limit * wmax
                            })
                            .unwrap_or_else(|| {
                                // foot of p1 on the outgoing cut line
                                b + dn * (p1 - b).dot(dn)
                            });
                        push_ccw(&mut parts, vec![v, a, p1, p2, b]);
                    }
                    _ => match mitre {
                        Some(m) if m.distance(v) <= mitre_limit * wmax => {
                            push_ccw(&mut parts, vec![v, a, m, b])
                        }
                        _ => squared(&mut parts),
                    },
                }
            }
        }
    }
    check_crossing(sew, widths, tol)?;
    let polys: Vec<Polygon<f64>> = parts
        .iter()
        .map(|r| {
            let ls: Vec<Coord<f64>> = r.iter().map(|p| Coord { x: p.x, y: p.y }).collect();
            Polygon::new(LineString::from(ls), vec![])
        })
        .collect();
    let union = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| geo::unary_union(&polys)))
        .map_err(|_| SeamFailure::Engine("polygon union panicked".into()))?;
    if union.0.is_empty() {
        return Err(SeamFailure::Engine("polygon union is empty".into()));
    }
    if union.0.len() > 1 {
        return Err(SeamFailure::Engine(format!(
            "union split into {} regions",
            union.0.len()
        )));
    }
    let pg = &union.0[0];
    for hole in pg.interiors() {
        let h: Vec<DVec2> = hole.0.iter().map(|c| DVec2::new(c.x, c.y)).collect();
        let area = poly::signed_area(&h).abs();
        if area > HOLE_AREA_EPS {
            let c = h.iter().copied().sum::<DVec2>() / h.len() as f64;
            return Err(SeamFailure::TooLarge(format!(
                "the allowance closes over a concave opening and traps a hole of {area:.1} mm² near ({:.1}, {:.1}) mm; {ADVICE}",
                c.x, c.y
            )));
        }
    }
    let ring: Vec<DVec2> = pg
        .exterior()
        .0
        .iter()
        .map(|c| DVec2::new(c.x, c.y))
        .collect();
    let mut cut = poly::dedup_closed(&ring, 1e-9);
    if poly::signed_area(&cut) < 0.0 {
        cut.reverse();
    }
    cut = drop_collinear(&cut, 1e-9);
    validate(sew, widths, &cut, tol, mitre_limit)?;
    Ok(SeamResult { cut })
}

/// What to do about an allowance that does not fit (the positions in the messages are the
/// piece's own pattern coordinates, as in its SVG).
const ADVICE: &str = "give this piece a narrower seam allowance (its `seam_allowance_mm` in the design, or the command's seam width), or widen the piece there";

/// The allowance of an edge must not reach across the piece: the outward normal from each
/// edge's midpoint must not meet the sew line again within the edge's width. Where it does,
/// the allowance lies over another part of the piece (a slot or neck narrower than the
/// allowance). Corners are excluded by construction (midpoints only), since overlapping
/// allowances at a concave corner are normal and resolved by the union.
fn check_crossing(sew: &[DVec2], widths: &[f64], tol: f64) -> Result<(), SeamFailure> {
    let n = sew.len();
    for i in 0..n {
        let w = widths[i];
        if w <= tol {
            continue;
        }
        let (a, b) = (sew[i], sew[(i + 1) % n]);
        let d = (b - a).normalize_or_zero();
        if d == DVec2::ZERO {
            continue;
        }
        let nrm = right_normal(d);
        let m = (a + b) * 0.5;
        // start just off the own edge so it is not hit at distance 0
        let start = m + nrm * (tol * 1e-3);
        if let Some(s) = poly::ray_hit(sew, start, nrm).filter(|s| *s < w - tol) {
            let q = start + nrm * s;
            return Err(SeamFailure::TooLarge(format!(
                "the {w:.1} mm allowance of the seam near ({:.1}, {:.1}) mm runs across the piece, meeting the sew line again {s:.1} mm away at ({:.1}, {:.1}) mm; {ADVICE}",
                m.x, m.y, q.x, q.y
            )));
        }
    }
    Ok(())
}

fn drop_collinear(p: &[DVec2], eps: f64) -> Vec<DVec2> {
    let n = p.len();
    if n < 4 {
        return p.to_vec();
    }
    let keep: Vec<bool> = (0..n)
        .map(|i| {
            let (a, b, c) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
            poly::seg_nearest(a, c, b).0 > eps
        })
        .collect();
    p.iter()
        .zip(keep)
        .filter(|(_, k)| *k)
        .map(|(q, _)| *q)
        .collect()
}

/// Independent checks of a cut ring against its sew ring.
fn validate(
    sew: &[DVec2],
    widths: &[f64],
    cut: &[DVec2],
    tol: f64,
    mitre_limit: f64,
) -> Result<(), SeamFailure> {
    let bad = |s: String| Err(SeamFailure::Engine(s));
    if cut.len() < 3 {
        return bad("cut line has fewer than 3 points".into());
    }
    if let Some((a, b, x)) = poly::first_self_intersection(cut) {
        return bad(format!(
            "cut line self-intersects (edges {a}, {b} near {:.3}, {:.3})",
            x.x, x.y
        ));
    }
    for q in sew {
        if !poly::contains(cut, *q) && poly::dist_to_closed(cut, *q) > tol {
            return bad(format!(
                "sew point ({:.3}, {:.3}) lies outside the cut line",
                q.x, q.y
            ));
        }
    }
    let n = sew.len();
    let wmax = widths.iter().copied().fold(0.0, f64::max);
    for c in cut {
        // no cut point closer to an edge than its width (it would eat into that seam)
        for i in 0..n {
            let (d, _) = poly::seg_nearest(sew[i], sew[(i + 1) % n], *c);
            if d < widths[i] - tol {
                return bad(format!(
                    "cut point ({:.3}, {:.3}) is {d:.3} mm from edge {i}, narrower than its {:.3} mm allowance",
                    c.x, c.y, widths[i]
                ));
            }
        }
        let d = poly::dist_to_closed(sew, *c);
        if d > mitre_limit * wmax + tol {
            return bad(format!(
                "cut point ({:.3}, {:.3}) is {d:.3} mm from the sew line",
                c.x, c.y
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// Max over cut vertices of |dist to sew| and the min: for a uniform width with mitred
    /// corners every cut point is at least w away and edge points exactly w.
    fn dist_range(sew: &[DVec2], cut: &[DVec2]) -> (f64, f64) {
        let ds: Vec<f64> = cut.iter().map(|c| poly::dist_to_closed(sew, *c)).collect();
        (
            ds.iter().copied().fold(f64::INFINITY, f64::min),
            ds.iter().copied().fold(0.0, f64::max),
        )
    }

    #[test]
    fn square_mitred_is_a_bigger_square() {
        let sq = [v(0., 0.), v(100., 0.), v(100., 50.), v(0., 50.)];
        let r = allowance(
            &sq,
            &[10.0; 4],
            CornerStyle::Mitred,
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        assert_eq!(r.cut.len(), 4);
        assert!((poly::signed_area(&r.cut) - 120.0 * 70.0).abs() < 1e-6);
    }

    #[test]
    fn fold_edge_has_zero_allowance() {
        let sq = [v(0., 0.), v(100., 0.), v(100., 50.), v(0., 50.)];
        let r = allowance(
            &sq,
            &[10.0, 10.0, 10.0, 0.0],
            CornerStyle::Mitred,
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        assert!((poly::signed_area(&r.cut) - 110.0 * 70.0).abs() < 1e-6);
        let minx = r.cut.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
        assert!(minx.abs() < 1e-9);
    }

    #[test]
    fn squared_corner_of_a_triangle_is_cut_at_the_width() {
        let tri = [v(0., 0.), v(100., 0.), v(50., 30.)];
        let w = 10.0;
        let r = allowance(
            &tri,
            &[w; 3],
            CornerStyle::Squared,
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        let (dmin, dmax) = dist_range(&tri, &r.cut);
        assert!((dmin - w).abs() < 1e-6, "{dmin}");
        // the base corners (31°) would mitre out to w / sin(15.5°) ≈ 37 mm; squared cuts the
        // corner at w along the bisector, so the farthest point stays far below the mitre
        let mitre = w / ((30.0f64 / 50.0).atan() / 2.0).sin();
        assert!(dmax > w && dmax < 0.5 * mitre, "{dmax} vs mitre {mitre}");
    }

    #[test]
    fn narrow_neck_trapping_material_is_too_large() {
        // a U whose 4 mm gap closes under a 10 mm allowance: the slot becomes a trapped hole
        let u = [
            v(0., 0.),
            v(60., 0.),
            v(60., 80.),
            v(32., 80.),
            v(32., 10.),
            v(28., 10.),
            v(28., 80.),
            v(0., 80.),
        ];
        match allowance(
            &u,
            &[10.0; 8],
            CornerStyle::Mitred,
            DEFAULT_MITRE_LIMIT,
            1e-6,
        ) {
            Err(SeamFailure::TooLarge(msg)) => assert!(
                msg.contains("across the piece") && msg.contains("narrower seam allowance"),
                "{msg}"
            ),
            other => panic!("expected TooLarge, got {other:?}"),
        }
        // a 1 mm allowance keeps the slot open
        assert!(
            allowance(
                &u,
                &[1.0; 8],
                CornerStyle::Mitred,
                DEFAULT_MITRE_LIMIT,
                1e-6
            )
            .is_ok()
        );
    }

    fn star(k: usize, r_in: f64, r_out: f64, phase: f64) -> Vec<DVec2> {
        (0..2 * k)
            .map(|i| {
                let r = if i % 2 == 0 { r_out } else { r_in };
                r * DVec2::from_angle(phase + i as f64 * std::f64::consts::PI / k as f64)
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Convex (regular polygon) and concave (star) outlines with a uniform width: the cut line
        /// contains the sew line, never comes closer than w, and reaches at most the mitre limit.
        #[test]
        fn offset_distance_holds(k in 3usize..9, r_in in 20.0f64..60.0, extra in 5.0f64..60.0,
                                 w in 0.5f64..15.0, phase in 0.0f64..std::f64::consts::TAU, style in 0usize..3) {
            let sew = star(k, r_in, r_in + extra, phase);
            let style = [CornerStyle::Mitred, CornerStyle::Squared, CornerStyle::Reflected][style];
            let r = allowance(&sew, &vec![w; sew.len()], style, DEFAULT_MITRE_LIMIT, 1e-6).unwrap();
            let (dmin, dmax) = dist_range(&sew, &r.cut);
            prop_assert!(dmin >= w - 1e-6, "dmin {dmin} < w {w}");
            prop_assert!(dmax <= DEFAULT_MITRE_LIMIT * w + 1e-6);
            prop_assert!(poly::first_self_intersection(&r.cut).is_none());
            // the sew edges' midpoints are at exactly w from the cut line on convex stretches
            // (an outer tip edge): check the outermost vertex direction
            let area_ratio = poly::signed_area(&r.cut) / poly::signed_area(&sew);
            prop_assert!(area_ratio > 1.0);
        }

        /// Narrow necks: two lobes joined by a neck of width g; the allowance either builds a
        /// valid cut line or reports TooLarge, never an invalid ring or a panic.
        #[test]
        fn narrow_neck_is_valid_or_rejected(g in 0.5f64..20.0, w in 0.5f64..15.0) {
            let h = g / 2.0;
            let sew = vec![v(0., 0.), v(40., 0.), v(40., 20.0 - h), v(60., 20.0 - h), v(60., 0.), v(100., 0.),
                           v(100., 40.), v(60., 40.), v(60., 20.0 + h), v(40., 20.0 + h), v(40., 40.), v(0., 40.)];
            match allowance(&sew, &vec![w; sew.len()], CornerStyle::Mitred, DEFAULT_MITRE_LIMIT, 1e-6) {
                Ok(r) => {
                    let (dmin, _) = dist_range(&sew, &r.cut);
                    prop_assert!(dmin >= w - 1e-6);
                }
                Err(SeamFailure::TooLarge(_)) => prop_assert!(w > 20.0 - h - 1e-6 || w > 10.0 - 1e-6),
                Err(e) => prop_assert!(false, "engine failure {e:?}"),
            }
        }
    }
}
