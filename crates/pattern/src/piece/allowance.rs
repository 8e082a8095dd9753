//! The cut line: the sew line grown by its seam widths, with the seam kernel's failures turned
//! into errors that name the piece.

use super::sew::SewLine;
use super::{PatternError, PieceOptions};
use crate::seam::{self, CornerStyle, SeamFailure};
use flatcut_geom::DVec2;

/// The cut line around `sew` (CCW, closed).
pub(super) fn cut_line(
    name: &str,
    sew: &SewLine,
    corner: CornerStyle,
    opts: &PieceOptions,
) -> Result<Vec<DVec2>, PatternError> {
    match seam::allowance(
        &sew.polyline,
        &sew.edge_widths,
        corner,
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
