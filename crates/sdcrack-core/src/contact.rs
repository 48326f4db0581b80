//! The contact solver: the linear complementarity problem of each multiplier space, reduced to the
//! crack by a Schur complement, solved by a primal–dual active set (semismooth Newton) iteration.
//!
//! With x₀ = K⁻¹b and Z = K⁻¹[Nᵀ; 0] (one block solve with the factor of K(δ)), the constraint
//! values are y = D P = S (N P₀ − H_N Sᵀ μ) with H_N = N Z_P. Writing H = S H_N Sᵀ and q = S N P₀,
//! every variant (paper (15) with (12), (13) or (14)) is the LCP
//!
//! ```text
//! μ ≥ 0,   w = H μ − q ≥ 0   (w = −D P: the constraint D P ≤ 0),   μ_i w_i = 0,
//! ```
//!
//! with H symmetric positive semidefinite and small (one row per multiplier). The active set A
//! (μ free, w = 0) is updated by A = {i : μ_i − w_i / H_ii > τ}, τ an activity tolerance of the size of
//! round-off, so that a round-off-size value never flips membership. A repeated active set that is
//! not the fixed point is a cycle: the solver then switches to Murty's least-index principal
//! pivoting, which terminates for P-matrices, and reports that it did. Non-convergence is reported,
//! never hidden.

use faer::linalg::solvers::Solve;
use faer::Mat;

/// Relative KKT residual under which a case counts as solved: the scalar and the elastic
/// study's, re-exported by [`crate::study`].
pub const KKT_TOLERANCE: f64 = 1e-10;

/// How an LCP solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LcpStatus {
    /// The active set is a fixed point and satisfies the sign conditions.
    Converged,
    /// The active-set iteration cycled; Murty's principal pivoting finished the solve.
    ConvergedAfterCycle,
    /// Neither method converged within its iteration limit.
    MaxIterations,
}

impl LcpStatus {
    /// True for the two converged outcomes.
    pub fn converged(self) -> bool {
        !matches!(self, LcpStatus::MaxIterations)
    }
    /// Short name for summaries.
    pub fn name(self) -> &'static str {
        match self {
            LcpStatus::Converged => "converged",
            LcpStatus::ConvergedAfterCycle => "converged after active-set cycle (Murty pivoting)",
            LcpStatus::MaxIterations => "not converged: iteration limit reached",
        }
    }
}

/// The result of one LCP solve.
#[derive(Clone, Debug)]
pub struct LcpSolution {
    /// The multipliers μ ≥ 0.
    pub mu: Vec<f64>,
    /// Membership of the final active set (μ free, w = 0).
    pub active: Vec<bool>,
    /// Linear solves done (active-set iterations plus pivots).
    pub iterations: usize,
    /// How it ended.
    pub status: LcpStatus,
}

impl LcpSolution {
    /// A converged solve: the multipliers of the final active set with round-off negatives
    /// clipped to 0 (μ ≥ 0 exactly).
    fn converged(mu: &[f64], active: Vec<bool>, iterations: usize, status: LcpStatus) -> Self {
        LcpSolution {
            mu: mu.iter().map(|&v| v.max(0.0)).collect(),
            active,
            iterations,
            status,
        }
    }
}

/// Dense symmetric LCP data: H (row-major m × m) and q.
#[derive(Clone, Debug)]
pub struct Lcp {
    /// Size m.
    pub m: usize,
    /// H, row-major.
    pub h: Vec<f64>,
    /// q.
    pub q: Vec<f64>,
}

/// Limits of the LCP solver.
#[derive(Clone, Copy, Debug)]
pub struct LcpOptions {
    /// Maximum active-set iterations before giving up.
    pub max_iterations: usize,
    /// Relative activity tolerance τ (times max_i |q_i| / H_ii).
    pub activity_tolerance: f64,
}

impl Default for LcpOptions {
    fn default() -> Self {
        LcpOptions {
            max_iterations: 200,
            activity_tolerance: 1e-12,
        }
    }
}

impl Lcp {
    /// H = S H_N Sᵀ and q = S q_N for a constraint map S (rows × crack nodes).
    pub fn reduce(s: &[Vec<f64>], h_n: &[f64], q_n: &[f64]) -> Lcp {
        let m = s.len();
        let n = q_n.len();
        // T = S H_N (m × n), then H = T Sᵀ.
        let mut t = vec![0.0; m * n];
        for i in 0..m {
            for (k, &sik) in s[i].iter().enumerate() {
                if sik != 0.0 {
                    for j in 0..n {
                        t[i * n + j] += sik * h_n[k * n + j];
                    }
                }
            }
        }
        let mut h = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                h[i * m + j] = (0..n).map(|k| t[i * n + k] * s[j][k]).sum();
            }
        }
        // Symmetrise away round-off.
        for i in 0..m {
            for j in 0..i {
                let a = 0.5 * (h[i * m + j] + h[j * m + i]);
                h[i * m + j] = a;
                h[j * m + i] = a;
            }
        }
        let q = s
            .iter()
            .map(|row| row.iter().zip(q_n).map(|(a, b)| a * b).sum())
            .collect();
        Lcp { m, h, q }
    }

    /// w = H μ − q.
    pub fn slack(&self, mu: &[f64]) -> Vec<f64> {
        (0..self.m)
            .map(|i| {
                let row = &self.h[i * self.m..(i + 1) * self.m];
                row.iter().zip(mu).map(|(a, b)| a * b).sum::<f64>() - self.q[i]
            })
            .collect()
    }

    /// μ with μ_A solving H_AA μ_A = q_A and μ_I = 0.
    fn solve_active(&self, active: &[bool]) -> Vec<f64> {
        let idx: Vec<usize> = (0..self.m).filter(|&i| active[i]).collect();
        let mut mu = vec![0.0; self.m];
        if idx.is_empty() {
            return mu;
        }
        let k = idx.len();
        let a = Mat::<f64>::from_fn(k, k, |i, j| self.h[idx[i] * self.m + idx[j]]);
        let b = Mat::<f64>::from_fn(k, 1, |i, _| self.q[idx[i]]);
        let x = a.partial_piv_lu().solve(&b);
        for (i, &g) in idx.iter().enumerate() {
            mu[g] = x[(i, 0)];
        }
        mu
    }

    /// Solves the LCP, starting from `warm` (an earlier active set) when given.
    pub fn solve(&self, warm: Option<&[bool]>, opts: LcpOptions) -> LcpSolution {
        let m = self.m;
        let diag: Vec<f64> = (0..m)
            .map(|i| self.h[i * m + i].max(f64::MIN_POSITIVE))
            .collect();
        let scale = (0..m)
            .map(|i| self.q[i].abs() / diag[i])
            .fold(0.0, f64::max);
        let tau = opts.activity_tolerance * scale;
        let mut active: Vec<bool> = match warm {
            Some(w) if w.len() == m => w.to_vec(),
            // Unconstrained solution violates the constraint where q_i > 0 (D P₀ > 0).
            _ => self.q.iter().map(|&q| q > 0.0).collect(),
        };
        let mut seen: Vec<Vec<bool>> = Vec::new();
        for it in 1..=opts.max_iterations {
            let mu = self.solve_active(&active);
            let w = self.slack(&mu);
            let next: Vec<bool> = (0..m).map(|i| mu[i] - w[i] / diag[i] > tau).collect();
            if next == active {
                return LcpSolution::converged(&mu, active, it, LcpStatus::Converged);
            }
            if seen.contains(&next) {
                let mut sol = self.murty(next, tau, opts.max_iterations.max(10 * m));
                sol.iterations += it;
                return sol;
            }
            seen.push(active);
            active = next;
        }
        let mu = self.solve_active(&active);
        LcpSolution {
            mu,
            active,
            iterations: opts.max_iterations,
            status: LcpStatus::MaxIterations,
        }
    }

    /// Murty's least-index principal pivoting (finite for P-matrices).
    fn murty(&self, mut active: Vec<bool>, tau: f64, max_pivots: usize) -> LcpSolution {
        for it in 1..=max_pivots {
            let mu = self.solve_active(&active);
            let w = self.slack(&mu);
            let diag = |i: usize| self.h[i * self.m + i].max(f64::MIN_POSITIVE);
            let violated = (0..self.m).find(|&i| {
                if active[i] {
                    mu[i] < -tau
                } else {
                    w[i] / diag(i) < -tau
                }
            });
            match violated {
                None => {
                    return LcpSolution::converged(&mu, active, it, LcpStatus::ConvergedAfterCycle);
                }
                Some(i) => active[i] = !active[i],
            }
        }
        let mu = self.solve_active(&active);
        LcpSolution {
            mu,
            active,
            iterations: max_pivots,
            status: LcpStatus::MaxIterations,
        }
    }
}

/// Relative KKT residuals of one discrete solution (all dimensionless).
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct KktResiduals {
    /// ‖K x + [Dᵀμ; 0] − b‖_∞ / max(‖b‖_∞, ‖Dᵀμ‖_∞).
    pub equations: f64,
    /// max(0, max_i (DP)_i) / (‖S‖_∞ ‖P‖_∞): violation of D P ≤ 0.
    pub primal: f64,
    /// max(0, −min_i μ_i) / ‖μ‖_∞: violation of μ ≥ 0.
    pub dual: f64,
    /// max_i |μ_i (DP)_i| / (‖μ‖_∞ ‖S‖_∞ ‖P‖_∞).
    pub complementarity: f64,
}

impl KktResiduals {
    /// The largest of the four.
    pub fn max(&self) -> f64 {
        self.equations
            .max(self.primal)
            .max(self.dual)
            .max(self.complementarity)
    }

    /// Feasibility and complementarity from μ, y = D P and the scale of y.
    pub fn constraint_part(mu: &[f64], y: &[f64], y_scale: f64) -> KktResiduals {
        let mu_max = mu.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let ys = if y_scale > 0.0 { y_scale } else { 1.0 };
        let ms = if mu_max > 0.0 { mu_max } else { 1.0 };
        KktResiduals {
            equations: 0.0,
            primal: y.iter().fold(0.0f64, |a, &b| a.max(b)) / ys,
            dual: mu.iter().fold(0.0f64, |a, &b| a.max(-b)) / ms,
            complementarity: mu
                .iter()
                .zip(y)
                .fold(0.0f64, |a, (m, v)| a.max((m * v).abs()))
                / (ms * ys),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The m × m matrix tridiag(−1, 2, −1), row-major (an M-matrix).
    fn laplacian_1d(m: usize) -> Vec<f64> {
        let mut h = vec![0.0; m * m];
        for i in 0..m {
            h[i * m + i] = 2.0;
            if i > 0 {
                h[i * m + i - 1] = -1.0;
                h[(i - 1) * m + i] = -1.0;
            }
        }
        h
    }

    /// A 1D Laplacian-like SPD H and a q with mixed signs: check the KKT conditions.
    #[test]
    fn solves_spd_lcp() {
        let m = 40;
        let h = laplacian_1d(m);
        let q: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
        let lcp = Lcp { m, h, q };
        let sol = lcp.solve(None, LcpOptions::default());
        assert_eq!(sol.status, LcpStatus::Converged);
        let w = lcp.slack(&sol.mu);
        for i in 0..m {
            assert!(sol.mu[i] >= 0.0);
            assert!(w[i] >= -1e-12, "w[{i}] = {}", w[i]);
            assert!((sol.mu[i] * w[i]).abs() < 1e-12);
        }
        // warm start from the solution converges in one iteration
        let again = lcp.solve(Some(&sol.active), LcpOptions::default());
        assert_eq!(again.iterations, 1);
    }

    /// Random dense SPD LCPs converge (through Murty pivoting where the active set cycles).
    #[test]
    fn dense_random_p_matrices_converge() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 10_000) as f64 / 5_000.0 - 1.0
        };
        for _ in 0..50 {
            let m = 12;
            let a: Vec<f64> = (0..m * m).map(|_| rnd()).collect();
            let mut h = vec![0.0; m * m];
            for i in 0..m {
                for j in 0..m {
                    h[i * m + j] = (0..m).map(|k| a[i * m + k] * a[j * m + k]).sum::<f64>();
                }
                h[i * m + i] += 0.1;
            }
            let q: Vec<f64> = (0..m).map(|_| rnd()).collect();
            let lcp = Lcp { m, h, q };
            let sol = lcp.solve(None, LcpOptions::default());
            assert!(sol.status.converged());
            let w = lcp.slack(&sol.mu);
            let scale = lcp.q.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            for i in 0..m {
                assert!(w[i] >= -1e-10 * scale && sol.mu[i] >= 0.0);
                assert!((sol.mu[i] * w[i]).abs() < 1e-10 * scale * scale.max(1.0) * 100.0);
            }
        }
    }

    #[test]
    fn iteration_limit_is_reported_not_hidden() {
        // Started from the empty active set, one iteration cannot reach the fixed point.
        let m = 6;
        let h = laplacian_1d(m);
        let q = vec![1.0, -1.0, 1.0, -1.0, 1.0, -1.0];
        let lcp = Lcp { m, h, q };
        let empty = vec![false; m];
        let full = lcp.solve(Some(&empty), LcpOptions::default());
        assert!(full.status.converged());
        assert!(full.iterations > 1, "needs more than one iteration");
        let short = lcp.solve(
            Some(&empty),
            LcpOptions {
                max_iterations: 1,
                ..LcpOptions::default()
            },
        );
        assert_eq!(short.status, LcpStatus::MaxIterations);
        assert!(!short.status.converged());
    }

    #[test]
    fn reduce_matches_dense_products() {
        let s = vec![vec![1.0, 2.0, 0.0], vec![0.0, 1.0, 1.0]];
        let h_n = vec![2.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 4.0];
        let q_n = vec![1.0, -1.0, 2.0];
        let l = Lcp::reduce(&s, &h_n, &q_n);
        // S H_N Sᵀ by hand: row0 = [1,2,0], row1 = [0,1,1]
        assert_eq!(l.h, vec![18.0, 9.0, 9.0, 9.0]);
        assert_eq!(l.q, vec![-1.0, 1.0]);
    }
}
