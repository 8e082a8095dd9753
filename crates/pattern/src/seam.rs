//! Seam allowance: the cut line is the sew line pushed outward by a width per boundary edge,
//! with pattern-maker corner styles.
//!
//! Construction: the allowance region is the union of the sew polygon, one strip per sew edge
//! (the edge swept outward by its width) and one corner patch per vertex ([`crate::corner`]:
//! the corner style, the cut lines of different widths joined, or a turned allowance's corner
//! reflected, which also clips off what lies beyond the reflection). The union is computed by
//! `geo`'s boolean operations (i_overlay, integer robust), which resolves every overlap a
//! concave outline or a narrow neck produces, without the cusp/loop trimming a hand-rolled
//! offset needs. The per-edge construction is what lets the width change from edge to edge (a
//! lasting margin beside a seam, 0 on a raw edge) — a uniform offset engine cannot. The call is
//! guarded with `catch_unwind`, and the result is validated independently: one closed simple
//! ring, no trapped holes, every sew point inside, and no cut point closer to the inside of a
//! sew edge than that edge's width.

use crate::corner::{self, Corner, right_normal};
use crate::poly;
use flatcut_geom::DVec2;
use geo::{BooleanOps, Coord, LineString, Polygon};

/// A mitre longer than this many widths is squared off instead (the usual CAD mitre limit; a
/// 4× mitre is reached at a turn of about 150°).
pub const DEFAULT_MITRE_LIMIT: f64 = 4.0;
/// A needle of the cut line this thin (mm) is dropped: far below any cutter, far above the
/// union's integer rounding.
const COLLINEAR_MM: f64 = 1e-5;
/// A vertex this close (mm) to the segment between its neighbours is dropped.
const STRAIGHT_MM: f64 = 1e-9;
/// Holes in the allowance region smaller than this (mm²) are numerical slivers, not trapped
/// material.
const HOLE_AREA_EPS: f64 = 1e-3;

/// Result of the offset: the cut ring (CCW, no repeated end point).
#[derive(Clone, Debug)]
pub struct SeamResult {
    /// The cut line: the sew line offset by its allowances, CCW, no repeated end point (mm).
    pub cut: Vec<DVec2>,
}

/// Reason an allowance could not be built (mapped to `PatternError` by the caller).
#[derive(Clone, Debug)]
pub enum SeamFailure {
    /// The allowance closes over the piece: why.
    TooLarge(String),
    /// The offset engine failed: what it reported.
    Engine(String),
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
/// `i` (vertex i → i+1), each vertex closed as `corners[i]` says.
pub fn allowance(
    sew: &[DVec2],
    widths: &[f64],
    corners: &[Corner],
    mitre_limit: f64,
    tol: f64,
) -> Result<SeamResult, SeamFailure> {
    let n = sew.len();
    let dir: Vec<DVec2> = (0..n)
        .map(|i| (sew[(i + 1) % n] - sew[i]).normalize_or_zero())
        .collect();
    let mut parts = corner::Parts {
        add: vec![sew.to_vec()],
        clip: Vec::new(),
    };
    for i in 0..n {
        let w = widths[i];
        if w <= 0.0 || dir[i] == DVec2::ZERO {
            continue;
        }
        let o = right_normal(dir[i]) * w;
        let (a, b) = (sew[i], sew[(i + 1) % n]);
        push_ccw(&mut parts.add, vec![a, b, b + o, a + o]);
    }
    for i in 0..n {
        let ip = (i + n - 1) % n;
        let vertex = corner::Vertex {
            v: sew[i],
            dp: dir[ip],
            dn: dir[i],
            wp: widths[ip],
            wn: widths[i],
        };
        corner::parts(&vertex, corners[i], mitre_limit, &mut parts);
    }
    check_crossing(sew, widths, tol)?;
    let polygons = |rings: &[Vec<DVec2>]| -> Vec<Polygon<f64>> {
        rings
            .iter()
            .map(|r| {
                let ls: Vec<Coord<f64>> = r.iter().map(|p| Coord { x: p.x, y: p.y }).collect();
                Polygon::new(LineString::from(ls), vec![])
            })
            .collect()
    };
    let (add, clip) = (polygons(&parts.add), polygons(&parts.clip));
    let union = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let u = geo::unary_union(&add);
        if clip.is_empty() {
            u
        } else {
            u.difference(&geo::unary_union(&clip))
        }
    }))
    .map_err(|_| SeamFailure::Engine("polygon union panicked".into()))?;
    // The boolean operations' rounding can leave slivers of 1e-14 mm² beside the cut region
    // (seen at reflected corners of shallow concave vertices): below the noise floor used for
    // holes they are not regions of the allowance.
    let union = geo::MultiPolygon(
        union
            .0
            .into_iter()
            .filter(|p| geo::Area::unsigned_area(p) > HOLE_AREA_EPS)
            .collect(),
    );
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
    cut = drop_collinear(&cut, COLLINEAR_MM);
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
        let hit = flatcut_geom::polygon::ray_hit(sew, start, nrm).filter(|h| h.t < w - tol);
        if let Some(h) = hit.filter(|h| !wedge(sew, i, h.edge, start + nrm * h.t, w, tol)) {
            let (s, q) = (h.t, start + nrm * h.t);
            return Err(SeamFailure::TooLarge(format!(
                "the {w:.1} mm allowance of the seam near ({:.1}, {:.1}) mm runs across the piece, meeting the sew line again {s:.1} mm away at ({:.1}, {:.1}) mm; {ADVICE}",
                m.x, m.y, q.x, q.y
            )));
        }
    }
    Ok(())
}

/// Steps a wedge's leg may take along the sew line, and how much longer than straight it may be.
const WEDGE_STEPS: usize = 64;
const WEDGE_STRAIGHT: f64 = 0.02;

/// Whether the allowance of edge `i` meeting the sew line again on edge `j` is the overlap of a
/// concave corner (a wedge) rather than of a slot or of another part of the piece: a vertex `c`
/// between them along the sew line from which it runs straight (within [`WEDGE_STRAIGHT`]) to
/// edge `i`'s midpoint and to the point `q` where the allowance met edge `j`, both within the depth
/// `w / tan(φ/2)` where the allowances of a wedge of opening φ meet. Such a corner is filled by
/// the union like every concave corner, however short its edges (seams meeting at a narrow
/// angle on a split piece); a slot has two corners at its bottom and is no wedge.
fn wedge(sew: &[DVec2], i: usize, j: usize, q: DVec2, w: f64, tol: f64) -> bool {
    let n = sew.len();
    let m = 0.5 * (sew[i] + sew[(i + 1) % n]);
    let legs = |c: DVec2, along_m: f64, along_q: f64| {
        let (dm, dq) = (m - c, q - c);
        let straight = |along: f64, d: DVec2| along <= d.length() * (1.0 + WEDGE_STRAIGHT) + tol;
        let phi = dm.angle_to(dq).abs();
        let depth = w / (0.5 * phi).tan();
        straight(along_m, dm)
            && straight(along_q, dq)
            && dm.length() <= depth + tol
            && dq.length() <= depth + tol
    };
    // Each way round from the midpoint to `q`: forward through vertices i+1, i+2, …, j;
    // backward through i, i-1, …, j+1.
    for forward in [true, false] {
        let mut path = vec![m];
        let mut k = if forward { (i + 1) % n } else { i };
        for _ in 0..WEDGE_STEPS.min(n) {
            path.push(sew[k]);
            let on_hit = if forward {
                k == j
            } else {
                (k + n - 1) % n == j
            };
            if on_hit {
                path.push(q);
                let mut cum = vec![0.0; path.len()];
                for c in 1..path.len() {
                    cum[c] = cum[c - 1] + path[c].distance(path[c - 1]);
                }
                let total = cum[path.len() - 1];
                if (1..path.len() - 1).any(|c| legs(path[c], cum[c], total - cum[c])) {
                    return true;
                }
                break;
            }
            k = if forward {
                (k + 1) % n
            } else {
                (k + n - 1) % n
            };
        }
    }
    false
}

/// Drops every vertex that lies between its two neighbours on the line through them (within
/// [`STRAIGHT_MM`]), or beyond one of them within `eps` (a needle: the union's rounding can
/// leave a hair where two parts' edges run along each other), until none is left.
fn drop_collinear(p: &[DVec2], eps: f64) -> Vec<DVec2> {
    let mut ring = p.to_vec();
    loop {
        let n = ring.len();
        if n < 4 {
            return ring;
        }
        let flat = |i: usize| {
            let (a, b, c) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            let (off, t) = poly::seg_nearest(a, c, b);
            let between = t > 0.0 && t < 1.0;
            let longest = a.distance(b).max(b.distance(c)).max(a.distance(c));
            let needle = !between && (b - a).perp_dot(c - a).abs() <= eps * longest;
            off <= STRAIGHT_MM || needle
        };
        let keep: Vec<bool> = (0..n).map(|i| !flat(i)).collect();
        if keep.iter().all(|k| *k) {
            return ring;
        }
        // drop every other flat vertex per pass, so two neighbours are never both dropped on
        // the strength of each other
        let mut dropped_prev = false;
        let mut next = Vec::with_capacity(n);
        for (i, q) in ring.iter().enumerate() {
            if !keep[i] && !dropped_prev {
                dropped_prev = true;
                continue;
            }
            dropped_prev = false;
            next.push(*q);
        }
        ring = next;
    }
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
        // no cut point outside an edge closer to it than its width (it would eat into that
        // seam); beside an edge's end the corner decides the shape (a narrower neighbour, a
        // reflected hem corner), and a point behind an edge (a raw edge's cut line meeting a
        // lasting margin at an acute corner) is not in its allowance
        for i in 0..n {
            let (a, b) = (sew[i], sew[(i + 1) % n]);
            let (d, t) = poly::seg_nearest(a, b, *c);
            let outside = (b - a).perp_dot(*c - a) < 0.0;
            let len = a.distance(b);
            let inner = t * len > tol && (1.0 - t) * len > tol;
            if outside && inner && d < widths[i] - tol {
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
    use crate::corner::CornerStyle;
    use proptest::prelude::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// The same corner style at every vertex of an `n`-gon.
    fn all(style: CornerStyle, n: usize) -> Vec<Corner> {
        vec![Corner::Join(style); n]
    }

    /// The least and largest distance to the sew line over the cut line's vertices and edge
    /// midpoints: for a uniform width every cut point is at least w away and edge points
    /// exactly w.
    fn dist_range(sew: &[DVec2], cut: &[DVec2]) -> (f64, f64) {
        let n = cut.len();
        let ds: Vec<f64> = (0..n)
            .flat_map(|i| [cut[i], 0.5 * (cut[i] + cut[(i + 1) % n])])
            .map(|c| poly::dist_to_closed(sew, c))
            .collect();
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
            &all(CornerStyle::Mitred, sq.len()),
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        assert_eq!(r.cut.len(), 4);
        assert!((poly::signed_area(&r.cut) - 120.0 * 70.0).abs() < 1e-6);
    }

    #[test]
    fn raw_edge_has_zero_allowance() {
        let sq = [v(0., 0.), v(100., 0.), v(100., 50.), v(0., 50.)];
        let r = allowance(
            &sq,
            &[10.0, 10.0, 10.0, 0.0],
            &all(CornerStyle::Mitred, 4),
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        assert!((poly::signed_area(&r.cut) - 110.0 * 70.0).abs() < 1e-6);
        let minx = r.cut.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
        assert!(minx.abs() < 1e-9);
    }

    /// The vertices of `cut` that turn clockwise (a notch or step into the allowance).
    fn reflex(cut: &[DVec2]) -> Vec<DVec2> {
        let n = cut.len();
        (0..n)
            .filter(|&i| {
                let (a, b, c) = (cut[(i + n - 1) % n], cut[i], cut[(i + 1) % n]);
                (b - a).perp_dot(c - b) < -1e-9
            })
            .map(|i| cut[i])
            .collect()
    }

    #[test]
    fn a_lasting_margin_beside_seams_meets_them_at_mitred_corners() {
        // 16 mm along the bottom, 8 mm elsewhere: the cut line is a rectangle, no notch
        let sq = [v(0., 0.), v(100., 0.), v(100., 50.), v(0., 50.)];
        let r = allowance(
            &sq,
            &[16.0, 8.0, 8.0, 8.0],
            &all(CornerStyle::Mitred, 4),
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        assert_eq!(r.cut.len(), 4, "{:?}", r.cut);
        for q in [v(-8., -16.), v(108., -16.), v(108., 58.), v(-8., 58.)] {
            assert!(
                r.cut.iter().any(|c| c.distance(q) < 1e-9),
                "{q} in {:?}",
                r.cut
            );
        }
    }

    #[test]
    fn different_widths_at_a_concave_corner_leave_no_notch() {
        // an L: the inner corner (60, 40) joins a 16 mm edge to an 8 mm one
        let l = [
            v(0., 0.),
            v(100., 0.),
            v(100., 40.),
            v(60., 40.),
            v(60., 100.),
            v(0., 100.),
        ];
        let widths = [8.0, 8.0, 16.0, 8.0, 8.0, 8.0];
        let r = allowance(
            &l,
            &widths,
            &all(CornerStyle::Mitred, 6),
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        // the 16 mm line y = 56 meets the 8 mm line x = 68 at (68, 56): the only reflex vertex
        assert_eq!(reflex(&r.cut), vec![v(68., 56.)], "{:?}", r.cut);
    }

    /// A flared skirt panel: hem along the bottom (40 mm, turned up), side seams leaning in by
    /// `alpha` (15 mm), waist 10 mm.
    fn flared(alpha: f64) -> (Vec<DVec2>, [f64; 4], Vec<Corner>) {
        let (h, b) = (200.0, 200.0);
        let t = b * 0.5 - h * alpha.tan();
        let sew = vec![v(-b / 2., 0.), v(b / 2., 0.), v(t, h), v(-t, h)];
        let mut corners = all(CornerStyle::Mitred, 4);
        corners[0] = Corner::FoldOutgoing;
        corners[1] = Corner::FoldIncoming;
        (sew, [40.0, 15.0, 10.0, 15.0], corners)
    }

    #[test]
    fn a_turned_hem_folds_onto_the_side_seams_cut_lines() {
        for alpha in [0.0f64, 0.15, 0.35] {
            let (sew, widths, corners) = flared(alpha);
            let r = allowance(&sew, &widths, &corners, DEFAULT_MITRE_LIMIT, 1e-6).unwrap();
            // every cut point below the hem line, folded up about it, lies on or inside the
            // side seams' cut lines and reaches them at the hem's ends
            let below: Vec<DVec2> = r.cut.iter().copied().filter(|p| p.y < -1e-9).collect();
            assert!(!below.is_empty());
            let (s, c) = alpha.sin_cos();
            let right = |p: DVec2| (p - v(100. + 15. * c, 15. * s)).perp_dot(v(-s, c));
            let left = |p: DVec2| (p - v(-100. - 15. * c, 15. * s)).perp_dot(v(-s, -c));
            let mut reach = (f64::INFINITY, f64::INFINITY);
            for p in &below {
                let f = v(p.x, -p.y);
                // (i_overlay rounds to its integer grid: a few nanometres)
                assert!(
                    right(f) <= 1e-6 && left(f) <= 1e-6,
                    "α {alpha}: {p} folds to {f}: {} {}",
                    right(f),
                    left(f)
                );
                reach = (reach.0.min(-right(f)), reach.1.min(-left(f)));
            }
            assert!(reach.0 < 1e-6 && reach.1 < 1e-6, "α {alpha}: {reach:?}");
            // the hem itself stays 40 mm deep
            let deepest = below.iter().map(|p| p.y).fold(0.0, f64::min);
            assert!((deepest + 40.0).abs() < 1e-6, "{deepest}");
        }
    }

    #[test]
    fn squared_corner_of_a_triangle_is_cut_at_the_width() {
        let tri = [v(0., 0.), v(100., 0.), v(50., 30.)];
        let w = 10.0;
        let r = allowance(
            &tri,
            &[w; 3],
            &all(CornerStyle::Squared, tri.len()),
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
            &all(CornerStyle::Mitred, u.len()),
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
                &all(CornerStyle::Mitred, u.len()),
                DEFAULT_MITRE_LIMIT,
                1e-6
            )
            .is_ok()
        );
    }

    #[test]
    fn a_narrow_wedge_of_short_edges_is_a_concave_corner_not_a_slot() {
        // A square with a V notch of 47° opening down from its top edge, 80 mm deep, its legs
        // of 5 mm edges (seams meeting at a narrow angle on a split piece). Near the apex the
        // allowance of a leg's edge meets the other leg within 6 mm: the corner the union
        // fills, as at every concave corner, not an allowance across the piece.
        let half = (47.0f64 / 2.0).to_radians().tan() * 80.0;
        let mut sew = vec![v(0., 0.), v(200., 0.), v(200., 200.)];
        let steps = 16;
        for k in 0..steps {
            sew.push(v(100.0 + half, 200.0).lerp(v(100., 120.), k as f64 / steps as f64));
        }
        for k in 0..steps {
            sew.push(v(100., 120.).lerp(v(100.0 - half, 200.0), k as f64 / steps as f64));
        }
        sew.push(v(100.0 - half, 200.0));
        sew.push(v(0., 200.));
        let n = sew.len();
        let r = allowance(
            &sew,
            &vec![6.0; n],
            &all(CornerStyle::Mitred, n),
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        let (dmin, _) = dist_range(&sew, &r.cut);
        assert!(dmin >= 6.0 - 1e-6, "{dmin}");
        // The cut line's notch ends where the two legs' allowances meet: 6 / sin(23.5°) mm
        // above the apex on the notch's axis.
        let apex = 6.0 / (47.0f64 / 2.0).to_radians().sin();
        let lowest = r
            .cut
            .iter()
            .filter(|p| (p.x - 100.0).abs() < 1.0 && p.y > 100.0)
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        assert!((lowest - (120.0 + apex)).abs() < 1e-3, "{lowest}");
    }

    fn star(k: usize, r_in: f64, r_out: f64, phase: f64) -> Vec<DVec2> {
        (0..2 * k)
            .map(|i| {
                let r = if i % 2 == 0 { r_out } else { r_in };
                r * DVec2::from_angle(phase + i as f64 * std::f64::consts::PI / k as f64)
            })
            .collect()
    }

    /// A case the property below found: a shallow three-pointed star with reflected corners,
    /// where the union's rounding left a 7e-15 mm² sliver beside the cut region, and the
    /// allowance failed with "union split into 2 regions".
    #[test]
    fn rounding_slivers_are_not_regions_of_the_allowance() {
        let sew = star(3, 35.63, 35.63 + 5.81, 2.7668935718910688);
        let r = allowance(
            &sew,
            &vec![3.4; sew.len()],
            &all(CornerStyle::Reflected, sew.len()),
            DEFAULT_MITRE_LIMIT,
            1e-6,
        )
        .unwrap();
        let (dmin, dmax) = dist_range(&sew, &r.cut);
        assert!(
            dmin >= 3.4 - 1e-6 && dmax <= DEFAULT_MITRE_LIMIT * 3.4 + 1e-6,
            "{dmin} {dmax}"
        );
        assert!(poly::first_self_intersection(&r.cut).is_none());
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
            let r = allowance(&sew, &vec![w; sew.len()], &all(style, sew.len()), DEFAULT_MITRE_LIMIT, 1e-6).unwrap();
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
            match allowance(&sew, &vec![w; sew.len()], &all(CornerStyle::Mitred, sew.len()), DEFAULT_MITRE_LIMIT, 1e-6) {
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
