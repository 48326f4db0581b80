use super::*;
use crate::problem::{PSpace, Polyline, USpace};
use crate::scene::testing;

/// The reuse test is the Neumann bound, and the bound is tight: K(δ) = A − (δ − δ') M with
/// A = diag(1, 2), M = diag(1, 0) has ‖K(δ)⁻¹‖₁ = 1 / (1 − Δ) for Δ = δ − δ' ≥ 0 while
/// ‖A⁻¹‖₁ = 1. With an estimate ‖A⁻¹‖₁ / 3 (the estimator's allowed shortfall), the largest Δ
/// that [`InverseNorm::serves`] accepts must leave 1 / (1 − Δ) ≤ the factor, and a Δ 1 %
/// larger already exceeds it (the inverse norm at that Δ is computed exactly, not taken from
/// the code under test).
#[test]
fn reuse_of_the_inverse_norm_follows_the_neumann_bound() {
    let known = InverseNorm {
        delta: 0.5,
        estimate: 1.0 / ESTIMATOR_SLACK,
    };
    let m_norm1 = 1.0;
    let true_ratio = |gap: f64| 1.0 / (1.0 - gap); // ‖K(δ)⁻¹‖₁ / ‖A⁻¹‖₁, exact
    let limit = 1.0 - 1.0 / CONDITION_REUSE_FACTOR;
    for sign in [1.0, -1.0] {
        assert!(known.serves(0.5 + sign * 0.99 * limit, m_norm1));
        assert!(!known.serves(0.5 + sign * 1.01 * limit, m_norm1));
    }
    assert!(true_ratio(0.99 * limit) <= CONDITION_REUSE_FACTOR);
    assert!(true_ratio(1.01 * limit) > CONDITION_REUSE_FACTOR);
    assert!(known.serves(0.5, m_norm1) && known.serves(0.5, 0.0));
    assert!(!known.serves(0.6, f64::INFINITY) && !known.serves(0.6, f64::NAN));
}

/// The two routes to H_N = N K⁻¹ Nᵀ agree: the dense trailing block of the factor (used) and
/// block solves (the fallback for an order that does not put the crack unknowns last).
#[test]
fn h_n_from_the_trailing_block_matches_block_solves() {
    // the structured default scene, and a gmsh mesh of a kinked crack beside a straight one
    // (two trace rows at the kink; nested dissection of the vertex graph)
    let mut unstructured = testing::mixed();
    unstructured.cracks = vec![
        Polyline {
            points: vec![[-0.6, -0.2], [0.0, -0.2], [0.5, 0.3]],
        },
        Polyline {
            points: vec![[-0.5, 0.5], [0.3, 0.6]],
        },
    ];
    unstructured.meshing = crate::problem::Meshing::MeshSize(0.3);
    for scene in [testing::mixed(), unstructured] {
        h_n_agrees_on(&scene);
    }
}

/// What a level's solves are built from, for one mesh and discretization: the u and p
/// topologies, the crack operators in the p unknowns, the assembled system and its symbolic
/// factorization in the study's elimination order.
struct Discretized {
    topo: UTopology,
    ptopo: PTopology,
    ops: CrackOperators,
    system: System,
    p_mass: PMass,
    symbolic: SymbolicLdlt,
}

impl Discretized {
    /// `scene`'s problem on `mesh` with the u space `space`, the p space `p_space` and the p
    /// mass `p_mass`.
    fn new(scene: &Scene, mesh: &Mesh, space: USpace, p_space: PSpace, p_mass: PMass) -> Self {
        let topo = mesh.u_topology(space);
        let ptopo = mesh.p_topology(p_space);
        let ops = CrackOperators::new(mesh).with_p_topology(&ptopo);
        let system = assemble(
            mesh,
            &topo,
            &ptopo,
            &scene.scalar().unwrap().f,
            &scene.scalar().unwrap().g,
            p_mass,
        )
        .unwrap();
        let order = elimination_order(mesh, &topo, &ptopo, &ops, p_mass);
        let symbolic = SymbolicLdlt::analyze_ordered(&system.base, &order).unwrap();
        Discretized {
            topo,
            ptopo,
            ops,
            system,
            p_mass,
            symbolic,
        }
    }

    /// The level context of a study without multiplier spaces or norms.
    fn context<'a>(&'a self, scene: &'a Scene, mesh: &'a Mesh) -> LevelContext<'a> {
        LevelContext {
            problem: scene.scalar().unwrap(),
            mesh,
            topo: &self.topo,
            ptopo: &self.ptopo,
            ops: &self.ops,
            multipliers: &[],
            system: &self.system,
            p_mass: self.p_mass,
            symbolic: &self.symbolic,
            norm_cache: None,
            base_timings: Timings::default(),
        }
    }
}

fn h_n_agrees_on(scene: &Scene) {
    let mesh = scene.mesh_source().unwrap().level(1).unwrap();
    for (space, p_mass, p_space) in [
        (USpace::Continuous, PMass::Consistent, PSpace::Continuous),
        (USpace::Broken, PMass::Consistent, PSpace::Continuous),
        (USpace::Broken, PMass::Lumped, PSpace::Continuous),
        (USpace::Broken, PMass::Consistent, PSpace::BrokenTangential),
        (USpace::Broken, PMass::Lumped, PSpace::BrokenTangential),
    ] {
        let level = Discretized::new(scene, &mesh, space, p_space, p_mass);
        let ctx = level.context(scene, &mesh);
        let system = &level.system;
        let ldlt = Ldlt::factor(&level.symbolic, &system.matrix(1e-3), &system.signs).unwrap();
        let dense = ctx.h_n_from_trailing_block(&ldlt).unwrap();
        let solved = ctx.h_n_by_solves(&ldlt);
        let scale = solved.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = dense
            .iter()
            .zip(&solved)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(
            scale > 0.0 && diff <= 1e-12 * scale,
            "{space}: {diff:e} vs {scale:e}"
        );
    }
}

/// Dense Cholesky A = L Lᵀ; None when a pivot is not positive (A not SPD).
fn cholesky(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for j in 0..n {
        let d = a[j][j] - (0..j).map(|k| l[j][k] * l[j][k]).sum::<f64>();
        if d <= 0.0 {
            return None;
        }
        l[j][j] = d.sqrt();
        for i in j + 1..n {
            l[i][j] = (a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>()) / l[j][j];
        }
    }
    Some(l)
}

fn cholesky_solve(l: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let n = l.len();
    let mut y = b.to_vec();
    for i in 0..n {
        y[i] = (y[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    for i in (0..n).rev() {
        y[i] = (y[i] - (i + 1..n).map(|k| l[k][i] * y[k]).sum::<f64>()) / l[i][i];
    }
    y
}

/// The lumped p mass eliminates p exactly: the p–p block is the diagonal D with
/// row sums 0.1 Σ_{T∋i}|T|; S(δ) = C + δM + B̃D⁻¹B̃ᵀ is SPD, also at δ = 0; the solution of
/// S U = F + B̃D⁻¹G_Γ with P = D⁻¹(G_Γ − B̃ᵀU) is the solver's K⁻¹b; and H_N, the LCP matrix
/// the solver takes from its factor's trailing block, is N D⁻¹ Nᵀ − Wᵀ S⁻¹ W, W = B̃ D⁻¹ Nᵀ.
/// Everything on the right is computed densely, independently of the sparse LDLᵀ. With the
/// broken-tangential p, on an oblique crack (its (ν, τ) frame is no axis), D is
/// still diagonal: 0.1 Σ|T| over the vertex's patch for p·ν, over the triangles whose
/// centroid lies on the + (−) side of the crack line for p⁺·τ (p⁻·τ).
#[test]
fn lumped_p_mass_is_an_exact_elimination() {
    lumped_elimination_is_exact(testing::mixed(), PSpace::Continuous);
    let mut scene = testing::mixed();
    scene.cracks = vec![Polyline {
        points: vec![[-0.5, -0.5], [0.5, 0.5]],
    }];
    for p_space in [PSpace::Continuous, PSpace::BrokenTangential] {
        lumped_elimination_is_exact(scene.clone(), p_space);
    }
}

fn lumped_elimination_is_exact(scene: Scene, p_space: PSpace) {
    let mesh = crate::mesh::MeshSource::new(
        &scene.domain,
        &scene.cracks,
        &crate::problem::Meshing::Cells([4, 4]),
    )
    .unwrap()
    .level(1)
    .unwrap();
    let level = Discretized::new(&scene, &mesh, USpace::Broken, p_space, PMass::Lumped);
    let (ptopo, ops, system) = (&level.ptopo, &level.ops, &level.system);
    let (n_p, n_u) = (system.n_p, system.n_u);
    // D = 0.1 Σ_{T∋i} |T| per component; at a doubled vertex p·τ sums one face's triangles
    let nv = mesh.vertices.len();
    let crack = scene.cracks[0].segment(0);
    let nu = crack.normal();
    let mut patch = vec![0.0; n_p];
    for t in &mesh.triangles {
        let area = TriangleGeometry::new(t.map(|v| mesh.vertices[v])).area;
        let c = crate::mesh::centroid(&mesh.vertices, t);
        let plus = (c[0] - crack.a[0]) * nu[0] + (c[1] - crack.a[1]) * nu[1] > 0.0;
        for &v in t {
            patch[2 * v] += area;
            match ptopo.doubled.iter().position(|&(w, _)| w == v) {
                Some(i) if !plus => patch[2 * nv + i] += area,
                _ => patch[2 * v + 1] += area,
            }
        }
    }
    let interior = mesh.cracks[0].nodes.len() - 2;
    let doubled = if p_space == PSpace::BrokenTangential {
        interior
    } else {
        0
    };
    assert_eq!(n_p, 2 * nv + doubled, "{p_space}");
    for delta in [0.0, 1e-2] {
        let k = system.matrix(delta).to_dense_rows();
        for i in 0..n_p {
            for j in 0..n_p {
                let want = if i == j { 0.1 * patch[i] } else { 0.0 };
                assert!((k[i][j] - want).abs() <= 1e-15, "D[{i}][{j}] = {}", k[i][j]);
            }
        }
        let d: Vec<f64> = (0..n_p).map(|i| k[i][i]).collect();
        let bt = |i: usize, a: usize| k[i][n_p + a]; // B̃ᵀ[i][a]: p row i, u column a
                                                     // S = A + B̃ D⁻¹ B̃ᵀ, A = −(u–u block) = C + δM
        let mut s_mat = vec![vec![0.0; n_u]; n_u];
        for a in 0..n_u {
            for b in 0..n_u {
                let coupling: f64 = (0..n_p).map(|i| bt(i, a) * bt(i, b) / d[i]).sum();
                s_mat[a][b] = -k[n_p + a][n_p + b] + coupling;
            }
        }
        let l = cholesky(&s_mat).expect("S(δ) is SPD");
        let g = &system.rhs[..n_p];
        let f: Vec<f64> = system.rhs[n_p..].iter().map(|v| -v).collect();
        let rhs_u: Vec<f64> = (0..n_u)
            .map(|a| f[a] + (0..n_p).map(|i| bt(i, a) * g[i] / d[i]).sum::<f64>())
            .collect();
        let u = cholesky_solve(&l, &rhs_u);
        let p: Vec<f64> = (0..n_p)
            .map(|i| (g[i] - (0..n_u).map(|a| bt(i, a) * u[a]).sum::<f64>()) / d[i])
            .collect();
        let ldlt = Ldlt::factor(&level.symbolic, &system.matrix(delta), &system.signs).unwrap();
        let mut x = system.rhs.clone();
        ldlt.solve_in_place(&mut x);
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, want) in p.iter().chain(&u).enumerate() {
            assert!((x[i] - want).abs() <= 1e-10 * scale, "δ = {delta}: x[{i}]");
        }
        // H_N by the Schur formula against the solver's trailing block
        let m = ops.nodes();
        let n_cols: Vec<Vec<f64>> = (0..m)
            .map(|j| {
                let mut e = vec![0.0; m];
                e[j] = 1.0;
                let mut col = vec![0.0; n_p];
                ops.add_nt(&e, &mut col);
                col
            })
            .collect();
        let w: Vec<Vec<f64>> = n_cols
            .iter()
            .map(|c| {
                (0..n_u)
                    .map(|a| (0..n_p).map(|i| bt(i, a) * c[i] / d[i]).sum())
                    .collect()
            })
            .collect();
        let s_inv_w: Vec<Vec<f64>> = w.iter().map(|wj| cholesky_solve(&l, wj)).collect();
        let ctx = level.context(&scene, &mesh);
        let h_n = ctx.h_n_from_trailing_block(&ldlt).unwrap();
        let h_scale = h_n.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..m {
            for j in 0..m {
                let ndn: f64 = (0..n_p).map(|r| n_cols[i][r] * n_cols[j][r] / d[r]).sum();
                let wsw: f64 = (0..n_u).map(|a| w[i][a] * s_inv_w[j][a]).sum();
                let want = ndn - wsw;
                assert!(
                    (h_n[i * m + j] - want).abs() <= 1e-10 * h_scale,
                    "δ = {delta}: H_N[{i}][{j}] = {} vs {want}",
                    h_n[i * m + j]
                );
            }
        }
    }
}
