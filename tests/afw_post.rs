//! The AFW solver's solutions read by the recovery and the error norms (issue 46:
//! `afw::recover`, `afw::errors`) on the repository's elastic scenes, loaded from their files:
//! the closed patch test exact, and Williams' open edge crack on tip-graded meshes converging at
//! the method's orders (σ 1, u* and ‖P0u − u_h‖ 2, the opening from the multiplier ≈ 1.8: an
//! independent numpy pilot of this method measured σ 0.97, u* 1.92, ‖P0u − u_h‖ 1.88 and the
//! opening 1.7–1.8 on its radially graded meshes, β = 0.4).

use std::path::Path;

use sdcrack_core::afw::{errors, recover, solve, AfwErrors, Recovered};
use sdcrack_core::contact::LcpStatus;
use sdcrack_core::mesh::MeshSource;
use sdcrack_core::problem::MultiplierSpace;
use sdcrack_core::scene::{Problem, Scene};
use sdcrack_io::scene_file::TomlScene;

/// A case's unknowns, its errors, and the opening error of a lumped recovery of the same
/// solution (λ_a = m_a/(ℓ/2) instead of M_e⁻¹ m: the mistake the consistent edge mass avoids).
struct Case {
    unknowns: usize,
    errors: AfwErrors,
    lumped_opening: f64,
}

/// The cases of the levels `levels` of the scene `name`.
fn scene_errors(name: &str, levels: std::ops::RangeInclusive<u32>) -> Vec<Case> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
    let scene = Scene::from_file(&path).unwrap();
    let Problem::Elasticity(data) = &scene.problem else {
        panic!("{name} is an elastic scene")
    };
    let exact = data.exact.as_ref().expect("an exact solution");
    let source = MeshSource::new(&scene.domain, &scene.cracks, &scene.meshing)
        .unwrap()
        .graded(scene.grading);
    levels
        .map(|level| {
            let mesh = source.level(level).unwrap();
            let sol = solve(&mesh, &scene.domain, data, MultiplierSpace::M1Star, 0.0).unwrap();
            assert_eq!(sol.lcp_status, LcpStatus::Converged, "{name} level {level}");
            let recovered = recover(&mesh, &data.material, &sol);
            let e = errors(&mesh, &data.material, &sol, &recovered, exact);
            let lumped = Recovered {
                opening: (sol.crack.iter())
                    .map(|edge| {
                        let [a, b] = edge.nodes.map(|v| mesh.vertices[v]);
                        let half = 0.5 * (b[0] - a[0]).hypot(b[1] - a[1]);
                        edge.opening_moment.map(|m| m / half)
                    })
                    .collect(),
                ..recovered
            };
            Case {
                unknowns: sol.unknowns,
                errors: e,
                lumped_opening: errors(&mesh, &data.material, &sol, &lumped, exact).opening_l2,
            }
        })
        .collect()
}

/// log2(e_l / e_{l+1}): the observed order per halving of h.
fn orders(e: &[f64]) -> Vec<f64> {
    e.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// Errors in scientific notation, three digits.
fn sci(e: &[f64]) -> String {
    let parts: Vec<String> = e.iter().map(|v| format!("{v:.3e}")).collect();
    parts.join(" ")
}

/// scenes/elastic-patch.toml: σ = diag(0, −1) across the closed crack: σ, sym σ, the opening,
/// slip and pressure, u* and P0u exact to round-off (the acceptance's 1e-10).
#[test]
fn the_closed_patch_is_exact_after_recovery() {
    for Case { errors: e, .. } in scene_errors("elastic-patch", 0..=1) {
        for (name, v) in [
            ("σ", e.stress_l2),
            ("sym σ", e.stress_sym_l2),
            ("as σ_h", e.asymmetry_l2),
            ("opening", e.opening_l2),
            ("slip", e.slip_l2),
            ("pressure", e.pressure_l2),
            ("u*", e.u_star_l2),
            ("P0u", e.projected_u_l2),
            ("γ", e.rotation_l2),
        ] {
            assert!(v < 1e-10, "{name}: {v:e} ({e:?})");
        }
    }
}

/// scenes/elastic-williams-open-graded.toml, levels 0–3: the errors and their observed orders,
/// judged on the last step against the acceptance's bounds for the graded scenes (σ, γ, u_h,
/// as σ_h ≥ 0.9; u*, ‖P0u − u_h‖ ≥ 1.8; opening, slip ≥ 1.7), which these levels already meet
/// (measured at 2 → 3: σ 1.16, u* 2.03, P0u 1.90, opening 2.43, slip 2.53). A lumped recovery
/// of the same solutions has an opening of order ≤ 1.2: the check fails for it.
#[test]
fn williams_open_graded_converges_at_the_methods_orders() {
    let cases = scene_errors("elastic-williams-open-graded", 0..=3);
    let column = |get: &dyn Fn(&Case) -> f64| cases.iter().map(get).collect::<Vec<_>>();
    let table = [
        ("σ", column(&|c| c.errors.stress_l2), 0.9),
        ("sym σ", column(&|c| c.errors.stress_sym_l2), 0.9),
        ("u*", column(&|c| c.errors.u_star_l2), 1.8),
        ("P0u − u_h", column(&|c| c.errors.projected_u_l2), 1.8),
        ("opening", column(&|c| c.errors.opening_l2), 1.7),
        ("slip", column(&|c| c.errors.slip_l2), 1.7),
        ("γ", column(&|c| c.errors.rotation_l2), 0.9),
        ("u − u_h", column(&|c| c.errors.u_l2), 0.9),
        ("as σ_h", column(&|c| c.errors.asymmetry_l2), 0.9),
    ];
    let unknowns = column(&|c| c.unknowns as f64);
    eprintln!("unknowns {unknowns:?}");
    for (name, e, _) in &table {
        eprintln!("{name:>10}: {} orders {:.2?}", sci(e), orders(e));
    }
    eprintln!("  pressure: {}", sci(&column(&|c| c.errors.pressure_l2)));
    let lumped = column(&|c| c.lumped_opening);
    eprintln!(
        "    lumped: {} orders {:.2?}",
        sci(&lumped),
        orders(&lumped)
    );
    for (name, e, least) in &table {
        let got = orders(e);
        let last = got[got.len() - 1];
        assert!(
            last >= *least,
            "{name}: orders {got:.3?}, expected ≥ {least}"
        );
    }
    let got = orders(&lumped);
    assert!(
        got[got.len() - 1] < 1.7,
        "a lumped opening passes: {got:.3?}"
    );
}

/// scenes/elastic-closed-slip-graded.toml, levels 0–3: the crack closed everywhere (every
/// multiplier zero, so the opening is zero to round-off), the slip from the tangential dofs'
/// residuals and the pressure from σ_h's normal trace. Judged on the last step: σ ≥ 0.9, u*,
/// ‖P0u − u_h‖ ≥ 1.8, slip ≥ 1.7 (the acceptance's bounds), the pressure ≥ 0.9 (σ_h's order;
/// measured at 2 → 3: σ 1.18, u* 2.34, P0u 2.56, slip 2.53, pressure 1.17).
#[test]
fn closed_slip_graded_converges_with_the_crack_shut() {
    let cases = scene_errors("elastic-closed-slip-graded", 0..=3);
    let column = |get: &dyn Fn(&Case) -> f64| cases.iter().map(get).collect::<Vec<_>>();
    let table = [
        ("σ", column(&|c| c.errors.stress_l2), 0.9),
        ("u*", column(&|c| c.errors.u_star_l2), 1.8),
        ("P0u − u_h", column(&|c| c.errors.projected_u_l2), 1.8),
        ("slip", column(&|c| c.errors.slip_l2), 1.7),
        ("pressure", column(&|c| c.errors.pressure_l2), 0.9),
    ];
    for (name, e, _) in &table {
        eprintln!("{name:>10}: {} orders {:.2?}", sci(e), orders(e));
    }
    for (name, e, least) in &table {
        let got = orders(e);
        let last = got[got.len() - 1];
        assert!(
            last >= *least,
            "{name}: orders {got:.3?}, expected ≥ {least}"
        );
    }
    // the opening of a shut crack: zero multipliers, residuals of round-off size (measured
    // ≤ 3.4e-17 against a slip error of 7.7e-4 and more)
    for c in &cases {
        assert!(c.errors.opening_l2 < 1e-14, "{:?}", c.errors);
    }
}

/// scenes/elastic-williams-open.toml (uniform meshes), levels 0–3: σ and γ at order ½ (u ∈
/// H^{3/2−ε}; the acceptance: within 0.15), the opening at order 1 (√r by P1 on a uniform mesh;
/// the bound 0.9). Measured at 2 → 3: σ 0.50, γ 0.50, opening 0.99 (the pilot: σ 0.50).
#[test]
fn williams_open_uniform_converges_at_the_singular_orders() {
    let cases = scene_errors("elastic-williams-open", 0..=3);
    let column = |get: &dyn Fn(&Case) -> f64| cases.iter().map(get).collect::<Vec<_>>();
    let last = |e: &[f64]| {
        let got = orders(e);
        eprintln!("{} orders {got:.2?}", sci(e));
        got[got.len() - 1]
    };
    for (name, e) in [
        ("σ", column(&|c| c.errors.stress_l2)),
        ("γ", column(&|c| c.errors.rotation_l2)),
    ] {
        let order = last(&e);
        assert!((order - 0.5).abs() <= 0.15, "{name}: order {order}");
    }
    let opening = last(&column(&|c| c.errors.opening_l2));
    assert!(opening >= 0.9, "opening: order {opening}");
}
