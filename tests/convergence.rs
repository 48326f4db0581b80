//! Observed orders of accuracy at δ = 0 against the exact solutions (docs/design.md, Error norms), every case's KKT
//! residuals, and the quadrature of the error norms.
//!
//! Measured on levels 2, 3, 4 of the 8×8 scenes (h = 0.0884, 0.0442, 0.0221), rates log2 between
//! levels 3 and 4 (remeasured after the √2 fix of the norms' quadrature weights, issue 12):
//!
//! (the X-norm of the p error, `p_x`, has rate 1.00 on the closed and 0.46 on the open crack)
//!
//! | scene  | u space    | mult.  | e_u (lvl 4) | rate u | e_p (lvl 4) | rate p | e_λ (lvl 4) | rate λ |
//! |--------|------------|--------|-------------|--------|-------------|--------|-------------|--------|
//! | closed | both       | all    | 3.25e-4     | 2.00   | 6.81e-2     | 1.00   | 0           | –      |
//! | open   | broken     | M0     | 9.99e-4     | 1.36   | 1.72e-1     | 0.47   | 2.19e-2     | 0.74   |
//! | open   | broken     | M1     | 9.96e-4     | 1.35   | 1.71e-1     | 0.46   | 7.27e-3     | 0.95   |
//! | open   | broken     | M1star | 9.96e-4     | 1.35   | 1.71e-1     | 0.46   | 7.27e-3     | 0.95   |
//! | open   | continuous | all    | 2.69e-1     | −0.01  | 9.30e-1     | −0.00  | 8.11e-1     | −0.01  |
//!
//! The lumped p mass (broken u; docs/design.md), same levels:
//!
//! | scene  | mult.  | e_u (lvl 4) | rate u | e_p (lvl 4) | rate p | e_λ (lvl 4) | rate λ |
//! |--------|--------|-------------|--------|-------------|--------|-------------|--------|
//! | closed | all    | 2.88e-4     | 2.01   | 7.60e-3     | 1.74   | 0           | –      |
//! | open   | M0     | 1.02e-3     | 1.25   | 1.98e-1     | 0.43   | 2.11e-2     | 0.75   |
//! | open   | M1     | 1.02e-3     | 1.24   | 1.97e-1     | 0.43   | 7.09e-3     | 0.93   |
//! | open   | M1star | 1.02e-3     | 1.24   | 1.97e-1     | 0.43   | 7.09e-3     | 0.93   |
//!
//! On the closed crack the lumped p, a patch-averaged gradient, is superconvergent (rate 1.74,
//! 9 × smaller than the consistent p at level 4); the test asserts only the first order that any
//! gradient approximation of this kind guarantees.
//!
//! The open crack has r^{1/2} tip singularities (u ∈ H^{3/2−ε}), which bounds the rates of u and p;
//! the `continuous` u space cannot carry the jump and does not converge at all (λ_h → 0, so
//! e_λ → ‖[u]‖ = 0.816): recorded here as a characterisation, not hidden.

mod common;

use sdcrack::norms::{NormQuadrature, TipRule};
use sdcrack::scene::{MultiplierSpace, PMass, PSpace, Scene, USpace};
use sdcrack::study::{run_study, CaseFilter, CasePlan, CaseResult, Silent};

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

/// Observed rate of the paper's X-norm of the p error between the last two levels.
fn last_px_rate(cases: &[CaseResult], u: USpace, m: MultiplierSpace) -> f64 {
    let s: Vec<(f64, f64)> = cases
        .iter()
        .filter(|c| c.u_space == u && c.multiplier == m)
        .map(|c| (c.h, c.errors.expect("exact scene has errors").p_x))
        .collect();
    let (a, b) = (s[s.len() - 2], s[s.len() - 1]);
    common::rate(a.0, a.1, b.0, b.1)
}

fn last_rates(s: &[(f64, f64, f64, f64)]) -> (f64, f64, f64) {
    let (a, b) = (s[s.len() - 2], s[s.len() - 1]);
    (
        common::rate(a.0, a.1, b.0, b.1),
        common::rate(a.0, a.2, b.0, b.2),
        common::rate(a.0, a.3, b.0, b.3),
    )
}

fn assert_kkt(cases: &[CaseResult]) {
    for c in cases {
        assert!(
            c.converged,
            "level {} {} {}: {:?}",
            c.level, c.u_space, c.multiplier, c.status
        );
        assert!(
            c.kkt.max() <= 1e-10,
            "level {} {} {}: KKT {:?}",
            c.level,
            c.u_space,
            c.multiplier,
            c.kkt
        );
    }
}

#[test]
fn closed_crack_converges_optimally_for_every_variant() {
    let scene = scene_at_levels("closed-exact", &[2, 3, 4]);
    let cases = common::solve(&scene, CaseFilter::default());
    assert_eq!(cases.len(), 3 * 6);
    assert_kkt(&cases);
    for u in [USpace::Continuous, USpace::Broken] {
        for m in MultiplierSpace::ALL {
            let s = common::error_series(&cases, u, m);
            let (ru, rp, _) = last_rates(&s);
            let finest = s[s.len() - 1];
            assert!(ru >= 1.85, "{u} {m}: u rate {ru}");
            assert!(rp >= 0.9, "{u} {m}: p rate {rp}");
            // X-norm (paper §4): observed 1.00
            let rx = last_px_rate(&cases, u, m);
            assert!(rx >= 0.9, "{u} {m}: p X-norm rate {rx}");
            assert!(finest.1 < 3.6e-4, "{u} {m}: e_u = {}", finest.1);
            assert!(finest.2 < 7.5e-2, "{u} {m}: e_p = {}", finest.2);
            // closed crack: λ_h = 0 = [u] exactly
            assert!(finest.3 < 1e-12, "{u} {m}: e_λ = {}", finest.3);
        }
    }
}

#[test]
fn open_crack_broken_converges_continuous_does_not() {
    let scene = scene_at_levels("open-exact", &[2, 3, 4]);
    let cases = common::solve(&scene, CaseFilter::default());
    assert_kkt(&cases);
    for m in MultiplierSpace::ALL {
        let s = common::error_series(&cases, USpace::Broken, m);
        let (ru, rp, rl) = last_rates(&s);
        // observed 1.35-1.36, 0.46-0.47, 0.74 (M0) / 0.95 (M1, M1star)
        assert!(ru >= 1.3, "broken {m}: u rate {ru}");
        assert!(rp >= 0.42, "broken {m}: p rate {rp}");
        // X-norm: observed 0.46, below the paper's 3/4 for M1star (u ~ r^{1/2} is not piecewise H²)
        let rx = last_px_rate(&cases, USpace::Broken, m);
        assert!(rx >= 0.42, "broken {m}: p X-norm rate {rx}");
        let rl_min = if m == MultiplierSpace::M0 { 0.68 } else { 0.9 };
        assert!(rl >= rl_min, "broken {m}: λ rate {rl}");
        let finest = s[2];
        assert!(
            finest.1 < 1.1e-3 && finest.2 < 0.19,
            "broken {m}: {finest:?}"
        );
        // the paper's rates (Thm 4.3: h^1/2 for M0 and M1, h^3/4 for M1star) are met or exceeded
        let paper = if m == MultiplierSpace::M1Star {
            0.75
        } else {
            0.5
        };
        assert!(
            rl >= paper,
            "broken {m}: λ rate {rl} below the paper's {paper}"
        );
    }
    // Characterisation of the continuous u space on an open crack (docs/design.md): the errors stall.
    // Recorded at level 4: e_u = 2.69e-1, e_p = 9.30e-1, e_λ = 8.11e-1 (λ_h → 0, so e_λ tends
    // to ‖[u]‖ = sqrt(2/3) = 0.8165, the closed form of the norms' unit test).
    for m in MultiplierSpace::ALL {
        let s = common::error_series(&cases, USpace::Continuous, m);
        let (ru, rp, rl) = last_rates(&s);
        assert!(
            ru < 0.05 && rp < 0.05 && rl < 0.05,
            "continuous {m} must not converge: {ru} {rp} {rl}"
        );
        let finest = s[2];
        assert!(
            (finest.1 - 0.269).abs() < 0.005,
            "continuous {m}: e_u = {}",
            finest.1
        );
        assert!(
            (finest.2 - 0.930).abs() < 0.005,
            "continuous {m}: e_p = {}",
            finest.2
        );
        assert!(
            (finest.3 - 0.811).abs() < 0.005,
            "continuous {m}: e_λ = {}",
            finest.3
        );
    }
}

#[test]
fn refining_the_norm_quadrature_changes_norms_by_less_than_1e10() {
    let scene = scene_at_levels("open-exact", &[2]);
    let filter = CaseFilter {
        u_space: Some(USpace::Broken),
        ..CaseFilter::default()
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
    for (a, b) in base.iter().zip(&fine) {
        let (ea, eb) = (a.errors.unwrap(), b.errors.unwrap());
        for (x, y, what) in [
            (ea.u_l2, eb.u_l2, "u"),
            (ea.p_l2, eb.p_l2, "p"),
            (ea.lambda_l2, eb.lambda_l2, "λ"),
        ] {
            assert!(
                (x - y).abs() < 1e-10 * y,
                "{} {what}: {x} vs {y}",
                a.multiplier
            );
        }
    }
}

/// The collapsed (Duffy) tip rule, the default since issue 26, against the graded rule it
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
        let mut plan = CasePlan::new(&scene, &CaseFilter::default());
        assert!(matches!(
            plan.norm_quadrature.tip,
            TipRule::Collapsed { .. }
        ));
        let collapsed = run_study(&scene, &plan, &mut Silent).unwrap().cases;
        plan.norm_quadrature.tip = TipRule::Graded { depth: 30 };
        let graded = run_study(&scene, &plan, &mut Silent).unwrap().cases;
        assert_eq!(collapsed.len(), graded.len());
        for (a, b) in collapsed.iter().zip(&graded) {
            let (ea, eb) = (a.errors.unwrap(), b.errors.unwrap());
            for (x, y, what) in [
                (ea.u_l2, eb.u_l2, "u"),
                (ea.p_l2, eb.p_l2, "p"),
                (ea.p_x, eb.p_x, "p_x"),
                (ea.lambda_l2, eb.lambda_l2, "λ"),
            ] {
                assert!(
                    (x - y).abs() <= 1e-10 * y.abs(),
                    "{name} level {} {:?} {} {:?} {what}: collapsed {x} vs graded {y}",
                    a.level,
                    a.u_space,
                    a.multiplier,
                    a.p_mass
                );
            }
        }
    }
}

#[test]
fn lumped_p_mass_converges_on_both_cracks() {
    let filter = CaseFilter {
        u_space: Some(USpace::Broken),
        p_mass: Some(PMass::Lumped),
        ..CaseFilter::default()
    };
    let closed = common::solve(&scene_at_levels("closed-exact", &[2, 3, 4]), filter);
    let open = common::solve(&scene_at_levels("open-exact", &[2, 3, 4]), filter);
    assert_eq!(closed.len(), 3 * 3);
    assert!(closed
        .iter()
        .chain(&open)
        .all(|c| c.p_mass == PMass::Lumped));
    assert_kkt(&closed);
    assert_kkt(&open);
    for m in MultiplierSpace::ALL {
        // closed crack: smooth u, optimal P1 rate for u, at least first order for p, λ = 0
        let s = common::error_series(&closed, USpace::Broken, m);
        let (ru, rp, _) = last_rates(&s);
        assert!(ru >= 1.85, "closed {m}: u rate {ru}");
        assert!(rp >= 0.9, "closed {m}: p rate {rp}");
        assert!(s[2].3 < 1e-12, "closed {m}: e_λ = {}", s[2].3);
        // open crack: u ∈ H^{3/2−ε} bounds the rates; u at least first order, p at the
        // verdict's minimum 0.4, λ at the paper's rates (Thm 4.3: 1/2 for M0 and M1, 3/4 for M1star)
        let s = common::error_series(&open, USpace::Broken, m);
        let (ru, rp, rl) = last_rates(&s);
        assert!(ru >= 1.0, "open {m}: u rate {ru}");
        assert!(rp >= 0.4, "open {m}: p rate {rp}");
        let paper = if m == MultiplierSpace::M1Star {
            0.75
        } else {
            0.5
        };
        assert!(
            rl >= paper,
            "open {m}: λ rate {rl} below the paper's {paper}"
        );
    }
}
