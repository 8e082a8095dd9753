//! The orthotropic distortion energy: the Green strain of the map in the material's frame,
//! weighted by the material's stiffness along the warp, across it and in shear.
//!
//! Each triangle's rest frame is turned so that its x axis is the warp's direction on the
//! surface ([`grain_frames`]); the Jacobian's columns are then the images p = F a of the warp and
//! q = F b of the weft, and with E = ½(FᵀF − I)
//!
//! Ψ = 4 k_a E_aa² + 4 k_b E_bb² + 2 k_s (2E_ab)² + guard(σ1, σ2),
//!
//! E_aa = ½(p·p − 1), E_bb = ½(q·q − 1), E_ab = ½ p·q. With k_a = k_b = k_s = 1 this is Duncan's
//! Green–Lagrange deviation (λ1 − 1)² + (λ2 − 1)² = 4‖E‖² exactly, so the stiffnesses are
//! relative to the isotropic sheet the other methods model. A woven fabric (k_s ≪ k_a, k_b) lets
//! its threads keep their lengths and shears instead: the strain goes to the bias.
//!
//! The guard is [`GuardedGreen`]'s collapse guard on the principal stretches (zero above 1/√3,
//! +∞ as a triangle degenerates), with its stiffness the largest of the three, so the energy is
//! a barrier like the isometric energies and every Newton iterate stays flip-free.
//!
//! Gradient: ∂Ψ/∂p = 8k_a E_aa p + 8k_s E_ab q, ∂Ψ/∂q = 8k_b E_bb q + 8k_s E_ab p. Hessian in
//! (p, q): H_pp = 8k_a(p pᵀ + E_aa I) + 4k_s q qᵀ, H_qq = 8k_b(q qᵀ + E_bb I) + 4k_s p pᵀ,
//! H_pq = 4k_s q pᵀ + 8k_s E_ab I. The energy is not a function of the singular values, so the
//! 4×4 Hessian is projected by a symmetric eigen-decomposition
//! ([`super::kernel::add_jacobian_terms`]) rather than by the analytic eigensystems.

use flatcut_geom::{DMat2, DVec2};
use nalgebra::Matrix4;

use super::kernel::{
    GREEN_CONCAVE_BELOW, GuardShape, GuardedGreen, IsoEnergy, Projection, RestTri, TriEnergy,
    TriEval, add_jacobian_terms, tri_eval_projected,
};
use crate::anisotropy::Stiffness;

/// The orthotropic energy of a material (see the module's documentation).
#[derive(Clone, Copy, Debug)]
pub struct Orthotropic {
    /// The material's stiffness.
    pub k: Stiffness,
    guard: CollapseGuard,
}

impl Orthotropic {
    /// The orthotropic energy of a material of stiffness `k`.
    pub fn new(k: Stiffness) -> Self {
        Self {
            k,
            guard: CollapseGuard(GuardedGreen {
                floor: GREEN_CONCAVE_BELOW,
                collapse: 0.0,
                k: k.along.max(k.across).max(k.shear),
                shape: GuardShape::Quadratic,
            }),
        }
    }

    /// Ψ without the guard, for the warp image `p` and the weft image `q`.
    fn strain_psi(&self, p: DVec2, q: DVec2) -> f64 {
        let (eaa, ebb, eab) = strains(p, q);
        4.0 * self.k.along * eaa * eaa
            + 4.0 * self.k.across * ebb * ebb
            + 8.0 * self.k.shear * eab * eab
    }
}

/// (E_aa, E_bb, E_ab) of the warp and weft images.
fn strains(p: DVec2, q: DVec2) -> (f64, f64, f64) {
    (
        0.5 * (p.dot(p) - 1.0),
        0.5 * (q.dot(q) - 1.0),
        0.5 * p.dot(q),
    )
}

impl TriEnergy for Orthotropic {
    fn tri_energy(&self, r: &RestTri, x: &[DVec2]) -> f64 {
        let f = r.jacobian(x);
        let det = f.determinant();
        if det.is_nan() || det <= 0.0 {
            return f64::INFINITY;
        }
        r.area * self.strain_psi(f.x_axis, f.y_axis) + self.guard.tri_energy(r, x)
    }

    fn tri_eval(&self, r: &RestTri, x: &[DVec2], proj: Option<Projection>) -> TriEval {
        let f = r.jacobian(x);
        let (p, q) = (f.x_axis, f.y_axis);
        let (eaa, ebb, eab) = strains(p, q);
        let k = self.k;
        let mut out = tri_eval_projected(&self.guard, r, x, proj);
        out.energy += r.area * self.strain_psi(p, q);
        // P = ∂Ψ/∂F (columns ∂Ψ/∂p, ∂Ψ/∂q); ∂E/∂x_v = A · P g_v.
        let dp = 8.0 * k.along * eaa * p + 8.0 * k.shear * eab * q;
        let dq = 8.0 * k.across * ebb * q + 8.0 * k.shear * eab * p;
        let pm = DMat2::from_cols(dp, dq);
        let h = proj.map(|_| strain_hessian(k, p, q, eaa, ebb, eab));
        add_jacobian_terms(&mut out, r, pm, h, proj);
        out
    }
}

/// The 4×4 Hessian of the strain terms in (p_x, p_y, q_x, q_y).
fn strain_hessian(k: Stiffness, p: DVec2, q: DVec2, eaa: f64, ebb: f64, eab: f64) -> Matrix4<f64> {
    let pv = [p.x, p.y];
    let qv = [q.x, q.y];
    let mut h = Matrix4::zeros();
    for i in 0..2 {
        for j in 0..2 {
            let id = if i == j { 1.0 } else { 0.0 };
            h[(i, j)] = 8.0 * k.along * (pv[i] * pv[j] + eaa * id) + 4.0 * k.shear * qv[i] * qv[j];
            h[(2 + i, 2 + j)] =
                8.0 * k.across * (qv[i] * qv[j] + ebb * id) + 4.0 * k.shear * pv[i] * pv[j];
            // ∂²Ψ/∂p_i∂q_j.
            let pq = 4.0 * k.shear * qv[i] * pv[j] + 8.0 * k.shear * eab * id;
            h[(i, 2 + j)] = pq;
            h[(2 + j, i)] = pq;
        }
    }
    h
}

/// The collapse guard of [`GuardedGreen`] alone (without its Green–Lagrange term).
#[derive(Clone, Copy, Debug)]
struct CollapseGuard(GuardedGreen);

impl IsoEnergy for CollapseGuard {
    fn psi(&self, s1: f64, s2: f64) -> f64 {
        if s2.is_nan() || s2 <= self.0.collapse.max(0.0) {
            return f64::INFINITY;
        }
        self.0.b(s1) + self.0.b(s2)
    }
    fn grad(&self, s1: f64, s2: f64) -> [f64; 2] {
        [self.0.db(s1), self.0.db(s2)]
    }
    fn hess(&self, s1: f64, s2: f64) -> [[f64; 2]; 2] {
        [[self.0.d2b(s1), 0.0], [0.0, self.0.d2b(s2)]]
    }
    fn is_barrier(&self) -> bool {
        true
    }
}

/// The rest frames turned so that each triangle's x axis is its warp direction: `warp[t]` is
/// the warp's direction in triangle t's original frame (a unit vector). F of the turned frame
/// is F·R, R = [warp, warp⊥], so its columns are the images of the warp and the weft.
pub fn grain_frames(rest: &[RestTri], warp: &[DVec2]) -> Vec<RestTri> {
    rest.iter()
        .zip(warp)
        .map(|(r, a)| {
            let rot = DMat2::from_cols(*a, a.perp());
            RestTri {
                v: r.v,
                dm_inv: r.dm_inv * rot,
                area: r.area,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nonlinear::kernel::tests::check_fd;
    use crate::nonlinear::kernel::{GreenStrain, rest_frames, tri_energy, tri_eval};

    #[test]
    fn derivatives_match_finite_differences() {
        for k in [
            Stiffness::ISOTROPIC,
            Stiffness {
                along: 1.0,
                across: 0.7,
                shear: 0.05,
            },
            Stiffness {
                along: 0.3,
                across: 2.0,
                shear: 0.6,
            },
        ] {
            check_fd(&Orthotropic::new(k));
        }
    }

    fn one_triangle() -> (Vec<RestTri>, Vec<DVec2>) {
        let rest = rest_frames(&crate::testmesh::skew_triangle()).unwrap();
        let x = vec![
            DVec2::new(0.1, 0.0),
            DVec2::new(2.2, 0.5),
            DVec2::new(0.2, 1.6),
        ];
        (rest, x)
    }

    #[test]
    fn isotropic_stiffness_is_duncans_green_lagrange_in_any_frame() {
        let (rest, x) = one_triangle();
        let want = tri_energy(&GreenStrain, &rest[0], &x);
        for ang in [0.0, 0.7, 2.1] {
            let r = grain_frames(&rest, &[DVec2::new(f64::cos(ang), f64::sin(ang))]);
            let got = tri_energy(&Orthotropic::new(Stiffness::ISOTROPIC), &r[0], &x);
            assert!(
                (got - want).abs() < 1e-12 * want.max(1.0),
                "{got} vs {want}"
            );
        }
    }

    #[test]
    fn turned_frames_measure_along_the_warp() {
        // Stretch the triangle along the 3D frame's x axis only; with the warp along that axis
        // the warp carries all the strain; with the warp across it, the weft does.
        let (rest, _) = one_triangle();
        let r = rest[0];
        let base = [DVec2::ZERO, DVec2::ZERO, DVec2::ZERO];
        // Corners in the original frame: invert dm_inv to get the rest edge matrix.
        let dm = r.dm_inv.inverse();
        let mut x = base.to_vec();
        x[1] = DVec2::new(1.02 * dm.x_axis.x, dm.x_axis.y);
        x[2] = DVec2::new(1.02 * dm.y_axis.x, dm.y_axis.y);
        let warp_only = Stiffness {
            along: 1.0,
            across: 1e-9,
            shear: 1e-9,
        };
        let along = grain_frames(&rest, &[DVec2::X]);
        let across = grain_frames(&rest, &[DVec2::Y]);
        let e = Orthotropic::new(warp_only);
        let ea = tri_energy(&e, &along[0], &x) / r.area;
        let eb = tri_energy(&e, &across[0], &x) / r.area;
        let eaa = 0.5 * (1.02f64 * 1.02 - 1.0);
        assert!((ea - 4.0 * eaa * eaa).abs() < 1e-9, "{ea}");
        assert!(eb < 1e-9, "{eb}");
    }

    #[test]
    fn projected_hessian_is_psd_under_compression_and_shear() {
        let (rest, _) = one_triangle();
        let x = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.9, 0.4),
            DVec2::new(0.5, 0.6),
        ];
        let e = Orthotropic::new(Stiffness {
            along: 1.0,
            across: 0.8,
            shear: 0.05,
        });
        let h = tri_eval(&e, &rest[0], &x, true).hess;
        let m = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, j| h[i][j]);
        let ev = m.symmetric_eigenvalues();
        let scale = ev.amax();
        assert!(ev.iter().all(|l| *l >= -1e-10 * scale), "{ev}");
        // Collapsing the triangle costs +∞: the energy is a barrier.
        let flat = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(2.0, 0.0),
        ];
        assert!(tri_energy(&e, &rest[0], &flat).is_infinite());
    }
}
