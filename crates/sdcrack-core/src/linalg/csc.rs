//! The symmetric sparse matrix [`SymCsc`]: lower triangle in compressed sparse columns, its
//! construction from triplets, norms and products, the checks of its invariants and its
//! faer view.

use faer::sparse::SymbolicSparseColMatRef;

use super::error::LinalgError;
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
    /// The full matrix as dense rows (both triangles): for tests on small systems.
    #[cfg(test)]
    pub(crate) fn to_dense_rows(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.n]; self.n];
        for c in 0..self.n {
            for idx in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = self.row_idx[idx];
                d[r][c] += self.values[idx];
                if r != c {
                    d[c][r] += self.values[idx];
                }
            }
        }
        d
    }

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
    pub(super) fn validate(&self) -> Result<(), LinalgError> {
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
    pub(super) fn pattern_hash(&self) -> u64 {
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
    pub(super) fn faer_symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}
