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
#[cfg(test)]
pub(crate) mod testing;
#[cfg(test)]
mod tests;

pub use contact::{solve, AfwCase};
pub use norms::{errors, AfwErrors};
pub use recovery::{recover, Recovered};

use crate::contact::{KktResiduals, LcpStatus};

/// The multiplier spaces the elastic solver has (docs/design.md, "Contact"): the pointwise one,
/// σ_νν ≤ 0 at both ends of every crack edge, whose multiplier is ∫_e λ_ν hat_a (the dual cone of
/// the scalar problem's M1star). A scene listing another is refused (`sdcrack check`).
pub const MULTIPLIER_SPACES: &[crate::problem::MultiplierSpace] =
    &[crate::problem::MultiplierSpace::M1Star];

/// Why an elastic case cannot be solved.
#[derive(Debug, thiserror::Error)]
pub enum AfwError {
    /// δ must be a finite number ≥ 0.
    #[error("delta = {0} is not a finite number >= 0")]
    InvalidDelta(f64),
    /// A boundary edge with neither a traction nor Dirichlet data.
    #[error("boundary part {part} has no traction and the scene has no g (data.gx, data.gy)")]
    NoDirichletData {
        /// The part.
        part: String,
    },
    /// A crack edge on ∂Ω.
    #[error("a crack edge at ({}, {}) lies on the boundary", at[0], at[1])]
    CrackOnBoundary {
        /// One end of the edge.
        at: [f64; 2],
    },
    /// Data not finite at a quadrature point.
    #[error(
        "data {name} = \"{source_text}\" evaluates to {value} at the quadrature point ({x}, {y})"
    )]
    NonFinite {
        /// `f`, `g` or `traction`.
        name: &'static str,
        /// The expression.
        source_text: String,
        /// The value.
        value: f64,
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
    },
    /// A fixed point that is not a mesh vertex.
    #[error("fixed point ({}, {}) is not a mesh vertex", point[0], point[1])]
    FixedPointNotAVertex {
        /// The point.
        point: [f64; 2],
    },
    /// An all-traction boundary whose fixed points leave a rigid motion free.
    #[error("the boundary is all traction and the fixed points leave a rigid motion free")]
    RigidModesLeft,
    /// The sparse solver failed.
    #[error(transparent)]
    Linalg(#[from] crate::linalg::LinalgError),
}

/// One crack edge of a solution: an edge of the uncracked mesh between two consecutive nodes
/// of a crack chain ([`crate::mesh::CrackChain`]), with the values of its two normal-trace
/// dofs at its ends. Crack by crack, each chain's segments in order.
#[derive(Clone, Debug, PartialEq)]
pub struct CrackEdge {
    /// Index of the crack (`Mesh::cracks`).
    pub crack: usize,
    /// Index of the segment along that chain.
    pub segment: usize,
    /// The edge's two mesh vertices, in chain order.
    pub nodes: [usize; 2],
    /// ν, the unit normal into the + face (the chain's normal of this segment).
    pub normal: [f64; 2],
    /// σ_νν of σ_h at the two ends (its normal trace is linear along the edge).
    pub normal_stress: [f64; 2],
    /// The opening moments μ_ν = ∫_e λ_ν φ_a at the two ends a (φ_a the edge's own P1 hat,
    /// 1 at end a, 0 at the other): the residuals of the equations of the normal dofs.
    pub opening_moment: [f64; 2],
    /// The slip moments ∫_e [u·t] φ_a: the residuals of the equations of the tangential dofs
    /// (eliminated by σ_tν = 0).
    pub slip_moment: [f64; 2],
    /// Whether each end is in contact (closed): outside the LCP's active set, its multiplier
    /// (opening moment) 0 and σ_νν free (≤ 0). An open end is in the active set: σ_νν = 0 and
    /// its opening moment ≥ 0. An end is closed when the constraint it belongs to is: its own
    /// (M1Star), its edge's mean (M0), its node's hat-weighted one (M1); see
    /// [`AfwSolution::multiplier`].
    pub closed: [bool; 2],
}

/// The discrete solution of one case (one mesh, multiplier space and δ), in the form every later
/// stage (recovery, norms, output) reads: piecewise polynomials per triangle, independent of
/// the BDM1 basis that produced them.
#[derive(Clone, Debug)]
pub struct AfwSolution {
    /// σ_h per triangle: its (linear) values at the triangle's three vertices, in the order of
    /// `Mesh::triangles[t]`, each as [σ_xx, σ_xy, σ_yx, σ_yy] (raw: only weakly symmetric).
    pub stress: Vec<[[f64; 4]; 3]>,
    /// u_h per triangle (P0): [u_x, u_y].
    pub displacement: Vec<[f64; 2]>,
    /// γ_h per triangle (P0).
    pub rotation: Vec<f64>,
    /// The crack edges with their traces and moments.
    pub crack: Vec<CrackEdge>,
    /// The multiplier space of the contact constraints (docs/design.md: which ones the elastic
    /// method has and what each constrains).
    pub multiplier: crate::problem::MultiplierSpace,
    /// The regularisation δ of the solve.
    pub delta: f64,
    /// The contact solve: the LCP's active-set iterations, summed over its refinement rounds.
    pub lcp_iterations: usize,
    /// How the LCP solve ended.
    pub lcp_status: LcpStatus,
    /// The relative KKT residuals: the constraint part as the scalar solver defines it, the
    /// equations per block of rows (σ, u, γ) rather than per row (docs/design.md, "What the
    /// solution reports").
    pub kkt: KktResiduals,
    /// Unknowns of the system: σ dofs (without the essential ones), 2 u and 1 γ per triangle.
    pub unknowns: usize,
}

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
