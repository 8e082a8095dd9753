//! The factorisation of a large SPD system split in two at the top separator of its nested
//! dissection, each half factored and solved on a thread of its own.
//!
//! In the nested-dissection order the unknowns come as `[A, B, S]`: the two halves, which no
//! entry couples, then the top separator. With `K` in that order,
//!
//! ```text
//!     K = [[K_AA, 0,    K_AS],
//!          [0,    K_BB, K_BS],
//!          [K_SA, K_SB, K_SS]],
//! ```
//!
//! each half `H` is factored apart, bordered by the separator with `K_SS` in its corner:
//! `[[K_HH, K_HS], [K_SH, K_SS]] = L_H L_Hᵀ`, faer's supernodal factorisation of the half's
//! pattern. The corner of that factor, `L_SH`'s lower block `C_H` (`C_H C_Hᵀ = K_SS −
//! K_SH K_HH⁻¹ K_HS`), gives the half's contribution to the separator's Schur complement, and the
//! complement is
//!
//! ```text
//!     Σ = K_SS − K_SA K_AA⁻¹ K_AS − K_SB K_BB⁻¹ K_BS = C_A C_Aᵀ + C_B C_Bᵀ − K_SS,
//! ```
//!
//! a dense matrix of the separator's size, factored densely (`Σ = G Gᵀ`). It is made in the
//! factors' own storage: each corner's product goes into the other corner's unused upper
//! triangle (its rows in two fixed blocks beside each other), their sum over `C_A`, and `G` stays
//! there. A half's substitutions only pass through its corner and back (`t_H` is multiplied
//! back by what they divided it by), so any invertible lower triangle serves there, `G` as well
//! as `C_A`. The corner is positive
//! definite whenever `K` is (`K_SS − K_SH K_HH⁻¹ K_HS ≥ Σ > 0`), and `Σ` comes out of it with the
//! cancellation of the whole factorisation, which subtracts the same products from `K_SS`. A
//! solve is a forward substitution in each half (the separator's right-hand side zero: its
//! result `t_H` gives `K_SH K_HH⁻¹`-weighted `−C_H t_H`), the separator's dense solve, and a back
//! substitution in each half from `C_Hᵀ x_S`.
//!
//! The two halves' factorisations and substitutions are independent and sequential (faer's
//! [`super::PAR`]), and their results are summed in one fixed order, so the solution is the same
//! bits with any number of threads; only the separator's work (two triangle products, one dense
//! factorisation) is extra, and waits for both halves.
//!
//! Memory: the whole factor is never analysed (its symbolic factor would hold as much as the
//! halves' together); the matrix's pattern is kept only as the halves' bordered patterns, which
//! the solver's slots and its refinement's products read; each half's factor holds the
//! separator's corner, so the two hold one `s × s` block more than the whole factor (11 MB in
//! single precision at a million faces), and `Σ` takes none.

use std::ops::Range;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::matmul::triangular::BlockStructure;
use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::traits::ComplexField;
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par, Side};

use super::{Idx, PAR, llt, supernodal};
use crate::beside::beside;

/// Unknowns from which a system ordered by nested dissection (from
/// [`super::NESTED_DISSECTION_FROM`] vertices) is factored in two halves beside each other.
/// Measured through the CLI (see [`super::PAR`]): a million-face isometric map (a million
/// unknowns) gains 2 s of its factorisations; a 330k-face one (332k unknowns) gained nothing at
/// load 4.4 and held 30 MB more, its factor double precision (below
/// [`super::SINGLE_PRECISION_FROM`] values), whose halves copy their part of the matrix.
/// Between them, this is about the size from which the Newton factor is single precision.
/// Smaller systems (a split map's pieces among them) and AMD-ordered ones keep the whole
/// factorisation.
pub const SPLIT_FROM: usize = 600_000;

/// Least share of the unknowns before the separator that the smaller half must hold: below it
/// the larger half's thread is most of the time, and the separator's work is not paid back.
const MIN_HALF: f64 = 0.25;

/// Most unknowns of the separator: its Schur complement is a dense matrix of `8 s²` bytes
/// (32 MB at 2000), factored at `s³ / 3` flops on one thread, and each half's corner the same.
const MAX_SEPARATOR: usize = 2000;

/// The precisions a split factor is made in: the solver's values are converted into it.
pub(crate) trait Precision: ComplexField + Copy + Default + Send + Sync {
    fn of(v: f64) -> Self;
    fn wide(self) -> f64;
}

impl Precision for f64 {
    fn of(v: f64) -> Self {
        v
    }
    fn wide(self) -> f64 {
        self
    }
}

impl Precision for f32 {
    fn of(v: f64) -> Self {
        v as f32
    }
    fn wide(self) -> f64 {
        f64::from(self)
    }
}

/// The analysis of a system split at its top separator: the two bordered halves' patterns and
/// faer's symbolic factors of them.
#[derive(Debug)]
pub(crate) struct Split {
    /// The first unknown (in the factor's order) of the separator, and the number of unknowns.
    sep: usize,
    n: usize,
    /// The values of the separator's columns in the whole matrix's lower triangle.
    sep_values: Range<usize>,
    halves: [Half; 2],
}

/// One half bordered by the separator: its unknowns first, the separator's after them.
#[derive(Debug)]
struct Half {
    /// Its own unknowns, in the whole factor's order.
    interior: Range<usize>,
    /// The values of its columns in the whole matrix's lower triangle.
    values: Range<usize>,
    /// The pattern of its bordered matrix's lower triangle, and faer's analysis of it.
    lower: SymbolicSparseColMat<Idx>,
    symbolic: SymbolicCholesky<Idx>,
}

/// The factor of a split system in the precision `T`: each half's, and the separator's Schur
/// complement's (double precision, dense, lower triangle).
#[derive(Debug)]
pub(crate) struct SplitFactor<T> {
    halves: [HalfFactor<T>; 2],
    /// The complement's factor `G`, when it is not in place of the first half's corner
    /// ([`Split::factor`]).
    schur: Option<Mat<T>>,
}

/// A half's factor, and the workspace of its factorisation, kept between factorisations (the
/// same size every time: allocated and paged in once).
struct HalfFactor<T> {
    l: Vec<T>,
    mem: Option<MemBuffer>,
}

impl<T> std::fmt::Debug for HalfFactor<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "HalfFactor({} values)", self.l.len())
    }
}

impl Split {
    /// The split of the system whose lower triangle (in the factor's order) is `lower` at the
    /// separator that starts at unknown `sep` (the last block of a nested dissection); `None`
    /// when the unknowns before it do not fall in two uncoupled halves of [`MIN_HALF`], or the
    /// separator is larger than [`MAX_SEPARATOR`]. The error is faer's analysis's.
    pub(crate) fn of(
        lower: &SymbolicSparseColMat<Idx>,
        sep: usize,
    ) -> Result<Option<Self>, String> {
        let n = lower.nrows();
        if sep == 0 || sep >= n || n - sep > MAX_SEPARATOR {
            return Ok(None);
        }
        let Some(mid) = halves_boundary(lower, sep) else {
            return Ok(None);
        };
        let col_ptr = lower.col_ptr();
        let at = |c: usize| col_ptr[c] as usize;
        let half = |interior: Range<usize>| -> Result<Half, String> {
            let values = at(interior.start)..at(interior.end);
            let pattern = bordered(lower, interior.clone(), sep);
            let symbolic = analyse(&pattern)?;
            if !matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
                return Err("the half's factor is not supernodal".into());
            }
            Ok(Half {
                interior,
                values,
                lower: pattern,
                symbolic,
            })
        };
        Ok(Some(Self {
            sep,
            n,
            sep_values: at(sep)..at(n),
            halves: [half(0..mid)?, half(mid..sep)?],
        }))
    }

    /// The slot (the index in the whole matrix's values, its lower triangle in the factor's
    /// order) of the entry in row `row` and column `col`, `row ≥ col`, found in the bordered
    /// half that holds its column (the separator's: the first half's); `None` if it is not in
    /// the pattern.
    pub(crate) fn slot(&self, row: usize, col: usize) -> Option<usize> {
        if row >= self.n || col > row {
            return None;
        }
        let (a, b) = (&self.halves[0], &self.halves[1]);
        let mid = b.interior.start;
        let (h, c, r, base) = if col < mid {
            let r = match row {
                r if r < mid => r,
                r if r >= self.sep => r - self.sep + mid,
                _ => return None,
            };
            (a, col, r, 0)
        } else if col < self.sep {
            (b, col - mid, row - mid, b.values.start)
        } else {
            let base = self.sep_values.start - a.lower.col_ptr()[mid] as usize;
            (a, col - self.sep + mid, row - self.sep + mid, base)
        };
        let (ptr, rows) = (h.lower.col_ptr(), h.lower.row_idx());
        let start = ptr[c] as usize;
        rows[start..ptr[c + 1] as usize]
            .binary_search(&(r as Idx))
            .ok()
            .map(|k| base + start + k)
    }

    /// Entries of the whole matrix's lower triangle.
    pub(crate) fn n_values(&self) -> usize {
        self.sep_values.end
    }

    /// `out = A v` for the symmetric `A` whose lower triangle (in the factor's order) has
    /// `values`: the whole matrix's columns in order, read from the halves' patterns.
    pub(crate) fn lower_mul(&self, values: &[f64], v: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let (a, b) = (&self.halves[0], &self.halves[1]);
        let (mid, sep) = (b.interior.start, self.sep);
        let a_row = |r: usize| if r < mid { r } else { r - mid + sep };
        let b_row = |r: usize| r + mid;
        let s_base = self.sep_values.start - a.lower.col_ptr()[mid] as usize;
        // (half, its columns, the first whole column, its base slot, whole row of a half row)
        let parts: [(&Half, Range<usize>, usize, usize, &dyn Fn(usize) -> usize); 3] = [
            (a, 0..mid, 0, 0, &a_row),
            (b, 0..sep - mid, mid, b.values.start, &b_row),
            (a, mid..mid + self.n_sep(), sep, s_base, &a_row),
        ];
        for (h, cols, first, base, row_of) in parts {
            let (ptr, rows) = (h.lower.col_ptr(), h.lower.row_idx());
            for (c, j) in cols.clone().zip(first..) {
                for k in ptr[c] as usize..ptr[c + 1] as usize {
                    let (i, x) = (row_of(rows[k] as usize), values[base + k]);
                    out[i] += x * v[j];
                    if i != j {
                        out[j] += x * v[i];
                    }
                }
            }
        }
    }

    /// Values of the two halves' factors together.
    pub(crate) fn len_val(&self) -> usize {
        self.halves.iter().map(|h| h.symbolic.len_val()).sum()
    }

    /// Unknowns of the separator.
    fn n_sep(&self) -> usize {
        self.n - self.sep
    }

    /// An empty factor, to be made by [`Split::factor`].
    pub(crate) fn empty<T: Precision>(&self) -> SplitFactor<T> {
        let half = || HalfFactor {
            l: Vec::new(),
            mem: None,
        };
        SplitFactor {
            halves: [half(), half()],
            schur: None,
        }
    }

    /// Factors the matrix whose lower triangle (in the factor's order) has `values` into `f`
    /// (its storage reused), in the precision `T`: the two halves beside each other, then the
    /// separator's complement. The error says why it failed (not positive definite).
    pub(crate) fn factor<T: Precision>(
        &self,
        values: &[f64],
        f: &mut SplitFactor<T>,
    ) -> Result<(), String> {
        let SplitFactor {
            halves: [fa, fb],
            schur,
        } = f;
        let (ha, hb) = (&self.halves[0], &self.halves[1]);
        let (ra, rb) = beside(
            || self.factor_half(ha, values, fa),
            || self.factor_half(hb, values, fb),
        );
        ra?;
        rb?;
        let s = self.n_sep();
        // Σ in the first half's corner when one supernode holds each corner (the top separator
        // is one): C_A C_Aᵀ made into the second corner's unused upper triangle, C_B C_Bᵀ into
        // the first's, and their sum over C_A, which is then no longer needed.
        let in_place = corner_block(ha, &fa.l).is_some() && corner_block(hb, &fb.l).is_some();
        let mut sigma = if in_place {
            *schur = None;
            let (Some(ca), Some(b_mut)) =
                (corner_block(ha, &fa.l), corner_block_mut(hb, &mut fb.l))
            else {
                return Err("the first half's corner is not one block".into());
            };
            let da = lower_product(b_mut.transpose_mut(), ca, Accum::Replace, true);
            let (Some(cb), Some(a_mut)) =
                (corner_block(hb, &fb.l), corner_block_mut(ha, &mut fa.l))
            else {
                return Err("the second half's corner is not one block".into());
            };
            let db = lower_product(a_mut.transpose_mut(), cb, Accum::Replace, true);
            let (Some(b), Some(mut a)) = (corner_block(hb, &fb.l), corner_block_mut(ha, &mut fa.l))
            else {
                return Err("the halves' corners are not blocks".into());
            };
            for j in 0..s {
                a[(j, j)] = T::of(da[j] + db[j]);
                for i in j + 1..s {
                    a[(i, j)] = T::of(b[(j, i)].wide() + a[(j, i)].wide());
                }
            }
            a
        } else {
            // The corners copied out of the supernodes that hold them, Σ a matrix of its own.
            let (ca, cb) = (corner_copy(ha, &fa.l, s), corner_copy(hb, &fb.l, s));
            let m = schur.get_or_insert_with(|| Mat::zeros(s, s));
            if m.nrows() != s {
                *m = Mat::zeros(s, s);
            }
            lower_product(m.as_mut(), ca.as_ref(), Accum::Replace, false);
            lower_product(m.as_mut(), cb.as_ref(), Accum::Add, false);
            m.as_mut()
        };
        // Σ = C_A C_Aᵀ + C_B C_Bᵀ − K_SS: K_SS's entries, the separator's columns of half A's
        // bordered pattern.
        let lower = &ha.lower;
        let first = lower.ncols() - s;
        let (rows, ptr) = (lower.row_idx(), lower.col_ptr());
        let k_ss = &values[self.sep_values.clone()];
        let base = ptr[first] as usize;
        for j in 0..s {
            for k in ptr[first + j] as usize..ptr[first + j + 1] as usize {
                let i = rows[k] as usize - first;
                sigma[(i, j)] = T::of(sigma[(i, j)].wide() - k_ss[k - base]);
            }
        }
        let mut mem = MemBuffer::try_new(
            faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<T>(
                s,
                Par::Seq,
                Default::default(),
            ),
        )
        .map_err(|e| format!("out of memory: {e:?}"))?;
        faer::linalg::cholesky::llt::factor::cholesky_in_place(
            sigma,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| {
            format!("the system is not positive definite (its separator's complement: {e:?})")
        })?;
        Ok(())
    }

    /// Factors half `h` bordered by `K_SS` into `f`.
    fn factor_half<T: Precision>(
        &self,
        h: &Half,
        values: &[f64],
        f: &mut HalfFactor<T>,
    ) -> Result<(), String> {
        let HalfFactor { l, mem } = f;
        // The half's columns, then the separator's: in the whole matrix's values the other
        // half's lie between them.
        let a: Vec<T> = values[h.values.clone()]
            .iter()
            .chain(&values[self.sep_values.clone()])
            .map(|&v| T::of(v))
            .collect();
        let size = h.symbolic.len_val();
        if l.len() != size {
            *l = Vec::new();
            *l = vec![T::default(); size];
        }
        if mem.is_none() {
            *mem = Some(
                MemBuffer::try_new(
                    h.symbolic
                        .factorize_numeric_llt_scratch::<T>(PAR, Default::default()),
                )
                .map_err(|e| format!("out of memory: {e:?}"))?,
            );
        }
        let Some(mem) = mem.as_mut() else {
            return Err("no workspace".into());
        };
        llt(
            &h.symbolic,
            SparseColMatRef::new(h.lower.as_ref(), &a),
            l,
            PAR,
            mem,
        )
    }
    /// Solves in place, in the factor's order, for the `k` columns of `y` with the factor `f`:
    /// the halves' substitutions beside each other, the separator's between them in double
    /// precision. The error is an allocation's.
    pub(crate) fn solve<T: Precision>(
        &self,
        f: &SplitFactor<T>,
        y: &mut [T],
        k: usize,
    ) -> Result<(), String> {
        let s = self.n_sep();
        let g = match &f.schur {
            Some(m) => m.as_ref(),
            None => corner_block(&self.halves[0], &f.halves[0].l)
                .ok_or("the complement's factor is not in the first half's corner")?,
        };
        for col in y.chunks_exact_mut(self.n).take(k) {
            let (a, rest) = col.split_at_mut(self.halves[1].interior.start);
            let (b, ys) = rest.split_at_mut(self.sep - self.halves[1].interior.start);
            let (fa, fb) = beside(
                || self.forward(&self.halves[0], &f.halves[0].l, a),
                || self.forward(&self.halves[1], &f.halves[1].l, b),
            );
            let ((mut za, wa), (mut zb, wb)) = (fa?, fb?);
            // K_SS-side right-hand side less both halves' parts, in this order.
            let mut xs = Mat::<T>::zeros(s, 1);
            for i in 0..s {
                xs[(i, 0)] = T::of(ys[i].wide() + wa[i] + wb[i]);
            }
            faer::linalg::cholesky::llt::solve::solve_in_place_with_conj(
                g,
                Conj::No,
                xs.as_mut(),
                Par::Seq,
                MemStack::new(&mut MemBuffer::new(faer::dyn_stack::StackReq::EMPTY)),
            );
            let xs: Vec<f64> = (0..s).map(|i| xs[(i, 0)].wide()).collect();
            let (ba, bb) = beside(
                || self.backward(&self.halves[0], &f.halves[0].l, &mut za, &xs, a),
                || self.backward(&self.halves[1], &f.halves[1].l, &mut zb, &xs, b),
            );
            ba?;
            bb?;
            for (y, &x) in ys.iter_mut().zip(&xs) {
                *y = T::of(x);
            }
        }
        Ok(())
    }

    /// The forward substitution of half `h` (factor `l`) for its part `y` of a right-hand side,
    /// the separator's part zero: the bordered solution (kept for [`Split::backward`]) and
    /// `C_H t_H`, its separator part `t_H` multiplied back (`−K_SH K_HH⁻¹ y`).
    fn forward<T: Precision>(
        &self,
        h: &Half,
        l: &[T],
        y: &[T],
    ) -> Result<(Vec<T>, Vec<f64>), String> {
        let len = h.interior.len();
        let mut z = Vec::with_capacity(len + self.n_sep());
        z.extend_from_slice(y);
        z.resize(len + self.n_sep(), T::default());
        let sym = supernodal_of(h)?;
        let mut mem = MemBuffer::try_new(sym.solve_in_place_scratch::<T>(1, PAR))
            .map_err(|e| format!("out of memory: {e:?}"))?;
        SupernodalLltRef::new(sym, l).l_solve_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut z, len + self.n_sep(), 1),
            PAR,
            MemStack::new(&mut mem),
        );
        let mut w = vec![0.0; self.n_sep()];
        corner_entries(h, l, |i, j, v| w[i] += v * z[len + j].wide());
        Ok((z, w))
    }

    /// The back substitution of half `h` (factor `l`) from its forward solution `z`, the
    /// separator's part set to `C_Hᵀ x_S`: its part `y` of the solution.
    fn backward<T: Precision>(
        &self,
        h: &Half,
        l: &[T],
        z: &mut [T],
        xs: &[f64],
        y: &mut [T],
    ) -> Result<(), String> {
        let len = h.interior.len();
        let mut u = vec![0.0; self.n_sep()];
        corner_entries(h, l, |i, j, v| u[j] += v * xs[i]);
        for (z, u) in z[len..].iter_mut().zip(u) {
            *z = T::of(u);
        }
        let sym = supernodal_of(h)?;
        let mut mem = MemBuffer::try_new(sym.solve_in_place_scratch::<T>(1, PAR))
            .map_err(|e| format!("out of memory: {e:?}"))?;
        SupernodalLltRef::new(sym, l).l_transpose_solve_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(z, len + self.n_sep(), 1),
            PAR,
            MemStack::new(&mut mem),
        );
        y.copy_from_slice(&z[..len]);
        Ok(())
    }
}

/// faer's supernodal analysis of half `h` (it is always supernodal, [`Split::of`]).
fn supernodal_of(h: &Half) -> Result<&SymbolicSupernodalCholesky<Idx>, String> {
    match h.symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => Ok(s),
        SymbolicCholeskyRaw::Simplicial(_) => Err("the half's factor is not supernodal".into()),
    }
}

/// The corner `C_H` of half `h`'s factor `l` as a view of it, when its last supernode holds
/// every separator column (and so the corner whole, rows and columns).
fn corner_block<'a, T: Precision>(h: &'a Half, l: &'a [T]) -> Option<MatRef<'a, T>> {
    let SymbolicCholeskyRaw::Supernodal(sym) = h.symbolic.raw() else {
        return None;
    };
    let len = h.interior.len();
    let last = sym.n_supernodes().checked_sub(1)?;
    let node = SupernodalLltRef::new(sym, l).supernode(last);
    let start = node.start();
    (start <= len && node.pattern().is_empty()).then(|| {
        let off = len - start;
        node.val()
            .submatrix(off, off, node.val().ncols() - off, node.val().ncols() - off)
    })
}

/// Calls `f(i, j, v)` for every entry `v` of the corner `C_H` of half `h`'s factor `l` (the
/// separator's rows and columns, lower triangle, `i ≥ j` counted from the separator's first
/// unknown), column by column.
fn corner_entries<T: Precision>(h: &Half, l: &[T], mut f: impl FnMut(usize, usize, f64)) {
    let SymbolicCholeskyRaw::Supernodal(sym) = h.symbolic.raw() else {
        return;
    };
    let len = h.interior.len();
    let factor = SupernodalLltRef::new(sym, l);
    let begin = sym.supernode_begin();
    // The first supernode holding a separator column: supernodes may straddle the border.
    let first = begin
        .partition_point(|&b| (b as usize) <= len)
        .saturating_sub(1);
    for s in first..sym.n_supernodes() {
        let node = factor.supernode(s);
        let m = node.val();
        let start = node.start();
        let ncols = m.ncols();
        for jj in len.saturating_sub(start)..ncols {
            let j = start + jj - len;
            for ii in jj..ncols {
                f(start + ii - len, j, m[(ii, jj)].wide());
            }
            for (p, &row) in node.pattern().iter().enumerate() {
                f(row as usize - len, j, m[(ncols + p, jj)].wide());
            }
        }
    }
}

/// The corner `C_H` of half `h`'s factor `l` copied out of the supernodes that hold it (an
/// `s × s` lower triangle), when no one supernode holds it whole ([`corner_block`]).
fn corner_copy<T: Precision>(h: &Half, l: &[T], s: usize) -> Mat<T> {
    let mut c = Mat::<T>::zeros(s, s);
    corner_entries(h, l, |i, j, v| c[(i, j)] = T::of(v));
    c
}

/// Fraction of the separator's rows whose part of the complement's product is made on one
/// thread, the rest on the other: the first `r` rows' lower triangle costs `r³ / 3` flops, the
/// rest `(s³ − r³) / 3`, equal at `r = s / ∛2`.
const TOP_ROWS: f64 = 0.7937;

/// `dst ← C Cᵀ` (or `dst += C Cᵀ`, as `accum` says), its lower triangle, strictly lower when
/// `strict`, for `C` lower triangular: the rows of `dst` in two fixed blocks ([`TOP_ROWS`])
/// beside each other, each the same sums whatever thread makes it. With `strict`, the diagonal
/// it leaves is returned (`Σ_k c_ik²`, in double precision), else nothing.
fn lower_product<T: Precision>(
    dst: MatMut<'_, T>,
    c: MatRef<'_, T>,
    accum: Accum,
    strict: bool,
) -> Vec<f64> {
    use BlockStructure::{Rectangular, StrictTriangularLower, TriangularLower, TriangularUpper};
    let s = dst.nrows();
    let r = ((s as f64 * TOP_ROWS).round() as usize).min(s);
    let out = if strict {
        StrictTriangularLower
    } else {
        TriangularLower
    };
    let (top, bottom) = dst.split_at_row_mut(r);
    let product = |dst: MatMut<'_, T>,
                   dst_s: BlockStructure,
                   lhs: MatRef<'_, T>,
                   lhs_s: BlockStructure,
                   rhs: MatRef<'_, T>,
                   rhs_s: BlockStructure,
                   accum: Accum| {
        faer::linalg::matmul::triangular::matmul(
            dst,
            dst_s,
            accum,
            lhs,
            lhs_s,
            rhs,
            rhs_s,
            T::of(1.0),
            Par::Seq,
        );
    };
    beside(
        || {
            // Rows 0..r, columns 0..r: C[..r, ..r] C[..r, ..r]ᵀ.
            let c = c.submatrix(0, 0, r, r);
            product(
                top.submatrix_mut(0, 0, r, r),
                out,
                c,
                TriangularLower,
                c.transpose(),
                TriangularUpper,
                accum,
            );
        },
        || {
            // Rows r..s: columns 0..r are C[r.., ..r] C[..r, ..r]ᵀ, columns r..s the lower
            // triangle of C[r.., ..r] C[r.., ..r]ᵀ + C[r.., r..] C[r.., r..]ᵀ.
            let (left, mut right) = bottom.split_at_col_mut(r);
            let m = s - r;
            let (c_top, c_left, c_corner) = (
                c.submatrix(0, 0, r, r),
                c.submatrix(r, 0, m, r),
                c.submatrix(r, r, m, m),
            );
            product(
                left,
                Rectangular,
                c_left,
                Rectangular,
                c_top.transpose(),
                TriangularUpper,
                accum,
            );
            product(
                right.rb_mut(),
                out,
                c_left,
                Rectangular,
                c_left.transpose(),
                Rectangular,
                accum,
            );
            product(
                right,
                out,
                c_corner,
                TriangularLower,
                c_corner.transpose(),
                TriangularUpper,
                Accum::Add,
            );
        },
    );
    if !strict {
        return Vec::new();
    }
    (0..s)
        .map(|i| (0..=i).map(|k| c[(i, k)].wide() * c[(i, k)].wide()).sum())
        .collect()
}

/// The corner of half `h`'s factor `l` as [`corner_block`] finds it, to be written.
fn corner_block_mut<'a, T: Precision>(h: &Half, l: &'a mut [T]) -> Option<MatMut<'a, T>> {
    let SymbolicCholeskyRaw::Supernodal(sym) = h.symbolic.raw() else {
        return None;
    };
    let len = h.interior.len();
    let last = sym.n_supernodes().checked_sub(1)?;
    let start = sym.supernode_begin()[last] as usize;
    let ncols = sym.supernode_end()[last] as usize - start;
    let vals = sym.col_ptr_for_val()[last] as usize..sym.col_ptr_for_val()[last + 1] as usize;
    // No rows below its columns: its values are a square block.
    if start > len || vals.len() != ncols * ncols {
        return None;
    }
    let off = len - start;
    let m = MatMut::from_column_major_slice_mut(&mut l[vals], ncols, ncols);
    Some(m.submatrix_mut(off, off, ncols - off, ncols - off))
}

/// faer's symbolic (supernodal, amalgamated) factorisation of the matrix whose lower triangle
/// (in the factor's order) is `lower`.
pub(super) fn analyse(lower: &SymbolicSparseColMat<Idx>) -> Result<SymbolicCholesky<Idx>, String> {
    // faer's analysis without an ordering reads the upper triangle.
    factorize_symbolic_cholesky(
        transposed(lower).as_ref(),
        Side::Upper,
        SymmetricOrdering::Identity,
        supernodal(),
    )
    .map_err(|e| format!("{e:?}"))
}

/// The boundary `mid` between the two halves of the unknowns before the separator `sep`: no
/// entry of `lower` couples an unknown before it with one from it to the separator. The most
/// balanced one, or `None` if even that leaves a half under [`MIN_HALF`].
fn halves_boundary(lower: &SymbolicSparseColMat<Idx>, sep: usize) -> Option<usize> {
    let (col_ptr, rows) = (lower.col_ptr(), lower.row_idx());
    // The farthest row (before the separator) reached by the columns so far.
    let mut reach = 0usize;
    let mut best: Option<usize> = None;
    for c in 0..sep {
        let col = &rows[col_ptr[c] as usize..col_ptr[c + 1] as usize];
        let before = col.partition_point(|&r| (r as usize) < sep);
        if let Some(&r) = col[..before].last() {
            reach = reach.max(r as usize);
        }
        reach = reach.max(c);
        // Columns 0..=c reach no row past c: a boundary at c + 1.
        let mid = c + 1;
        if reach < mid && mid < sep {
            let off = |m: usize| m.abs_diff(sep - m);
            if best.is_none_or(|b| off(mid) < off(b)) {
                best = Some(mid);
            }
        }
    }
    let mid = best?;
    let least = (MIN_HALF * sep as f64).ceil() as usize;
    (mid.min(sep - mid) >= least).then_some(mid)
}

/// The lower triangle of the matrix of `interior` bordered by the separator (from `sep` to the
/// end), renumbered: the interior's unknowns first, then the separator's.
fn bordered(
    lower: &SymbolicSparseColMat<Idx>,
    interior: Range<usize>,
    sep: usize,
) -> SymbolicSparseColMat<Idx> {
    let n = lower.nrows();
    let len = interior.len();
    let (col_ptr, rows) = (lower.col_ptr(), lower.row_idx());
    let renumber = |r: usize| {
        if r >= sep {
            r - sep + len
        } else {
            r - interior.start
        }
    };
    let cols = interior.clone().chain(sep..n);
    let mut ptr = Vec::with_capacity(len + n - sep + 1);
    let mut idx = Vec::new();
    ptr.push(0 as Idx);
    for c in cols {
        idx.extend(
            rows[col_ptr[c] as usize..col_ptr[c + 1] as usize]
                .iter()
                .map(|&r| renumber(r as usize) as Idx),
        );
        ptr.push(idx.len() as Idx);
    }
    SymbolicSparseColMat::new_checked(len + n - sep, len + n - sep, ptr, None, idx)
}

/// The transpose of `a` (the upper triangle of a symmetric matrix whose lower one is `a`), rows
/// sorted in each column.
fn transposed(a: &SymbolicSparseColMat<Idx>) -> SymbolicSparseColMat<Idx> {
    let n = a.ncols();
    let (col_ptr, rows) = (a.col_ptr(), a.row_idx());
    let mut ptr = vec![0 as Idx; n + 1];
    for &r in rows {
        ptr[r as usize + 1] += 1;
    }
    for c in 0..n {
        ptr[c + 1] += ptr[c];
    }
    let mut next = ptr.clone();
    let mut idx = vec![0 as Idx; rows.len()];
    // Columns in increasing order: each transposed column's rows come out sorted.
    for c in 0..n {
        for &r in &rows[col_ptr[c] as usize..col_ptr[c + 1] as usize] {
            idx[next[r as usize] as usize] = c as Idx;
            next[r as usize] += 1;
        }
    }
    SymbolicSparseColMat::new_checked(n, n, ptr, None, idx)
}

#[cfg(test)]
mod tests {
    use super::super::tests::{grid_mesh, node_pattern, residual, same_bits, values_of};
    use super::super::{Ordering, SpdSolver, SymPattern, SymTriplets};
    use crate::FlattenError;

    /// A `w × h` grid mesh system (`k` unknowns a vertex), its solver split at the top
    /// separator and one not split, both factored.
    fn split_and_whole(
        w: usize,
        h: usize,
        k: usize,
        t: &SymTriplets,
        node_of: Vec<u32>,
    ) -> (SymPattern, SpdSolver, SpdSolver) {
        let pattern = node_pattern(t, node_of, w * h);
        let mut split = SpdSolver::split_at_any_size(&pattern, "test").unwrap();
        assert!(split.is_split(), "{w}×{h}×{k} is split");
        let mut whole =
            SpdSolver::with_ordering(&pattern, "test", Ordering::NestedDissection).unwrap();
        assert!(!whole.is_split());
        split.factor(values_of(&split, &pattern, t)).unwrap();
        whole.factor(values_of(&whole, &pattern, t)).unwrap();
        (pattern, split, whole)
    }

    /// The largest entry of `a` in absolute value.
    fn largest(a: &[f64]) -> f64 {
        a.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    #[test]
    fn the_split_solve_is_the_whole_solve() {
        for (w, h, k) in [(90, 70, 2), (130, 60, 1)] {
            let (t, node_of) = grid_mesh(w, h, k);
            let (pattern, mut split, whole) = split_and_whole(w, h, k, &t, node_of);
            // The complement is factored in place of the first half's corner.
            let super::super::Factor::SplitDouble(f) = &split.factor else {
                panic!("not a split double-precision factor");
            };
            assert!(
                f.schur.is_none(),
                "{w}×{h}×{k}: the complement is a matrix apart"
            );
            let n = k * w * h;
            let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.2).collect();
            let a = pattern.matrix(t.values(), "test").unwrap();
            let mut b = vec![0.0; n];
            super::super::sym_mul(&a, &x_true, &mut b);
            // Two right-hand sides at once: b and 2b.
            let mut xs: Vec<f64> = b.iter().chain(&b).copied().collect();
            xs[n..].iter_mut().for_each(|v| *v *= 2.0);
            let mut xw = xs.clone();
            let mut again = xs.clone();
            split.solve_many_in_place(&mut xs, 2).unwrap();
            whole.solve_many_in_place(&mut xw, 2).unwrap();
            // Factored again over the corner the complement took: the same bits.
            split.refactor().unwrap();
            split.solve_many_in_place(&mut again, 2).unwrap();
            assert!(same_bits(&xs, &again), "{w}×{h}×{k} refactored");
            let scale = largest(&xw);
            for i in 0..2 * n {
                let want = x_true[i % n] * if i < n { 1.0 } else { 2.0 };
                assert!(
                    (xs[i] - xw[i]).abs() <= 1e-12 * scale,
                    "{w}×{h}×{k} unknown {i}: {} split, {} whole",
                    xs[i],
                    xw[i]
                );
                assert!((xs[i] - want).abs() <= 1e-11 * scale, "unknown {i}");
            }
        }
    }

    #[test]
    fn the_split_solve_is_the_same_bits_on_one_thread_and_on_two() {
        let (w, h) = (100, 80);
        let (t, node_of) = grid_mesh(w, h, 2);
        let pattern = node_pattern(&t, node_of, w * h);
        let n = 2 * w * h;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        let solve = |single: bool| {
            let s = SpdSolver::split_at_any_size(&pattern, "test").unwrap();
            let mut s = if single { s.single() } else { s };
            assert!(s.is_split());
            s.factor(values_of(&s, &pattern, &t)).unwrap();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            x
        };
        // Off rayon's threads the halves run on two threads; on the only worker of a pool, one
        // after the other on it.
        let one_thread = |single: bool| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap()
                .install(|| solve(single))
        };
        for single in [false, true] {
            let (two, one) = (solve(single), one_thread(single));
            assert!(same_bits(&two, &one), "single precision {single}");
            assert!(same_bits(&two, &solve(single)), "repeated, single {single}");
        }
    }

    #[test]
    fn a_split_single_precision_factor_refines_to_double_precision() {
        let (w, h) = (90, 80);
        let (t, node_of) = grid_mesh(w, h, 2);
        let pattern = node_pattern(&t, node_of, w * h);
        let n = 2 * w * h;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin() + 0.5).collect();
        let mut s = SpdSolver::split_at_any_size(&pattern, "test")
            .unwrap()
            .single();
        s.factor(values_of(&s, &pattern, &t)).unwrap();
        assert!(matches!(s.factor, super::super::Factor::SplitSingle(_)));
        let mut x = b.clone();
        s.solve_in_place(&mut x).unwrap();
        let (res, nb) = residual(&pattern, &t, &x, &b);
        assert!(res <= 1e-12 * nb, "residual {res} of {nb}");
    }

    /// The scalar Laplacian of a `w × h` triangulated grid (diagonal the degree) less `shift` on
    /// the diagonal: singular at no shift, indefinite at any positive one, while every
    /// principal block short of the whole is positive definite (a connected graph's Laplacian
    /// with some of its nodes held fixed) up to shifts of its smallest eigenvalue.
    fn shifted_laplacian(w: usize, h: usize, shift: f64) -> (SymTriplets, Vec<u32>) {
        let n = w * h;
        let mut t = SymTriplets::new(n);
        let mut degree = vec![0.0; n];
        for y in 0..h {
            for x in 0..w {
                let v = y * w + x;
                for (dx, dy) in [(1, 0), (0, 1), (1, 1)] {
                    if x + dx < w && y + dy < h {
                        let u = (y + dy) * w + x + dx;
                        t.add(u, v, -1.0);
                        degree[u] += 1.0;
                        degree[v] += 1.0;
                    }
                }
            }
        }
        for (v, d) in degree.into_iter().enumerate() {
            t.add(v, v, d - shift);
        }
        (t, (0..n as u32).collect())
    }

    #[test]
    fn an_indefinite_system_is_refused_by_its_separators_complement() {
        let (w, h) = (80, 60);
        // Each bordered half is positive definite (the whole's smallest eigenvalue moves up by
        // far more than 1e-4 once a half is held fixed), the whole is not: only the separator's
        // complement, the sum of both halves' contributions, can tell.
        let (t, node_of) = shifted_laplacian(w, h, 1e-4);
        let pattern = node_pattern(&t, node_of, w * h);
        let mut s = SpdSolver::split_at_any_size(&pattern, "test").unwrap();
        assert!(s.is_split());
        let err = s.factor(values_of(&s, &pattern, &t)).unwrap_err();
        assert!(
            matches!(&err, FlattenError::Solver { reason, .. } if reason.contains("complement")),
            "{err:?}"
        );
        assert!(s.solve_in_place(&mut vec![1.0; w * h]).is_err());
        // Shifted the other way it is positive definite, and solves.
        let (t, node_of) = shifted_laplacian(w, h, -1e-4);
        let pattern = node_pattern(&t, node_of, w * h);
        let mut s = SpdSolver::split_at_any_size(&pattern, "test").unwrap();
        s.factor(values_of(&s, &pattern, &t)).unwrap();
    }

    #[test]
    fn an_indefinite_half_and_a_non_finite_entry_are_refused() {
        let (w, h) = (80, 60);
        let (mut t, node_of) = grid_mesh(w, h, 1);
        let pattern = node_pattern(&t, node_of.clone(), w * h);
        let mut s = SpdSolver::split_at_any_size(&pattern, "test").unwrap();
        // Unknown 0 is in one of the halves or the separator; either way it is refused.
        let mut values = values_of(&s, &pattern, &t);
        let slot = s.slot(0, 0).unwrap();
        values[slot] = -5.0;
        assert!(matches!(
            s.factor(values.clone()),
            Err(FlattenError::Solver { .. })
        ));
        values[slot] = f64::NAN;
        assert!(matches!(s.factor(values), Err(FlattenError::Solver { .. })));
        // And once made positive definite again, factors.
        t.values_mut().iter_mut().for_each(|v| *v *= 1.0);
        s.factor(values_of(&s, &pattern, &t)).unwrap();
    }

    #[test]
    fn a_system_without_a_top_separator_or_below_the_threshold_is_factored_whole() {
        // 12 × 10 vertices are one leaf of the dissection: no separator to split at.
        for (w, h, any_size) in [(12, 10, true), (90, 70, false)] {
            let (t, node_of) = grid_mesh(w, h, 2);
            let pattern = node_pattern(&t, node_of, w * h);
            let mut s = if any_size {
                SpdSolver::split_at_any_size(&pattern, "test").unwrap()
            } else {
                // Below the threshold, even ordered by nested dissection.
                assert!(2 * w * h < super::SPLIT_FROM);
                SpdSolver::with_ordering(&pattern, "test", Ordering::NestedDissection).unwrap()
            };
            assert!(!s.is_split(), "{w}×{h}");
            s.factor(values_of(&s, &pattern, &t)).unwrap();
            let n = 2 * w * h;
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            let (res, nb) = residual(&pattern, &t, &x, &b);
            assert!(res <= 1e-12 * nb, "{w}×{h}: residual {res} of {nb}");
        }
    }

    #[test]
    fn the_halves_are_uncoupled_and_balanced() {
        let (w, h) = (120, 90);
        let (t, node_of) = grid_mesh(w, h, 2);
        let pattern = node_pattern(&t, node_of, w * h);
        let s = SpdSolver::split_at_any_size(&pattern, "test").unwrap();
        let split = s.split.as_ref().unwrap();
        let [a, b] = &split.halves;
        assert_eq!(a.interior.start, 0);
        assert_eq!(a.interior.end, b.interior.start);
        assert_eq!(b.interior.end, split.sep);
        // The root split's balance (the ordering's, on vertices: two unknowns each).
        let least = (0.45 * (w * h) as f64).floor() as usize * 2;
        assert!(
            a.interior.len() >= least && b.interior.len() >= least,
            "{} and {} of {}",
            a.interior.len(),
            b.interior.len(),
            split.n
        );
        // The separator is the dissection's top block, both unknowns of each of its vertices,
        // and each of its unknowns is coupled to one of the halves.
        assert_eq!(split.sep, pattern.nested_dissection().1);
        assert_eq!(split.n, 2 * w * h);
        let slots = s.slots();
        let coupled = |c: usize| (0..split.sep).any(|k| slots.slot_in_order(c, k).is_some());
        for c in split.sep..split.n {
            assert_eq!(
                s.fwd[c] / 2,
                s.fwd[c ^ 1] / 2,
                "vertex of separator unknown {c}"
            );
            assert!(coupled(c), "separator unknown {c} touches no half");
        }
        // No entry of the matrix between the halves, and every one of them has its slot.
        let m = pattern.matrix(t.values(), "test").unwrap();
        let mut slots_seen = vec![false; s.n_values()];
        for j in 0..m.ncols() {
            for &i in m.symbolic().row_idx_of_col_raw(j) {
                let (p, q) = (s.inv[i] as usize, s.inv[j] as usize);
                let (r, c) = (p.max(q), p.min(q));
                assert!(
                    !(a.interior.contains(&c) && b.interior.contains(&r)),
                    "({r}, {c})"
                );
                let slot = slots.slot_in_order(r, c).unwrap();
                assert!(!slots_seen[slot], "slot {slot} twice");
                slots_seen[slot] = true;
            }
        }
        assert!(slots_seen.iter().all(|&s| s));
        // The separator is a grid cross-section: about one row or column of vertices.
        assert!(split.n - split.sep <= 2 * 2 * w, "{}", split.n - split.sep);
    }
}
