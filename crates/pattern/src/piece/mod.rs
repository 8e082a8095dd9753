//! A pattern piece as a cutting room uses it: the fitted sew line, the cut line with seam
//! allowance, notches at match marks, drill holes, the grain line and a label.
//!
//! Input is a flattened boundary (closed polyline in mm, counter-clockwise) with marks; the
//! piece is built by [`Piece::build`] and turned into a [`Drawing`](crate::Drawing) by [`Piece::to_drawing`].
//! Allowances by edge: named stretches of the outline ([`EdgeAllowance`]) carry their own width
//! and kind (seam, hem, fold, lasting, raw); the rest of the outline takes
//! [`PieceOptions::default_seam`].

mod allowance;
mod draw;
mod edge_marks;
mod edges;
mod grain_line;
mod label;
#[cfg(test)]
mod label_tests;
mod marks;
mod orient;
mod outline;
mod placement;
mod sew;
#[cfg(test)]
mod tests;

pub use crate::label_info::LabelInfo;
pub use crate::placement::Placement;
pub use edges::{EdgeAllowance, EdgeKind};
pub use grain_line::grain_line_along;
pub use label::short_code;
pub use orient::orientation;
pub use placement::PlacedPiece;

use crate::PatternError;
use crate::corner::CornerStyle;
use crate::fit::{self, PathSeg};
use crate::poly;
use crate::seam;
use flatcut_geom::{Aabb2, DVec2};
use serde::{Deserialize, Serialize};

/// What a mark is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MarkKind {
    /// A match mark on the boundary: cut as a notch so pieces are sewn in register.
    Notch,
    /// A drill hole (pocket corners, dart ends): punched/cut as a small circle.
    Drill,
    /// A drawn reference point (button, placement): a small cross on the draw layer.
    Point,
}

/// A mark on the piece.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mark {
    /// A notch, a drill hole or a drawn point.
    pub kind: MarkKind,
    /// Position in the piece's flat frame (mm).
    pub pos: DVec2,
    /// Index of the outline vertex the mark sits on, when it lies on the boundary (notches,
    /// seam ends). Notches without it snap to the nearest outline vertex.
    pub boundary_index: Option<usize>,
}

/// Everything a piece is built from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PieceInput {
    /// Piece name; used in ids and error messages.
    pub name: String,
    /// Sew line, closed (first point not repeated), counter-clockwise, mm.
    pub outline: Vec<DVec2>,
    /// Notches, drill holes and reference points.
    pub marks: Vec<Mark>,
    /// Drawn internal lines (stitch lines, placement lines), open polylines in the flat frame
    /// (mm), each of at least two points.
    #[serde(default)]
    pub lines: Vec<Vec<DVec2>>,
    /// Sew lines inside the piece: the legs of a folded dart, mouth to point to mouth, open
    /// polylines (mm).
    #[serde(default)]
    pub sew_lines: Vec<Vec<DVec2>>,
    /// Grain line as two points in the flat frame (direction carried through the map).
    pub grain: Option<(DVec2, DVec2)>,
    /// Named stretches of the outline with their own allowance (see the module doc); they must
    /// not overlap.
    #[serde(default)]
    pub edges: Vec<EdgeAllowance>,
    /// How the allowance turns at the outline's corners.
    pub corner_style: CornerStyle,
    /// What the piece's label says.
    pub label: LabelInfo,
    /// Names of the notch marks, by mark index (a mating seam's notch carries the seam's name
    /// into the notch's id); marks past its end, and empty names, are unnamed.
    #[serde(default)]
    pub mark_names: Vec<String>,
}

impl PieceInput {
    /// A piece with an outline only; everything else default.
    pub fn new(name: impl Into<String>, outline: Vec<DVec2>) -> Self {
        let name = name.into();
        Self {
            label: LabelInfo {
                name: name.clone(),
                quantity: 1,
                ..LabelInfo::default()
            },
            name,
            outline,
            marks: Vec::new(),
            lines: Vec::new(),
            sew_lines: Vec::new(),
            grain: None,
            edges: Vec::new(),
            corner_style: CornerStyle::default(),
            mark_names: Vec::new(),
        }
    }
}

/// Notch shape.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NotchStyle {
    /// A single slit perpendicular to the cut line (knife cutters).
    #[default]
    Slit,
    /// A V (laser, scissors).
    V,
}

/// Options of [`Piece::build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PieceOptions {
    /// Outline fitting tolerance (mm).
    pub fit_tol: f64,
    /// Chordal tolerance when curves become polylines (mm).
    pub chord_tol: f64,
    /// Turn (degrees) above which a boundary vertex is kept as a corner.
    pub corner_deg: f64,
    /// Seam width of the outline's edges no named stretch covers (mm).
    pub default_seam: f64,
    /// Mitre limit in widths.
    pub mitre_limit: f64,
    /// How notches are cut: a slit or a V.
    pub notch_style: NotchStyle,
    /// Notch depth (mm), clipped to 3/4 of the local allowance.
    pub notch_depth: f64,
    /// Opening of a V notch (mm).
    pub notch_width: f64,
    /// Drill-hole diameter (mm).
    pub drill_diameter: f64,
    /// Maximum label cap height (mm); smaller when the piece is small.
    pub label_height: f64,
}

impl PieceOptions {
    /// 0.1 mm: below what knife or laser reproduces, well above mesh facet noise.
    pub const DEFAULT_FIT_TOL: f64 = 0.1;
    /// 0.02 mm chordal error on exported polylines.
    pub const DEFAULT_CHORD_TOL: f64 = 0.02;
    /// 10 mm: the usual garment seam allowance (3/8").
    pub const DEFAULT_SEAM: f64 = 10.0;
    /// 4 mm notch: visible on the cut piece, short of a 10 mm seam.
    pub const DEFAULT_NOTCH_DEPTH: f64 = 4.0;
    /// 2 mm V opening.
    pub const DEFAULT_NOTCH_WIDTH: f64 = 2.0;
    /// 3 mm drill (a common awl/punch size).
    pub const DEFAULT_DRILL_DIAMETER: f64 = 3.0;
    /// 6 mm cap height reads well on fabric and leather.
    pub const DEFAULT_LABEL_HEIGHT: f64 = 6.0;
    /// The defaults above.
    pub const DEFAULT: Self = Self {
        fit_tol: Self::DEFAULT_FIT_TOL,
        chord_tol: Self::DEFAULT_CHORD_TOL,
        corner_deg: fit::DEFAULT_CORNER_DEG,
        default_seam: Self::DEFAULT_SEAM,
        mitre_limit: seam::DEFAULT_MITRE_LIMIT,
        notch_style: NotchStyle::Slit,
        notch_depth: Self::DEFAULT_NOTCH_DEPTH,
        notch_width: Self::DEFAULT_NOTCH_WIDTH,
        drill_diameter: Self::DEFAULT_DRILL_DIAMETER,
        label_height: Self::DEFAULT_LABEL_HEIGHT,
    };
    /// These options with fitting tolerance `v` (mm).
    pub fn with_fit_tol(mut self, v: f64) -> Self {
        self.fit_tol = v;
        self
    }
    /// These options with chordal tolerance `v` (mm).
    pub fn with_chord_tol(mut self, v: f64) -> Self {
        self.chord_tol = v;
        self
    }
    /// These options with default seam width `v` (mm).
    pub fn with_default_seam(mut self, v: f64) -> Self {
        self.default_seam = v;
        self
    }
    /// These options with notch style `v`.
    pub fn with_notch_style(mut self, v: NotchStyle) -> Self {
        self.notch_style = v;
        self
    }
    /// These options with notch depth `v` (mm).
    pub fn with_notch_depth(mut self, v: f64) -> Self {
        self.notch_depth = v;
        self
    }
    /// These options with corner threshold `v` (degrees).
    pub fn with_corner_deg(mut self, v: f64) -> Self {
        self.corner_deg = v;
        self
    }
    /// These options with maximum label cap height `v` (mm).
    pub fn with_label_height(mut self, v: f64) -> Self {
        self.label_height = v;
        self
    }
}

impl Default for PieceOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A built piece, in its own flat frame (mm, y up).
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// The piece's name, as ids and labels carry it.
    pub name: String,
    /// Fitted sew line: lines, arcs, cubics, closed.
    pub sew: Vec<PathSeg>,
    /// Sew line flattened within the chord tolerance (CCW).
    pub sew_polyline: Vec<DVec2>,
    /// Cut line (sew line plus allowance), CCW, closed.
    pub cut: Vec<DVec2>,
    /// Notch strokes (open polylines cut through the allowance).
    pub notches: Vec<Vec<DVec2>>,
    /// The name of each notch (empty when unnamed), in the order of `notches`.
    pub notch_names: Vec<String>,
    /// Drill holes: centre and diameter.
    pub drills: Vec<(DVec2, f64)>,
    /// Reference points (drawn crosses).
    pub points: Vec<DVec2>,
    /// Internal lines (stitch and placement lines), drawn, open.
    pub lines: Vec<Vec<DVec2>>,
    /// Sew lines inside the piece (dart legs), drawn, open.
    pub sew_lines: Vec<Vec<DVec2>>,
    /// Grain line end points.
    pub grain: Option<(DVec2, DVec2)>,
    /// What the label says (all of it, before shortening).
    pub label: LabelInfo,
    /// Label text strokes (open polylines).
    pub label_strokes: Vec<Vec<DVec2>>,
    /// The lines the label writes (all of the label's, the first few, or its short code where
    /// the piece has no room for more at [`MIN_LABEL_HEIGHT`]).
    pub label_text: Vec<String>,
    /// The label's cap height (mm); 0 without a label.
    pub label_height: f64,
    /// The outline as runs of one allowance: every named stretch and the default seam between
    /// them, in sew-line order.
    pub edges: Vec<PieceEdge>,
    /// Text written inside the allowance of lasting edges (LASTING), strokes in mm.
    pub edge_labels: Vec<Vec<DVec2>>,
    chord_tol: f64,
}

/// The smallest cap height (mm) a cutter reads on the cut piece: a label with less room is
/// shortened, down to the piece's short code.
pub const MIN_LABEL_HEIGHT: f64 = 3.0;

/// A run of the sew line with one allowance: a named stretch or the default seam between them.
#[derive(Clone, Debug, PartialEq)]
pub struct PieceEdge {
    /// The stretch's name (empty for the default seam).
    pub name: String,
    /// How the run is finished: seam, hem, fold, lasting or raw.
    pub kind: EdgeKind,
    /// Allowance (mm): the distance from the sew line to the cut line along the run.
    pub width: f64,
    /// The run's sew line, open, in order (mm).
    pub sew: Vec<DVec2>,
}

/// A piece name made safe for element ids and file names: ASCII letters, digits, `-` and `_`
/// kept, everything else `_`; an empty name is `piece`. Two pieces of a design must not share
/// it (the facade refuses such a design).
pub fn safe_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() { "piece".into() } else { s }
}

/// An invalid-input error of piece `piece`.
fn invalid(piece: &str, reason: String) -> PatternError {
    PatternError::InvalidInput {
        piece: piece.into(),
        reason,
    }
}

/// A non-finite-value error of piece `piece` in `what`.
fn non_finite(piece: &str, what: &str) -> PatternError {
    PatternError::NonFinite {
        piece: piece.into(),
        what: what.into(),
    }
}

/// Refuses non-finite coordinates and widths and non-positive tolerances before any geometry.
fn check_numbers(input: &PieceInput, opts: &PieceOptions) -> Result<(), PatternError> {
    let name = &input.name;
    if !input.outline.iter().all(|p| flatcut_geom::finite2(*p)) {
        return Err(non_finite(name, "outline"));
    }
    if !input.marks.iter().all(|m| flatcut_geom::finite2(m.pos)) {
        return Err(non_finite(name, "marks"));
    }
    if input
        .edges
        .iter()
        .any(|e| e.width.is_some_and(|w| !w.is_finite()))
    {
        return Err(non_finite(name, "edge widths"));
    }
    for (what, v) in [
        ("fit tolerance", opts.fit_tol),
        ("chord tolerance", opts.chord_tol),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(invalid(name, format!("{what} must be positive, got {v}")));
        }
    }
    Ok(())
}

impl Piece {
    /// Builds a piece; errors name the piece and what is wrong. The steps: the outline cleaned
    /// (`outline`), the outline's edges given their allowances (`edges`), the sew line
    /// fitted (`sew`), the allowance added (`allowance`), the marks and internal lines placed
    /// (`marks`), the lasting edges labelled (`edge_marks`) and the label laid out
    /// (`label`).
    pub fn build(input: &PieceInput, opts: &PieceOptions) -> Result<Piece, PatternError> {
        check_numbers(input, opts)?;
        let outline = outline::Outline::clean(&input.name, &input.outline)?;
        let edges = edges::OutlineEdges::of(input, &outline, opts.default_seam)?;
        let sew = sew::SewLine::fit(&input.name, &outline, &edges, opts)?;
        let cut = allowance::cut_line(&input.name, &sew, input.corner_style, opts)?;
        let placed = marks::place_marks(input, &outline, &edges, &sew.polyline, &cut, opts)?;
        let runs = edge_marks::runs(input, &sew);
        let lines = marks::internal_lines(input, &cut, opts.chord_tol)?;
        let sew_lines = marks::inner_sew_lines(input, opts.chord_tol)?;
        marks::check_grain(input)?;
        let edge_labels = edge_marks::lasting_labels(&runs, &sew.polyline, &cut);
        let mut piece = Piece {
            name: input.name.clone(),
            sew: sew.segs,
            sew_polyline: sew.polyline,
            cut,
            notches: placed.notches,
            notch_names: placed.notch_names,
            drills: placed.drills,
            points: placed.points,
            lines,
            sew_lines,
            grain: input.grain,
            label: input.label.clone(),
            label_strokes: Vec::new(),
            label_text: Vec::new(),
            label_height: 0.0,
            edges: runs,
            edge_labels,
            chord_tol: opts.chord_tol,
        };
        piece.lay_out_label(opts.label_height);
        Ok(piece)
    }

    /// Bounding box of the cut line.
    pub fn bbox(&self) -> Aabb2 {
        Aabb2::from_points(self.cut.iter().copied())
    }

    /// Area enclosed by the cut line (mm²).
    pub fn cut_area(&self) -> f64 {
        poly::signed_area(&self.cut)
    }

    /// Length of the cut line (mm).
    pub fn cut_length(&self) -> f64 {
        let n = self.cut.len();
        (0..n)
            .map(|i| self.cut[i].distance(self.cut[(i + 1) % n]))
            .sum()
    }

    /// Id prefix of instance `instance` of this piece, e.g. `vamp-1`.
    pub fn instance_id(&self, instance: u32) -> String {
        format!("{}-{}", safe_name(&self.name), instance)
    }

    /// The label fields with the piece's name filled in where the label has none.
    pub fn label_with_name(&self) -> LabelInfo {
        let mut l = self.label.clone();
        if l.name.is_empty() {
            l.name = self.name.clone();
        }
        l
    }
}
