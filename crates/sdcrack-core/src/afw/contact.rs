//! The solve of one case ([`solve`]): dofs, assembly and factorisation of K(δ), the contact LCP
//! on the crack edges' normal dofs through [`crate::contact::Lcp`], the recovery solve, the
//! KKT residuals, the rigid motion of an all-traction boundary, and the [`AfwSolution`].
//!
//! The constraints D = S N ([`Constraints`]): N selects the crack edges' normal dofs, S is the
//! multiplier space's map (docs/design.md, "Multiplier spaces": S = I for the pointwise
//! [`MultiplierSpace::M1Star`], σ_νν ≤ 0 at both ends of every crack edge; edge means for M0;
//! hat-weighted means for M1). With x₀ = K⁻¹b, H = S N K⁻¹ Nᵀ Sᵀ (symmetric positive
//! semi-definite: K⁻¹'s σ–σ block is) and q = S N x₀, the multipliers solve the LCP μ ≥ 0,
//! w = Hμ − q ≥ 0 (w = −D σ), μ·w = 0; then K x = b − Nᵀ Sᵀ μ, and Sᵀμ are the opening moments
//! ∫_e λ_ν hat_a.

use faer::linalg::solvers::Solve;
use faer::Mat;

use super::assembly::{assemble, basis, sigma_coefficients, sigma_residuals, AfwSystem};
use super::dofs::{sigma_dof, AfwDofs, EdgeKind};
use super::element::Compliance;
use super::{AfwError, AfwSolution, CrackEdge};
use crate::contact::{KktResiduals, Lcp, LcpOptions, LcpSolution, LcpStatus};
use crate::elasticity::ElasticData;
use crate::linalg::{Ldlt, SymCsc, SymbolicLdlt};
use crate::mesh::Mesh;
use crate::problem::{Domain, MultiplierSpace};

/// Refinement steps of each solve with K(δ), at most (δ = 0 regularises the pivots of the u and
/// γ rows; refinement against the exact K removes the perturbation).
const REFINEMENT_STEPS: usize = 10;
/// Refinement stops once the componentwise backward error is ≤ this (a few ε).
const REFINEMENT_TOLERANCE: f64 = 1e-15;
/// Rounds of the LCP's refinement against the exact K, at most ([`contact_solve`]).
const LCP_REFINEMENTS: usize = 8;
/// The LCP's refinement stops once the primal and complementarity residuals of the exact σ_νν
/// are ≤ this (a thousand times below the KKT tolerance 1e-10 the tests and the study use).
const LCP_REFINEMENT_TOLERANCE: f64 = 1e-13;
/// Right-hand sides per block solve of H = N K⁻¹ Nᵀ.
const REDUCTION_BLOCK: usize = 32;

/// Solves the elastic problem `data` on `mesh` (of `domain`) with the AFW element, the contact
/// constraint of `multiplier` on the cracks and the regularisation δ = `delta` ≥ 0.
///
/// An all-traction boundary (no Dirichlet edge) at δ = 0 leaves the rigid motions as the
/// kernel of K: (u, γ) = (P0 r, −ω) for r = a + ω(−y, x) (the σ rows' (u, div τ) + (γ, as τ)
/// vanish since div τ ∈ P0: (P0 r, div τ) = (r, div τ) = ω (as τ, 1)). On such a boundary the
/// load is first made orthogonal to that kernel ([`make_compatible`], for every δ: otherwise
/// the δ-solutions' rigid part grows like 1/δ). At δ = 0 the solve then holds u and γ of
/// triangle 0 at 0 (the three unknowns' rows and columns become −I; no kernel member vanishes
/// there), and adds the rigid motion that makes u* — the element-wise P1 reconstruction
/// u_h + (A σ̄_h + γ_h J)(x − x_T), σ̄_h the mean of σ_h on T — meet the scene's fixed
/// components at its fixed points, u* at a point being the mean of its values on the triangles
/// at that vertex. The pinned triangle's dropped equations then hold too (the load is
/// compatible): the KKT residuals are those of the whole system. At δ > 0 nothing is pinned
/// and the fixed points play no part (−δM fixes the rigid part).
///
/// # Errors
/// [`AfwError`]: an invalid δ, bad data (see
/// [`AfwDofs::new`]), a factorisation failure, fixed points that leave a rigid mode free.
pub fn solve(
    mesh: &Mesh,
    domain: &Domain,
    data: &ElasticData,
    multiplier: MultiplierSpace,
    delta: f64,
) -> Result<AfwSolution, AfwError> {
    AfwCase::new(mesh, domain, data)?.solve(multiplier, delta)
}

/// One mesh's system, assembled and analysed once, for any number of solves (δ, multiplier
/// spaces): the dofs, K(0) and ∂K/∂δ, the load (made compatible on an all-traction boundary)
/// and the symbolic analysis of K's pattern, which every δ shares (pinning changes values, not
/// the pattern).
pub struct AfwCase<'a> {
    mesh: &'a Mesh,
    data: &'a ElasticData,
    dofs: AfwDofs,
    system: AfwSystem,
    /// The load b (compatible with the rigid motions on an all-traction boundary).
    rhs: Vec<f64>,
    all_traction: bool,
    symbolic: SymbolicLdlt,
    /// The constrained unknowns: the normal dofs of the crack edges, each edge's end slots 0, 1.
    rows: Vec<usize>,
}

impl<'a> AfwCase<'a> {
    /// The system of `data` on `mesh` (of `domain`).
    ///
    /// # Errors
    /// Bad data ([`AfwDofs::new`], [`assemble`]), a failed symbolic analysis.
    pub fn new(
        mesh: &'a Mesh,
        domain: &Domain,
        data: &'a ElasticData,
    ) -> Result<AfwCase<'a>, AfwError> {
        let dofs = AfwDofs::new(mesh, domain, data)?;
        let system = assemble(mesh, &dofs, data)?;
        let all_traction =
            !(dofs.edges.iter()).any(|e| matches!(e.kind, EdgeKind::Dirichlet { .. }));
        let mut rhs = system.rhs.clone();
        if all_traction {
            make_compatible(mesh, &dofs, &mut rhs);
        }
        let rows: Vec<usize> = (dofs.crack_edges.iter())
            .flat_map(|&e| [0, 1].map(|s| dofs.normal_unknown(e, s)))
            .collect();
        let symbolic = analyze_with_last(&system.base, &rows)?;
        Ok(AfwCase {
            mesh,
            data,
            dofs,
            system,
            rhs,
            all_traction,
            symbolic,
            rows,
        })
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.dofs.n()
    }

    /// The solution with the constraint of `multiplier` and the regularisation `delta` (see
    /// [`solve`]).
    ///
    /// # Errors
    /// An invalid δ, a factorisation failure,
    /// fixed points that leave a rigid mode free.
    pub fn solve(&self, multiplier: MultiplierSpace, delta: f64) -> Result<AfwSolution, AfwError> {
        if !(delta >= 0.0 && delta.is_finite()) {
            return Err(AfwError::InvalidDelta(delta));
        }
        let dofs = &self.dofs;
        let pinned: Vec<usize> = if self.all_traction && delta == 0.0 {
            (0..3).map(|k| dofs.element_unknown(0, k)).collect()
        } else {
            Vec::new()
        };
        let matrix = self.system.matrix(delta);
        let (factored, rhs) = pin(&matrix, &self.rhs, &pinned);
        let ldlt = Ldlt::factor(&self.symbolic, &factored, &self.system.signs)?;
        let constraints = Constraints::new(self.mesh, dofs, multiplier);
        let (sol, mut x) = contact_solve(
            &ldlt,
            &factored,
            &rhs,
            &self.rows,
            &constraints,
            dofs.n_sigma,
        );
        if !pinned.is_empty() {
            add_rigid_motion(self.mesh, dofs, self.data, &mut x)?;
        }
        let kkt = kkt_residuals(
            &self.rhs,
            &matrix,
            &self.rows,
            &constraints,
            &sol,
            &x,
            dofs.n_sigma,
        );
        let crack = (multiplier, constraints.row_of_end.as_slice());
        Ok(solution(
            self.mesh,
            dofs,
            &self.system,
            self.data,
            crack,
            sol,
            x,
            kkt,
            delta,
        ))
    }
}

/// The symbolic analysis of K in an order that eliminates the unknowns `last` last: AMD of K
/// without them, then them in their order. The factor's trailing block then gives
/// H_N = N K⁻¹ Nᵀ in O(m³) ([`Ldlt::trailing_inverse`]) instead of a solve per crack dof.
fn analyze_with_last(k: &SymCsc, last: &[usize]) -> Result<SymbolicLdlt, AfwError> {
    if last.is_empty() {
        return Ok(SymbolicLdlt::analyze(k)?);
    }
    let mut is_last = vec![false; k.n];
    for &i in last {
        is_last[i] = true;
    }
    let kept: Vec<usize> = (0..k.n).filter(|&i| !is_last[i]).collect();
    let mut new_index = vec![usize::MAX; k.n];
    for (j, &i) in kept.iter().enumerate() {
        new_index[i] = j;
    }
    let mut triplets = Vec::with_capacity(k.row_idx.len());
    for c in 0..k.n {
        for idx in k.col_ptr[c]..k.col_ptr[c + 1] {
            let r = k.row_idx[idx];
            if !is_last[r] && !is_last[c] {
                triplets.push((new_index[r], new_index[c], 1.0));
            }
        }
    }
    let reduced = SymCsc::from_triplets(kept.len(), &triplets)?;
    let order: Vec<usize> = (SymbolicLdlt::analyze(&reduced)?.order().into_iter())
        .map(|i| kept[i])
        .chain(last.iter().copied())
        .collect();
    Ok(SymbolicLdlt::analyze_ordered(k, &order)?)
}

/// Makes b orthogonal to the kernel of K(0) on an all-traction boundary, the rigid motions
/// k_r = (σ = 0, u = P0 r, γ = −ω) for r = a + ω(−y, x). Then b·k_r = −(f, P0 r) − ∮ r·t_h (t_h the
/// traction interpolant, the essential σ moved over), while equilibrium of the data is
/// (f, r) + ∮ r·t = 0: the interpolant keeps ∮ r·t (r is linear on each edge), but
/// (f, P0 r) ≠ (f, r) for the rotation — an O(h²) moment imbalance that a pinned solve would
/// dump on the pinned triangle. The u rows' load −(f, v) is corrected by the P0 body force
/// Σ_j α_j r_j (a rigid-motion density, O(h²) for balanced data) with α from the 3 × 3 Gram
/// system of the P0 mass: b·k_r = 0 for all three r afterwards.
fn make_compatible(mesh: &Mesh, dofs: &AfwDofs, b: &mut [f64]) {
    let nt = dofs.triangles();
    let modes = |t: usize| {
        let c = crate::mesh::centroid(&mesh.vertices, &mesh.triangles[t]);
        // u of the three modes at T's centroid, and their γ
        [([1.0, 0.0], 0.0), ([0.0, 1.0], 0.0), ([-c[1], c[0]], -1.0)]
    };
    let area = |t: usize| {
        let [a, p, q] = mesh.triangles[t].map(|v| mesh.vertices[v]);
        0.5 * ((p[0] - a[0]) * (q[1] - a[1]) - (q[0] - a[0]) * (p[1] - a[1]))
    };
    let mut gram = Mat::<f64>::zeros(3, 3);
    let mut c = Mat::<f64>::zeros(3, 1);
    for t in 0..nt {
        let k = modes(t);
        let [ux, uy, g] = [0, 1, 2].map(|j| dofs.element_unknown(t, j));
        for i in 0..3 {
            c[(i, 0)] += b[ux] * k[i].0[0] + b[uy] * k[i].0[1] + b[g] * k[i].1;
            for j in 0..3 {
                gram[(i, j)] += area(t) * (k[i].0[0] * k[j].0[0] + k[i].0[1] * k[j].0[1]);
            }
        }
    }
    let alpha = gram.partial_piv_lu().solve(&c);
    for t in 0..nt {
        let k = modes(t);
        for d in 0..2 {
            let density: f64 = (0..3).map(|j| alpha[(j, 0)] * k[j].0[d]).sum();
            b[dofs.element_unknown(t, d)] -= area(t) * density;
        }
    }
}

/// K with the unknowns `pinned` held at 0: their rows and columns zero but the diagonal, −1,
/// and their right-hand sides 0.
fn pin(k: &SymCsc, rhs: &[f64], pinned: &[usize]) -> (SymCsc, Vec<f64>) {
    let mut k = k.clone();
    let mut rhs = rhs.to_vec();
    if pinned.is_empty() {
        return (k, rhs);
    }
    for c in 0..k.n {
        for idx in k.col_ptr[c]..k.col_ptr[c + 1] {
            let r = k.row_idx[idx];
            if pinned.contains(&r) || pinned.contains(&c) {
                k.values[idx] = if r == c { -1.0 } else { 0.0 };
            }
        }
    }
    for &i in pinned {
        rhs[i] = 0.0;
    }
    (k, rhs)
}

/// K⁻¹ b, refined against K.
fn refined(ldlt: &Ldlt, k: &SymCsc, b: &[f64]) -> Vec<f64> {
    let mut x = vec![0.0; b.len()];
    ldlt.solve_refined_many(k, b, &mut x, REFINEMENT_STEPS, REFINEMENT_TOLERANCE);
    x
}

/// The contact solve: x₀ = K⁻¹b, H = N K⁻¹ Nᵀ and q = N x₀, the LCP, x = K⁻¹(b − Nᵀμ).
///
/// At δ = 0 the factor has regularised pivots (the u and γ rows have a zero diagonal): solves
/// refined against K are exact, but H from the factor's plain solves is off by ~1e-6 relative,
/// and so would be σ_νν = 0 on the open dofs. Refining H column by column costs a refined solve
/// per crack dof; instead the LCP is refined as a whole. With μ_k the current multipliers and
/// y_k = N K⁻¹(b − Nᵀμ_k) = q − Hμ_k from a refined solve, the exact slack is
/// w(μ) = H(μ − μ_k) − y_k ≈ H̃μ − (y_k + H̃μ_k): the LCP of H̃ and q_k = y_k + H̃μ_k (warm-started
/// from the last active set) gives μ_{k+1}, a fixed-point iteration contracting like
/// ‖H̃ − H‖/‖H‖. It stops once the exact y meets the constraint part of the KKT conditions to
/// [`LCP_REFINEMENT_TOLERANCE`], or after [`LCP_REFINEMENTS`] rounds (the KKT residuals report
/// what is left). The LCP's iterations are summed over the rounds.
fn contact_solve(
    ldlt: &Ldlt,
    k: &SymCsc,
    rhs: &[f64],
    rows: &[usize],
    constraints: &Constraints,
    n_sigma: usize,
) -> (LcpSolution, Vec<f64>) {
    let x0 = refined(ldlt, k, rhs);
    let m = constraints.s.len();
    let mut sol = LcpSolution {
        mu: Vec::new(),
        active: Vec::new(),
        iterations: 0,
        status: LcpStatus::Converged,
    };
    if m == 0 {
        return (sol, x0);
    }
    let h_n = (ldlt.trailing_inverse(rows)).unwrap_or_else(|| schur_complement(ldlt, k.n, rows));
    let at_rows = |x: &[f64]| rows.iter().map(|&i| x[i]).collect::<Vec<f64>>();
    let h = Lcp::reduce(&constraints.s, &h_n, &at_rows(&x0)).h;
    let (mut mu, mut y, mut x) = (vec![0.0; m], constraints.apply(&at_rows(&x0)), x0);
    let mut warm: Option<Vec<bool>> = None;
    let mut iterations = 0;
    for _ in 0..LCP_REFINEMENTS {
        let q: Vec<f64> = (0..m)
            .map(|i| y[i] + (0..m).map(|j| h[i * m + j] * mu[j]).sum::<f64>())
            .collect();
        sol = Lcp { m, h: h.clone(), q }.solve(warm.as_deref(), LcpOptions::default());
        iterations += sol.iterations;
        warm = Some(sol.active.clone());
        mu.clone_from(&sol.mu);
        let mut b = rhs.to_vec();
        for (&i, &v) in rows.iter().zip(&constraints.transpose_apply(&mu)) {
            b[i] -= v;
        }
        x = refined(ldlt, k, &b);
        y = constraints.apply(&at_rows(&x));
        let kkt = constraints.kkt(&mu, &y, &x[..n_sigma]);
        if !sol.status.converged()
            || kkt.primal.max(kkt.complementarity) <= LCP_REFINEMENT_TOLERANCE
        {
            break;
        }
    }
    sol.iterations = iterations;
    (sol, x)
}

/// The contact constraints D = S N of a multiplier space: S's rows over the crack edges' normal
/// dofs (edge j's end slot a at 2j + a), and the row each normal dof's end is constrained by.
struct Constraints {
    /// S, one row per multiplier.
    s: Vec<Vec<f64>>,
    /// Per normal dof (2j + a): the row of S it belongs to (its end is closed when that row is
    /// outside the active set).
    row_of_end: Vec<usize>,
}

impl Constraints {
    /// The constraints of `multiplier` on the crack edges of `dofs` (docs/design.md,
    /// "Multiplier spaces"): M1Star σ_νν ≤ 0 at every end (S = I); M0 ∫_e σ_νν ≤ 0 per edge (row
    /// ℓ/2 (1, 1)); M1 ∫_Σ φ_j σ_νν ≤ 0 per crack node j with the continuous hats (row j:
    /// ℓ_e/6 (2, 1) on the normal dofs of each edge e at node j, 2 at j's end).
    fn new(mesh: &Mesh, dofs: &AfwDofs, multiplier: MultiplierSpace) -> Constraints {
        let n = 2 * dofs.crack_edges.len();
        let mut s = Vec::new();
        let mut row_of_end = vec![0; n];
        let row = |entries: &[(usize, f64)], s: &mut Vec<Vec<f64>>| {
            let mut r = vec![0.0; n];
            for &(k, v) in entries {
                r[k] += v;
            }
            s.push(r);
            s.len() - 1
        };
        match multiplier {
            MultiplierSpace::M1Star => {
                for k in 0..n {
                    row_of_end[k] = row(&[(k, 1.0)], &mut s);
                }
            }
            MultiplierSpace::M0 => {
                for (j, &e) in dofs.crack_edges.iter().enumerate() {
                    let half = 0.5 * dofs.edges[e].length;
                    let r = row(&[(2 * j, half), (2 * j + 1, half)], &mut s);
                    row_of_end[2 * j] = r;
                    row_of_end[2 * j + 1] = r;
                }
            }
            MultiplierSpace::M1 => {
                // the edges of each chain in order: node k of a chain sits between its edges
                // k − 1 and k; the end slot of the chain's node k on edge k is chain_slots[0]
                let mut j = 0;
                for chain in &mesh.cracks {
                    let edges = j..j + chain.segments();
                    for node in 0..chain.nodes.len() {
                        let mut entries = Vec::new();
                        for (edge, chain_end) in [(node.wrapping_sub(1), 1), (node, 0)] {
                            if edge >= chain.segments() {
                                continue;
                            }
                            let g = edges.start + edge;
                            let e = dofs.crack_edges[g];
                            let super::dofs::EdgeKind::Crack { chain_slots, .. } =
                                dofs.edges[e].kind
                            else {
                                unreachable!("a crack edge")
                            };
                            let sixth = dofs.edges[e].length / 6.0;
                            let (own, other) = (chain_slots[chain_end], chain_slots[1 - chain_end]);
                            entries.push((2 * g + own, 2.0 * sixth));
                            entries.push((2 * g + other, sixth));
                        }
                        let r = row(&entries, &mut s);
                        for (edge, chain_end) in [(node.wrapping_sub(1), 1), (node, 0)] {
                            if edge < chain.segments() {
                                let g = edges.start + edge;
                                let super::dofs::EdgeKind::Crack { chain_slots, .. } =
                                    dofs.edges[dofs.crack_edges[g]].kind
                                else {
                                    unreachable!("a crack edge")
                                };
                                row_of_end[2 * g + chain_slots[chain_end]] = r;
                            }
                        }
                    }
                    j = edges.end;
                }
            }
        }
        Constraints { s, row_of_end }
    }

    /// S y.
    fn apply(&self, y: &[f64]) -> Vec<f64> {
        (self.s.iter())
            .map(|r| r.iter().zip(y).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// Sᵀ μ.
    fn transpose_apply(&self, mu: &[f64]) -> Vec<f64> {
        let n = self.row_of_end.len();
        (0..n)
            .map(|k| self.s.iter().zip(mu).map(|(r, m)| r[k] * m).sum())
            .collect()
    }

    /// The constraint part of the KKT residuals: μ, y = S N σ against ‖S‖_∞ ‖σ‖_∞.
    fn kkt(&self, mu: &[f64], y: &[f64], sigma: &[f64]) -> KktResiduals {
        let s_norm = (self.s.iter())
            .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let sigma_inf = sigma.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        KktResiduals::constraint_part(mu, y, s_norm * sigma_inf)
    }
}

/// H = N K⁻¹ Nᵀ (row-major m × m) for the unknowns `rows` (N selects them) from the factor's
/// block solves with the columns of Nᵀ, symmetrised away from round-off: the fallback where the
/// factor's trailing block is not them ([`analyze_with_last`] puts them there).
fn schur_complement(ldlt: &Ldlt, n: usize, rows: &[usize]) -> Vec<f64> {
    let m = rows.len();
    let mut h = vec![0.0; m * m];
    for start in (0..m).step_by(REDUCTION_BLOCK) {
        let cols = REDUCTION_BLOCK.min(m - start);
        let mut z = vec![0.0; n * cols];
        for c in 0..cols {
            z[c * n + rows[start + c]] = 1.0;
        }
        ldlt.solve_many_in_place(&mut z, cols);
        for c in 0..cols {
            for (i, &r) in rows.iter().enumerate() {
                h[i * m + start + c] = z[c * n + r];
            }
        }
    }
    for i in 0..m {
        for j in 0..i {
            let a = 0.5 * (h[i * m + j] + h[j * m + i]);
            h[i * m + j] = a;
            h[j * m + i] = a;
        }
    }
    h
}

/// The relative KKT residuals (contact::KktResiduals): the constraint part as the scalar solver
/// defines it, y = σ_νν at the constrained dofs measured against ‖σ‖_∞ (‖S‖_∞ = 1); the equations
/// K x + Nᵀμ = b of the whole (unpinned) system by block — σ rows, u rows, γ rows — each block's
/// largest |residual| over its largest row scale (|K||x| + |Nᵀμ| + |b|)_i. Not the scalar
/// solver's componentwise (per row) backward error: a block of rows that vanishes identically
/// (the u_x rows of σ = diag(0, −1), whose σ_x dofs are zero up to round-off) has rows of scale
/// ~1e-13 whose round-off residuals make that measure O(1). The per-block measure keeps its
/// invariance under the dilations of the domain and the scaling of the data (each block scales
/// by one factor).
fn kkt_residuals(
    rhs: &[f64],
    k: &SymCsc,
    rows: &[usize],
    constraints: &Constraints,
    sol: &LcpSolution,
    x: &[f64],
    n_sigma: usize,
) -> KktResiduals {
    let n = k.n;
    let mut kx = vec![0.0; n];
    let mut scale = vec![0.0; n];
    k.mul_vec_with_abs(x, &mut kx, &mut scale);
    for i in 0..n {
        kx[i] -= rhs[i];
        scale[i] += rhs[i].abs();
    }
    let moments = constraints.transpose_apply(&sol.mu);
    for (&i, &mu) in rows.iter().zip(&moments) {
        kx[i] += mu;
        scale[i] += mu.abs();
    }
    let y = constraints.apply(&rows.iter().map(|&i| x[i]).collect::<Vec<_>>());
    let mut kkt = constraints.kkt(&sol.mu, &y, &x[..n_sigma]);
    // per block (σ rows, u rows, γ rows): a block's worst residual over its largest scale
    let u_rows = |i: &usize| *i >= n_sigma && (i - n_sigma) % 3 < 2;
    let blocks: [Vec<usize>; 3] = [
        (0..n_sigma).collect(),
        (n_sigma..n).filter(u_rows).collect(),
        (n_sigma..n).filter(|i| !u_rows(i)).collect(),
    ];
    kkt.equations = blocks
        .iter()
        .map(|rows| {
            let r = rows.iter().fold(0.0f64, |a, &i| a.max(kx[i].abs()));
            let s = rows.iter().fold(0.0f64, |a, &i| a.max(scale[i]));
            if s > 0.0 {
                r / s
            } else {
                r
            }
        })
        .fold(0.0, f64::max);
    kkt
}

/// u* of triangle `t` at the point `p`: u_h + (A σ̄_h + γ_h J)(p − x_T).
fn reconstructed_u(
    mesh: &Mesh,
    stress: &[[f64; 4]; 3],
    u: [f64; 2],
    gamma: f64,
    compliance: Compliance,
    t: usize,
    p: [f64; 2],
) -> [f64; 2] {
    let mean: [f64; 4] =
        std::array::from_fn(|r| (stress[0][r] + stress[1][r] + stress[2][r]) / 3.0);
    let mut g = compliance.apply(mean);
    g[1] += gamma;
    g[2] -= gamma;
    let c = crate::mesh::centroid(&mesh.vertices, &mesh.triangles[t]);
    let d = [p[0] - c[0], p[1] - c[1]];
    [
        u[0] + g[0] * d[0] + g[1] * d[1],
        u[1] + g[2] * d[0] + g[3] * d[1],
    ]
}

/// Adds to x the rigid motion (P0 r, −ω), r = a + ω(−y, x), that makes u* meet the fixed
/// components of `data.fixed` (least squares over the conditions; the scene's validation
/// makes them remove all three modes).
fn add_rigid_motion(
    mesh: &Mesh,
    dofs: &AfwDofs,
    data: &ElasticData,
    x: &mut [f64],
) -> Result<(), AfwError> {
    let compliance = Compliance::of(&data.material);
    let sigma = sigma_coefficients(dofs, x);
    let mut rows: Vec<([f64; 3], f64)> = Vec::new();
    for fixed in &data.fixed {
        let p = fixed.point;
        let at: Vec<usize> = (0..mesh.triangles.len())
            .filter(|&t| mesh.triangles[t].iter().any(|&v| mesh.vertices[v] == p))
            .collect();
        if at.is_empty() {
            return Err(AfwError::FixedPointNotAVertex { point: p });
        }
        let mut value = [0.0; 2];
        for &t in &at {
            let stress = triangle_stress(mesh, dofs, &sigma, t);
            let u = [0, 1].map(|k| x[dofs.element_unknown(t, k)]);
            let gamma = x[dofs.element_unknown(t, 2)];
            let v = reconstructed_u(mesh, &stress, u, gamma, compliance, t, p);
            value[0] += v[0] / at.len() as f64;
            value[1] += v[1] / at.len() as f64;
        }
        // r(p) = (a_x − ω y, a_y + ω x) must cancel u*(p) in each held component
        if fixed.components[0] {
            rows.push(([1.0, 0.0, -p[1]], -value[0]));
        }
        if fixed.components[1] {
            rows.push(([0.0, 1.0, p[0]], -value[1]));
        }
    }
    let normal = Mat::<f64>::from_fn(3, 3, |i, j| rows.iter().map(|(r, _)| r[i] * r[j]).sum());
    let right = Mat::<f64>::from_fn(3, 1, |i, _| rows.iter().map(|(r, v)| r[i] * v).sum());
    if crate::elasticity::rigid_modes_removed(&data.fixed) < 3 {
        return Err(AfwError::RigidModesLeft);
    }
    let z = normal.partial_piv_lu().solve(&right);
    let (a, omega) = ([z[(0, 0)], z[(1, 0)]], z[(2, 0)]);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let c = crate::mesh::centroid(&mesh.vertices, tri);
        // P0 r = r at the centroid (r is linear)
        x[dofs.element_unknown(t, 0)] += a[0] - omega * c[1];
        x[dofs.element_unknown(t, 1)] += a[1] + omega * c[0];
        // γ of r: ½(∂_y r_x − ∂_x r_y) = −ω
        x[dofs.element_unknown(t, 2)] -= omega;
    }
    Ok(())
}

/// σ_h of triangle `t` at its three vertices, each [σ_xx, σ_xy, σ_yx, σ_yy]: row r of Ψ_p is
/// (d_p)_r φ_p, and φ_p at vertex v is w_p where v is p's end, 0 at the other vertices.
pub(super) fn triangle_stress(
    mesh: &Mesh,
    dofs: &AfwDofs,
    sigma: &[f64],
    t: usize,
) -> [[f64; 4]; 3] {
    let bdm = basis(mesh, dofs, t);
    let mut out = [[0.0; 4]; 3];
    for (i, &e) in dofs.triangle_edges[t].iter().enumerate() {
        let directions = dofs.edges[e].directions;
        for s in 0..2 {
            let (v, w) = (bdm.ends[i][s], bdm.w[i][s]);
            for (k, d) in directions.iter().enumerate() {
                let c = sigma[sigma_dof(e, s, k)];
                out[v][0] += c * d[0] * w[0];
                out[v][1] += c * d[0] * w[1];
                out[v][2] += c * d[1] * w[0];
                out[v][3] += c * d[1] * w[1];
            }
        }
    }
    out
}

/// The [`AfwSolution`] of the unknowns `x` and the LCP's `sol`.
#[allow(clippy::too_many_arguments)]
fn solution(
    mesh: &Mesh,
    dofs: &AfwDofs,
    system: &AfwSystem,
    data: &ElasticData,
    (multiplier, row_of_end): (MultiplierSpace, &[usize]),
    sol: LcpSolution,
    x: Vec<f64>,
    kkt: KktResiduals,
    delta: f64,
) -> AfwSolution {
    let compliance = Compliance::of(&data.material);
    let sigma = sigma_coefficients(dofs, &x);
    let nt = dofs.triangles();
    let stress = (0..nt)
        .map(|t| triangle_stress(mesh, dofs, &sigma, t))
        .collect();
    let displacement = (0..nt)
        .map(|t| [0, 1].map(|k| x[dofs.element_unknown(t, k)]))
        .collect();
    let rotation = (0..nt).map(|t| x[dofs.element_unknown(t, 2)]).collect();
    // the residuals of the normal (k = 0) and tangential (k = 1) dofs of every crack edge
    let residual_rows: Vec<usize> = (dofs.crack_edges.iter())
        .flat_map(|&e| (0..4).map(move |r| 4 * e + r))
        .collect();
    let residuals = sigma_residuals(mesh, dofs, system, compliance, &sigma, &x, &residual_rows);
    let crack = (dofs.crack_edges.iter().enumerate())
        .map(|(j, &e)| {
            let edge = &dofs.edges[e];
            let EdgeKind::Crack {
                crack,
                segment,
                normal,
                chain_slots,
            } = edge.kind
            else {
                unreachable!("a crack edge")
            };
            let node = |end: usize| edge.nodes[chain_slots[end]];
            let at = |end: usize, k: usize| 4 * j + 2 * chain_slots[end] + k;
            CrackEdge {
                crack,
                segment,
                nodes: [node(0), node(1)],
                normal,
                normal_stress: [0, 1].map(|end| sigma[sigma_dof(e, chain_slots[end], 0)]),
                opening_moment: [0, 1].map(|end| residuals[at(end, 0)]),
                slip_moment: [0, 1].map(|end| residuals[at(end, 1)]),
                closed: [0, 1].map(|end| !sol.active[row_of_end[2 * j + chain_slots[end]]]),
            }
        })
        .collect();
    AfwSolution {
        stress,
        displacement,
        rotation,
        crack,
        multiplier,
        delta,
        lcp_iterations: sol.iterations,
        lcp_status: sol.status,
        kkt,
        unknowns: dofs.n(),
    }
}
