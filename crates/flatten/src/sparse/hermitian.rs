//! A sparse Cholesky solver of complex Hermitian positive definite systems `H z = b`, factored
//! once: the complex counterpart of [`SpdSolver`](super::SpdSolver) for a system of two real
//! fields that is the realification of a complex one.
//!
//! A real symmetric system `[[L, M], [Mᵀ, L]] (u, v) = (b_u, b_v)` with `M` antisymmetric (LSCM's:
//! `L` the Dirichlet energy of each coordinate, `M` the boundary's signed area coupling them) is
//! `H z = b_u + i b_v` for `H = L − i M`, Hermitian, and `z = u + i v`. Its factor is one node
//! per mesh vertex instead of two unknowns: half the unknowns to order and analyse, and where
//! the real factor couples u and v (every separator above the boundary, most of the flops) a
//! complex entry is four real products where the real factor's 2 × 2 block is eight.
//!
//! Its analysis is the real solver's ([`Analysis`]), on the pattern of `H`; faer's supernodal
//! Cholesky is generic over the field. Values are made straight into the factor's order
//! ([`HermitianSolver::values_of`]) and factored in place; every faer call is sequential
//! ([`PAR`]), so the factor is the same bits with any number of threads.

use super::{Analysis, Ordering, PAR, SymPattern, Triangles, llt, paged_in, permute_in_place};
use crate::FlattenError;
use crate::internal::InternalError;
use crate::timings::Timings;
use faer::c64;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::LltRef;
use faer::{Conj, MatMut};
use std::time::{Duration, Instant};

/// Whether the analysis amalgamates supernodes (faer's default relaxation: fewer and larger
/// dense blocks, for the explicit zeros it adds). Not: on a million-face toe's LSCM system the
/// factor holds 29.3M values without, 34.9M with (89 MB more), and factors in the same CPU time
/// (1.58–1.69 s against 1.54–1.69 s, sampled by `perf` at load 6–7).
const AMALGAMATE: bool = false;

/// Sparse Cholesky `P H Pᵀ = L Lᴴ` of a Hermitian positive definite matrix, analysed for its
/// pattern, factored once ([`HermitianSolver::factor`]) and then solved for any number of
/// right-hand sides.
#[derive(Debug)]
pub struct HermitianSolver {
    stage: &'static str,
    analysis: Analysis,
    /// The factor's values; empty until the matrix is factored.
    factor: Vec<c64>,
    factor_time: Duration,
    factorisations: usize,
    solve_time: Duration,
}

impl HermitianSolver {
    /// Analyses `pattern` (the lower or upper triangle of `H`: ordering, elimination tree,
    /// supernodes), the lower triangle in the factor's order made beside faer's analysis of the
    /// upper one. Nested dissection from [`super::NESTED_DISSECTION_FROM`] nodes, AMD below.
    /// `stage` names the computation in errors.
    pub fn new(pattern: &SymPattern, stage: &'static str) -> Result<Self, FlattenError> {
        Self::with_ordering(pattern, stage, Ordering::for_nodes(pattern.n_nodes()))
    }

    /// [`HermitianSolver::new`] with a chosen fill-reducing ordering.
    fn with_ordering(
        pattern: &SymPattern,
        stage: &'static str,
        ordering: Ordering,
    ) -> Result<Self, FlattenError> {
        let analysis = Analysis::of(pattern, stage, ordering, Triangles::SideBySide, AMALGAMATE)?;
        Ok(Self {
            stage,
            analysis,
            factor: Vec::new(),
            factor_time: Duration::ZERO,
            factorisations: 0,
            solve_time: Duration::ZERO,
        })
    }

    /// The dimension `n`.
    pub fn dim(&self) -> usize {
        self.analysis.fwd.len()
    }

    /// Number of values a factorisation reads.
    pub fn n_values(&self) -> usize {
        self.analysis.lower.row_idx().len()
    }

    /// The values [`HermitianSolver::factor`] reads of the matrix whose entry in row `i` and
    /// column `j` is `entry(i, j)` (unknowns numbered as in the pattern analysed), asked once for
    /// each entry of the lower triangle in the factor's order, so `i` and `j` either way round
    /// (the other one is its conjugate): made in parallel, the same bits with any number of
    /// threads.
    pub fn values_of(&self, entry: impl Fn(usize, usize) -> c64 + Sync) -> Vec<c64> {
        super::values_in_order(&self.analysis.fwd, &self.analysis.lower, entry)
    }

    /// Numeric factorisation of the matrix with these `values` (as
    /// [`HermitianSolver::values_of`] makes them), freed after it. Fails with
    /// [`FlattenError::Solver`] when the matrix is not numerically positive definite or holds a
    /// non-finite value.
    pub fn factor(&mut self, values: Vec<c64>) -> Result<(), FlattenError> {
        let started = Instant::now();
        self.factor = Vec::new();
        let done = self.factor_untimed(values);
        self.factor_time += started.elapsed();
        self.factorisations += 1;
        done
    }

    /// [`HermitianSolver::factor`], untimed.
    fn factor_untimed(&mut self, values: Vec<c64>) -> Result<(), FlattenError> {
        if values.len() != self.n_values() {
            return Err(FlattenError::Internal(InternalError::ValueCount {
                stage: self.stage,
                got: values.len(),
                want: self.n_values(),
            }));
        }
        if let Some(k) = values
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(FlattenError::Solver {
                stage: self.stage,
                reason: format!("matrix entry {k} is not finite"),
            });
        }
        let symbolic = &self.analysis.symbolic;
        let mut mem =
            self.buffer(symbolic.factorize_numeric_llt_scratch::<c64>(PAR, Default::default()))?;
        let mut l = Vec::new();
        paged_in(&mut l, symbolic.len_val());
        let a = SparseColMatRef::new(self.analysis.lower.as_ref(), values.as_slice());
        llt(symbolic, a, &mut l, PAR, &mut mem).map_err(|reason| FlattenError::Solver {
            stage: self.stage,
            reason,
        })?;
        self.factor = l;
        Ok(())
    }

    /// Solves `H z = rhs` in place. On an error `rhs` holds no solution.
    pub fn solve_in_place(&mut self, rhs: &mut [c64]) -> Result<(), FlattenError> {
        let started = Instant::now();
        let done = self.solve_untimed(rhs);
        self.solve_time += started.elapsed();
        done
    }

    /// [`HermitianSolver::solve_in_place`], untimed.
    fn solve_untimed(&self, rhs: &mut [c64]) -> Result<(), FlattenError> {
        let n = self.dim();
        if rhs.len() != n {
            return Err(FlattenError::Internal(InternalError::RhsLength {
                stage: self.stage,
                len: rhs.len(),
                columns: 1,
                size: n,
            }));
        }
        if self.factor.is_empty() && n > 0 {
            return Err(FlattenError::Internal(InternalError::SolveBeforeFactor {
                stage: self.stage,
            }));
        }
        let mut scratch = Vec::with_capacity(n);
        permute_in_place(rhs, &self.analysis.fwd, &mut scratch);
        let symbolic = &self.analysis.symbolic;
        let mut mem = self.buffer(symbolic.solve_in_place_scratch::<c64>(1, PAR))?;
        LltRef::new(symbolic, &self.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            PAR,
            MemStack::new(&mut mem),
        );
        if let Some(p) = rhs
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(FlattenError::Solver {
                stage: self.stage,
                reason: format!(
                    "the solution is not finite at unknown {}",
                    self.analysis.fwd[p]
                ),
            });
        }
        permute_in_place(rhs, &self.analysis.inv, &mut scratch);
        Ok(())
    }

    /// A workspace of `size`, or an out-of-memory solver error.
    fn buffer(&self, size: StackReq) -> Result<MemBuffer, FlattenError> {
        super::workspace(self.stage, size)
    }

    /// Where this solver's time went: the analysis, the numeric factorisation and the solves.
    pub fn timings(&self) -> Timings {
        Timings {
            ordering: self.analysis.time,
            factorisation: self.factor_time,
            factorisations: self.factorisations,
            solve: self.solve_time,
            ..Timings::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::{SpdSolver, SymTriplets};
    use std::collections::BTreeMap;

    /// The lower triangle of a Hermitian positive definite matrix on a `w × h` grid of vertices
    /// split into triangles (the 7-point pattern of a triangle mesh), by (row, column): a real
    /// Laplacian plus a diagonal shift, and imaginary antisymmetric entries on the outline's
    /// edges (as LSCM's signed area).
    fn grid(w: usize, h: usize) -> BTreeMap<(usize, usize), c64> {
        let rim = |v: usize| {
            let (x, y) = (v % w, v / w);
            x == 0 || y == 0 || x + 1 == w || y + 1 == h
        };
        let mut entries = BTreeMap::new();
        for y in 0..h {
            for x in 0..w {
                let v = y * w + x;
                entries.insert((v, v), c64::new(7.0, 0.0));
                for (dx, dy) in [(1, 0), (0, 1), (1, 1)] {
                    if x + dx < w && y + dy < h {
                        let u = (y + dy) * w + x + dx;
                        let im = if rim(u) && rim(v) && dx + dy == 1 {
                            0.5
                        } else {
                            0.0
                        };
                        entries.insert((u, v), c64::new(-1.0, im));
                    }
                }
            }
        }
        entries
    }

    /// The pattern of `entries` (lower triangle of an `n × n` matrix).
    fn pattern_of(n: usize, entries: &BTreeMap<(usize, usize), c64>) -> SymPattern {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for &(r, c) in entries.keys() {
            cols[c].push(r);
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for rows in cols {
            row_idx.extend(rows);
            col_ptr.push(row_idx.len());
        }
        SymPattern::from_lower_csc(n, col_ptr, row_idx, "test").unwrap()
    }

    /// The entry of `entries` at row `i`, column `j` of the Hermitian matrix.
    fn entry(entries: &BTreeMap<(usize, usize), c64>, i: usize, j: usize) -> c64 {
        if i >= j {
            entries[&(i, j)]
        } else {
            entries[&(j, i)].conj()
        }
    }

    /// The real symmetric form of `entries`: unknowns 2i and 2i + 1 the real and imaginary
    /// parts of unknown i, each entry the block [[Re, −Im], [Im, Re]].
    fn real_form(n: usize, entries: &BTreeMap<(usize, usize), c64>) -> SymTriplets {
        let mut t = SymTriplets::new(2 * n);
        for (&(r, c), h) in entries {
            let block = [[h.re, -h.im], [h.im, h.re]];
            for (f, row) in block.iter().enumerate() {
                for (g, &q) in row.iter().enumerate() {
                    if r != c || f >= g {
                        t.add(2 * r + f, 2 * c + g, q);
                    }
                }
            }
        }
        t
    }

    /// Solves the system of `entries` for `b` with `ordering`.
    fn solve(
        n: usize,
        entries: &BTreeMap<(usize, usize), c64>,
        ordering: Ordering,
        b: &[c64],
    ) -> Vec<c64> {
        let pattern = pattern_of(n, entries);
        let mut s = HermitianSolver::with_ordering(&pattern, "test", ordering).unwrap();
        s.factor(s.values_of(|i, j| entry(entries, i, j))).unwrap();
        let mut z = b.to_vec();
        s.solve_in_place(&mut z).unwrap();
        z
    }

    #[test]
    fn a_hermitian_system_solves_as_its_real_form() {
        let (w, h) = (40, 30);
        let n = w * h;
        let entries = grid(w, h);
        let b: Vec<c64> = (0..n)
            .map(|i| c64::new((i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()))
            .collect();
        let mut x: Vec<f64> = b.iter().flat_map(|z| [z.re, z.im]).collect();
        SpdSolver::from_triplets(&real_form(n, &entries), "test")
            .unwrap()
            .solve_in_place(&mut x)
            .unwrap();
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for ordering in [Ordering::Amd, Ordering::NestedDissection] {
            let z = solve(n, &entries, ordering, &b);
            for i in 0..n {
                let err = (z[i].re - x[2 * i])
                    .abs()
                    .max((z[i].im - x[2 * i + 1]).abs());
                assert!(
                    err <= 1e-13 * scale,
                    "{ordering:?}, unknown {i}: {} against {}, {}",
                    z[i],
                    x[2 * i],
                    x[2 * i + 1]
                );
            }
        }
    }

    #[test]
    fn the_solution_is_the_same_bits_with_any_threads() {
        let (w, h) = (70, 60);
        let n = w * h;
        let entries = grid(w, h);
        let b: Vec<c64> = (0..n).map(|i| c64::new(1.0, (i % 7) as f64)).collect();
        let solutions: Vec<Vec<c64>> = [1, 2]
            .into_iter()
            .map(|threads| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| solve(n, &entries, Ordering::NestedDissection, &b))
            })
            .collect();
        for (p, q) in solutions[0].iter().zip(&solutions[1]) {
            assert_eq!(p.re.to_bits(), q.re.to_bits());
            assert_eq!(p.im.to_bits(), q.im.to_bits());
        }
    }

    #[test]
    fn indefinite_and_non_finite_matrices_and_bad_solves_are_errors() {
        let n = 12;
        let mut entries = grid(4, 3);
        let pattern = pattern_of(n, &entries);
        let mut s = HermitianSolver::new(&pattern, "test").unwrap();
        let mut z = vec![c64::new(1.0, 0.0); n];
        assert!(matches!(
            s.solve_in_place(&mut z),
            Err(FlattenError::Internal(
                InternalError::SolveBeforeFactor { .. }
            ))
        ));
        // A diagonal entry far below its row's couplings: not positive definite.
        entries.insert((5, 5), c64::new(-1.0, 0.0));
        assert!(matches!(
            s.factor(s.values_of(|i, j| entry(&entries, i, j))),
            Err(FlattenError::Solver { stage: "test", .. })
        ));
        entries.insert((5, 5), c64::new(7.0, f64::NAN));
        assert!(matches!(
            s.factor(s.values_of(|i, j| entry(&entries, i, j))),
            Err(FlattenError::Solver { .. })
        ));
        entries.insert((5, 5), c64::new(7.0, 0.0));
        s.factor(s.values_of(|i, j| entry(&entries, i, j))).unwrap();
        assert!(s.solve_in_place(&mut z[..n - 1]).is_err());
        assert!(s.solve_in_place(&mut z).is_ok());
    }
}
