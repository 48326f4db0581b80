//! δ → 0 at fixed h (Theorem 2.1, discrete form): ‖x_δ − x_0‖ decreases linearly in δ, and δ = 0
//! itself is solvable (the condensed bubbles stabilise the P1–P1 pair).

mod common;

use sdcrack::scene::{FieldSet, MultiplierSpace, PMass, PSpace, USpace};
use sdcrack::study::CaseFilter;

#[test]
fn distance_to_delta_zero_is_linear_in_delta() {
    let mut scene = common::load("mixed");
    scene.levels = vec![3];
    scene.deltas = vec![1e-2, 1e-3, 1e-4, 1e-5, 0.0];
    scene.fields = FieldSet {
        u: true,
        p: true,
        lambda: true,
    };
    for (u_space, p_mass, p_space) in [
        (USpace::Continuous, PMass::Consistent, PSpace::Continuous),
        (USpace::Broken, PMass::Consistent, PSpace::Continuous),
        (USpace::Broken, PMass::Lumped, PSpace::Continuous),
        (USpace::Broken, PMass::Consistent, PSpace::BrokenTangential),
        (USpace::Broken, PMass::Lumped, PSpace::BrokenTangential),
    ] {
        for m in MultiplierSpace::ALL {
            let cases = common::solve(
                &scene,
                CaseFilter {
                    u_space: Some(u_space),
                    multiplier: Some(m),
                    p_mass: Some(p_mass),
                    p_space: Some(p_space),
                    ..CaseFilter::default()
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
                    (c.delta, du.max(dp))
                })
                .collect();
            // least-squares slope of log(dist) against log(δ)
            let n = dist.len() as f64;
            let (sx, sy) = dist
                .iter()
                .fold((0.0, 0.0), |a, (d, e)| (a.0 + d.ln(), a.1 + e.ln()));
            let (mx, my) = (sx / n, sy / n);
            let (num, den) = dist.iter().fold((0.0, 0.0), |a, (d, e)| {
                (
                    a.0 + (d.ln() - mx) * (e.ln() - my),
                    a.1 + (d.ln() - mx).powi(2),
                )
            });
            let slope = num / den;
            assert!(
                (slope - 1.0).abs() <= 0.1,
                "{u_space} {m} {p_mass:?} {p_space}: slope {slope}, distances {dist:?}"
            );
        }
    }
}
