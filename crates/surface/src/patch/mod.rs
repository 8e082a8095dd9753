//! Patches: tensor-product Bézier, Hermite, B-spline/NURBS, Coons, Gordon, ruled, developable, triangular.
