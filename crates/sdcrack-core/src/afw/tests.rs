//! Tests of [`super::solve`]: the patch tests (exact), the order of a smooth manufactured
//! solution, Williams' open edge crack (the opening's sign and size, the singular orders), the
//! closed crack with slip. The few error norms are computed here with a plain per-triangle rule
//! (a collapsed one at the crack tip): the product's norms live in their own module.

use super::element::Compliance;
use super::{solve, AfwSolution};
use crate::contact::LcpStatus;
use crate::elasticity::{ElasticData, ElasticExact, Material};
use crate::fe::p1::TriangleGeometry;
use crate::fe::quadrature::{
    collapsed_tip_rule, physical_points, triangle_rule, REFERENCE_TRIANGLE,
};
use crate::mesh::{Mesh, MeshSource};
use crate::problem::{Domain, Grading, Meshing, MultiplierSpace, Polyline};
use crate::scene::elastic_testing as et;

/// The L² errors of one solution: σ (raw, all four components), u_h against u, u_h against the
/// mean of u per triangle, u* against u, γ.
#[derive(Clone, Copy, Debug)]
struct Errors {
    sigma: f64,
    u: f64,
    projected_u: f64,
    u_star: f64,
}

/// The exact σ as [xx, xy, yx, yy] at p.
fn exact_stress(e: &ElasticExact, p: [f64; 2]) -> [f64; 4] {
    let [xx, yy, xy] = e.stress.each_ref().map(|s| s.eval(p[0], p[1]));
    [xx, xy, xy, yy]
}

/// The errors of `sol` against `exact`, by a degree-10 rule per triangle, the collapsed rule
/// (its 1/√r terms integrated to round-off) on the triangles at `tip`.
fn errors(
    mesh: &Mesh,
    m: &Material,
    sol: &AfwSolution,
    exact: &ElasticExact,
    tip: Option<[f64; 2]>,
) -> Errors {
    let comp = Compliance::of(m);
    let (plain, collapsed) = (triangle_rule(10), collapsed_tip_rule(14));
    let mut sum = [0.0; 4];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        // rotate the corners so that a tip corner comes first (the collapsed rule's vertex)
        let k0 = (0..3).find(|&k| Some(mesh.vertices[tri[k]]) == tip);
        let order = match k0 {
            Some(k) => [k, (k + 1) % 3, (k + 2) % 3],
            None => [0, 1, 2],
        };
        let rule = if k0.is_some() { &collapsed } else { &plain };
        let v = order.map(|k| mesh.vertices[tri[k]]);
        let stress = order.map(|k| sol.stress[t][k]);
        let (uh, gamma) = (sol.displacement[t], sol.rotation[t]);
        let geo = TriangleGeometry::new(v);
        let mean: [f64; 4] =
            std::array::from_fn(|r| (0..3).map(|k| stress[k][r]).sum::<f64>() / 3.0);
        let mut grad = comp.apply(mean);
        grad[1] += gamma;
        grad[2] -= gamma;
        let c = crate::mesh::centroid(&mesh.vertices, tri);
        let mut u_mean = [0.0; 2];
        for q in physical_points(rule, v, REFERENCE_TRIANGLE) {
            let l = TriangleGeometry::barycentric(q.xi);
            let s = exact_stress(exact, q.x);
            for r in 0..4 {
                let sh: f64 = (0..3).map(|k| l[k] * stress[k][r]).sum();
                sum[0] += q.weight * (s[r] - sh).powi(2);
            }
            let u = exact.u.each_ref().map(|e| e.eval(q.x[0], q.x[1]));
            let d = [q.x[0] - c[0], q.x[1] - c[1]];
            let ustar = [
                uh[0] + grad[0] * d[0] + grad[1] * d[1],
                uh[1] + grad[2] * d[0] + grad[3] * d[1],
            ];
            for r in 0..2 {
                sum[1] += q.weight * (u[r] - uh[r]).powi(2);
                sum[3] += q.weight * (u[r] - ustar[r]).powi(2);
                u_mean[r] += q.weight * u[r] / geo.area;
            }
        }
        sum[2] += geo.area * ((u_mean[0] - uh[0]).powi(2) + (u_mean[1] - uh[1]).powi(2));
    }
    let [sigma, u, projected_u, u_star] = sum.map(f64::sqrt);
    Errors {
        sigma,
        u,
        projected_u,
        u_star,
    }
}

/// Observed orders log2(e_l / e_{l+1}) of errors on meshes halving h.
fn orders(e: &[f64]) -> Vec<f64> {
    e.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

fn meshes(
    domain: &Domain,
    cracks: &[Polyline],
    cells: [usize; 2],
    graded: bool,
    levels: u32,
) -> Vec<Mesh> {
    let grading = graded.then_some(Grading {
        beta: 0.4,
        radius: 0.25,
    });
    let source = MeshSource::new(domain, cracks, &Meshing::Cells(cells))
        .unwrap()
        .graded(grading);
    (0..=levels).map(|l| source.level(l).unwrap()).collect()
}

fn solved(mesh: &Mesh, domain: &Domain, data: &ElasticData) -> AfwSolution {
    let sol = solve(mesh, domain, data, MultiplierSpace::M1Star, 0.0).unwrap();
    assert_eq!(sol.lcp_status, LcpStatus::Converged);
    assert!(sol.kkt.max() < 1e-10, "{:?}", sol.kkt);
    sol
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |a, b| a.max(b.abs()))
}

/// A linear u (constant σ) with g = u on ∂Ω and no crack: σ_h = σ, γ_h = γ, u_h = u at the
/// centroids and u* = u, to round-off (the discrete equations hold for (σ, P0 u, γ) exactly:
/// div τ ∈ P0, and the edge rule integrates g·hat exactly).
#[test]
fn patch_test_linear_displacement_is_exact() {
    let m = et::steel_like();
    let u = ["0.3 + 0.5*x - 0.2*y", "-0.1 + 0.4*x + 0.7*y"];
    let data = et::Elastic::new(m, u, ["0", "0"]).g_is_u().data;
    let exact = data.exact.clone().unwrap();
    let domain = et::square();
    let mesh = &meshes(&domain, &[], [3, 4], false, 0)[0];
    let sol = solved(mesh, &domain, &data);
    let s = exact_stress(&exact, [0.0, 0.0]);
    let scale = max_abs(s);
    for stress in &sol.stress {
        for v in stress {
            for r in 0..4 {
                assert!((v[r] - s[r]).abs() < 1e-12 * scale, "{v:?} vs {s:?}");
            }
        }
    }
    assert!(
        sol.rotation.iter().all(|&g| (g + 0.3).abs() < 1e-12),
        "γ = −0.3"
    );
    let e = errors(mesh, &m, &sol, &exact, None);
    assert!(e.u_star < 1e-12 && e.projected_u < 1e-12, "{e:?}");
    assert!(e.u > 1e-2, "u_h is P0: {e:?}");
    assert!(sol.crack.is_empty() && sol.unknowns > 0);
}

/// scenes/elastic-patch.toml: uniform compression σ = diag(0, −1) across the closed crack
/// [−1/2, 1/2] × {0}, free sides, u = g on top and bottom: σ exact, every crack dof closed with
/// σ_νν = −1 and zero opening moments.
#[test]
fn closed_patch_test_is_exact_with_every_crack_dof_closed() {
    let m = et::steel_like();
    let u = ["0.39*x", "-0.91*y"];
    let data = et::Elastic::new(m, u, ["0", "0"])
        .g_is_u()
        .traction("left", ["0", "0"])
        .traction("right", ["0", "0"])
        .data;
    let domain = et::square();
    let cracks = [et::crack([-0.5, 0.0], [0.5, 0.0])];
    for mesh in &meshes(&domain, &cracks, [8, 8], false, 1) {
        let sol = solved(mesh, &domain, &data);
        let want = [0.0, 0.0, 0.0, -1.0];
        for stress in &sol.stress {
            for v in stress {
                for r in 0..4 {
                    assert!((v[r] - want[r]).abs() < 1e-10, "{v:?}");
                }
            }
        }
        assert_eq!(sol.crack.len(), 4 << mesh.level);
        for edge in &sol.crack {
            assert_eq!(edge.closed, [true, true]);
            assert_eq!(edge.normal, [0.0, 1.0]);
            for k in 0..2 {
                assert!((edge.normal_stress[k] + 1.0).abs() < 1e-10, "{edge:?}");
                assert!(edge.opening_moment[k].abs() < 1e-10, "{edge:?}");
                assert!(edge.slip_moment[k].abs() < 1e-10, "{edge:?}");
            }
        }
    }
}

/// A smooth manufactured solution (u_C of the closed scenes, c = 1, no crack, g = u) on three
/// uniform levels: σ, u_h at order 1, ‖P0 u − u_h‖ and u* at order 2 (AFW's superconvergence).
#[test]
fn smooth_solution_converges_at_the_element_orders() {
    let m = et::steel_like();
    let (u, f) = (et::closed(1.0), et::closed_force(1.0, &m));
    let data = et::Elastic::new(m, [&u[0], &u[1]], [&f[0], &f[1]])
        .g_is_u()
        .data;
    let exact = data.exact.clone().unwrap();
    let domain = et::square();
    let errs: Vec<Errors> = meshes(&domain, &[], [8, 8], false, 2)
        .iter()
        .map(|mesh| errors(mesh, &m, &solved(mesh, &domain, &data), &exact, None))
        .collect();
    eprintln!("{errs:?}");
    let rates = |get: fn(&Errors) -> f64| orders(&errs.iter().map(get).collect::<Vec<_>>());
    let (sigma, u, pu, us) = (
        rates(|e| e.sigma),
        rates(|e| e.u),
        rates(|e| e.projected_u),
        rates(|e| e.u_star),
    );
    eprintln!("orders σ {sigma:?} u {u:?} P0u {pu:?} u* {us:?}");
    for (name, got, want) in [
        ("σ", &sigma, 1.0),
        ("u", &u, 1.0),
        ("P0 u", &pu, 2.0),
        ("u*", &us, 2.0),
    ] {
        let last = got[got.len() - 1];
        assert!((last - want).abs() < 0.1, "{name}: orders {got:?}");
    }
}
