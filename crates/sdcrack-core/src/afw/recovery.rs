//! What users see of an AFW solution (docs/design.md, "The smooth-domain method for elasticity":
//! Recovery): the opening, slip and contact pressure on the crack edges, σ symmetrised, and the
//! element-wise P1 displacement u*, all read off an [`AfwSolution`].
//!
//! **On Σ** (P1-discontinuous: two values per crack edge, at its ends in chain order). The
//! solution stores per crack edge e the moments m_a = ∫_e λ φ_a against the edge's own hats φ_a
//! (the residuals of the normal and tangential dofs' equations, [`crate::afw::CrackEdge`]) — in
//! every multiplier space. The recovery of λ from them is the L² projection onto the space's λ on
//! e, exact where λ lies in that space:
//! - M1star (the pointwise constraints σ_νν(a) ≤ 0, implemented first) and M1 (continuous P1 λ):
//!   λ is linear on e, λ = M_e⁻¹ (m_a, m_b) with the consistent edge mass
//!   M_e = ℓ/6 [[2, 1], [1, 2]], M_e⁻¹ = 2/ℓ [[2, −1], [−1, 2]]. (For M1 the two edges at an
//!   interior node give the same nodal value, up to round-off.) A lumped recovery m_a/(ℓ/2) is
//!   wrong for every non-constant λ: O(h) where M_e⁻¹ is exact.
//! - M0 (one constraint ∫_e σ_νν ≤ 0 per edge, λ ∈ P0): λ = (m_a + m_b)/ℓ = μ_e/ℓ, μ_e = ∫_e λ
//!   (the edge's mean), at both ends. ASSUMPTION (the contract fixes only M1star so far): the
//!   solver's M0 stores the same hat moments, m_a = m_b = μ_e/2, not μ_e itself.
//!
//! The slip [u·t] is the multiplier of σ_tν = 0, imposed on both tangential dofs of every crack
//! edge in every multiplier space: always P1 per edge, M_e⁻¹ of its moments. The pressure
//! p = −σ_νν is σ_h's own normal trace at the ends (linear along e).
//!
//! **On the triangles.** sym σ_h = ½(σ_h + σ_hᵀ) at the vertices, as [σ_xx, σ_yy, σ_xy]. u* is P1
//! on each triangle T with mean(u*) = u_h and ∇u* = mean_T(Aσ_h) + γ_h J (from ∇u = Aσ + γJ,
//! (∇u)_ij = ∂_j u_i, J = [[0, 1], [−1, 0]], A applied to the whole, unsymmetric σ_h; the weak
//! symmetry makes mean_T(as σ_h) = 0, so mean_T(Aσ_h) is symmetric). u* is exact for a linear u
//! with σ_h = σ(u) and γ_h = γ(u). ‖as σ_h‖_{L²(Ω)}, as σ = σ_xy − σ_yx, is the weak-symmetry
//! defect: O(h), as large as the σ error, hence sym σ_h where users see σ.

use super::element::Compliance;
use super::solution::AfwSolution;
use crate::elasticity::Material;
use crate::fe::p1::TriangleGeometry;
use crate::mesh::Mesh;
use crate::problem::MultiplierSpace;

/// The recovered fields of an [`AfwSolution`] ([`recover`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Recovered {
    /// The opening λ_ν = \[u·ν\] at the two ends of each crack edge (P1-discontinuous along Σ;
    /// the edges in the order of [`AfwSolution::crack`], the ends in chain order).
    pub opening: Vec<[f64; 2]>,
    /// The slip \[u·t\] (t = ν turned by −90°) at the ends of each crack edge, as `opening`.
    pub slip: Vec<[f64; 2]>,
    /// The contact pressure p = −σ_νν of σ_h at the ends of each crack edge, as `opening`.
    pub pressure: Vec<[f64; 2]>,
    /// sym σ_h per triangle at its three vertices (`Mesh::triangles` order), [σ_xx, σ_yy, σ_xy].
    pub stress_sym: Vec<[[f64; 3]; 3]>,
    /// u* per triangle at its three vertices: [u_x, u_y].
    pub u_star: Vec<[[f64; 2]; 3]>,
    /// ‖as σ_h‖_{L²(Ω)}, as σ = σ_xy − σ_yx (exact: σ_h is linear on each triangle).
    pub asymmetry_l2: f64,
}

/// The recovered fields of `solution` on `mesh` (its mesh) for `material`.
pub fn recover(mesh: &Mesh, material: &Material, solution: &AfwSolution) -> Recovered {
    let n = mesh.triangles.len();
    assert_eq!(solution.stress.len(), n, "σ_h on every triangle");
    assert_eq!(solution.displacement.len(), n, "u_h on every triangle");
    assert_eq!(solution.rotation.len(), n, "γ_h on every triangle");
    let length = |e: &super::solution::CrackEdge| {
        let [a, b] = e.nodes.map(|v| mesh.vertices[v]);
        (b[0] - a[0]).hypot(b[1] - a[1])
    };
    let crack = &solution.crack;
    let opening = (crack.iter())
        .map(|e| opening_from_moments(solution.multiplier, length(e), e.opening_moment))
        .collect();
    let slip = (crack.iter())
        .map(|e| edge_mass_solve(length(e), e.slip_moment))
        .collect();
    let pressure = crack.iter().map(|e| e.normal_stress.map(|s| -s)).collect();
    let stress_sym = solution.stress.iter().map(|s| s.map(symmetric)).collect();
    let compliance = Compliance::of(material);
    let mut u_star = Vec::with_capacity(n);
    let mut asymmetry = 0.0;
    for (ti, t) in mesh.triangles.iter().enumerate() {
        let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
        let sigma = &solution.stress[ti];
        u_star.push(element_u_star(
            &geo,
            &compliance,
            sigma,
            solution.displacement[ti],
            solution.rotation[ti],
        ));
        asymmetry += linear_square_integral(geo.area, sigma.map(|s| s[1] - s[2]));
    }
    Recovered {
        opening,
        slip,
        pressure,
        stress_sym,
        u_star,
        asymmetry_l2: asymmetry.sqrt(),
    }
}

/// λ_ν at an edge's two ends from its moments m_a = ∫_e λ_ν φ_a, in the λ of the multiplier
/// space `space` (the module's doc: M_e⁻¹ m for M1star and M1, the mean for M0).
pub fn opening_from_moments(space: MultiplierSpace, length: f64, m: [f64; 2]) -> [f64; 2] {
    match space {
        MultiplierSpace::M1Star | MultiplierSpace::M1 => edge_mass_solve(length, m),
        MultiplierSpace::M0 => {
            let mean = (m[0] + m[1]) / length;
            [mean, mean]
        }
    }
}

/// The linear λ on an edge of length ℓ whose hat moments are m: M_e⁻¹ m with the consistent edge
/// mass M_e = ℓ/6 [[2, 1], [1, 2]], M_e⁻¹ = 2/ℓ [[2, −1], [−1, 2]].
pub fn edge_mass_solve(length: f64, m: [f64; 2]) -> [f64; 2] {
    let c = 2.0 / length;
    [c * (2.0 * m[0] - m[1]), c * (2.0 * m[1] - m[0])]
}

/// sym σ of a raw [σ_xx, σ_xy, σ_yx, σ_yy], as [σ_xx, σ_yy, σ_xy].
pub fn symmetric(s: [f64; 4]) -> [f64; 3] {
    [s[0], s[3], 0.5 * (s[1] + s[2])]
}

/// u* of one triangle at its vertices: u_h + G (x_i − x_c), G = mean_T(Aσ_h) + γ_h J, x_c the
/// centroid (a P1 function's mean over T is its value there). `sigma`: σ_h at the vertices.
fn element_u_star(
    geo: &TriangleGeometry,
    compliance: &Compliance,
    sigma: &[[f64; 4]; 3],
    u_h: [f64; 2],
    gamma_h: f64,
) -> [[f64; 2]; 3] {
    let mean = [0, 1, 2, 3].map(|k| (sigma[0][k] + sigma[1][k] + sigma[2][k]) / 3.0);
    let a = compliance.apply(mean);
    // ∇u* = [[∂_x u_x, ∂_y u_x], [∂_x u_y, ∂_y u_y]] = Aσ̄ + γ J, J = [[0, 1], [−1, 0]]
    let grad = [[a[0], a[1] + gamma_h], [a[2] - gamma_h, a[3]]];
    let [p, q, r] = geo.vertices;
    let c = [(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0];
    geo.vertices.map(|x| {
        let d = [x[0] - c[0], x[1] - c[1]];
        [0, 1].map(|i| u_h[i] + grad[i][0] * d[0] + grad[i][1] * d[1])
    })
}

/// ∫_T f² for f linear on T with vertex values `f`: |T|/12 (Σ f_i² + (Σ f_i)²) (the P1 mass
/// matrix |T|/12 (1 + δ_ij)).
fn linear_square_integral(area: f64, f: [f64; 3]) -> f64 {
    let sum = f[0] + f[1] + f[2];
    let squares = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    area / 12.0 * (squares + sum * sum)
}

#[cfg(test)]
mod tests;
