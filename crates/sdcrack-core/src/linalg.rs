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
//! later pivots: with `S = 0`, tinier values give huge pivots (even non-finite ones)
//! and refinement stalls far above round-off, while `1e-6` refines to round-off.
//! With a semi-definite
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

mod cholesky;
mod csc;
mod error;
mod estimate;
mod ldlt;
mod refine;
#[cfg(test)]
mod tests;

pub use cholesky::{cholesky_solve, Cholesky, CholeskyTimings};
pub use csc::SymCsc;
pub use error::LinalgError;
pub use estimate::CONDITION_ITERATIONS;
pub use ldlt::{FactorStats, Ldlt, SymbolicLdlt};
pub use refine::componentwise_backward_error;
