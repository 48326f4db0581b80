use super::*;
use crate::afw::recover;
use crate::afw::testing::{cell_mean, edge_crack, interpolant, seen_from, square_mesh};
use crate::elasticity::PlaneModel;
use crate::expr::Expr;
use crate::norms::TipRule;
use crate::problem::MultiplierSpace;
use crate::scene::elastic_testing::{steel_like, williams, williams_stress, Elastic};

/// The errors of the synthetic solution of `e` ([`interpolant`]) on `mesh`.
fn errors_of_interpolant(mesh: &Mesh, e: &Elastic) -> AfwErrors {
    let exact = e.data.exact.as_ref().unwrap();
    let m = e.data.material;
    let sol = interpolant(mesh, exact, MultiplierSpace::M1Star);
    errors(mesh, &m, &sol, &recover(mesh, &m, &sol), exact)
}

/// The errors of the zero solution against `exact`, with the quadrature `quad`.
fn errors_of_zero(
    mesh: &Mesh,
    m: &Material,
    exact: &ElasticExact,
    quad: NormQuadrature,
) -> AfwErrors {
    let zero = Elastic::new(*m, ["0", "0"], ["0", "0"]);
    let sol = interpolant(
        mesh,
        zero.data.exact.as_ref().unwrap(),
        MultiplierSpace::M1Star,
    );
    errors_with(mesh, m, &sol, &recover(mesh, m, &sol), exact, quad)
}

#[test]
fn a_linear_stress_interpolated_has_no_stress_projection_or_crack_error() {
    // u quadratic: σ linear (σ_h its interpolant, exact), P0u = u_h (cell means by another rule),
    // no jump, σ_νν linear along the crack
    let e = Elastic::new(
        steel_like(),
        ["x^2 + 0.3*x*y - 0.5*y^2", "x*y - 0.2*x^2 + y^2"],
        ["0", "0"],
    );
    let mesh = square_mesh(2, 1, &[edge_crack()]);
    let err = errors_of_interpolant(&mesh, &e);
    for (name, v) in [
        ("σ", err.stress_l2),
        ("sym σ", err.stress_sym_l2),
        ("σ energy", err.stress_energy),
        ("P0u", err.projected_u_l2),
        ("as σ", err.asymmetry_l2),
        ("opening", err.opening_l2),
        ("slip", err.slip_l2),
        ("pressure", err.pressure_l2),
    ] {
        assert!(v < 1e-13, "{name}: {v:e}");
    }
    // u ∉ P0, u* and γ not exact for a quadratic u
    assert!(
        err.u_l2 > 0.1 && err.u_star_l2 > 1e-3 && err.rotation_l2 > 1e-2,
        "{err:?}"
    );
}

/// λ* = 0 (so σ_yy = 2μ ε_yy does not see the jump of ∂_x u_x) and μ = 1.
fn no_lambda() -> Material {
    Material {
        lambda: 0.0,
        mu: 1.0,
        plane: PlaneModel::Strain,
    }
}

/// u linear on each side of y = 0 and jumping across it: [u_x] = 0.6 (x + 1), [u_y] = 0.8 (x + 1)
/// on the crack (ν = (0, 1), t = (1, 0)); ∇u = [[1 ± 0.3, 0.5], [0.2 ± 0.4, −1]] on y ≷ 0.
const JUMPING_U: [&str; 2] = [
    "x + 0.5*y + 0.3*sign(y)*(x + 1)",
    "0.2*x - y + 0.4*sign(y)*(x + 1)",
];

#[test]
fn a_field_linear_on_each_side_is_recovered_exactly_but_u_h() {
    let e = Elastic::new(no_lambda(), JUMPING_U, ["0", "0"]);
    let exact = e.data.exact.as_ref().unwrap();
    // the faces' limits by the signed-zero rule
    let (p, nu) = ([-0.3, 0.0], [0.0, 1.0]);
    assert!((exact_opening(exact, p, nu) - 0.8 * 0.7).abs() < 1e-15);
    assert!((exact_slip(exact, p, nu) - 0.6 * 0.7).abs() < 1e-15);
    assert!((exact_pressure(exact, p, nu) - 2.0).abs() < 1e-15);
    let mesh = square_mesh(2, 1, &[edge_crack()]);
    let err = errors_of_interpolant(&mesh, &e);
    for (name, v) in [
        ("σ", err.stress_l2),
        ("sym σ", err.stress_sym_l2),
        ("σ energy", err.stress_energy),
        ("P0u", err.projected_u_l2),
        ("u*", err.u_star_l2),
        ("γ", err.rotation_l2),
        ("opening", err.opening_l2),
        ("slip", err.slip_l2),
        ("pressure", err.pressure_l2),
    ] {
        assert!(v < 1e-13, "{name}: {v:e}");
    }
    // u − u_h is linear with zero mean on each T: ∫_T = |T|/12 Σ_i (∇u (x_i − c))²
    let mut expected = 0.0;
    for t in &mesh.triangles {
        let v = t.map(|k| mesh.vertices[k]);
        let c = [0, 1].map(|d| (v[0][d] + v[1][d] + v[2][d]) / 3.0);
        let area = 0.5
            * ((v[1][0] - v[0][0]) * (v[2][1] - v[0][1])
                - (v[2][0] - v[0][0]) * (v[1][1] - v[0][1]));
        for x in v {
            let (y, yc) = (seen_from(x, c), c);
            for u in &exact.u {
                let d = u.eval(y[0], y[1]) - u.eval(yc[0], yc[1]);
                expected += area / 12.0 * d * d;
            }
        }
    }
    assert!(
        (err.u_l2 - expected.sqrt()).abs() < 1e-14,
        "{} {}",
        err.u_l2,
        expected.sqrt()
    );
}

#[test]
fn the_zero_solution_has_the_fields_closed_form_norms() {
    // u = (x² y, x − y²), λ = 2, μ = 1/2 (elasticity.rs's test): σ = (6xy − 4y, 4xy − 6y,
    // (x² + 1)/2), γ = (x² − 1)/2; over (−1, 1)²: ‖u‖² = 4/15 + 4/3 + 4/5 = 12/5,
    // ‖σ‖² = (16 + 64/3) + (64/9 + 48) + 56/15 = 4328/45, ‖σ‖²_A = ∫ ε:σ = 16/3 + 16 + 56/15
    // = 376/15, ‖γ‖² = 8/15. On the crack (−1, 0) × {0}, the given opening 7.28 √(−x/(2π)),
    // slip 3.64 √(−x/(2π)) and pressure x²: 7.28²/(4π), 3.64²/(4π), 1/5.
    let m = Material {
        lambda: 2.0,
        mu: 0.5,
        plane: PlaneModel::Strain,
    };
    let e = Elastic::new(m, ["x^2*y", "x - y^2"], ["0", "0"])
        .opening("7.28*sqrt(-x/(2*pi))")
        .slip("3.64*sqrt(-x/(2*pi))")
        .pressure("x^2");
    let exact = e.data.exact.as_ref().unwrap();
    let mesh = square_mesh(2, 1, &[edge_crack()]);
    let err = errors_of_zero(&mesh, &m, exact, NormQuadrature::default());
    let pi = std::f64::consts::PI;
    let close = |name: &str, got: f64, squared: f64| {
        let want = squared.sqrt();
        assert!(
            (got - want).abs() < 1e-13 * want,
            "{name}: {got} against {want}"
        );
    };
    close("u", err.u_l2, 2.4);
    close("u*", err.u_star_l2, 2.4);
    close("σ", err.stress_l2, 4328.0 / 45.0);
    close("sym σ", err.stress_sym_l2, 4328.0 / 45.0);
    close("σ energy", err.stress_energy, 376.0 / 15.0);
    close("γ", err.rotation_l2, 8.0 / 15.0);
    close("opening", err.opening_l2, 7.28 * 7.28 / (4.0 * pi));
    close("slip", err.slip_l2, 3.64 * 3.64 / (4.0 * pi));
    close("pressure", err.pressure_l2, 0.2);
    // ‖P0u‖² = Σ_T |T| |mean_T u|², the means by the degree-20 rule
    let mut p0 = 0.0;
    for t in &mesh.triangles {
        let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
        for u in &exact.u {
            let mean = cell_mean(&geo, |x| u.eval(x[0], x[1]));
            p0 += geo.area * mean * mean;
        }
    }
    close("P0u", err.projected_u_l2, p0);
}

#[test]
fn the_lumped_openings_error_is_order_h() {
    // λ = 0.5 + 2x: a lumped recovery errs by (Δ/3)(1 − 2s) on each edge (Δ = 2ℓ), so
    // ‖e‖² = Σ_e (Δ²/9) ℓ/3 = (4ℓ²/27)·(length 1): ‖e‖ = 2ℓ/√27; the consistent one is exact.
    let e = Elastic::new(steel_like(), ["0", "0"], ["0", "0"]).opening("0.5 + 2*x");
    let exact = e.data.exact.as_ref().unwrap();
    let m = steel_like();
    for (level, len) in [(1, 0.25), (2, 0.125)] {
        let mesh = square_mesh(4, level, &[edge_crack()]);
        let sol = interpolant(&mesh, exact, MultiplierSpace::M1Star);
        let mut r = recover(&mesh, &m, &sol);
        assert!(errors(&mesh, &m, &sol, &r, exact).opening_l2 < 1e-14);
        r.opening = (sol.crack.iter())
            .map(|e| e.opening_moment.map(|v| v / (0.5 * len)))
            .collect();
        let lumped = errors(&mesh, &m, &sol, &r, exact).opening_l2;
        let want = 2.0 * len / 27f64.sqrt();
        assert!(
            (lumped - want).abs() < 1e-14,
            "level {level}: {lumped} against {want}"
        );
    }
}

/// Williams' field K_I = 1, K_II = 1/2 (the open edge crack's exact solution).
fn williams_exact(m: &Material) -> ElasticExact {
    let u = williams(1.0, 0.5, m);
    let s = williams_stress(1.0, 0.5);
    Elastic::new(*m, [&u[0], &u[1]], ["0", "0"])
        .stress([&s[0], &s[1], &s[2]])
        .data
        .exact
        .unwrap()
}

#[test]
fn the_collapsed_tip_rule_integrates_williams_field() {
    // ‖σ‖² ~ ∫ 1/r at the tip. With the rules away from the tip fixed (degree 30), the default
    // tip rule (16 × 16 collapsed points) against far finer ones: 40 × 40 collapsed points, and
    // the recursive splits toward the tip (40 of them, degree-30 pieces). Measured: 2.5e-13
    // relative at worst (the energy norm); a Gauss rule of degree 20 on the tip triangles is off
    // by 5.7e-4.
    let m = steel_like();
    let exact = williams_exact(&m);
    let mesh = square_mesh(4, 0, &[edge_crack()]);
    let at = |tip| NormQuadrature {
        degree: 30,
        tip_degree: 30,
        tip,
    };
    let collapsed = errors_of_zero(&mesh, &m, &exact, at(TipRule::Collapsed { points: 16 }));
    let quantities = |e: &AfwErrors| {
        [
            ("σ", e.stress_l2),
            ("σ energy", e.stress_energy),
            ("u", e.u_l2),
            ("P0u", e.projected_u_l2),
            ("γ", e.rotation_l2),
            ("opening", e.opening_l2),
            ("slip", e.slip_l2),
        ]
    };
    let agree = |a: &AfwErrors, b: &AfwErrors, tol: f64| {
        for ((name, x), (_, y)) in quantities(a).into_iter().zip(quantities(b)) {
            assert!((x - y).abs() <= tol * y, "{name}: {x} against {y}");
        }
    };
    for tip in [
        TipRule::Collapsed { points: 40 },
        TipRule::Graded { depth: 40 },
    ] {
        agree(
            &collapsed,
            &errors_of_zero(&mesh, &m, &exact, at(tip)),
            1e-12,
        );
    }
    let plain = errors_of_zero(&mesh, &m, &exact, at(TipRule::Graded { depth: 0 }));
    let rel = (plain.stress_l2 - collapsed.stress_l2).abs() / collapsed.stress_l2;
    assert!(rel > 1e-4, "a Gauss rule at the tip is off by only {rel:e}");
    // The default quadrature (degree 10, 20 around the tip) as a whole: within 2e-10 of the fine
    // rules on this coarsest mesh (h = 1/2, the singular field across every triangle; measured
    // 1.2e-10 on the energy norm, 7e-11 on σ).
    let default = errors_of_zero(&mesh, &m, &exact, NormQuadrature::default());
    agree(&default, &collapsed, 2e-10);
    // The scene's opening, slip and pressure (Williams' jumps, free faces) and the faces' limits
    // of u and σ give the same errors.
    let scene = ElasticExact {
        opening: Some(Expr::parse("7.28*sqrt(-x/(2*pi))").unwrap()),
        slip: Some(Expr::parse("3.64*sqrt(-x/(2*pi))").unwrap()),
        pressure: Some(Expr::parse("0").unwrap()),
        ..exact.clone()
    };
    let given = errors_of_zero(&mesh, &m, &scene, NormQuadrature::default());
    assert!((default.opening_l2 - given.opening_l2).abs() < 1e-13);
    assert!((default.slip_l2 - given.slip_l2).abs() < 1e-13);
    assert!(default.pressure_l2 < 1e-13 && given.pressure_l2 == 0.0);
}

#[test]
fn a_mouth_is_not_collapsed_a_tip_is() {
    // the edge crack (−1, 0) → (0, 0): its first segment starts at the mouth (plain Gauss
    // points, s = t), its last one ends at the tip (s = 1 − t², collapsed there)
    let mesh = square_mesh(4, 0, &[edge_crack()]);
    let quad = NormQuadrature::default();
    let rule = CrackRule::new(&mesh, quad);
    let g = crate::fe::quadrature::gauss_legendre(quad.tip_degree / 2 + 1);
    let first: Vec<f64> = rule
        .points
        .iter()
        .filter(|q| q.segment == 0)
        .map(|q| q.s)
        .collect();
    assert_eq!(first, g.points);
    let last: Vec<f64> = rule
        .points
        .iter()
        .filter(|q| q.segment == 1)
        .map(|q| q.s)
        .collect();
    let collapsed: Vec<f64> = g.points.iter().map(|t| 1.0 - t * t).collect();
    assert_eq!(last, collapsed);
}
