//! The exact solutions of the repository scenes satisfy the crack problem (the problem, docs/scenes.md): −Δu = f off
//! the crack, u = g on Γ, and on Γc the face conditions [∂u/∂ν] = 0, [u] ≥ 0, ∂u/∂ν ≤ 0,
//! [u] ∂u/∂ν = 0 — all checked by finite differences, independently of the solver.

mod common;

use sdcrack_core::problem::eval_on_face;
use sdcrack_core::scene::Scene;

const H: f64 = 1e-4;

fn laplacian(s: &Scene, x: f64, y: f64) -> f64 {
    let u = &s.scalar().unwrap().exact.as_ref().unwrap().u;
    (u.eval(x + H, y) + u.eval(x - H, y) + u.eval(x, y + H) + u.eval(x, y - H) - 4.0 * u.eval(x, y))
        / (H * H)
}

/// Deterministic sample points in the domain, farther than 0.01 from the crack line and 0.1 from
/// the tips (where u ~ r^{1/2} makes finite differences inaccurate).
fn sample_points(n: usize) -> Vec<(f64, f64)> {
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pts = Vec::new();
    while pts.len() < n {
        let (x, y) = (-0.95 + 1.9 * next(), -0.95 + 1.9 * next());
        let near_tip = [(-0.5f64, 0.0f64), (0.5, 0.0)]
            .iter()
            .any(|(a, b)| (x - a).hypot(y - b) < 0.1);
        if y.abs() > 0.01 && !near_tip {
            pts.push((x, y));
        }
    }
    pts
}

fn check_pde_and_boundary(name: &str) {
    let s = common::load(name);
    let exact = s.scalar().unwrap().exact.as_ref().unwrap();
    for (x, y) in sample_points(200) {
        let r = -laplacian(&s, x, y) - s.scalar().unwrap().f.eval(x, y);
        assert!(
            r.abs() < 1e-4 * (1.0 + s.scalar().unwrap().f.eval(x, y).abs()),
            "{name}: −Δu − f = {r} at ({x}, {y})"
        );
        // the symbolic gradient agrees with finite differences
        let dx = (exact.u.eval(x + H, y) - exact.u.eval(x - H, y)) / (2.0 * H);
        let dy = (exact.u.eval(x, y + H) - exact.u.eval(x, y - H)) / (2.0 * H);
        assert!(
            (dx - exact.px.eval(x, y)).abs() < 1e-6,
            "{name}: px at ({x}, {y})"
        );
        assert!(
            (dy - exact.py.eval(x, y)).abs() < 1e-6,
            "{name}: py at ({x}, {y})"
        );
    }
    for k in 0..=40 {
        let t = -1.0 + 2.0 * k as f64 / 40.0;
        for (x, y) in [(t, -1.0), (t, 1.0), (-1.0, t), (1.0, t)] {
            assert!(
                (exact.u.eval(x, y) - s.scalar().unwrap().g.eval(x, y)).abs() < 1e-14,
                "{name}: g ≠ u at ({x}, {y})"
            );
        }
    }
}

/// (jump, ∂u/∂ν on the + face, ∂u/∂ν on the − face) at crack point x (crack on y = 0, ν = (0, 1)).
fn face_values(s: &Scene, x: f64) -> (f64, f64, f64) {
    let e = s.scalar().unwrap().exact.as_ref().unwrap();
    let nu = [0.0, 1.0];
    let up = eval_on_face(&e.u, [x, 0.0], nu, 1.0);
    let um = eval_on_face(&e.u, [x, 0.0], nu, -1.0);
    // one-sided second-order differences into each face
    let dplus = (-3.0 * up + 4.0 * e.u.eval(x, H) - e.u.eval(x, 2.0 * H)) / (2.0 * H);
    let dminus = (3.0 * um - 4.0 * e.u.eval(x, -H) + e.u.eval(x, -2.0 * H)) / (2.0 * H);
    if let Some(j) = &e.jump {
        assert!(
            (j.eval(x, 0.0) - (up - um)).abs() < 1e-12,
            "jump expression ≠ u⁺ − u⁻ at x = {x}"
        );
    }
    (up - um, dplus, dminus)
}

/// Checks the PDE and boundary data of scene `name` (check_pde_and_boundary) and returns
/// (x, face_values) at 39 interior points of its crack (−1/2, 1/2) × {0}.
fn along_the_crack(name: &str) -> Vec<(f64, (f64, f64, f64))> {
    check_pde_and_boundary(name);
    let s = common::load(name);
    (1..40)
        .map(|k| -0.5 + k as f64 / 40.0)
        .map(|x| (x, face_values(&s, x)))
        .collect()
}

#[test]
fn closed_exact_solution_satisfies_the_crack_problem() {
    for (_, (jump, dp, dm)) in along_the_crack("closed-exact") {
        assert!(jump.abs() < 1e-14, "closed: [u] = {jump}");
        assert!((dp - dm).abs() < 1e-6, "[∂u/∂ν] = {}", dp - dm);
        assert!(dp < -0.5, "closed: ∂u/∂ν = {dp} must be < 0");
    }
}

#[test]
fn open_exact_solution_satisfies_the_crack_problem() {
    for (x, (jump, dp, dm)) in along_the_crack("open-exact") {
        assert!(jump > 0.0, "open: [u] = {jump} must be > 0");
        assert!((jump - 2.0 * (0.25 - x * x).sqrt()).abs() < 1e-12);
        assert!(
            dp.abs() < 1e-5 && dm.abs() < 1e-5,
            "open faces are traction free: {dp}, {dm}"
        );
    }
}
