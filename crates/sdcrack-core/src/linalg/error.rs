//! [`LinalgError`]: why a sparse matrix is refused or a factorization fails; the one error type
//! of every module of the solver.

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
    /// The CSC arrays of a [`SymCsc`](super::SymCsc) violate its invariants.
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
