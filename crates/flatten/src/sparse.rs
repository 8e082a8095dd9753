//! Thin helpers over faer's sparse matrices: triplet assembly with a reusable pattern, and a
//! symmetric positive definite solver whose symbolic Cholesky factorization is computed once.
//!
//! Every linear method of this crate (Tutte, LSCM, ARAP, the Yamabe solve of
//! `conformal-boundary`) reduces to SPD systems whose sparsity pattern is fixed by the mesh
//! while the values change (ARAP, Newton-type solvers of the nonlinear methods). The pattern is
//! therefore captured once as a [`SymPattern`] (a faer symbolic matrix plus the permutation that
//! sorts the triplets) and the fill-reducing ordering and elimination tree once as a
//! [`SpdSolver`]; each [`SpdSolver::factor`] call only redoes the numeric factorization, on the
//! values of the matrix already renumbered into the factor's order (so faer factors them in
//! place, with no copy).
//!
//! Every faer call is given its parallelism explicitly, and every one is sequential ([`PAR`]),
//! the numeric factorisations too (see [`PAR`] for the measurements): a map's second core is
//! given whole tasks beside them instead (the Newton solve's analysis beside its start map's
//! factorisation, `nonlinear::solve`), and the two halves of a large factorisation under its
//! top separator beside each other ([`split`]). faer's parallel supernodal factorisation would split
//! the dense updates by output blocks, so the factor is the same bits with any number of
//! threads (checked by `the_parallel_factorisation_gives_the_same_bits`).
//!
//! A solver asked for refined solves ([`SpdSolver::refined`]) makes large factors ([`SINGLE_PRECISION_FROM`]) in
//! single precision, half the memory, and refines every solve with them by conjugate gradients
//! on the double-precision matrix it holds ([`crate::refine`]), to the residual the caller needs
//! (a Newton direction far less than a map). A matrix that single precision cannot factor, and a
//! solve whose refinement stalls, fall back to a double-precision factor.

use crate::internal::InternalError;
use faer::Index;
use faer::Par;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{Argsort, Pair, SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Side};

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering as Memory};
use std::time::{Duration, Instant};

use crate::FlattenError;
use crate::beside::beside;
use crate::ordering;
use crate::refine::preconditioned_cg;
use crate::timings::{SharedDuration, Timings};
use rayon::prelude::*;

pub(crate) mod hermitian;
pub(crate) mod split;

use split::{Split, SplitFactor};

/// Nodes (mesh vertices) from which the factorisations use nested dissection instead of AMD.
/// Measured on triangulated grids (`nested_dissection_fills_a_grid_mesh_no_more_than_amd`), the
/// fill of nested dissection against AMD's: with one unknown per vertex +3 % at 22k vertices,
/// −6 % at 90k, −13 % at 360k; with two (u, v) +4 % at 12k, equal at 62k and 109k, −13 % at 200k.
pub const NESTED_DISSECTION_FROM: usize = 150_000;

/// The parallelism of every faer call in this crate, the numeric factorisations included:
/// sequential. faer's supernodal factorisation is a sequential loop over the supernodes that
/// hands each one's dense updates to rayon, hundreds of thousands of small tasks at a million
/// faces (1.56 million futex and 0.9 million `sched_yield` calls in one isometric map): on two
/// cores the second thread's waiting takes the first one's time. Measured through the CLI,
/// one thread against two (`RAYON_NUM_THREADS`, the same binary, alternately, with other work on
/// the machine at load 4–7), the factorisation stage of a toe / saddle map: 100k faces,
/// isometric 1.13 / 0.51 s against 0.92 / 0.84 s, then 1.17 / 0.54 s against 1.58 / 0.84 s;
/// 200k, isometric 2.36 / 1.44 s against 3.95 / 1.78 s, LSCM 0.51 / 0.40 s against 0.72 /
/// 0.54 s; the 1M toe, isometric 9.04 s against 12.71 s (5.64 s against 7.71 s at load 1.3),
/// LSCM 3.17 s against 3.16 s. Two threads paid only on a quiet machine and below a million
/// faces (5 % at 100k, 17 % at 200k, an earlier build), and lost up to 1.7× as soon as
/// anything else ran.
///
/// What is parallel instead is coarse and fixed: a system of [`split::SPLIT_FROM`] unknowns or
/// more ordered by nested dissection is factored and solved in the two halves under its top
/// separator, each sequential on a thread of its own, two tasks for the whole factorisation
/// ([`split`]). Measured through the CLI against the sequential factor (the landed build,
/// alternately), the factorisation stage of a 1M-face isometric map: at load 1.9–2.3, the toe
/// 3.32 / 3.41 s against 5.45 / 6.46 s (the map 9.8 / 11.3 s wall against 12.5 / 16.8 s, CPU
/// 15.3 / 15.6 s against 14.8 / 15.8 s), the hemisphere 3.40 s against 5.85 / 5.91 s; at load
/// 3.1, the toe 4.34 s and once 6.73 s against 6.71 / 7.28 s; at load 4.6–6.2, with the second
/// core taken by other work, no gain or a loss: the toe 6.16 / 6.99 s against 6.10 / 5.91 s,
/// the hemisphere 7.06 / 7.12 s against 5.86 / 5.95 s (the split does 3 % more fill, and about
/// four dense operations of `s³ / 3` flops more at the separator of `s` unknowns). Peak 889–901
/// MB against 871–879 MB. A 330k-face toe gained nothing at load 4.4 ([`split::SPLIT_FROM`]).
pub const PAR: Par = Par::Seq;

/// Values of the Cholesky factor from which a solver asked for refined solves
/// ([`SpdSolver::refined`]) makes it in single precision and refines its solutions by conjugate
/// gradients on the double-precision matrix ([`crate::refine`]). The factor is most of a large
/// map's memory (1.03 GB of 1.58 at a million faces), and single precision halves it. Below, the
/// factor is double precision and a solve is two triangular solves.
pub const SINGLE_PRECISION_FROM: usize = 40_000_000;

/// The relative residual at which a refined solve ends unless its solver says otherwise (a
/// double-precision triangular solve of these systems leaves about 1e-14).
const REFINE_TOL: f64 = 1e-12;

/// Most conjugate-gradient steps of a refined solve that keep single precision worth it; a solver
/// whose refinement takes more makes its later factors in double precision. A step is a
/// single-precision triangular solve (0.16 s at a million faces). An isometric Newton solve
/// takes 1–2 steps to its tolerance, and is 0.9× the double-precision time; f1's, whose length
/// constraints stiffen the system, took 5–7, and were 1.19× slower in single precision.
const REFINE_CHEAP: usize = 4;

/// Most conjugate-gradient iterations of a refined solve; a single-precision factor of these
/// systems takes 2–7 to 1e-12 on a Newton system, 31 on a million-face LSCM system.
const REFINE_MAX: usize = 50;

/// Values of a solver's matrix made by one task of [`SpdSolver::values_of`].
const VALUES_BLOCK: usize = 1 << 16;

/// The index type of the solvers' matrices and factors: half the memory of `usize` for their
/// row indices (a million-face map's factor has 8M, its matrix 7.5M). A system too large for
/// it is refused with an error.
pub(crate) type Idx = u32;

/// Entries of a symmetric matrix, accumulated as `(row, col, value)` triplets. Only the lower
/// triangle is stored: an entry above the diagonal is mirrored below it. Duplicate positions
/// are summed on assembly.
#[derive(Clone, Debug, Default)]
pub struct SymTriplets {
    n: usize,
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl SymTriplets {
    /// An empty `n × n` symmetric matrix.
    #[cfg(test)]
    pub fn new(n: usize) -> Self {
        Self {
            n,
            ..Default::default()
        }
    }

    /// An empty matrix with room for `cap` entries.
    pub fn with_capacity(n: usize, cap: usize) -> Self {
        Self {
            n,
            rows: Vec::with_capacity(cap),
            cols: Vec::with_capacity(cap),
            vals: Vec::with_capacity(cap),
        }
    }

    /// Number of triplets (before duplicates are summed).
    pub fn len(&self) -> usize {
        self.vals.len()
    }

    /// Adds `v` at `(i, j)` and, implicitly, at `(j, i)` (an off-diagonal call therefore adds
    /// `v` to both symmetric positions; call it once per unordered pair).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        self.rows.push(r);
        self.cols.push(c);
        self.vals.push(v);
    }

    /// The values in the order they were added (the order [`SymPattern::matrix`] and
    /// [`SpdSolver::factor`] expect).
    #[cfg(test)]
    pub fn values(&self) -> &[f64] {
        &self.vals
    }

    /// Mutable values, to refill a matrix of the same pattern.
    #[cfg(test)]
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.vals
    }
}

/// The sparsity pattern of a symmetric matrix, from which an [`SpdSolver`] is built: either from
/// [`SymTriplets`] (lower triangle, duplicates merged, with the order that maps triplet values to
/// matrix values) or given directly in compressed-column form (upper triangle). Either triangle
/// is one symmetric pattern to the solver, which holds its own renumbered copy.
#[derive(Clone, Debug)]
pub struct SymPattern {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    /// `Some` for a pattern built from triplets: the sort from triplet order to column order.
    argsort: Option<Argsort<usize>>,
    /// Number of values a refill passes (triplets, or stored entries).
    n_values: usize,
    /// The node (mesh vertex) of each unknown, for the fill-reducing ordering; `None`: each
    /// unknown is its own node.
    nodes: Option<(Vec<u32>, usize)>,
    /// The order of the nodes, when it is given rather than made from the pattern's graph
    /// ([`SymPattern::with_node_order`]).
    node_order: Option<Arc<ordering::Dissected>>,
}

impl SymPattern {
    /// Captures the pattern of `t`. `stage` names the computation in errors.
    pub fn new(t: &SymTriplets, stage: &'static str) -> Result<Self, FlattenError> {
        let pairs: Vec<Pair<usize, usize>> = t
            .rows
            .iter()
            .zip(&t.cols)
            .map(|(&row, &col)| Pair { row, col })
            .collect();
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(t.n, t.n, &pairs)
            .map_err(|e| FlattenError::Solver {
                stage,
                reason: format!("cannot build the sparse pattern: {e:?}"),
            })?;
        Ok(Self {
            n: t.n,
            n_values: t.len(),
            symbolic,
            argsort: Some(argsort),
            nodes: None,
            node_order: None,
        })
    }

    /// Captures the pattern of `t` and sums its values into it, consuming the triplets: the
    /// pattern is then in compressed-column form (values in the returned order, no triplet
    /// order kept). For a matrix factored once, this frees the triplets and their sort before
    /// the factor is allocated: at a million faces LSCM's triplets alone are 336 MB.
    pub fn compress(t: SymTriplets, stage: &'static str) -> Result<(Self, Vec<f64>), FlattenError> {
        let with_order = Self::new(&t, stage)?;
        let matrix = with_order.matrix(&t.vals, stage)?;
        drop(t);
        drop(with_order);
        let (symbolic, values) = matrix.into_parts();
        let n_values = values.len();
        Ok((
            Self {
                n: symbolic.nrows(),
                symbolic,
                argsort: None,
                n_values,
                nodes: None,
                node_order: None,
            },
            values,
        ))
    }

    /// Groups the unknowns into `n_nodes` nodes (`node_of[i]` for unknown `i`): the
    /// fill-reducing ordering then works on the graph of the nodes and keeps the unknowns of a
    /// node together (the u and v of one mesh vertex). A wrong grouping costs fill, never
    /// correctness.
    pub fn with_nodes(mut self, node_of: Vec<u32>, n_nodes: usize) -> Result<Self, FlattenError> {
        if node_of.len() != self.n || node_of.iter().any(|&v| v as usize >= n_nodes) {
            return Err(FlattenError::Internal(InternalError::NodeLabels {
                labels: node_of.len(),
                nodes: n_nodes,
                unknowns: self.n,
            }));
        }
        self.nodes = Some((node_of, n_nodes));
        Ok(self)
    }

    /// Orders the nodes of [`SymPattern::with_nodes`] by the nested dissection `d` of a graph
    /// given apart from this pattern (the mesh's vertex graph, [`ordering::Graph::of_triangles`],
    /// ordered by [`ordering::shared_dissection`]) instead of the quotient of this pattern: a
    /// system whose pinned unknowns are not in its matrix (LSCM's) then orders the graph of the
    /// map's other systems, and shares their order. The graph must couple at least the nodes
    /// the pattern couples, or the order costs fill (never correctness).
    pub fn with_node_order(mut self, d: Arc<ordering::Dissected>) -> Result<Self, FlattenError> {
        if d.order.len() != self.n_nodes() {
            return Err(FlattenError::Internal(InternalError::NodeLabels {
                labels: d.order.len(),
                nodes: self.n_nodes(),
                unknowns: self.n,
            }));
        }
        self.node_order = Some(d);
        Ok(self)
    }

    /// Number of nodes: of the grouping given to [`SymPattern::with_nodes`], else of unknowns.
    pub fn n_nodes(&self) -> usize {
        self.nodes.as_ref().map_or(self.n, |(_, k)| *k)
    }

    /// The nested-dissection elimination order of the node graph ([`crate::ordering`]), shared
    /// with the last system of the same graph ([`ordering::shared_dissection`]), and the position
    /// in it of the first unknown of its last block (the top separator, when the graph was
    /// split).
    fn nested_dissection(&self) -> (Vec<usize>, usize) {
        let identity;
        let (node_of, n_nodes) = match &self.nodes {
            Some((v, k)) => (v.as_slice(), *k),
            None => {
                identity = (0..self.n as u32).collect::<Vec<u32>>();
                (identity.as_slice(), self.n)
            }
        };
        let (col_ptr, row_idx) = self.csc();
        let nodes = match &self.node_order {
            Some(d) => Arc::clone(d),
            None => ordering::shared_dissection(ordering::Graph::quotient(
                col_ptr, row_idx, node_of, n_nodes,
            )),
        };
        let last = nodes.groups.last().map_or(0, |&g| g as usize);
        let mut per_node = vec![0usize; n_nodes];
        for &v in node_of {
            per_node[v as usize] += 1;
        }
        let before: usize = nodes.order[..last]
            .iter()
            .map(|&v| per_node[v as usize])
            .sum();
        (ordering::expand(&nodes.order, node_of), before)
    }

    /// The upper triangle (row ≤ column) in compressed-column form: `col_ptr` (n + 1 offsets) and
    /// `row_idx` (sorted, unique rows of each column). Values are then passed in this order.
    pub fn from_upper_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        stage: &'static str,
    ) -> Result<Self, FlattenError> {
        Self::from_csc(n, col_ptr, row_idx, Side::Upper, stage)
    }

    /// The lower triangle (row ≥ column) in compressed-column form, as [`SymPattern::compress`]
    /// makes it of triplets: a pattern known without its values (LSCM's, from the mesh's graph).
    pub fn from_lower_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        stage: &'static str,
    ) -> Result<Self, FlattenError> {
        Self::from_csc(n, col_ptr, row_idx, Side::Lower, stage)
    }

    /// The triangle `side` in compressed-column form, checked.
    fn from_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        side: Side,
        stage: &'static str,
    ) -> Result<Self, FlattenError> {
        let bad = |reason: String| FlattenError::Solver {
            stage,
            reason: format!("cannot build the sparse pattern: {reason}"),
        };
        if col_ptr.len() != n + 1 || col_ptr.last() != Some(&row_idx.len()) {
            return Err(bad("column offsets do not match the row indices".into()));
        }
        for c in 0..n {
            let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            let outside = match side {
                Side::Upper => rows.last().is_some_and(|&r| r > c),
                Side::Lower => rows.first().is_some_and(|&r| r < c),
            };
            if rows.windows(2).any(|w| w[0] >= w[1]) || outside {
                return Err(bad(format!("column {c} is not a sorted {side:?} triangle")));
            }
        }
        let n_values = row_idx.len();
        Ok(Self {
            n,
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
            argsort: None,
            n_values,
            nodes: None,
            node_order: None,
        })
    }

    /// Column offsets and row indices of the stored triangle.
    pub fn csc(&self) -> (&[usize], &[usize]) {
        (self.symbolic.col_ptr(), self.symbolic.row_idx())
    }

    /// The lower-triangular matrix with these triplet `values` (same order as they were added).
    pub fn matrix(
        &self,
        values: &[f64],
        stage: &'static str,
    ) -> Result<SparseColMat<usize, f64>, FlattenError> {
        if values.len() != self.n_values {
            return Err(FlattenError::Internal(InternalError::TripletCount {
                stage,
                got: values.len(),
                want: self.n_values,
            }));
        }
        let Some(argsort) = &self.argsort else {
            return Err(FlattenError::Internal(InternalError::NoTripletOrder {
                stage,
            }));
        };
        SparseColMat::new_from_argsort(self.symbolic.clone(), argsort, values).map_err(|e| {
            FlattenError::Solver {
                stage,
                reason: format!("cannot assemble the matrix: {e:?}"),
            }
        })
    }
}

/// `y = A x` for the symmetric matrix whose lower triangle is `lower` (as built by
/// [`SymPattern::matrix`]).
#[cfg(test)]
pub fn sym_mul(lower: &SparseColMat<usize, f64>, x: &[f64], y: &mut [f64]) {
    lower_mul(lower.as_ref(), x, y);
}

/// The fill-reducing ordering of a factorisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ordering {
    /// faer's approximate minimum degree.
    Amd,
    /// Nested dissection of the node graph ([`crate::ordering`]).
    NestedDissection,
}

impl Ordering {
    /// Nested dissection from [`NESTED_DISSECTION_FROM`] nodes, AMD below.
    pub fn for_nodes(n_nodes: usize) -> Self {
        if n_nodes >= NESTED_DISSECTION_FROM {
            Self::NestedDissection
        } else {
            Self::Amd
        }
    }
}

/// Symbolic parameters that always choose the supernodal factorisation. faer picks the
/// simplicial one below a flop-per-entry ratio that the maps of this crate fall under up to
/// about 10k faces, where it is slower: a 10k-face scanned patch solved in 0.30 s instead of
/// 0.51 s, a 2k-face toe in 21 ms instead of 31 ms, with nothing slower on the bench.
fn supernodal() -> CholeskySymbolicParams<'static> {
    CholeskySymbolicParams {
        supernodal_flop_ratio_threshold:
            faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    }
}

/// The fill-reducing elimination order of `pattern` under `ordering`: `fwd[k]` is the unknown
/// eliminated k-th. AMD is faer's, called as its symbolic factorisation calls it.
#[cfg(test)]
fn elimination_order(pattern: &SymPattern, ordering: Ordering) -> Result<Vec<usize>, String> {
    ordered(pattern, ordering).map(|(fwd, _)| fwd)
}

/// [`elimination_order`], and with nested dissection the position of the first unknown of the
/// top separator ([`SymPattern::nested_dissection`]).
fn ordered(
    pattern: &SymPattern,
    ordering: Ordering,
) -> Result<(Vec<usize>, Option<usize>), String> {
    if ordering == Ordering::NestedDissection {
        let (fwd, sep) = pattern.nested_dissection();
        return Ok((fwd, Some(sep)));
    }
    let n = pattern.n;
    let a = pattern.symbolic.as_ref();
    let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
        n,
        a.compute_nnz(),
    ))
    .map_err(|e| format!("out of memory: {e:?}"))?;
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        a,
        supernodal().amd_params,
        MemStack::new(&mut mem),
    )
    .map_err(|e| format!("{e:?}"))?;
    Ok((fwd, None))
}

/// The inverse of the permutation `fwd`.
fn inverse(fwd: &[usize]) -> Vec<usize> {
    let mut inv = vec![0usize; fwd.len()];
    for (k, &i) in fwd.iter().enumerate() {
        inv[i] = k;
    }
    inv
}

/// One triangle of `P A Pᵀ` (P: unknown `i` becomes `inv[i]`) for the stored triangle of
/// `pattern`: the lower one (row ≥ column) or the upper one, rows sorted in each column. `None`
/// when its size or entries do not fit the solver's 32-bit indices.
fn permuted_triangle(
    pattern: &SymPattern,
    inv: &[usize],
    side: Side,
) -> Option<SymbolicSparseColMat<Idx>> {
    Some(permuted_triangle_in(
        pattern,
        inv,
        side,
        TriangleStorage::for_pattern(pattern)?,
    ))
}

/// The storage of a [`permuted_triangle`] (zeroed): its column offsets, a copy of them to fill
/// by, and its rows. Made by the thread that keeps the triangle, when another one fills it.
struct TriangleStorage(Vec<Idx>, Vec<Idx>, Vec<Idx>);

impl TriangleStorage {
    /// Storage for a triangle of `pattern`; `None` when its size or entries do not fit the
    /// solver's 32-bit indices.
    fn for_pattern(pattern: &SymPattern) -> Option<Self> {
        let (n, nnz) = (pattern.n, pattern.csc().1.len());
        Idx::try_from(n).ok()?;
        Idx::try_from(nnz).ok()?;
        Some(Self(vec![0; n + 1], vec![0; n + 1], vec![0; nnz]))
    }
}

/// [`permuted_triangle`] in `storage`.
fn permuted_triangle_in(
    pattern: &SymPattern,
    inv: &[usize],
    side: Side,
    storage: TriangleStorage,
) -> SymbolicSparseColMat<Idx> {
    let TriangleStorage(mut new_ptr, mut next, mut new_rows) = storage;
    let n = pattern.n;
    let (col_ptr, row_idx) = pattern.csc();
    let place = |i: usize, j: usize| {
        let (a, b) = (inv[i], inv[j]);
        match side {
            Side::Lower => (a.max(b), a.min(b)),
            Side::Upper => (a.min(b), a.max(b)),
        }
    };
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            new_ptr[place(i, j).1 + 1] += 1;
        }
    }
    for c in 0..n {
        new_ptr[c + 1] += new_ptr[c];
    }
    next.copy_from_slice(&new_ptr);
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            let (r, c) = place(i, j);
            new_rows[next[c] as usize] = r as Idx;
            next[c] += 1;
        }
    }
    drop(next);
    for c in 0..n {
        new_rows[new_ptr[c] as usize..new_ptr[c + 1] as usize].sort_unstable();
    }
    SymbolicSparseColMat::new_checked(n, n, new_ptr, None, new_rows)
}

/// Entries per task of [`paged_in`]: 8 MB of a double-precision factor.
const PAGE_IN_BLOCK: usize = 1 << 20;

/// Makes `l` `size` entries long, its new entries zero and written in parallel: a new factor's
/// storage (590 MB at a million faces) is paged in by both cores rather than one (0.4 s of
/// page faults alone). faer zeroes the factor itself before it factors.
pub(crate) fn paged_in<T: Copy + Default + Send + Sync>(l: &mut Vec<T>, size: usize) {
    if l.len() == size {
        return;
    }
    *l = Vec::new();
    // Zeroed pages from the system, not yet touched.
    *l = vec![T::default(); size];
    l.par_chunks_mut(PAGE_IN_BLOCK)
        .for_each(|c| c.fill(T::default()));
}

/// The values a factorisation of an analysis (its order `fwd` and its lower triangle `lower`)
/// reads, of the matrix whose entry between unknowns `i` and `j` (numbered as in the pattern
/// analysed, `i` the row of the lower triangle in the factor's order) is `entry(i, j)`, asked
/// once for each entry of the pattern's triangle: made in parallel, blocks of the factor's
/// columns at once, each value by `entry` alone, so the same bits with any number of threads.
pub(crate) fn values_in_order<T: Copy + Default + Send>(
    fwd: &[Idx],
    lower: &SymbolicSparseColMat<Idx>,
    entry: impl Fn(usize, usize) -> T + Sync,
) -> Vec<T> {
    let n = fwd.len();
    let col_ptr = lower.col_ptr();
    let rows = lower.row_idx();
    let mut out = vec![T::default(); rows.len()];
    // Blocks of whole columns of about VALUES_BLOCK values.
    let mut blocks = Vec::new();
    let mut rest = out.as_mut_slice();
    let mut first = 0;
    while first < n {
        let start = col_ptr[first] as usize;
        let mut end = first + 1;
        while end < n && (col_ptr[end] as usize) - start < VALUES_BLOCK {
            end += 1;
        }
        let (block, tail) = rest.split_at_mut(col_ptr[end] as usize - start);
        blocks.push((first..end, block));
        rest = tail;
        first = end;
    }
    blocks.into_par_iter().for_each(|(cols, block)| {
        let base = col_ptr[cols.start] as usize;
        for c in cols {
            let j = fwd[c] as usize;
            for k in col_ptr[c] as usize..col_ptr[c + 1] as usize {
                block[k - base] = entry(fwd[rows[k] as usize] as usize, j);
            }
        }
    });
    out
}

/// How an [`Analysis`] makes the two triangles of the matrix in the factor's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Triangles {
    /// The upper one, faer's analysis of it, then the lower one: never both held at once.
    OneAfterTheOther,
    /// The lower one beside faer's analysis of the upper one (both sequential, 0.1 and 0.3 s at
    /// a million faces), the two held together: sooner, for an analysis the map waits for, made
    /// before its factor's memory (LSCM's).
    SideBySide,
}

/// The analysis of a sparse pattern, which a factorisation of its values reads: the elimination
/// order, the pattern of P A Pᵀ's lower triangle (the form faer's supernodal factorisation reads
/// in place) and faer's symbolic factor. The same for real symmetric values ([`SpdSolver`]) and
/// complex Hermitian ones ([`crate::hermitian::HermitianSolver`]).
#[derive(Debug)]
pub(crate) struct Analysis {
    /// The elimination order: unknown `fwd[k]` is the factor's k-th, and `inv` its inverse.
    pub fwd: Vec<Idx>,
    pub inv: Vec<Idx>,
    /// The pattern of P A Pᵀ's lower triangle.
    pub lower: SymbolicSparseColMat<Idx>,
    pub symbolic: SymbolicCholesky<Idx>,
    /// How long the analysis took.
    pub time: Duration,
}

impl Analysis {
    /// The nested-dissection order of `pattern` (`fwd` and its inverse), the pattern of the
    /// matrix's lower triangle in it, and the position of the top separator: all of
    /// [`Analysis::of`] but faer's symbolic factorisation, which a split solver makes of its
    /// halves instead ([`split`]).
    #[allow(clippy::type_complexity)]
    fn lower_of(
        pattern: &SymPattern,
        stage: &'static str,
    ) -> Result<(Vec<Idx>, Vec<Idx>, SymbolicSparseColMat<Idx>, Option<usize>), FlattenError> {
        let failed = |reason: String| FlattenError::Solver {
            stage,
            reason: format!("symbolic factorization failed: {reason}"),
        };
        let (fwd, separator) = ordered(pattern, Ordering::NestedDissection).map_err(failed)?;
        let inv = inverse(&fwd);
        let lower = TriangleStorage::for_pattern(pattern)
            .map(|storage| permuted_triangle_in(pattern, &inv, Side::Lower, storage))
            .ok_or_else(|| failed(format!("{} unknowns are too many to index", pattern.n)))?;
        Ok((
            fwd.into_iter().map(|i| i as Idx).collect(),
            inv.into_iter().map(|i| i as Idx).collect(),
            lower,
            separator,
        ))
    }

    /// Orders `pattern` by `ordering` and analyses it, its two triangles made as `triangles`
    /// says, with faer's supernode amalgamation or without (`amalgamate`: a factor with the
    /// explicit zeros it adds, for fewer and larger dense blocks). `stage` names the
    /// computation in errors.
    pub(crate) fn of(
        pattern: &SymPattern,
        stage: &'static str,
        ordering: Ordering,
        triangles: Triangles,
        amalgamate: bool,
    ) -> Result<Self, FlattenError> {
        let failed = |reason: String| FlattenError::Solver {
            stage,
            reason: format!("symbolic factorization failed: {reason}"),
        };
        let started = Instant::now();
        let (fwd, _) = ordered(pattern, ordering).map_err(failed)?;
        let inv = inverse(&fwd);
        // faer's symbolic analysis reads the upper triangle when no ordering is asked of it, its
        // supernodal numeric factorisation the lower one.
        let too_large = || failed(format!("{} unknowns are too many to index", pattern.n));
        let upper = permuted_triangle(pattern, &inv, Side::Upper).ok_or_else(too_large)?;
        let mut params = supernodal();
        if !amalgamate {
            params.supernodal_params =
                faer::sparse::linalg::SymbolicSupernodalParams { relax: None };
        }
        let symbolic_of = |upper: SymbolicSparseColMat<Idx>| {
            factorize_symbolic_cholesky(
                upper.as_ref(),
                Side::Upper,
                SymmetricOrdering::Identity,
                params,
            )
        };
        let (symbolic, lower) = match triangles {
            Triangles::OneAfterTheOther => {
                let symbolic = symbolic_of(upper);
                let lower = TriangleStorage::for_pattern(pattern)
                    .map(|storage| permuted_triangle_in(pattern, &inv, Side::Lower, storage));
                (symbolic, lower)
            }
            // The lower triangle in storage made here: what the solver keeps, and frees, is this
            // thread's memory, which the allocations after it reuse (another thread's would not).
            Triangles::SideBySide => {
                let storage = TriangleStorage::for_pattern(pattern).ok_or_else(too_large)?;
                let (lower, symbolic) = beside(
                    || permuted_triangle_in(pattern, &inv, Side::Lower, storage),
                    || symbolic_of(upper),
                );
                (symbolic, Some(lower))
            }
        };
        let lower = lower.ok_or_else(too_large)?;
        let symbolic = symbolic.map_err(|e| failed(format!("{e:?}")))?;
        Ok(Self {
            fwd: fwd.into_iter().map(|i| i as Idx).collect(),
            inv: inv.into_iter().map(|i| i as Idx).collect(),
            lower,
            symbolic,
            time: started.elapsed(),
        })
    }
}

/// Sparse Cholesky `P A Pᵀ = L Lᵀ` of a symmetric positive definite matrix with a fixed pattern:
/// the fill-reducing ordering and symbolic factorization are computed in [`SpdSolver::new`],
/// each [`SpdSolver::factor`] redoes only the numeric part.
///
/// The solver holds the matrix in the factor's order, P A Pᵀ's lower triangle, which is the
/// form faer's supernodal factorisation reads in place: values are given in that order (by
/// [`SpdSolver::slot`], or renumbered once by [`SpdSolver::gather`]). Handed A in its own order
/// with the permutation, faer would copy and renumber the whole matrix at every factorisation
/// (4 % of a darted toe's time, and 140 MB of the memory peak at a million faces).
#[derive(Debug)]
pub struct SpdSolver {
    stage: &'static str,
    n: usize,
    /// The elimination order: unknown `fwd[k]` is the factor's k-th, and `inv` its inverse.
    fwd: Vec<Idx>,
    inv: Vec<Idx>,
    /// The pattern of P A Pᵀ's lower triangle; none with `split`, whose halves' bordered
    /// patterns hold it (a copy would be 34 MB at a million faces).
    lower: Option<SymbolicSparseColMat<Idx>>,
    /// faer's analysis of the whole factor, or with `split` none: the split's halves have
    /// theirs, and the whole one would hold as much again.
    symbolic: Option<SymbolicCholesky<Idx>>,
    /// The split of a large system at its top separator ([`split`]): its factors are then made
    /// of the two halves, beside each other.
    split: Option<Split>,
    /// The matrix: the values of P A Pᵀ's lower triangle, in the order of [`SpdSolver::slot`].
    values: Vec<f64>,
    /// The storage of the factor, kept between factorisations.
    factor: Factor,
    /// Whether `factor` is the factor of `values`.
    factored: bool,
    /// The relative residual solves are refined to, when factorisations are made in single
    /// precision ([`SpdSolver::refined`]).
    refine: Option<f64>,
    /// Set by a refined solve that took more than [`REFINE_CHEAP`] steps: the factorisations
    /// after it are made in double precision.
    slow_refinement: AtomicBool,
    /// Parallelism of the numeric factorisation.
    par: Par,
    /// Workspace of the numeric factorisation, kept between factorisations.
    scratch: Option<Scratch>,
    /// Time spent on the ordering and the symbolic factorisation, on numeric factorisations
    /// (and how many), and on solves.
    analysis_time: Duration,
    factor_time: Duration,
    factorisations: usize,
    solve_time: SharedDuration,
    /// Single-precision triangular solves made by refined solves.
    refinements: AtomicUsize,
}

/// Where each entry of a solver's matrix is in its values: the pattern of the matrix in the
/// factor's order, borrowed apart from the values.
#[derive(Clone, Copy, Debug)]
pub struct Slots<'a> {
    inv: &'a [Idx],
    lower: Lower<'a>,
}

/// The pattern of a solver's matrix (its lower triangle in the factor's order): whole, or held
/// by the halves of its split ([`Split::slot`]).
#[derive(Clone, Copy, Debug)]
enum Lower<'a> {
    Whole(&'a SymbolicSparseColMat<Idx>),
    Split(&'a Split),
}

impl<'a> Lower<'a> {
    /// A solver's pattern: `lower`, or else `split`'s.
    fn of(lower: &'a Option<SymbolicSparseColMat<Idx>>, split: &'a Option<Split>) -> Self {
        match (lower, split) {
            (_, Some(split)) => Self::Split(split),
            (Some(lower), None) => Self::Whole(lower),
            (None, None) => Self::Whole(&EMPTY),
        }
    }

    /// Entries of the lower triangle: the values a factorisation reads.
    fn len(self) -> usize {
        match self {
            Self::Whole(lower) => lower.row_idx().len(),
            Self::Split(split) => split.n_values(),
        }
    }

    /// `out = A v` for the symmetric `A` whose lower triangle has this pattern and `values`.
    fn mul(self, values: &[f64], v: &[f64], out: &mut [f64]) {
        match self {
            Self::Whole(lower) => lower_mul(SparseColMatRef::new(lower.as_ref(), values), v, out),
            Self::Split(split) => split.lower_mul(values, v, out),
        }
    }
}

/// The pattern of no matrix.
static EMPTY: std::sync::LazyLock<SymbolicSparseColMat<Idx>> =
    std::sync::LazyLock::new(|| SymbolicSparseColMat::new_checked(0, 0, vec![0], None, Vec::new()));

impl Slots<'_> {
    /// The slot of entry `(r, c)` (or `(c, r)`); `None` if it is not in the pattern.
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        self.slot_in_order(self.position(r)?, self.position(c)?)
    }

    /// The position of unknown `i` in the factor's order.
    pub fn position(&self, i: usize) -> Option<usize> {
        self.inv.get(i).map(|&k| k as usize)
    }

    /// The slot of the entry between the unknowns at positions `a` and `b` of the factor's
    /// order ([`Slots::position`]); `None` if it is not in the pattern.
    pub fn slot_in_order(&self, a: usize, b: usize) -> Option<usize> {
        let (row, col) = (a.max(b), a.min(b));
        let lower = match self.lower {
            Lower::Whole(lower) => lower,
            Lower::Split(split) => return split.slot(row, col),
        };
        let start = *lower.col_ptr().get(col)? as usize;
        let rows = &lower.row_idx()[start..lower.col_ptr()[col + 1] as usize];
        rows.binary_search(&(row as Idx)).ok().map(|k| start + k)
    }
}

/// A factorisation workspace (faer's buffer, which has no `Debug`), large enough for a
/// double-precision factorisation or only for a single-precision one.
struct Scratch {
    mem: MemBuffer,
    double: bool,
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Scratch")
    }
}

impl SpdSolver {
    /// Analyses `pattern` (ordering, elimination tree, supernodes). `stage` names the
    /// computation in errors ("lscm", "arap global step", ...).
    pub fn new(pattern: &SymPattern, stage: &'static str) -> Result<Self, FlattenError> {
        let ordering = Ordering::for_nodes(pattern.n_nodes());
        Self::analysed(pattern, stage, ordering, split::SPLIT_FROM)
    }

    /// [`SpdSolver::new`] with a chosen fill-reducing ordering.
    #[cfg(test)]
    pub fn with_ordering(
        pattern: &SymPattern,
        stage: &'static str,
        ordering: Ordering,
    ) -> Result<Self, FlattenError> {
        Self::analysed(pattern, stage, ordering, split::SPLIT_FROM)
    }

    /// [`SpdSolver::with_ordering`] (nested dissection), split at its top separator whatever
    /// its size when the separator allows it.
    #[cfg(test)]
    pub(crate) fn split_at_any_size(
        pattern: &SymPattern,
        stage: &'static str,
    ) -> Result<Self, FlattenError> {
        Self::analysed(pattern, stage, Ordering::NestedDissection, 0)
    }

    /// Whether this solver's factors are made in two halves.
    #[cfg(test)]
    pub(crate) fn is_split(&self) -> bool {
        self.split.is_some()
    }

    /// The analysis of [`SpdSolver::with_ordering`]: its two triangles one after the other, so
    /// that an analysis made beside a factorisation (the Newton solve's, beside its start map's)
    /// holds the least memory. A nested dissection of `split_from` unknowns or more is split at
    /// its top separator ([`split`]) when the separator allows it, and the whole factor is then
    /// not analysed at all.
    fn analysed(
        pattern: &SymPattern,
        stage: &'static str,
        ordering: Ordering,
        split_from: usize,
    ) -> Result<Self, FlattenError> {
        if ordering == Ordering::NestedDissection && pattern.n >= split_from {
            return Self::analysed_split(pattern, stage);
        }
        // Factors made at every Newton step amalgamate supernodes: without, a Newton factor
        // would hold 9 % fewer values for 12 % more time.
        let Analysis {
            fwd,
            inv,
            lower,
            symbolic,
            time,
        } = Analysis::of(pattern, stage, ordering, Triangles::OneAfterTheOther, true)?;
        Ok(Self::of_analysis(
            stage,
            (pattern.n, fwd, inv, lower),
            Some(symbolic),
            None,
            time,
        ))
    }

    /// [`SpdSolver::analysed`] of a nested dissection split at its top separator, or analysed
    /// whole if the separator does not split it ([`Split::of`]).
    fn analysed_split(pattern: &SymPattern, stage: &'static str) -> Result<Self, FlattenError> {
        let started = Instant::now();
        let (fwd, inv, lower, separator) = Analysis::lower_of(pattern, stage)?;
        let failed = |reason: String| FlattenError::Solver {
            stage,
            reason: format!("symbolic factorization failed: {reason}"),
        };
        let split = match separator {
            Some(sep) => Split::of(&lower, sep).map_err(failed)?,
            None => None,
        };
        let symbolic = match split {
            Some(_) => None,
            None => Some(split::analyse(&lower).map_err(failed)?),
        };
        Ok(Self::of_analysis(
            stage,
            (pattern.n, fwd, inv, lower),
            symbolic,
            split,
            started.elapsed(),
        ))
    }

    /// A solver of `n` unknowns in the order `fwd` (`inv` its inverse) whose matrix's lower
    /// triangle has the pattern `lower`, factored whole by `symbolic` or split by `split`, its
    /// analysis having taken `time`.
    fn of_analysis(
        stage: &'static str,
        (n, fwd, inv, lower): (usize, Vec<Idx>, Vec<Idx>, SymbolicSparseColMat<Idx>),
        symbolic: Option<SymbolicCholesky<Idx>>,
        split: Option<Split>,
        time: Duration,
    ) -> Self {
        let n_lower = lower.row_idx().len();
        Self {
            stage,
            n,
            fwd,
            inv,
            lower: split.is_none().then_some(lower),
            values: vec![0.0; n_lower],
            symbolic,
            split,
            factor: Factor::None,
            factored: false,
            refine: None,
            slow_refinement: AtomicBool::new(false),
            par: PAR,
            scratch: None,
            analysis_time: time,
            factor_time: Duration::ZERO,
            factorisations: 0,
            solve_time: SharedDuration::default(),
            refinements: AtomicUsize::new(0),
        }
    }

    /// faer's analysis of the whole factor (not made for a split solver).
    fn whole(&self) -> Result<&SymbolicCholesky<Idx>, FlattenError> {
        self.symbolic
            .as_ref()
            .ok_or(FlattenError::Internal(InternalError::NoFactor {
                stage: self.stage,
            }))
    }

    /// Values of a factor: the whole one's, or the split halves' together.
    fn factor_len(&self) -> usize {
        match (&self.symbolic, &self.split) {
            (Some(s), _) => s.len_val(),
            (None, Some(split)) => split.len_val(),
            (None, None) => 0,
        }
    }

    /// The same solver with its factorisations run with `par`.
    #[cfg(test)]
    fn with_par(mut self, par: Par) -> Self {
        self.par = par;
        self.scratch = None;
        self
    }

    /// The values of the last factor, when it is in double precision (empty otherwise).
    #[cfg(test)]
    fn double_factor(&self) -> &[f64] {
        match &self.factor {
            Factor::Double(l) => l,
            _ => &[],
        }
    }

    /// The same solver with its factors made in single precision when they have
    /// [`SINGLE_PRECISION_FROM`] values or more, and its solves then refined to the relative
    /// residual `tol`. (By default factors are double precision.)
    pub fn refined(mut self, tol: f64) -> Self {
        self.refine = (self.factor_len() >= SINGLE_PRECISION_FROM).then_some(tol);
        self
    }

    /// Refined solves (where the factor is single precision) are made to the relative residual
    /// `tol` from now on: an inexact Newton step's direction is solved to its forcing term.
    pub fn set_refinement_tol(&mut self, tol: f64) {
        if self.refine.is_some() {
            self.refine = Some(tol);
        }
    }

    /// [`SpdSolver::refined`] whatever the factor's size (small systems in tests).
    #[cfg(test)]
    pub(crate) fn refined_always(mut self, tol: f64) -> Self {
        self.refine = Some(tol);
        self
    }

    /// The same solver with its factors made in single precision whatever their size, and its
    /// solves refined to [`REFINE_TOL`].
    #[cfg(test)]
    fn single(mut self) -> Self {
        self.refine = Some(REFINE_TOL);
        self
    }

    /// Builds the pattern of `t` and analyses it, then factors `t`'s values.
    #[cfg(test)]
    pub fn from_triplets(t: &SymTriplets, stage: &'static str) -> Result<Self, FlattenError> {
        let pattern = SymPattern::new(t, stage)?;
        let mut s = Self::new(&pattern, stage)?;
        let values = s.gather_matrix(pattern.matrix(t.values(), stage)?.as_ref());
        s.factor(values)?;
        Ok(s)
    }

    /// The dimension `n`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of values a factorisation reads.
    pub fn n_values(&self) -> usize {
        Lower::of(&self.lower, &self.split).len()
    }

    /// Where the value of entry `(r, c)` (or `(c, r)`) of A goes in the values
    /// [`SpdSolver::factor`] reads; `None` if it is not in the pattern.
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        self.slots().slot(r, c)
    }

    /// The slots of the matrix's entries ([`SpdSolver::slot`]), to look up while the values
    /// are changed ([`SpdSolver::slots_and_values_mut`]).
    pub fn slots(&self) -> Slots<'_> {
        Slots {
            inv: &self.inv,
            lower: Lower::of(&self.lower, &self.split),
        }
    }

    /// [`SpdSolver::slots`] and [`SpdSolver::values_mut`] at once.
    pub fn slots_and_values_mut(&mut self) -> (Slots<'_>, &mut [f64]) {
        self.factored = false;
        let slots = Slots {
            inv: &self.inv,
            lower: Lower::of(&self.lower, &self.split),
        };
        (slots, &mut self.values)
    }

    /// The values of a compressed-column `pattern` (as [`SymPattern::compress`] returns them,
    /// the pattern this solver was built for) renumbered into the order [`SpdSolver::factor`]
    /// reads.
    pub fn gather(&self, pattern: &SymPattern, values: &[f64]) -> Result<Vec<f64>, FlattenError> {
        if pattern.argsort.is_some() || values.len() != self.n_values() || pattern.n != self.n {
            return Err(FlattenError::Internal(InternalError::GatherMismatch {
                stage: self.stage,
                values: values.len(),
                size: pattern.n,
                solver_values: self.n_values(),
                solver_size: self.n,
            }));
        }
        Ok(self.gather_matrix(SparseColMatRef::new(pattern.symbolic.as_ref(), values)))
    }

    /// [`SpdSolver::gather`] of a matrix with the pattern this solver was built for.
    fn gather_matrix(&self, a: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
        let mut out = vec![0.0; self.n_values()];
        for j in 0..a.ncols() {
            let rows = a.symbolic().row_idx_of_col_raw(j);
            for (&i, &v) in rows.iter().zip(a.val_of_col(j)) {
                if let Some(k) = self.slot(i, j) {
                    out[k] = v;
                }
            }
        }
        out
    }

    /// The matrix's values, in the order of [`SpdSolver::slot`].
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The matrix's values, to be changed: the factor no longer holds until
    /// [`SpdSolver::refactor`].
    pub fn values_mut(&mut self) -> &mut [f64] {
        self.factored = false;
        &mut self.values
    }

    /// Numeric factorization of the matrix with these `values` (in the order of
    /// [`SpdSolver::slot`]), which the solver keeps. Fails with [`FlattenError::Solver`] when the
    /// matrix is not numerically positive definite or holds a non-finite value.
    pub fn factor(&mut self, values: Vec<f64>) -> Result<(), FlattenError> {
        self.factored = false;
        if values.len() != self.n_values() {
            return Err(FlattenError::Internal(InternalError::ValueCount {
                stage: self.stage,
                got: values.len(),
                want: self.n_values(),
            }));
        }
        self.values = values;
        self.refactor()
    }

    /// Numeric factorization of the matrix's current values (see [`SpdSolver::factor`]).
    pub fn refactor(&mut self) -> Result<(), FlattenError> {
        let started = Instant::now();
        let done = self.refactor_numeric();
        self.factor_time += started.elapsed();
        self.factorisations += 1;
        done
    }

    /// Where this solver's time went: the analysis, the numeric factorisations and the solves.
    pub fn timings(&self) -> Timings {
        Timings {
            ordering: self.analysis_time,
            factorisation: self.factor_time,
            factorisations: self.factorisations,
            solve: self.solve_time.get(),
            refinements: self.refinements.load(Memory::Relaxed),
            ..Timings::default()
        }
    }

    /// [`SpdSolver::refactor`], untimed.
    fn refactor_numeric(&mut self) -> Result<(), FlattenError> {
        self.factored = false;
        if let Some(k) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(FlattenError::Solver {
                stage: self.stage,
                reason: format!("matrix entry {k} is not finite"),
            });
        }
        let single = self.refine.is_some() && !self.slow_refinement.load(Memory::Relaxed);
        let single = single && self.values.iter().all(|v| v.abs() <= f64::from(f32::MAX));
        if self.split.is_some() {
            return self.refactor_split(single);
        }
        // The factor's storage is reused: it is the same size every time.
        let size = self.factor_len();
        if single {
            let mut l = match std::mem::take(&mut self.factor) {
                Factor::Single(l) => l,
                _ => Vec::new(),
            };
            paged_in(&mut l, size);
            let a: Vec<f32> = self.values.iter().map(|&v| v as f32).collect();
            if self.factor_numeric(&mut l, &a, false).is_ok() {
                self.factor = Factor::Single(l);
                self.factored = true;
                return Ok(());
            }
            // Not positive definite in single precision (an ill-conditioned system): this
            // factorisation is made in double precision; the next tries single again.
        }
        let mut l = match std::mem::take(&mut self.factor) {
            Factor::Double(l) => l,
            _ => Vec::new(),
        };
        paged_in(&mut l, size);
        let a = std::mem::take(&mut self.values);
        let done = self.factor_numeric(&mut l, &a, true);
        self.values = a;
        done?;
        self.factor = Factor::Double(l);
        self.factored = true;
        Ok(())
    }

    /// [`SpdSolver::refactor_numeric`] of a split system: in single precision when `single`
    /// says and it can, else in double.
    fn refactor_split(&mut self, single: bool) -> Result<(), FlattenError> {
        let Some(split) = &self.split else {
            return Err(FlattenError::Internal(InternalError::NoFactor {
                stage: self.stage,
            }));
        };
        if single {
            let mut f = match std::mem::take(&mut self.factor) {
                Factor::SplitSingle(f) => f,
                _ => split.empty(),
            };
            if split.factor::<f32>(&self.values, &mut f).is_ok() {
                self.factor = Factor::SplitSingle(f);
                self.factored = true;
                return Ok(());
            }
        }
        let mut f = match std::mem::take(&mut self.factor) {
            Factor::SplitDouble(f) => f,
            _ => split.empty(),
        };
        split
            .factor::<f64>(&self.values, &mut f)
            .map_err(|reason| FlattenError::Solver {
                stage: self.stage,
                reason,
            })?;
        self.factor = Factor::SplitDouble(f);
        self.factored = true;
        Ok(())
    }

    /// faer's numeric factorisation of the matrix with `values` into `l`, in the precision of
    /// `T` (`double`: f64), with the kept scratch.
    fn factor_numeric<T: ComplexField>(
        &mut self,
        l: &mut [T],
        values: &[T],
        double: bool,
    ) -> Result<(), FlattenError> {
        // The scratch is the same size for every factorisation of this pattern and precision:
        // allocated once, so the later ones neither page-fault nor zero it again. Its room for a
        // renumbered copy of the matrix is never written here (the matrix is already in the
        // factor's order and triangle), so it is never paged in either.
        if !self.scratch.as_ref().is_some_and(|s| s.double || !double) {
            self.scratch = None;
            let symbolic = self.whole()?;
            let mut size =
                symbolic.factorize_numeric_llt_scratch::<f32>(self.par, Default::default());
            if double {
                size =
                    size.or(
                        symbolic.factorize_numeric_llt_scratch::<f64>(self.par, Default::default())
                    );
            }
            self.scratch = Some(Scratch {
                mem: self.buffer(size)?,
                double,
            });
        }
        let Some(Scratch { mem, .. }) = self.scratch.as_mut() else {
            return Err(FlattenError::Internal(InternalError::NoScratch {
                stage: self.stage,
            }));
        };
        let (Some(lower), Some(symbolic)) = (&self.lower, &self.symbolic) else {
            return Err(FlattenError::Internal(InternalError::NoFactor {
                stage: self.stage,
            }));
        };
        let a = SparseColMatRef::new(lower.as_ref(), values);
        llt(symbolic, a, l, self.par, mem).map_err(|reason| FlattenError::Solver {
            stage: self.stage,
            reason,
        })
    }

    /// A workspace of `size`, or an out-of-memory solver error.
    fn buffer(&self, size: StackReq) -> Result<MemBuffer, FlattenError> {
        workspace(self.stage, size)
    }

    /// Solves `A x = rhs` in place for one right-hand side.
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> Result<(), FlattenError> {
        self.solve_many_in_place(rhs, 1)
    }

    /// Solves `A X = RHS` in place for the columns of `rhs` (column-major `n × k` slice). On an
    /// error `rhs` holds no solution.
    pub fn solve_many_in_place(&self, rhs: &mut [f64], k: usize) -> Result<(), FlattenError> {
        let n = self.dim();
        if rhs.len() != n * k {
            return Err(FlattenError::Internal(InternalError::RhsLength {
                stage: self.stage,
                len: rhs.len(),
                columns: k,
                size: n,
            }));
        }
        if !self.factored {
            return Err(FlattenError::Internal(InternalError::SolveBeforeFactor {
                stage: self.stage,
            }));
        }
        let started = Instant::now();
        let done = self.solve_many_timed(rhs, k);
        self.solve_time.add_since(started);
        done
    }

    /// [`SpdSolver::solve_many_in_place`] once the arguments are checked, untimed.
    fn solve_many_timed(&self, rhs: &mut [f64], k: usize) -> Result<(), FlattenError> {
        let n = self.dim();
        // Into the factor's order, solved there, and back, in place (a copy is 8 MB a column at a
        // million faces).
        let mut scratch = Vec::with_capacity(n);
        for col in rhs.chunks_exact_mut(n) {
            permute_in_place(col, &self.fwd, &mut scratch);
        }
        let tol = self.refine.unwrap_or(REFINE_TOL);
        match &self.factor {
            Factor::Double(l) => self.solve_factored(l, rhs, k)?,
            Factor::Single(l) => self.solve_refined(Single::Whole(l), rhs, tol, REFINE_MAX)?,
            Factor::SplitDouble(f) => self.solve_split(f, rhs, k)?,
            Factor::SplitSingle(f) => self.solve_refined(Single::Split(f), rhs, tol, REFINE_MAX)?,
            Factor::None => {
                return Err(FlattenError::Internal(InternalError::NoFactor {
                    stage: self.stage,
                }));
            }
        }
        for (j, col) in rhs.chunks_exact_mut(n).enumerate() {
            if let Some(p) = col.iter().position(|v| !v.is_finite()) {
                return Err(FlattenError::Solver {
                    stage: self.stage,
                    reason: format!(
                        "the solution is not finite at unknown {} (column {j})",
                        self.fwd[p]
                    ),
                });
            }
            permute_in_place(col, &self.inv, &mut scratch);
        }
        Ok(())
    }

    /// Solves in place, in the factor's order, for the `k` columns of `y` with the factor `l`.
    fn solve_factored<T: ComplexField>(
        &self,
        l: &[T],
        y: &mut [T],
        k: usize,
    ) -> Result<(), FlattenError> {
        let symbolic = self.whole()?;
        let mut mem = self.buffer(symbolic.solve_in_place_scratch::<T>(k, PAR))?;
        LltRef::new(symbolic, l).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(y, self.n, k),
            PAR,
            MemStack::new(&mut mem),
        );
        Ok(())
    }

    /// Solves in place, in the factor's order, for the `k` columns of `y` with the split factor
    /// `f`.
    fn solve_split<T: split::Precision>(
        &self,
        f: &SplitFactor<T>,
        y: &mut [T],
        k: usize,
    ) -> Result<(), FlattenError> {
        let Some(split) = &self.split else {
            return Err(FlattenError::Internal(InternalError::NoFactor {
                stage: self.stage,
            }));
        };
        split.solve(f, y, k).map_err(|reason| FlattenError::Solver {
            stage: self.stage,
            reason,
        })
    }

    /// Solves in place, in the factor's order, for the columns of `y`: conjugate gradients on
    /// the matrix, preconditioned by its single-precision factor `l`, to the relative residual
    /// `tol`. A column that does not get there in `max_iter` iterations is solved with a
    /// double-precision factor of the matrix, made for it.
    fn solve_refined(
        &self,
        l: Single<'_>,
        y: &mut [f64],
        tol: f64,
        max_iter: usize,
    ) -> Result<(), FlattenError> {
        let n = self.n;
        let pattern = Lower::of(&self.lower, &self.split);
        let applied = AtomicUsize::new(0);
        let precondition = |r: &[f64], z: &mut [f64]| {
            applied.fetch_add(1, Memory::Relaxed);
            // Scaled into f32's range whatever the residual's size.
            let scale = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if scale == 0.0 || !scale.is_finite() {
                z.copy_from_slice(r);
                return;
            }
            let mut r32: Vec<f32> = r.iter().map(|&v| (v / scale) as f32).collect();
            let solved = match l {
                Single::Whole(l) => self.solve_factored(l, &mut r32, 1),
                Single::Split(f) => self.solve_split(f, &mut r32, 1),
            };
            if solved.is_err() {
                z.copy_from_slice(r);
                return;
            }
            for (z, &v) in z.iter_mut().zip(&r32) {
                *z = f64::from(v) * scale;
            }
        };
        let mut stalled = Vec::new();
        for (j, col) in y.chunks_exact_mut(n).enumerate() {
            let mut x = vec![0.0; n];
            let done = preconditioned_cg(
                col,
                &mut x,
                |v, out| pattern.mul(&self.values, v, out),
                precondition,
                tol,
                max_iter,
            );
            if done.is_some_and(|it| it > REFINE_CHEAP) {
                self.slow_refinement.store(true, Memory::Relaxed);
            }
            if done.is_some() {
                col.copy_from_slice(&x);
            } else {
                stalled.push(j);
            }
        }
        self.refinements
            .fetch_add(applied.load(Memory::Relaxed), Memory::Relaxed);
        if stalled.is_empty() {
            return Ok(());
        }
        let failed = |reason| FlattenError::Solver {
            stage: self.stage,
            reason,
        };
        if let Some(split) = &self.split {
            let mut f = split.empty();
            split.factor::<f64>(&self.values, &mut f).map_err(failed)?;
            for j in stalled {
                self.solve_split(&f, &mut y[j * n..(j + 1) * n], 1)?;
            }
            return Ok(());
        }
        let (Some(lower), Some(symbolic)) = (&self.lower, &self.symbolic) else {
            return Err(FlattenError::Internal(InternalError::NoFactor {
                stage: self.stage,
            }));
        };
        let lower = SparseColMatRef::new(lower.as_ref(), self.values.as_slice());
        let mut l64 = vec![0.0; symbolic.len_val()];
        let mut mem = self
            .buffer(symbolic.factorize_numeric_llt_scratch::<f64>(self.par, Default::default()))?;
        llt(symbolic, lower, &mut l64, self.par, &mut mem).map_err(failed)?;
        for j in stalled {
            self.solve_factored(&l64, &mut y[j * n..(j + 1) * n], 1)?;
        }
        Ok(())
    }
}

/// The factor of a solver's matrix.
#[derive(Debug, Default)]
enum Factor {
    /// None made yet.
    #[default]
    None,
    /// In double precision: solves are two triangular solves.
    Double(Vec<f64>),
    /// In single precision: solves refine its solutions to double precision on the matrix.
    Single(Vec<f32>),
    /// A split system's ([`split`]), in double precision.
    SplitDouble(SplitFactor<f64>),
    /// A split system's, in single precision, refined as [`Factor::Single`].
    SplitSingle(SplitFactor<f32>),
}

/// A single-precision factor, which a refined solve is preconditioned with.
#[derive(Clone, Copy)]
enum Single<'a> {
    Whole(&'a [f32]),
    Split(&'a SplitFactor<f32>),
}

/// `a[k] ← a[perm[k]]` for every k, through `scratch` (as long as `a` once grown). A gather:
/// one scattered read an entry, where following the permutation's cycles in place read and
/// wrote four places at random (a twentieth of a million-face solve's time, for the 8 MB a
/// column saved).
pub(crate) fn permute_in_place<T: Copy>(a: &mut [T], perm: &[Idx], scratch: &mut Vec<T>) {
    scratch.clear();
    scratch.extend(perm.iter().map(|&p| a[p as usize]));
    a.copy_from_slice(scratch);
}

/// faer's numeric Cholesky factorisation of `a` (lower triangle, in `symbolic`'s order) into
/// `l`, in `mem`; the error says why it failed.
pub(crate) fn llt<T: ComplexField>(
    symbolic: &SymbolicCholesky<Idx>,
    a: SparseColMatRef<'_, Idx, T>,
    l: &mut [T],
    par: Par,
    mem: &mut MemBuffer,
) -> Result<(), String> {
    symbolic
        .factorize_numeric_llt::<T>(
            l,
            a,
            Side::Lower,
            LltRegularization::default(),
            par,
            MemStack::new(mem),
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| format!("the system is not positive definite ({e:?})"))
}

/// `out = A v` for the symmetric `A` whose lower triangle is `lower`.
fn lower_mul<I: Index>(lower: SparseColMatRef<'_, I, f64>, v: &[f64], out: &mut [f64]) {
    out.iter_mut().for_each(|o| *o = 0.0);
    for j in 0..lower.ncols() {
        let rows = lower.symbolic().row_idx_of_col_raw(j);
        for (&i, &a) in rows.iter().zip(lower.val_of_col(j)) {
            let i = i.zx();
            out[i] += a * v[j];
            if i != j {
                out[j] += a * v[i];
            }
        }
    }
}

/// A workspace of `size` for a faer call of `stage`, or an out-of-memory solver error.
fn workspace(stage: &'static str, size: StackReq) -> Result<MemBuffer, FlattenError> {
    MemBuffer::try_new(size).map_err(|e| FlattenError::Solver {
        stage,
        reason: format!("out of memory: {e:?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1D Laplacian plus identity on `n` unknowns: SPD, known product.
    fn tridiag(n: usize) -> SymTriplets {
        let mut t = SymTriplets::new(n);
        for i in 0..n {
            t.add(i, i, 3.0);
            if i + 1 < n {
                // Given in the upper triangle on purpose: it must be mirrored.
                t.add(i, i + 1, -1.0);
            }
        }
        // A duplicate that must be summed: diagonal 0 becomes 3.5.
        t.add(0, 0, 0.5);
        t
    }

    #[test]
    fn a_compressed_pattern_sums_duplicates_and_solves_to_the_same_bits() {
        let n = 40;
        let t = tridiag(n);
        let by_triplets = SpdSolver::from_triplets(&t, "test").unwrap();
        let (pattern, values) = SymPattern::compress(t.clone(), "test").unwrap();
        // One value per stored entry: n diagonal entries (the duplicate summed) and n − 1 below.
        assert_eq!(values.len(), 2 * n - 1);
        let (col_ptr, row_idx) = pattern.csc();
        assert_eq!(values[col_ptr[0]], 3.5);
        assert!(row_idx[col_ptr[0]..col_ptr[1]].contains(&1));
        let mut compressed = SpdSolver::new(&pattern, "test").unwrap();
        compressed
            .factor(compressed.gather(&pattern, &values).unwrap())
            .unwrap();
        let rhs: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64).cos()).collect();
        let (mut a, mut b) = (rhs.clone(), rhs);
        by_triplets.solve_in_place(&mut a).unwrap();
        compressed.solve_in_place(&mut b).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn solves_and_refactors_with_the_same_pattern() {
        let n = 50;
        let mut t = tridiag(n);
        let mut s = SpdSolver::from_triplets(&t, "test").unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let pattern = SymPattern::new(&t, "test").unwrap();
        let a = pattern.matrix(t.values(), "test").unwrap();
        let mut b = vec![0.0; n];
        sym_mul(&a, &x_true, &mut b);
        // Check the product against the dense definition.
        for i in 0..n {
            let mut r = 3.0 * x_true[i] + if i == 0 { 0.5 * x_true[0] } else { 0.0 };
            if i > 0 {
                r -= x_true[i - 1];
            }
            if i + 1 < n {
                r -= x_true[i + 1];
            }
            assert!((b[i] - r).abs() < 1e-14);
        }
        s.solve_in_place(&mut b).unwrap();
        for i in 0..n {
            assert!((b[i] - x_true[i]).abs() < 1e-12);
        }
        // New values, same pattern: scale the matrix by 2, the solution halves.
        t.values_mut().iter_mut().for_each(|v| *v *= 2.0);
        s.factor(values_of(&s, &pattern, &t)).unwrap();
        let mut b2 = vec![0.0; 2 * n];
        sym_mul(&a, &x_true, &mut b2[..n]);
        b2[n..].copy_from_slice(&x_true);
        s.solve_many_in_place(&mut b2, 2).unwrap();
        for i in 0..n {
            assert!((b2[i] - 0.5 * x_true[i]).abs() < 1e-12);
        }
    }

    /// The pattern of the triplets `t` with its unknowns grouped into `nodes` nodes by `node_of`.
    pub(super) fn node_pattern(t: &SymTriplets, node_of: Vec<u32>, nodes: usize) -> SymPattern {
        SymPattern::new(t, "test")
            .unwrap()
            .with_nodes(node_of, nodes)
            .unwrap()
    }

    /// The Laplacian-plus-identity of a `w × h` grid of vertices split into triangles along one
    /// diagonal (the 7-point pattern of a triangle mesh), with `k` unknowns per vertex coupled
    /// in full blocks. Unknowns `k·v … k·v + k − 1` belong to vertex `v`.
    pub(super) fn grid_mesh(w: usize, h: usize, k: usize) -> (SymTriplets, Vec<u32>) {
        let nv = w * h;
        let mut t = SymTriplets::new(k * nv);
        let block = |t: &mut SymTriplets, a: usize, b: usize, v: f64| {
            for i in 0..k {
                for j in 0..k {
                    if a != b || i >= j {
                        let off = if i == j { v } else { 0.1 * v };
                        t.add(k * a + i, k * b + j, off);
                    }
                }
            }
        };
        for y in 0..h {
            for x in 0..w {
                let v = y * w + x;
                block(&mut t, v, v, 7.0);
                for (dx, dy) in [(1, 0), (0, 1), (1, 1)] {
                    if x + dx < w && y + dy < h {
                        block(&mut t, v, (y + dy) * w + x + dx, -1.0);
                    }
                }
            }
        }
        let node_of = (0..(k * nv) as u32).map(|i| i / k as u32).collect();
        (t, node_of)
    }

    /// The values of the triplets `t` (of `pattern`) in the order `s` factors them.
    pub(super) fn values_of(s: &SpdSolver, pattern: &SymPattern, t: &SymTriplets) -> Vec<f64> {
        s.gather_matrix(pattern.matrix(t.values(), "test").unwrap().as_ref())
    }

    /// Values of the Cholesky factor of `pattern` in the elimination order `fwd`, made with
    /// `params`.
    fn factor_len(pattern: &SymPattern, fwd: &[usize], params: CholeskySymbolicParams) -> usize {
        let upper = permuted_triangle(pattern, &inverse(fwd), Side::Upper).unwrap();
        factorize_symbolic_cholesky(
            upper.as_ref(),
            Side::Upper,
            SymmetricOrdering::Identity,
            params,
        )
        .unwrap()
        .len_val()
    }

    /// Entries of the Cholesky factor's lower triangle (its exact fill, no supernode padding).
    fn fill(pattern: &SymPattern, ordering: Ordering) -> usize {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold:
                faer::sparse::linalg::SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        factor_len(
            pattern,
            &elimination_order(pattern, ordering).unwrap(),
            params,
        )
    }

    /// The factor of `pattern`'s matrix `t` as faer computes it when handed the matrix in its
    /// own order with the elimination order (faer renumbers it itself).
    fn factored_by_faer(pattern: &SymPattern, t: &SymTriplets, ordering: Ordering) -> Vec<f64> {
        let fwd = elimination_order(pattern, ordering).unwrap();
        let inv = inverse(&fwd);
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv, pattern.n)),
            supernodal(),
        )
        .unwrap();
        let a = pattern.matrix(t.values(), "test").unwrap();
        let mut l = vec![0.0; symbolic.len_val()];
        let mut mem =
            MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(PAR, Default::default()));
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut l,
                a.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                PAR,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .unwrap();
        l
    }

    #[test]
    fn the_matrix_held_in_the_factors_order_factors_to_faers_bits() {
        let (t, node_of) = grid_mesh(70, 60, 2);
        let pattern = node_pattern(&t, node_of, 70 * 60);
        for ordering in [Ordering::Amd, Ordering::NestedDissection] {
            let mut s = SpdSolver::with_ordering(&pattern, "test", ordering).unwrap();
            s.factor(values_of(&s, &pattern, &t)).unwrap();
            let by_faer = factored_by_faer(&pattern, &t, ordering);
            assert_eq!(s.double_factor().len(), by_faer.len(), "{ordering:?}");
            assert!(
                same_bits(s.double_factor(), &by_faer),
                "{ordering:?}: the factors differ"
            );
        }
    }

    #[test]
    fn nested_dissection_is_a_permutation_that_keeps_vertices_together() {
        let (t, node_of) = grid_mesh(60, 50, 2);
        let p = node_pattern(&t, node_of, 3000);
        let (order, _) = p.nested_dissection();
        let mut seen = vec![false; p.n];
        for &i in &order {
            assert!(!seen[i], "unknown {i} twice");
            seen[i] = true;
        }
        assert!(seen.iter().all(|&s| s), "every unknown ordered");
        for pair in order.chunks(2) {
            assert_eq!(pair[0] / 2, pair[1] / 2, "u and v of a vertex are adjacent");
        }
        // Deterministic: the same order on a second run, and on a clone of the pattern.
        assert_eq!(order, p.clone().nested_dissection().0);
    }

    #[test]
    fn nested_dissection_fills_a_grid_mesh_no_more_than_amd() {
        for (w, h, k) in [(400, 400, 1), (500, 400, 2)] {
            let (t, node_of) = grid_mesh(w, h, k);
            let p = node_pattern(&t, node_of, w * h);
            let (nd, amd) = (
                fill(&p, Ordering::NestedDissection),
                fill(&p, Ordering::Amd),
            );
            assert!(nd <= amd, "{w}×{h}×{k}: nested dissection {nd} > AMD {amd}");
        }
    }

    #[test]
    fn nested_dissection_solves_like_amd_and_repeats_its_bits() {
        let (t, node_of) = grid_mesh(80, 70, 2);
        let n = 2 * 80 * 70;
        let pattern = node_pattern(&t, node_of, 80 * 70);
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let a = pattern.matrix(t.values(), "test").unwrap();
        let mut b = vec![0.0; n];
        sym_mul(&a, &x_true, &mut b);
        let solve = |ordering| {
            let mut s = SpdSolver::with_ordering(&pattern, "test", ordering).unwrap();
            s.factor(values_of(&s, &pattern, &t)).unwrap();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            x
        };
        let (nd, amd) = (solve(Ordering::NestedDissection), solve(Ordering::Amd));
        for i in 0..n {
            assert!((nd[i] - x_true[i]).abs() < 1e-12, "ND unknown {i}");
            assert!((nd[i] - amd[i]).abs() < 1e-12, "ND and AMD at {i}");
        }
        let again = solve(Ordering::NestedDissection);
        assert!(same_bits(&nd, &again));
    }

    #[test]
    fn the_parallel_factorisation_gives_the_same_bits() {
        let (w, h) = (160, 120);
        let (t, node_of) = grid_mesh(w, h, 2);
        let pattern = node_pattern(&t, node_of, w * h);
        let solver =
            || SpdSolver::with_ordering(&pattern, "test", Ordering::NestedDissection).unwrap();
        let factor = |threads: usize| {
            let mut s = solver().with_par(Par::rayon(0));
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| s.factor(values_of(&s, &pattern, &t)))
                .unwrap();
            s
        };
        let (one, two) = (factor(1), factor(2));
        assert!(
            same_bits(one.double_factor(), two.double_factor()),
            "the factors differ between one and two threads"
        );
        let mut seq = solver().with_par(Par::Seq);
        seq.factor(values_of(&seq, &pattern, &t)).unwrap();
        let n = 2 * w * h;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
        let (mut x2, mut xs) = (b.clone(), b);
        two.solve_in_place(&mut x2).unwrap();
        seq.solve_in_place(&mut xs).unwrap();
        for i in 0..n {
            assert!(
                (x2[i] - xs[i]).abs() <= 1e-12 * xs[i].abs().max(1.0),
                "unknown {i}"
            );
        }
    }

    #[test]
    fn the_analysis_side_by_side_is_the_analysis_one_triangle_after_the_other() {
        let (w, h) = (90, 70);
        let (t, node_of) = grid_mesh(w, h, 2);
        let pattern = node_pattern(&t, node_of, w * h);
        let after = SpdSolver::new(&pattern, "test").unwrap();
        let ordering = Ordering::for_nodes(pattern.n_nodes());
        let sooner = Analysis::of(&pattern, "test", ordering, Triangles::SideBySide, true).unwrap();
        assert_eq!(after.fwd, sooner.fwd);
        assert_eq!(after.inv, sooner.inv);
        let lower = after.lower.as_ref().unwrap();
        assert_eq!(lower.col_ptr(), sooner.lower.col_ptr());
        assert_eq!(lower.row_idx(), sooner.lower.row_idx());
        assert_eq!(after.factor_len(), sooner.symbolic.len_val());
        // The values made entry by entry are the values gathered from the matrix.
        let a = pattern.matrix(t.values(), "test").unwrap();
        let entry = |i: usize, j: usize| {
            let (r, c) = (i.max(j), i.min(j));
            let rows = a.symbolic().row_idx_of_col_raw(c);
            a.val_of_col(c)[rows.binary_search(&r).unwrap()]
        };
        assert!(same_bits(
            &values_in_order(&sooner.fwd, &sooner.lower, entry),
            &values_of(&after, &pattern, &t)
        ));
    }

    #[test]
    fn a_permutation_in_place_is_the_copying_one_and_its_inverse_undoes_it() {
        // Cycles of lengths 1, 2, 3 and 5 over 11 entries.
        let perm: Vec<Idx> = vec![0, 2, 1, 4, 5, 3, 7, 8, 9, 10, 6];
        let a: Vec<f64> = (0..11).map(|i| i as f64 * 1.5 - 3.0).collect();
        let mut b = a.clone();
        let mut scratch = Vec::new();
        permute_in_place(&mut b, &perm, &mut scratch);
        assert_eq!(
            b,
            vec![-3.0, 0.0, -1.5, 3.0, 4.5, 1.5, 7.5, 9.0, 10.5, 12.0, 6.0]
        );
        let mut inv = vec![0 as Idx; 11];
        for (k, &p) in perm.iter().enumerate() {
            inv[p as usize] = k as Idx;
        }
        permute_in_place(&mut b, &inv, &mut scratch);
        assert_eq!(b, a);
    }

    /// Whether `a` and `b` hold the same bits, pair by pair.
    pub(super) fn same_bits(a: &[f64], b: &[f64]) -> bool {
        a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits())
    }

    /// ‖A x − b‖ and ‖b‖ for the matrix of `t`.
    pub(super) fn residual(
        pattern: &SymPattern,
        t: &SymTriplets,
        x: &[f64],
        b: &[f64],
    ) -> (f64, f64) {
        let a = pattern.matrix(t.values(), "test").unwrap();
        let mut r = vec![0.0; b.len()];
        sym_mul(&a, x, &mut r);
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|e| e * e).sum::<f64>().sqrt();
        (
            norm(&mut r.iter().zip(b).map(|(p, q)| p - q)),
            norm(&mut b.iter().copied()),
        )
    }

    /// Solves of `t`'s system for `b` by a double-precision solver and by one forced to single
    /// precision (nested dissection, as large maps are ordered).
    fn single_and_double(
        pattern: &SymPattern,
        t: &SymTriplets,
        b: &[f64],
    ) -> (SpdSolver, Vec<f64>, Vec<f64>) {
        let solve = |single: bool| {
            let s = SpdSolver::with_ordering(pattern, "test", Ordering::NestedDissection).unwrap();
            let mut s = if single { s.single() } else { s };
            s.factor(values_of(&s, pattern, t)).unwrap();
            let mut x = b.to_vec();
            s.solve_in_place(&mut x).unwrap();
            (s, x)
        };
        let (_, xd) = solve(false);
        let (single, xs) = solve(true);
        (single, xs, xd)
    }

    #[test]
    fn a_single_precision_factor_solves_to_double_precision() {
        let (w, h) = (60, 50);
        let (mut t, node_of) = grid_mesh(w, h, 2);
        // A weaker diagonal, so the system is less well conditioned than the grid's own.
        t.values_mut().iter_mut().for_each(|v| *v *= 1.0 + 1e-3);
        let pattern = node_pattern(&t, node_of, w * h);
        let n = 2 * w * h;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 0.3).collect();
        let (single, xs, xd) = single_and_double(&pattern, &t, &b);
        assert!(
            single.double_factor().is_empty(),
            "the factor is single precision"
        );
        let (res, nb) = residual(&pattern, &t, &xs, &b);
        assert!(res <= REFINE_TOL * nb, "residual {res}");
        let scale = xd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            assert!(
                (xs[i] - xd[i]).abs() <= 1e-10 * scale,
                "unknown {i}: {} vs {}",
                xs[i],
                xd[i]
            );
        }
        // The same bits again.
        let (_, again, _) = single_and_double(&pattern, &t, &b);
        assert!(same_bits(&xs, &again));
    }

    #[test]
    fn a_system_single_precision_cannot_factor_is_factored_in_double() {
        // [[1, 1 − 1e-9], [1 − 1e-9, 1]] is positive definite; rounded to f32 it is singular.
        let mut t = SymTriplets::new(2);
        t.add(0, 0, 1.0);
        t.add(1, 0, 1.0 - 1e-9);
        t.add(1, 1, 1.0);
        let pattern = SymPattern::new(&t, "test").unwrap();
        let mut s = SpdSolver::new(&pattern, "test").unwrap().single();
        s.factor(values_of(&s, &pattern, &t)).unwrap();
        assert!(
            !s.double_factor().is_empty(),
            "factored in double precision"
        );
        // A (1, −1) = 1e-9 (1, −1).
        let mut x = vec![1e-9, -1e-9];
        s.solve_in_place(&mut x).unwrap();
        assert!(
            (x[0] - 1.0).abs() < 1e-6 && (x[1] + 1.0).abs() < 1e-6,
            "{x:?}"
        );
    }

    #[test]
    fn a_refinement_that_stalls_is_solved_with_a_double_factor() {
        let t = tridiag(30);
        let pattern = SymPattern::new(&t, "test").unwrap();
        let mut single = SpdSolver::new(&pattern, "test").unwrap().single();
        let mut double = SpdSolver::new(&pattern, "test").unwrap();
        single.factor(values_of(&single, &pattern, &t)).unwrap();
        double.factor(values_of(&double, &pattern, &t)).unwrap();
        let b: Vec<f64> = (0..30).map(|i| (i as f64).cos()).collect();
        let mut want = b.clone();
        double.solve_in_place(&mut want).unwrap();
        let Factor::Single(l) = &single.factor else {
            panic!("not single precision");
        };
        let l = Single::Whole(l);
        // No iteration allowed: the column stalls and is solved directly (in the factor's
        // order, as the solver holds it).
        let mut y: Vec<f64> = single.fwd.iter().map(|&i| b[i as usize]).collect();
        single.solve_refined(l, &mut y, REFINE_TOL, 0).unwrap();
        for (k, &i) in single.fwd.iter().enumerate() {
            assert_eq!(y[k].to_bits(), want[i as usize].to_bits(), "unknown {i}");
        }
    }

    #[test]
    fn a_solver_whose_refinement_is_slow_factors_in_double_precision_after_it() {
        // A 1D Laplacian with a small shift: κ ≈ 1e6, so the single-precision factor is a
        // loose preconditioner and the refinement to 1e-12 takes several steps.
        let n = 2000;
        let mut t = SymTriplets::new(n);
        for i in 0..n {
            t.add(i, i, 2.0 + 1e-6);
            if i + 1 < n {
                t.add(i + 1, i, -1.0);
            }
        }
        let pattern = SymPattern::new(&t, "test").unwrap();
        let mut s = SpdSolver::new(&pattern, "test").unwrap().single();
        s.factor(values_of(&s, &pattern, &t)).unwrap();
        assert!(s.double_factor().is_empty());
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.01).sin()).collect();
        let mut x = b.clone();
        s.solve_in_place(&mut x).unwrap();
        let (res, nb) = residual(&pattern, &t, &x, &b);
        assert!(
            s.slow_refinement.load(Memory::Relaxed),
            "the refinement was slow"
        );
        s.refactor().unwrap();
        assert!(
            !s.double_factor().is_empty(),
            "refactored in double precision"
        );
        let mut y = b.clone();
        s.solve_in_place(&mut y).unwrap();
        let (res_double, _) = residual(&pattern, &t, &y, &b);
        // As accurate as the double-precision solve (whose residual, κ ≈ 1e6, is above 1e-12).
        assert!(
            res <= (REFINE_TOL * nb).max(10.0 * res_double),
            "{res} against {res_double}"
        );
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            assert!((x[i] - y[i]).abs() <= 1e-9 * scale, "unknown {i}");
        }
    }

    #[test]
    fn indefinite_and_non_finite_are_solver_errors() {
        let mut t = SymTriplets::new(2);
        t.add(0, 0, 1.0);
        t.add(1, 1, -1.0);
        assert!(matches!(
            SpdSolver::from_triplets(&t, "test"),
            Err(FlattenError::Solver { stage: "test", .. })
        ));
        let mut t = SymTriplets::new(2);
        t.add(0, 0, 1.0);
        t.add(1, 1, f64::NAN);
        assert!(matches!(
            SpdSolver::from_triplets(&t, "test"),
            Err(FlattenError::Solver { .. })
        ));
    }

    #[test]
    fn solve_before_factor_and_bad_length_are_errors() {
        let t = tridiag(4);
        let s = SpdSolver::new(&SymPattern::new(&t, "test").unwrap(), "test").unwrap();
        assert!(s.solve_in_place(&mut [0.0; 4]).is_err());
        let s = SpdSolver::from_triplets(&t, "test").unwrap();
        assert!(s.solve_in_place(&mut [0.0; 3]).is_err());
    }
}
