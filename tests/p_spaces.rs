//! The broken-tangential p (docs/design.md, The p spaces): observed orders at δ = 0 against the
//! exact solutions, on the smooth open cracks (straight on the axes, and turned by 45° so that no
//! frame is an axis), on the graded singular open crack, and on the closed, kinked and
//! two-crack scenes, whose answers it must leave as they were.
//!
//! The orders asserted are the theory's for P1 u and P1 ⊕ bubble p on each side of an open crack
//! (scenes/orders.toml, read as compare/sdcompare_lib/theory.py reads it): u 2, p 1, λ 2 for the
//! P1 multipliers (M1, M1star) and 1 for the P0 one (M0), each less the verdict's margin. The
//! continuous p of the same scenes is held to its own, lower, orders (p 1/2 where the crack
//! opens), so that a change which made the two spaces the same fails here.

mod common;

use common::orders::Orders;
use common::{errors_by_level, last_two_rates, QUANTITIES};
use sdcrack_core::case::CasePattern;
use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};
use sdcrack_core::scene::Scene;
use sdcrack_core::study::CaseResult;
use sdcrack_io::scene_file::TomlScene;

/// The repository scene `name` at `levels`, δ = 0, no fields, both p spaces and both p masses.
fn scene_at_levels(name: &str, levels: &[u32]) -> Scene {
    at_levels(common::load(name), levels)
}

/// `s` at `levels`, δ = 0, no fields, both p spaces and both p masses.
fn at_levels(mut s: Scene, levels: &[u32]) -> Scene {
    s.axes.levels = levels.to_vec();
    s.axes.p_masses = vec![PMass::Consistent, PMass::Lumped];
    s.axes.p_spaces = vec![PSpace::Continuous, PSpace::BrokenTangential];
    s.axes.deltas = vec![0.0];
    s.fields = Default::default();
    s
}

/// Broken u, every multiplier, both p masses, both p spaces.
fn solve_broken(scene: &Scene) -> Vec<CaseResult> {
    let cases = common::solve(
        scene,
        CasePattern {
            u_space: Some(USpace::Broken),
            ..CasePattern::default()
        },
    );
    for c in &cases {
        assert!(
            c.converged && c.kkt.max() <= 1e-10,
            "level {} {} {} {}: {:?}",
            c.key.level,
            c.key.multiplier,
            c.key.p_mass,
            c.key.p_space,
            c.kkt
        );
    }
    cases
}

/// One series of the broken-u `cases`, levels increasing: (size, [e_u, e_p, e_p_x, e_λ]); the
/// size is h, or N^{-1/2} (N the unknowns) when `by_unknowns`.
fn series(
    cases: &[CaseResult],
    (m, p_mass, p_space): (MultiplierSpace, PMass, PSpace),
    by_unknowns: bool,
) -> Vec<(f64, [f64; 4])> {
    let keep = |c: &CaseResult| {
        c.key.multiplier == m && c.key.p_mass == p_mass && c.key.p_space == p_space
    };
    errors_by_level(cases, keep, by_unknowns)
}

/// The lowest rates of [`QUANTITIES`] that meet the theory's orders of the broken-tangential p
/// with broken u on a smooth (or graded) open crack, s = 1 (theory.tangential_rate): P1's u 2s,
/// p and p_x s; λ 2s for M1 and M1star, for M0's piecewise-constant λ the P0 jump's 1.
fn lowest_tangential_rates(m: MultiplierSpace) -> [f64; 4] {
    let o = Orders::repository();
    let s = o.regularity.smooth_s;
    let lambda = if m == MultiplierSpace::M0 {
        o.lambda.p0_jump
    } else {
        o.p1_u(s)
    };
    [o.p1_u(s), o.p1_p(s), o.p1_px(s), lambda].map(|order| o.lowest_rate(order))
}

/// Asserts the broken-tangential p's orders (lowest_tangential_rates) on each of the last two
/// steps of every series of `cases` with a multiplier of `multipliers`, both p masses; the p rate
/// held to at least `p_floor` where a measured bound is stricter.
fn assert_orders(
    what: &str,
    cases: &[CaseResult],
    multipliers: &[MultiplierSpace],
    by_unknowns: bool,
    p_floor: Option<f64>,
) {
    for &m in multipliers {
        for p_mass in [PMass::Consistent, PMass::Lumped] {
            let s = series(cases, (m, p_mass, PSpace::BrokenTangential), by_unknowns);
            let mut want = lowest_tangential_rates(m);
            if let Some(floor) = p_floor {
                want[1] = want[1].max(floor);
            }
            for q in 0..4 {
                for r in last_two_rates(&s, q) {
                    assert!(
                        r >= want[q],
                        "{what} {m} {p_mass}: {} rate {r:.3} < {}",
                        QUANTITIES[q],
                        want[q]
                    );
                }
            }
        }
    }
}

/// open-smooth (u = sign(y)·max(1/4 − x², 0)³·cos y, no tip singularity), uniform levels 0–5:
/// the broken-tangential p meets the orders of P1 on each side, while the continuous p of the
/// same cases stays at its order 1/2 where the crack opens (its last p rate below 1/2 + the
/// margin). The level-4 errors (128 × 64 cells) of broken u, M1, consistent p are those of an
/// independent prototype (Python, its own assembly and norms), to its three printed digits:
/// 2.46e-6, 5.08e-4, 4.99e-6 with the doubled tangential part, 3.10e-5, 2.44e-3, 1.43e-4 with the
/// continuous p.
#[test]
fn broken_tangential_p_reaches_the_optimal_orders_on_a_smooth_open_crack() {
    let cases = solve_broken(&scene_at_levels("open-smooth", &[0, 1, 2, 3, 4, 5]));
    assert_eq!(cases.len(), 6 * 3 * 2 * 2);
    assert_orders("open-smooth", &cases, &MultiplierSpace::ALL, false, None);
    let o = Orders::repository();
    let highest = o.open_crack.order + o.rule.margin;
    for p_mass in [PMass::Consistent, PMass::Lumped] {
        let s = series(
            &cases,
            (MultiplierSpace::M1, p_mass, PSpace::Continuous),
            false,
        );
        let [_, r] = last_two_rates(&s, 1);
        assert!(
            r < highest,
            "continuous p, {p_mass}: p rate {r} (expected ≈ 1/2)"
        );
    }
    for (p_space, want) in [
        (PSpace::BrokenTangential, [2.46e-6, 5.08e-4, 4.99e-6]),
        (PSpace::Continuous, [3.10e-5, 2.44e-3, 1.43e-4]),
    ] {
        let s = series(
            &cases,
            (MultiplierSpace::M1, PMass::Consistent, p_space),
            false,
        );
        let e = s[4].1;
        for (got, want, what) in [
            (e[0], want[0], "u"),
            (e[1], want[1], "p"),
            (e[3], want[2], "λ"),
        ] {
            // the prototype prints three digits: a rounding of at most half a unit of the last
            assert!(
                (got - want).abs() <= 0.005e-6f64.max(0.0051 * want),
                "{p_space} level 4 e_{what} = {got:e}, prototype {want:e}"
            );
        }
    }
}

/// tests/data/scenes/open-smooth-inclined.toml (open-smooth turned by 45°: the frames (ν, τ) are
/// no axes, so the rotation of the corner unknowns is exercised), uniform levels 1–4, M1: the
/// same orders.
#[test]
fn broken_tangential_p_converges_on_an_oblique_open_crack() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/scenes/open-smooth-inclined.toml");
    let mut scene = at_levels(
        Scene::from_file(&path).expect("test scene is valid"),
        &[1, 2, 3, 4],
    );
    scene.axes.multipliers = vec![MultiplierSpace::M1];
    let cases = solve_broken(&scene);
    assert_orders(
        "open-smooth-inclined",
        &cases,
        &scene.axes.multipliers,
        false,
        None,
    );
}

/// open-graded (the singular open crack, u ~ r^{1/2} at the tips, β = 0.4), levels 0–5, rates per
/// halving of N^{-1/2}: the broken-tangential p reaches the references' orders, where the
/// continuous p falls back to u ≈ 0.8–0.9, p ≈ 0.6 (docs/design.md); p is held to the measured
/// bound of scenes/orders.toml's [regression] (the references' ∇u order 1, without margin).
#[test]
fn broken_tangential_p_reaches_the_references_orders_on_graded_meshes() {
    let mut scene = scene_at_levels("open-graded", &[0, 1, 2, 3, 4, 5]);
    scene.axes.p_spaces = vec![PSpace::BrokenTangential];
    let cases = solve_broken(&scene);
    let p_floor = Orders::repository().regression.graded_tangential_p_rate;
    let all = MultiplierSpace::ALL;
    assert_orders("open-graded", &cases, &all, true, Some(p_floor));
}

/// The closed cracks (smooth u, λ = 0): the extra tangential unknowns change nothing that
/// matters. closed-exact (structured), kinked-exact (a kink, where p stays shared) and
/// two-cracks-exact (two cracks, gmsh levels): u within 0.5 % and p within 0.5 % (consistent) or
/// 4 % (lumped: the recovered p⁻·τ averages half a patch) of the continuous p's at every level,
/// λ = 0, and P1's orders on a smooth u, u 2, p 1, less the margin.
#[test]
fn closed_cracks_are_unchanged_by_the_broken_tangential_p() {
    let o = Orders::repository();
    let s = o.regularity.smooth_s;
    let (u_min, p_min) = (o.lowest_rate(o.p1_u(s)), o.lowest_rate(o.p1_p(s)));
    for name in ["closed-exact", "kinked-exact", "two-cracks-exact"] {
        let mut scene = scene_at_levels(name, &[1, 2, 3]);
        scene.axes.multipliers = vec![MultiplierSpace::M1, MultiplierSpace::M1Star];
        let cases = solve_broken(&scene);
        for m in &scene.axes.multipliers {
            for (p_mass, p_band) in [(PMass::Consistent, 0.005), (PMass::Lumped, 0.04)] {
                let new = series(&cases, (*m, p_mass, PSpace::BrokenTangential), false);
                let old = series(&cases, (*m, p_mass, PSpace::Continuous), false);
                for (a, b) in new.iter().zip(&old) {
                    let close = |x: f64, y: f64, band: f64| (x - y).abs() <= band * y;
                    assert!(close(a.1[0], b.1[0], 0.005), "{name} {m} {p_mass}: u");
                    assert!(close(a.1[1], b.1[1], p_band), "{name} {m} {p_mass}: p");
                    assert!(a.1[3] < 1e-12, "{name} {m} {p_mass}: e_λ = {}", a.1[3]);
                }
                for r in last_two_rates(&new, 0) {
                    assert!(r >= u_min, "{name} {m} {p_mass}: u rate {r}");
                }
                for r in last_two_rates(&new, 1) {
                    assert!(r >= p_min, "{name} {m} {p_mass}: p rate {r}");
                }
            }
        }
    }
}
