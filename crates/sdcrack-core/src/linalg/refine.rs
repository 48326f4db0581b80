//! Iterative refinement of [`Ldlt`] solves against the exact (unregularized) matrix: on the
//! max-norm residual for one right-hand side ([`Ldlt::solve_refined`]), on the componentwise
//! (Oettli–Prager) backward error column by column ([`Ldlt::solve_refined_many`]).

use super::csc::SymCsc;
use super::ldlt::Ldlt;

/// Refinement stops after this many consecutive steps without a new best residual.
const STAGNATION_STEPS: usize = 2;

impl Ldlt {
    /// The unrefined solve `x = K⁻¹ b`; returns a zeroed residual buffer of the dimension.
    fn first_solve(&self, b: &[f64], x: &mut [f64]) -> Vec<f64> {
        x.copy_from_slice(b);
        self.solve_in_place(x);
        vec![0.0; self.n]
    }

    /// One refinement step given the residual `r = b − K x`: `x += K⁻¹ r` (`r` is overwritten
    /// by the correction).
    fn correct(&self, x: &mut [f64], r: &mut [f64]) {
        self.solve_in_place(r);
        x.iter_mut().zip(&*r).for_each(|(xi, di)| *xi += di);
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
        let relative_residual = |x: &[f64], r: &mut [f64]| residual(matrix, b, x, r) / b_norm;
        let mut stagnant = 0;
        let not_stagnant = |rel: f64, best_rel: f64| {
            if rel < best_rel {
                stagnant = 0;
            } else {
                stagnant += 1;
            }
            stagnant < STAGNATION_STEPS
        };
        self.refine_keeping_best(b, x, max_steps, tol, relative_residual, not_stagnant)
    }

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
        // a step that does not halve ω means the round-off floor: another would not help
        let halved = |omega: f64, best: f64| omega < 0.5 * best;
        b.chunks_exact(n)
            .zip(x.chunks_exact_mut(n))
            .map(|(bj, xj)| {
                let omega = backward_error(matrix, bj);
                self.refine_keeping_best(bj, xj, max_steps, tol, omega, halved)
            })
            .collect()
    }

    /// Iterative refinement that keeps the best iterate: `x = K⁻¹ b`, then steps
    /// `x += K⁻¹ (b − K x)`, each followed by `measure(x, r)`, which fills the residual
    /// `r = b − K x` and returns the measure of the error (the smaller the better). Stops before
    /// a step once the best measure is at most `tol` (not before the first step) or the current
    /// one is not finite, after `max_steps` steps (at least 1), or after a step where
    /// `go_on(measure, best before the step)` is false. Leaves the best iterate in `x` and
    /// returns its measure.
    fn refine_keeping_best(
        &self,
        b: &[f64],
        x: &mut [f64],
        max_steps: usize,
        tol: f64,
        mut measure: impl FnMut(&[f64], &mut [f64]) -> f64,
        mut go_on: impl FnMut(f64, f64) -> bool,
    ) -> f64 {
        let mut r = self.first_solve(b, x);
        let mut current = measure(x, &mut r);
        let mut best = current;
        let mut best_x = x.to_vec();
        for step in 0..max_steps.max(1) {
            if (step > 0 && best <= tol) || !current.is_finite() {
                break;
            }
            self.correct(x, &mut r);
            current = measure(x, &mut r);
            let going_on = go_on(current, best);
            if current < best {
                best = current;
                best_x.copy_from_slice(x);
            }
            if !going_on {
                break;
            }
        }
        x.copy_from_slice(&best_x);
        best
    }
}

/// The measure of [`Ldlt::solve_refined_many`]'s refinement of `K x = b`: given `x`, fills
/// `r = b − K x` and returns its componentwise backward error
/// `ω = max_i |r_i| / (|K||x| + |b|)_i`.
fn backward_error<'a>(
    matrix: &'a SymCsc,
    b: &'a [f64],
) -> impl FnMut(&[f64], &mut [f64]) -> f64 + 'a {
    let n = b.len();
    let mut kx = vec![0.0; n];
    let mut scale = vec![0.0; n];
    move |x: &[f64], r: &mut [f64]| -> f64 {
        matrix.mul_vec_with_abs(x, &mut kx, &mut scale);
        for i in 0..n {
            r[i] = b[i] - kx[i];
            scale[i] += b[i].abs();
        }
        componentwise_backward_error(r, &scale)
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

/// `r = b − K x`, returns `‖r‖_∞`.
pub(super) fn residual(matrix: &SymCsc, b: &[f64], x: &[f64], r: &mut [f64]) -> f64 {
    matrix.mul_vec(x, r);
    r.iter_mut().zip(b).for_each(|(ri, bi)| *ri = bi - *ri);
    inf_norm(r)
}

/// `‖v‖_∞`, NaN-propagating.
pub(super) fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, &a| {
        if a.is_nan() || m.is_nan() {
            f64::NAN
        } else {
            m.max(a.abs())
        }
    })
}
