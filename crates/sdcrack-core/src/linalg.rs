//! Sparse symmetric direct solver: the one sparse direct solver interface of `sdcrack`.
//!
//! Every sparse linear system of the project (the quasi-definite saddle systems
//! `K = [[G, Bᵀ], [B, −S]]`, with `G` SPD and `S` symmetric positive semi-definite)
//! is stored as a [`SymCsc`] (lower triangle, CSC) and solved through this module,
//! which wraps the supernodal / simplicial sparse `LDLᵀ` of `faer` 0.24
//! (`faer::sparse::linalg::cholesky`). Nothing else in the crate talks to faer's
//! sparse factorizations directly.
//!
//! # Workflow
//!
//! 1. [`SymbolicLdlt::analyze`]: AMD fill-reducing ordering, elimination tree,
//!    supernodes (faer picks simplicial or supernodal from its flop-ratio
//!    heuristic). Done once per sparsity pattern.
//! 2. [`Ldlt::factor`]: numeric `LDLᵀ` (no pivoting) with sign-aware dynamic
//!    regularization. Can be repeated for any matrix with the same pattern
//!    (checked: `n`, `nnz` and a 64-bit hash of the pattern must match).
//! 3. [`Ldlt::solve_in_place`], [`Ldlt::solve_many_in_place`] (multi right-hand
//!    side, blocked), [`Ldlt::solve_refined`] (iterative refinement against the
//!    exact matrix).
//!
//! # Equilibration
//!
//! [`Ldlt::factor`] factors `K̃ = S K S` with `S = diag(|K_ii|^{-1/2})` (a row's largest entry
//! where the diagonal is zero), and every solve returns `x = S K̃⁻¹ S b`, so callers see `K⁻¹`.
//! Blocks of different physical size (on a domain of size L the p–p block scales as L², the u–u
//! block as 1) then meet the same pivot threshold: without it, L = 1e-5 regularised thousands of
//! p pivots (tests/stability.rs). The pivot statistics and thresholds below are those of `K̃`.
//!
//! # Regularization policy
//!
//! The caller gives the expected sign of every pivot (`+1` for rows of the `G`
//! block, `−1` for rows of the `S` block, in the original numbering; they are
//! permuted along with the matrix). With `scale = max_i |K̃_ii|` (or `max |K̃_ij|`
//! if the diagonal is identically zero), faer's `LdltRegularization` is used with
//!
//! * threshold `eps = PIVOT_EPS_REL · scale`, `PIVOT_EPS_REL = 1e-13`,
//! * replacement `delta = PIVOT_DELTA_REL · scale`, `PIVOT_DELTA_REL = 1e-6`:
//!
//! a pivot `d` expected positive with `d <= eps`, or expected negative with
//! `d >= −eps` (i.e. tiny or of the wrong sign), is replaced by `sign · delta`.
//! This is equivalent to perturbing that diagonal entry of `K` during the
//! elimination, so the factorization of a quasi-definite matrix whose `S` block
//! is singular always succeeds; iterative refinement against the exact matrix
//! then removes the perturbation.
//!
//! `PIVOT_DELTA_REL = 1e-6` (rather than a tinier value) is deliberate: when many
//! pivots are regularized (worst case `S = 0`, where AMD eliminates `S` rows before
//! their `G` neighbours), each regularized pivot feeds `1/delta`-sized updates to
//! later pivots. Measured on 5·10⁵-unknown grids with `S = 0`: `1e-10` gives
//! pivots up to 1e21 and refinement stalls at ~1e-9; `1e-8` reaches ~2e-11 or
//! overflows to a non-finite pivot; `1e-6` refines to ~3e-14. With a semi-definite
//! Neumann-type `S` coupled through `B`, no pivot is regularized at all.
//! If the factorization still meets a zero / non-finite pivot, it is retried with
//! `delta` multiplied by `DELTA_RETRY_FACTOR = 100`, at most `MAX_DELTA_RETRIES = 2`
//! times, before [`LinalgError::Numeric`] is returned.
//!
//! [`FactorStats::regularized_pivots`] counts the pivots of the factor that are
//! exactly `±delta` (faer 0.24's high-level API does not return its own counter,
//! and its dense supernodal kernel only counts the positive-sign corrections).
//!
//! # Refinement policy
//!
//! [`Ldlt::solve_refined`] computes `x = solve(b)`, then repeats
//! `r = b − K x; x += solve(r)` with the exact (unregularized) matrix `K`, at least
//! one step and at most `max_steps`, stopping early once
//! `‖r‖_∞ <= tol · ‖b‖_∞`, or after `STAGNATION_STEPS = 2` consecutive steps that
//! do not improve the best residual (round-off floor). The iterate with the
//! smallest residual is returned (the residual history is not monotone when many
//! pivots were regularized).
//!
//! # Parallelism
//!
//! The numeric factorization uses `faer::Par::rayon(0)` (the current rayon pool,
//! so `rayon::ThreadPool::install` controls it). Solves run faer's sequential
//! kernels (its parallel sparse triangular solves were several times slower on
//! FE-sized supernodes); [`Ldlt::solve_many_in_place`] instead splits the
//! right-hand sides into contiguous column blocks, one scoped thread per block,
//! up to the rayon pool size, with at least `MIN_COLS_PER_THREAD = 16` columns each.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side, Spec};

/// Relative pivot threshold: `|d| <= PIVOT_EPS_REL · scale` counts as a zero pivot.
const PIVOT_EPS_REL: f64 = 1e-13;
/// Relative magnitude of a regularized pivot: it becomes `± PIVOT_DELTA_REL · scale`.
const PIVOT_DELTA_REL: f64 = 1e-6;
/// Factor by which `delta` grows when a factorization meets a non-finite pivot.
const DELTA_RETRY_FACTOR: f64 = 100.0;
/// Retries with a larger `delta` before giving up.
const MAX_DELTA_RETRIES: usize = 2;
/// Refinement stops after this many consecutive steps without a new best residual.
const STAGNATION_STEPS: usize = 2;
/// Minimum number of right-hand sides per thread in [`Ldlt::solve_many_in_place`].
const MIN_COLS_PER_THREAD: usize = 16;
/// Minimum `n · ncols` for [`Ldlt::solve_many_in_place`] to spawn threads.
const MIN_WORK_FOR_THREADS: usize = 1 << 16;

/// Errors of the sparse symmetric solver.
#[derive(Debug, thiserror::Error)]
pub enum LinalgError {
    /// The symbolic analysis (ordering, elimination tree) failed, e.g. out of memory.
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    /// The numeric factorization failed (out of memory, zero or non-finite pivot, zero matrix).
    #[error("numeric factorization failed: {0}")]
    Numeric(String),
    /// A vector or matrix has the wrong size.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    Dimension {
        /// What was being checked.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A triplet index lies outside the `n × n` matrix.
    #[error("entry ({row}, {col}) out of bounds for a {n}x{n} matrix")]
    IndexOutOfBounds {
        /// Row index of the offending entry.
        row: usize,
        /// Column index of the offending entry.
        col: usize,
        /// Matrix dimension.
        n: usize,
    },
    /// The CSC arrays of a [`SymCsc`] violate its invariants.
    #[error("invalid symmetric CSC structure: {0}")]
    Structure(String),
    /// A pivot sign other than `+1` / `−1` was given.
    #[error("invalid pivot sign {value} at index {index} (expected +1 or -1)")]
    InvalidSign {
        /// Row (original numbering) of the offending sign.
        index: usize,
        /// The sign given.
        value: i8,
    },
    /// The matrix does not have the sparsity pattern the symbolic analysis was made for.
    #[error("matrix pattern differs from the one used for the symbolic analysis")]
    PatternMismatch,
    /// A matrix entry is NaN or infinite.
    #[error("non-finite matrix entry")]
    NonFinite,
}

/// Symmetric sparse matrix, lower triangle (diagonal included) stored column-major (CSC), sorted row indices.
///
/// Invariants (checked by [`SymbolicLdlt::analyze`] and [`Ldlt::factor`]):
/// `col_ptr.len() == n + 1`, `col_ptr[0] == 0`, `col_ptr` non-decreasing,
/// `col_ptr[n] == row_idx.len() == values.len()`, and in column `j` the row indices
/// are strictly increasing, `>= j` and `< n`. Explicit zeros are kept (they are
/// part of the pattern).
#[derive(Clone, Debug, Default)]
pub struct SymCsc {
    /// Dimension of the (square) matrix.
    pub n: usize,
    /// Column pointers, length `n + 1`.
    pub col_ptr: Vec<usize>,
    /// Row indices of the lower-triangle entries, sorted within each column.
    pub row_idx: Vec<usize>,
    /// Values matching `row_idx`.
    pub values: Vec<f64>,
}

impl SymCsc {
    /// Build from (row, col, value) triplets of the FULL or LOWER part (entries with row < col are mirrored to (col,row); duplicates summed).
    ///
    /// Note: when giving the full matrix, each off-diagonal pair `(i, j)`, `(j, i)` is
    /// mirrored onto the same lower entry and therefore summed; give either the lower
    /// part or the upper part of an off-diagonal entry, not both, unless the halves
    /// are meant to add up. Entries summing to zero stay in the pattern.
    ///
    /// # Errors
    /// [`LinalgError::IndexOutOfBounds`] for an index `>= n`,
    /// [`LinalgError::NonFinite`] for a NaN / infinite value.
    pub fn from_triplets(
        n: usize,
        triplets: &[(usize, usize, f64)],
    ) -> Result<SymCsc, LinalgError> {
        let mut counts = vec![0usize; n + 1];
        for &(r, c, v) in triplets {
            if r >= n || c >= n {
                return Err(LinalgError::IndexOutOfBounds { row: r, col: c, n });
            }
            if !v.is_finite() {
                return Err(LinalgError::NonFinite);
            }
            counts[r.min(c) + 1] += 1;
        }
        for j in 0..n {
            counts[j + 1] += counts[j];
        }
        // Counting sort by column.
        let mut next = counts.clone();
        let mut entries = vec![(0usize, 0.0f64); triplets.len()];
        for &(r, c, v) in triplets {
            let (row, col) = (r.max(c), r.min(c));
            entries[next[col]] = (row, v);
            next[col] += 1;
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(triplets.len());
        let mut values = Vec::with_capacity(triplets.len());
        col_ptr.push(0);
        for j in 0..n {
            let col = &mut entries[counts[j]..counts[j + 1]];
            col.sort_unstable_by_key(|e| e.0);
            let start = row_idx.len();
            for &(row, v) in col.iter() {
                if row_idx.len() > start && row_idx[row_idx.len() - 1] == row {
                    let last = values.len() - 1;
                    values[last] += v;
                } else {
                    row_idx.push(row);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Ok(SymCsc {
            n,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// `‖K‖₁ = max_j Σ_i |K_ij|` over both triangles of the symmetric matrix.
    pub fn norm1(&self) -> f64 {
        self.norm1_with(&self.values)
    }

    /// The 1-norm of the symmetric matrix with this pattern and the entries `values` (e.g.
    /// `∂K/∂δ`, stored on the pattern of `K`).
    ///
    /// # Panics
    /// If `values.len()` differs from the pattern's (caller bug).
    pub fn norm1_with(&self, values: &[f64]) -> f64 {
        assert_eq!(
            values.len(),
            self.row_idx.len(),
            "SymCsc::norm1_with: pattern"
        );
        let mut sums = vec![0.0f64; self.n];
        for j in 0..self.n {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let (i, v) = (self.row_idx[k], values[k].abs());
                sums[j] += v;
                if i != j {
                    sums[i] += v;
                }
            }
        }
        sums.into_iter().fold(0.0, f64::max)
    }

    /// y = K x and s = |K| |x| (entrywise absolute values) in one pass over the matrix: s is
    /// the scale of each row of K x, for componentwise backward errors.
    ///
    /// # Panics
    /// If a length differs from `n` (caller bug).
    pub fn mul_vec_with_abs(&self, x: &[f64], y: &mut [f64], s: &mut [f64]) {
        let n = self.n;
        assert!(
            x.len() == n && y.len() == n && s.len() == n,
            "SymCsc::mul_vec_with_abs: lengths"
        );
        y.fill(0.0);
        s.fill(0.0);
        for j in 0..n {
            let (xj, aj) = (x[j], x[j].abs());
            let (mut yj, mut sj) = (0.0, 0.0);
            let range = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &v) in self.row_idx[range.clone()].iter().zip(&self.values[range]) {
                y[i] += v * xj;
                s[i] += v.abs() * aj;
                if i != j {
                    yj += v * x[i];
                    sj += v.abs() * x[i].abs();
                }
            }
            y[j] += yj;
            s[j] += sj;
        }
    }

    /// y = K x using the symmetric storage (both triangles).
    ///
    /// # Panics
    /// If `x.len() != n` or `y.len() != n` (caller bug: dimensions are internal).
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.n, "SymCsc::mul_vec: x has the wrong length");
        assert_eq!(y.len(), self.n, "SymCsc::mul_vec: y has the wrong length");
        y.fill(0.0);
        for j in 0..self.n {
            let xj = x[j];
            let mut acc = 0.0;
            let range = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &a) in self.row_idx[range.clone()].iter().zip(&self.values[range]) {
                y[i] += a * xj;
                if i != j {
                    acc += a * x[i];
                }
            }
            y[j] += acc;
        }
    }

    /// Same sparsity pattern check (used to reuse a symbolic factorization).
    pub fn same_pattern(&self, other: &SymCsc) -> bool {
        self.n == other.n && self.col_ptr == other.col_ptr && self.row_idx == other.row_idx
    }

    /// Checks the structural invariants documented on [`SymCsc`].
    fn validate(&self) -> Result<(), LinalgError> {
        let n = self.n;
        if self.col_ptr.len() != n + 1 {
            return Err(LinalgError::Dimension {
                what: "SymCsc::col_ptr",
                expected: n + 1,
                found: self.col_ptr.len(),
            });
        }
        let nnz = self.col_ptr[n];
        if self.col_ptr[0] != 0 {
            return Err(LinalgError::Structure("col_ptr[0] != 0".into()));
        }
        if self.row_idx.len() != nnz {
            return Err(LinalgError::Dimension {
                what: "SymCsc::row_idx",
                expected: nnz,
                found: self.row_idx.len(),
            });
        }
        if self.values.len() != nnz {
            return Err(LinalgError::Dimension {
                what: "SymCsc::values",
                expected: nnz,
                found: self.values.len(),
            });
        }
        for j in 0..n {
            let (start, end) = (self.col_ptr[j], self.col_ptr[j + 1]);
            if start > end {
                return Err(LinalgError::Structure(format!(
                    "col_ptr decreases at column {j}"
                )));
            }
            let rows = &self.row_idx[start..end];
            if let Some(&first) = rows.first() {
                if first < j {
                    return Err(LinalgError::Structure(format!(
                        "entry ({first}, {j}) is above the diagonal"
                    )));
                }
            }
            if let Some(&last) = rows.last() {
                if last >= n {
                    return Err(LinalgError::IndexOutOfBounds {
                        row: last,
                        col: j,
                        n,
                    });
                }
            }
            if rows.windows(2).any(|w| w[0] >= w[1]) {
                return Err(LinalgError::Structure(format!(
                    "row indices of column {j} are not strictly increasing"
                )));
            }
        }
        Ok(())
    }

    /// 64-bit FNV-style hash of the pattern (`n`, `col_ptr`, `row_idx`).
    fn pattern_hash(&self) -> u64 {
        const PRIME: u64 = 0x0000_0100_0000_01b3;
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut mix = |v: usize| {
            h = (h ^ v as u64).wrapping_mul(PRIME);
        };
        mix(self.n);
        self.col_ptr.iter().for_each(|&v| mix(v));
        self.row_idx.iter().for_each(|&v| mix(v));
        h
    }

    /// Read-only faer view (lower triangle). Requires `validate()` to have passed.
    fn faer_symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

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

    /// Number of stored values of the factor `L` (including the dense zeros of the
    /// supernodal blocks and the diagonal holding `D`).
    pub fn factor_nnz(&self) -> usize {
        self.inner.len_val()
    }
}

/// Numeric LDLᵀ factorization with sign-aware dynamic regularization.
pub struct Ldlt {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    /// S of the factored K̃ = S K S (see [`equilibration`]).
    equilibration: Vec<f64>,
    n: usize,
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
    /// touch, measured 35–60 % of the numeric factorisation on 10⁶-unknown systems.
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

    /// Solve with iterative refinement against the EXACT (unregularized) `matrix`: x = solve(b); repeat { r = b - K x; x += solve(r) } up to `max_steps` (at least 1 step is always done) or until ‖r‖_inf <= tol*‖b‖_inf. Returns the final relative residual ‖b − Kx‖_inf/‖b‖_inf (0 if b = 0).
    ///
    /// Also stops after `STAGNATION_STEPS = 2` consecutive steps without a new best
    /// residual, and returns the best iterate seen (see the module documentation).
    /// `matrix` must be the matrix that was factored (the values before
    /// regularization); only its dimension is checked.
    ///
    /// # Panics
    /// If `matrix.n`, `b.len()` or `x.len()` differ from the factored dimension (caller bug).
    pub fn solve_refined(
        &self,
        matrix: &SymCsc,
        b: &[f64],
        x: &mut [f64],
        max_steps: usize,
        tol: f64,
    ) -> f64 {
        let n = self.n;
        assert_eq!(matrix.n, n, "Ldlt::solve_refined: matrix dimension");
        assert_eq!(b.len(), n, "Ldlt::solve_refined: b length");
        assert_eq!(x.len(), n, "Ldlt::solve_refined: x length");
        let b_norm = inf_norm(b);
        if b_norm == 0.0 {
            x.fill(0.0);
            return 0.0;
        }
        x.copy_from_slice(b);
        self.solve_in_place(x);
        let mut r = vec![0.0; n];
        let mut rel = residual(matrix, b, x, &mut r) / b_norm;
        let mut best_rel = rel;
        let mut best_x = x.to_vec();
        let mut stagnant = 0;
        for step in 0..max_steps.max(1) {
            if step > 0 && (best_rel <= tol || stagnant >= STAGNATION_STEPS) {
                break;
            }
            if !rel.is_finite() {
                break;
            }
            self.solve_in_place(&mut r);
            x.iter_mut().zip(&r).for_each(|(xi, di)| *xi += di);
            rel = residual(matrix, b, x, &mut r) / b_norm;
            if rel < best_rel {
                best_rel = rel;
                best_x.copy_from_slice(x);
                stagnant = 0;
            } else {
                stagnant += 1;
            }
        }
        x.copy_from_slice(&best_x);
        best_rel
    }
}

/// Seconds spent by [`cholesky_solve`] in each phase.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct CholeskyTimings {
    /// AMD ordering, elimination tree, supernodes.
    pub symbolic_s: f64,
    /// Numeric LLᵀ.
    pub numeric_s: f64,
    /// One forward/backward solve.
    pub solve_s: f64,
    /// Stored values of the factor.
    pub factor_nnz: usize,
}

/// Solves `A x = b` in place for an SPD `A` with faer's sparse Cholesky `LLᵀ` and its default
/// settings (AMD ordering): the plain sparse direct solve that `sdcrack bench` uses as its
/// yardstick. Returns the time of each phase.
///
/// # Errors
/// Invalid structure, [`LinalgError::Symbolic`], [`LinalgError::Numeric`] when `A` is not
/// positive definite or memory runs out.
pub fn cholesky_solve(matrix: &SymCsc, b: &mut [f64]) -> Result<CholeskyTimings, LinalgError> {
    let (factor, mut timings) = Cholesky::factor(matrix)?;
    let t2 = std::time::Instant::now();
    factor.solve_in_place(b);
    timings.solve_s = t2.elapsed().as_secs_f64();
    Ok(timings)
}

/// faer's sparse Cholesky `A = LLᵀ` (AMD ordering, default settings) of an SPD matrix, kept for
/// repeated solves: the yardstick of `sdcrack bench` and the preconditioner of
/// [`crate::krylov`].
pub struct Cholesky {
    n: usize,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl Cholesky {
    /// Factors `matrix`; the timings' `solve_s` is 0.
    ///
    /// # Errors
    /// Invalid structure, [`LinalgError::Symbolic`], [`LinalgError::Numeric`] when `A` is not
    /// positive definite or memory runs out.
    pub fn factor(matrix: &SymCsc) -> Result<(Cholesky, CholeskyTimings), LinalgError> {
        use faer::linalg::cholesky::llt::factor::LltRegularization;
        use std::time::Instant;
        matrix.validate()?;
        let t0 = Instant::now();
        let symbolic = factorize_symbolic_cholesky(
            matrix.faer_symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| LinalgError::Symbolic(format!("{e:?}")))?;
        let symbolic_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let par = Par::rayon(0);
        let mut values = factor_buffer(symbolic.len_val())?;
        let mut mem =
            MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Spec::default()))
                .map_err(|_| LinalgError::Numeric("out of memory for the workspace".into()))?;
        let a = SparseColMatRef::new(matrix.faer_symbolic(), &matrix.values);
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Spec::default(),
            )
            .map_err(|e| LinalgError::Numeric(format!("Cholesky: {e:?}")))?;
        let timings = CholeskyTimings {
            symbolic_s,
            numeric_s: t1.elapsed().as_secs_f64(),
            solve_s: 0.0,
            factor_nnz: symbolic.len_val(),
        };
        Ok((
            Cholesky {
                n: matrix.n,
                symbolic,
                values,
            },
            timings,
        ))
    }

    /// Overwrites `b` with `A⁻¹ b`.
    ///
    /// # Panics
    /// If `b.len()` is not the dimension (caller bug).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        use faer::sparse::linalg::cholesky::LltRef;
        assert_eq!(b.len(), self.n, "Cholesky::solve_in_place: dimension");
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let rhs = MatMut::from_column_major_slice_mut(b, self.n, 1);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
}

impl Ldlt {
    /// [`Ldlt::solve_refined`] for `k` right-hand sides (column-major `n × k` in `b` and `x`),
    /// each column solved and refined on its own. Residuals are
    /// componentwise backward errors `ω = max_i |b − K x|_i / (|K||x| + |b|)_i` (Oettli–Prager:
    /// the smallest relative change of the entries of K and b that x solves exactly). A column
    /// keeps its best iterate; its refinement stops once `ω ≤ tol`, after `max_steps` (at least
    /// 1), or after a step that did not halve ω (the round-off floor). Returns ω of each column.
    ///
    /// # Panics
    /// If the dimensions disagree (caller bug).
    pub fn solve_refined_many(
        &self,
        matrix: &SymCsc,
        b: &[f64],
        x: &mut [f64],
        max_steps: usize,
        tol: f64,
    ) -> Vec<f64> {
        let n = self.n;
        assert_eq!(matrix.n, n, "Ldlt::solve_refined_many: matrix dimension");
        assert_eq!(b.len(), x.len(), "Ldlt::solve_refined_many: b and x");
        if n == 0 {
            return Vec::new();
        }
        // One column at a time: faer's multi-column solve does not give a column the bits of a
        // single-column solve, and a rerun of one multiplier space must reproduce the full run's
        // numbers bit for bit (tests/python/test_campaign.py).
        b.chunks_exact(n)
            .zip(x.chunks_exact_mut(n))
            .map(|(bj, xj)| self.refine_column(matrix, bj, xj, max_steps, tol))
            .collect()
    }

    /// Solve and refine one right-hand side on the componentwise backward error (see
    /// [`Ldlt::solve_refined_many`]); returns the best ω.
    fn refine_column(
        &self,
        matrix: &SymCsc,
        b: &[f64],
        x: &mut [f64],
        max_steps: usize,
        tol: f64,
    ) -> f64 {
        let n = self.n;
        x.copy_from_slice(b);
        self.solve_in_place(x);
        let mut r = vec![0.0; n];
        let mut kx = vec![0.0; n];
        let mut scale = vec![0.0; n];
        // r = b − K x and ω = max_i |r_i| / (|K||x| + |b|)_i
        let mut residual = |x: &[f64], r: &mut [f64]| -> f64 {
            matrix.mul_vec_with_abs(x, &mut kx, &mut scale);
            for i in 0..n {
                r[i] = b[i] - kx[i];
                scale[i] += b[i].abs();
            }
            componentwise_backward_error(r, &scale)
        };
        let mut omega = residual(x, &mut r);
        let mut best = omega;
        let mut best_x = x.to_vec();
        for step in 0..max_steps.max(1) {
            if (step > 0 && best <= tol) || !omega.is_finite() {
                break;
            }
            self.solve_in_place(&mut r);
            x.iter_mut().zip(&r).for_each(|(xi, di)| *xi += di);
            omega = residual(x, &mut r);
            let halved = omega < 0.5 * best;
            if omega < best {
                best = omega;
                best_x.copy_from_slice(x);
            }
            // a step that does not halve ω means the round-off floor: another would not help
            if !halved {
                break;
            }
        }
        x.copy_from_slice(&best_x);
        best
    }
}

/// The componentwise (Oettli–Prager) backward error `max_i |r_i| / scale_i` of a residual `r`
/// whose rows have the sizes `scale` (e.g. `(|K||x| + |b|)_i`): 0/0 counts as 0, a non-zero
/// residual over a zero scale as ∞, and a NaN residual gives NaN.
pub fn componentwise_backward_error(residual: &[f64], scale: &[f64]) -> f64 {
    let mut omega = 0.0f64;
    for (&r, &d) in residual.iter().zip(scale) {
        if r.is_nan() {
            return f64::NAN;
        }
        if r != 0.0 {
            omega = omega.max(if d > 0.0 { r.abs() / d } else { f64::INFINITY });
        }
    }
    omega
}

impl Ldlt {
    /// An estimate of `‖K⁻¹‖₁` of the factored matrix, for the condition number
    /// `κ₁(K) = ‖K‖₁ ‖K⁻¹‖₁` (`‖K‖₁` by [`SymCsc::norm1`]).
    ///
    /// Hager's method as refined by Higham (LAPACK `dlacon`; Higham, ACM TOMS 14, 1988), at most
    /// [`CONDITION_ITERATIONS`] iterations, each two solves (`K` is symmetric, so `K⁻ᵀ = K⁻¹`),
    /// plus Higham's alternating-sign test vector, solved together with the first. The result is
    /// a lower bound of the true norm, usually within a factor 3.
    pub fn inverse_norm1_estimate(&self) -> f64 {
        let mut probes = condition_probes(self.n);
        self.solve_many_in_place(&mut probes, 2);
        self.inverse_norm1_from_probes(&probes)
    }

    /// [`Ldlt::inverse_norm1_estimate`] given `K⁻¹` applied to the two [`condition_probes`]
    /// (column-major `n × 2`).
    ///
    /// # Panics
    /// If `solved_probes.len() != 2 n` (caller bug).
    fn inverse_norm1_from_probes(&self, solved_probes: &[f64]) -> f64 {
        let n = self.n;
        assert_eq!(solved_probes.len(), 2 * n, "condition probes: n × 2");
        if n == 0 {
            return 0.0;
        }
        let norm1 = |v: &[f64]| v.iter().map(|a| a.abs()).sum::<f64>();
        let block = solved_probes;
        let alternating = 2.0 * norm1(&block[n..]) / (3.0 * n as f64);
        let mut y = block[..n].to_vec();
        let mut x = vec![1.0 / n as f64; n];
        let mut estimate = norm1(&y);
        for _ in 0..CONDITION_ITERATIONS {
            let mut z: Vec<f64> = y
                .iter()
                .map(|&v| if v >= 0.0 { 1.0 } else { -1.0 })
                .collect();
            self.solve_in_place(&mut z);
            let ztx: f64 = z.iter().zip(&x).map(|(a, b)| a * b).sum();
            let (j, zj) = z.iter().enumerate().fold((0, 0.0f64), |(bj, bv), (i, &v)| {
                if v.abs() > bv {
                    (i, v.abs())
                } else {
                    (bj, bv)
                }
            });
            if zj.is_nan() || zj <= ztx {
                break;
            }
            x.fill(0.0);
            x[j] = 1.0;
            y.copy_from_slice(&x);
            self.solve_in_place(&mut y);
            let next = norm1(&y);
            if next.is_nan() || next <= estimate {
                break;
            }
            estimate = next;
        }
        estimate.max(alternating)
    }
}

/// Hager–Higham iterations of [`Ldlt::inverse_norm1_estimate`] (LAPACK uses at most 5). One
/// iteration (two solves after the probes) is used: each further one costs two solves per δ,
/// measured 10 % of a numeric factorisation at 10⁵ vertices, and rarely raises the estimate
/// (Higham 1988: the first iteration's estimate is usually within a factor 3).
pub const CONDITION_ITERATIONS: usize = 1;

/// The two right-hand sides whose solves start [`Ldlt::inverse_norm1_estimate`], column-major
/// `n × 2`: `1/n` (Hager's start) and Higham's `(−1)^i (1 + i/(n−1))`.
fn condition_probes(n: usize) -> Vec<f64> {
    let mut block = vec![1.0 / n.max(1) as f64; 2 * n];
    for i in 0..n {
        let t = if n > 1 {
            i as f64 / (n - 1) as f64
        } else {
            0.0
        };
        block[n + i] = if i % 2 == 0 { 1.0 + t } else { -(1.0 + t) };
    }
    block
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
/// Fresh memory is expensive on these machines: the first touch of each page (here, by the
/// zeroing) cost ~2.2 s per GB in the measurements of docs/performance.md, with or without
/// transparent huge pages or `MADV_POPULATE_WRITE` (both tried, neither faster). That is why a
/// δ sweep refactors into the previous δ's buffer ([`Ldlt::refactor`]).
fn factor_buffer(len: usize) -> Result<Vec<f64>, LinalgError> {
    let mut values: Vec<f64> = Vec::new();
    values
        .try_reserve_exact(len)
        .map_err(|_| LinalgError::Numeric("out of memory for the factor".into()))?;
    values.resize(len, 0.0);
    Ok(values)
}

/// `r = b − K x`, returns `‖r‖_∞`.
fn residual(matrix: &SymCsc, b: &[f64], x: &[f64], r: &mut [f64]) -> f64 {
    matrix.mul_vec(x, r);
    r.iter_mut().zip(b).for_each(|(ri, bi)| *ri = bi - *ri);
    inf_norm(r)
}

/// `‖v‖_∞`, NaN-propagating.
fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, &a| {
        if a.is_nan() || m.is_nan() {
            f64::NAN
        } else {
            m.max(a.abs())
        }
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64: deterministic test randomness without extra dependencies.
    struct Rng(u64);
    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        /// Uniform in [-1, 1).
        fn uniform(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next_u64() % n as u64) as usize
        }
    }

    /// Dense row-major copy of the full symmetric matrix.
    fn dense(m: &SymCsc) -> Vec<f64> {
        let n = m.n;
        let mut a = vec![0.0; n * n];
        for j in 0..n {
            for p in m.col_ptr[j]..m.col_ptr[j + 1] {
                let i = m.row_idx[p];
                a[i * n + j] = m.values[p];
                a[j * n + i] = m.values[p];
            }
        }
        a
    }

    /// Dense Gaussian elimination with partial pivoting (row-major `a`).
    fn dense_solve(mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
                .unwrap();
            for c in 0..n {
                a.swap(k * n + c, p * n + c);
            }
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i * n + k] / a[k * n + k];
                for c in k..n {
                    a[i * n + c] -= f * a[k * n + c];
                }
                b[i] -= f * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|c| a[k * n + c] * x[c]).sum();
            x[k] = (b[k] - s) / a[k * n + k];
        }
        x
    }

    fn rel_residual(m: &SymCsc, b: &[f64], x: &[f64]) -> f64 {
        let mut r = vec![0.0; m.n];
        residual(m, b, x, &mut r) / inf_norm(b)
    }

    fn random_vec(rng: &mut Rng, n: usize) -> Vec<f64> {
        (0..n).map(|_| rng.uniform()).collect()
    }

    /// Random sparse SPD matrix: random symmetric off-diagonals, diagonally dominant.
    fn random_spd(n: usize, per_row: usize, seed: u64) -> SymCsc {
        let mut rng = Rng(seed);
        let mut trip = Vec::new();
        let mut rowsum = vec![0.0; n];
        for i in 0..n {
            for _ in 0..per_row {
                let j = rng.below(n);
                if j != i {
                    let v = rng.uniform();
                    trip.push((i, j, v));
                    rowsum[i] += v.abs();
                    rowsum[j] += v.abs();
                }
            }
        }
        for (i, s) in rowsum.iter().enumerate() {
            trip.push((i, i, s + 0.5 + rng.uniform().abs()));
        }
        SymCsc::from_triplets(n, &trip).unwrap()
    }

    /// Quasi-definite saddle matrix `[[G, Bᵀ], [B, −s_scale·S]]` on an `m × m` grid:
    /// `G` = 5-point Laplacian + I (SPD), `S` = Neumann 5-point Laplacian (singular,
    /// constants in its kernel), `B` = identity coupling + two random couplings to
    /// nearby grid nodes (full row rank, so `K` is nonsingular even for
    /// `s_scale = 0`). Returns `(K, signs, n_g)`.
    fn saddle_scaled(m: usize, seed: u64, s_scale: f64) -> (SymCsc, Vec<i8>, usize) {
        let mut rng = Rng(seed);
        let ng = m * m;
        let ns = m * m;
        let id = |i: usize, j: usize| i * m + j;
        let mut trip = Vec::new();
        for i in 0..m {
            for j in 0..m {
                let k = id(i, j);
                trip.push((k, k, 4.0 + 1.0));
                let mut deg = 0.0;
                for (ii, jj) in [(i + 1, j), (i, j + 1)] {
                    if ii < m && jj < m {
                        let l = id(ii, jj);
                        trip.push((l, k, -1.0));
                        trip.push((ng + l, ng + k, s_scale));
                    }
                }
                for (ii, jj) in [
                    (i.wrapping_sub(1), j),
                    (i + 1, j),
                    (i, j.wrapping_sub(1)),
                    (i, j + 1),
                ] {
                    if ii < m && jj < m {
                        deg += 1.0;
                    }
                }
                trip.push((ng + k, ng + k, -s_scale * deg));
                trip.push((ng + k, k, 1.0));
                for _ in 0..2 {
                    let ii = (i + rng.below(3)).saturating_sub(1).min(m - 1);
                    let jj = (j + rng.below(3)).saturating_sub(1).min(m - 1);
                    trip.push((ng + k, id(ii, jj), 0.3 * rng.uniform()));
                }
            }
        }
        let signs = (0..ng + ns).map(|i| if i < ng { 1 } else { -1 }).collect();
        (SymCsc::from_triplets(ng + ns, &trip).unwrap(), signs, ng)
    }

    fn saddle(m: usize, seed: u64) -> (SymCsc, Vec<i8>, usize) {
        saddle_scaled(m, seed, 1.0)
    }

    #[test]
    fn random_spd_matches_dense() {
        let n = 200;
        let k = random_spd(n, 3, 7);
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        let f = Ldlt::factor(&sym, &k, &vec![1; n]).unwrap();
        assert_eq!(f.stats().positive_pivots, n);
        assert_eq!(f.stats().regularized_pivots, 0);
        let mut rng = Rng(3);
        let b = random_vec(&mut rng, n);
        let mut x = b.clone();
        f.solve_in_place(&mut x);
        let res = rel_residual(&k, &b, &x);
        assert!(res < 1e-12, "residual {res}");
        let xd = dense_solve(dense(&k), b.clone());
        let err = x
            .iter()
            .zip(&xd)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / inf_norm(&xd);
        assert!(err < 1e-12, "difference to dense solve {err}");
    }

    fn check_saddle(m: usize) {
        let (k, signs, ng) = saddle(m, 11);
        let n = k.n;
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        assert!(sym.factor_nnz() >= k.row_idx.len());
        let f = Ldlt::factor(&sym, &k, &signs).unwrap();
        let st = f.stats();
        assert_eq!(st.positive_pivots, ng, "{st:?}");
        assert_eq!(st.negative_pivots, n - ng, "{st:?}");
        assert!(st.min_abs_pivot > 0.0 && st.max_abs_pivot.is_finite());
        let mut rng = Rng(5);
        let b = random_vec(&mut rng, n);
        let mut x = vec![0.0; n];
        let rel = f.solve_refined(&k, &b, &mut x, 10, 1e-14);
        let check = rel_residual(&k, &b, &x);
        assert_eq!(rel, check);
        assert!(rel < 1e-12, "m = {m}: residual {rel}, stats {st:?}");
        // b = 0 gives x = 0.
        let mut z = vec![1.0; n];
        assert_eq!(f.solve_refined(&k, &vec![0.0; n], &mut z, 3, 1e-14), 0.0);
        assert!(z.iter().all(|&v| v == 0.0));
    }

    /// `trailing_inverse` agrees with column-by-column solves, on the simplicial (m = 10) and
    /// supernodal (m = 60) paths, and refuses unknowns that are not eliminated last.
    #[test]
    fn trailing_inverse_matches_solves() {
        for m in [10, 60] {
            let (k, signs, _) = saddle(m, 5);
            let n = k.n;
            let picked: Vec<usize> = (0..n).filter(|i| i % 7 == 2).take(12).collect();
            let mut order: Vec<usize> = (0..n).filter(|i| !picked.contains(i)).collect();
            order.extend(picked.iter().rev());
            let sym = SymbolicLdlt::analyze_ordered(&k, &order).unwrap();
            let f = Ldlt::factor(&sym, &k, &signs).unwrap();
            let inv = f.trailing_inverse(&picked).unwrap();
            let c = picked.len();
            let mut worst = 0.0f64;
            let mut scale = 0.0f64;
            for (b, &j) in picked.iter().enumerate() {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                f.solve_in_place(&mut e);
                for (a, &i) in picked.iter().enumerate() {
                    worst = worst.max((inv[a * c + b] - e[i]).abs());
                    scale = scale.max(e[i].abs());
                }
            }
            assert!(worst <= 1e-12 * scale, "m = {m}: {worst:e} vs {scale:e}");
            assert!(f.trailing_inverse(&[0]).is_none() || order[n - 1] == 0);
            let amd = Ldlt::factor(&SymbolicLdlt::analyze(&k).unwrap(), &k, &signs).unwrap();
            let trailing_amd = amd.symbolic.perm().unwrap().arrays().0[n - 1];
            assert!(amd.trailing_inverse(&[trailing_amd]).is_some());
            assert!(amd.trailing_inverse(&[(trailing_amd + 1) % n]).is_none());
        }
        let (k, _, _) = saddle(10, 5);
        assert!(SymbolicLdlt::analyze_ordered(&k, &[0, 0]).is_err());
        let mut order: Vec<usize> = (0..k.n).collect();
        order[1] = 0;
        assert!(SymbolicLdlt::analyze_ordered(&k, &order).is_err());
    }

    #[test]
    fn cholesky_solve_matches_ldlt() {
        let k = random_spd(300, 4, 9);
        let mut rng = Rng(4);
        let b = random_vec(&mut rng, k.n);
        let mut x = b.clone();
        let t = cholesky_solve(&k, &mut x).unwrap();
        assert!(t.factor_nnz >= k.n);
        assert!(rel_residual(&k, &b, &x) < 1e-13);
        let mut not_spd = k.clone();
        not_spd.values.iter_mut().for_each(|v| *v = -*v);
        assert!(cholesky_solve(&not_spd, &mut x).is_err());
    }

    #[test]
    fn refactor_and_block_refinement_match_single_solves() {
        let (k, signs, _) = saddle(60, 3);
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        let first = Ldlt::factor(&sym, &k, &signs).unwrap();
        let mut shifted = k.clone();
        shifted.values.iter_mut().for_each(|v| *v *= 1.5);
        let again = Ldlt::refactor(&sym, &shifted, &signs, Some(first)).unwrap();
        let fresh = Ldlt::factor(&sym, &shifted, &signs).unwrap();
        assert_eq!(again.values, fresh.values);
        let mut rng = Rng(8);
        let mut b = random_vec(&mut rng, 3 * k.n);
        b[k.n..2 * k.n].fill(0.0);
        let mut x = vec![0.0; b.len()];
        let rel = again.solve_refined_many(&shifted, &b, &mut x, 3, 1e-15);
        assert_eq!(rel.len(), 3);
        assert_eq!(rel[1], 0.0);
        for j in [0, 2] {
            let cols = j * k.n..(j + 1) * k.n;
            assert!(rel[j] < 1e-14, "{rel:?}");
            assert!(rel_residual(&shifted, &b[cols.clone()], &x[cols]) < 1e-14);
        }
        assert!(x[k.n..2 * k.n].iter().all(|&v| v == 0.0));
    }

    /// The estimate is a lower bound of κ₁ from the dense inverse, and within a factor 3 of it.
    #[test]
    fn condition_estimate_brackets_the_dense_condition_number() {
        for (m, seed) in [(10, 1), (60, 2)] {
            let (k, signs, _) = saddle(m, seed);
            let f = Ldlt::factor(&SymbolicLdlt::analyze(&k).unwrap(), &k, &signs).unwrap();
            let n = k.n;
            let mut inv_norm1 = 0.0f64;
            for j in 0..n {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                f.solve_in_place(&mut e);
                inv_norm1 = inv_norm1.max(e.iter().map(|v| v.abs()).sum());
            }
            let a = dense(&k);
            let k_norm1 = (0..n)
                .map(|j| (0..n).map(|i| a[i * n + j].abs()).sum::<f64>())
                .fold(0.0, f64::max);
            assert!((k.norm1() - k_norm1).abs() <= 1e-12 * k_norm1);
            let exact = k_norm1 * inv_norm1;
            let est = k.norm1() * f.inverse_norm1_estimate();
            assert!(
                est <= exact * (1.0 + 1e-10) && est >= exact / 3.0,
                "m = {m}: {est:e} vs {exact:e}"
            );
        }
    }

    #[test]
    fn componentwise_backward_error_conventions() {
        assert_eq!(
            componentwise_backward_error(&[0.0, 1e-16], &[0.0, 1.0]),
            1e-16
        );
        assert_eq!(componentwise_backward_error(&[-2.0, 1.0], &[4.0, 8.0]), 0.5);
        assert_eq!(
            componentwise_backward_error(&[1e-300], &[0.0]),
            f64::INFINITY
        );
        assert!(componentwise_backward_error(&[0.0, f64::NAN], &[1.0, 1.0]).is_nan());
    }

    #[test]
    fn saddle_m10() {
        check_saddle(10);
    }

    #[test]
    fn saddle_m60() {
        check_saddle(60);
    }

    /// Pure saddle point (`S = 0`): AMD eliminates many `S` rows before their
    /// `G` neighbours, so zero pivots appear and are regularized to `−delta`
    /// (simplicial path for m = 20, supernodal for m = 60); refinement against the
    /// exact matrix recovers full accuracy.
    #[test]
    fn zero_s_block_is_regularized_and_refined() {
        for m in [20, 60] {
            let (k, signs, ng) = saddle_scaled(m, 11, 0.0);
            let sym = SymbolicLdlt::analyze(&k).unwrap();
            let f = Ldlt::factor(&sym, &k, &signs).unwrap();
            let st = f.stats();
            assert!(st.regularized_pivots > 0, "{st:?}");
            assert_eq!(st.positive_pivots, ng, "{st:?}");
            assert_eq!(st.negative_pivots, k.n - ng, "{st:?}");
            let mut rng = Rng(2);
            let b = random_vec(&mut rng, k.n);
            let mut x = vec![0.0; k.n];
            let rel = f.solve_refined(&k, &b, &mut x, 10, 1e-14);
            assert!(rel < 1e-12, "m = {m}: residual {rel}");
        }
    }

    #[test]
    fn wrong_sign_and_singular_pivots_are_regularized() {
        // [[1, 0], [0, 0]] with signs (+, -): second pivot is zero -> -delta.
        let k = SymCsc::from_triplets(2, &[(0, 0, 1.0), (1, 1, 0.0), (1, 0, 0.0)]).unwrap();
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        let f = Ldlt::factor(&sym, &k, &[1, -1]).unwrap();
        assert_eq!(f.stats().regularized_pivots, 1);
        assert_eq!(f.stats().negative_pivots, 1);
        assert_eq!(f.stats().min_abs_pivot, PIVOT_DELTA_REL);
        // diag(1, 2) with signs (+, -): wrong sign -> -delta.
        let k2 = SymCsc::from_triplets(2, &[(0, 0, 1.0), (1, 1, 2.0), (1, 0, 0.0)]).unwrap();
        let f2 = Ldlt::factor(&sym, &k2, &[1, -1]).unwrap();
        assert_eq!(f2.stats().regularized_pivots, 1);
        assert_eq!(f2.stats().negative_pivots, 1);
    }

    #[test]
    fn symbolic_reuse_and_same_pattern() {
        let (k1, signs, _) = saddle(12, 1);
        let mut k2 = k1.clone();
        let mut rng = Rng(9);
        // Same pattern, different values: scale G rows / perturb couplings.
        for j in 0..k2.n {
            for p in k2.col_ptr[j]..k2.col_ptr[j + 1] {
                if k2.row_idx[p] != j {
                    k2.values[p] *= 1.0 + 0.2 * rng.uniform();
                } else {
                    k2.values[p] *= 1.5;
                }
            }
        }
        assert!(k1.same_pattern(&k2));
        let sym = SymbolicLdlt::analyze(&k1).unwrap();
        for k in [&k1, &k2] {
            let f = Ldlt::factor(&sym, k, &signs).unwrap();
            let b = random_vec(&mut rng, k.n);
            let mut x = vec![0.0; k.n];
            let rel = f.solve_refined(k, &b, &mut x, 5, 1e-15);
            assert!(rel < 1e-12, "residual {rel}");
        }
        // Different pattern: detected by same_pattern and refused by factor.
        let mut trip = Vec::new();
        for j in 0..k1.n {
            for p in k1.col_ptr[j]..k1.col_ptr[j + 1] {
                trip.push((k1.row_idx[p], j, k1.values[p]));
            }
        }
        trip.push((k1.n - 1, 0, 0.0));
        let k3 = SymCsc::from_triplets(k1.n, &trip).unwrap();
        assert!(!k1.same_pattern(&k3));
        assert!(!k1.same_pattern(&random_spd(5, 2, 1)));
        assert!(matches!(
            Ldlt::factor(&sym, &k3, &signs),
            Err(LinalgError::PatternMismatch)
        ));
        assert!(matches!(
            Ldlt::factor(&sym, &k1, &signs[1..]),
            Err(LinalgError::Dimension { .. })
        ));
        let mut bad = signs.clone();
        bad[3] = 0;
        assert!(matches!(
            Ldlt::factor(&sym, &k1, &bad),
            Err(LinalgError::InvalidSign { index: 3, value: 0 })
        ));
        let mut nan = k1.clone();
        nan.values[0] = f64::NAN;
        assert!(matches!(
            Ldlt::factor(&sym, &nan, &signs),
            Err(LinalgError::NonFinite)
        ));
        let mut broken = k1.clone();
        broken.row_idx.swap(0, 1);
        assert!(SymbolicLdlt::analyze(&broken).is_err());
    }

    #[test]
    fn solve_many_matches_single_solves() {
        // (15, 7): one sequential block; (20, 100): 800 × 100 rhs, split over threads
        // whenever the rayon pool has more than one thread.
        for (m, ncols) in [(15, 7), (20, 100)] {
            let (k, signs, _) = saddle(m, 4);
            let n = k.n;
            let sym = SymbolicLdlt::analyze(&k).unwrap();
            let f = Ldlt::factor(&sym, &k, &signs).unwrap();
            let mut rng = Rng(8);
            let b = random_vec(&mut rng, n * ncols);
            let mut many = b.clone();
            f.solve_many_in_place(&mut many, ncols);
            for c in 0..ncols {
                let mut one = b[c * n..(c + 1) * n].to_vec();
                f.solve_in_place(&mut one);
                let scale = inf_norm(&one);
                for (a, s) in many[c * n..(c + 1) * n].iter().zip(&one) {
                    assert!((a - s).abs() <= 1e-13 * scale, "column {c}: {a} vs {s}");
                }
            }
            f.solve_many_in_place(&mut [], 0);
        }
    }

    #[test]
    fn from_triplets_sums_mirrors_and_multiplies() {
        let n = 4;
        let trip = [
            (0, 0, 2.0),
            (0, 0, 1.0), // duplicate: 3
            (0, 2, 1.5), // upper: mirrored to (2, 0)
            (2, 0, 0.5), // same lower entry: 2.0 in total
            (3, 1, -1.0),
            (1, 1, 4.0),
            (3, 3, 5.0),
            (2, 2, 6.0),
            (3, 2, 0.0), // explicit zero kept in the pattern
        ];
        let k = SymCsc::from_triplets(n, &trip).unwrap();
        assert_eq!(k.col_ptr, vec![0, 2, 4, 6, 7]);
        assert_eq!(k.row_idx, vec![0, 2, 1, 3, 2, 3, 3]);
        assert_eq!(k.values, vec![3.0, 2.0, 4.0, -1.0, 6.0, 0.0, 5.0]);
        let a = dense(&k);
        let x = [1.0, -2.0, 0.5, 3.0];
        let mut y = [0.0; 4];
        k.mul_vec(&x, &mut y);
        for i in 0..n {
            let yi: f64 = (0..n).map(|j| a[i * n + j] * x[j]).sum();
            assert!((y[i] - yi).abs() < 1e-15);
        }
        assert_eq!(a[2], 2.0);
        assert_eq!(a[2 * n], 2.0);
        // Random larger check against the dense product.
        let big = random_spd(50, 4, 2);
        let ad = dense(&big);
        let mut rng = Rng(1);
        let x = random_vec(&mut rng, 50);
        let mut y = vec![0.0; 50];
        big.mul_vec(&x, &mut y);
        for i in 0..50 {
            let yi: f64 = (0..50).map(|j| ad[i * 50 + j] * x[j]).sum();
            assert!((y[i] - yi).abs() < 1e-12);
        }
        assert!(matches!(
            SymCsc::from_triplets(2, &[(2, 0, 1.0)]),
            Err(LinalgError::IndexOutOfBounds {
                row: 2,
                col: 0,
                n: 2
            })
        ));
        assert!(matches!(
            SymCsc::from_triplets(2, &[(1, 0, f64::INFINITY)]),
            Err(LinalgError::NonFinite)
        ));
    }

    #[test]
    fn empty_matrix() {
        let k = SymCsc::from_triplets(0, &[]).unwrap();
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        let f = Ldlt::factor(&sym, &k, &[]).unwrap();
        let mut x: Vec<f64> = vec![];
        assert_eq!(f.solve_refined(&k, &[], &mut x, 2, 1e-12), 0.0);
        f.solve_in_place(&mut x);
    }
}
