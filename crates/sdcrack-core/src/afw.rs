//! The smooth-domain method for elasticity (issue 46; docs/design.md, "The smooth-domain method
//! for elasticity"): the dual mixed (Hellinger–Reissner) form with weak symmetry on the whole,
//! uncracked Ω, discretised by the lowest-order Arnold–Falk–Winther element — each row of σ in
//! BDM1, u ∈ P0², the rotation γ ∈ P0 — with the crack Σ entering only through its edges'
//! normal-trace degrees of freedom:
//!
//! ```text
//! (Aσ, τ) + (u, div τ) + (γ, as τ) + ⟨λ_ν, τ_νν⟩_Σ = ⟨g, τn⟩_{Γ_D}   ∀τ, τn = 0 on Γ_N, τ_tν = 0 on Σ
//! (div σ, v) − δ (u, v)                          = −(f, v)            ∀v ∈ P0²
//! (as σ, η)                                      = 0                  ∀η ∈ P0
//! σn = t on Γ_N,  σ_tν = 0,  σ_νν ≤ 0,  λ_ν = [u·ν] ≥ 0,  λ_ν σ_νν = 0  on Σ,
//! ```
//!
//! A the compliance (Aσ = (σ − λ*/(2(μ + λ*)) tr σ I)/(2μ), applied to the whole, unsymmetric σ),
//! as τ = τ_xy − τ_yx, γ = ½(∂_y u_x − ∂_x u_y) (so ∇u = Aσ + γ J, J = [[0, 1], [−1, 0]]),
//! ν the crack's normal into its + face, t = ν turned by −90° (the crack's direction),
//! σ_νν = ν·σν, σ_tν = t·σν, [v] = v⁺ − v⁻.
//!
//! This module owns the types the stages exchange; each stage is a submodule with one job:
//! element (the BDM1 basis and the local matrices), dofs (edges, orientations, the σ, u, γ
//! numbering, the crack and traction dofs), assembly (K(δ) and the load), contact (the crack
//! LCP on the normal dofs through [`crate::contact::Lcp`], δ, the KKT residuals), recovery (the
//! opening and slip from the moments, σ symmetrised, u*), norms (errors against
//! [`crate::elasticity::ElasticExact`]).

pub mod assembly;
pub mod contact;
pub mod dofs;
pub mod element;
pub mod norms;
pub mod recovery;
pub mod solution;
#[cfg(test)]
pub(crate) mod testing;
#[cfg(test)]
mod tests;

pub use contact::{solve, AfwCase};
pub use norms::{errors, AfwErrors};
pub use recovery::{recover, Recovered};
pub use solution::{AfwError, AfwSolution, CrackEdge, MULTIPLIER_SPACES};

// The stages' entry points (each documented in its submodule):
// - `afw::solve(mesh: &Mesh, domain: &Domain, data: &ElasticData, multiplier: MultiplierSpace,
//   delta: f64) -> Result<AfwSolution, AfwError>`: dofs, assembly, the contact LCP, the KKT
//   residuals (submodules element, dofs, assembly, contact); `afw::AfwCase::new(mesh, domain,
//   data)?.solve(multiplier, delta)` the same with one assembly and symbolic analysis per mesh
//   for several δ;
// - `afw::recover(mesh: &Mesh, material: &Material, solution: &AfwSolution) -> Recovered`: the
//   opening, slip and pressure per crack edge end (P1-disc along Σ), σ symmetrised, u* (submodule
//   recovery);
// - `afw::errors(mesh, material, solution, &recovered, exact: &ElasticExact) -> AfwErrors`:
//   the error norms (submodule norms).
