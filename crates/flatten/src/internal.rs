//! What can only go wrong through a bug in flatcut: a broken invariant of a flattening method or
//! of the sparse solver's bookkeeping, one variant per invariant, each with the message the
//! report asks users to send ([`crate::FlattenError::Internal`]).

use crate::Method;

/// A broken invariant, named by what broke.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InternalError {
    /// A triangle of a mesh that passed the disk check has no rest frame (zero area).
    #[error("triangle {triangle} is degenerate after the disk check")]
    DegenerateTriangle {
        /// The triangle (0-based).
        triangle: usize,
    },
    /// The developable unfolding reached a triangle with no edge placed yet.
    #[error("developable: triangle {triangle} reached without a placed edge")]
    UnfoldWithoutEdge {
        /// The triangle (0-based).
        triangle: usize,
    },
    /// The developable unfolding placed an edge's two ends at one point.
    #[error("developable: edge {a}-{b} collapsed while unfolding")]
    UnfoldEdgeCollapsed {
        /// The edge's first vertex (0-based).
        a: u32,
        /// The edge's second vertex (0-based).
        b: u32,
    },
    /// A reduced system has no free unknown left to solve for.
    #[error("{stage}: every unknown is fixed")]
    EveryUnknownFixed {
        /// The solver stage (a static name of the step that failed).
        stage: &'static str,
    },
    /// The conformal-boundary method found no boundary loop on a disk.
    #[error("conformal-boundary: no boundary loop")]
    ConformalBoundaryNoLoop,
    /// LSCM found no boundary on a disk.
    #[error("lscm: the mesh has no boundary")]
    LscmNoBoundary,
    /// LSCM's two pinned boundary vertices are one vertex.
    #[error("lscm: the boundary has a single vertex")]
    LscmSingleVertex,
    /// Tutte's embedding was given a mesh with other than one boundary loop.
    #[error("tutte: a disk has one boundary loop, this mesh has {loops}")]
    TutteLoops {
        /// Boundary loops found.
        loops: usize,
    },
    /// A linear method was sent down the nonlinear methods' path.
    #[error("method {method} is not a nonlinear method")]
    NotNonlinear {
        /// The method.
        method: Method,
    },
    /// Material limits that exclude the identity map got past the parameter checks.
    #[error("material limits must allow the identity (σ ≤ {hi}, σ ≥ {lo})")]
    LimitsExcludeIdentity {
        /// The upper stretch limit σ1 (factor, not percent).
        hi: f64,
        /// The lower stretch limit σ2 (factor).
        lo: f64,
    },
    /// ARAP's solver asked for its cost before it had a start map.
    #[error("arap: no start map")]
    ArapNoStartMap,
    /// ARAP's solver asked for a step before it had a current map.
    #[error("arap: no current map")]
    ArapNoCurrentMap,
    /// ARAP's problem was taken out of its solver before the end.
    #[error("arap: the problem was moved out")]
    ArapProblemMoved,
    /// ARAP's solver ended without a result.
    #[error("arap: no result")]
    ArapNoResult,
    /// ARAP's flip-free line search let a flipped triangle through.
    #[error("arap: a flipped triangle survived the flip-free line search")]
    ArapFlipSurvived,
    /// The unknowns' grouping into nodes does not cover them.
    #[error("{labels} node labels (< {nodes}) for {unknowns} unknowns")]
    NodeLabels {
        /// Labels given (one per unknown).
        labels: usize,
        /// Number of nodes the labels must stay below.
        nodes: usize,
        /// Number of unknowns.
        unknowns: usize,
    },
    /// A matrix's values do not match its triplet pattern.
    #[error("{stage}: {got} values for a pattern of {want} triplets")]
    TripletCount {
        /// The solver stage.
        stage: &'static str,
        /// Values given.
        got: usize,
        /// Triplets in the pattern.
        want: usize,
    },
    /// A compressed-column pattern was asked for its triplet order.
    #[error("{stage}: a compressed-column pattern has no triplet order")]
    NoTripletOrder {
        /// The solver stage (a static name of the step that failed).
        stage: &'static str,
    },
    /// A compressed pattern's values do not fit the solver built for it.
    #[error(
        "{stage}: {values} values of a {size}×{size} pattern for a solver of {solver_values} values and size {solver_size}"
    )]
    GatherMismatch {
        /// The solver stage.
        stage: &'static str,
        /// Values given.
        values: usize,
        /// The pattern's size (rows = columns).
        size: usize,
        /// Values the solver was built for.
        solver_values: usize,
        /// The solver's size.
        solver_size: usize,
    },
    /// A factorisation's values do not match the solver's pattern.
    #[error("{stage}: {got} values for a pattern of {want} entries")]
    ValueCount {
        /// The solver stage.
        stage: &'static str,
        /// Values given.
        got: usize,
        /// Entries in the pattern.
        want: usize,
    },
    /// The factorisation's workspace was missing after it was made.
    #[error("{stage}: no factorisation scratch")]
    NoScratch {
        /// The solver stage (a static name of the step that failed).
        stage: &'static str,
    },
    /// A right-hand side of the wrong length.
    #[error("{stage}: right-hand side of length {len} for {columns} columns of size {size}")]
    RhsLength {
        /// The solver stage.
        stage: &'static str,
        /// The right-hand side's length.
        len: usize,
        /// Number of right-hand sides.
        columns: usize,
        /// The system's size.
        size: usize,
    },
    /// A solve asked of a solver whose last factorisation failed or never ran.
    #[error("{stage}: solve before a successful factorization")]
    SolveBeforeFactor {
        /// The solver stage (a static name of the step that failed).
        stage: &'static str,
    },
    /// A solve found no factor although the solver counts itself factored.
    #[error("{stage}: no factor to solve with")]
    NoFactor {
        /// The solver stage (a static name of the step that failed).
        stage: &'static str,
    },
}
