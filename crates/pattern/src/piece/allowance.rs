//! The cut line: the sew line grown by its edges' allowances, each vertex closed as its edges
//! ask (a turned hem or fold reflected at its ends, the piece's corner style at the corners of
//! the fit, mitred inside fitted curves), with the seam kernel's failures turned into errors
//! that name the piece.

use super::sew::SewLine;
use super::{PatternError, PieceOptions};
use crate::corner::Corner;
use crate::corner::CornerStyle;
use crate::seam::{self, SeamFailure};
use flatcut_geom::DVec2;

/// The cut line around `sew` (CCW, closed).
pub(super) fn cut_line(
    name: &str,
    sew: &SewLine,
    style: CornerStyle,
    opts: &PieceOptions,
) -> Result<Vec<DVec2>, PatternError> {
    match seam::allowance(
        &sew.polyline,
        &sew.widths(),
        &corners(sew, style),
        opts.mitre_limit,
        opts.chord_tol.max(1e-6),
    ) {
        Ok(r) => Ok(r.cut),
        Err(SeamFailure::TooLarge(reason)) => Err(PatternError::AllowanceTooLarge {
            piece: name.into(),
            reason,
        }),
        Err(SeamFailure::Engine(reason)) => Err(PatternError::OffsetFailed {
            piece: name.into(),
            reason,
        }),
    }
}

/// How each vertex of the sew line is closed: where a turned edge (hem, fold) meets one that is
/// not, reflected about the turned edge; at the other corners of the fit in the piece's style;
/// inside fitted curves mitred (their turns are a chord's).
fn corners(sew: &SewLine, style: CornerStyle) -> Vec<Corner> {
    let n = sew.polyline.len();
    (0..n)
        .map(|i| {
            let (p, q) = (sew.finish[(i + n - 1) % n], sew.finish[i]);
            let (tp, tq) = (p.kind.is_turned(), q.kind.is_turned());
            if p.stretch != q.stretch && tp != tq {
                if tp {
                    Corner::FoldIncoming
                } else {
                    Corner::FoldOutgoing
                }
            } else if sew.corner[i] {
                Corner::Join(style)
            } else {
                Corner::Join(CornerStyle::Mitred)
            }
        })
        .collect()
}
