use super::*;
use crate::afw::testing::{edge_crack, hat_moments, interpolant, square_mesh};
use crate::elasticity::PlaneModel;
use crate::scene::elastic_testing::{steel_like, Elastic};

/// The largest |a − b| over two lists of edge values.
fn max_diff(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    assert_eq!(a.len(), b.len());
    (a.iter().zip(b))
        .flat_map(|(p, q)| [(p[0] - q[0]).abs(), (p[1] - q[1]).abs()])
        .fold(0.0, f64::max)
}

/// λ = |x + 1/2| − 0.3 x: linear on each crack edge of the level-0 (4 × 4) mesh (its kink at the
/// crack node x = −1/2), not linear along Σ; its values at each edge's ends, and the solution's
/// edges carrying its hat moments as the opening and (× −2) as the slip.
fn piecewise_linear_lambda(space: MultiplierSpace) -> (Mesh, AfwSolution, Vec<[f64; 2]>) {
    let lambda = |x: [f64; 2]| (x[0] + 0.5).abs() - 0.3 * x[0];
    let mesh = square_mesh(4, 1, &[edge_crack()]);
    let e = Elastic::new(steel_like(), ["0", "0"], ["0", "0"]);
    let mut sol = interpolant(&mesh, e.data.exact.as_ref().unwrap(), space);
    let mut exact = Vec::new();
    for edge in &mut sol.crack {
        let [a, b] = edge.nodes.map(|v| mesh.vertices[v]);
        edge.opening_moment = hat_moments(a, b, lambda);
        edge.slip_moment = hat_moments(a, b, |x| -2.0 * lambda(x));
        exact.push([lambda(a), lambda(b)]);
    }
    (mesh, sol, exact)
}

#[test]
fn the_opening_and_slip_of_a_lambda_linear_on_each_edge_are_exact() {
    let (mesh, sol, exact) = piecewise_linear_lambda(MultiplierSpace::M1Star);
    assert_eq!(
        sol.crack.len(),
        4,
        "level 1: four crack edges of length 1/4"
    );
    let r = recover(&mesh, &steel_like(), &sol);
    assert!(max_diff(&r.opening, &exact) < 1e-14, "{:?}", r.opening);
    let slip: Vec<_> = exact.iter().map(|v| v.map(|x| -2.0 * x)).collect();
    assert!(max_diff(&r.slip, &slip) < 1e-14);
    // M1 (continuous P1 λ) reads its edges the same way
    let m1 = recover(
        &mesh,
        &steel_like(),
        &AfwSolution {
            multiplier: MultiplierSpace::M1,
            ..sol
        },
    );
    assert_eq!(m1.opening, r.opening);
}

#[test]
fn a_lumped_recovery_fails_the_linear_test() {
    // lumped: λ_a = m_a/(ℓ/2) = (2λ_a + λ_b)/3, off by (λ_b − λ_a)/3 at each end: the consistent
    // edge mass is needed
    let (mesh, sol, exact) = piecewise_linear_lambda(MultiplierSpace::M1Star);
    let lumped: Vec<[f64; 2]> = (sol.crack.iter())
        .map(|e| {
            let [a, b] = e.nodes.map(|v| mesh.vertices[v]);
            let half = 0.5 * (b[0] - a[0]).hypot(b[1] - a[1]);
            e.opening_moment.map(|m| m / half)
        })
        .collect();
    let expected = (exact.iter())
        .map(|v| (v[1] - v[0]).abs() / 3.0)
        .fold(0.0, f64::max);
    // the largest slope is 1.3 on edges of length 1/4: 1.3/4/3 ≈ 0.108
    assert!((max_diff(&lumped, &exact) - expected).abs() < 1e-14);
    assert!(expected > 0.1);
}

#[test]
fn m0_reads_the_edges_mean() {
    let (mesh, sol, exact) = piecewise_linear_lambda(MultiplierSpace::M0);
    let r = recover(&mesh, &steel_like(), &sol);
    let means: Vec<[f64; 2]> = exact.iter().map(|v| [0.5 * (v[0] + v[1]); 2]).collect();
    assert!(max_diff(&r.opening, &means) < 1e-14);
    // the slip is P1 per edge in every multiplier space
    let slip: Vec<_> = exact.iter().map(|v| v.map(|x| -2.0 * x)).collect();
    assert!(max_diff(&r.slip, &slip) < 1e-14);
    // the same moments, read as M1star, give the linear λ: the two spaces differ
    assert!(max_diff(&opening_m1star(&mesh, &sol), &means) > 0.05);
}

fn opening_m1star(mesh: &Mesh, sol: &AfwSolution) -> Vec<[f64; 2]> {
    recover(
        mesh,
        &steel_like(),
        &AfwSolution {
            multiplier: MultiplierSpace::M1Star,
            ..sol.clone()
        },
    )
    .opening
}

#[test]
fn edge_mass_solve_inverts_the_consistent_edge_mass() {
    let (len, lam) = (0.37, [1.25, -0.5]);
    let m = [
        len / 6.0 * (2.0 * lam[0] + lam[1]),
        len / 6.0 * (lam[0] + 2.0 * lam[1]),
    ];
    let back = edge_mass_solve(len, m);
    assert!((back[0] - lam[0]).abs() < 1e-15 && (back[1] - lam[1]).abs() < 1e-15);
}

#[test]
fn the_pressure_is_minus_the_normal_stress() {
    let (mesh, mut sol, _) = piecewise_linear_lambda(MultiplierSpace::M1Star);
    for (k, e) in sol.crack.iter_mut().enumerate() {
        e.normal_stress = [-(k as f64), 0.5 * k as f64];
    }
    let r = recover(&mesh, &steel_like(), &sol);
    for (k, p) in r.pressure.iter().enumerate() {
        assert_eq!(*p, [k as f64, -0.5 * k as f64]);
    }
}

/// u = (0.1 + 0.4x − 0.7y, −0.2 + 0.9x + 0.3y): γ = ½(−0.7 − 0.9) = −0.8.
const LINEAR_U: [&str; 2] = ["0.1 + 0.4*x - 0.7*y", "-0.2 + 0.9*x + 0.3*y"];

#[test]
fn u_star_is_exact_for_a_linear_u_in_both_plane_models() {
    for plane in [PlaneModel::Strain, PlaneModel::Stress] {
        let m = Material {
            plane,
            ..steel_like()
        };
        let e = Elastic::new(m, LINEAR_U, ["0", "0"]);
        let exact = e.data.exact.as_ref().unwrap();
        let mesh = square_mesh(4, 1, &[edge_crack()]);
        let sol = interpolant(&mesh, exact, MultiplierSpace::M1Star);
        assert!(sol.rotation.iter().all(|g| (g + 0.8).abs() < 1e-14));
        let r = recover(&mesh, &m, &sol);
        let mut worst: f64 = 0.0;
        for (t, u) in mesh.triangles.iter().zip(&r.u_star) {
            for (k, &v) in t.iter().enumerate() {
                let x = mesh.vertices[v];
                for i in 0..2 {
                    worst = worst.max((u[k][i] - exact.u[i].eval(x[0], x[1])).abs());
                }
            }
        }
        assert!(worst < 1e-14, "{plane:?}: u* off by {worst:e}");
        // the rotation's coupling matters: γ_h of the wrong sign moves u*
        let flipped = AfwSolution {
            rotation: sol.rotation.iter().map(|g| -g).collect(),
            ..sol.clone()
        };
        let wrong = recover(&mesh, &m, &flipped);
        let off = (wrong.u_star.iter().zip(&r.u_star))
            .flat_map(|(a, b)| (0..3).flat_map(move |k| [a[k][0] - b[k][0], a[k][1] - b[k][1]]))
            .fold(0.0, |m: f64, d| m.max(d.abs()));
        assert!(off > 0.1, "{off}");
        // and the in-plane λ: the other plane model's compliance misses u*
        let other = Material {
            plane: match plane {
                PlaneModel::Strain => PlaneModel::Stress,
                PlaneModel::Stress => PlaneModel::Strain,
            },
            ..m
        };
        let wrong = recover(&mesh, &other, &sol);
        assert_ne!(wrong.u_star, r.u_star);
    }
}

#[test]
fn sym_keeps_a_symmetric_stress_and_averages_an_unsymmetric_one() {
    let u = ["x^2*y", "x - y^2"];
    let e = Elastic::new(steel_like(), u, ["0", "0"]);
    let mesh = square_mesh(2, 1, &[edge_crack()]);
    let sol = interpolant(
        &mesh,
        e.data.exact.as_ref().unwrap(),
        MultiplierSpace::M1Star,
    );
    let r = recover(&mesh, &steel_like(), &sol);
    for (s, sym) in sol.stress.iter().zip(&r.stress_sym) {
        for k in 0..3 {
            assert_eq!(sym[k], [s[k][0], s[k][3], s[k][1]]);
        }
    }
    assert_eq!(r.asymmetry_l2, 0.0);
    assert_eq!(symmetric([1.0, 2.0, 5.0, 7.0]), [1.0, 7.0, 3.5]);
}

#[test]
fn the_asymmetry_norm_of_linear_defects() {
    // σ_xy − σ_yx = c + x on (−1, 1)²: ‖as σ_h‖² = ∫ (c + x)² = 4c² + 4/3
    let e = Elastic::new(steel_like(), ["0", "0"], ["0", "0"]);
    let mesh = square_mesh(2, 1, &[edge_crack()]);
    let mut sol = interpolant(
        &mesh,
        e.data.exact.as_ref().unwrap(),
        MultiplierSpace::M1Star,
    );
    let c = 0.7;
    for (t, s) in mesh.triangles.iter().zip(&mut sol.stress) {
        for k in 0..3 {
            let x = mesh.vertices[t[k]][0];
            s[k][1] = 0.5 * (c + x);
            s[k][2] = -0.5 * (c + x);
        }
    }
    let r = recover(&mesh, &steel_like(), &sol);
    let expected = (4.0 * c * c + 4.0 / 3.0f64).sqrt();
    assert!(
        (r.asymmetry_l2 - expected).abs() < 1e-14,
        "{}",
        r.asymmetry_l2
    );
    // its symmetric part is zero
    assert!(r.stress_sym.iter().flatten().all(|s| s[2].abs() < 1e-16));
}
