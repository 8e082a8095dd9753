//! Construction errors of curves and surfaces.

/// Why a curve or a surface could not be built. Messages name the offending element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// The number of control points does not match the degree / knot vector.
    #[error("wrong number of control points: expected {expected}, got {got}")]
    ControlPointCount { expected: usize, got: usize },
    /// Knots must be non-decreasing; `index` is the first knot that decreases.
    #[error("knot vector is decreasing at index {index} ({prev} > {next})")]
    DecreasingKnots { index: usize, prev: f64, next: f64 },
    /// A knot vector of the wrong length for its degree and control-point count.
    #[error("knot vector has {got} knots, expected {expected}")]
    KnotCount { expected: usize, got: usize },
    /// NURBS weights must be finite and strictly positive.
    #[error("weight {index} is {value}: weights must be finite and > 0")]
    BadWeight { index: usize, value: f64 },
    /// A coordinate is NaN or infinite.
    #[error("{what} {index} has a non-finite coordinate")]
    NonFinite { what: &'static str, index: usize },
    /// A degree of zero or one that is too high for the data.
    #[error("invalid degree {degree}: {reason}")]
    BadDegree { degree: usize, reason: &'static str },
    /// A size, radius or tolerance that must be finite and positive is not.
    #[error("{what} must be finite and > 0, got {value}")]
    NotPositive { what: String, value: f64 },
    /// A tolerance (named before its value) that must be finite and positive is not.
    #[error("{what} {value} must be finite and > 0")]
    BadTolerance { what: &'static str, value: f64 },
    /// A radius that must be finite and non-negative is not.
    #[error("{what} must be finite and >= 0, got {value}")]
    Negative { what: &'static str, value: f64 },
    /// A frame's origin, axis or reference direction is not finite.
    #[error("{what} is not finite")]
    FrameNotFinite { what: &'static str },
    /// A direction vector has zero length.
    #[error("{what} has zero length")]
    ZeroLength { what: &'static str },
    /// A frame's reference direction is parallel to its axis.
    #[error("frame reference direction is parallel to its axis")]
    ReferenceAlongAxis,
    /// A vector that must be finite and non-zero is not.
    #[error("{what} must be finite and nonzero")]
    ZeroVector { what: &'static str },
    /// A circle arc's axes do not span a plane.
    #[error("circle arc axes must be finite, non-zero and not parallel")]
    ArcAxes,
    /// A circle arc's angles do not make a turn of at most 2π.
    #[error("circle arc angles {a0}..{a1} must satisfy 0 < a1 − a0 ≤ 2π")]
    ArcAngles { a0: f64, a1: f64 },
    /// A circle arc's radius is not finite and positive.
    #[error("circle arc radius {radius} must be finite and > 0")]
    ArcRadius { radius: f64 },
    /// A cone's semi-angle is outside (0, π/2).
    #[error("cone semi-angle must lie in (0, π/2) radians, got {semi_angle}")]
    ConeAngle { semi_angle: f64 },
    /// A torus whose tube is as wide as its centre circle.
    #[error("torus minor radius {minor} must be below the major radius {major}")]
    TorusRadii { major: f64, minor: f64 },
    /// A curve's parameter interval is empty or not finite.
    #[error("curve interval [{t0}, {t1}] is empty or not finite")]
    EmptyInterval { t0: f64, t1: f64 },
    /// A named boundary curve's domain is empty or not finite.
    #[error("{name}: curve domain ({t0}, {t1}) is empty or not finite")]
    EmptyCurveDomain { name: String, t0: f64, t1: f64 },
    /// A surface's parameter rectangle is empty or not finite.
    #[error("parameter domain {domain:?} is empty or not finite")]
    EmptyDomain { domain: crate::Domain2 },
    /// A knot repeated more often than the degree plus one allows.
    #[error("knot {index} ({knot}) has multiplicity {multiplicity}, more than degree + 1 = {max}")]
    KnotMultiplicity {
        index: usize,
        knot: f64,
        multiplicity: usize,
        max: usize,
    },
    /// A knot vector whose first and last effective knots coincide.
    #[error(
        "empty parameter domain: knot {first} ({first_knot}) is not below knot {last} ({last_knot})"
    )]
    EmptyKnotDomain {
        first: usize,
        first_knot: f64,
        last: usize,
        last_knot: f64,
    },
    /// A patch's interior knot repeated more often than its degree (the patch would break).
    #[error("{dir} knot {index} = {knot} has multiplicity {multiplicity} > degree {degree}")]
    InteriorKnotMultiplicity {
        dir: &'static str,
        index: usize,
        knot: f64,
        multiplicity: usize,
        degree: usize,
    },
    /// A knot to insert outside the curve's open domain.
    #[error("knot {knot} to insert lies outside the open domain ({lo}, {hi})")]
    InsertOutside { knot: f64, lo: f64, hi: f64 },
    /// Inserting a knot that many times would break the curve.
    #[error(
        "inserting knot {knot} {times} times would raise its multiplicity {multiplicity} above the degree {degree}"
    )]
    InsertTooOften {
        knot: f64,
        times: usize,
        multiplicity: usize,
        degree: usize,
    },
    /// A list of weights of another length than its points.
    #[error("{what} needs one weight per control point: {points} points, {weights} weights")]
    WeightCount {
        what: &'static str,
        points: usize,
        weights: usize,
    },
    /// A B-spline patch's weights of another count than its poles.
    #[error("{weights} weights given for {poles} poles")]
    PoleWeightCount { weights: usize, poles: usize },
    /// A revolved profile's weights of another count than its points.
    #[error("profile has {points} points but {weights} weights")]
    ProfileWeightCount { points: usize, weights: usize },
    /// A Hermite spline's tangents of another count than its points.
    #[error("Hermite spline needs one tangent per point: {points} points, {tangents} tangents")]
    TangentCount { points: usize, tangents: usize },
    /// Interpolation parameters of another count than the points.
    #[error(
        "Bézier interpolation needs one parameter per point: {points} points, {params} parameters"
    )]
    BezierParamCount { points: usize, params: usize },
    /// A spline's explicit parameters of another count than its points need.
    #[error("spline needs {want} parameters for {points} points ({ends}), got {got}")]
    SplineParamCount {
        want: usize,
        points: usize,
        ends: &'static str,
        got: usize,
    },
    /// A blossom evaluated with another number of arguments than the degree.
    #[error("blossom of a degree-{degree} Bézier curve takes {degree} arguments, got {got}")]
    BlossomArity { degree: usize, got: usize },
    /// Bézier pieces with another number of breakpoints than pieces plus one.
    #[error("{pieces} Bézier pieces need {want} breakpoints, got {got}")]
    BreakpointCount {
        pieces: usize,
        want: usize,
        got: usize,
    },
    /// Bézier pieces of different degrees joined into one spline.
    #[error("Bézier piece {piece} has degree {degree}, piece 0 has degree {first}")]
    PieceDegree {
        piece: usize,
        degree: usize,
        first: usize,
    },
    /// A Bézier piece that does not start where the previous one ends.
    #[error("Bézier piece {piece} starts {gap} mm away from the end of piece {previous}")]
    PieceGap {
        piece: usize,
        gap: f64,
        previous: usize,
    },
    /// Explicit spline parameters that do not increase.
    #[error(
        "spline parameters must increase strictly: parameter {index} ({value}) ≤ parameter {previous} ({previous_value})"
    )]
    SplineParamOrder {
        index: usize,
        value: f64,
        previous: usize,
        previous_value: f64,
    },
    /// Two consecutive spline points at one place.
    #[error("spline points {first} and {second} coincide: no chord-length parameter interval")]
    SplinePointsCoincide { first: usize, second: usize },
    /// Two consecutive spline points so close their parameter interval vanishes.
    #[error(
        "spline points {first} and {second} (almost) coincide: parameter interval {interval} of total {total}"
    )]
    SplinePointsNear {
        first: usize,
        second: usize,
        interval: f64,
        total: f64,
    },
    /// Two consecutive points to fit at one place.
    #[error("fit points {first} and {second} coincide")]
    FitPointsCoincide { first: usize, second: usize },
    /// No B-spline within the tolerance was found.
    #[error("no B-spline fit found")]
    NoFit,
    /// The least-squares fit's system is singular.
    #[error(
        "least-squares system for {control_points} control points is singular (too few points per span)"
    )]
    FitSingular { control_points: usize },
    /// Bézier interpolation at repeated parameters.
    #[error("Bézier interpolation parameters are not distinct (singular system)")]
    BezierInterpolationSingular,
    /// The triangular patch's interpolation system is singular.
    #[error("triangular interpolation system is singular")]
    TriangularInterpolationSingular,
    /// A Hermite end tangent that is zero or not finite.
    #[error("end tangent {which} must be finite and non-zero, got {tangent}")]
    EndTangent {
        which: &'static str,
        tangent: flatcut_geom::DVec3,
    },
    /// A Hermite segment whose two ends coincide.
    #[error("end points r0 = {r0} and r1 = {r1} coincide: no cubic segment between them")]
    EndsCoincide {
        r0: flatcut_geom::DVec3,
        r1: flatcut_geom::DVec3,
    },
    /// The minimum-energy cubic would run backwards along a tangent.
    #[error(
        "minimum-energy cubic has {which} speed {speed} ≤ 0: the tangent would be reversed (tangents point away from the chord)"
    )]
    ReversedSpeed { which: &'static str, speed: f64 },
    /// A tangent pointing back along the chord: no circular-arc cubic.
    #[error(
        "tangent {which} points back along the chord (1 + cos α = {one_plus_cos:.3}): no circular-arc cubic"
    )]
    TangentBackwards {
        which: &'static str,
        one_plus_cos: f64,
    },
    /// A segment of a Hermite spline could not be built.
    #[error("segment {index} (points {index}–{next}): {source}")]
    Segment {
        index: usize,
        next: usize,
        source: Box<SurfaceError>,
    },
    /// Coons boundary curves that do not meet at a corner.
    #[error(
        "Coons corner ({i},{j}): the boundary curves miss each other by {gap:.3e} mm (tolerance {tol:.1e} mm)"
    )]
    CoonsCorner {
        i: usize,
        j: usize,
        gap: f64,
        tol: f64,
    },
    /// Gordon parameters too few.
    #[error("Gordon: need at least two {what}")]
    GordonTooFew { what: &'static str },
    /// Gordon parameters that do not increase.
    #[error("Gordon: {what} must increase strictly (index {index})")]
    GordonOrder { what: &'static str, index: usize },
    /// Gordon parameters outside [0, 1].
    #[error("Gordon: {what} must lie in [0, 1]")]
    GordonRange { what: &'static str },
    /// Gordon curves of other counts than their parameters.
    #[error(
        "Gordon: {u_curves} u-curves for {u_params} u parameters, {v_curves} v-curves for {v_params} v parameters"
    )]
    GordonCount {
        u_curves: usize,
        u_params: usize,
        v_curves: usize,
        v_params: usize,
    },
    /// Gordon curves that do not meet at a grid point.
    #[error("Gordon: u-curve {u} and v-curve {v} miss each other by {gap:.3e} mm")]
    GordonMiss { u: usize, v: usize, gap: f64 },
    /// A developable between rails asked over an empty domain or in no steps.
    #[error("developable: empty rail domain or zero steps")]
    DevelopableEmpty,
    /// No ruling from the first rail meets the second with a common tangent plane.
    #[error(
        "developable: no ruling from rail 0 near r={r} meets rail 1 at t={t} with a common tangent plane"
    )]
    DevelopableNoRuling { r: f64, t: f64 },
    /// The rails admit no developable at a parameter.
    #[error(
        "developable: the rails admit no developable at rail-1 parameter t={t:.6}: [λ−μ, λ'', μ'] vanishes (ruling tangent to a rail or through a cone vertex)"
    )]
    DevelopableDegenerate { t: f64 },
    /// The first rail ends before any ruling.
    #[error("developable: rail 0 ends immediately (no ruling beyond t={t})")]
    DevelopableRailEnds { t: f64 },
    /// The normals along a ruling differ: the strip is not developable.
    #[error("developable: normals along the ruling at t={t:.6} differ by sin θ = {sin:.2e}")]
    DevelopableNormals { t: f64, sin: f64 },
    /// A ruling of zero length cannot be unfolded.
    #[error("developable: ruling {index} has zero length; cannot unfold")]
    ZeroRuling { index: usize },
    /// A patch's side evaluates to a non-finite point.
    #[error("model: patch {patch} side {side} evaluates to a non-finite point at sample {sample}")]
    NonFiniteSide {
        patch: usize,
        side: String,
        sample: usize,
    },
}
