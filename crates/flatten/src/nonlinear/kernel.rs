//! Per-triangle kernel of the nonlinear methods: the rest frame of each 3D triangle, the
//! Jacobian of the map, its rotation-aware 2×2 SVD, isotropic distortion energies Ψ(σ1, σ2)
//! with their gradient and the analytically eigen-projected (positive semi-definite) Hessian.
//!
//! The projection follows Smith, de Goes & Kim, "Analytic eigensystems for isotropic distortion
//! energies" (TOG 2019): for any energy of the singular values, the 4×4 Hessian in F-space has
//! two "scaling" eigenvectors U diag(a) Vᵀ (a from the 2×2 Hessian of Ψ in σ), the symmetric
//! off-diagonal mode U `[[0,1],[1,0]]` Vᵀ/√2 with eigenvalue (Ψ₁ − Ψ₂)/(σ₁ − σ₂) ("twist" below)
//! and the skew, rotation-like mode U `[[0,−1],[1,0]]` Vᵀ/√2 with eigenvalue (Ψ₁ + Ψ₂)/(σ₁ + σ₂)
//! ("flip" below, the one that goes negative). Clamping the eigenvalues at zero gives the projected
//! Newton Hessian without any numerical eigensolver. Written here (not taken from a library)
//! because no maintained Rust crate provides it and it is ~200 lines.

use flatcut_geom::{DMat2, DVec2};
use flatcut_mesh::TriMesh;
use flatcut_mesh::distortion::local_frame;
use nalgebra::{Matrix4, SymmetricEigen};

/// Relative gap |σ₁ − σ₂| / (σ₁ + σ₂) below which the twist eigenvalue is taken from its limit
/// (Ψ₁₁ − Ψ₁₂) instead of the difference quotient, which would lose all digits there.
const TWIST_LIMIT_GAP: f64 = 1e-7;

/// The rest shape of one triangle: inverse of its edge matrix in an orthonormal frame of its
/// plane, and its 3D area.
#[derive(Clone, Copy, Debug)]
pub struct RestTri {
    /// Vertex indices.
    pub v: [usize; 3],
    /// Inverse of the rest edge matrix [p1 − p0, p2 − p0] (columns), frame coordinates.
    pub dm_inv: DMat2,
    /// 3D area (mm²).
    pub area: f64,
}

impl RestTri {
    /// Gradient coefficients g_v = ∂F/∂x_v (row vector) for the three corners: F = Σ x_v g_vᵀ.
    /// Row j of Dm⁻¹ is the coefficient of x_{j+1} (F = Ds Dm⁻¹, Ds = [x1 − x0, x2 − x0]).
    /// Computed where used rather than stored: at a million faces they would be 48 MB.
    #[inline]
    pub fn g(&self) -> [DVec2; 3] {
        let m = self.dm_inv;
        let r0 = DVec2::new(m.x_axis.x, m.y_axis.x);
        let r1 = DVec2::new(m.x_axis.y, m.y_axis.y);
        [-(r0 + r1), r0, r1]
    }

    /// The Jacobian F (2×2, columns = images of the frame axes) of the map for positions `x`.
    #[inline]
    pub fn jacobian(&self, x: &[DVec2]) -> DMat2 {
        let p0 = x[self.v[0]];
        let ds = DMat2::from_cols(x[self.v[1]] - p0, x[self.v[2]] - p0);
        ds * self.dm_inv
    }
}

/// Builds the rest frames of every triangle. Returns the index of the first degenerate
/// triangle (zero area or non-finite corners) as the error.
pub fn rest_frames(mesh: &TriMesh) -> Result<Vec<RestTri>, usize> {
    let mut out = Vec::with_capacity(mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let c = mesh.corners(t);
        let (loc, _, _) = local_frame(c[0], c[1], c[2]).ok_or(t)?;
        let dm = DMat2::from_cols(loc[1] - loc[0], loc[2] - loc[0]);
        let det = dm.determinant();
        if !det.is_finite() || det <= 0.0 {
            return Err(t);
        }
        out.push(RestTri {
            v: [tri[0] as usize, tri[1] as usize, tri[2] as usize],
            dm_inv: dm.inverse(),
            area: 0.5 * det,
        });
    }
    Ok(out)
}

/// Rotation-aware SVD F = U diag(σ1, σ2) Vᵀ with U, V proper rotations; σ2 is negative for a
/// reflected map (signed SVD).
#[derive(Clone, Copy, Debug)]
pub struct Svd2 {
    /// The left rotation U (determinant +1).
    pub u: DMat2,
    /// The right rotation V (determinant +1).
    pub v: DMat2,
    /// The larger singular value σ1 (stretch factor, ≥ |σ2|).
    pub s1: f64,
    /// The smaller singular value σ2, negative for a reflected map.
    pub s2: f64,
}

/// The parts of Blinn's construction: the similarity part (e, h) and the anti-similarity part
/// (f, g) of a 2×2 matrix, F = [[e + f, g − h], [g + h, e − f]].
#[inline]
fn blinn_parts(f: DMat2) -> (f64, f64, f64, f64) {
    let (a, c) = (f.x_axis.x, f.x_axis.y);
    let (b, d) = (f.y_axis.x, f.y_axis.y);
    (0.5 * (a + d), 0.5 * (c - b), 0.5 * (a - d), 0.5 * (c + b))
}

/// The signed singular values (σ1, σ2) of a 2×2 matrix, σ2 < 0 for a reflection: [`svd2`]'s,
/// bit for bit, without its rotations (no trigonometry), for the energy evaluations of the line
/// searches and the limit checks.
#[inline]
pub fn singular_values(f: DMat2) -> (f64, f64) {
    let (e, h, ff, g) = blinn_parts(f);
    let q = (e * e + h * h).sqrt();
    let r = (ff * ff + g * g).sqrt();
    (q + r, q - r)
}

/// Closed-form signed SVD of a 2×2 matrix (Blinn's construction), without trigonometry: with
/// a₁ and a₂ the angles of the anti-similarity part (f, g) and of the similarity part (e, h),
/// F = R(φ) diag(σ1, σ2) R(θ) for φ = (a₂ + a₁)/2, θ = (a₂ − a₁)/2. The rotations come from the
/// parts' unit vectors and one half angle; either half of a₂ + a₁ will do, since the other turns
/// U and V by π together (F, and every product U D Vᵀ of the Newton step, unchanged). On a
/// million-face map the arc tangents and sines of the angle form were an eighth of the solve.
pub fn svd2(f: DMat2) -> Svd2 {
    let (e, h, ff, g) = blinn_parts(f);
    let q = (e * e + h * h).sqrt();
    let r = (ff * ff + g * g).sqrt();
    // The unit vectors of a₂ and a₁ (angle 0 where a part vanishes, as atan2(0, 0) = 0).
    let (c2, s2) = if q > 0.0 { (e / q, h / q) } else { (1.0, 0.0) };
    let (c1, s1) = if r > 0.0 { (ff / r, g / r) } else { (1.0, 0.0) };
    let (cp, sp) = half_angle(c1 * c2 - s1 * s2, s1 * c2 + c1 * s2);
    // θ = φ − a₁.
    let (ct, st) = (cp * c1 + sp * s1, sp * c1 - cp * s1);
    // F = R(φ) diag(σ1, σ2) R(θ), so V = R(θ)ᵀ = R(−θ).
    Svd2 {
        u: DMat2::from_cols(DVec2::new(cp, sp), DVec2::new(-sp, cp)),
        v: DMat2::from_cols(DVec2::new(ct, -st), DVec2::new(st, ct)),
        s1: q + r,
        s2: q - r,
    }
}

/// (cos, sin) of a half of the angle whose (cos, sin) are (`c`, `s`), from the better
/// conditioned of the two half-angle formulas.
#[inline]
fn half_angle(c: f64, s: f64) -> (f64, f64) {
    if c >= 0.0 {
        let ch = (0.5 * (1.0 + c)).sqrt();
        (ch, s / (2.0 * ch))
    } else {
        let sh = (0.5 * (1.0 - c)).sqrt();
        (s / (2.0 * sh), sh)
    }
}

/// An isotropic per-triangle energy density Ψ(σ1, σ2) (dimensionless; integrated over 3D area).
pub trait IsoEnergy: Sync {
    /// Ψ at σ1 ≥ |σ2|, σ2 > 0; +∞ where the map is degenerate or reflected if the energy is a
    /// barrier.
    fn psi(&self, s1: f64, s2: f64) -> f64;
    /// (∂Ψ/∂σ1, ∂Ψ/∂σ2).
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2];
    /// The 2×2 Hessian [[Ψ11, Ψ12], [Ψ12, Ψ22]].
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2];
    /// Twist eigenvalue (Ψ1 − Ψ2)/(σ1 − σ2), with its limit at σ1 = σ2.
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        twist_from(s1, s2, || self.grad(s1, s2), || self.hess(s1, s2))
    }
    /// Flip eigenvalue (Ψ1 + Ψ2)/(σ1 + σ2).
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        flip_from(s1, s2, self.grad(s1, s2))
    }
    /// Ψ, its derivatives and the twist and flip eigenvalues at once, as a Newton step needs
    /// them. An energy whose terms share a costly part (the logarithms of a barrier) overrides
    /// it to compute that part once; the values must equal the separate methods' bit for bit.
    fn derivs(&self, s1: f64, s2: f64) -> IsoDerivs {
        IsoDerivs {
            psi: self.psi(s1, s2),
            grad: self.grad(s1, s2),
            hess: self.hess(s1, s2),
            twist: self.twist(s1, s2),
            flip: self.flip(s1, s2),
        }
    }
    /// True if the energy goes to +∞ as a triangle degenerates (so a line search on it can
    /// never step onto an inverted triangle by itself).
    fn is_barrier(&self) -> bool;
}

/// An isotropic energy's value and derivatives at one pair of singular values
/// ([`IsoEnergy::derivs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsoDerivs {
    /// The energy density Ψ(σ1, σ2) per unit rest area.
    pub psi: f64,
    /// The gradient (∂Ψ/∂σ1, ∂Ψ/∂σ2).
    pub grad: [f64; 2],
    /// The 2×2 Hessian of Ψ in (σ1, σ2).
    pub hess: [[f64; 2]; 2],
    /// The twist eigenvalue (Ψ1 − Ψ2)/(σ1 − σ2) of the F-space Hessian (its limit at σ1 = σ2).
    pub twist: f64,
    /// The flip eigenvalue (Ψ1 + Ψ2)/(σ1 + σ2), the one that goes negative.
    pub flip: f64,
}

/// The twist eigenvalue (Ψ1 − Ψ2)/(σ1 − σ2) from the gradient, or its limit Ψ11 − Ψ12 from the
/// Hessian where σ1 and σ2 are too close to divide (each asked for only where it is used).
pub fn twist_from(
    s1: f64,
    s2: f64,
    grad: impl FnOnce() -> [f64; 2],
    hess: impl FnOnce() -> [[f64; 2]; 2],
) -> f64 {
    if (s1 - s2).abs() <= TWIST_LIMIT_GAP * (s1.abs() + s2.abs()) {
        let h = hess();
        h[0][0] - h[0][1]
    } else {
        let g = grad();
        (g[0] - g[1]) / (s1 - s2)
    }
}

/// The flip eigenvalue (Ψ1 + Ψ2)/(σ1 + σ2) from the gradient.
pub fn flip_from(s1: f64, s2: f64, g: [f64; 2]) -> f64 {
    (g[0] + g[1]) / (s1 + s2)
}

/// Duncan's isometric distortion δ2 = (σ1² + σ1⁻² + σ2² + σ2⁻² − 4)/2 (symmetric Dirichlet).
#[derive(Clone, Copy, Debug, Default)]
pub struct SymDirichlet;

impl IsoEnergy for SymDirichlet {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        if s2.is_nan() || s2 <= 0.0 {
            return f64::INFINITY;
        }
        0.5 * (s1 * s1 + 1.0 / (s1 * s1) + s2 * s2 + 1.0 / (s2 * s2) - 4.0)
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        [s1 - 1.0 / (s1 * s1 * s1), s2 - 1.0 / (s2 * s2 * s2)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        [
            [1.0 + 3.0 / (s1 * s1 * s1 * s1), 0.0],
            [0.0, 1.0 + 3.0 / (s2 * s2 * s2 * s2)],
        ]
    }
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        let p = s1 * s2;
        1.0 + (s1 * s1 + s1 * s2 + s2 * s2) / (p * p * p)
    }
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        let p = s1 * s2;
        1.0 - (s1 * s1 - s1 * s2 + s2 * s2) / (p * p * p)
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// The MIPS energy σ1/σ2 + σ2/σ1 − 2 = 2 cosh(δ1/2) − 2, a monotone function of Duncan's
/// conformal distortion δ1 = 2 log(σ1/σ2).
#[derive(Clone, Copy, Debug, Default)]
pub struct Mips;

impl IsoEnergy for Mips {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        if s2.is_nan() || s2 <= 0.0 {
            return f64::INFINITY;
        }
        s1 / s2 + s2 / s1 - 2.0
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        [1.0 / s2 - s2 / (s1 * s1), 1.0 / s1 - s1 / (s2 * s2)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        let h12 = -1.0 / (s1 * s1) - 1.0 / (s2 * s2);
        [
            [2.0 * s2 / (s1 * s1 * s1), h12],
            [h12, 2.0 * s1 / (s2 * s2 * s2)],
        ]
    }
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        let p = s1 * s2;
        1.0 / p + (s1 * s1 + s1 * s2 + s2 * s2) / (p * p)
    }
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        let p = s1 * s2;
        1.0 / p - (s1 * s1 - s1 * s2 + s2 * s2) / (p * p)
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// Duncan's pointwise deviation δ = (λ1 − 1)² + (λ2 − 1)² with λi = σi² the principal values of
/// the metric (the Green–Lagrange strain norm). Not a barrier: flips are excluded by the line
/// search only.
#[derive(Clone, Copy, Debug, Default)]
pub struct GreenStrain;

impl IsoEnergy for GreenStrain {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        let (a, b) = (s1 * s1 - 1.0, s2 * s2 - 1.0);
        a * a + b * b
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        [4.0 * s1 * (s1 * s1 - 1.0), 4.0 * s2 * (s2 * s2 - 1.0)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        [[12.0 * s1 * s1 - 4.0, 0.0], [0.0, 12.0 * s2 * s2 - 4.0]]
    }
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        4.0 * (s1 * s1 + s1 * s2 + s2 * s2 - 1.0)
    }
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        4.0 * (s1 * s1 - s1 * s2 + s2 * s2 - 1.0)
    }
    fn is_barrier(&self) -> bool {
        false
    }
}

/// Principal stretch below which Duncan's Green–Lagrange term (σ² − 1)² turns concave in σ
/// (its second derivative 12σ² − 4 vanishes at σ = 1/√3): below it, squeezing one triangle
/// further costs less per unit of compression than spreading it, so a solver that must shorten
/// the interior collapses a few triangles instead of compressing many.
pub const GREEN_CONCAVE_BELOW: f64 = 0.577_350_269_189_625_8;

/// Duncan's Green–Lagrange deviation with a collapse guard: [`GreenStrain`] plus a guard on each
/// principal stretch σ below the floor f, a power of u = (f − c)/(σ − c) − 1 ([`GuardShape`]):
/// zero above f, +∞ as σ → c. With f ≥ [`GREEN_CONCAVE_BELOW`] and k ≥ 2/3 the guarded term is
/// convex in each σ below f (the guard's second derivative outgrows the Green term's, which is
/// at least −4), so compression spreads instead of localising, and no stretch can reach c: the
/// smallest admissible stretch. Maps whose stretches all stay above f are scored exactly as by
/// Duncan's energy.
#[derive(Clone, Copy, Debug)]
pub struct GuardedGreen {
    /// Stretch floor f below which the guard acts.
    pub floor: f64,
    /// Stretch c < f at which the guard becomes infinite (0 for a plain anti-collapse barrier).
    pub collapse: f64,
    /// Guard stiffness k (dimensionless, relative to the Green–Lagrange density).
    pub k: f64,
    /// How the guard starts at the floor.
    pub shape: GuardShape,
}

/// How a [`GuardedGreen`]'s guard starts at its floor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GuardShape {
    /// k·u²: its slope is continuous at the floor, its curvature jumps there from 0 to
    /// 2k/(f − c)².
    Quadratic,
    /// k·u³: slope and curvature continuous at the floor. Placed where the Green term is still
    /// convex (f > 1/√3), it makes the guarded term's curvature in σ continuous and positive
    /// everywhere, which a Newton solve needs to converge fast where many stretches sit near the
    /// floor (a jump in curvature there makes the steps alternate between too long and too
    /// short).
    Cubic,
}

impl GuardedGreen {
    /// u = (f − c)/(σ − c) − 1 and its first two derivatives in σ.
    fn u(&self, s: f64) -> (f64, f64, f64) {
        let (w, d) = (self.floor - self.collapse, s - self.collapse);
        (w / d - 1.0, -w / (d * d), 2.0 * w / (d * d * d))
    }

    /// The guard on one principal stretch (its derivatives below).
    pub(crate) fn b(&self, s: f64) -> f64 {
        if s >= self.floor {
            return 0.0;
        }
        let (u, _, _) = self.u(s);
        match self.shape {
            GuardShape::Quadratic => self.k * u * u,
            GuardShape::Cubic => self.k * u * u * u,
        }
    }
    pub(crate) fn db(&self, s: f64) -> f64 {
        if s >= self.floor {
            return 0.0;
        }
        let (u, du, _) = self.u(s);
        match self.shape {
            // Written as before the cubic shape existed, so its results keep their bits.
            GuardShape::Quadratic => {
                let (w, d) = (self.floor - self.collapse, s - self.collapse);
                -2.0 * self.k * u * w / (d * d)
            }
            GuardShape::Cubic => 3.0 * self.k * u * u * du,
        }
    }
    pub(crate) fn d2b(&self, s: f64) -> f64 {
        if s >= self.floor {
            return 0.0;
        }
        let (u, du, d2u) = self.u(s);
        match self.shape {
            GuardShape::Quadratic => {
                let (w, d) = (self.floor - self.collapse, s - self.collapse);
                2.0 * self.k * (du * du + u * 2.0 * w / (d * d * d))
            }
            GuardShape::Cubic => 3.0 * self.k * u * (2.0 * du * du + u * d2u),
        }
    }
}

impl IsoEnergy for GuardedGreen {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        if s2.is_nan() || s2 <= self.collapse.max(0.0) {
            return f64::INFINITY;
        }
        GreenStrain.psi(s1, s2) + self.b(s1) + self.b(s2)
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        let g = GreenStrain.grad(s1, s2);
        [g[0] + self.db(s1), g[1] + self.db(s2)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        let mut h = GreenStrain.hess(s1, s2);
        h[0][0] += self.d2b(s1);
        h[1][1] += self.d2b(s2);
        h
    }
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        let extra = if (s1 - s2).abs() <= TWIST_LIMIT_GAP * (s1.abs() + s2.abs()) {
            self.d2b(s1)
        } else {
            (self.db(s1) - self.db(s2)) / (s1 - s2)
        };
        GreenStrain.twist(s1, s2) + extra
    }
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        GreenStrain.flip(s1, s2) + (self.db(s1) + self.db(s2)) / (s1 + s2)
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// Material limits as a one-sided quadratic penalty on each principal stretch:
/// k·(σ − s_max)₊² + k·(s_min − σ)₊², added to an inner energy.
#[derive(Clone, Copy, Debug)]
pub struct WithLimits<E> {
    /// The energy the penalty is added to.
    pub inner: E,
    /// Largest allowed stretch factor σ1 (∞ for none).
    pub s_max: f64,
    /// Smallest allowed stretch factor σ2 (0 for none).
    pub s_min: f64,
    /// Penalty stiffness (dimensionless, relative to the inner density).
    pub k: f64,
}

impl<E: IsoEnergy> WithLimits<E> {
    fn f(&self, s: f64) -> f64 {
        let a = (s - self.s_max).max(0.0);
        let b = (self.s_min - s).max(0.0);
        self.k * (a * a + b * b)
    }
    fn df(&self, s: f64) -> f64 {
        let a = (s - self.s_max).max(0.0);
        let b = (self.s_min - s).max(0.0);
        2.0 * self.k * (a - b)
    }
    fn d2f(&self, s: f64) -> f64 {
        if s > self.s_max || s < self.s_min {
            2.0 * self.k
        } else {
            0.0
        }
    }
}

impl<E: IsoEnergy> IsoEnergy for WithLimits<E> {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        self.inner.psi(s1, s2) + self.f(s1) + self.f(s2)
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        let g = self.inner.grad(s1, s2);
        [g[0] + self.df(s1), g[1] + self.df(s2)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        let mut h = self.inner.hess(s1, s2);
        h[0][0] += self.d2f(s1);
        h[1][1] += self.d2f(s2);
        h
    }
    fn twist(&self, s1: f64, s2: f64) -> f64 {
        let extra = if (s1 - s2).abs() <= TWIST_LIMIT_GAP * (s1.abs() + s2.abs()) {
            self.d2f(s1)
        } else {
            (self.df(s1) - self.df(s2)) / (s1 - s2)
        };
        self.inner.twist(s1, s2) + extra
    }
    fn flip(&self, s1: f64, s2: f64) -> f64 {
        self.inner.flip(s1, s2) + (self.df(s1) + self.df(s2)) / (s1 + s2)
    }
    fn is_barrier(&self) -> bool {
        self.inner.is_barrier()
    }
}

/// Energy, gradient (3 corners × 2) and projected Hessian (6×6, dof order (v0x, v0y, v1x, …))
/// of one triangle, all multiplied by the triangle's area.
pub struct TriEval {
    /// The triangle's energy (density times rest area).
    pub energy: f64,
    /// The gradient with respect to each corner's 2D position, corners in the triangle's order.
    pub grad: [DVec2; 3],
    /// The projected (positive semidefinite) Hessian, dofs ordered (v0x, v0y, v1x, v1y, v2x, v2y).
    pub hess: [[f64; 6]; 6],
}

/// How the indefinite eigenvalues of a triangle's Hessian are made non-negative.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// Clamped at zero: the closest PSD matrix, exact Newton where the energy is locally convex.
    Clamp,
    /// Mirrored (|λ|): keeps the curvature of the modes that head for inversion as a stiffness,
    /// so a sliver on its way to collapse slows the step down instead of bounding it at the
    /// first inversion (Chen et al., "Trust-region eigenvalue filtering for projected Newton",
    /// 2024).
    Abs,
    /// Not projected: the energy's own Hessian, indefinite on single triangles.
    Raw,
}

/// A per-triangle energy the projected Newton minimises: an isotropic Ψ(σ1, σ2) (every
/// [`IsoEnergy`]) or one that depends on the directions of the map too (the orthotropic energy,
/// [`super::orthotropic`]).
pub trait TriEnergy: Sync {
    /// The area-weighted energy of one triangle (+∞ where a barrier sees an inverted one).
    fn tri_energy(&self, r: &RestTri, x: &[DVec2]) -> f64;
    /// Energy, gradient and Hessian projected by `proj` (`None` skips it) of one triangle.
    fn tri_eval(&self, r: &RestTri, x: &[DVec2], proj: Option<Projection>) -> TriEval;
}

impl<E: IsoEnergy> TriEnergy for E {
    fn tri_energy(&self, r: &RestTri, x: &[DVec2]) -> f64 {
        iso_tri_energy(self, r, x)
    }
    fn tri_eval(&self, r: &RestTri, x: &[DVec2], proj: Option<Projection>) -> TriEval {
        iso_tri_eval(self, r, x, proj)
    }
}

/// Evaluates the area-weighted energy of one triangle only (`None` if not finite).
#[inline]
pub fn tri_energy<E: TriEnergy>(e: &E, r: &RestTri, x: &[DVec2]) -> f64 {
    e.tri_energy(r, x)
}

/// [`tri_energy`] of an isotropic energy.
#[inline]
fn iso_tri_energy<E: IsoEnergy>(e: &E, r: &RestTri, x: &[DVec2]) -> f64 {
    let f = r.jacobian(x);
    let det = f.determinant();
    if (det.is_nan() || det <= 0.0) && e.is_barrier() {
        return f64::INFINITY;
    }
    let (s1, s2) = singular_values(f);
    r.area * e.psi(s1, s2)
}

/// Full evaluation of one triangle with the clamped Hessian; `with_hess` = false skips it.
pub fn tri_eval<E: TriEnergy>(e: &E, r: &RestTri, x: &[DVec2], with_hess: bool) -> TriEval {
    tri_eval_projected(e, r, x, with_hess.then_some(Projection::Clamp))
}

/// Full evaluation of one triangle with its Hessian projected by `proj` (`None` skips it).
pub fn tri_eval_projected<E: TriEnergy>(
    e: &E,
    r: &RestTri,
    x: &[DVec2],
    proj: Option<Projection>,
) -> TriEval {
    e.tri_eval(r, x, proj)
}

/// Adds to `out` the area-weighted gradient and projected Hessian of a density Ψ(F) that is not
/// a function of the singular values alone (the orthotropic energy, per-direction limits):
/// `p` = ∂Ψ/∂F (columns: the derivatives by F's columns) and `h` its 4×4 Hessian in F's entries
/// taken column by column, (F₁₁, F₂₁, F₁₂, F₂₂), or `None` when no Hessian is asked for.
/// The Hessian is projected by a symmetric eigen-decomposition (nalgebra's, deterministic) as
/// `proj` says, then carried to the corners: corner v's coordinate c moves F's column 1 entry c
/// by g_v.x and column 2 entry c by g_v.y.
pub fn add_jacobian_terms(
    out: &mut TriEval,
    r: &RestTri,
    p: DMat2,
    h: Option<Matrix4<f64>>,
    proj: Option<Projection>,
) {
    let g = r.g();
    for c in 0..3 {
        out.grad[c] += r.area * (p * g[c]);
    }
    let (Some(h), Some(proj)) = (h, proj) else {
        return;
    };
    let h4 = project4(h, proj);
    let mut jac = [[0.0; 6]; 4];
    for v in 0..3 {
        for c in 0..2 {
            jac[c][2 * v + c] = g[v].x;
            jac[2 + c][2 * v + c] = g[v].y;
        }
    }
    for i in 0..6 {
        for j in 0..6 {
            let mut s = 0.0;
            for a in 0..4 {
                if jac[a][i] == 0.0 {
                    continue;
                }
                for b in 0..4 {
                    s += jac[a][i] * h4[(a, b)] * jac[b][j];
                }
            }
            out.hess[i][j] += r.area * s;
        }
    }
}

/// A 4×4 Hessian with its eigenvalues made non-negative as `proj` says.
fn project4(h: Matrix4<f64>, proj: Projection) -> Matrix4<f64> {
    if proj == Projection::Raw {
        return h;
    }
    let eig = SymmetricEigen::new(h);
    let mut out = Matrix4::zeros();
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        let l = match proj {
            Projection::Abs => l.abs(),
            _ => l.max(0.0),
        };
        if l > 0.0 {
            let v = eig.eigenvectors.column(i);
            out += l * v * v.transpose();
        }
    }
    out
}

/// [`tri_eval_projected`] of an isotropic energy.
fn iso_tri_eval<E: IsoEnergy>(
    e: &E,
    r: &RestTri,
    x: &[DVec2],
    proj: Option<Projection>,
) -> TriEval {
    let f = r.jacobian(x);
    let s = svd2(f);
    let (s1, s2) = (s.s1, s.s2);
    let d = e.derivs(s1, s2);
    let energy = r.area * d.psi;
    let g = d.grad;
    // P = ∂Ψ/∂F = U diag(g) Vᵀ; ∂E/∂x_v = A · P g_v.
    let p = s.u * DMat2::from_diagonal(DVec2::new(g[0], g[1])) * s.v.transpose();
    let gv = r.g();
    let grad = [
        r.area * (p * gv[0]),
        r.area * (p * gv[1]),
        r.area * (p * gv[2]),
    ];
    let mut hess = [[0.0; 6]; 6];
    if let Some(proj) = proj {
        let h = d.hess;
        // Eigen-decomposition of the symmetric 2×2 scaling block.
        let (a, b, c) = (h[0][0], h[0][1], h[1][1]);
        let mean = 0.5 * (a + c);
        let rad = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        let (l1, l2) = (mean + rad, mean - rad);
        // Eigenvector of l1: robust choice between the two formulas.
        let ev1 = if b.abs() > 0.0 {
            let v = if a >= c {
                DVec2::new(l1 - c, b)
            } else {
                DVec2::new(b, l1 - a)
            };
            v.normalize()
        } else if a >= c {
            DVec2::X
        } else {
            DVec2::Y
        };
        let ev2 = DVec2::new(-ev1.y, ev1.x);
        let inv_sqrt2 = std::f64::consts::FRAC_1_SQRT_2;
        let vt = s.v.transpose();
        let modes = [
            (l1, s.u * DMat2::from_diagonal(ev1) * vt),
            (l2, s.u * DMat2::from_diagonal(ev2) * vt),
            (
                d.twist,
                s.u * DMat2::from_cols(DVec2::new(0.0, inv_sqrt2), DVec2::new(inv_sqrt2, 0.0)) * vt,
            ),
            (
                d.flip,
                s.u * DMat2::from_cols(DVec2::new(0.0, inv_sqrt2), DVec2::new(-inv_sqrt2, 0.0))
                    * vt,
            ),
        ];
        for (lambda, m) in modes {
            let lambda = match proj {
                Projection::Clamp => lambda,
                Projection::Abs => lambda.abs(),
                Projection::Raw if lambda.is_finite() => lambda,
                Projection::Raw => 0.0,
            };
            if !lambda.is_finite() || lambda == 0.0 || (proj != Projection::Raw && lambda < 0.0) {
                continue;
            }
            // Mode vector in x-space: for corner v, m · g_v.
            let w = [m * gv[0], m * gv[1], m * gv[2]];
            let q = [w[0].x, w[0].y, w[1].x, w[1].y, w[2].x, w[2].y];
            let scale = r.area * lambda;
            for i in 0..6 {
                let si = scale * q[i];
                for j in 0..6 {
                    hess[i][j] += si * q[j];
                }
            }
        }
    }
    TriEval { energy, grad, hess }
}

/// The largest step t ∈ (0, ∞] such that det F(x + s·d) > 0 for all s ∈ [0, t) for one
/// triangle, i.e. the smallest positive root of the quadratic det(Ds + t dDs) = 0.
pub fn max_step_tri(r: &RestTri, x: &[DVec2], d: &[DVec2]) -> f64 {
    max_step_corners(r.v, x, d)
}

/// Largest step along `d` before the triangle of the vertices `v` (counter-clockwise in `x`)
/// turns over.
pub fn max_step_corners(v: [usize; 3], x: &[DVec2], d: &[DVec2]) -> f64 {
    let (i0, i1, i2) = (v[0], v[1], v[2]);
    let a0 = x[i1] - x[i0];
    let b0 = x[i2] - x[i0];
    let da = d[i1] - d[i0];
    let db = d[i2] - d[i0];
    let c = a0.perp_dot(b0);
    let b = a0.perp_dot(db) + da.perp_dot(b0);
    let a = da.perp_dot(db);
    smallest_positive_root(a, b, c)
}

/// Smallest positive root of a t² + b t + c (c > 0 expected), +∞ if none.
fn smallest_positive_root(a: f64, b: f64, c: f64) -> f64 {
    let scale = a.abs().max(b.abs()).max(c.abs());
    if scale == 0.0 {
        return f64::INFINITY;
    }
    // Relative size under which the quadratic term is negligible against the others.
    const QUAD_NEGLIGIBLE: f64 = 1e-14;
    if a.abs() <= QUAD_NEGLIGIBLE * scale {
        return if b < 0.0 { -c / b } else { f64::INFINITY };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    let sq = disc.sqrt();
    let q = -0.5 * (b + b.signum() * sq);
    let mut best = f64::INFINITY;
    for t in [q / a, if q != 0.0 { c / q } else { f64::INFINITY }] {
        if t > 0.0 && t < best {
            best = t;
        }
    }
    best
}

/// Test support: asserts that `e`'s energy, gradient and unprojected Hessian on the triangle
/// `r` mapped by `x` match its `tri_energy` and central differences of it (step 1e-6; gradient
/// to 1e-6, Hessian to 1e-5, relative). The map must lie where the energy is finite.
#[cfg(any(test, feature = "test-support"))]
pub fn check_derivatives<E: TriEnergy>(e: &E, r: &RestTri, x: &[DVec2]) {
    let ev = e.tri_eval(r, x, Some(Projection::Raw));
    let te = e.tri_energy(r, x);
    assert!(
        te.is_finite(),
        "the test map must lie where the energy is finite"
    );
    assert!(
        (ev.energy - te).abs() < 1e-12 * te.abs().max(1.0),
        "{} vs {te}",
        ev.energy
    );
    let h = 1e-6;
    let coord = |g: &[DVec2; 3], i: usize| g[i / 2].to_array()[i % 2];
    for i in 0..6 {
        let bump = |s: f64| {
            let mut y = x.to_vec();
            y[i / 2][i % 2] += s;
            y
        };
        let (xp, xm) = (bump(h), bump(-h));
        let fd = (e.tri_energy(r, &xp) - e.tri_energy(r, &xm)) / (2.0 * h);
        let g = coord(&ev.grad, i);
        assert!(
            (g - fd).abs() < 1e-6 * (1.0 + fd.abs()),
            "grad {i}: {g} vs {fd}"
        );
        // Hessian column by differencing the gradient.
        let (gp, gm) = (e.tri_eval(r, &xp, None).grad, e.tri_eval(r, &xm, None).grad);
        for j in 0..6 {
            let fdh = (coord(&gp, j) - coord(&gm, j)) / (2.0 * h);
            let hij = ev.hess[i][j];
            assert!(
                (hij - fdh).abs() < 1e-5 * (1.0 + fdh.abs()),
                "hess {i},{j}: {hij} vs {fdh}"
            );
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    fn tri_mesh() -> (TriMesh, Vec<RestTri>) {
        let m = TriMesh::new(
            vec![
                DVec3::new(0.3, -0.2, 0.1),
                DVec3::new(2.1, 0.4, -0.3),
                DVec3::new(0.7, 1.9, 0.5),
            ],
            vec![[0, 1, 2]],
        );
        let r = rest_frames(&m).unwrap();
        (m, r)
    }

    /// The largest absolute entry of `m`.
    fn max_abs(m: DMat2) -> f64 {
        m.to_cols_array().iter().fold(0.0, |a, e| a.max(e.abs()))
    }

    #[test]
    fn svd_reconstructs_and_signs() {
        // Generic maps, a reflection, a similarity (no anti-similarity part), a pure
        // anti-similarity, angle sums near ±π (the other half-angle formula), and a spread of
        // pseudo-random maps.
        let mut maps = vec![
            DMat2::from_cols(DVec2::new(1.3, 0.2), DVec2::new(-0.4, 0.8)),
            DMat2::from_cols(DVec2::new(-1.0, 0.5), DVec2::new(0.3, 0.9)),
            DMat2::from_cols(DVec2::new(2.0, 0.0), DVec2::new(0.0, 2.0)),
            DMat2::from_angle(2.5) * 1.7,
            DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(0.0, -1.0)),
            DMat2::from_cols(DVec2::new(-1.0, 1e-9), DVec2::new(1e-9, 1.0)),
            DMat2::from_cols(DVec2::new(-1.0, -1e-9), DVec2::new(-1e-9, 1.0)),
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..2000 {
            maps.push(DMat2::from_cols(
                DVec2::new(next(), next()),
                DVec2::new(next(), next()),
            ));
        }
        for f in maps {
            let s = svd2(f);
            for m in [s.u, s.v] {
                assert!((m.determinant() - 1.0).abs() < 1e-12, "a proper rotation");
                assert!(max_abs(m.transpose() * m - DMat2::IDENTITY) < 1e-12);
            }
            let (s1, s2) = singular_values(f);
            assert!(s1.to_bits() == s.s1.to_bits() && s2.to_bits() == s.s2.to_bits());
            let back = s.u * DMat2::from_diagonal(DVec2::new(s.s1, s.s2)) * s.v.transpose();
            let scale = max_abs(f).max(1.0);
            assert!(
                (back - f)
                    .abs()
                    .to_cols_array()
                    .iter()
                    .all(|e| *e < 1e-13 * scale),
                "{f:?}"
            );
            assert!((s.s1 * s.s2 - f.determinant()).abs() < 1e-13);
            assert!(s.s1 >= s.s2.abs());
        }
    }

    /// Checks the gradient and the Hessian of `e` against central differences at a stretched,
    /// sheared and rotated map of one triangle (where the exact Hessian is positive definite).
    pub(crate) fn check_fd<E: TriEnergy>(e: &E) {
        let (_, r) = tri_mesh();
        let r = r[0];
        // A stretched (σ > 1), sheared and rotated image of the rest triangle: every eigenvalue
        // of the exact Hessian is positive there, so the projection is inactive.
        let (m, _) = tri_mesh();
        let c = m.corners(0);
        let (loc, _, _) = local_frame(c[0], c[1], c[2]).unwrap();
        let a =
            DMat2::from_angle(0.4) * DMat2::from_cols(DVec2::new(1.3, 0.1), DVec2::new(0.15, 1.2));
        let x: Vec<DVec2> = loc.iter().map(|p| a * *p + DVec2::new(0.5, -0.2)).collect();
        check_derivatives(e, &r, &x);
    }

    #[test]
    fn symdirichlet_derivatives_match_finite_differences() {
        check_fd(&SymDirichlet);
    }

    #[test]
    fn green_strain_derivatives_match_finite_differences() {
        check_fd(&GreenStrain);
    }

    #[test]
    fn guarded_green_derivatives_match_finite_differences() {
        // Floor above the test map's stretches (≈ 1.1–1.4), so the guard is active in both
        // directions and its derivatives are checked too.
        for shape in [GuardShape::Quadratic, GuardShape::Cubic] {
            for (floor, collapse) in [(1.6, 0.0), (1.6, 0.5), (GREEN_CONCAVE_BELOW, 0.2)] {
                check_fd(&GuardedGreen {
                    floor,
                    collapse,
                    k: 1.0,
                    shape,
                });
            }
        }
    }

    #[test]
    fn guarded_green_is_green_above_the_floor_and_a_barrier_below() {
        let c = 0.2;
        let g = GuardedGreen {
            floor: GREEN_CONCAVE_BELOW,
            collapse: c,
            k: 1.0,
            shape: GuardShape::Quadratic,
        };
        assert_eq!(g.psi(1.2, 0.8), GreenStrain.psi(1.2, 0.8));
        assert!(g.psi(1.0, c + 1e-3) > 1e4);
        assert!(g.psi(1.0, c).is_infinite());
        assert!(g.psi(1.0, 0.1).is_infinite());
        // Convex in σ2 below the floor: the second derivative stays positive down to c.
        for i in 1..100 {
            let s = c + (GREEN_CONCAVE_BELOW - c) * i as f64 / 100.0;
            assert!(g.hess(1.0, s)[1][1] > 0.0, "σ2 = {s}");
        }
    }

    #[test]
    fn a_cubic_guard_above_the_inflection_keeps_the_curvature_continuous_and_positive() {
        // The second derivative in σ of (σ² − 1)² plus the guard, for every collapse stretch the
        // boundary-isometric method may choose (0 to 0.2), from just above c to well above f.
        let floor = 0.7;
        for c in [0.0, 0.05, 0.1, 0.2] {
            let g = GuardedGreen {
                floor,
                collapse: c,
                k: 1.0,
                shape: GuardShape::Cubic,
            };
            let curvature = |s: f64| g.hess(1.0, s)[1][1];
            for i in 1..=400 {
                let s = c + (1.5 - c) * i as f64 / 400.0;
                assert!(curvature(s) > 0.0, "c = {c}, σ = {s}: {}", curvature(s));
            }
            // Continuous at the floor: Green's 12f² − 4 from both sides.
            let (below, above) = (curvature(floor - 1e-9), curvature(floor + 1e-9));
            assert!((below - above).abs() < 1e-6, "{below} {above}");
            assert!((above - (12.0 * floor * floor - 4.0)).abs() < 1e-6);
            assert_eq!(g.psi(1.0, 0.9), GreenStrain.psi(1.0, 0.9));
        }
    }

    #[test]
    fn projected_hessian_is_psd_far_from_rest() {
        let (_, r) = tri_mesh();
        let x = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(5.0, 0.1),
            DVec2::new(0.3, 0.05),
        ];
        for h in [
            tri_eval(&SymDirichlet, &r[0], &x, true).hess,
            tri_eval(&Mips, &r[0], &x, true).hess,
        ] {
            let m = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, j| h[i][j]);
            let ev = m.symmetric_eigenvalues();
            let scale = ev.amax();
            assert!(ev.iter().all(|l| *l >= -1e-10 * scale), "{ev}");
        }
    }

    #[test]
    fn max_step_hits_zero_area() {
        let (_, r) = tri_mesh();
        let x = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 1.0),
        ];
        // Move the apex straight down: it crosses the base at t = 0.5.
        let d = vec![DVec2::ZERO, DVec2::ZERO, DVec2::new(0.3, -2.0)];
        let t = max_step_tri(&r[0], &x, &d);
        assert!((t - 0.5).abs() < 1e-14, "{t}");
        let d = vec![DVec2::ZERO, DVec2::ZERO, DVec2::new(0.0, 1.0)];
        assert!(max_step_tri(&r[0], &x, &d).is_infinite());
    }
}
