//! faer's sparse Cholesky `LLᵀ` of an SPD [`SymCsc`] with its default settings (AMD
//! ordering): the plain direct solve that `sdcrack bench` uses as its yardstick, and the
//! preconditioner of [`crate::krylov`]. Times are wall-clock seconds.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par, Side, Spec};

use super::csc::SymCsc;
use super::error::LinalgError;
use super::ldlt::factor_buffer;

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
