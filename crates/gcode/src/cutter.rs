//! Cutter geometry shared by the G-code and HP-GL writers, applied to a closed path before the
//! tool model (knife compensation, arc fitting): laser kerf compensation, tabs (bridges) and
//! lead-ins/lead-outs that land in the scrap.
//!
//! Sides: for a closed loop in machine coordinates, the *scrap side* is outside an outer
//! contour and inside a hole — where a kerf offset moves the path and where a lead lands.

use flatcut_geom::DVec2;

use crate::profile::{LeadConfig, LeadKind};

/// Segments shorter than this carry no direction (mm).
const MIN_SEGMENT_MM: f64 = 1e-9;
/// A kerf offset vertex may move at most this many half-kerfs (mitre limit at sharp corners).
const MITRE_LIMIT: f64 = 4.0;
/// Chords of an arc lead.
const ARC_LEAD_SEGMENTS: usize = 8;

fn signed_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>() * 0.5
}

/// +1 when the scrap lies to the left of the loop's direction, −1 when to the right.
fn scrap_left(loop_pts: &[DVec2], outer: bool) -> f64 {
    let ccw = signed_area(loop_pts) > 0.0;
    // CCW: the inside is on the left. An outer contour's scrap is outside; a hole's is inside.
    if ccw != outer { 1.0 } else { -1.0 }
}

fn left_normal(d: DVec2) -> DVec2 {
    DVec2::new(-d.y, d.x)
}

/// Offsets a closed loop (first point not repeated) by `dist` to its scrap side: outward for an
/// outer contour, inward for a hole. Each vertex moves along its bisector by `dist / cos(θ/2)`,
/// capped by a mitre limit; `dist` is a fraction of a millimetre (half a laser kerf), far
/// below any feature a laser cuts, so the offset of a valid part outline stays simple.
pub fn kerf_offset(loop_pts: &[DVec2], outer: bool, dist: f64) -> Vec<DVec2> {
    let n = loop_pts.len();
    if n < 3 || dist <= 0.0 {
        return loop_pts.to_vec();
    }
    let side = scrap_left(loop_pts, outer);
    (0..n)
        .map(|i| {
            let (a, b, c) = (
                loop_pts[(i + n - 1) % n],
                loop_pts[i],
                loop_pts[(i + 1) % n],
            );
            let n0 = left_normal((b - a).normalize_or_zero());
            let n1 = left_normal((c - b).normalize_or_zero());
            let bis = (n0 + n1).normalize_or_zero();
            let cos_half = bis.dot(n1).max(1.0 / MITRE_LIMIT);
            if bis == DVec2::ZERO {
                return b + n1 * side * dist;
            }
            b + bis * side * (dist / cos_half)
        })
        .collect()
}

/// Splits a closed run (first point repeated at the end) into `count` open pieces with gaps of
/// `width` mm (tabs) evenly spaced along it; each gap is left uncut.
pub fn split_tabs(run: &[DVec2], count: u32, width: f64) -> Vec<Vec<DVec2>> {
    let total: f64 = run.windows(2).map(|w| w[0].distance(w[1])).sum();
    if count == 0 || total <= f64::from(count) * width * 2.0 {
        return vec![run.to_vec()];
    }
    let spacing = total / f64::from(count);
    // Cut intervals [k·spacing + width/2, (k+1)·spacing − width/2] along the arc length.
    let intervals: Vec<(f64, f64)> = (0..count)
        .map(|k| {
            (
                f64::from(k) * spacing + width * 0.5,
                f64::from(k + 1) * spacing - width * 0.5,
            )
        })
        .collect();
    intervals
        .iter()
        .map(|&(s0, s1)| sub_run(run, s0, s1))
        .filter(|p| p.len() >= 2)
        .collect()
}

/// The part of `run` between arc lengths `s0` and `s1`.
fn sub_run(run: &[DVec2], s0: f64, s1: f64) -> Vec<DVec2> {
    let mut out = Vec::new();
    let mut s = 0.0;
    for w in run.windows(2) {
        let l = w[0].distance(w[1]);
        if l <= MIN_SEGMENT_MM {
            continue;
        }
        let (a, b) = (s, s + l);
        if b >= s0 && a <= s1 {
            let t0 = ((s0 - a) / l).clamp(0.0, 1.0);
            let t1 = ((s1 - a) / l).clamp(0.0, 1.0);
            if out.is_empty() {
                out.push(w[0].lerp(w[1], t0));
            }
            out.push(w[0].lerp(w[1], t1));
        }
        s = b;
    }
    out
}

/// Adds a lead-in before and a lead-out after a closed run (first point repeated at the end),
/// both on the scrap side of the loop `loop_pts`. The run is restarted at the middle of its
/// longest segment, so the leads meet a straight stretch rather than a corner (where a tangent
/// arc would swing behind the corner, into the part); `overcut` mm are cut past the new start
/// before the lead-out (a drag knife's overcut).
pub fn with_leads(
    run: &[DVec2],
    loop_pts: &[DVec2],
    outer: bool,
    cfg: &LeadConfig,
    overcut: f64,
) -> Vec<DVec2> {
    if run.len() < 3 {
        return run.to_vec();
    }
    let longest = (0..run.len() - 1)
        .max_by(|&a, &b| {
            run[a]
                .distance(run[a + 1])
                .total_cmp(&run[b].distance(run[b + 1]))
        })
        .unwrap_or(0);
    let mid = run[longest].lerp(run[longest + 1], 0.5);
    let mut restarted = vec![mid];
    restarted.extend_from_slice(&run[longest + 1..]);
    restarted.extend_from_slice(&run[1..=longest]);
    restarted.push(mid);
    let run = if overcut > 0.0 {
        crate::knife::with_overcut(&restarted, overcut)
    } else {
        restarted
    };
    add_leads(&run, scrap_left(loop_pts, outer), cfg, true)
}

/// Adds a lead-in before and a lead-out after an open `run`, one piece of a closed contour
/// `loop_pts` that tabs split (each piece is entered and left on its own): both on the scrap
/// side, so a laser pierces in the scrap for every piece, as for a whole contour. A piece
/// starts where a tab ends, maybe next to a corner, where an arc lead would swing behind the
/// corner into the part: then a line lead is used, and where neither fits in the scrap (a
/// hole narrower than the lead) the piece has none.
pub fn with_open_leads(
    run: &[DVec2],
    loop_pts: &[DVec2],
    outer: bool,
    cfg: &LeadConfig,
) -> Vec<DVec2> {
    if run.len() < 2 {
        return run.to_vec();
    }
    let side = scrap_left(loop_pts, outer);
    let in_scrap = |p: &DVec2| flatcut_geom::polygon::contains(loop_pts, *p) != outer;
    let line = LeadConfig {
        kind: LeadKind::Line,
        ..*cfg
    };
    for c in [*cfg, line] {
        let out = add_leads(run, side, &c, false);
        let leads = (out.len() - run.len()) / 2;
        let lead_points = out[..leads].iter().chain(&out[out.len() - leads..]);
        if lead_points.clone().all(in_scrap) {
            return out;
        }
    }
    run.to_vec()
}

/// `run` with a lead before its first point and after its last, on the `side` of the path
/// where the scrap is (+1 left, −1 right). A line lead of a `closed` run (first point = last
/// point) goes in and out along one direction, the mean of the ends' normals; otherwise each
/// end has its own.
fn add_leads(run: &[DVec2], side: f64, cfg: &LeadConfig, closed: bool) -> Vec<DVec2> {
    let first = (run[1] - run[0]).normalize_or_zero();
    let k = run.len();
    let last = (run[k - 1] - run[k - 2]).normalize_or_zero();
    let r = cfg.length_mm;
    let mut out = Vec::with_capacity(run.len() + 2 * ARC_LEAD_SEGMENTS + 2);
    match cfg.kind {
        LeadKind::Line => {
            let (n_in, n_out) = if closed {
                let n = (left_normal(first) + left_normal(last)).normalize_or_zero();
                let n = if n == DVec2::ZERO {
                    left_normal(first)
                } else {
                    n
                };
                (n, n)
            } else {
                (left_normal(first), left_normal(last))
            };
            out.push(run[0] + n_in * side * r);
            out.extend_from_slice(run);
            out.push(run[k - 1] + n_out * side * r);
        }
        LeadKind::Arc => {
            // Quarter circles on the scrap side, tangent to the first and last segments.
            let c_in = run[0] + left_normal(first) * side * r;
            let a_in = (run[0] - c_in).to_angle();
            let c_out = run[k - 1] + left_normal(last) * side * r;
            let a_out = (run[k - 1] - c_out).to_angle();
            // Scrap on the right: the arcs run clockwise (angles fall), on the left counter-clockwise.
            let turn = -side * std::f64::consts::FRAC_PI_2;
            for j in 0..ARC_LEAD_SEGMENTS {
                let t = j as f64 / ARC_LEAD_SEGMENTS as f64;
                out.push(c_in + r * DVec2::from_angle(a_in + turn * (1.0 - t)));
            }
            out.extend_from_slice(run);
            for j in 1..=ARC_LEAD_SEGMENTS {
                let t = j as f64 / ARC_LEAD_SEGMENTS as f64;
                out.push(c_out + r * DVec2::from_angle(a_out - turn * t));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: f64, h: f64) -> Vec<DVec2> {
        vec![
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, h),
            DVec2::new(0.0, h),
        ]
    }

    #[test]
    fn kerf_moves_outlines_out_and_holes_in() {
        let o = kerf_offset(&rect(50.0, 30.0), true, 0.1);
        let bb = flatcut_geom::Aabb2::from_points(o.iter().copied());
        assert!((bb.width() - 50.2).abs() < 1e-12 && (bb.height() - 30.2).abs() < 1e-12);
        let mut cw = rect(10.0, 10.0);
        cw.reverse();
        let h = kerf_offset(&cw, false, 0.1);
        let bb = flatcut_geom::Aabb2::from_points(h.iter().copied());
        assert!((bb.width() - 9.8).abs() < 1e-12 && (bb.min.x - 0.1).abs() < 1e-12);
    }

    #[test]
    fn tabs_leave_gaps_of_the_given_width() {
        let mut run = rect(40.0, 20.0);
        run.push(run[0]);
        let pieces = split_tabs(&run, 4, 2.0);
        assert_eq!(pieces.len(), 4);
        let cut: f64 = pieces
            .iter()
            .map(|p| p.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>())
            .sum();
        assert!((cut - (120.0 - 8.0)).abs() < 1e-9, "{cut}");
    }

    #[test]
    fn leads_land_in_the_scrap() {
        let lp = rect(40.0, 20.0);
        let mut run = lp.clone();
        run.push(run[0]);
        for kind in [LeadKind::Line, LeadKind::Arc] {
            let cfg = LeadConfig {
                kind,
                length_mm: 3.0,
            };
            let out = with_leads(&run, &lp, true, &cfg, 0.0);
            for p in [out[0], *out.last().unwrap()] {
                let inside = p.x > 0.0 && p.x < 40.0 && p.y > 0.0 && p.y < 20.0;
                assert!(!inside, "{kind:?}: lead at {p} inside the part");
                let to_edge =
                    p.y.abs()
                        .min((p.y - 20.0).abs())
                        .min(p.x.abs())
                        .min((p.x - 40.0).abs());
                assert!(to_edge > 2.0 || p.y < -2.0, "{kind:?}: {p}");
            }
            let hole = with_leads(&run, &lp, false, &cfg, 0.0);
            let p = hole[0];
            assert!(
                p.x > 0.0 && p.x < 40.0 && p.y > 0.0 && p.y < 20.0,
                "{kind:?}: {p}"
            );
        }
    }
}
