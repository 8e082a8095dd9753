//! Curves: Bézier, B-spline/NURBS, Hermite, interpolating splines, arc length, Frenet frames.
