//! The error norms of an AFW solution against the exact fields of an elastic scene
//! ([`ElasticExact`]; docs/design.md, "The smooth-domain method for elasticity": Error norms).
//!
//! The quadrature is the scalar norms' ([`crate::norms`]: [`NormQuadrature`], the same points):
//! the Duffy rule collapsed at each crack tip with r = σ² on the triangles touching it (σ ~
//! r^{-1/2}, the error density |σ − σ_h|² ~ r^{-1} is then a polynomial in σ times a smooth
//! function of the angle), the Gauss rule of degree `tip_degree` on their neighbours, `degree`
//! elsewhere; on Σ each crack edge with `tip_degree/2 + 1` Gauss points, collapsed likewise at a
//! tip. Mouths (an edge crack's end on ∂Ω) are not tips. Every point is interior to a triangle or
//! an edge, so the exact fields are never evaluated at a tip; on Σ the exact opening, slip and
//! pressure are the scene's expressions, or else the limits of u and σ from the faces by the
//! signed-zero rule of [`crate::problem::eval_on_face`].

use super::element::Compliance;
use super::recovery::Recovered;
use super::solution::AfwSolution;
use crate::elasticity::{ElasticExact, Material};
use crate::expr::{BatchScratch, ExprBatch, Var};
use crate::fe::p1::TriangleGeometry;
use crate::fe::quadrature::PhysicalPoint;
use crate::mesh::Mesh;
use crate::norms::{CrackRule, MeshRule, NormQuadrature, Piece};
use crate::problem::eval_on_face;

/// The error norms of an AFW case (summary.json's elastic errors). All are L² norms over Ω
/// (tensors in the Frobenius norm) or over Σ, the crack; σ_h is the raw, weakly symmetric
/// stress, sym σ_h = ½(σ_h + σ_hᵀ).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct AfwErrors {
    /// ‖σ − σ_h‖_{L²(Ω)}, all four components of σ_h against the symmetric exact σ.
    pub stress_l2: f64,
    /// ‖σ − sym σ_h‖_{L²(Ω)}: what users see.
    pub stress_sym_l2: f64,
    /// ‖σ − σ_h‖_A = (A(σ − σ_h), σ − σ_h)^{1/2}, the energy norm of the compliance A (the
    /// material's), on the raw σ_h.
    pub stress_energy: f64,
    /// ‖u − u_h‖_{L²(Ω)}, u_h ∈ P0².
    pub u_l2: f64,
    /// ‖P0u − u_h‖_{L²(Ω)}, P0u the exact cell means (by the norms' own rule): superconvergent.
    pub projected_u_l2: f64,
    /// ‖u − u*‖_{L²(Ω)}, u* the element-wise P1 reconstruction ([`crate::afw::recovery`]).
    pub u_star_l2: f64,
    /// ‖γ − γ_h‖_{L²(Ω)}, γ = ½(∂_y u_x − ∂_x u_y).
    pub rotation_l2: f64,
    /// ‖as σ_h‖_{L²(Ω)}, as σ = σ_xy − σ_yx: the weak-symmetry defect (zero for the exact σ).
    pub asymmetry_l2: f64,
    /// ‖λ_ν − \[u·ν\]‖_{L²(Σ)}: the opening recovered from the multiplier.
    pub opening_l2: f64,
    /// ‖λ_t − \[u·t\]‖_{L²(Σ)}: the slip recovered from the tangential dofs' residuals.
    pub slip_l2: f64,
    /// ‖p_h − p‖_{L²(Σ)}, p = −σ_νν the contact pressure, p_h that of σ_h.
    pub pressure_l2: f64,
}

/// The exact opening \[u·ν\] at a crack point `p` of normal `nu`: the scene's `opening`, else
/// u⁺·ν − u⁻·ν from the faces.
pub fn exact_opening(exact: &ElasticExact, p: [f64; 2], nu: [f64; 2]) -> f64 {
    match &exact.opening {
        Some(e) => e.eval(p[0], p[1]),
        None => face_jump(exact, p, nu, nu),
    }
}

/// The exact slip \[u·t\] (t = ν turned by −90°) at a crack point: the scene's `slip`, else from
/// the faces.
pub fn exact_slip(exact: &ElasticExact, p: [f64; 2], nu: [f64; 2]) -> f64 {
    match &exact.slip {
        Some(e) => e.eval(p[0], p[1]),
        None => face_jump(exact, p, nu, [nu[1], -nu[0]]),
    }
}

/// The exact contact pressure −σ_νν at a crack point: the scene's `pressure`, else the mean of
/// the two faces' −σ_νν (equal for an exact field: σν is continuous across Σ, which the scene's
/// exact-data check verifies).
pub fn exact_pressure(exact: &ElasticExact, p: [f64; 2], nu: [f64; 2]) -> f64 {
    match &exact.pressure {
        Some(e) => e.eval(p[0], p[1]),
        None => {
            let snn = |side: f64| {
                let [xx, yy, xy] = exact
                    .stress
                    .each_ref()
                    .map(|e| eval_on_face(e, p, nu, side));
                nu[0] * nu[0] * xx + nu[1] * nu[1] * yy + 2.0 * nu[0] * nu[1] * xy
            };
            -0.5 * (snn(1.0) + snn(-1.0))
        }
    }
}

/// \[u·d\] = u⁺·d − u⁻·d at `p`, each face's limit by the signed-zero rule.
fn face_jump(exact: &ElasticExact, p: [f64; 2], nu: [f64; 2], d: [f64; 2]) -> f64 {
    let along = |side: f64| {
        d[0] * eval_on_face(&exact.u[0], p, nu, side)
            + d[1] * eval_on_face(&exact.u[1], p, nu, side)
    };
    along(1.0) - along(-1.0)
}

/// The error norms of `solution` (on `mesh`, recovered as `recovered`) against `exact`, with the
/// scalar norms' default quadrature.
pub fn errors(
    mesh: &Mesh,
    material: &Material,
    solution: &AfwSolution,
    recovered: &Recovered,
    exact: &ElasticExact,
) -> AfwErrors {
    errors_with(
        mesh,
        material,
        solution,
        recovered,
        exact,
        NormQuadrature::default(),
    )
}

/// Triangles per chunk: fixed chunks summed in order, then the chunk sums in order, so the norms
/// do not depend on the threads.
const CHUNK: usize = 4096;

/// The squared norms over Ω, summed triangle by triangle (the fields of [`AfwErrors`] in order,
/// up to `rotation`).
type Sums = [f64; 7];

/// [`errors`] with the quadrature `quad`.
pub fn errors_with(
    mesh: &Mesh,
    material: &Material,
    solution: &AfwSolution,
    recovered: &Recovered,
    exact: &ElasticExact,
    quad: NormQuadrature,
) -> AfwErrors {
    use rayon::prelude::*;
    let n = mesh.triangles.len();
    assert_eq!(solution.stress.len(), n, "a solution on this mesh");
    assert_eq!(recovered.u_star.len(), n, "recovered on this mesh");
    let rule = MeshRule::new(mesh, quad);
    // u_x, u_y, σ_xx, σ_yy, σ_xy, ∂_y u_x, ∂_x u_y
    let (dux_dy, duy_dx) = (exact.u[0].derivative(Var::Y), exact.u[1].derivative(Var::X));
    let [sxx, syy, sxy] = &exact.stress;
    let program = ExprBatch::new(&[&exact.u[0], &exact.u[1], sxx, syy, sxy, &dux_dy, &duy_dx]);
    let compliance = Compliance::of(material);
    let add = |a: Sums, b: Sums| std::array::from_fn(|k| a[k] + b[k]);
    let sums = (mesh.triangles.par_chunks(CHUNK).enumerate())
        .map(|(c, tris)| {
            let mut work = Work::default();
            let mut acc = [0.0; 7];
            for (j, t) in tris.iter().enumerate() {
                let ti = c * CHUNK + j;
                let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
                rule.triangle_points(t, &geo, &mut work.pieces, &mut work.points);
                let local = Local {
                    sigma: &solution.stress[ti],
                    sym: &recovered.stress_sym[ti],
                    u_star: &recovered.u_star[ti],
                    u_h: solution.displacement[ti],
                    gamma_h: solution.rotation[ti],
                };
                acc = add(acc, element(&program, &compliance, &local, &mut work));
            }
            acc
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold([0.0; 7], add);
    let [stress, sym, energy, u, projected, u_star, rotation] = sums.map(f64::sqrt);
    let [opening_l2, slip_l2, pressure_l2] = crack_errors(mesh, solution, recovered, exact, quad);
    AfwErrors {
        stress_l2: stress,
        stress_sym_l2: sym,
        stress_energy: energy,
        u_l2: u,
        projected_u_l2: projected,
        u_star_l2: u_star,
        rotation_l2: rotation,
        asymmetry_l2: recovered.asymmetry_l2,
        opening_l2,
        slip_l2,
        pressure_l2,
    }
}

/// One thread's buffers: a triangle's pieces and points, their coordinates and the exact values.
#[derive(Default)]
struct Work {
    pieces: Vec<Piece>,
    points: Vec<PhysicalPoint>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    values: Vec<f64>,
    scratch: BatchScratch,
}

/// The discrete fields of one triangle.
struct Local<'a> {
    /// σ_h at the vertices, [xx, xy, yx, yy].
    sigma: &'a [[f64; 4]; 3],
    /// sym σ_h at the vertices, [xx, yy, xy].
    sym: &'a [[f64; 3]; 3],
    /// u* at the vertices.
    u_star: &'a [[f64; 2]; 3],
    u_h: [f64; 2],
    gamma_h: f64,
}

/// One triangle's contributions to the squared norms ([`Sums`]) at `work.points`.
fn element(program: &ExprBatch, compliance: &Compliance, local: &Local, work: &mut Work) -> Sums {
    let n = work.points.len();
    work.xs.clear();
    work.xs.extend(work.points.iter().map(|q| q.x[0]));
    work.ys.clear();
    work.ys.extend(work.points.iter().map(|q| q.x[1]));
    work.values.resize(7 * n, 0.0);
    program.eval(&work.xs, &work.ys, &mut work.scratch, &mut work.values);
    let v = |k: usize, j: usize| work.values[k * n + j];
    let interpolate =
        |l: [f64; 3], f: &dyn Fn(usize) -> f64| l[0] * f(0) + l[1] * f(1) + l[2] * f(2);
    let mut s = [0.0; 7];
    // ∫_T u and |T| by the same rule: P0u = ∫_T u / |T|
    let (mut mean_u, mut area) = ([0.0; 2], 0.0);
    for (j, q) in work.points.iter().enumerate() {
        let (l, w) = (TriangleGeometry::barycentric(q.xi), q.weight);
        let u = [v(0, j), v(1, j)];
        let (xx, yy, xy) = (v(2, j), v(3, j), v(4, j));
        let gamma = 0.5 * (v(5, j) - v(6, j));
        let sigma_h: [f64; 4] = std::array::from_fn(|k| interpolate(l, &|i| local.sigma[i][k]));
        let sym_h: [f64; 3] = std::array::from_fn(|k| interpolate(l, &|i| local.sym[i][k]));
        let u_star: [f64; 2] = std::array::from_fn(|k| interpolate(l, &|i| local.u_star[i][k]));
        let d = [
            xx - sigma_h[0],
            xy - sigma_h[1],
            xy - sigma_h[2],
            yy - sigma_h[3],
        ];
        let ad = compliance.apply(d);
        let ds = [xx - sym_h[0], yy - sym_h[1], xy - sym_h[2]];
        let du = [u[0] - local.u_h[0], u[1] - local.u_h[1]];
        let dstar = [u[0] - u_star[0], u[1] - u_star[1]];
        let dgamma = gamma - local.gamma_h;
        s[0] += w * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
        s[1] += w * (ds[0] * ds[0] + ds[1] * ds[1] + 2.0 * ds[2] * ds[2]);
        s[2] += w * (ad[0] * d[0] + ad[1] * d[1] + ad[2] * d[2] + ad[3] * d[3]);
        s[3] += w * (du[0] * du[0] + du[1] * du[1]);
        s[5] += w * (dstar[0] * dstar[0] + dstar[1] * dstar[1]);
        s[6] += w * dgamma * dgamma;
        mean_u = [mean_u[0] + w * u[0], mean_u[1] + w * u[1]];
        area += w;
    }
    let dp = [0, 1].map(|i| mean_u[i] / area - local.u_h[i]);
    s[4] = area * (dp[0] * dp[0] + dp[1] * dp[1]);
    s
}

/// ‖λ_ν − \[u·ν\]‖, ‖λ_t − \[u·t\]‖, ‖p_h − p‖ on Σ: per chain, the chains' integrals added in
/// order. The crack edges of `solution` are the chains' segments in order.
fn crack_errors(
    mesh: &Mesh,
    solution: &AfwSolution,
    recovered: &Recovered,
    exact: &ElasticExact,
    quad: NormQuadrature,
) -> [f64; 3] {
    let rule = CrackRule::new(mesh, quad);
    let mut total = [0.0; 3];
    let mut first = 0;
    for (c, (chain, range)) in mesh.cracks.iter().zip(&rule.chains).enumerate() {
        for k in 0..chain.segments() {
            let e = &solution.crack[first + k];
            assert!(
                e.crack == c && e.segment == k,
                "the solution's crack edges are the chains' segments in order"
            );
        }
        let mut chain_total = [0.0; 3];
        for q in &rule.points[range.clone()] {
            let e = first + q.segment;
            let at = |v: &[[f64; 2]]| (1.0 - q.s) * v[e][0] + q.s * v[e][1];
            let d = [
                at(&recovered.opening) - exact_opening(exact, q.x, q.normal),
                at(&recovered.slip) - exact_slip(exact, q.x, q.normal),
                at(&recovered.pressure) - exact_pressure(exact, q.x, q.normal),
            ];
            for k in 0..3 {
                chain_total[k] += q.weight * d[k] * d[k];
            }
        }
        for k in 0..3 {
            total[k] += chain_total[k];
        }
        first += chain.segments();
    }
    assert_eq!(
        first,
        solution.crack.len(),
        "one crack edge per chain segment"
    );
    total.map(f64::sqrt)
}

#[cfg(test)]
mod tests;
