//! A symmetric positive-definite sparse system with a fixed pattern for the Newton steps: the
//! values live in the order the factorisation reads them (the lower triangle of the matrix
//! renumbered by the fill-reducing order) so that the per-triangle Hessians are scattered
//! straight into precomputed slots, and the factorisation is the crate's one sparse
//! Cholesky, `crate::sparse::SpdSolver` (faer; AMD, or nested dissection of the vertex graph
//! from `crate::sparse::NESTED_DISSECTION_FROM` vertices; symbolic factorisation computed
//! once and reused for every step; sequential, `crate::sparse::PAR`).
//!
//! The pattern is handed to `crate::sparse::SymPattern` in compressed-column form and then
//! dropped; the slots are the solver's (`crate::sparse::SpdSolver::slot`), and the values are
//! the solver's own, the array its factorisation reads in place: no duplicate summing, no copy,
//! no renumbering, no per-step assembly beyond the scatter.

use crate::sparse::{Slots, SpdSolver, SymPattern};

/// The relative residual a Newton direction is solved to where the factor is single precision
/// (from `crate::sparse::SINGLE_PRECISION_FROM` factor values, about 300k faces). A Newton
/// step needs its direction to a few digits, not to the last: on a million-face cap the
/// isometric solve takes the same 3 steps to the same δ2 at 1e-4 as at 1e-12, with 1–2 refinement
/// steps per solve instead of 7. Far from the minimum a Newton step needs less still: the
/// solver loosens it there ([`SpdSystem::set_direction_tol`], the forcing term of
/// `super::newton`).
pub const DIRECTION_TOL: f64 = 1e-4;

/// A fixed-pattern SPD matrix and its reusable symbolic Cholesky factorisation.
pub struct SpdSystem {
    n: usize,
    /// Slot of each diagonal entry (32 bits, as the solver's indices).
    diag: Vec<u32>,
    solver: SpdSolver,
}

impl SpdSystem {
    /// Builds the pattern from (row, col) pairs (any order, duplicates allowed; entries with
    /// row > col are mirrored). Every diagonal entry is added.
    pub fn new(n: usize, mut entries: Vec<(usize, usize)>) -> Result<Self, String> {
        for e in entries.iter_mut() {
            if e.0 > e.1 {
                *e = (e.1, e.0);
            }
        }
        entries.extend((0..n).map(|i| (i, i)));
        // Sort by (col, row) for CSC.
        entries.sort_unstable_by_key(|&(r, c)| (c, r));
        entries.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(_, c) in &entries {
            col_ptr[c + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx = entries.iter().map(|e| e.0).collect();
        Self::from_csc(n, col_ptr, row_idx, None)
    }

    /// The pattern of 2×2 blocks over `n_vertices` vertices (dofs 2v, 2v + 1): one block for
    /// each vertex pair in `pairs` (any order, duplicates allowed, (a, b) and (b, a) the same)
    /// and one for each vertex with itself.
    pub fn from_vertex_pairs(
        n_vertices: usize,
        mut pairs: Vec<(u32, u32)>,
    ) -> Result<Self, String> {
        for p in pairs.iter_mut() {
            if p.0 > p.1 {
                *p = (p.1, p.0);
            }
        }
        pairs.extend((0..n_vertices as u32).map(|v| (v, v)));
        // By column vertex, then row vertex: the CSC order of the upper triangle.
        pairs.sort_unstable_by_key(|&(a, b)| (b, a));
        pairs.dedup();
        let n = 2 * n_vertices;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(4 * pairs.len());
        col_ptr.push(0);
        let mut start = 0;
        for col in 0..n_vertices {
            let mut end = start;
            while end < pairs.len() && pairs[end].1 as usize == col {
                end += 1;
            }
            for cj in [2 * col, 2 * col + 1] {
                for &(a, _) in &pairs[start..end] {
                    for r in [2 * a as usize, 2 * a as usize + 1] {
                        if r <= cj {
                            row_idx.push(r);
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
            start = end;
        }
        drop(pairs);
        let node_of = (0..n as u32).map(|i| i / 2).collect();
        Self::from_csc(n, col_ptr, row_idx, Some((node_of, n_vertices)))
    }

    /// The system of the upper-triangle CSC pattern `col_ptr`/`row_idx`, whose diagonal is
    /// stored (last in each column); `nodes` groups the unknowns by mesh vertex for the ordering.
    fn from_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        nodes: Option<(Vec<u32>, usize)>,
    ) -> Result<Self, String> {
        if (0..n).any(|c| col_ptr[c + 1] == col_ptr[c] || row_idx[col_ptr[c + 1] - 1] != c) {
            return Err("the pattern lacks a diagonal entry".into());
        }
        let mut pattern =
            SymPattern::from_upper_csc(n, col_ptr, row_idx, "newton").map_err(|e| e.to_string())?;
        if let Some((node_of, n_nodes)) = nodes {
            pattern = pattern
                .with_nodes(node_of, n_nodes)
                .map_err(|e| e.to_string())?;
        }
        let solver = SpdSolver::new(&pattern, "newton")
            .map_err(|e| e.to_string())?
            .refined(DIRECTION_TOL);
        drop(pattern);
        let diag = (0..n)
            .map(|c| {
                solver
                    .slot(c, c)
                    .map(|s| s as u32)
                    .ok_or("the pattern lacks a diagonal entry")
            })
            .collect::<Result<Vec<u32>, _>>()?;
        Ok(Self { n, diag, solver })
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The slot of entry (r, c) (or (c, r)) in `values`; `None` if not in the pattern.
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        self.solver.slot(r, c)
    }

    /// Slot of diagonal entry i.
    pub fn diag_slot(&self, i: usize) -> usize {
        self.diag[i] as usize
    }

    /// The slots of the entries ([`Self::slot`]).
    pub fn slots(&self) -> Slots<'_> {
        self.solver.slots()
    }

    /// The slots of the entries ([`Self::slot`]) and the values to be changed, at once.
    pub fn slots_and_values_mut(&mut self) -> (Slots<'_>, &mut [f64]) {
        self.solver.slots_and_values_mut()
    }

    /// Values of the matrix, in the solver's order ([`Self::slot`]).
    pub fn values(&self) -> &[f64] {
        self.solver.values()
    }

    /// Values of the matrix, to be changed (the last factorisation no longer holds).
    pub fn values_mut(&mut self) -> &mut [f64] {
        self.solver.values_mut()
    }

    /// Zeroes all values.
    pub fn clear(&mut self) {
        self.values_mut().iter_mut().for_each(|v| *v = 0.0);
    }

    /// Factorises the current values (numeric phase only) and solves A x = b in place.
    /// Returns an error if the matrix is not numerically positive definite.
    pub fn factor_solve(&mut self, b: &mut [f64]) -> Result<(), String> {
        self.solver.refactor().map_err(|e| e.to_string())?;
        self.solver.solve_in_place(b).map_err(|e| e.to_string())
    }

    /// Solves `(A + σ I) x = b`, the smallest shift `σ` of `shift`, `100·shift`, … (`tries` of
    /// them) whose matrix factorises with a finite solution: a projected Hessian is only
    /// positive semi-definite (rigid motions). The values are left shifted by the `σ` tried last;
    /// only the diagonal is saved between tries (the whole matrix would be 60 MB at a million
    /// faces). `None` when no try succeeds.
    pub fn solve_shifted(&mut self, b: &[f64], shift: f64, tries: usize) -> Option<Vec<f64>> {
        let base: Vec<f64> = self
            .diag
            .iter()
            .map(|&s| self.values()[s as usize])
            .collect();
        let mut shift = shift;
        for _ in 0..tries {
            let values = self.solver.values_mut();
            for (&s, &d) in self.diag.iter().zip(&base) {
                values[s as usize] = d + shift;
            }
            let mut x = b.to_vec();
            if self.factor_solve(&mut x).is_ok() && x.iter().all(|v| v.is_finite()) {
                return Some(x);
            }
            shift *= 100.0;
        }
        None
    }

    /// The relative residual the next solves are refined to where the factor is single
    /// precision ([`DIRECTION_TOL`] until changed: an inexact Newton step's forcing term);
    /// exact solves are unaffected.
    pub fn set_direction_tol(&mut self, tol: f64) {
        self.solver.set_refinement_tol(tol);
    }

    /// The same system with its factors made in single precision and its solves refined
    /// whatever its size (small systems in tests).
    #[cfg(test)]
    pub(crate) fn refined_always(mut self) -> Self {
        self.solver = self.solver.refined_always(DIRECTION_TOL);
        self
    }

    /// Where this system's time went (analysis, factorisations, solves).
    pub fn timings(&self) -> crate::Timings {
        self.solver.timings()
    }

    /// Solves A x = b in place with the factorisation of the last successful
    /// [`Self::factor_solve`]; an error once the values have been changed since.
    pub fn solve_factored(&self, b: &mut [f64]) -> Result<(), String> {
        self.solver.solve_in_place(b).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_spd_system() {
        // Tridiagonal 1-D Laplacian + I.
        let n = 50;
        let mut entries = Vec::new();
        for i in 0..n - 1 {
            entries.push((i, i + 1));
        }
        let mut s = SpdSystem::new(n, entries).unwrap();
        for i in 0..n {
            let d = s.diag_slot(i);
            s.values_mut()[d] = 3.0;
            if i + 1 < n {
                let k = s.slot(i, i + 1).unwrap();
                s.values_mut()[k] = -1.0;
            }
        }
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut b: Vec<f64> = (0..n)
            .map(|i| {
                3.0 * x[i]
                    - if i > 0 { x[i - 1] } else { 0.0 }
                    - if i + 1 < n { x[i + 1] } else { 0.0 }
            })
            .collect();
        s.factor_solve(&mut b).unwrap();
        for i in 0..n {
            assert!((b[i] - x[i]).abs() < 1e-12);
        }
    }
}
