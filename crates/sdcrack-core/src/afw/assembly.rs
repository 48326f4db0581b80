//! The AFW system of one mesh (docs/design.md, "The smooth-domain method for elasticity"):
//!
//! ```text
//! K(δ) = [[A, Bᵀ, Cᵀ], [B, −δM, 0], [C, 0, 0]],   b = [⟨g, τn⟩_{Γ_D} − K_{σ,E} σ_E ; −(f, v) ; 0]
//! ```
//!
//! on the free σ dofs, u ∈ P0² and γ ∈ P0 ([`super::dofs`]' numbering), A the compliance mass,
//! B = (div σ, v), C = (as σ, η), M the P0 mass of u (the γ–γ block stays 0 for δ > 0), σ_E the
//! essential σ values (the traction interpolant; the zero tangential crack dofs) moved to the
//! right-hand side. Stored as [`SymCsc`] (lower triangle) with the δ-dependent entries listed, so
//! that K(δ) for any δ shares one pattern and one symbolic analysis. Also the element residuals
//! of single σ rows (the moments of the eliminated and of the constrained crack dofs).

use rayon::prelude::*;

use super::dofs::{sigma_dof, AfwDofs, EdgeKind, EDGE_POINTS};
use super::element::{local_matrices, Bdm1, Compliance, LocalMatrices, SIGMA_LOCAL};
use super::solution::AfwError;
use crate::elasticity::ElasticData;
use crate::expr::Expr;
use crate::fe::quadrature::{gauss_legendre, physical_points, triangle_rule, REFERENCE_TRIANGLE};
use crate::linalg::SymCsc;
use crate::mesh::Mesh;

/// Degree of the triangle rule of the load −∫_T f (exact for f of degree ≤ 8).
const LOAD_DEGREE: usize = 8;

/// Local unknowns of a triangle: its 12 σ basis functions, then u_x, u_y, γ.
const LOCAL: usize = SIGMA_LOCAL + 3;

/// The assembled system of one mesh.
#[derive(Clone, Debug)]
pub struct AfwSystem {
    /// K(0), lower triangle.
    pub base: SymCsc,
    /// The entries of ∂K/∂δ (−M, the u–u diagonal): position in `base`'s values and value.
    pub delta_entries: Vec<(usize, f64)>,
    /// b, the essential σ values moved over.
    pub rhs: Vec<f64>,
    /// Expected pivot signs: + for σ, − for u and γ.
    pub signs: Vec<i8>,
    /// Per σ dof 4e + 2s + k (free or essential): its load ⟨g, Ψ n⟩_{Γ_D}.
    pub sigma_load: Vec<f64>,
}

impl AfwSystem {
    /// K(δ), a new matrix of `base`'s pattern.
    pub fn matrix(&self, delta: f64) -> SymCsc {
        let mut k = self.base.clone();
        if delta != 0.0 {
            for &(position, d) in &self.delta_entries {
                k.values[position] += delta * d;
            }
        }
        k
    }
}

/// The BDM1 basis of triangle `t`, with its edges' global normals and end slots.
pub fn basis(mesh: &Mesh, dofs: &AfwDofs, t: usize) -> Bdm1 {
    let tri = mesh.triangles[t];
    let edges = dofs.triangle_edges[t].map(|e| &dofs.edges[e]);
    let local = |v: usize| {
        (0..3)
            .find(|&k| tri[k] == v)
            .expect("an edge's ends are its triangle's vertices")
    };
    let ends = edges.map(|e| e.nodes.map(local));
    Bdm1::new(tri.map(|v| mesh.vertices[v]), edges.map(|e| e.normal), ends)
}

/// The basis and local matrices of triangle `t`.
pub fn element(
    mesh: &Mesh,
    dofs: &AfwDofs,
    compliance: Compliance,
    t: usize,
) -> (Bdm1, LocalMatrices) {
    let bdm = basis(mesh, dofs, t);
    let directions = dofs.triangle_edges[t].map(|e| dofs.edges[e].directions);
    let lm = local_matrices(&bdm, &directions, compliance);
    (bdm, lm)
}

/// The σ dof (4e + 2s + k) of local basis function p = 4i + 2s + k of triangle `t`.
pub fn local_sigma_dof(dofs: &AfwDofs, t: usize, p: usize) -> usize {
    sigma_dof(dofs.triangle_edges[t][p / 4], (p / 2) % 2, p % 2)
}

/// Entry (p, q) of the 15 × 15 element matrix K(0) (σ 0..12, then u_x, u_y, γ), and of ∂K/∂δ.
fn local_entry(lm: &LocalMatrices, area: f64, p: usize, q: usize) -> (f64, f64) {
    let (p, q) = if p >= q { (p, q) } else { (q, p) };
    match (p, q) {
        (p, q) if p < SIGMA_LOCAL => (lm.a[p][q], 0.0),
        (p, q) if q < SIGMA_LOCAL && p < SIGMA_LOCAL + 2 => (lm.b[p - SIGMA_LOCAL][q], 0.0),
        (_, q) if q < SIGMA_LOCAL => (lm.c[q], 0.0),
        (p, q) if p == q && p < SIGMA_LOCAL + 2 => (0.0, -area),
        _ => (0.0, 0.0),
    }
}

/// Assembles the system of `mesh` with the dofs `dofs` and the data `data`.
///
/// # Errors
/// [`AfwError::NonFinite`] where f or g is not finite at a quadrature point,
/// [`AfwError::Linalg`] if the triplets do not make a matrix (a bug).
pub fn assemble(mesh: &Mesh, dofs: &AfwDofs, data: &ElasticData) -> Result<AfwSystem, AfwError> {
    let compliance = Compliance::of(&data.material);
    let n = dofs.n();
    let nt = dofs.triangles();
    let elements: Vec<(f64, LocalMatrices)> = (0..nt)
        .into_par_iter()
        .map(|t| {
            let (bdm, lm) = element(mesh, dofs, compliance, t);
            (bdm.geo.area, lm)
        })
        .collect();
    let sigma_load = dirichlet_load(mesh, dofs, data)?;
    let mut rhs = vec![0.0; n];
    for (dof, unknown) in dofs.sigma_unknown.iter().enumerate() {
        if let Some(i) = unknown {
            rhs[*i] = sigma_load[dof];
        }
    }
    let loads = body_load(mesh, &data.f)?;
    for (t, l) in loads.iter().enumerate() {
        for r in 0..2 {
            rhs[dofs.element_unknown(t, r)] = -l[r];
        }
    }
    let mut triplets: Vec<(usize, usize, f64)> = Vec::with_capacity(nt * LOCAL * (LOCAL + 1) / 2);
    let mut derivative: Vec<(usize, f64)> = Vec::with_capacity(2 * nt);
    for (t, (area, lm)) in elements.iter().enumerate() {
        // unknown (Ok) or essential value (Err) of each local function
        let slots: [Result<usize, f64>; LOCAL] = std::array::from_fn(|p| {
            if p < SIGMA_LOCAL {
                let dof = local_sigma_dof(dofs, t, p);
                dofs.sigma_unknown[dof].ok_or(dofs.essential[dof])
            } else {
                Ok(dofs.element_unknown(t, p - SIGMA_LOCAL))
            }
        });
        for p in 0..LOCAL {
            let Ok(row) = slots[p] else { continue };
            for q in 0..LOCAL {
                let (v, d) = local_entry(lm, *area, p, q);
                match slots[q] {
                    Err(value) => rhs[row] -= v * value,
                    Ok(col) if q <= p => {
                        triplets.push((row, col, v));
                        if d != 0.0 {
                            derivative.push((row, d));
                        }
                    }
                    Ok(_) => {}
                }
            }
        }
    }
    let base = SymCsc::from_triplets(n, &triplets)?;
    drop(triplets);
    let delta_entries = derivative
        .into_iter()
        .map(|(i, d)| {
            let column = &base.row_idx[base.col_ptr[i]..base.col_ptr[i + 1]];
            (
                base.col_ptr[i] + column.binary_search(&i).expect("the diagonal"),
                d,
            )
        })
        .collect();
    let mut signs = vec![-1i8; n];
    signs[..dofs.n_sigma].fill(1);
    Ok(AfwSystem {
        base,
        delta_entries,
        rhs,
        signs,
        sigma_load,
    })
}

fn non_finite(name: &'static str, e: &Expr, value: f64, p: [f64; 2]) -> AfwError {
    AfwError::NonFinite {
        name,
        source_text: e.source().to_string(),
        value,
        x: p[0],
        y: p[1],
    }
}

/// ⟨g, Ψ n⟩ on the Dirichlet edges, per σ dof: Ψ n = d (n_e·n) hat_s, so the dof (e, s, k) gets
/// ∫_e (g·d_k)(n_e·n) hat_s by Gauss–Legendre (its points interior to the edge: at a crack mouth
/// each boundary edge sees its own face's g).
fn dirichlet_load(mesh: &Mesh, dofs: &AfwDofs, data: &ElasticData) -> Result<Vec<f64>, AfwError> {
    let mut load = vec![0.0; 4 * dofs.edges.len()];
    let Some(g) = &data.g else {
        return Ok(load);
    };
    let rule = gauss_legendre(EDGE_POINTS);
    for (e, edge) in dofs.edges.iter().enumerate() {
        let EdgeKind::Dirichlet { outward } = edge.kind else {
            continue;
        };
        let orientation = edge.normal[0] * outward[0] + edge.normal[1] * outward[1];
        let [a, b] = edge.nodes.map(|v| mesh.vertices[v]);
        for (&s, &w) in rule.points.iter().zip(&rule.weights) {
            let p = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
            let gv = [0, 1].map(|r| g[r].eval(p[0], p[1]));
            for r in 0..2 {
                if !gv[r].is_finite() {
                    return Err(non_finite("g", &g[r], gv[r], p));
                }
            }
            let weight = w * edge.length * orientation;
            for (slot, hat) in [(0, 1.0 - s), (1, s)] {
                for k in 0..2 {
                    let d = edge.directions[k];
                    load[sigma_dof(e, slot, k)] += weight * hat * (gv[0] * d[0] + gv[1] * d[1]);
                }
            }
        }
    }
    Ok(load)
}

/// ∫_T f per triangle (zero without evaluating f when f is the constant 0).
fn body_load(mesh: &Mesh, f: &[Expr; 2]) -> Result<Vec<[f64; 2]>, AfwError> {
    if f.iter().all(|f| f.is_constant() && f.eval(0.0, 0.0) == 0.0) {
        return Ok(vec![[0.0; 2]; mesh.triangles.len()]);
    }
    let rule = triangle_rule(LOAD_DEGREE);
    mesh.triangles
        .par_iter()
        .map(|t| {
            let mut sum = [0.0; 2];
            for q in physical_points(&rule, t.map(|v| mesh.vertices[v]), REFERENCE_TRIANGLE) {
                for r in 0..2 {
                    let v = f[r].eval(q.x[0], q.x[1]);
                    if !v.is_finite() {
                        return Err(non_finite("f", &f[r], v, q.x));
                    }
                    sum[r] += q.weight * v;
                }
            }
            Ok(sum)
        })
        .collect()
}

/// The σ coefficients of every σ dof (free from `x`, essential from the dofs).
pub fn sigma_coefficients(dofs: &AfwDofs, x: &[f64]) -> Vec<f64> {
    (dofs.sigma_unknown.iter().zip(&dofs.essential))
        .map(|(u, &e)| u.map_or(e, |i| x[i]))
        .collect()
}

/// The residuals b_i − (K x)_i of the σ dofs `rows` (any σ dofs, free or essential) in the
/// system of every σ dof, computed element by element on the triangles at the rows' edges:
/// `sigma` the coefficients of every σ dof, `x` the unknowns (σ rows carry no δ). For a crack
/// edge's normal dof this is the opening moment, for its eliminated tangential dof the slip
/// moment.
pub fn sigma_residuals(
    mesh: &Mesh,
    dofs: &AfwDofs,
    system: &AfwSystem,
    compliance: Compliance,
    sigma: &[f64],
    x: &[f64],
    rows: &[usize],
) -> Vec<f64> {
    let wanted: std::collections::HashMap<usize, usize> =
        rows.iter().enumerate().map(|(k, &r)| (r, k)).collect();
    let edges: std::collections::HashSet<usize> = rows.iter().map(|r| r / 4).collect();
    let mut out: Vec<f64> = rows.iter().map(|&r| system.sigma_load[r]).collect();
    for t in 0..dofs.triangles() {
        if !dofs.triangle_edges[t].iter().any(|e| edges.contains(e)) {
            continue;
        }
        let (bdm, lm) = element(mesh, dofs, compliance, t);
        let values: [f64; LOCAL] = std::array::from_fn(|q| {
            if q < SIGMA_LOCAL {
                sigma[local_sigma_dof(dofs, t, q)]
            } else {
                x[dofs.element_unknown(t, q - SIGMA_LOCAL)]
            }
        });
        for p in 0..SIGMA_LOCAL {
            if let Some(&k) = wanted.get(&local_sigma_dof(dofs, t, p)) {
                let kx: f64 = (0..LOCAL)
                    .map(|q| local_entry(&lm, bdm.geo.area, p, q).0 * values[q])
                    .sum();
                out[k] -= kx;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{Domain, Rectangle};
    use crate::scene::elastic_testing as et;

    /// The rigid motions are the kernel of Bᵀ, Cᵀ: u = P0 r, γ = −ω for r = a + ω(−y, x) on an
    /// all-traction boundary give (u, div τ) + (γ, as τ) = 0 for every τ (the σ rows of K x
    /// vanish), and the u–u block is −δ times the areas.
    #[test]
    fn rigid_motions_are_the_kernel_of_the_coupling_and_the_delta_part_is_the_u_mass() {
        let r = Rectangle {
            min: [0.0, -0.5],
            max: [1.0, 0.5],
        };
        let m =
            crate::mesh::structured::structured(r, [4, 2], &[et::crack([0.0, 0.0], [0.5, 0.0])], 1)
                .unwrap();
        let data = et::Elastic::new(et::steel_like(), ["0", "0"], ["0", "0"])
            .traction("boundary", ["0", "0"])
            .data;
        let dofs = AfwDofs::new(&m, &Domain::Rectangle(r), &data).unwrap();
        let sys = assemble(&m, &dofs, &data).unwrap();
        let k = sys.matrix(0.0).to_dense_rows();
        let (a, omega) = ([0.3, -0.7], 1.9);
        let mut x = vec![0.0; dofs.n()];
        for (t, tri) in m.triangles.iter().enumerate() {
            let c = crate::mesh::centroid(&m.vertices, tri);
            x[dofs.element_unknown(t, 0)] = a[0] - omega * c[1];
            x[dofs.element_unknown(t, 1)] = a[1] + omega * c[0];
            x[dofs.element_unknown(t, 2)] = -omega;
        }
        for row in 0..dofs.n_sigma {
            let kx: f64 = (0..dofs.n()).map(|c| k[row][c] * x[c]).sum();
            assert!(kx.abs() < 1e-13, "σ row {row}: {kx}");
        }
        let d = sys.matrix(1.0);
        let total: f64 = (d.values.iter().zip(&sys.base.values))
            .map(|(a, b)| a - b)
            .sum();
        assert!((total + 2.0 * 1.0).abs() < 1e-13, "Σ δM = 2|Ω|: {total}");
    }
}

#[cfg(test)]
mod mouth_tests {
    use super::*;
    use crate::problem::Domain;
    use crate::scene::elastic_testing as et;

    /// At the mouth (−1, 0) of Williams' edge crack g jumps (θ = ±π on the two faces): each of
    /// the two boundary edges at the mouth must see its own face's g. The load of their dofs
    /// equals a 40-point Gauss–Legendre integral of the same integrand (g is smooth on each
    /// closed edge when taken from that edge's face); a rule evaluating g at the mouth itself
    /// would take one face's value on both edges.
    #[test]
    fn each_boundary_edge_at_a_crack_mouth_sees_its_own_face() {
        let m = et::steel_like();
        let u = et::williams(1.0, 0.5, &m);
        let data = et::Elastic::new(m, [&u[0], &u[1]], ["0", "0"])
            .g_is_u()
            .data;
        let Domain::Rectangle(r) = et::square() else {
            unreachable!()
        };
        let mesh = crate::mesh::structured::structured(
            r,
            [4, 4],
            &[et::crack([-1.0, 0.0], [0.0, 0.0])],
            0,
        )
        .unwrap();
        let dofs = AfwDofs::new(&mesh, &et::square(), &data).unwrap();
        let sys = assemble(&mesh, &dofs, &data).unwrap();
        let g = data.g.as_ref().unwrap();
        let rule = gauss_legendre(40);
        let mouth = mesh.cracks[0].nodes[0];
        let mut seen = 0;
        for (e, edge) in dofs.edges.iter().enumerate() {
            let EdgeKind::Dirichlet { outward } = edge.kind else {
                continue;
            };
            if !edge.nodes.contains(&mouth) {
                continue;
            }
            seen += 1;
            let orientation = edge.normal[0] * outward[0] + edge.normal[1] * outward[1];
            let [a, b] = edge.nodes.map(|v| mesh.vertices[v]);
            for slot in 0..2 {
                for k in 0..2 {
                    let d = edge.directions[k];
                    let want: f64 = (rule.points.iter().zip(&rule.weights))
                        .map(|(&s, &w)| {
                            let p = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
                            let hat = if slot == 0 { 1.0 - s } else { s };
                            let gd = g[0].eval(p[0], p[1]) * d[0] + g[1].eval(p[0], p[1]) * d[1];
                            w * edge.length * orientation * hat * gd
                        })
                        .sum();
                    let got = sys.sigma_load[sigma_dof(e, slot, k)];
                    // the 5-point rule's own error on this smooth but not polynomial g over an
                    // edge of length 1/2 is ~1e-10; the other face's g is O(1) away ([u] at the
                    // mouth is 7.28·(1/(2π))^½ ≈ 2.9 in u_y)
                    assert!(
                        (got - want).abs() < 1e-8,
                        "edge {e} ({slot}, {k}): {got} vs {want}"
                    );
                }
            }
        }
        assert_eq!(seen, 2, "two boundary edges at the mouth");
    }
}
