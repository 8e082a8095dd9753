//! Seam segments: the boundary divided at the marks that carry a boundary index, and the seam
//! width of each segment (see the module doc of [`super`]).

use super::outline::Outline;
use super::{MarkKind, PatternError, PieceInput, invalid};
use crate::poly;

/// Where the marks sit on the cleaned outline and how wide each seam segment is.
pub(super) struct SeamSegments {
    /// The outline vertex of each mark (by mark index): boundary marks and notches; `None` for
    /// marks inside the piece.
    pub mark_vertex: Vec<Option<usize>>,
    /// The vertices that start a seam segment, ascending (empty: one segment).
    starts: Vec<usize>,
    /// The seam width of each segment (mm).
    pub widths: Vec<f64>,
}

impl SeamSegments {
    /// Carries the marks onto `outline` and gives each segment its width from the input (none:
    /// `default_seam` everywhere; one: that everywhere; else one per segment).
    pub fn of(
        input: &PieceInput,
        outline: &Outline,
        default_seam: f64,
    ) -> Result<SeamSegments, PatternError> {
        let mark_vertex = mark_vertices(input, outline)?;
        let mut starts: Vec<usize> = input
            .marks
            .iter()
            .zip(&mark_vertex)
            .filter(|(m, _)| m.boundary_index.is_some())
            .filter_map(|(_, v)| *v)
            .collect();
        starts.sort_unstable();
        starts.dedup();
        let n_seg = starts.len().max(1);
        let widths: Vec<f64> = match input.seam_widths.len() {
            0 => vec![default_seam; n_seg],
            1 => vec![input.seam_widths[0]; n_seg],
            k if k == n_seg => input.seam_widths.clone(),
            k => {
                return Err(invalid(
                    &input.name,
                    format!("{k} seam widths for {n_seg} seam segments (between boundary marks)"),
                ));
            }
        };
        if let Some(w) = widths.iter().find(|w| **w < 0.0 || !w.is_finite()) {
            return Err(PatternError::AllowanceTooLarge {
                piece: input.name.clone(),
                reason: format!("negative width {w} mm"),
            });
        }
        Ok(SeamSegments {
            mark_vertex,
            starts,
            widths,
        })
    }

    /// The seam width at the segment that outline vertex `v` starts or lies in.
    pub fn width_at(&self, v: usize) -> f64 {
        let seg = if self.starts.is_empty() {
            0
        } else {
            match self.starts.iter().rposition(|&m| m <= v) {
                Some(j) => j,
                None => self.starts.len() - 1,
            }
        };
        self.widths[seg]
    }

    /// The outline vertices the fit must keep as corners: every mark on the boundary.
    pub fn forced_corners(&self) -> Vec<usize> {
        self.mark_vertex.iter().filter_map(|v| *v).collect()
    }
}

/// The outline vertex of each mark: a boundary index through the weld map, a notch without one
/// at its nearest vertex, other marks none.
fn mark_vertices(
    input: &PieceInput,
    outline: &Outline,
) -> Result<Vec<Option<usize>>, PatternError> {
    let n = outline.points.len();
    let mut out = Vec::with_capacity(input.marks.len());
    for (k, m) in input.marks.iter().enumerate() {
        let v = match (m.boundary_index, m.kind) {
            (Some(i), _) if i < outline.map.len() => Some(outline.map[i]),
            (Some(i), _) => {
                return Err(invalid(
                    &input.name,
                    format!("mark {k}: boundary index {i} out of range"),
                ));
            }
            (None, MarkKind::Notch) => {
                let (i, t, _, _) = poly::nearest_on_closed(&outline.points, m.pos);
                Some(if t < 0.5 { i } else { (i + 1) % n })
            }
            _ => None,
        };
        out.push(v);
    }
    Ok(out)
}
