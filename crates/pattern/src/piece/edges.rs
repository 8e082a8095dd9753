//! Allowances by edge: the named stretches of a piece's outline ([`EdgeAllowance`]) carried onto
//! the cleaned outline, every outline edge given its width and kind (the rest of the outline
//! takes the piece's default seam width), and where the marks sit.
//!
//! A stretch runs counter-clockwise from its `from` vertex to its `to` vertex (`from == to`: the
//! whole outline). Its ends are corners of the sew line, so the fitted curves never run across
//! a change of allowance and the cut line changes width exactly there.

use super::outline::Outline;
use super::{MarkKind, PatternError, PieceInput, invalid};
use crate::poly;
use serde::{Deserialize, Serialize};

/// What an edge of a pattern piece is, for its allowance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EdgeKind {
    /// Sewn to another edge (the default).
    #[default]
    Seam,
    /// Turned back and stitched: the allowance is folded along the sew line, so the corners at
    /// the stretch's ends are reflected (the folded allowance lies flat against its neighbours).
    Hem,
    /// Folded along the sew line (a leather topline's folded edge): reflected corners, as a hem.
    Fold,
    /// Pulled over the last and cemented under it: written LASTING on the pattern.
    Lasting,
    /// Cut on the line, no allowance (the top piece of a lapped seam).
    Raw,
}

impl EdgeKind {
    /// The allowance is turned back along the sew line (its end corners are reflected).
    pub fn is_turned(self) -> bool {
        matches!(self, EdgeKind::Hem | EdgeKind::Fold)
    }

    /// The kind's name as designs write it.
    pub fn name(self) -> &'static str {
        match self {
            EdgeKind::Seam => "seam",
            EdgeKind::Hem => "hem",
            EdgeKind::Fold => "fold",
            EdgeKind::Lasting => "lasting",
            EdgeKind::Raw => "raw",
        }
    }
}

/// A named stretch of a piece's outline with its own allowance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeAllowance {
    /// Names the edge in errors, annotations and reports (a design's edge or style line).
    pub name: String,
    /// How the stretch is finished: seam, hem, fold, lasting or raw.
    pub kind: EdgeKind,
    /// Allowance in mm; `None`: the piece's default seam width. A raw edge has none (0).
    pub width: Option<f64>,
    /// Outline vertex (index into [`PieceInput::outline`]) where the stretch starts.
    pub from: usize,
    /// Outline vertex where it ends, counter-clockwise from `from`; `to == from`: the whole
    /// outline.
    pub to: usize,
}

impl EdgeAllowance {
    /// The allowance in mm (`default` where the edge gives none; 0 on a raw edge).
    pub fn width_or(&self, default: f64) -> f64 {
        match self.kind {
            EdgeKind::Raw => 0.0,
            _ => self.width.unwrap_or(default),
        }
    }
}

/// How each edge of the cleaned outline is finished, and where the marks sit on it.
pub(super) struct OutlineEdges {
    /// The outline vertex of each mark (by mark index): boundary marks and notches; `None` for
    /// marks inside the piece.
    pub mark_vertex: Vec<Option<usize>>,
    /// For each cleaned outline edge (vertex i → i + 1), the named stretch it belongs to.
    pub edge_of: Vec<Option<usize>>,
    /// The width (mm) and kind of each named stretch, then of the rest of the outline (last).
    finish: Vec<(f64, EdgeKind)>,
    /// Vertices the fit must keep as corners: boundary marks and the ends of named stretches.
    corners: Vec<usize>,
}

impl OutlineEdges {
    /// Carries the marks and the named stretches onto `outline`; refuses a stretch whose ends
    /// are not outline vertices, a negative or non-finite width, and two stretches that share
    /// an edge.
    pub fn of(
        input: &PieceInput,
        outline: &Outline,
        default_seam: f64,
    ) -> Result<OutlineEdges, PatternError> {
        let n = outline.points.len();
        let mark_vertex = mark_vertices(input, outline)?;
        let mut corners: Vec<usize> = mark_vertex.iter().filter_map(|v| *v).collect();
        if !(default_seam.is_finite() && default_seam >= 0.0) {
            return Err(PatternError::AllowanceTooLarge {
                piece: input.name.clone(),
                reason: format!("default seam width {default_seam} mm"),
            });
        }
        let mut edge_of: Vec<Option<usize>> = vec![None; n];
        let mut finish = Vec::with_capacity(input.edges.len() + 1);
        for (k, e) in input.edges.iter().enumerate() {
            let w = e.width_or(default_seam);
            if !(w.is_finite() && w >= 0.0) {
                return Err(PatternError::AllowanceTooLarge {
                    piece: input.name.clone(),
                    reason: format!("edge '{}': width {w} mm", e.name),
                });
            }
            finish.push((w, e.kind));
            let vertex = |i: usize, end: &str| {
                outline.map.get(i).copied().ok_or_else(|| {
                    invalid(
                        &input.name,
                        format!(
                            "edge '{}': `{end}` is vertex {i}, but the outline has {} vertices",
                            e.name,
                            outline.map.len()
                        ),
                    )
                })
            };
            let (a, b) = (vertex(e.from, "from")?, vertex(e.to, "to")?);
            if a == b && e.from != e.to {
                return Err(invalid(
                    &input.name,
                    format!(
                        "edge '{}': `from` and `to` are one point of the outline",
                        e.name
                    ),
                ));
            }
            let mut i = a;
            loop {
                if let Some(j) = edge_of[i] {
                    return Err(invalid(
                        &input.name,
                        format!(
                            "edges '{}' and '{}' overlap at ({:.2}, {:.2}) mm",
                            input.edges[j].name, e.name, outline.points[i].x, outline.points[i].y
                        ),
                    ));
                }
                edge_of[i] = Some(k);
                i = (i + 1) % n;
                if i == b {
                    break;
                }
            }
            if a != b {
                corners.extend([a, b]);
            }
        }
        finish.push((default_seam, EdgeKind::Seam));
        corners.sort_unstable();
        corners.dedup();
        Ok(OutlineEdges {
            mark_vertex,
            edge_of,
            finish,
            corners,
        })
    }

    /// The named stretch (index into the input's edges) of the edge that outline vertex `v`
    /// starts.
    pub fn stretch_at(&self, v: usize) -> Option<usize> {
        self.edge_of[v % self.edge_of.len()]
    }

    /// The width (mm) and kind of the edge that outline vertex `v` starts.
    pub fn finish_at(&self, v: usize) -> (f64, EdgeKind) {
        match self.stretch_at(v) {
            Some(k) => self.finish[k],
            None => self.finish[self.finish.len() - 1],
        }
    }

    /// The outline vertices the fit must keep as corners.
    pub fn forced_corners(&self) -> &[usize] {
        &self.corners
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
