//! Preconditioned conjugate gradients on the lumped system's Schur complement: the iterative
//! alternative to the direct LDLᵀ, which `sdcrack bench` measures against it.
//!
//! Owns the operator `A(δ) = C + δM + B̃ D⁻¹ B̃ᵀ` on the u unknowns (the negated Schur complement
//! of `K(δ)` after the diagonal lumped p–p block `D` is eliminated, applied matrix-free through
//! the blocks of `K(δ)`), its preconditioner (faer's Cholesky of the P1 stiffness matrix of the
//! u topology plus the boundary mass over h, which pins the constants as the weak Dirichlet
//! condition does in `A`), and the CG iteration. `sdcrack bench` times one solve this way; the
//! solver itself keeps the direct route (see docs/performance.md for why).

use std::collections::HashSet;

use crate::assembly::{assemble, AssemblyError, System};
use crate::fe::p1::TriangleGeometry;
use crate::linalg::{Cholesky, CholeskyTimings, LinalgError, SymCsc};
use crate::mesh::{Mesh, UTopology};
use crate::problem::{PMass, PSpace};
use crate::scene::ScalarProblem;

/// Errors of the iterative route.
#[derive(Debug, thiserror::Error)]
pub enum KrylovError {
    /// The p–p block is not diagonal: only the lumped p mass has the Schur operator on u.
    #[error("the p–p block of K is not diagonal (entry ({row}, {col})): PCG on S needs the lumped p mass")]
    NotLumped {
        /// Row of the off-diagonal p–p entry.
        row: usize,
        /// Its column.
        col: usize,
    },
    /// The preconditioner could not be factored.
    #[error("preconditioner: {0}")]
    Preconditioner(#[from] LinalgError),
}

/// `A = −(K_uu − K_up D⁻¹ K_pu)` for `K(δ)` stored as [`System`] orders it (p unknowns first,
/// then u), applied without forming `A`.
pub struct SchurOperator<'a> {
    k: &'a SymCsc,
    n_p: usize,
    /// `D⁻¹`, the inverse of the diagonal p–p block.
    inv_d: Vec<f64>,
}

impl<'a> SchurOperator<'a> {
    /// The operator of `k = K(δ)` whose first `n_p` unknowns are p.
    ///
    /// # Errors
    /// [`KrylovError::NotLumped`] when the p–p block has an off-diagonal entry.
    pub fn new(k: &'a SymCsc, n_p: usize) -> Result<SchurOperator<'a>, KrylovError> {
        let mut inv_d = vec![0.0; n_p];
        for (j, d) in inv_d.iter_mut().enumerate() {
            for e in k.col_ptr[j]..k.col_ptr[j + 1] {
                let i = k.row_idx[e];
                if i == j {
                    *d = 1.0 / k.values[e];
                } else if i < n_p && k.values[e] != 0.0 {
                    return Err(KrylovError::NotLumped { row: i, col: j });
                }
            }
        }
        Ok(SchurOperator { k, n_p, inv_d })
    }

    /// Unknowns of the operator (the u dofs).
    pub fn n(&self) -> usize {
        self.k.n - self.n_p
    }

    /// `y = A x`.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        let (k, n_p) = (self.k, self.n_p);
        // z = K_pu x (p rows), y = K_uu x; the lower triangle holds K_up (u rows, p columns)
        // and the lower half of K_uu.
        let mut z = vec![0.0; n_p];
        y.fill(0.0);
        for j in 0..k.n {
            for e in k.col_ptr[j]..k.col_ptr[j + 1] {
                let (i, v) = (k.row_idx[e], k.values[e]);
                if j < n_p {
                    if i >= n_p {
                        z[j] += v * x[i - n_p];
                    }
                } else {
                    y[i - n_p] += v * x[j - n_p];
                    if i != j {
                        y[j - n_p] += v * x[i - n_p];
                    }
                }
            }
        }
        z.iter_mut().zip(&self.inv_d).for_each(|(a, d)| *a *= d);
        // y = K_up D⁻¹ K_pu x − K_uu x
        y.iter_mut().for_each(|v| *v = -*v);
        for j in 0..n_p {
            for e in k.col_ptr[j]..k.col_ptr[j + 1] {
                let i = k.row_idx[e];
                if i >= n_p {
                    y[i - n_p] += k.values[e] * z[j];
                }
            }
        }
    }

    /// The right-hand side of `A u = K_up D⁻¹ b_p − b_u` whose solution is the u part of
    /// `K x = b` (the p part is then `D⁻¹ (b_p − K_pu u)`).
    pub fn reduced_rhs(&self, b: &[f64]) -> Vec<f64> {
        let (k, n_p) = (self.k, self.n_p);
        let mut r: Vec<f64> = b[n_p..].iter().map(|v| -v).collect();
        for j in 0..n_p {
            let zj = self.inv_d[j] * b[j];
            for e in k.col_ptr[j]..k.col_ptr[j + 1] {
                let i = k.row_idx[e];
                if i >= n_p {
                    r[i - n_p] += k.values[e] * zj;
                }
            }
        }
        r
    }
}

/// The condensed system of the scalar `problem` on `mesh` with the u space of `topo`, the
/// continuous p and the p–p block `p_mass`: the system [`solve_u`] takes (which refuses all but
/// the lumped mass).
///
/// # Errors
/// The scene's data cannot be integrated ([`AssemblyError`]).
pub fn continuous_p_system(
    mesh: &Mesh,
    topo: &UTopology,
    problem: &ScalarProblem,
    p_mass: PMass,
) -> Result<System, AssemblyError> {
    assemble(
        mesh,
        topo,
        &mesh.p_topology(PSpace::Continuous),
        &problem.f,
        &problem.g,
        p_mass,
    )
}

/// The preconditioner's matrix: the P1 stiffness of `topo` (the broken topology keeps the crack's
/// faces apart, as `A` does) plus `1/h` times the lumped mass of the domain's boundary edges.
pub fn preconditioner_matrix(mesh: &Mesh, topo: &UTopology) -> SymCsc {
    let boundary: HashSet<[usize; 2]> = mesh
        .boundary_edges
        .iter()
        .map(|&[a, b]| [a.min(b), a.max(b)])
        .collect();
    let weight = 1.0 / mesh.h();
    let mut triplets = Vec::with_capacity(6 * mesh.triangles.len());
    for (t, dofs) in mesh.triangles.iter().zip(&topo.triangle_dofs) {
        let corners = t.map(|v| mesh.vertices[v]);
        let k = TriangleGeometry::new(corners).stiffness();
        for a in 0..3 {
            for b in 0..=a {
                triplets.push((dofs[a], dofs[b], k[a][b]));
            }
            let b = (a + 1) % 3;
            if boundary.contains(&[t[a].min(t[b]), t[a].max(t[b])]) {
                let (p, q) = (corners[a], corners[b]);
                let half = 0.5 * weight * (p[0] - q[0]).hypot(p[1] - q[1]);
                triplets.push((dofs[a], dofs[a], half));
                triplets.push((dofs[b], dofs[b], half));
            }
        }
    }
    // Indices come from the topology and the entries are finite for a valid mesh.
    SymCsc::from_triplets(topo.n_dofs, &triplets).unwrap_or_else(|e| unreachable!("{e}"))
}

/// The outcome of one PCG solve.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct PcgReport {
    /// Iterations (applications of A and of the preconditioner).
    pub iterations: usize,
    /// Final `‖b − A x‖₂ / ‖b‖₂` (recomputed from x, not the recursion's estimate).
    pub relative_residual: f64,
    /// True when the tolerance was reached within the iteration limit.
    pub converged: bool,
}

/// Solves `A x = b` by CG preconditioned with `m` (x starts at 0), until
/// `‖b − A x‖₂ ≤ tol ‖b‖₂` or `max_iterations`.
pub fn pcg(
    a: &SchurOperator,
    m: &Cholesky,
    b: &[f64],
    x: &mut [f64],
    tol: f64,
    max_iterations: usize,
) -> PcgReport {
    let n = a.n();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(p, q)| p * q).sum::<f64>();
    let b_norm = dot(b, b).sqrt();
    x.fill(0.0);
    let mut r = b.to_vec();
    let mut z = r.clone();
    m.solve_in_place(&mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    let mut iterations = 0;
    while iterations < max_iterations && dot(&r, &r).sqrt() > tol * b_norm {
        a.apply(&p, &mut ap);
        let alpha = rz / dot(&p, &ap);
        x.iter_mut().zip(&p).for_each(|(xi, pi)| *xi += alpha * pi);
        r.iter_mut().zip(&ap).for_each(|(ri, qi)| *ri -= alpha * qi);
        z.copy_from_slice(&r);
        m.solve_in_place(&mut z);
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        p.iter_mut()
            .zip(&z)
            .for_each(|(pi, zi)| *pi = zi + beta * *pi);
        iterations += 1;
    }
    a.apply(x, &mut ap);
    let residual = b
        .iter()
        .zip(&ap)
        .map(|(bi, ai)| (bi - ai) * (bi - ai))
        .sum::<f64>()
        .sqrt();
    let relative_residual = if b_norm > 0.0 {
        residual / b_norm
    } else {
        residual
    };
    PcgReport {
        iterations,
        relative_residual,
        converged: relative_residual <= tol,
    }
}

/// One solve of `K(δ) x = b` by this route, for `sdcrack bench`: the u part by PCG.
pub struct IterativeSolve {
    /// Setup of the preconditioner (assembly of its matrix and Cholesky).
    pub preconditioner: CholeskyTimings,
    /// Seconds to assemble the preconditioner's matrix.
    pub preconditioner_assembly_s: f64,
    /// Seconds of the PCG solve.
    pub solve_s: f64,
    /// The solve's outcome.
    pub report: PcgReport,
    /// The u part of the solution.
    pub u: Vec<f64>,
}

/// Solves `K(δ) x = system.rhs` for the u part by PCG on the Schur operator to `tol`.
///
/// # Errors
/// [`KrylovError`] for a consistent p mass or a preconditioner that cannot be factored.
pub fn solve_u(
    mesh: &Mesh,
    topo: &UTopology,
    system: &System,
    delta: f64,
    tol: f64,
) -> Result<IterativeSolve, KrylovError> {
    use std::time::Instant;
    let k = system.matrix(delta);
    let a = SchurOperator::new(&k, system.n_p)?;
    let t0 = Instant::now();
    let p_matrix = preconditioner_matrix(mesh, topo);
    let preconditioner_assembly_s = t0.elapsed().as_secs_f64();
    let (m, preconditioner) = Cholesky::factor(&p_matrix)?;
    drop(p_matrix);
    let b = a.reduced_rhs(&system.rhs);
    let mut u = vec![0.0; a.n()];
    let t1 = Instant::now();
    let report = pcg(&a, &m, &b, &mut u, tol, MAX_ITERATIONS);
    Ok(IterativeSolve {
        preconditioner,
        preconditioner_assembly_s,
        solve_s: t1.elapsed().as_secs_f64(),
        report,
        u,
    })
}

/// The max-norm distance of `u` from the u part of the direct LDLᵀ solution of
/// `K(δ) x = system.rhs`, relative to that part's max norm: the yardstick of this route's accuracy.
///
/// # Errors
/// [`LinalgError`] when the direct factorisation fails.
pub fn distance_to_direct(system: &System, delta: f64, u: &[f64]) -> Result<f64, LinalgError> {
    use crate::linalg::{Ldlt, SymbolicLdlt};
    let k = system.matrix(delta);
    let symbolic = SymbolicLdlt::analyze(&k)?;
    let mut x = system.rhs.clone();
    Ldlt::factor(&symbolic, &k, &system.signs)?.solve_in_place(&mut x);
    let direct = &x[system.n_p..];
    let scale = direct.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let distance = direct
        .iter()
        .zip(u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    Ok(distance / scale)
}

/// The relative residual to which `sdcrack bench` solves: its u then equals the direct route's to
/// 1e-10 relative (tested in this module on repository scenes).
pub const ROUTE_TOLERANCE: f64 = 1e-13;

/// Iteration limit of [`solve_u`].
pub const MAX_ITERATIONS: usize = 2000;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::USpace;
    use crate::scene::{testing, Scene};

    fn load(name: &str) -> Scene {
        match name {
            "mixed" => testing::mixed(),
            "open-exact" => testing::open_exact(),
            _ => unreachable!("{name}"),
        }
    }

    /// The route's u equals the direct LDLᵀ's to 1e-10 relative (max norm) on repository scenes,
    /// both u spaces, δ = 0 and 1e-2. PCG stops at a relative residual of 1e-13; with the
    /// preconditioned condition number below 1e2 (the iteration counts say so: ≤ ~60) the error
    /// is below 1e-11 relative, so 1e-10 leaves a margin of 10 and no more.
    #[test]
    fn pcg_on_the_schur_operator_gives_the_direct_solution() {
        for name in ["mixed", "open-exact"] {
            let scene = load(name);
            let source = scene.mesh_source().unwrap();
            let mesh = source.level(2).unwrap();
            for space in [USpace::Continuous, USpace::Broken] {
                let topo = mesh.u_topology(space);
                let system =
                    continuous_p_system(&mesh, &topo, scene.scalar().unwrap(), PMass::Lumped)
                        .unwrap();
                for delta in [0.0, 1e-2] {
                    let it = solve_u(&mesh, &topo, &system, delta, ROUTE_TOLERANCE).unwrap();
                    assert!(
                        it.report.converged,
                        "{name} {space} {delta}: {:?}",
                        it.report
                    );
                    assert!(it.report.iterations <= 200, "{:?}", it.report);
                    let distance = distance_to_direct(&system, delta, &it.u).unwrap();
                    assert!(
                        distance <= 1e-10,
                        "{name} {space} δ = {delta}: |Δu| / |u| = {distance:e}"
                    );
                }
            }
        }
    }

    /// The consistent p mass has no diagonal p–p block: refused with the entry's position.
    #[test]
    fn consistent_p_mass_is_refused() {
        let scene = load("mixed");
        let mesh = scene.mesh_source().unwrap().level(0).unwrap();
        let topo = mesh.u_topology(USpace::Broken);
        let system =
            continuous_p_system(&mesh, &topo, scene.scalar().unwrap(), PMass::Consistent).unwrap();
        let err = solve_u(&mesh, &topo, &system, 0.0, 1e-12).err().unwrap();
        assert!(matches!(err, KrylovError::NotLumped { .. }), "{err}");
    }
}
