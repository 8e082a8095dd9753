//! The joint problem of several pieces flattened together: the triangles of every piece (one
//! vertex numbering for all) with a distortion energy, plus an augmented-Lagrangian term per
//! pair of seam edges that must come out equally long,
//! L²·(λ c + w c²/2) with c = (|e_a|² − |e_b|²)/L² (L the edges' 3D length),
//! minimised by the same flip-free projected Newton as one piece ([`crate::nonlinear::newton`]):
//! the per-triangle kernel and its eigen-projected Hessian, a fixed-pattern sparse Cholesky whose
//! symbolic factorisation is computed once, steps bounded before the first inversion, Armijo
//! backtracking. The pattern includes the couplings of the four vertices of each edge pair, which
//! join vertices of different pieces; one factorisation serves every energy and every outer
//! iteration.

use flatcut_geom::DVec2;

use crate::Budget;
use crate::nonlinear::kernel::{IsoEnergy, RestTri, max_step_tri, tri_energy, tri_eval};
use crate::nonlinear::newton::{ARMIJO_C, INVERSION_STEP_FRACTION, MAX_HALVINGS, REG_REL};
use crate::nonlinear::spd::SpdSystem;

/// Two edges (vertex pairs, joint numbering) whose flat lengths must be equal; `l` is their 3D
/// length (the mean of the two sides').
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgePair {
    /// The first edge's two vertices (joint numbering, 0-based).
    pub a: [usize; 2],
    /// The second edge's two vertices (joint numbering, 0-based).
    pub b: [usize; 2],
    /// The target flat length of both edges in mm (the mean of the two 3D lengths).
    pub l: f64,
}

/// The joint problem with its multipliers, penalty weight and sparse system.
pub struct Joint<'a> {
    rest: &'a [RestTri],
    pairs: &'a [EdgePair],
    n: usize,
    /// Lagrange multipliers, one per pair.
    pub lambda: Vec<f64>,
    /// Penalty weight w.
    pub weight: f64,
    sys: SpdSystem,
    tri_slots: Vec<[u32; 36]>,
    pair_slots: Vec<[u32; 64]>,
}

/// Slots of the local dof pairs (p, q) of one element in the upper-triangle pattern: each pair
/// (r, c) of global dofs with r ≤ c is written from its (p, q) with dof[p] ≤ dof[q], so an
/// element that names a vertex twice adds both of its mixed terms to that diagonal entry.
fn slots<const K: usize, const KK: usize>(sys: &SpdSystem, dofs: &[usize; K]) -> [u32; KK] {
    let mut out = [u32::MAX; KK];
    for p in 0..K {
        for q in 0..K {
            let (r, c) = (dofs[p], dofs[q]);
            if r <= c
                && let Some(s) = sys.slot(r, c)
            {
                out[p * K + q] = s as u32;
            }
        }
    }
    out
}

fn tri_dofs(r: &RestTri) -> [usize; 6] {
    let v = r.v;
    [
        2 * v[0],
        2 * v[0] + 1,
        2 * v[1],
        2 * v[1] + 1,
        2 * v[2],
        2 * v[2] + 1,
    ]
}

fn pair_dofs(p: &EdgePair) -> [usize; 8] {
    let [a0, a1] = p.a;
    let [b0, b1] = p.b;
    [
        2 * a0,
        2 * a0 + 1,
        2 * a1,
        2 * a1 + 1,
        2 * b0,
        2 * b0 + 1,
        2 * b1,
        2 * b1 + 1,
    ]
}

impl<'a> Joint<'a> {
    /// The problem over `n` vertices, with the sparse pattern and its symbolic factorisation.
    pub fn new(rest: &'a [RestTri], pairs: &'a [EdgePair], n: usize) -> Result<Self, String> {
        let mut entries = Vec::with_capacity(rest.len() * 36 + pairs.len() * 64);
        for r in rest {
            let d = tri_dofs(r);
            for &p in &d {
                for &q in &d {
                    entries.push((p, q));
                }
            }
        }
        for pr in pairs {
            let d = pair_dofs(pr);
            for &p in &d {
                for &q in &d {
                    entries.push((p, q));
                }
            }
        }
        let sys = SpdSystem::new(2 * n, entries)?;
        let tri_slots = rest.iter().map(|r| slots(&sys, &tri_dofs(r))).collect();
        let pair_slots = pairs.iter().map(|p| slots(&sys, &pair_dofs(p))).collect();
        Ok(Self {
            rest,
            pairs,
            n,
            lambda: vec![0.0; pairs.len()],
            weight: 0.0,
            sys,
            tri_slots,
            pair_slots,
        })
    }

    /// Constraint value c_k of pair k.
    pub fn constraint(&self, k: usize, x: &[DVec2]) -> f64 {
        let p = &self.pairs[k];
        let la = (x[p.a[1]] - x[p.a[0]]).length_squared();
        let lb = (x[p.b[1]] - x[p.b[0]]).length_squared();
        (la - lb) / (p.l * p.l)
    }

    /// Largest relative length difference |ℓa − ℓb| / L over the pairs.
    pub fn max_mismatch(&self, x: &[DVec2]) -> f64 {
        self.pairs
            .iter()
            .map(|p| {
                let la = (x[p.a[1]] - x[p.a[0]]).length();
                let lb = (x[p.b[1]] - x[p.b[0]]).length();
                (la - lb).abs() / p.l
            })
            .fold(0.0, f64::max)
    }

    /// λ ← λ + w c.
    pub fn update_multipliers(&mut self, x: &[DVec2]) {
        for k in 0..self.pairs.len() {
            self.lambda[k] += self.weight * self.constraint(k, x);
        }
    }

    fn pair_energy(&self, x: &[DVec2]) -> f64 {
        (0..self.pairs.len())
            .map(|k| {
                let l = self.pairs[k].l;
                let c = self.constraint(k, x);
                l * l * (self.lambda[k] * c + 0.5 * self.weight * c * c)
            })
            .sum()
    }

    /// Total energy (+∞ if a barrier energy sees an inverted or out-of-bounds triangle).
    pub fn total_energy<E: IsoEnergy>(&self, e: &E, x: &[DVec2]) -> f64 {
        self.rest.iter().map(|r| tri_energy(e, r, x)).sum::<f64>() + self.pair_energy(x)
    }

    /// Largest step along `d` before any triangle inverts.
    fn max_step(&self, x: &[DVec2], d: &[DVec2]) -> f64 {
        self.rest
            .iter()
            .map(|r| max_step_tri(r, x, d))
            .fold(f64::INFINITY, f64::min)
    }

    /// Energy, gradient and the mean diagonal entry of the triangles' Hessian (the scale the
    /// Newton step's regularisation is taken from); the projected Hessian, the pair terms' with
    /// it, goes into the system.
    fn assemble<E: IsoEnergy>(&mut self, e: &E, x: &[DVec2]) -> (f64, Vec<f64>, f64) {
        let mut g = vec![0.0; 2 * self.n];
        self.sys.clear();
        let mut en = 0.0;
        let mut trace = 0.0;
        for (t, r) in self.rest.iter().enumerate() {
            let ev = tri_eval(e, r, x, true);
            en += ev.energy;
            trace += (0..6).map(|p| ev.hess[p][p]).sum::<f64>();
            for k in 0..3 {
                g[2 * r.v[k]] += ev.grad[k].x;
                g[2 * r.v[k] + 1] += ev.grad[k].y;
            }
            let s = &self.tri_slots[t];
            for p in 0..6 {
                for q in 0..6 {
                    if s[p * 6 + q] != u32::MAX {
                        self.sys.values_mut()[s[p * 6 + q] as usize] += ev.hess[p][q];
                    }
                }
            }
        }
        for (k, pr) in self.pairs.iter().enumerate() {
            let (da, db) = (x[pr.a[1]] - x[pr.a[0]], x[pr.b[1]] - x[pr.b[0]]);
            let l2 = pr.l * pr.l;
            let c = self.constraint(k, x);
            en += l2 * (self.lambda[k] * c + 0.5 * self.weight * c * c);
            let m = self.lambda[k] + self.weight * c;
            // ∂/∂da = 2 m da, ∂/∂db = −2 m db; J maps (a0, a1, b0, b1) to (da, db).
            let gd = [
                2.0 * m * da.x,
                2.0 * m * da.y,
                -2.0 * m * db.x,
                -2.0 * m * db.y,
            ];
            let dofs = pair_dofs(pr);
            let jt = |p: usize| -> (usize, f64) {
                // Local dof p → (component of (da, db), sign).
                match p {
                    0 | 1 => (p, -1.0),
                    2 | 3 => (p - 2, 1.0),
                    4 | 5 => (p - 2, -1.0),
                    _ => (p - 4, 1.0),
                }
            };
            for p in 0..8 {
                let (i, s) = jt(p);
                g[dofs[p]] += s * gd[i];
            }
            // Hessian in (da, db): (4w/L²) u uᵀ with u = (da, −db), plus 2 max(m, 0) on da and
            // 2 max(−m, 0) on db (the positive part of 2m·diag(I, −I)).
            let u = [da.x, da.y, -db.x, -db.y];
            let mut h = [[0.0; 4]; 4];
            for i in 0..4 {
                for j in 0..4 {
                    h[i][j] = 4.0 * self.weight * u[i] * u[j] / l2;
                }
                h[i][i] += if i < 2 {
                    2.0 * m.max(0.0)
                } else {
                    2.0 * (-m).max(0.0)
                };
            }
            let s = &self.pair_slots[k];
            for p in 0..8 {
                let (i, sp) = jt(p);
                for q in 0..8 {
                    let slot = s[p * 8 + q];
                    if slot != u32::MAX {
                        let (j, sq) = jt(q);
                        self.sys.values_mut()[slot as usize] += sp * sq * h[i][j];
                    }
                }
            }
        }
        (en, g, trace / (2 * self.n) as f64)
    }

    /// Projected Newton on `e` plus the pair terms from the flip-free `x0`: stops when an
    /// iteration gains less than `rel_tolerance` of the energy, the Newton decrement falls below
    /// `abs_tolerance`, no step decreases the energy, or after `max_iters`. Returns the map and
    /// the iterations taken.
    pub fn minimise<E: IsoEnergy>(
        &mut self,
        e: &E,
        x0: &[DVec2],
        max_iters: usize,
        rel_tolerance: f64,
        abs_tolerance: f64,
        budget: &Budget,
    ) -> Result<(Vec<DVec2>, usize), String> {
        let max_iters = budget.allow(max_iters);
        let (x, it) = self.descend(e, x0, max_iters, rel_tolerance, abs_tolerance, budget)?;
        budget.spend(it);
        Ok((x, it))
    }

    /// [`Joint::minimise`] for at most `max_iters` iterations, stopping at the budget's time
    /// limit and reporting progress to it.
    fn descend<E: IsoEnergy>(
        &mut self,
        e: &E,
        x0: &[DVec2],
        max_iters: usize,
        rel_tolerance: f64,
        abs_tolerance: f64,
        budget: &Budget,
    ) -> Result<(Vec<DVec2>, usize), String> {
        let mut x = x0.to_vec();
        if !self.total_energy(e, &x).is_finite() {
            return Err("the start has an inverted or out-of-bounds triangle".into());
        }
        for it in 0..max_iters {
            if budget.expired() || budget.hooks.cancelled() {
                return Ok((x, it));
            }
            // The shift that makes the projected Hessian definite (rigid motions) is relative to
            // the triangles' stiffness alone: taken from the whole diagonal, it grew with the
            // pair terms' weight until it outweighed the triangles' stiffness and the steps
            // shrank towards the gradient's.
            let (e0, g, mean_diag) = self.assemble(e, &x);
            let reg = REG_REL * mean_diag.max(f64::MIN_POSITIVE);
            let minus_g: Vec<f64> = g.iter().map(|v| -v).collect();
            let mut dir = self.sys.solve_shifted(&minus_g, reg, 8).unwrap_or_default();
            let mut gd: f64 = g.iter().zip(&dir).map(|(a, b)| a * b).sum();
            if dir.is_empty() || gd.is_nan() || gd >= 0.0 {
                dir = g.iter().map(|v| -v).collect();
                gd = -g.iter().map(|v| v * v).sum::<f64>();
            }
            let d: Vec<DVec2> = dir
                .chunks_exact(2)
                .map(|c| DVec2::new(c[0], c[1]))
                .collect();
            let mut t = (INVERSION_STEP_FRACTION * self.max_step(&x, &d)).min(1.0);
            let mut xn = x.clone();
            let mut accepted = None;
            for _ in 0..MAX_HALVINGS {
                for (k, q) in xn.iter_mut().enumerate() {
                    *q = x[k] + t * d[k];
                }
                let en = self.total_energy(e, &xn);
                if en.is_finite() && en <= e0 + ARMIJO_C * t * gd {
                    accepted = Some(en);
                    break;
                }
                t *= 0.5;
            }
            let Some(en) = accepted.filter(|en| *en < e0) else {
                return Ok((x, it));
            };
            x = xn;
            budget.hooks.report(&crate::FlattenProgress {
                stage: budget.stage,
                iteration: budget.used() + it + 1,
                max_iterations: budget.cap(),
                energy: en,
                elapsed: budget.started.elapsed(),
            });
            if e0 - en <= rel_tolerance * en.abs() || -0.5 * gd <= abs_tolerance {
                return Ok((x, it + 1));
            }
        }
        Ok((x, max_iters))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nonlinear::kernel::{SymDirichlet, rest_frames};
    use flatcut_geom::DVec3;
    use flatcut_mesh::TriMesh;

    #[test]
    fn pair_terms_match_finite_differences() {
        // Two separate triangles; pair edge (0, 1) of the first with edge (3, 4) of the second.
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.5, 1.5, 0.2),
                DVec3::new(0.0, 0.0, 1.0),
                DVec3::new(2.1, 0.1, 1.0),
                DVec3::new(1.0, 1.7, 1.0),
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        let rest = rest_frames(&m).unwrap();
        let pairs = [EdgePair {
            a: [0, 1],
            b: [3, 4],
            l: 2.05,
        }];
        let mut j = Joint::new(&rest, &pairs, 6).unwrap();
        j.weight = 3.0;
        j.lambda[0] = 0.7;
        let x = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.2, 0.1),
            DVec2::new(0.4, 1.6),
            DVec2::new(5.0, 0.0),
            DVec2::new(6.9, 0.3),
            DVec2::new(5.8, 1.7),
        ];
        let e = SymDirichlet;
        let (_, g, _) = j.assemble(&e, &x);
        let h = 1e-6;
        for k in 0..12 {
            let mut xp = x.clone();
            let mut xm = x.clone();
            if k % 2 == 0 {
                xp[k / 2].x += h;
                xm[k / 2].x -= h;
            } else {
                xp[k / 2].y += h;
                xm[k / 2].y -= h;
            }
            let fd = (j.total_energy(&e, &xp) - j.total_energy(&e, &xm)) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() < 1e-5 * (1.0 + fd.abs()),
                "{k}: {fd} vs {}",
                g[k]
            );
        }
        // Minimising brings the two edges to the same length.
        j.lambda[0] = 0.0;
        j.weight = 10.0;
        let mut y = x.clone();
        for _ in 0..10 {
            y = j
                .minimise(&e, &y, 100, 1e-14, 0.0, &Budget::none("test"))
                .unwrap()
                .0;
            j.update_multipliers(&y);
        }
        assert!(j.max_mismatch(&y) < 1e-8, "{}", j.max_mismatch(&y));
    }

    /// Newton steps of `j` from `x` to a relative energy gain of 1e-12.
    fn steps_to_converge(j: &mut Joint, x: &[DVec2]) -> usize {
        j.minimise(&SymDirichlet, x, 200, 1e-12, 0.0, &Budget::none("test"))
            .unwrap()
            .1
    }

    #[test]
    fn a_stiff_seam_does_not_slow_the_pieces_newton_steps() {
        // Two copies of a cap, started from the same map, an edge of each of their first
        // triangles paired with its copy: the pairs agree from the start and all along, so the
        // weight of their terms must not change how fast the pieces converge.
        let cap = crate::testmesh::spherical_cap(50.0, 0.8, 8);
        let n = cap.positions.len();
        let mut rest = rest_frames(&cap).unwrap();
        rest.extend(rest_frames(&cap).unwrap().into_iter().map(|mut t| {
            t.v = t.v.map(|v| v + n);
            t
        }));
        let pairs: Vec<EdgePair> = cap.triangles[..12]
            .iter()
            .map(|t| {
                let [a0, a1] = [t[0] as usize, t[1] as usize];
                EdgePair {
                    a: [a0, a1],
                    b: [a0 + n, a1 + n],
                    l: cap.positions[a0].distance(cap.positions[a1]),
                }
            })
            .collect();
        let params = crate::FlattenParams::new(crate::Method::Lscm);
        let one = crate::flatten(&cap, &params).unwrap().uv;
        let x: Vec<DVec2> = one.iter().chain(&one).copied().collect();
        let steps = |weight: f64| {
            let mut j = Joint::new(&rest, &pairs, 2 * n).unwrap();
            j.weight = weight;
            steps_to_converge(&mut j, &x)
        };
        // Ten times the largest weight a solve uses: with the shift taken from the whole
        // diagonal, 21 steps here (189 at a hundred times), 5 at weight 10.
        let stiff = 10.0 * crate::assembly::MAX_WEIGHT;
        let (a, b) = (steps(10.0), steps(stiff));
        assert!(b <= a + 2, "{a} steps at weight 10, {b} at {stiff:e}");
    }
}
