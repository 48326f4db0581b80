//! The condition estimate's reuse between δ: a δ of a sweep may report κ₁(K(δ)) with
//! the `‖K⁻¹‖₁` estimated at an earlier δ' only where the perturbation bound says the two
//! differ by at most `CONDITION_REUSE_FACTOR`. Checked against estimates made afresh, δ by δ, in
//! studies of one δ each, over a sweep whose large δ change κ₁ by 10× per step (so that a reuse
//! the bound does not allow is caught).

mod common;

use sdcrack_core::case::CasePattern;
use sdcrack_core::problem::{MultiplierSpace, PMass, USpace};
use sdcrack_core::study::CONDITION_REUSE_FACTOR;

#[test]
fn reused_condition_estimates_are_within_the_declared_factor_of_fresh_ones() {
    let mut scene = common::load("mixed");
    scene.axes.levels = vec![1];
    let deltas = vec![1e6, 1e4, 1e2, 1.0, 1e-2, 1e-4, 1e-6, 0.0];
    let mut reused = 0;
    let mut steps_beyond_the_factor = 0;
    for p_mass in [PMass::Consistent, PMass::Lumped] {
        let filter = CasePattern {
            u_space: Some(USpace::Broken),
            multiplier: Some(MultiplierSpace::M1),
            p_mass: Some(p_mass),
            ..CasePattern::default()
        };
        scene.axes.deltas = deltas.clone();
        let sweep = common::solve(&scene, filter);
        assert_eq!(sweep.len(), deltas.len());
        let mut previous_fresh: Option<f64> = None;
        for case in &sweep {
            scene.axes.deltas = vec![case.key.delta];
            let alone = common::solve(&scene, filter);
            let fresh = &alone[0];
            assert_eq!(
                fresh.condition_delta, case.key.delta,
                "a lone δ estimates afresh"
            );
            let ratio = case.condition_estimate / fresh.condition_estimate;
            assert!(
                (1.0 / CONDITION_REUSE_FACTOR..=CONDITION_REUSE_FACTOR).contains(&ratio),
                "{p_mass} δ = {:e}: reported {:e} (‖K⁻¹‖₁ from δ' = {:e}), afresh {:e}",
                case.key.delta,
                case.condition_estimate,
                case.condition_delta,
                fresh.condition_estimate
            );
            if case.condition_delta != case.key.delta {
                assert!(
                    case.condition_delta > case.key.delta,
                    "reused from an earlier δ"
                );
                reused += 1;
            }
            if let Some(before) = previous_fresh {
                let change = fresh.condition_estimate / before;
                if !(1.0 / CONDITION_REUSE_FACTOR..=CONDITION_REUSE_FACTOR).contains(&change) {
                    steps_beyond_the_factor += 1;
                }
            }
            previous_fresh = Some(fresh.condition_estimate);
        }
    }
    // the test has teeth: some estimates are reused, and some steps of the sweep change κ₁ by
    // more than the factor (where a reuse would have been caught above)
    assert!(reused >= 4, "{reused} reuses");
    assert!(steps_beyond_the_factor >= 4, "{steps_beyond_the_factor}");
}
