//! A symmetric positive-definite sparse system with a fixed pattern for the Newton steps: the
//! values live in CSC order (upper triangle, rows ≤ column) so that the per-triangle Hessians are
//! scattered straight into precomputed slots, and the factorisation is the crate's one sparse
//! Cholesky, [`crate::sparse::SpdSolver`] (faer, AMD ordering, symbolic factorisation computed
//! once and reused for every step, sequential `Par::Seq`: faster on small machines and
//! bit-for-bit deterministic, crates.md §3).
//!
//! The pattern is handed to [`crate::sparse::SymPattern`] as one triplet per stored entry in slot
//! order, so `values` is exactly the triplet value array that [`crate::sparse::SpdSolver::factor`]
//! expects: no duplicate summing, no per-step assembly beyond the scatter.

use crate::sparse::{SpdSolver, SymPattern, SymTriplets};

/// A fixed-pattern SPD matrix and its reusable symbolic Cholesky factorisation.
pub struct SpdSystem {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Values of the upper triangle, in CSC order.
    pub values: Vec<f64>,
    /// Slot of each diagonal entry.
    diag: Vec<usize>,
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
        let mut row_idx = Vec::with_capacity(entries.len());
        let mut triplets = SymTriplets::with_capacity(n, entries.len());
        for &(r, c) in &entries {
            col_ptr[c + 1] += 1;
            row_idx.push(r);
            triplets.add(r, c, 0.0);
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let diag = (0..n)
            .map(|c| col_ptr[c + 1] - 1) // rows sorted, the diagonal is last in its column
            .collect();
        let pattern = SymPattern::new(&triplets, "newton").map_err(|e| e.to_string())?;
        let solver = SpdSolver::new(pattern, "newton").map_err(|e| e.to_string())?;
        let nnz = row_idx.len();
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            values: vec![0.0; nnz],
            diag,
            solver,
        })
    }

    /// The pattern of 2×2 blocks over `n_vertices` vertices (dofs 2v, 2v + 1): one block for
    /// each vertex pair in `pairs` (any order, duplicates allowed, (a, b) and (b, a) the same).
    pub fn from_vertex_pairs(
        n_vertices: usize,
        mut pairs: Vec<(u32, u32)>,
    ) -> Result<Self, String> {
        for p in pairs.iter_mut() {
            if p.0 > p.1 {
                *p = (p.1, p.0);
            }
        }
        // By column vertex, then row vertex: the CSC order of the upper triangle.
        pairs.sort_unstable_by_key(|&(a, b)| (b, a));
        pairs.dedup();
        let mut entries = Vec::with_capacity(4 * pairs.len());
        let mut start = 0;
        while start < pairs.len() {
            let col = pairs[start].1;
            let mut end = start;
            while end < pairs.len() && pairs[end].1 == col {
                end += 1;
            }
            let (c0, c1) = (2 * col as usize, 2 * col as usize + 1);
            for cj in [c0, c1] {
                for &(a, _) in &pairs[start..end] {
                    for r in [2 * a as usize, 2 * a as usize + 1] {
                        if r <= cj {
                            entries.push((r, cj));
                        }
                    }
                }
            }
            start = end;
        }
        Self::new(2 * n_vertices, entries)
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The slot of entry (r, c) of the upper triangle (r ≤ c); `None` if not in the pattern.
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        let (r, c) = if r <= c { (r, c) } else { (c, r) };
        let rows = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
        rows.binary_search(&r).ok().map(|k| self.col_ptr[c] + k)
    }

    /// Slot of diagonal entry i.
    pub fn diag_slot(&self, i: usize) -> usize {
        self.diag[i]
    }

    /// Zeroes all values.
    pub fn clear(&mut self) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
    }

    /// Factorises the current values (numeric phase only) and solves A x = b in place.
    /// Returns an error if the matrix is not numerically positive definite.
    pub fn factor_solve(&mut self, b: &mut [f64]) -> Result<(), String> {
        self.solver
            .factor(&self.values)
            .map_err(|e| e.to_string())?;
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
            s.values[d] = 3.0;
            if i + 1 < n {
                let k = s.slot(i, i + 1).unwrap();
                s.values[k] = -1.0;
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
