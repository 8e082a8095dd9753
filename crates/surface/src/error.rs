//! Construction errors of curves and surfaces.

/// Why a curve or a surface could not be built. Messages name the offending element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// The number of control points does not match the degree / knot vector.
    #[error("wrong number of control points: expected {expected}, got {got}")]
    ControlPointCount {
        /// Control points the degree and knot vector call for.
        expected: usize,
        /// Control points given.
        got: usize,
    },
    /// Knots must be non-decreasing; `index` is the first knot that decreases.
    #[error("knot vector is decreasing at index {index} ({prev} > {next})")]
    DecreasingKnots {
        /// 0-based index of the first knot below its predecessor.
        index: usize,
        /// The knot before it.
        prev: f64,
        /// The decreasing knot's value.
        next: f64,
    },
    /// A knot vector of the wrong length for its degree and control-point count.
    #[error("knot vector has {got} knots, expected {expected}")]
    KnotCount {
        /// Knots the degree and control-point count call for (`n + p + 1`).
        expected: usize,
        /// Knots given.
        got: usize,
    },
    /// NURBS weights must be finite and strictly positive.
    #[error("weight {index} is {value}: weights must be finite and > 0")]
    BadWeight {
        /// 0-based index of the weight.
        index: usize,
        /// The offending weight.
        value: f64,
    },
    /// A coordinate is NaN or infinite.
    #[error("{what} {index} has a non-finite coordinate")]
    NonFinite {
        /// What holds the coordinate, e.g. "control point".
        what: &'static str,
        /// 0-based index of that element.
        index: usize,
    },
    /// A degree of zero or one that is too high for the data.
    #[error("invalid degree {degree}: {reason}")]
    BadDegree {
        /// The degree given.
        degree: usize,
        /// Why it cannot be used.
        reason: &'static str,
    },
    /// A size, radius or tolerance that must be finite and positive is not.
    #[error("{what} must be finite and > 0, got {value}")]
    NotPositive {
        /// The quantity's name, e.g. "cylinder radius".
        what: String,
        /// The value given (mm for lengths).
        value: f64,
    },
    /// A tolerance (named before its value) that must be finite and positive is not.
    #[error("{what} {value} must be finite and > 0")]
    BadTolerance {
        /// The tolerance's name.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A radius that must be finite and non-negative is not.
    #[error("{what} must be finite and >= 0, got {value}")]
    Negative {
        /// The radius's name.
        what: &'static str,
        /// The value given, in mm.
        value: f64,
    },
    /// A frame's origin, axis or reference direction is not finite.
    #[error("{what} is not finite")]
    FrameNotFinite {
        /// Which of the frame's vectors is not finite.
        what: &'static str,
    },
    /// A direction vector has zero length.
    #[error("{what} has zero length")]
    ZeroLength {
        /// Which direction has zero length.
        what: &'static str,
    },
    /// A frame's reference direction is parallel to its axis.
    #[error("frame reference direction is parallel to its axis")]
    ReferenceAlongAxis,
    /// A vector that must be finite and non-zero is not.
    #[error("{what} must be finite and nonzero")]
    ZeroVector {
        /// Which vector is zero or not finite.
        what: &'static str,
    },
    /// A circle arc's axes do not span a plane.
    #[error("circle arc axes must be finite, non-zero and not parallel")]
    ArcAxes,
    /// A circle arc's angles do not make a turn of at most 2π.
    #[error("circle arc angles {a0}..{a1} must satisfy 0 < a1 − a0 ≤ 2π")]
    ArcAngles {
        /// Start angle in radians.
        a0: f64,
        /// End angle in radians.
        a1: f64,
    },
    /// A circle arc's radius is not finite and positive.
    #[error("circle arc radius {radius} must be finite and > 0")]
    ArcRadius {
        /// The radius given, in mm.
        radius: f64,
    },
    /// A cone's semi-angle is outside (0, π/2).
    #[error("cone semi-angle must lie in (0, π/2) radians, got {semi_angle}")]
    ConeAngle {
        /// The semi-angle given, in radians.
        semi_angle: f64,
    },
    /// A torus whose tube is as wide as its centre circle.
    #[error("torus minor radius {minor} must be below the major radius {major}")]
    TorusRadii {
        /// Radius of the centre circle, in mm.
        major: f64,
        /// Radius of the tube, in mm.
        minor: f64,
    },
    /// A curve's parameter interval is empty or not finite.
    #[error("curve interval [{t0}, {t1}] is empty or not finite")]
    EmptyInterval {
        /// Start of the interval.
        t0: f64,
        /// End of the interval.
        t1: f64,
    },
    /// A named boundary curve's domain is empty or not finite.
    #[error("{name}: curve domain ({t0}, {t1}) is empty or not finite")]
    EmptyCurveDomain {
        /// The curve's name, e.g. "coons u0".
        name: String,
        /// Start of the curve's domain.
        t0: f64,
        /// End of the curve's domain.
        t1: f64,
    },
    /// A surface's parameter rectangle is empty or not finite.
    #[error("parameter domain {domain:?} is empty or not finite")]
    EmptyDomain {
        /// The rectangle given.
        domain: crate::Domain2,
    },
    /// A knot repeated more often than the degree plus one allows.
    #[error("knot {index} ({knot}) has multiplicity {multiplicity}, more than degree + 1 = {max}")]
    KnotMultiplicity {
        /// 0-based index of the first occurrence of the knot.
        index: usize,
        /// The knot's value.
        knot: f64,
        /// How often it occurs.
        multiplicity: usize,
        /// The most it may occur: degree + 1.
        max: usize,
    },
    /// A knot vector whose first and last effective knots coincide.
    #[error(
        "empty parameter domain: knot {first} ({first_knot}) is not below knot {last} ({last_knot})"
    )]
    EmptyKnotDomain {
        /// 0-based index of the first effective knot (the degree's).
        first: usize,
        /// Its value.
        first_knot: f64,
        /// 0-based index of the last effective knot.
        last: usize,
        /// Its value.
        last_knot: f64,
    },
    /// A patch's interior knot repeated more often than its degree (the patch would break).
    #[error("{dir} knot {index} = {knot} has multiplicity {multiplicity} > degree {degree}")]
    InteriorKnotMultiplicity {
        /// The parameter direction, "u" or "v".
        dir: &'static str,
        /// 0-based index of the knot in that direction's vector.
        index: usize,
        /// The knot's value.
        knot: f64,
        /// How often it occurs.
        multiplicity: usize,
        /// The patch's degree in that direction.
        degree: usize,
    },
    /// A knot to insert outside the curve's open domain.
    #[error("knot {knot} to insert lies outside the open domain ({lo}, {hi})")]
    InsertOutside {
        /// The knot to insert.
        knot: f64,
        /// Start of the curve's domain.
        lo: f64,
        /// End of the curve's domain.
        hi: f64,
    },
    /// Inserting a knot that many times would break the curve.
    #[error(
        "inserting knot {knot} {times} times would raise its multiplicity {multiplicity} above the degree {degree}"
    )]
    InsertTooOften {
        /// The knot to insert.
        knot: f64,
        /// How many times it was to be inserted.
        times: usize,
        /// Its multiplicity before insertion.
        multiplicity: usize,
        /// The curve's degree.
        degree: usize,
    },
    /// A list of weights of another length than its points.
    #[error("{what} needs one weight per control point: {points} points, {weights} weights")]
    WeightCount {
        /// The curve or surface kind.
        what: &'static str,
        /// Control points given.
        points: usize,
        /// Weights given.
        weights: usize,
    },
    /// A B-spline patch's weights of another count than its poles.
    #[error("{weights} weights given for {poles} poles")]
    PoleWeightCount {
        /// Weights given.
        weights: usize,
        /// Poles given.
        poles: usize,
    },
    /// A revolved profile's weights of another count than its points.
    #[error("profile has {points} points but {weights} weights")]
    ProfileWeightCount {
        /// Profile points given.
        points: usize,
        /// Weights given.
        weights: usize,
    },
    /// A Hermite spline's tangents of another count than its points.
    #[error("Hermite spline needs one tangent per point: {points} points, {tangents} tangents")]
    TangentCount {
        /// Points given.
        points: usize,
        /// Tangents given.
        tangents: usize,
    },
    /// Interpolation parameters of another count than the points.
    #[error(
        "Bézier interpolation needs one parameter per point: {points} points, {params} parameters"
    )]
    BezierParamCount {
        /// Points given.
        points: usize,
        /// Parameters given.
        params: usize,
    },
    /// A spline's explicit parameters of another count than its points need.
    #[error("spline needs {want} parameters for {points} points ({ends}), got {got}")]
    SplineParamCount {
        /// Parameters the points and end conditions call for.
        want: usize,
        /// Points given.
        points: usize,
        /// The end conditions, "open" or "closed" (which needs one parameter more).
        ends: &'static str,
        /// Parameters given.
        got: usize,
    },
    /// A blossom evaluated with another number of arguments than the degree.
    #[error("blossom of a degree-{degree} Bézier curve takes {degree} arguments, got {got}")]
    BlossomArity {
        /// The curve's degree.
        degree: usize,
        /// Arguments given.
        got: usize,
    },
    /// Bézier pieces with another number of breakpoints than pieces plus one.
    #[error("{pieces} Bézier pieces need {want} breakpoints, got {got}")]
    BreakpointCount {
        /// Bézier pieces given.
        pieces: usize,
        /// Breakpoints they call for: pieces + 1.
        want: usize,
        /// Breakpoints given.
        got: usize,
    },
    /// Bézier pieces of different degrees joined into one spline.
    #[error("Bézier piece {piece} has degree {degree}, piece 0 has degree {first}")]
    PieceDegree {
        /// 0-based index of the piece.
        piece: usize,
        /// Its degree.
        degree: usize,
        /// The degree of piece 0.
        first: usize,
    },
    /// A Bézier piece that does not start where the previous one ends.
    #[error("Bézier piece {piece} starts {gap} mm away from the end of piece {previous}")]
    PieceGap {
        /// 0-based index of the piece that starts away.
        piece: usize,
        /// Distance from the previous piece's end, in mm.
        gap: f64,
        /// 0-based index of the previous piece.
        previous: usize,
    },
    /// Explicit spline parameters that do not increase.
    #[error(
        "spline parameters must increase strictly: parameter {index} ({value}) ≤ parameter {previous} ({previous_value})"
    )]
    SplineParamOrder {
        /// 0-based index of the parameter that does not increase.
        index: usize,
        /// Its value.
        value: f64,
        /// 0-based index of the parameter before it.
        previous: usize,
        /// That parameter's value.
        previous_value: f64,
    },
    /// Two consecutive spline points at one place.
    #[error("spline points {first} and {second} coincide: no chord-length parameter interval")]
    SplinePointsCoincide {
        /// 0-based index of the first point.
        first: usize,
        /// 0-based index of the point after it.
        second: usize,
    },
    /// Two consecutive spline points so close their parameter interval vanishes.
    #[error(
        "spline points {first} and {second} (almost) coincide: parameter interval {interval} of total {total}"
    )]
    SplinePointsNear {
        /// 0-based index of the first point.
        first: usize,
        /// 0-based index of the point after it.
        second: usize,
        /// Their chord-length parameter interval.
        interval: f64,
        /// The total chord length the intervals share.
        total: f64,
    },
    /// Two consecutive points to fit at one place.
    #[error("fit points {first} and {second} coincide")]
    FitPointsCoincide {
        /// 0-based index of the first point.
        first: usize,
        /// 0-based index of the point after it.
        second: usize,
    },
    /// No B-spline within the tolerance was found.
    #[error("no B-spline fit found")]
    NoFit,
    /// The least-squares fit's system is singular.
    #[error(
        "least-squares system for {control_points} control points is singular (too few points per span)"
    )]
    FitSingular {
        /// Control points the fit was solving for.
        control_points: usize,
    },
    /// Bézier interpolation at repeated parameters.
    #[error("Bézier interpolation parameters are not distinct (singular system)")]
    BezierInterpolationSingular,
    /// The triangular patch's interpolation system is singular.
    #[error("triangular interpolation system is singular")]
    TriangularInterpolationSingular,
    /// A Hermite end tangent that is zero or not finite.
    #[error("end tangent {which} must be finite and non-zero, got {tangent}")]
    EndTangent {
        /// Which end's tangent, "t0" or "t1".
        which: &'static str,
        /// The tangent given.
        tangent: flatcut_geom::DVec3,
    },
    /// A Hermite segment whose two ends coincide.
    #[error("end points r0 = {r0} and r1 = {r1} coincide: no cubic segment between them")]
    EndsCoincide {
        /// The start point.
        r0: flatcut_geom::DVec3,
        /// The end point.
        r1: flatcut_geom::DVec3,
    },
    /// The minimum-energy cubic would run backwards along a tangent.
    #[error(
        "minimum-energy cubic has {which} speed {speed} ≤ 0: the tangent would be reversed (tangents point away from the chord)"
    )]
    ReversedSpeed {
        /// Which end's speed.
        which: &'static str,
        /// The speed (≤ 0) the cubic would have there.
        speed: f64,
    },
    /// A tangent pointing back along the chord: no circular-arc cubic.
    #[error(
        "tangent {which} points back along the chord (1 + cos α = {one_plus_cos:.3}): no circular-arc cubic"
    )]
    TangentBackwards {
        /// Which end's tangent.
        which: &'static str,
        /// `1 + cos α`, α the angle between the tangent and the chord; near 0 when it points back.
        one_plus_cos: f64,
    },
    /// A segment of a Hermite spline could not be built.
    #[error("segment {index} (points {index}–{next}): {source}")]
    Segment {
        /// 0-based index of the segment (and of its first point).
        index: usize,
        /// 0-based index of its last point.
        next: usize,
        /// Why the segment could not be built.
        source: Box<SurfaceError>,
    },
    /// Coons boundary curves that do not meet at a corner.
    #[error(
        "Coons corner ({i},{j}): the boundary curves miss each other by {gap:.3e} mm (tolerance {tol:.1e} mm)"
    )]
    CoonsCorner {
        /// The corner's u index, 0 or 1.
        i: usize,
        /// The corner's v index, 0 or 1.
        j: usize,
        /// Distance between the two curves' ends there, in mm.
        gap: f64,
        /// The largest distance accepted, in mm.
        tol: f64,
    },
    /// Gordon parameters too few.
    #[error("Gordon: need at least two {what}")]
    GordonTooFew {
        /// Which list is too short.
        what: &'static str,
    },
    /// Gordon parameters that do not increase.
    #[error("Gordon: {what} must increase strictly (index {index})")]
    GordonOrder {
        /// Which parameter list.
        what: &'static str,
        /// 0-based index of the first parameter that does not increase.
        index: usize,
    },
    /// Gordon parameters outside [0, 1].
    #[error("Gordon: {what} must lie in [0, 1]")]
    GordonRange {
        /// Which parameter list.
        what: &'static str,
    },
    /// Gordon curves of other counts than their parameters.
    #[error(
        "Gordon: {u_curves} u-curves for {u_params} u parameters, {v_curves} v-curves for {v_params} v parameters"
    )]
    GordonCount {
        /// u-curves given.
        u_curves: usize,
        /// u parameters given.
        u_params: usize,
        /// v-curves given.
        v_curves: usize,
        /// v parameters given.
        v_params: usize,
    },
    /// Gordon curves that do not meet at a grid point.
    #[error("Gordon: u-curve {u} and v-curve {v} miss each other by {gap:.3e} mm")]
    GordonMiss {
        /// 0-based index of the u-curve.
        u: usize,
        /// 0-based index of the v-curve.
        v: usize,
        /// Their distance at the grid point, in mm.
        gap: f64,
    },
    /// A developable between rails asked over an empty domain or in no steps.
    #[error("developable: empty rail domain or zero steps")]
    DevelopableEmpty,
    /// No ruling from the first rail meets the second with a common tangent plane.
    #[error(
        "developable: no ruling from rail 0 near r={r} meets rail 1 at t={t} with a common tangent plane"
    )]
    DevelopableNoRuling {
        /// Parameter on rail 0 where the search started.
        r: f64,
        /// Parameter on rail 1.
        t: f64,
    },
    /// The rails admit no developable at a parameter.
    #[error(
        "developable: the rails admit no developable at rail-1 parameter t={t:.6}: [λ−μ, λ'', μ'] vanishes (ruling tangent to a rail or through a cone vertex)"
    )]
    DevelopableDegenerate {
        /// Parameter on rail 1 where the rails admit no developable.
        t: f64,
    },
    /// The first rail ends before any ruling.
    #[error("developable: rail 0 ends immediately (no ruling beyond t={t})")]
    DevelopableRailEnds {
        /// Parameter on rail 0 where it ends.
        t: f64,
    },
    /// The normals along a ruling differ: the strip is not developable.
    #[error("developable: normals along the ruling at t={t:.6} differ by sin θ = {sin:.2e}")]
    DevelopableNormals {
        /// Parameter on rail 1 of the ruling.
        t: f64,
        /// Sine of the largest angle between the normals along the ruling.
        sin: f64,
    },
    /// A ruling of zero length cannot be unfolded.
    #[error("developable: ruling {index} has zero length; cannot unfold")]
    ZeroRuling {
        /// 0-based index of the ruling.
        index: usize,
    },
    /// A patch's side evaluates to a non-finite point.
    #[error("model: patch {patch} side {side} evaluates to a non-finite point at sample {sample}")]
    NonFiniteSide {
        /// 0-based index of the patch.
        patch: usize,
        /// Which side of the patch, e.g. "u0".
        side: String,
        /// 0-based index of the sample along the side.
        sample: usize,
    },
}
