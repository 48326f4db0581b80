//! The sparse `LDLᵀ` of a quasi-definite [`SymCsc`]: the symbolic analysis
//! ([`SymbolicLdlt`], AMD or a given elimination order), the numeric factorization of the
//! equilibrated matrix with sign-aware dynamic regularization ([`Ldlt`], see the module
//! documentation of [`crate::linalg`] for the policy), its pivot statistics and its plain
//! solves. Refinement is in [`super::refine`], the condition estimate in [`super::estimate`].

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par, Side, Spec};

use super::csc::SymCsc;
use super::error::LinalgError;

/// Relative pivot threshold: `|d| <= PIVOT_EPS_REL · scale` counts as a zero pivot.
const PIVOT_EPS_REL: f64 = 1e-13;
/// Relative magnitude of a regularized pivot: it becomes `± PIVOT_DELTA_REL · scale`.
pub(super) const PIVOT_DELTA_REL: f64 = 1e-6;
/// Factor by which `delta` grows when a factorization meets a non-finite pivot.
const DELTA_RETRY_FACTOR: f64 = 100.0;
/// Retries with a larger `delta` before giving up.
const MAX_DELTA_RETRIES: usize = 2;
/// Minimum number of right-hand sides per thread in [`Ldlt::solve_many_in_place`].
const MIN_COLS_PER_THREAD: usize = 16;
/// Minimum `n · ncols` for [`Ldlt::solve_many_in_place`] to spawn threads.
const MIN_WORK_FOR_THREADS: usize = 1 << 16;

/// Symbolic analysis (fill-reducing ordering + elimination tree/supernodes), done once per pattern.
pub struct SymbolicLdlt {
    inner: Arc<SymbolicCholesky<usize>>,
    n: usize,
    nnz: usize,
    pattern_hash: u64,
}

impl SymbolicLdlt {
    /// Analyzes the pattern of `matrix` (AMD ordering, elimination tree, supernodes).
    ///
    /// # Errors
    /// [`LinalgError::Structure`] / [`LinalgError::Dimension`] /
    /// [`LinalgError::IndexOutOfBounds`] for an invalid [`SymCsc`],
    /// [`LinalgError::Symbolic`] if faer fails (e.g. out of memory, index overflow).
    pub fn analyze(matrix: &SymCsc) -> Result<SymbolicLdlt, LinalgError> {
        Self::analyze_with(matrix, SymmetricOrdering::Amd)
    }

    /// Analyzes the pattern of `matrix` with a given elimination order: `order[position]` is
    /// the unknown eliminated at `position` (e.g. [`crate::ordering::nested_dissection`]).
    ///
    /// # Errors
    /// As [`SymbolicLdlt::analyze`], and [`LinalgError::Dimension`] /
    /// [`LinalgError::Symbolic`] when `order` is not a permutation of `0..n`.
    pub fn analyze_ordered(matrix: &SymCsc, order: &[usize]) -> Result<SymbolicLdlt, LinalgError> {
        if order.len() != matrix.n {
            return Err(LinalgError::Dimension {
                what: "order",
                expected: matrix.n,
                found: order.len(),
            });
        }
        let mut inverse = vec![usize::MAX; order.len()];
        for (position, &k) in order.iter().enumerate() {
            if k >= order.len() || inverse[k] != usize::MAX {
                return Err(LinalgError::Symbolic(format!(
                    "the elimination order is not a permutation (entry {position} = {k})"
                )));
            }
            inverse[k] = position;
        }
        let perm = faer::perm::PermRef::new_checked(order, &inverse, order.len());
        Self::analyze_with(matrix, SymmetricOrdering::Custom(perm))
    }

    fn analyze_with(
        matrix: &SymCsc,
        ordering: SymmetricOrdering<'_, usize>,
    ) -> Result<SymbolicLdlt, LinalgError> {
        matrix.validate()?;
        let inner = factorize_symbolic_cholesky(
            matrix.faer_symbolic(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| LinalgError::Symbolic(format!("{e:?}")))?;
        Ok(SymbolicLdlt {
            inner: Arc::new(inner),
            n: matrix.n,
            nnz: matrix.row_idx.len(),
            pattern_hash: matrix.pattern_hash(),
        })
    }

    /// The elimination order of this analysis: `order[position]` is the unknown eliminated at
    /// `position` (the identity when faer chose none).
    pub fn order(&self) -> Vec<usize> {
        match self.inner.perm() {
            Some(perm) => perm.arrays().0.to_vec(),
            None => (0..self.n).collect(),
        }
    }

    /// Number of stored values of the factor `L` (including the dense zeros of the
    /// supernodal blocks and the diagonal holding `D`).
    pub fn factor_nnz(&self) -> usize {
        self.inner.len_val()
    }
}

/// Numeric LDLᵀ factorization with sign-aware dynamic regularization.
pub struct Ldlt {
    pub(super) symbolic: Arc<SymbolicCholesky<usize>>,
    pub(super) values: Vec<f64>,
    /// S of the factored K̃ = S K S (see [`equilibration`]).
    equilibration: Vec<f64>,
    pub(super) n: usize,
    stats: FactorStats,
}

/// Pivot statistics of a numeric factorization (pivots = entries of `D`).
#[derive(Clone, Debug, PartialEq)]
pub struct FactorStats {
    /// Pivots replaced by `±delta` (tiny or of the wrong sign).
    pub regularized_pivots: usize,
    /// Number of positive pivots (inertia: positive eigenvalues of the factored matrix).
    pub positive_pivots: usize,
    /// Number of negative pivots.
    pub negative_pivots: usize,
    /// Smallest `|d|` (`+inf` for an empty matrix).
    pub min_abs_pivot: f64,
    /// Largest `|d|` (`0` for an empty matrix).
    pub max_abs_pivot: f64,
}

impl Ldlt {
    /// `signs[i]` = +1 / -1 : expected sign of pivot i (in the ORIGINAL numbering). Dynamic regularization:
    /// a pivot whose |d| <= eps*max or whose sign is wrong is replaced by sign*delta (choose eps, delta sensibly, e.g. eps=1e-13 relative, delta = 1e-10 * max|diag|; document).
    ///
    /// Here `max = max_i |K_ii|` (or `max |K_ij|` if the diagonal is zero),
    /// `eps = 1e-13` and `delta = 1e-6 · max` (not `1e-10`: see the module
    /// documentation for the measurements); on a zero / non-finite pivot the
    /// factorization is retried with `delta` ×100, at most twice.
    ///
    /// # Errors
    /// Invalid structure, [`LinalgError::PatternMismatch`] if `matrix` is not the
    /// pattern `symbolic` was built from, [`LinalgError::Dimension`] /
    /// [`LinalgError::InvalidSign`] for bad `signs`, [`LinalgError::NonFinite`],
    /// [`LinalgError::Numeric`] for a zero matrix, out of memory or a pivot that is
    /// still zero / non-finite after regularization.
    pub fn factor(
        symbolic: &SymbolicLdlt,
        matrix: &SymCsc,
        signs: &[i8],
    ) -> Result<Ldlt, LinalgError> {
        Self::refactor(symbolic, matrix, signs, None)
    }

    /// As [`Ldlt::factor`], reusing the value buffer of `previous` (a factor of the same
    /// pattern, e.g. at the previous δ): a fresh buffer costs a page fault per 4 KiB on first
    /// touch, a large part of the numeric factorisation on large systems.
    ///
    /// # Errors
    /// As [`Ldlt::factor`].
    pub fn refactor(
        symbolic: &SymbolicLdlt,
        matrix: &SymCsc,
        signs: &[i8],
        previous: Option<Ldlt>,
    ) -> Result<Ldlt, LinalgError> {
        matrix.validate()?;
        let n = matrix.n;
        if n != symbolic.n
            || matrix.row_idx.len() != symbolic.nnz
            || matrix.pattern_hash() != symbolic.pattern_hash
        {
            return Err(LinalgError::PatternMismatch);
        }
        if signs.len() != n {
            return Err(LinalgError::Dimension {
                what: "signs",
                expected: n,
                found: signs.len(),
            });
        }
        if let Some((index, &value)) = signs.iter().enumerate().find(|(_, &s)| s != 1 && s != -1) {
            return Err(LinalgError::InvalidSign { index, value });
        }
        if matrix.values.iter().any(|v| !v.is_finite()) {
            return Err(LinalgError::NonFinite);
        }

        // Symmetric diagonal (Jacobi) equilibration: K̃ = S K S, S = diag(|K_ii|^{-1/2}), so that
        // blocks of different physical scale (p–p ~ L², u–u ~ 1 on a domain of size L) meet the
        // same pivot threshold; K x = b is solved as x = S K̃⁻¹ S b.
        let equilibration = equilibration(matrix);
        let scaled: Vec<f64> = (0..n)
            .flat_map(|j| {
                let (col, eq) = (matrix.col_ptr[j]..matrix.col_ptr[j + 1], &equilibration);
                col.map(move |k| matrix.values[k] * eq[matrix.row_idx[k]] * eq[j])
            })
            .collect();
        let mut scale = 0.0f64;
        for j in 0..n {
            let start = matrix.col_ptr[j];
            if start < matrix.col_ptr[j + 1] && matrix.row_idx[start] == j {
                scale = scale.max(scaled[start].abs());
            }
        }
        if scale == 0.0 {
            scale = scaled.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        }
        if scale == 0.0 && n > 0 {
            return Err(LinalgError::Numeric("matrix is zero".into()));
        }
        let eps = PIVOT_EPS_REL * scale;
        let mut delta = PIVOT_DELTA_REL * scale;

        let inner = &*symbolic.inner;
        let par = Par::rayon(0);
        let params = Spec::default();
        let mut values = previous.map(|p| p.values).unwrap_or_default();
        if values.len() == inner.len_val() {
            values.fill(0.0);
        } else {
            values = factor_buffer(inner.len_val())?;
        }
        let mut mem = MemBuffer::try_new(inner.factorize_numeric_ldlt_scratch::<f64>(par, params))
            .map_err(|_| LinalgError::Numeric("out of memory for the workspace".into()))?;
        let a = SparseColMatRef::new(matrix.faer_symbolic(), &scaled);
        let mut attempt = 0;
        loop {
            let regularization = LdltRegularization {
                dynamic_regularization_signs: Some(signs),
                dynamic_regularization_delta: delta,
                dynamic_regularization_epsilon: eps,
            };
            match inner.factorize_numeric_ldlt(
                &mut values,
                a,
                Side::Lower,
                regularization,
                par,
                MemStack::new(&mut mem),
                params,
            ) {
                Ok(_) => break,
                Err(LdltError::ZeroPivot { index }) => {
                    if attempt == MAX_DELTA_RETRIES {
                        return Err(LinalgError::Numeric(format!(
                            "zero or non-finite pivot near elimination step {index} \
                             (regularization delta {delta:e})"
                        )));
                    }
                    attempt += 1;
                    delta *= DELTA_RETRY_FACTOR;
                }
            }
        }
        drop(mem);

        drop(scaled);
        let stats = pivot_stats(inner, &values, delta);
        Ok(Ldlt {
            symbolic: Arc::clone(&symbolic.inner),
            values,
            equilibration,
            n,
            stats,
        })
    }

    /// Pivot statistics (inertia, regularized pivots, pivot range) of this factorization.
    pub fn stats(&self) -> &FactorStats {
        &self.stats
    }

    /// `(K⁻¹)[indices, indices]` as a dense row-major `c × c` matrix (`c = indices.len()`), for
    /// the factored (possibly regularized) `K`, read off the trailing block of the factor.
    ///
    /// With `K = P L D Lᵀ Pᵀ` and the unknowns `indices` eliminated last, the trailing `c × c`
    /// blocks `L_S`, `D_S` factor the Schur complement `S` of everything else, and
    /// `(K⁻¹)_SS = S⁻¹ = L_S⁻ᵀ D_S⁻¹ L_S⁻¹`: O(c³) dense work instead of `c` sparse solves.
    /// Returns `None` when `indices` are not the last `c` unknowns of the elimination order
    /// (analyse with [`SymbolicLdlt::analyze_ordered`] and put them at the end) or repeat.
    pub fn trailing_inverse(&self, indices: &[usize]) -> Option<Vec<f64>> {
        let (n, c) = (self.n, indices.len());
        if c == 0 || c > n {
            return None;
        }
        let t0 = n - c;
        // local[k] = position of indices[k] inside the trailing block
        let local: Vec<usize> = match self.symbolic.perm() {
            Some(perm) => {
                let (_, inverse) = perm.arrays();
                indices
                    .iter()
                    .map(|&i| inverse.get(i).copied())
                    .collect::<Option<_>>()?
            }
            None => indices.to_vec(),
        };
        let mut seen = vec![false; c];
        for &p in &local {
            if p < t0 || std::mem::replace(&mut seen[p - t0], true) {
                return None;
            }
        }
        let (l, d) = self.trailing_factor(t0);
        // X = L_S⁻¹ (unit lower triangular), then (K⁻¹)_SS = Xᵀ D⁻¹ X.
        let mut x = faer::Mat::<f64>::identity(c, c);
        faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
            l.as_ref(),
            x.as_mut(),
            Par::Seq,
        );
        let mut dx = x.clone();
        for i in 0..c {
            for j in 0..c {
                dx[(i, j)] /= d[i];
            }
        }
        let inv = x.transpose() * &dx;
        // (K⁻¹)_SS = S (K̃⁻¹)_SS S
        let mut out = vec![0.0; c * c];
        for (a, (&pa, &ia)) in local.iter().zip(indices).enumerate() {
            for (b, (&pb, &ib)) in local.iter().zip(indices).enumerate() {
                out[a * c + b] =
                    self.equilibration[ia] * inv[(pa - t0, pb - t0)] * self.equilibration[ib];
            }
        }
        Some(out)
    }

    /// The trailing `L_S` (unit lower, dense) and `D_S` of the factor, from position `t0` on.
    fn trailing_factor(&self, t0: usize) -> (faer::Mat<f64>, Vec<f64>) {
        let c = self.n - t0;
        let mut l = faer::Mat::<f64>::identity(c, c);
        let mut d = vec![0.0; c];
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (col_ptr, row_idx) = (s.col_ptr(), s.row_idx());
                for j in t0..self.n {
                    // the first entry of a column holds D_jj, the others L_ij (i > j)
                    d[j - t0] = self.values[col_ptr[j]];
                    for k in col_ptr[j] + 1..col_ptr[j + 1] {
                        l[(row_idx[k] - t0, j - t0)] = self.values[k];
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let factor = SupernodalLdltRef::new(s, &self.values);
                for sn in 0..s.n_supernodes() {
                    let (begin, end) = (s.supernode_begin()[sn], s.supernode_end()[sn]);
                    if end <= t0 {
                        continue;
                    }
                    let node = factor.supernode(sn);
                    let val = node.val();
                    let width = end - begin;
                    for j in begin.max(t0)..end {
                        let jj = j - begin;
                        d[j - t0] = val[(jj, jj)];
                        for ii in jj + 1..width {
                            l[(begin + ii - t0, j - t0)] = val[(ii, jj)];
                        }
                        for (k, &row) in node.pattern().iter().enumerate() {
                            l[(row - t0, j - t0)] = val[(width + k, jj)];
                        }
                    }
                }
            }
        }
        (l, d)
    }

    /// x = K⁻¹ b for the factored (possibly regularized) matrix, in place.
    ///
    /// # Panics
    /// If `rhs.len() != n` (caller bug).
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        assert_eq!(rhs.len(), self.n, "Ldlt::solve_in_place: wrong rhs length");
        self.solve_many_in_place(rhs, 1);
    }

    /// Many right-hand sides at once, column-major n×k buffer (used for Schur complements on ~100-1000 crack dofs); use faer's multi-rhs solve so it is efficient.
    ///
    /// # Panics
    /// If `rhs.len() != n * ncols` (caller bug).
    pub fn solve_many_in_place(&self, rhs: &mut [f64], ncols: usize) {
        let n = self.n;
        assert_eq!(
            Some(rhs.len()),
            n.checked_mul(ncols),
            "Ldlt::solve_many_in_place: rhs.len() != n * ncols"
        );
        if n == 0 || ncols == 0 {
            return;
        }
        let threads = match Par::rayon(0) {
            Par::Rayon(t) => t.get(),
            Par::Seq => 1,
        };
        let blocks = threads.min(ncols / MIN_COLS_PER_THREAD);
        self.equilibrate(rhs);
        if blocks <= 1 || n * ncols < MIN_WORK_FOR_THREADS {
            self.solve_block(rhs, ncols);
        } else {
            let cols_per_block = ncols.div_ceil(blocks);
            std::thread::scope(|scope| {
                for block in rhs.chunks_mut(n * cols_per_block) {
                    scope.spawn(move || self.solve_block(block, block.len() / n));
                }
            });
        }
        self.equilibrate(rhs);
    }

    /// Multiplies every column of an `n × k` block by S (before and after the solve with K̃).
    fn equilibrate(&self, block: &mut [f64]) {
        for column in block.chunks_exact_mut(self.n) {
            column
                .iter_mut()
                .zip(&self.equilibration)
                .for_each(|(v, s)| *v *= s);
        }
    }

    /// Sequential multi-rhs solve of a column-major `n × ncols` block.
    fn solve_block(&self, rhs: &mut [f64], ncols: usize) {
        let n = self.n;
        debug_assert_eq!(rhs.len(), n * ncols);
        let par = Par::Seq;
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(ncols, par));
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, ncols);
        LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut mem),
        );
    }
}

/// The symmetric equilibration S = diag(s) of [`Ldlt::factor`]: `s_i = |K_ii|^{-1/2}` where the
/// diagonal entry is non-zero, else `(max_j |K_ij|)^{-1/2}` over row i, else 1 (an empty row).
fn equilibration(matrix: &SymCsc) -> Vec<f64> {
    let n = matrix.n;
    let mut diag = vec![0.0f64; n];
    let mut row_max = vec![0.0f64; n];
    for j in 0..n {
        for k in matrix.col_ptr[j]..matrix.col_ptr[j + 1] {
            let (i, v) = (matrix.row_idx[k], matrix.values[k].abs());
            if i == j {
                diag[j] = v;
            }
            row_max[i] = row_max[i].max(v);
            row_max[j] = row_max[j].max(v);
        }
    }
    diag.iter()
        .zip(&row_max)
        .map(|(&d, &r)| {
            let pick = if d > 0.0 { d } else { r };
            if pick > 0.0 && pick.is_finite() {
                1.0 / pick.sqrt()
            } else {
                1.0
            }
        })
        .collect()
}

/// A zeroed buffer for the values of a factor, or an out-of-memory error.
///
/// Fresh memory is expensive: the first touch of each page (here, by the zeroing) costs seconds
/// per gigabyte (docs/performance.md), with or without transparent huge pages or
/// `MADV_POPULATE_WRITE` (neither is faster). That is why a δ sweep refactors into the previous
/// δ's buffer ([`Ldlt::refactor`]).
pub(super) fn factor_buffer(len: usize) -> Result<Vec<f64>, LinalgError> {
    let mut values: Vec<f64> = Vec::new();
    values
        .try_reserve_exact(len)
        .map_err(|_| LinalgError::Numeric("out of memory for the factor".into()))?;
    values.resize(len, 0.0);
    Ok(values)
}

/// Reads the pivots `D` from faer's factor storage and summarizes them.
fn pivot_stats(symbolic: &SymbolicCholesky<usize>, values: &[f64], delta: f64) -> FactorStats {
    let mut stats = FactorStats {
        regularized_pivots: 0,
        positive_pivots: 0,
        negative_pivots: 0,
        min_abs_pivot: f64::INFINITY,
        max_abs_pivot: 0.0,
    };
    let mut visit = |d: f64| {
        if d > 0.0 {
            stats.positive_pivots += 1;
        } else if d < 0.0 {
            stats.negative_pivots += 1;
        }
        if delta > 0.0 && d.abs() == delta {
            stats.regularized_pivots += 1;
        }
        stats.min_abs_pivot = stats.min_abs_pivot.min(d.abs());
        stats.max_abs_pivot = stats.max_abs_pivot.max(d.abs());
    };
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            // The first entry of every column of the simplicial factor holds D_kk.
            let col_ptr = s.col_ptr();
            for k in 0..s.nrows() {
                visit(values[col_ptr[k]]);
            }
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            // The diagonal of each supernode's top (square) block holds D.
            let l = SupernodalLdltRef::new(s, values);
            for sn in 0..s.n_supernodes() {
                let block = l.supernode(sn).val();
                for j in 0..block.ncols() {
                    visit(block[(j, j)]);
                }
            }
        }
    }
    stats
}
