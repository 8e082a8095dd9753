//! One use of an edge in a face's loop: the unit the model's loops are made of and that
//! healing reorders and turns.

/// One use of an edge in a loop: forward when the loop runs from the edge's start vertex to its
/// end vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeUse {
    /// The edge (index into [`crate::Model::edges`]).
    pub edge: usize,
    /// True when the loop runs the edge from its start vertex to its end vertex.
    pub forward: bool,
}
