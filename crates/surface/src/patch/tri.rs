//! Triangular Bézier patches (Gravesen §3.4 (3.21)–(3.25), Salomon §6.23–6.24, Hartmann §13.5).
//!
//! `r(u, v) = Σ_{i+j+k=n} b_ijk n!/(i! j! k!) u^i v^j w^k` with `w = 1 − u − v`. Points come from
//! the triangular de Casteljau scheme `b^r_ijk = u b^{r−1}_{i+1,j,k} + v b^{r−1}_{i,j+1,k} +
//! w b^{r−1}_{i,j,k+1}`; stopping it two levels early gives first and second derivatives by
//! differences (G (3.24)): `∂_u = n (E1 − E3)`, `∂_v = n (E2 − E3)` applied to the level-(n−1)
//! net, and their products on the level-(n−2) net. Sub-patches over any triangle come from the
//! blossom (G (3.23)).

use crate::{Domain2, DomainKind, ParamSurface, SurfaceDerivs, SurfaceError};
use glam::{DVec2, DVec3};

/// A triangular Bézier patch of degree `n` over `u, v ≥ 0, u + v ≤ 1`.
///
/// Control points `b_ijk` (`i` = power of u, `j` = power of v, `k = n − i − j` = power of w)
/// are stored row by row in increasing `j`, and within a row in increasing `i`:
/// index `j (n + 1) − j (j − 1)/2 + i`. So the first point is `b_00n` (the vertex `u = v = 0`),
/// the `n + 1`-th is `b_n00` (vertex u = 1), the last `b_0n0` (vertex v = 1).
#[derive(Clone, Debug, PartialEq)]
pub struct TriBezierPatch {
    degree: usize,
    points: Vec<DVec3>,
}

/// Number of control points of a degree-`n` triangular net.
pub const fn tri_count(n: usize) -> usize {
    (n + 1) * (n + 2) / 2
}

#[inline]
fn idx(n: usize, i: usize, j: usize) -> usize {
    j * (n + 1) - j * j.saturating_sub(1) / 2 + i
}

/// One de Casteljau level: net of degree `n` → degree `n − 1` with barycentric weights `(a, b, c)`.
fn step(net: &[DVec3], n: usize, a: f64, b: f64, c: f64) -> Vec<DVec3> {
    let m = n - 1;
    let mut out = vec![DVec3::ZERO; tri_count(m)];
    for j in 0..=m {
        for i in 0..=m - j {
            out[idx(m, i, j)] =
                net[idx(n, i + 1, j)] * a + net[idx(n, i, j + 1)] * b + net[idx(n, i, j)] * c;
        }
    }
    out
}

impl TriBezierPatch {
    /// Builds a patch of degree `degree ≥ 1` from `(n+1)(n+2)/2` control points (see the type docs
    /// for the order).
    pub fn new(degree: usize, points: Vec<DVec3>) -> Result<Self, SurfaceError> {
        if degree == 0 {
            return Err(SurfaceError::BadDegree {
                degree,
                reason: "a triangular patch needs degree at least 1",
            });
        }
        if points.len() != tri_count(degree) {
            return Err(SurfaceError::ControlPointCount {
                expected: tri_count(degree),
                got: points.len(),
            });
        }
        super::check_finite(&points, "triangular Bézier control point")?;
        Ok(Self { degree, points })
    }

    /// The degree-`n` patch interpolating `f` at the `(n+1)(n+2)/2` points `(i/n, j/n)` of the
    /// domain (a dense linear solve; for approximating analytic surfaces).
    pub fn interpolate(degree: usize, f: impl Fn(f64, f64) -> DVec3) -> Result<Self, SurfaceError> {
        if degree == 0 {
            return Err(SurfaceError::BadDegree {
                degree,
                reason: "interpolation needs degree ≥ 1",
            });
        }
        let n = degree;
        let m = tri_count(n);
        let mut a = nalgebra::DMatrix::<f64>::zeros(m, m);
        let mut rhs = nalgebra::DMatrix::<f64>::zeros(m, 3);
        let unit = |k: usize| {
            let mut e = vec![DVec3::ZERO; m];
            e[k] = DVec3::X;
            e
        };
        let basis: Vec<TriBezierPatch> = (0..m)
            .map(|k| Self {
                degree: n,
                points: unit(k),
            })
            .collect();
        for j in 0..=n {
            for i in 0..=n - j {
                let row = idx(n, i, j);
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                for (k, b) in basis.iter().enumerate() {
                    a[(row, k)] = b.eval(u, v).x;
                }
                let p = f(u, v);
                rhs[(row, 0)] = p.x;
                rhs[(row, 1)] = p.y;
                rhs[(row, 2)] = p.z;
            }
        }
        let sol = a
            .lu()
            .solve(&rhs)
            .ok_or(SurfaceError::TriangularInterpolationSingular)?;
        let pts = (0..m)
            .map(|k| DVec3::new(sol[(k, 0)], sol[(k, 1)], sol[(k, 2)]))
            .collect();
        Self::new(n, pts)
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.degree
    }
    /// The control points in storage order.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }
    /// Control point `b_ijk` with `k = n − i − j`.
    pub fn point(&self, i: usize, j: usize) -> DVec3 {
        self.points[idx(self.degree, i, j)]
    }

    /// Runs de Casteljau down to degree `level` at `(u, v)`.
    fn reduce(&self, u: f64, v: f64, level: usize) -> Vec<DVec3> {
        let w = 1.0 - u - v;
        let mut net = self.points.clone();
        for n in (level + 1..=self.degree).rev() {
            net = step(&net, n, u, v, w);
        }
        net
    }

    /// The blossom `b(x_1, …, x_n)` with the n arguments given as barycentric triples.
    fn blossom(&self, args: &[[f64; 3]]) -> DVec3 {
        let mut net = self.points.clone();
        for (s, a) in args.iter().enumerate() {
            net = step(&net, self.degree - s, a[0], a[1], a[2]);
        }
        net[0]
    }

    /// The patch restricted to the triangle with vertices `a, b, c` (domain points `(u, v)`), as a
    /// patch of the same degree: its vertex `u = 1` is `a`, `v = 1` is `b`, `u = v = 0` is `c`.
    /// Vertices outside the domain extrapolate (G (3.23)).
    pub fn reparam(&self, a: DVec2, b: DVec2, c: DVec2) -> Self {
        let bary = |p: DVec2| [p.x, p.y, 1.0 - p.x - p.y];
        let (ba, bb, bc) = (bary(a), bary(b), bary(c));
        let n = self.degree;
        let mut pts = vec![DVec3::ZERO; tri_count(n)];
        for j in 0..=n {
            for i in 0..=n - j {
                let k = n - i - j;
                let args: Vec<[f64; 3]> = std::iter::repeat_n(ba, i)
                    .chain(std::iter::repeat_n(bb, j))
                    .chain(std::iter::repeat_n(bc, k))
                    .collect();
                pts[idx(n, i, j)] = self.blossom(&args);
            }
        }
        Self {
            degree: n,
            points: pts,
        }
    }

    /// Splits at the interior point `(u, v)` into the three sub-patches with vertices
    /// `(p, e_v, e_w)`, `(e_u, p, e_w)`, `(e_u, e_v, p)` (`e_u = (1,0)`, `e_v = (0,1)`, `e_w = (0,0)`).
    pub fn subdivide_at(&self, u: f64, v: f64) -> [Self; 3] {
        let p = DVec2::new(u, v);
        let (eu, ev, ew) = (DVec2::X, DVec2::Y, DVec2::ZERO);
        [
            self.reparam(p, ev, ew),
            self.reparam(eu, p, ew),
            self.reparam(eu, ev, p),
        ]
    }

    /// The regular 4-way split at the edge midpoints: corner triangles at `e_u`, `e_v`, `e_w`,
    /// then the (flipped) middle triangle.
    pub fn subdivide4(&self) -> [Self; 4] {
        let (eu, ev, ew) = (DVec2::X, DVec2::Y, DVec2::ZERO);
        let (muv, mvw, mwu) = ((eu + ev) * 0.5, (ev + ew) * 0.5, (ew + eu) * 0.5);
        [
            self.reparam(eu, muv, mwu),
            self.reparam(muv, ev, mvw),
            self.reparam(mwu, mvw, ew),
            self.reparam(mvw, mwu, muv),
        ]
    }

    /// The same surface at degree `n + 1`:
    /// `b*_ijk = (i b_{i−1,j,k} + j b_{i,j−1,k} + k b_{i,j,k−1}) / (n + 1)`.
    pub fn elevate(&self) -> Self {
        let n = self.degree;
        let m = n + 1;
        let mut pts = vec![DVec3::ZERO; tri_count(m)];
        for j in 0..=m {
            for i in 0..=m - j {
                let k = m - i - j;
                let mut p = DVec3::ZERO;
                if i > 0 {
                    p += self.point(i - 1, j) * i as f64;
                }
                if j > 0 {
                    p += self.point(i, j - 1) * j as f64;
                }
                if k > 0 {
                    p += self.point(i, j) * k as f64;
                }
                pts[idx(m, i, j)] = p / m as f64;
            }
        }
        Self {
            degree: m,
            points: pts,
        }
    }
}

impl ParamSurface for TriBezierPatch {
    fn domain(&self) -> Domain2 {
        Domain2::UNIT
    }
    fn domain_kind(&self) -> DomainKind {
        DomainKind::Triangle
    }
    fn eval(&self, u: f64, v: f64) -> DVec3 {
        self.reduce(u, v, 0)[0]
    }
    fn deriv1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let n = self.degree;
        let q = self.reduce(u, v, 1);
        // Level-1 net: q[idx(1,1,0)] = b_100, q[idx(1,0,1)] = b_010, q[idx(1,0,0)] = b_001.
        let (a, b, c) = (q[idx(1, 1, 0)], q[idx(1, 0, 1)], q[idx(1, 0, 0)]);
        let w = 1.0 - u - v;
        let nf = n as f64;
        (a * u + b * v + c * w, (a - c) * nf, (b - c) * nf)
    }
    fn deriv2(&self, u: f64, v: f64) -> SurfaceDerivs {
        let n = self.degree;
        if n < 2 {
            let (p, su, sv) = self.deriv1(u, v);
            return SurfaceDerivs {
                p,
                su,
                sv,
                ..Default::default()
            };
        }
        let w = 1.0 - u - v;
        let q = self.reduce(u, v, 2);
        let g = |i: usize, j: usize| q[idx(2, i, j)];
        let (q200, q020, q002, q110, q101, q011) =
            (g(2, 0), g(0, 2), g(0, 0), g(1, 1), g(1, 0), g(0, 1));
        let l1 = step(&q, 2, u, v, w);
        let (a, b, c) = (l1[idx(1, 1, 0)], l1[idx(1, 0, 1)], l1[idx(1, 0, 0)]);
        let nf = n as f64;
        let k = (n * (n - 1)) as f64;
        SurfaceDerivs {
            p: a * u + b * v + c * w,
            su: (a - c) * nf,
            sv: (b - c) * nf,
            suu: (q200 - q101 * 2.0 + q002) * k,
            suv: (q110 - q101 - q011 + q002) * k,
            svv: (q020 - q011 * 2.0 + q002) * k,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::testutil::check_derivs_fd;
    use proptest::prelude::*;

    fn tv25() -> TriBezierPatch {
        // P_ijk = (2i + j, j, i).
        let n = 3;
        let mut pts = vec![DVec3::ZERO; tri_count(n)];
        for j in 0..=n {
            for i in 0..=n - j {
                pts[idx(n, i, j)] = DVec3::new((2 * i + j) as f64, j as f64, i as f64);
            }
        }
        TriBezierPatch::new(3, pts).unwrap()
    }

    fn wavy(n: usize, seed: u64) -> TriBezierPatch {
        let mut s = seed | 1;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut pts = vec![DVec3::ZERO; tri_count(n)];
        for j in 0..=n {
            for i in 0..=n - j {
                pts[idx(n, i, j)] =
                    DVec3::new(i as f64 + 0.3 * rnd(), j as f64 + 0.3 * rnd(), rnd());
            }
        }
        TriBezierPatch::new(n, pts).unwrap()
    }

    #[test]
    fn tv25_cubic_triangle() {
        let p = tv25();
        // (u, v, w) = (1/6, 2/6, 3/6) → (2, 1, 1/2).
        assert!((p.eval(1.0 / 6.0, 2.0 / 6.0) - DVec3::new(2.0, 1.0, 0.5)).length() < 1e-14);
        // Vertices: u ↔ (6,0,3), v ↔ (3,3,0), w ↔ (0,0,0).
        assert!((p.eval(1.0, 0.0) - DVec3::new(6.0, 0.0, 3.0)).length() < 1e-14);
        assert!((p.eval(0.0, 1.0) - DVec3::new(3.0, 3.0, 0.0)).length() < 1e-14);
        assert!(p.eval(0.0, 0.0).length() < 1e-14);
    }

    #[test]
    fn planar_triangle_is_exact() {
        let (a, b, c) = (
            DVec3::new(1.0, 2.0, 0.5),
            DVec3::new(4.0, 0.0, 1.0),
            DVec3::new(-1.0, -1.0, 2.0),
        );
        let lin = TriBezierPatch::new(1, vec![c, a, b]).unwrap();
        let q = lin.elevate().elevate().elevate();
        assert_eq!(q.degree(), 4);
        for &(u, v) in &[(0.1, 0.2), (0.5, 0.5), (0.0, 0.7), (0.3, 0.3)] {
            let exact = a * u + b * v + c * (1.0 - u - v);
            assert!((q.eval(u, v) - exact).length() < 1e-14);
            let d = q.deriv2(u, v);
            assert!((d.su - (a - c)).length() < 1e-13);
            assert!((d.sv - (b - c)).length() < 1e-13);
            assert!(d.suu.length() + d.suv.length() + d.svv.length() < 1e-12);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for n in 1..=5 {
            check_derivs_fd(&wavy(n, n as u64 * 77), 1e-6);
        }
    }

    #[test]
    fn sphere_octant_approximation_converges() {
        // Interpolate the unit-sphere octant (normalized barycentric combination of the axes)
        // at the uniform grid; the radial error must shrink as the degree grows.
        let f = |u: f64, v: f64| DVec3::new(u, v, 1.0 - u - v).normalize();
        let mut prev = f64::INFINITY;
        let mut errs = Vec::new();
        for n in [2, 4, 6, 8] {
            let p = TriBezierPatch::interpolate(n, f).unwrap();
            let mut worst = 0.0f64;
            for j in 0..=40 {
                for i in 0..=40 - j {
                    let (u, v) = (i as f64 / 40.0, j as f64 / 40.0);
                    worst = worst.max((p.eval(u, v).length() - 1.0).abs());
                }
            }
            errs.push(worst);
            assert!(worst < prev * 0.5, "degree {n}: error {worst} vs {prev}");
            prev = worst;
        }
        // Radial error over an 861-point grid, measured 0.104, 0.0213, 0.0054, 0.0015 for
        // degrees 2, 4, 6, 8; the bounds leave ~20 % headroom.
        assert!(errs[0] < 0.125, "{errs:?}");
        assert!(errs[1] < 0.026, "{errs:?}");
        assert!(errs[2] < 0.0065, "{errs:?}");
        assert!(errs[3] < 0.0018, "{errs:?}");
    }

    proptest! {
        #[test]
        fn subdivision_and_elevation_preserve_the_surface(
            seed in 1u64..500, n in 1usize..5, a in 0.05f64..0.9, b in 0.05f64..0.9,
            x in 0.0f64..1.0, y in 0.0f64..1.0,
        ) {
            prop_assume!(a + b < 0.95);
            let p = wavy(n, seed);
            // A local point (x, y) folded into the unit triangle.
            let (x, y) = if x + y > 1.0 { (1.0 - x, 1.0 - y) } else { (x, y) };
            let z = 1.0 - x - y;
            let e = p.elevate();
            prop_assert!((e.eval(x, y) - p.eval(x, y)).length() < 1e-12);
            let (pt, eu, ev, ew) = (DVec2::new(a, b), DVec2::X, DVec2::Y, DVec2::ZERO);
            let verts = [[pt, ev, ew], [eu, pt, ew], [eu, ev, pt]];
            for (sub, vv) in p.subdivide_at(a, b).iter().zip(verts) {
                let g = vv[0] * x + vv[1] * y + vv[2] * z;
                prop_assert!((sub.eval(x, y) - p.eval(g.x, g.y)).length() < 1e-12);
            }
            let (muv, mvw, mwu) = ((eu + ev) * 0.5, (ev + ew) * 0.5, (ew + eu) * 0.5);
            let verts4 = [[eu, muv, mwu], [muv, ev, mvw], [mwu, mvw, ew], [mvw, mwu, muv]];
            for (sub, vv) in p.subdivide4().iter().zip(verts4) {
                let g = vv[0] * x + vv[1] * y + vv[2] * z;
                prop_assert!((sub.eval(x, y) - p.eval(g.x, g.y)).length() < 1e-12);
            }
        }

        #[test]
        fn partition_of_unity(seed in 1u64..500, x in 0.0f64..1.0, y in 0.0f64..1.0, t in -3.0f64..3.0) {
            let p = wavy(4, seed);
            let q = TriBezierPatch::new(4, p.points().iter().map(|&c| c + DVec3::splat(t)).collect()).unwrap();
            prop_assert!((q.eval(x, y) - p.eval(x, y) - DVec3::splat(t)).length() < 1e-12);
        }
    }
}
