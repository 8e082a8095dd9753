//! The allowance at one vertex of the sew line: the patch that closes the cut line between the
//! strips of the two edges meeting there (mitred, squared, or the offset lines joined where
//! their widths differ), and, where one edge's allowance is turned back (a hem, a fold), the
//! corner reflected about that edge's sew line so the turned allowance lies flat.
//!
//! A reflected corner is Seamly2D's "by first edge symmetry" done on the cut lines: the other
//! edge's cut line is mirrored about the turned edge's sew line, and the turned allowance ends
//! on that mirror image. Folded back, its end then lies exactly along the neighbour's cut line.
//! The allowance beyond the mirror image (which the turned edge's own strip may reach when the
//! corner is acute) is clipped off after the union.

use flatcut_geom::DVec2;

/// How the allowance is closed at a convex corner of the sew line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CornerStyle {
    /// The two cut lines are extended until they meet (up to the mitre limit, then squared).
    #[default]
    Mitred,
    /// The corner is cut square to the bisector at the larger width from the sew corner.
    Squared,
    /// The allowance of the incoming seam ends on the mirror image of the outgoing seam's cut
    /// line about the incoming sew line (as it lies when the allowance is folded back along the
    /// incoming seam), so the folded allowance matches the neighbouring seam: Seamly2D's "by
    /// first edge symmetry" (this module).
    Reflected,
}

/// How the allowance is closed at one vertex of the sew line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corner {
    /// Joined in a corner style (at a corner of the fit) or mitred (inside a fitted curve).
    Join(CornerStyle),
    /// The incoming edge's allowance is turned back: reflected about its sew line.
    FoldIncoming,
    /// The outgoing edge's allowance is turned back: reflected about its sew line.
    FoldOutgoing,
}

/// Corner patches of vertices turning less than this (radians) are skipped for equal widths:
/// the neighbouring strips already overlap within this chord sagitta.
const TURN_EPS: f64 = 1e-9;

/// What one vertex adds to the allowance region and what it clips off it.
#[derive(Default)]
pub(crate) struct Parts {
    /// Polygons united with the strips (counter-clockwise).
    pub add: Vec<Vec<DVec2>>,
    /// Polygons taken away from the union afterwards.
    pub clip: Vec<Vec<DVec2>>,
}

/// The outward (right) normal of a counter-clockwise edge direction.
pub(crate) fn right_normal(d: DVec2) -> DVec2 {
    DVec2::new(d.y, -d.x)
}

/// The intersection of the lines `a + s·da` and `b + t·db`, if they are not parallel.
pub(crate) fn line_intersect(a: DVec2, da: DVec2, b: DVec2, db: DVec2) -> Option<DVec2> {
    let den = da.perp_dot(db);
    if den.abs() < 1e-12 {
        return None;
    }
    let t = (b - a).perp_dot(db) / den;
    Some(a + da * t)
}

fn push_ccw(out: &mut Vec<Vec<DVec2>>, ring: Vec<DVec2>) {
    let a = crate::poly::signed_area(&ring);
    if a.abs() < 1e-12 {
        return;
    }
    let mut r = ring;
    if a < 0.0 {
        r.reverse();
    }
    out.push(r);
}

/// One vertex `v` of the sew line: the incoming edge runs along `dp` with allowance `wp`, the
/// outgoing one along `dn` with `wn` (unit directions).
pub(crate) struct Vertex {
    pub v: DVec2,
    pub dp: DVec2,
    pub dn: DVec2,
    pub wp: f64,
    pub wn: f64,
}

impl Vertex {
    fn a(&self) -> DVec2 {
        self.v + right_normal(self.dp) * self.wp
    }
    fn b(&self) -> DVec2 {
        self.v + right_normal(self.dn) * self.wn
    }
    fn wmax(&self) -> f64 {
        self.wp.max(self.wn)
    }
    /// The intersection of the two cut lines (the two edges' offsets).
    fn mitre(&self) -> Option<DVec2> {
        line_intersect(self.a(), self.dp, self.b(), self.dn)
    }
}

/// The parts vertex `x` adds to the allowance region, closed as `corner` says.
pub(crate) fn parts(x: &Vertex, corner: Corner, mitre_limit: f64, out: &mut Parts) {
    if (x.wp <= 0.0 && x.wn <= 0.0) || x.dp == DVec2::ZERO || x.dn == DVec2::ZERO {
        return;
    }
    let turn = x.dp.perp_dot(x.dn);
    if turn <= TURN_EPS {
        concave(x, turn, mitre_limit, out);
        return;
    }
    let folded = match corner {
        Corner::FoldIncoming | Corner::Join(CornerStyle::Reflected) => fold(x, true, mitre_limit),
        Corner::FoldOutgoing => fold(x, false, mitre_limit),
        Corner::Join(_) => None,
    };
    if let Some(f) = folded {
        out.add.extend(f.add);
        out.clip.extend(f.clip);
        return;
    }
    let style = match corner {
        Corner::Join(CornerStyle::Squared) => CornerStyle::Squared,
        _ => CornerStyle::Mitred,
    };
    convex(x, style, mitre_limit, &mut out.add);
}

/// A concave or straight vertex: with equal widths the strips overlap and nothing is added;
/// with different widths the two cut lines are joined where they meet (no notch is left between
/// the wider strip's end and the narrower cut line), or, when they meet too far away (nearly
/// straight), the cut line steps across along the normal.
fn concave(x: &Vertex, turn: f64, mitre_limit: f64, add: &mut Parts) {
    if (x.wp - x.wn).abs() <= 1e-12 {
        return;
    }
    let (v, a, b) = (x.v, x.a(), x.b());
    match x.mitre() {
        Some(m) if turn < -TURN_EPS && m.distance(v) <= mitre_limit * x.wmax() => {
            push_ccw(&mut add.add, vec![v, a, m]);
            push_ccw(&mut add.add, vec![v, m, b]);
        }
        _ => push_ccw(&mut add.add, vec![v, a, b]),
    }
}

/// A convex vertex, mitred (squared beyond the mitre limit) or squared at the larger width.
fn convex(x: &Vertex, style: CornerStyle, mitre_limit: f64, add: &mut Vec<Vec<DVec2>>) {
    let (v, a, b, dp, dn) = (x.v, x.a(), x.b(), x.dp, x.dn);
    let wmax = x.wmax();
    let squared = |add: &mut Vec<Vec<DVec2>>| {
        // cut perpendicular to the outward bisector at distance wmax from v
        let bis = (right_normal(dp) + right_normal(dn)).normalize_or_zero();
        let q = v + bis * wmax;
        let perp = DVec2::new(-bis.y, bis.x);
        let pa = line_intersect(a, dp, q, perp).unwrap_or(a);
        let pb = line_intersect(b, dn, q, perp).unwrap_or(b);
        push_ccw(add, vec![v, a, pa, pb, b]);
    };
    let limit = match style {
        CornerStyle::Squared => wmax * (1.0 + 1e-9),
        _ => mitre_limit * wmax,
    };
    match x.mitre() {
        Some(m) if m.distance(v) <= limit => push_ccw(add, vec![v, a, m, b]),
        _ => squared(add),
    }
}

/// The reflected corner where the incoming (`incoming`) or the outgoing edge's allowance is
/// turned back; `None` where the construction degenerates (the edges nearly straight, the
/// mirror image beyond the mitre limit): the caller mitres instead.
fn fold(x: &Vertex, incoming: bool, mitre_limit: f64) -> Option<Parts> {
    // t: the turned edge; o: the other. `e` runs along the turned edge's sew line toward and past
    // the vertex, away from the turned edge's body.
    let (e, wt, nt, d_o, wo, no) = if incoming {
        (
            x.dp,
            x.wp,
            right_normal(x.dp),
            x.dn,
            x.wn,
            right_normal(x.dn),
        )
    } else {
        (
            -x.dn,
            x.wn,
            right_normal(x.dn),
            x.dp,
            x.wp,
            right_normal(x.dp),
        )
    };
    if wt <= 0.0 {
        return None;
    }
    let v = x.v;
    let a_t = v + nt * wt;
    let b_o = v + no * wo;
    // X: where the other edge's cut line crosses the turned edge's sew line; its mirror image
    // about that line passes X too and meets the turned edge's cut line at P1.
    let cross = line_intersect(b_o, d_o, v, e)?;
    let mirrored = 2.0 * d_o.dot(e) * e - d_o;
    let p1 = line_intersect(a_t, e, cross, mirrored)?;
    let limit = mitre_limit * x.wmax();
    if cross.distance(v) > limit || p1.distance(v) > limit {
        return None;
    }
    let mut out = Parts::default();
    for tri in [[v, a_t, p1], [v, p1, cross], [v, cross, b_o]] {
        push_ccw(&mut out.add, tri.to_vec());
    }
    // Everything between the sew line and the turned edge's cut line beyond the mirror image.
    let reach = 2.0 * (wt + wo + cross.distance(v) + p1.distance(v));
    push_ccw(
        &mut out.clip,
        vec![cross, p1, p1 + e * reach, cross + e * reach],
    );
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// A hem along +x meeting a seam that leans in by `alpha` (a flared skirt's hem corner).
    fn hem_corner(alpha: f64, wp: f64, wn: f64) -> Vertex {
        Vertex {
            v: DVec2::ZERO,
            dp: DVec2::X,
            dn: v(-alpha.sin(), alpha.cos()),
            wp,
            wn,
        }
    }

    #[test]
    fn a_square_hem_corner_reflects_to_a_square() {
        let mut p = Parts::default();
        parts(
            &hem_corner(0.0, 40.0, 15.0),
            Corner::FoldIncoming,
            4.0,
            &mut p,
        );
        // X = (15, 0), P1 = (15, −40): the patch is the rectangle's corner
        let pts: Vec<DVec2> = p.add.iter().flatten().copied().collect();
        assert!(
            pts.iter().any(|q| q.distance(v(15., -40.)) < 1e-9),
            "{pts:?}"
        );
        assert!(pts.iter().any(|q| q.distance(v(15., 0.)) < 1e-9));
    }

    #[test]
    fn a_flared_hem_ends_on_the_mirror_of_the_side_seams_cut_line() {
        let alpha = 0.3f64;
        let (wp, wn) = (40.0, 15.0);
        let mut p = Parts::default();
        parts(
            &hem_corner(alpha, wp, wn),
            Corner::FoldIncoming,
            4.0,
            &mut p,
        );
        let (s, c) = alpha.sin_cos();
        // the side seam's cut line crosses the hem line at X = (wn / cos α, 0); its mirror image
        // meets the hem's cut line y = −wp at x = (wn − wp·sin α) / cos α
        let x = v(wn / c, 0.0);
        let p1 = v((wn - wp * s) / c, -wp);
        let pts: Vec<DVec2> = p.add.iter().flatten().copied().collect();
        assert!(pts.iter().any(|q| q.distance(x) < 1e-9), "{pts:?}");
        assert!(pts.iter().any(|q| q.distance(p1) < 1e-9), "{pts:?}");
        // folded up about y = 0, P1 lands on the side seam's cut line
        let folded = v(p1.x, -p1.y);
        let on_cut = (folded - v(wn * c, wn * s)).perp_dot(v(-s, c)).abs();
        assert!(on_cut < 1e-9, "{on_cut}");
        assert_eq!(p.clip.len(), 1);
    }

    #[test]
    fn different_widths_at_a_concave_corner_meet_at_their_cut_lines() {
        // incoming along +x, outgoing turning right by 60°: widths 16 and 8
        let x = Vertex {
            v: DVec2::ZERO,
            dp: DVec2::X,
            dn: DVec2::from_angle(-std::f64::consts::FRAC_PI_3),
            wp: 16.0,
            wn: 8.0,
        };
        let mut p = Parts::default();
        parts(&x, Corner::Join(CornerStyle::Mitred), 4.0, &mut p);
        let m = x.mitre().unwrap();
        assert!(p.add.iter().flatten().any(|q| q.distance(m) < 1e-12));
        // m is on both cut lines
        assert!(((m - x.a()).perp_dot(x.dp)).abs() < 1e-9);
        assert!(((m - x.b()).perp_dot(x.dn)).abs() < 1e-9);
    }
}
