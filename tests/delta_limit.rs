//! δ → 0 at fixed h (Theorem 2.1, discrete form): ‖x_δ − x_0‖ decreases linearly in δ, and δ = 0
//! itself is solvable (the condensed bubbles stabilise the P1–P1 pair).

mod common;

use sdcrack_core::case::CasePattern;
use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};
use sdcrack_core::scene::FieldSet;

/// Every (u space, p mass, p space) sdcrack runs: the p spaces with the u spaces they serve.
const VARIANTS: [(USpace, PMass, PSpace); 5] = [
    (USpace::Continuous, PMass::Consistent, PSpace::Continuous),
    (USpace::Broken, PMass::Consistent, PSpace::Continuous),
    (USpace::Broken, PMass::Lumped, PSpace::Continuous),
    (USpace::Broken, PMass::Consistent, PSpace::BrokenTangential),
    (USpace::Broken, PMass::Lumped, PSpace::BrokenTangential),
];

#[test]
fn distance_to_delta_zero_is_linear_in_delta() {
    let mut scene = common::load("mixed");
    scene.axes.levels = vec![3];
    scene.axes.deltas = vec![1e-2, 1e-3, 1e-4, 1e-5, 0.0];
    scene.fields = FieldSet {
        u: true,
        p: true,
        lambda: true,
    };
    for (u_space, p_mass, p_space) in VARIANTS {
        for m in MultiplierSpace::ALL {
            let cases = common::solve(
                &scene,
                CasePattern {
                    u_space: Some(u_space),
                    multiplier: Some(m),
                    p_mass: Some(p_mass),
                    p_space: Some(p_space),
                    ..CasePattern::default()
                },
            );
            assert!(cases.iter().all(|c| c.converged && c.kkt.max() <= 1e-10));
            let zero = cases.last().unwrap().fields.as_ref().unwrap();
            let dist: Vec<(f64, f64)> = cases[..cases.len() - 1]
                .iter()
                .map(|c| {
                    let f = c.fields.as_ref().unwrap();
                    let du =
                        f.u.iter()
                            .zip(&zero.u)
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0, f64::max);
                    let dp =
                        f.p.iter()
                            .zip(&zero.p)
                            .map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()))
                            .fold(0.0, f64::max);
                    (c.key.delta, du.max(dp))
                })
                .collect();
            let slope = common::loglog_slope(&dist);
            assert!(
                (slope - 1.0).abs() <= 0.1,
                "{u_space} {m} {p_mass:?} {p_space}: slope {slope}, distances {dist:?}"
            );
        }
    }
}

/// The relative max-norm difference of two arrays (0 for two zero arrays).
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().chain(b).fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if scale == 0.0 {
        0.0
    } else {
        diff / scale
    }
}

fn flat(fields: &sdcrack_core::study::CaseFieldData) -> [Vec<f64>; 4] {
    let lambda = match &fields.lambda {
        sdcrack_core::multiplier::CrackField::PerSegment(v)
        | sdcrack_core::multiplier::CrackField::PerNode(v) => v.clone(),
    };
    [
        fields.u.clone(),
        fields.p.iter().flatten().copied().collect(),
        fields.p_bubble.iter().flatten().copied().collect(),
        lambda,
    ]
}

/// δ = 0 reached at the end of a sweep (each LCP warm-started from the previous δ's active set,
/// K(δ) refactorised in place) and δ = 0 solved alone (cold start) are the same
/// discrete solution: the LCP's solution is unique and both paths end in the same reduced linear
/// system, so their fields agree to round-off of that solve, ≤ 10·κ·ε relative (κ the reported
/// condition estimate). mixed has a partly open crack, so the warm start really starts from another
/// active set than the cold one.
#[test]
fn delta_zero_at_the_end_of_a_sweep_is_delta_zero_solved_alone() {
    let mut sweep = common::load("mixed");
    sweep.axes.levels = vec![2];
    sweep.axes.deltas = vec![1.0, 1e-2, 1e-4, 0.0];
    sweep.fields = FieldSet {
        u: true,
        p: true,
        lambda: true,
    };
    let mut alone = sweep.clone();
    alone.axes.deltas = vec![0.0];
    let mut compared = 0;
    for (u_space, p_mass, p_space) in VARIANTS {
        let filter = CasePattern {
            u_space: Some(u_space),
            p_mass: Some(p_mass),
            p_space: Some(p_space),
            ..CasePattern::default()
        };
        let swept = common::solve(&sweep, filter);
        let direct = common::solve(&alone, filter);
        for d in &direct {
            let s = swept
                .iter()
                .find(|s| s.key.multiplier == d.key.multiplier && s.key.delta == 0.0)
                .expect("the sweep has δ = 0");
            assert!(s.converged && d.converged);
            let tol = 10.0 * s.condition_estimate.max(d.condition_estimate) * f64::EPSILON;
            let (fs, fd) = (
                flat(s.fields.as_ref().unwrap()),
                flat(d.fields.as_ref().unwrap()),
            );
            for (name, (a, b)) in ["u", "p", "p bubble", "λ"].iter().zip(fs.iter().zip(&fd)) {
                let diff = relative_difference(a, b);
                assert!(
                    diff <= tol,
                    "{u_space} {} {p_mass:?} {p_space}: {name} of δ = 0 differs by {diff:e} \
                     between the sweep and the direct solve (> 10·κ·ε = {tol:e})",
                    d.key.multiplier
                );
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 15);
}
