//! The outline as runs of one allowance ([`PieceEdge`]s), and what a lasting edge carries: the
//! word LASTING written inside its margin, upright, where the margin holds it at a readable
//! height.

use super::edges::EdgeKind;
use super::sew::SewLine;
use super::{MIN_LABEL_HEIGHT, PieceEdge, PieceInput};
use crate::poly;
use flatcut_font as font;
use flatcut_geom::DVec2;

/// What a lasting margin is labelled with.
pub const LASTING_TEXT: &str = "LASTING";
/// Largest cap height of the LASTING text (mm), and its share of the margin's width.
const LASTING_HEIGHT_MM: f64 = 5.0;
const LASTING_SHARE: f64 = 0.45;
/// Where along a run the text may sit (fractions of its length), tried in this order.
const ALONG: [f64; 5] = [0.5, 0.35, 0.65, 0.2, 0.8];

/// The sew line's runs of one finish, in sew-line order starting at a change of finish (one
/// closed run when the whole outline is finished alike).
pub(super) fn runs(input: &PieceInput, sew: &SewLine) -> Vec<PieceEdge> {
    let n = sew.polyline.len();
    let same = |i: usize, j: usize| {
        let (a, b) = (sew.finish[i], sew.finish[j]);
        a.stretch == b.stretch && a.kind == b.kind && a.width == b.width
    };
    let name = |i: usize| {
        sew.finish[i]
            .stretch
            .and_then(|k| input.edges.get(k))
            .map(|e| e.name.clone())
            .unwrap_or_default()
    };
    let Some(start) = (0..n).find(|&i| !same((i + n - 1) % n, i)) else {
        let mut pts = sew.polyline.clone();
        pts.extend(sew.polyline.first().copied());
        return vec![PieceEdge {
            name: name(0),
            kind: sew.finish[0].kind,
            width: sew.finish[0].width,
            sew: pts,
        }];
    };
    let mut out: Vec<PieceEdge> = Vec::new();
    let mut i = start;
    loop {
        let mut pts = vec![sew.polyline[i]];
        let first = i;
        loop {
            let j = (i + 1) % n;
            pts.push(sew.polyline[j]);
            i = j;
            if i == start || !same(first, i) {
                break;
            }
        }
        out.push(PieceEdge {
            name: name(first),
            kind: sew.finish[first].kind,
            width: sew.finish[first].width,
            sew: pts,
        });
        if i == start {
            return out;
        }
    }
}

/// LASTING written in the margin of every lasting run, along the run and upright, as large as
/// [`LASTING_HEIGHT_MM`] and at least [`MIN_LABEL_HEIGHT`]: wholly between the sew line and the
/// cut line, at the first place along the run that holds it. A margin too narrow or too
/// curved for that gets no text.
pub(super) fn lasting_labels(runs: &[PieceEdge], sew: &[DVec2], cut: &[DVec2]) -> Vec<Vec<DVec2>> {
    let mut out = Vec::new();
    for r in runs.iter().filter(|r| r.kind == EdgeKind::Lasting) {
        let h = (LASTING_SHARE * r.width).min(LASTING_HEIGHT_MM);
        if h < MIN_LABEL_HEIGHT {
            continue;
        }
        if let Some(text) = ALONG
            .iter()
            .find_map(|&f| text_in_margin(&r.sew, f, r.width, h, sew, cut))
        {
            out.extend(text);
        }
    }
    out
}

/// The text centred in the margin at fraction `f` of the run `line` (margin `width` mm), if it
/// lies wholly inside the cut line and outside the sew line there.
fn text_in_margin(
    line: &[DVec2],
    f: f64,
    width: f64,
    h: f64,
    sew: &[DVec2],
    cut: &[DVec2],
) -> Option<Vec<Vec<DVec2>>> {
    let len = font::text_width(LASTING_TEXT, h);
    let total: f64 = line.windows(2).map(|w| w[0].distance(w[1])).sum();
    if total < len {
        return None;
    }
    let s = (f * total).clamp(0.5 * len, total - 0.5 * len);
    let (a, b) = (at(line, s - 0.5 * len), at(line, s + 0.5 * len));
    let tangent = (b - a).normalize_or_zero();
    if tangent == DVec2::ZERO {
        return None;
    }
    let outward = DVec2::new(tangent.y, -tangent.x);
    let centre = 0.5 * (a + b) + outward * (0.5 * width);
    // upright: read left to right (bottom to top on a vertical run)
    let dir = if tangent.x < -1e-9 || (tangent.x.abs() <= 1e-9 && tangent.y < 0.0) {
        -tangent
    } else {
        tangent
    };
    let up = DVec2::new(-dir.y, dir.x);
    let origin = centre - dir * (0.5 * len) - up * (0.5 * h);
    let strokes = font::text_strokes(LASTING_TEXT, origin, h, dir);
    let inside = strokes.iter().flatten().all(|p| {
        poly::contains(cut, *p)
            && !poly::contains(sew, *p)
            && poly::dist_to_closed(sew, *p) > 0.1 * h
            && poly::dist_to_closed(cut, *p) > 0.1 * h
    });
    inside.then_some(strokes)
}

/// The point at arc length `s` along an open polyline.
fn at(line: &[DVec2], s: f64) -> DVec2 {
    let mut left = s.max(0.0);
    for w in line.windows(2) {
        let l = w[0].distance(w[1]);
        if left <= l && l > 0.0 {
            return w[0].lerp(w[1], left / l);
        }
        left -= l;
    }
    line.last().copied().unwrap_or(DVec2::ZERO)
}
