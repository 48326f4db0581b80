//! Observed orders of accuracy at δ = 0 against the exact solutions (docs/design.md, Error
//! norms), every case's KKT residuals, and the quadrature of the error norms.
//!
//! Each rate from level 3 to level 4 of closed-exact and open-exact is held to the theory's
//! expected order minus the compare tool's margin (scenes/orders.toml, as the compare tool reads
//! it) and to the measured regression bounds the compare tool checks at level 4
//! (scenes/expectations.toml: the rate from level 3 to 4 and the level-4 error, which these tests
//! solve). The measured errors and rates are in docs/verification.md (Measured by the Rust
//! tests).
//!
//! On the closed crack the lumped p, a patch-averaged gradient, is superconvergent; the tests
//! assert only the first order that any gradient approximation of this kind guarantees.
//!
//! The open crack has r^{1/2} tip singularities (u ∈ H^{3/2−ε}), which bounds the rates of u and p;
//! the `continuous` u space cannot carry the jump and does not converge at all (λ_h → 0, so
//! e_λ → ‖[u]‖ = 0.816): recorded here as a characterisation, not hidden.

mod common;

use common::expectations::{bound, SeriesAt};
use common::orders::Orders;
use common::{errors_by_level, last_two_rates, QUANTITIES};
use sdcrack_core::case::CasePattern;
use sdcrack_core::norms::{NormQuadrature, TipRule};
use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};
use sdcrack_core::scene::Scene;
use sdcrack_core::study::{run_study, CasePlan, CaseResult, Silent};

/// The scene `name` at `levels`, δ = 0, no fields, the consistent p mass only (the lumped one
/// has its own test).
fn scene_at_levels(name: &str, levels: &[u32]) -> Scene {
    let mut s = common::load(name);
    s.axes.levels = levels.to_vec();
    s.axes.p_masses = vec![PMass::Consistent];
    s.axes.p_spaces = vec![PSpace::Continuous];
    s.axes.deltas = vec![0.0];
    s.fields = Default::default();
    s
}

/// The errors per level of variant (u, m, p_mass) of `cases` (one p space, the continuous).
fn series(
    cases: &[CaseResult],
    u: USpace,
    m: MultiplierSpace,
    p_mass: PMass,
) -> Vec<(f64, [f64; 4])> {
    errors_by_level(
        cases,
        |c| c.key.u_space == u && c.key.multiplier == m && c.key.p_mass == p_mass,
        false,
    )
}

fn assert_kkt(cases: &[CaseResult]) {
    for c in cases {
        assert!(
            c.converged,
            "level {} {} {}: {:?}",
            c.key.level, c.key.u_space, c.key.multiplier, c.status
        );
        assert!(
            c.kkt.max() <= 1e-10,
            "level {} {} {}: KKT {:?}",
            c.key.level,
            c.key.u_space,
            c.key.multiplier,
            c.kkt
        );
    }
}

/// Asserts one series (u, m, p_mass, continuous p) of `scene` solved up to its level 4: the rate
/// of each of [`QUANTITIES`] from the finest level but one to the finest at least the theory's
/// `orders` minus the margin (None: no order asserted) and at least scenes/expectations.toml's
/// `min_rate`, its finest error below the expectations' `max_error`.
fn assert_finest_level(
    scene: &str,
    cases: &[CaseResult],
    (u, m, p_mass): (USpace, MultiplierSpace, PMass),
    orders: [Option<f64>; 4],
) {
    let table = Orders::repository();
    let level = cases.iter().map(|c| c.key.level).max().expect("cases");
    let s = series(cases, u, m, p_mass);
    let finest = s[s.len() - 1].1;
    for (q, quantity) in QUANTITIES.iter().enumerate() {
        let id = format!("{scene} {u} {m} {p_mass} {quantity}");
        let [_, r] = last_two_rates(&s, q);
        if let Some(order) = orders[q] {
            let lowest = table.lowest_rate(order);
            assert!(
                r >= lowest,
                "{id}: rate {r} < the theory's {order} − margin"
            );
        }
        let b = bound(&SeriesAt {
            scene,
            u_space: u,
            multiplier: m,
            p_mass,
            p_space: PSpace::Continuous,
            quantity,
            level,
        });
        if let Some(min) = b.min_rate {
            assert!(
                r >= min,
                "{id}: rate {r} < {min} (scenes/expectations.toml)"
            );
        }
        if let Some(max) = b.max_error {
            let e = finest[q];
            assert!(
                e < max,
                "{id}: level {level} error {e} ≥ {max} (expectations)"
            );
        }
    }
}

/// The closed crack's orders (smooth u): P1's u 2, p and p_x 1; λ_h = [u] = 0 exactly, which the
/// expectations' `max_error` holds, so no order for λ.
fn closed_crack_orders(o: &Orders) -> [Option<f64>; 4] {
    let s = o.regularity.smooth_s;
    [Some(o.p1_u(s)), Some(o.p1_p(s)), Some(o.p1_px(s)), None]
}

/// Asserts broken u, multiplier `m`, `p_mass` on open-exact: the continuous p's order where the
/// crack opens for u, p and p_x, Theorem 4.3's for λ (assert_finest_level), and beyond it the
/// paper's λ rate met without margin and u at the measured pre-asymptotic bound of the table's
/// [regression] section.
fn assert_open_exact(cases: &[CaseResult], m: MultiplierSpace, p_mass: PMass) {
    let o = Orders::repository();
    let (open, paper) = (o.open_crack.order, o.paper_lambda(m));
    let orders = [Some(open), Some(open), Some(open), Some(paper)];
    assert_finest_level("open-exact", cases, (USpace::Broken, m, p_mass), orders);
    let s = series(cases, USpace::Broken, m, p_mass);
    let [_, ru] = last_two_rates(&s, 0);
    let [_, rl] = last_two_rates(&s, 3);
    let u_min = o.regression.open_exact_u_rate;
    assert!(ru >= u_min, "broken {m} {p_mass}: u rate {ru} < {u_min}");
    assert!(
        rl >= paper,
        "broken {m} {p_mass}: λ rate {rl} below the paper's {paper}"
    );
}

#[test]
fn closed_crack_converges_optimally_for_every_variant() {
    let scene = scene_at_levels("closed-exact", &[2, 3, 4]);
    let cases = common::solve(&scene, CasePattern::default());
    assert_eq!(cases.len(), 3 * 6);
    assert_kkt(&cases);
    let orders = closed_crack_orders(&Orders::repository());
    for u in [USpace::Continuous, USpace::Broken] {
        for m in MultiplierSpace::ALL {
            let variant = (u, m, PMass::Consistent);
            assert_finest_level("closed-exact", &cases, variant, orders);
        }
    }
}

#[test]
fn open_crack_broken_converges_continuous_does_not() {
    let scene = scene_at_levels("open-exact", &[2, 3, 4]);
    let cases = common::solve(&scene, CasePattern::default());
    assert_kkt(&cases);
    for m in MultiplierSpace::ALL {
        assert_open_exact(&cases, m, PMass::Consistent);
    }
    // Characterisation of the continuous u space on an open crack (docs/design.md): the errors
    // stall, λ_h → 0, so e_λ tends to ‖[u]‖ = sqrt(2/3) = 0.8165, the closed form of the norms'
    // unit test.
    let stalled = Orders::repository().regression.stalled_rate;
    for m in MultiplierSpace::ALL {
        let s = series(&cases, USpace::Continuous, m, PMass::Consistent);
        let rates = [0, 1, 3].map(|q| last_two_rates(&s, q)[1]);
        assert!(
            rates.iter().all(|&r| r < stalled),
            "continuous {m} must not converge: u, p, λ rates {rates:?}"
        );
        let finest = s[2].1;
        for (q, want) in [(0, 0.269), (1, 0.930), (3, 0.811)] {
            assert!(
                (finest[q] - want).abs() < 0.005,
                "continuous {m}: {} = {}",
                QUANTITIES[q],
                finest[q]
            );
        }
    }
}

#[test]
fn refining_the_norm_quadrature_changes_norms_by_less_than_1e10() {
    let scene = scene_at_levels("open-exact", &[2]);
    let filter = CasePattern {
        u_space: Some(USpace::Broken),
        ..CasePattern::default()
    };
    let mut plan = CasePlan::new(&scene, &filter);
    let base = run_study(&scene, &plan, &mut Silent).unwrap().cases;
    let q = NormQuadrature::default();
    // Twice the degrees and twice the collapsed rule's points per direction.
    plan.norm_quadrature = NormQuadrature {
        degree: 2 * q.degree,
        tip_degree: 2 * q.tip_degree,
        tip: match q.tip {
            TipRule::Collapsed { points } => TipRule::Collapsed { points: 2 * points },
            TipRule::Graded { depth } => TipRule::Graded { depth: depth + 8 },
        },
    };
    let fine = run_study(&scene, &plan, &mut Silent).unwrap().cases;
    assert_same_norms("open-exact, doubled quadrature", &base, &fine);
}

/// Asserts that each case of `a` and the same case of `b` (the same cases, their norms computed
/// two ways) have the four error norms equal to 1e-10 relative to `b`'s.
fn assert_same_norms(what: &str, a: &[CaseResult], b: &[CaseResult]) {
    assert_eq!(a.len(), b.len());
    for (ca, cb) in a.iter().zip(b) {
        let (xs, ys) = (
            common::quantities(&ca.errors.unwrap()),
            common::quantities(&cb.errors.unwrap()),
        );
        for ((x, y), quantity) in xs.into_iter().zip(ys).zip(QUANTITIES) {
            assert!(
                (x - y).abs() <= 1e-10 * y.abs(),
                "{what} level {} {} {} {} {quantity}: {x} vs {y}",
                ca.key.level,
                ca.key.u_space,
                ca.key.multiplier,
                ca.key.p_mass
            );
        }
    }
}

/// The collapsed (Duffy) tip rule, the default, against the graded rule it
/// replaced (30 recursive splits toward each tip, ~28 times the points per tip triangle): the
/// four norms agree to 1e-10 relative on every repository scene with an exact solution, on two
/// levels, for both u spaces, every multiplier and both p masses (the solutions as the solver
/// computes them, not zero fields).
#[test]
fn collapsed_tip_rule_gives_the_graded_rules_norms_to_1e10() {
    for name in [
        "open-exact",
        "closed-exact",
        "kinked-exact",
        "two-cracks-exact",
        "open-graded",
    ] {
        let mut scene = scene_at_levels(name, &[0, 2]);
        scene.axes.p_masses = vec![PMass::Consistent, PMass::Lumped];
        let mut plan = CasePlan::new(&scene, &CasePattern::default());
        assert!(matches!(
            plan.norm_quadrature.tip,
            TipRule::Collapsed { .. }
        ));
        let collapsed = run_study(&scene, &plan, &mut Silent).unwrap().cases;
        plan.norm_quadrature.tip = TipRule::Graded { depth: 30 };
        let graded = run_study(&scene, &plan, &mut Silent).unwrap().cases;
        assert_same_norms(&format!("{name}, collapsed vs graded"), &collapsed, &graded);
    }
}

#[test]
fn lumped_p_mass_converges_on_both_cracks() {
    let filter = CasePattern {
        u_space: Some(USpace::Broken),
        p_mass: Some(PMass::Lumped),
        ..CasePattern::default()
    };
    let closed = common::solve(&scene_at_levels("closed-exact", &[2, 3, 4]), filter);
    let open = common::solve(&scene_at_levels("open-exact", &[2, 3, 4]), filter);
    assert_eq!(closed.len(), 3 * 3);
    assert!(closed
        .iter()
        .chain(&open)
        .all(|c| c.key.p_mass == PMass::Lumped));
    assert_kkt(&closed);
    assert_kkt(&open);
    let orders = closed_crack_orders(&Orders::repository());
    for m in MultiplierSpace::ALL {
        let variant = (USpace::Broken, m, PMass::Lumped);
        assert_finest_level("closed-exact", &closed, variant, orders);
        assert_open_exact(&open, m, PMass::Lumped);
    }
}
