//! Outline fitting: a closed polyline (a flattened mesh boundary) becomes a path of lines,
//! circular arcs and cubic Béziers within a tolerance in mm, split at corners (marks and sharp
//! turns) so corners stay sharp and smooth stretches lose the mesh's facets.
//!
//! The cubic fit is Schneider's algorithm ("An algorithm for automatically fitting digitized
//! curves", Graphics Gems 1990): chord-length parameters, least squares for the two tangent
//! magnitudes, Newton reparameterisation, split at the worst point. Lines and arcs are tried
//! first so straight seams and round corners come out as the primitives cutters know (DXF
//! bulges, G2/G3). kurbo's fitter needs a smooth curve source; ours is a noisy polyline, hence
//! this small dedicated implementation.

use crate::poly;
use flatcut_geom::DVec2;

/// One segment of a fitted path. Arcs are stored with a DXF-style bulge: `tan(sweep/4)`,
/// positive for counter-clockwise sweeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathSeg {
    /// Straight segment.
    Line {
        /// Start point (mm).
        p0: DVec2,
        /// End point (mm).
        p1: DVec2,
    },
    /// Circular arc from `p0` to `p1` with bulge `tan(sweep/4)` (|sweep| < 2π).
    Arc {
        /// Start point (mm).
        p0: DVec2,
        /// End point (mm).
        p1: DVec2,
        /// `tan(sweep/4)`: 0 straight, 1 a half circle, negative clockwise.
        bulge: f64,
    },
    /// Cubic Bézier.
    Cubic {
        /// Start point (mm).
        p0: DVec2,
        /// First control point (mm): the start tangent points at it.
        c1: DVec2,
        /// Second control point (mm): the end tangent comes from it.
        c2: DVec2,
        /// End point (mm).
        p1: DVec2,
    },
}

/// Iterations of Newton reparameterisation before a cubic span is split.
const REPARAM_ITERS: usize = 4;
/// A turn sharper than this (degrees between the incoming and outgoing chords over the probe
/// length) is a corner: 40° is well above the facet turns of a mesh boundary at the usual
/// resolution yet below any intentional pattern corner.
pub const DEFAULT_CORNER_DEG: f64 = 40.0;
/// Chords used to measure the turn at a vertex reach this far (mm) along the boundary, so a
/// single jagged facet does not read as a corner.
pub const CORNER_PROBE_MM: f64 = 2.0;

impl PathSeg {
    /// Start point.
    pub fn start(&self) -> DVec2 {
        match *self {
            PathSeg::Line { p0, .. } | PathSeg::Arc { p0, .. } | PathSeg::Cubic { p0, .. } => p0,
        }
    }

    /// End point.
    pub fn end(&self) -> DVec2 {
        match *self {
            PathSeg::Line { p1, .. } | PathSeg::Arc { p1, .. } | PathSeg::Cubic { p1, .. } => p1,
        }
    }

    /// Point at parameter `t ∈ [0, 1]`.
    pub fn eval(&self, t: f64) -> DVec2 {
        match *self {
            PathSeg::Line { p0, p1 } => p0.lerp(p1, t),
            PathSeg::Arc { p0, p1, bulge } => {
                let (c, _r, a0, sweep) = arc_geometry(p0, p1, bulge);
                let a = a0 + sweep * t;
                c + (p0 - c).length() * DVec2::new(a.cos(), a.sin())
            }
            PathSeg::Cubic { p0, c1, c2, p1 } => bezier(p0, c1, c2, p1, t),
        }
    }

    /// Polyline approximation within `tol` mm (chordal deviation); the start point is
    /// included, the end point too.
    pub fn flatten(&self, tol: f64, out: &mut Vec<DVec2>) {
        let tol = tol.max(1e-6);
        let n = match *self {
            PathSeg::Line { .. } => 1,
            PathSeg::Arc { p0, p1, bulge } => {
                let (_, r, _, sweep) = arc_geometry(p0, p1, bulge);
                let step = 2.0 * (1.0 - (tol / r).min(1.0)).acos();
                ((sweep.abs() / step.max(1e-3)).ceil() as usize).clamp(1, 4096)
            }
            PathSeg::Cubic { p0, c1, c2, p1 } => {
                // |B''| ≤ 6·max second difference; chord error ≤ |B''|max / (8 n²).
                let m = (p0 - 2.0 * c1 + c2)
                    .length()
                    .max((c1 - 2.0 * c2 + p1).length());
                ((6.0 * m / (8.0 * tol)).sqrt().ceil() as usize).clamp(1, 4096)
            }
        };
        if out.last() != Some(&self.start()) {
            out.push(self.start());
        }
        for i in 1..=n {
            out.push(if i == n {
                self.end()
            } else {
                self.eval(i as f64 / n as f64)
            });
        }
    }
}

/// Centre, radius, start angle and signed sweep of an arc given by end points and bulge.
pub fn arc_geometry(p0: DVec2, p1: DVec2, bulge: f64) -> (DVec2, f64, f64, f64) {
    let sweep = 4.0 * bulge.atan();
    let chord = p1 - p0;
    let half = chord.length() * 0.5;
    let r = half / (sweep * 0.5).sin().abs();
    // Distance from the chord midpoint to the centre, signed toward the left of the chord for
    // counter-clockwise sweeps below π.
    let h = r * (sweep * 0.5).cos();
    let left = DVec2::new(-chord.y, chord.x).normalize_or_zero();
    let c = (p0 + p1) * 0.5 + left * h * sweep.signum();
    let a0 = (p0 - c).y.atan2((p0 - c).x);
    (c, r, a0, sweep)
}

fn bezier(p0: DVec2, c1: DVec2, c2: DVec2, p1: DVec2, t: f64) -> DVec2 {
    let s = 1.0 - t;
    p0 * (s * s * s) + c1 * (3.0 * s * s * t) + c2 * (3.0 * s * t * t) + p1 * (t * t * t)
}

fn bezier_d1(p0: DVec2, c1: DVec2, c2: DVec2, p1: DVec2, t: f64) -> DVec2 {
    let s = 1.0 - t;
    (c1 - p0) * (3.0 * s * s) + (c2 - c1) * (6.0 * s * t) + (p1 - c2) * (3.0 * t * t)
}

fn bezier_d2(p0: DVec2, c1: DVec2, c2: DVec2, p1: DVec2, t: f64) -> DVec2 {
    (c2 - 2.0 * c1 + p0) * (6.0 * (1.0 - t)) + (p1 - 2.0 * c2 + c1) * (6.0 * t)
}

/// Indices of corner vertices of a closed polyline: every vertex in `forced`, plus vertices
/// whose turn (measured with chords of [`CORNER_PROBE_MM`]) exceeds `corner_deg` and is the
/// largest turn within the probe window.
pub fn find_corners(p: &[DVec2], forced: &[usize], corner_deg: f64) -> Vec<usize> {
    let n = p.len();
    let s = poly::cumulative_length(p);
    let perim = s[n];
    let probe = CORNER_PROBE_MM.min(perim / 8.0);
    let mut turn = vec![0.0; n];
    for i in 0..n {
        // walk back and forward until the probe length is reached
        let (mut b, mut f) = (i, i);
        let mut lb = 0.0;
        while lb < probe {
            let pb = (b + n - 1) % n;
            lb += p[b].distance(p[pb]);
            b = pb;
            if b == i {
                break;
            }
        }
        let mut lf = 0.0;
        while lf < probe {
            let nf = (f + 1) % n;
            lf += p[f].distance(p[nf]);
            f = nf;
            if f == i {
                break;
            }
        }
        let din = (p[i] - p[b]).normalize_or_zero();
        let dout = (p[f] - p[i]).normalize_or_zero();
        turn[i] = din.perp_dot(dout).atan2(din.dot(dout)).abs().to_degrees();
    }
    let mut corners: Vec<usize> = forced.iter().copied().filter(|&i| i < n).collect();
    for i in 0..n {
        if turn[i] <= corner_deg {
            continue;
        }
        // local maximum within the probe window (ties resolved toward the lower index)
        let mut is_max = true;
        let mut d = 0.0;
        let mut j = i;
        loop {
            let nj = (j + 1) % n;
            d += p[j].distance(p[nj]);
            j = nj;
            if j == i || d > probe {
                break;
            }
            if turn[j] > turn[i] {
                is_max = false;
            }
        }
        let mut d = 0.0;
        let mut j = i;
        loop {
            let pj = (j + n - 1) % n;
            d += p[j].distance(p[pj]);
            j = pj;
            if j == i || d > probe {
                break;
            }
            if turn[j] >= turn[i] {
                is_max = false;
            }
        }
        if is_max {
            corners.push(i);
        }
    }
    corners.sort_unstable();
    corners.dedup();
    corners
}

/// Fits a closed polyline with corners at `corners` (vertex indices, sorted). Returns the
/// segments in order, starting at the first corner (or vertex 0 without corners); each
/// point of the input is within `tol` of the path.
pub fn fit_closed(p: &[DVec2], corners: &[usize], tol: f64) -> Vec<PathSeg> {
    fit_closed_spans(p, corners, tol)
        .into_iter()
        .flat_map(|(_, s)| s)
        .collect()
}

/// Like [`fit_closed`], grouped by corner span: `(start vertex, segments)`, one entry per
/// corner (one entry starting at vertex 0 without corners).
pub fn fit_closed_spans(p: &[DVec2], corners: &[usize], tol: f64) -> Vec<(usize, Vec<PathSeg>)> {
    let n = p.len();
    let mut spans = Vec::new();
    if n < 3 {
        return spans;
    }
    let cs: Vec<usize> = if corners.is_empty() {
        vec![0]
    } else {
        corners.to_vec()
    };
    for k in 0..cs.len() {
        let a = cs[k];
        let b = cs[(k + 1) % cs.len()];
        let mut span = Vec::new();
        let mut i = a;
        loop {
            span.push(p[i]);
            if i == b && span.len() > 1 {
                break;
            }
            i = (i + 1) % n;
        }
        let closed_smooth = corners.is_empty();
        let (t0, t1) = if closed_smooth {
            // tangent continuity across the seam of a corner-free loop
            let t = (p[1] - p[n - 1]).normalize_or_zero();
            (t, -t)
        } else {
            end_tangents(&span)
        };
        let mut out = Vec::new();
        fit_span(&span, t0, t1, tol, 0, &mut out);
        spans.push((a, out));
    }
    spans
}

fn end_tangents(span: &[DVec2]) -> (DVec2, DVec2) {
    let m = span.len();
    let k = (m / 4).clamp(1, 3).min(m - 1);
    (
        (span[k] - span[0]).normalize_or_zero(),
        (span[m - 1 - k] - span[m - 1]).normalize_or_zero(),
    )
}

/// Depth limit of recursive splitting; 2^24 spans is far beyond any outline.
const MAX_DEPTH: usize = 24;

fn fit_span(pts: &[DVec2], t0: DVec2, t1: DVec2, tol: f64, depth: usize, out: &mut Vec<PathSeg>) {
    let m = pts.len();
    let (p0, p1) = (pts[0], pts[m - 1]);
    if m <= 2 || depth >= MAX_DEPTH {
        for w in pts.windows(2) {
            out.push(PathSeg::Line { p0: w[0], p1: w[1] });
        }
        return;
    }
    // 1. line
    let line_err = pts
        .iter()
        .map(|&q| poly::seg_nearest(p0, p1, q).0)
        .fold(0.0, f64::max);
    if line_err <= tol {
        out.push(PathSeg::Line { p0, p1 });
        return;
    }
    // 2. arc through both ends and the point at half arc length
    if let Some(arc) = try_arc(pts, tol) {
        out.push(arc);
        return;
    }
    // 3. cubic
    let (bez, err, split) = fit_cubic(pts, t0, t1);
    if err <= tol {
        out.push(bez);
        return;
    }
    let split = split.clamp(1, m - 2);
    let tc = (pts[split + 1] - pts[split - 1]).normalize_or_zero();
    fit_span(&pts[..=split], t0, -tc, tol, depth + 1, out);
    fit_span(&pts[split..], tc, t1, tol, depth + 1, out);
}

fn try_arc(pts: &[DVec2], tol: f64) -> Option<PathSeg> {
    let m = pts.len();
    if m < 3 {
        return None;
    }
    let s = {
        let mut s = vec![0.0];
        for w in pts.windows(2) {
            s.push(s[s.len() - 1] + w[0].distance(w[1]));
        }
        s
    };
    let half = s[m - 1] * 0.5;
    let mid = s
        .iter()
        .position(|&x| x >= half)
        .unwrap_or(m / 2)
        .clamp(1, m - 2);
    let (a, b, c) = (pts[0], pts[mid], pts[m - 1]);
    let d = 2.0 * (a.x * (b.y - c.y) + b.x * (c.y - a.y) + c.x * (a.y - b.y));
    if d.abs() < 1e-12 {
        return None;
    }
    let (a2, b2, c2) = (a.length_squared(), b.length_squared(), c.length_squared());
    let center = DVec2::new(
        (a2 * (b.y - c.y) + b2 * (c.y - a.y) + c2 * (a.y - b.y)) / d,
        (a2 * (c.x - b.x) + b2 * (a.x - c.x) + c2 * (b.x - a.x)) / d,
    );
    let r = center.distance(a);
    if !r.is_finite() || r > 1e5 {
        return None;
    }
    // signed sweep: accumulate angle increments along the points (monotone for a true arc)
    let ang = |q: DVec2| (q - center).y.atan2((q - center).x);
    let mut sweep = 0.0;
    let mut sign = 0.0;
    for w in pts.windows(2) {
        let mut da = ang(w[1]) - ang(w[0]);
        if da > std::f64::consts::PI {
            da -= std::f64::consts::TAU;
        } else if da < -std::f64::consts::PI {
            da += std::f64::consts::TAU;
        }
        if sign == 0.0 && da != 0.0 {
            sign = da.signum();
        }
        if da * sign < -1e-9 {
            return None; // not monotone: doubles back
        }
        sweep += da;
    }
    if sweep.abs() >= std::f64::consts::TAU - 1e-6 || sweep == 0.0 {
        return None;
    }
    let seg = PathSeg::Arc {
        p0: a,
        p1: c,
        bulge: (sweep / 4.0).tan(),
    };
    // every point within tol of the circle, and chord midpoints too (sagitta of the input)
    let ok = pts.iter().all(|&q| (q.distance(center) - r).abs() <= tol);
    ok.then_some(seg)
}

/// Schneider cubic fit with fixed end tangents; returns the curve, the max point error and
/// the index of the worst point.
fn fit_cubic(pts: &[DVec2], t0: DVec2, t1: DVec2) -> (PathSeg, f64, usize) {
    let m = pts.len();
    let mut u = vec![0.0; m];
    for i in 1..m {
        u[i] = u[i - 1] + pts[i].distance(pts[i - 1]);
    }
    let total = u[m - 1].max(1e-300);
    u.iter_mut().for_each(|x| *x /= total);
    let mut best = None;
    for _ in 0..=REPARAM_ITERS {
        let bez = solve_tangent_magnitudes(pts, &u, t0, t1);
        let (err, idx) = max_error(pts, &u, bez);
        if best.as_ref().is_none_or(|(_, e, _)| err < *e) {
            best = Some((bez, err, idx));
        }
        // Newton step on each parameter: minimise |B(u) - p|
        let [p0, c1, c2, p1] = bez;
        for i in 1..m - 1 {
            let d = bezier(p0, c1, c2, p1, u[i]) - pts[i];
            let d1 = bezier_d1(p0, c1, c2, p1, u[i]);
            let d2 = bezier_d2(p0, c1, c2, p1, u[i]);
            let den = d1.length_squared() + d.dot(d2);
            if den.abs() > 1e-300 {
                u[i] = (u[i] - d.dot(d1) / den).clamp(0.0, 1.0);
            }
        }
    }
    let (b, e, i) = best.unwrap_or((
        [pts[0], pts[0], pts[m - 1], pts[m - 1]],
        f64::INFINITY,
        m / 2,
    ));
    (
        PathSeg::Cubic {
            p0: b[0],
            c1: b[1],
            c2: b[2],
            p1: b[3],
        },
        e,
        i,
    )
}

fn solve_tangent_magnitudes(pts: &[DVec2], u: &[f64], t0: DVec2, t1: DVec2) -> [DVec2; 4] {
    let m = pts.len();
    let (p0, p3) = (pts[0], pts[m - 1]);
    let (mut c00, mut c01, mut c11, mut x0, mut x1) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..m {
        let t = u[i];
        let s = 1.0 - t;
        let b1 = 3.0 * s * s * t;
        let b2 = 3.0 * s * t * t;
        let a0 = t0 * b1;
        let a1 = t1 * b2;
        c00 += a0.dot(a0);
        c01 += a0.dot(a1);
        c11 += a1.dot(a1);
        let tmp = pts[i] - (p0 * (s * s * s + b1) + p3 * (b2 + t * t * t));
        x0 += a0.dot(tmp);
        x1 += a1.dot(tmp);
    }
    let det = c00 * c11 - c01 * c01;
    let seg_len = p0.distance(p3);
    let eps = 1e-6 * seg_len;
    let (mut al, mut ar) = if det.abs() > 1e-12 {
        ((x0 * c11 - x1 * c01) / det, (c00 * x1 - c01 * x0) / det)
    } else {
        (seg_len / 3.0, seg_len / 3.0)
    };
    if al < eps || ar < eps || !al.is_finite() || !ar.is_finite() {
        al = seg_len / 3.0;
        ar = seg_len / 3.0;
    }
    [p0, p0 + t0 * al, p3 + t1 * ar, p3]
}

fn max_error(pts: &[DVec2], u: &[f64], b: [DVec2; 4]) -> (f64, usize) {
    let m = pts.len();
    let mut worst = (0.0, m / 2);
    for i in 1..m - 1 {
        let e = bezier(b[0], b[1], b[2], b[3], u[i]).distance(pts[i]);
        if e > worst.0 {
            worst = (e, i);
        }
    }
    // the curve between samples must not bulge away either: check midpoints of the chords
    for i in 0..m - 1 {
        let um = 0.5 * (u[i] + u[i + 1]);
        let q = bezier(b[0], b[1], b[2], b[3], um);
        let e = poly::seg_nearest(pts[i], pts[i + 1], q).0;
        if e > worst.0 {
            worst = (e, i.clamp(1, m.saturating_sub(2)));
        }
    }
    worst
}

/// Flattens a closed path to a polyline (no repeated closing point) within `tol` mm.
pub fn flatten_closed(segs: &[PathSeg], tol: f64) -> Vec<DVec2> {
    let mut out = Vec::new();
    for s in segs {
        s.flatten(tol, &mut out);
    }
    if out.len() > 1 && out[0].distance(out[out.len() - 1]) < 1e-12 {
        out.pop();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn circle(n: usize, r: f64) -> Vec<DVec2> {
        (0..n)
            .map(|i| r * DVec2::from_angle(i as f64 * 2.0 * PI / n as f64))
            .collect()
    }

    #[test]
    fn square_fits_to_four_lines_with_sharp_corners() {
        let mut p = Vec::new();
        for k in 0..4 {
            let a = [
                DVec2::new(0., 0.),
                DVec2::new(50., 0.),
                DVec2::new(50., 50.),
                DVec2::new(0., 50.),
            ];
            for j in 0..10 {
                p.push(a[k].lerp(a[(k + 1) % 4], j as f64 / 10.0));
            }
        }
        let c = find_corners(&p, &[], DEFAULT_CORNER_DEG);
        assert_eq!(c, vec![0, 10, 20, 30]);
        let segs = fit_closed(&p, &c, 0.05);
        assert_eq!(segs.len(), 4);
        assert!(segs.iter().all(|s| matches!(s, PathSeg::Line { .. })));
    }

    #[test]
    fn arc_geometry_round_trip() {
        let (c, r, _, sweep) =
            arc_geometry(DVec2::new(1., 0.), DVec2::new(0., 1.), (PI / 8.0).tan());
        assert!(c.length() < 1e-12 && (r - 1.0).abs() < 1e-12 && (sweep - PI / 2.0).abs() < 1e-12);
        let s = PathSeg::Arc {
            p0: DVec2::new(1., 0.),
            p1: DVec2::new(0., 1.),
            bulge: (PI / 8.0).tan(),
        };
        assert!(s.eval(0.5).distance(DVec2::splat(0.5f64.sqrt())) < 1e-12);
        // clockwise, more than half a turn
        let b = -(1.5 * PI / 4.0).tan();
        let s = PathSeg::Arc {
            p0: DVec2::new(1., 0.),
            p1: DVec2::new(0., 1.),
            bulge: b,
        };
        assert!(
            s.eval(0.5)
                .distance(DVec2::new(-(0.5f64.sqrt()), -(0.5f64.sqrt())))
                < 1e-12
        );
    }

    #[test]
    fn noisy_circle_is_smooth_within_tolerance() {
        // a 200-gon with ±0.02 mm radial jitter: fitted with few segments, all points within tol
        let mut p = circle(200, 40.0);
        for (i, q) in p.iter_mut().enumerate() {
            *q *= 1.0 + 0.0005 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
        }
        let tol = 0.1;
        let c = find_corners(&p, &[], DEFAULT_CORNER_DEG);
        assert!(c.is_empty(), "no corners on a circle: {c:?}");
        let segs = fit_closed(&p, &c, tol);
        assert!(segs.len() <= 8, "{} segments", segs.len());
        let flat = flatten_closed(&segs, 0.005);
        for q in &p {
            assert!(poly::dist_to_closed(&flat, *q) <= tol + 0.006);
        }
        // and the fitted path stays close to the true circle (no facets)
        for q in &flat {
            assert!((q.length() - 40.0).abs() < 0.1);
        }
    }

    #[test]
    fn flatten_respects_chord_tolerance_on_cubic() {
        let s = PathSeg::Cubic {
            p0: DVec2::ZERO,
            c1: DVec2::new(10., 30.),
            c2: DVec2::new(40., -20.),
            p1: DVec2::new(50., 0.),
        };
        let mut pl = Vec::new();
        s.flatten(0.01, &mut pl);
        for k in 0..=1000 {
            let q = s.eval(k as f64 / 1000.0);
            let d = pl
                .windows(2)
                .map(|w| poly::seg_nearest(w[0], w[1], q).0)
                .fold(f64::INFINITY, f64::min);
            assert!(d <= 0.01 + 1e-9, "deviation {d}");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
        /// Ellipses with a flattened "D" side (a corner pair), densely sampled: every input point
        /// lies within the tolerance of the fitted path, and the fit is far sparser than the input.
        #[test]
        fn fit_stays_within_tolerance(a in 20.0f64..120.0, b in 10.0f64..80.0, n in 60usize..300,
                                      cut in 0.0f64..0.9, tol in 0.02f64..0.3) {
            let xcut = a * (1.0 - cut);
            let p: Vec<DVec2> = (0..n)
                .map(|i| {
                    let q = DVec2::new(a * (i as f64 / n as f64 * 2.0 * PI).cos(), b * (i as f64 / n as f64 * 2.0 * PI).sin());
                    DVec2::new(q.x.min(xcut), q.y)
                })
                .collect();
            let p = poly::dedup_closed(&p, 1e-9);
            let c = find_corners(&p, &[], DEFAULT_CORNER_DEG);
            let segs = fit_closed(&p, &c, tol);
            let flat = flatten_closed(&segs, tol * 0.05);
            for q in &p {
                let d = poly::dist_to_closed(&flat, *q);
                proptest::prop_assert!(d <= tol * 1.05 + 1e-9, "point {q} off by {d}");
            }
            proptest::prop_assert!(segs.len() < p.len(), "{} segments for {} points", segs.len(), p.len());
            if n >= 150 && tol >= 0.05 {
                // dense input and a workshop tolerance: the facets are gone
                proptest::prop_assert!(segs.len() * 3 <= p.len(), "{} segments for {} points", segs.len(), p.len());
            }
            // consecutive segments join
            for k in 0..segs.len() {
                let next = segs[(k + 1) % segs.len()];
                proptest::prop_assert!(segs[k].end().distance(next.start()) < 1e-9);
            }
        }
    }
}
