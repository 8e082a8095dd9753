//! Whether a job marks the pieces it cuts: a profile with a pen, or a laser's engrave layer,
//! writes each piece's label (name, size, side of a pair) on it; a knife-only profile writes
//! nothing, so once cut the pieces of a set cannot be told apart by what is on them. Jobs say
//! which in their summaries.

use flatcut_pattern::{Drawing, Layer, StrokeKind};

use crate::profile::Profile;

/// What a job writes on its pieces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marking {
    /// The labels of this many pieces are written.
    Labelled {
        /// Pieces whose labels are written.
        pieces: usize,
        /// Pieces in the job.
        of: usize,
    },
    /// The profile writes no labels: the pieces come off the table unmarked.
    Unmarked {
        /// Pieces in the job.
        pieces: usize,
    },
}

impl Marking {
    /// What `profile` writes on the pieces of `drawing` (pieces counted by their outer cuts).
    pub fn of(profile: &Profile, drawing: &Drawing) -> Marking {
        let mut pieces: Vec<Option<u32>> = drawing
            .strokes
            .iter()
            .filter(|s| s.is_outer())
            .map(|s| s.piece)
            .collect();
        pieces.sort_unstable();
        pieces.dedup();
        let of = pieces.len();
        if !profile.layer(Layer::Engrave).enabled {
            return Marking::Unmarked { pieces: of };
        }
        let labelled = pieces
            .iter()
            .filter(|p| {
                drawing.strokes.iter().any(|s| {
                    s.piece == **p && s.kind == StrokeKind::Text && s.layer == Layer::Engrave
                })
            })
            .count();
        Marking::Labelled {
            pieces: labelled,
            of,
        }
    }

    /// Whether every piece is marked.
    pub fn all_marked(&self) -> bool {
        matches!(self, Marking::Labelled { pieces, of } if pieces == of)
    }

    /// One line for a job's summary.
    pub fn note(&self, profile: &str) -> String {
        match *self {
            Marking::Labelled { pieces, of } if pieces == of => format!(
                "labels written on all {of} pieces (name, size and side; the {profile} profile's engrave layer)"
            ),
            Marking::Labelled { pieces, of } => format!(
                "labels written on {pieces} of {of} pieces (the others have no label in the pattern)"
            ),
            Marking::Unmarked { pieces } => format!(
                "pieces are unmarked: the {profile} profile writes no labels, so the {pieces} pieces cannot be told apart by size or side once cut; sort them as they come off the table, or cut with a profile that has a pen or an engrave layer"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec2;
    use flatcut_pattern::Stroke;

    fn stroke(kind: StrokeKind, layer: Layer, piece: u32) -> Stroke {
        Stroke {
            layer,
            points: vec![DVec2::ZERO, DVec2::X, DVec2::ONE],
            closed: kind == StrokeKind::Boundary,
            piece: Some(piece),
            kind,
            id: String::new(),
        }
    }

    #[test]
    fn a_knife_leaves_pieces_unmarked_and_a_pen_labels_them() {
        let d = Drawing::from_strokes(vec![
            stroke(StrokeKind::Boundary, Layer::Cut, 1),
            stroke(StrokeKind::Text, Layer::Engrave, 1),
            stroke(StrokeKind::Boundary, Layer::Cut, 2),
            stroke(StrokeKind::Text, Layer::Engrave, 2),
        ]);
        let knife = Marking::of(&Profile::knife(), &d);
        assert_eq!(knife, Marking::Unmarked { pieces: 2 });
        assert!(knife.note("knife").starts_with("pieces are unmarked"));
        let pen = Marking::of(&Profile::pen(), &d);
        assert_eq!(pen, Marking::Labelled { pieces: 2, of: 2 });
        assert!(pen.all_marked());
        let laser = Marking::of(&Profile::laser(), &d);
        assert!(laser.all_marked());
    }
}
