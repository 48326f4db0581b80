//! The scene's exact data checked against what the scene implies, before any solve is judged
//! against them (issue 42): `[exact] px`, `py` against ∂u/∂x, ∂u/∂y of `[exact] u`; `[data] f`
//! against −Δu on both sides of every crack; `[data] g` against u on ∂Ω; `[exact] jump` (or, when
//! it is not given, u⁺ − u⁻ by the face rule of
//! [`crate::problem::eval_on_face`]) against the one-sided limits of
//! u on Γc; and the contact conditions of the problem (docs/scenes.md): [∂u/∂ν] = 0, [u] ≥ 0,
//! ∂u/∂ν ≤ 0 and [u]·∂u/∂ν = 0 on Γc (ν the crack's normal, the + face the side it points into).
//!
//! The derivatives are symbolic ([`Expr::derivative`]); the comparisons are at sampled points
//! (the expression language has no simplifier that could prove two expressions equal), each with
//! a tolerance from the evaluation itself:
//! - two values that should be equal differ by more than [`ROUNDOFF_SAFETY`] × the sum of their
//!   running round-off bounds ([`Expr::eval_bounded`]: first-order, so a margin of 4 covers the
//!   neglected second-order terms). A correct scene's two sides agree to round-off; a wrong one
//!   (a flipped sign, a wrong term) is off by the size of the term, 10¹⁰ times more here;
//! - a value on a face of Γc is the one-sided limit of the value at c ± εν, extrapolated from
//!   ε = [`LIMIT_STEP`]·|segment| and ε/2 (Richardson: L = 2a(ε/2) − a(ε), exact for a linear
//!   a(ε)), with the truncation estimate |a(ε) − a(ε/2)|, which bounds the remainder of a smooth
//!   a(ε) (= |c₁|ε/2 + O(ε²) against the remainder's O(ε²)); it enters the tolerance times
//!   [`TRUNCATION_SAFETY`], on top of the round-off bounds.
//!
//! Sampled points: a [`GRID`]² grid over Ω's bounding box (offset by the irrational fraction
//! [`GRID_OFFSET`] of a cell, so that no point falls on an axis or a crack line of the scenes),
//! points at the distance [`NEAR_CRACK`]·|segment| on both sides of every crack segment, at the
//! fractions k/[`CRACK_SAMPLES`] along it (0 < k < [`CRACK_SAMPLES`]: the tips and kinks, where
//! u may be singular, are never sampled); [`BOUNDARY_SAMPLES`] points per edge of ∂Ω; the crack
//! points themselves for the jump and the contact conditions. A point where a value is not finite
//! (a singular derivative) is skipped: NaN data are refused elsewhere, at the quadrature points.

use super::exact_check::{
    at, boundary_points, crack_points, face_name, interior_points, num, one_sided, CrackPoint,
    Known,
};
pub use super::exact_check::{
    ExactDataError, BOUNDARY_SAMPLES, CRACK_SAMPLES, GRID, GRID_OFFSET, LIMIT_STEP, NEAR_CRACK,
    ROUNDOFF_SAFETY, TRUNCATION_SAFETY,
};
use super::validated::Problem;
use super::validated::Scene;
use crate::expr::{Expr, Var};
use crate::problem::{face_point, Exact};

/// Checks the scene's `[exact]` data (nothing to check without it); an elastic scene's by
/// [`super::elastic_exact_data::check`].
pub fn check(scene: &Scene) -> Result<(), ExactDataError> {
    let problem = match &scene.problem {
        Problem::Elasticity(data) => {
            return super::elastic_exact_data::check(data, &scene.domain, &scene.cracks)
        }
        Problem::Scalar(problem) => problem,
    };
    let Some(exact) = &problem.exact else {
        return Ok(());
    };
    check_gradient(exact, scene)?;
    check_source(exact, &problem.f, scene)?;
    check_boundary(exact, &problem.g, scene)?;
    check_crack(exact, scene)
}

fn check_gradient(exact: &Exact, scene: &Scene) -> Result<(), ExactDataError> {
    for (key, given, var, name) in [
        ("exact.px", &exact.px, Var::X, "∂u/∂x"),
        ("exact.py", &exact.py, Var::Y, "∂u/∂y"),
    ] {
        let derivative = exact.u.derivative(var);
        for p in interior_points(&scene.domain, &scene.cracks) {
            let g = Known::bounded(given.eval_bounded(p[0], p[1]));
            let d = Known::bounded(derivative.eval_bounded(p[0], p[1]));
            if g.differs(d) {
                return Err(ExactDataError::new(
                    key,
                    format!(
                        "{key} is not {name} of exact.u: {} = {}, {name} = {} at {}",
                        &key[6..],
                        num(g.value),
                        num(d.value),
                        at(p)
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn check_source(exact: &Exact, source: &Expr, scene: &Scene) -> Result<(), ExactDataError> {
    let uxx = exact.u.derivative(Var::X).derivative(Var::X);
    let uyy = exact.u.derivative(Var::Y).derivative(Var::Y);
    for p in interior_points(&scene.domain, &scene.cracks) {
        let f = Known::bounded(source.eval_bounded(p[0], p[1]));
        let (a, ea) = uxx.eval_bounded(p[0], p[1]);
        let (b, eb) = uyy.eval_bounded(p[0], p[1]);
        let minus_laplacian = -(a + b);
        let laplacian = Known::bounded((
            minus_laplacian,
            ea + eb + f64::EPSILON / 2.0 * minus_laplacian.abs(),
        ));
        if f.differs(laplacian) {
            return Err(ExactDataError::new(
                "data.f",
                format!(
                    "data.f is not −Δu of exact.u (−Δu = f in Ω \\ Γc): f = {}, −Δu = {} at {}",
                    num(f.value),
                    num(laplacian.value),
                    at(p)
                ),
            ));
        }
    }
    Ok(())
}

fn check_boundary(exact: &Exact, dirichlet: &Expr, scene: &Scene) -> Result<(), ExactDataError> {
    for p in boundary_points(&scene.domain) {
        let g = Known::bounded(dirichlet.eval_bounded(p[0], p[1]));
        let u = Known::bounded(exact.u.eval_bounded(p[0], p[1]));
        if g.differs(u) {
            return Err(ExactDataError::new(
                "data.g",
                format!(
                    "data.g is not exact.u on ∂Ω (u = g on ∂Ω): g = {}, u = {} at {}",
                    num(g.value),
                    num(u.value),
                    at(p)
                ),
            ));
        }
    }
    Ok(())
}

/// The scene's [u] at a crack point: `[exact] jump`, else u⁺ − u⁻ by the face rule.
fn scene_jump(exact: &Exact, c: &CrackPoint) -> Known {
    match &exact.jump {
        Some(j) => Known::bounded(j.eval_bounded(c.p[0], c.p[1])),
        None => {
            let face = |side: f64| {
                let q = face_point(c.p, c.normal, side);
                exact.u.eval_bounded(q[0], q[1])
            };
            let ((up, ep), (um, em)) = (face(1.0), face(-1.0));
            Known::bounded((up - um, ep + em + f64::EPSILON / 2.0 * (up - um).abs()))
        }
    }
}

fn check_crack(exact: &Exact, scene: &Scene) -> Result<(), ExactDataError> {
    let (jump_key, jump_name) = match exact.jump {
        Some(_) => ("exact.jump", "jump"),
        None => ("exact.u", "u⁺ − u⁻ by the face rule"),
    };
    let u = |q: [f64; 2]| exact.u.eval_bounded(q[0], q[1]);
    for c in crack_points(&scene.cracks) {
        let nu = c.normal;
        let flux = |q: [f64; 2]| {
            let (px, ex) = exact.px.eval_bounded(q[0], q[1]);
            let (py, ey) = exact.py.eval_bounded(q[0], q[1]);
            let v = px * nu[0] + py * nu[1];
            (
                v,
                ex * nu[0].abs() + ey * nu[1].abs() + 2.0 * f64::EPSILON * v.abs(),
            )
        };
        let jump = scene_jump(exact, &c);
        let (u_plus, u_minus) = (one_sided(&u, &c, 1.0), one_sided(&u, &c, -1.0));
        let limits = u_plus.minus(u_minus);
        let where_ = format!("at {} (ν = {})", at(c.p), at(nu));
        if jump.differs(limits) {
            return Err(ExactDataError::new(jump_key, format!(
                "{jump_key} is not u⁺ − u⁻ on Γc (+ face: the side ν points into): {jump_name} = {}, u⁺ − u⁻ = {} (the limits of exact.u from the faces) {where_}",
                num(jump.value),
                num(limits.value)
            )));
        }
        let faces = [
            (1.0, one_sided(&flux, &c, 1.0)),
            (-1.0, one_sided(&flux, &c, -1.0)),
        ];
        if faces[0].1.differs(faces[1].1) {
            return Err(ExactDataError::new("exact.u", format!(
                "exact.u breaks [∂u/∂ν] = 0 on Γc: ∂u/∂ν = {} on the + face, {} on the − face {where_}",
                num(faces[0].1.value),
                num(faces[1].1.value)
            )));
        }
        if jump.certainly_negative() {
            return Err(ExactDataError::new(
                jump_key,
                format!(
                    "{jump_key} breaks [u] ≥ 0 on Γc: [u] = {} {where_}",
                    num(jump.value)
                ),
            ));
        }
        for (side, q) in faces {
            if q.certainly_positive() {
                return Err(ExactDataError::new(
                    "exact.u",
                    format!(
                        "exact.u breaks ∂u/∂ν ≤ 0 on Γc: ∂u/∂ν = {} on the {} face {where_}",
                        num(q.value),
                        face_name(side)
                    ),
                ));
            }
            if jump.certainly_positive() && q.certainly_negative() {
                return Err(ExactDataError::new("exact.u", format!(
                    "exact.u breaks [u]·∂u/∂ν = 0 on Γc: the crack is open ([u] = {}) and its {} face is loaded (∂u/∂ν = {}) {where_}",
                    num(jump.value),
                    face_name(side),
                    num(q.value)
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check;
    use crate::scene::testing::scene;
    use crate::scene::KeyPath;

    const W: &str = "max(0.25 - x^2, 0)^3";
    /// W'' for W = max(1/4 − x², 0)³: −6·max(…)² + 24x²·max(…).
    const W_XX: &str = "(-6*max(0.25 - x^2, 0)^2 + 24*x^2*max(0.25 - x^2, 0))";

    /// Each contact condition of the problem fails on an exact solution that breaks it, with the
    /// other data consistent: the message names that condition.
    #[test]
    fn each_contact_condition_fails_alone() {
        let negative = format!("-sign(y)*{W}");
        let loaded = format!("sign(y)*{W} - y");
        let cases = [
            (
                scene(
                    "negative-jump",
                    &format!("sign(y)*{W_XX}"),
                    &negative,
                    Some((&negative, &format!("-2*{W}"))),
                ),
                "breaks [u] ≥ 0",
            ),
            (
                scene("pushing", "0", "y", Some(("y", "0"))),
                "breaks ∂u/∂ν ≤ 0",
            ),
            (
                scene(
                    "open-loaded",
                    &format!("-sign(y)*{W_XX}"),
                    &loaded,
                    Some((&loaded, &format!("2*{W}"))),
                ),
                "breaks [u]·∂u/∂ν = 0",
            ),
            (
                scene("kink", "0", "-y - abs(y)/2", Some(("-y - abs(y)/2", "0"))),
                "breaks [∂u/∂ν] = 0",
            ),
        ];
        for (s, words) in cases {
            let e = check(&s).expect_err(&s.name).message;
            assert!(e.contains(words), "{}: {e}", s.name);
            assert!(!e.contains(" is not "), "{}: {e}", s.name);
        }
    }

    /// The repository's exact solutions built by the test support pass; each datum changed by a
    /// sign or a term fails, naming its key.
    #[test]
    fn consistent_data_pass_and_each_changed_datum_fails() {
        let u = "sin(pi*x)*cos(pi*y) - y";
        let f = "2*pi^2*sin(pi*x)*cos(pi*y)";
        check(&scene("closed", f, u, Some((u, "0")))).unwrap();
        let cases = [
            (
                scene("f", "pi^2*sin(pi*x)*cos(pi*y)", u, Some((u, "0"))),
                "data.f is not −Δu",
            ),
            (
                scene("g", f, "sin(pi*x)*cos(pi*y) + y", Some((u, "0"))),
                "data.g is not exact.u",
            ),
            (
                scene("jump", f, u, Some((u, "0.1"))),
                "exact.jump is not u⁺ − u⁻",
            ),
        ];
        for (s, words) in cases {
            let e = check(&s).expect_err(&s.name).message;
            assert!(
                e.starts_with(&words[..6]) && e.contains(words),
                "{}: {e}",
                s.name
            );
            assert!(e.contains(" at ("), "{e}");
        }
        let mut s = scene("px", f, u, Some((u, "0")));
        s.scalar_mut().unwrap().exact.as_mut().unwrap().px =
            crate::expr::Expr::parse("-pi*cos(pi*x)*cos(pi*y)").unwrap();
        let e = check(&s).unwrap_err();
        assert_eq!(e.key, KeyPath::keys("exact.px"));
        assert!(e.message.starts_with("exact.px is not ∂u/∂x"), "{e}");
    }

    /// The round-off bound holds: the Laplacian of a harmonic u (open-exact's, with r^{1/2} tips)
    /// is evaluated to within its bound at points near the tips too, and the bound is not loose
    /// beyond 10⁴ (median).
    #[test]
    fn the_round_off_bound_covers_the_laplacian_of_a_harmonic_u() {
        use crate::expr::{Expr, Var};
        let u = Expr::parse(
            "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
        )
        .unwrap();
        let uxx = u.derivative(Var::X).derivative(Var::X);
        let uyy = u.derivative(Var::Y).derivative(Var::Y);
        let mut ratios = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (-0.99 + 0.0497 * i as f64, -0.9871 + 0.0493 * j as f64);
                let ((a, ea), (b, eb)) = (uxx.eval_bounded(x, y), uyy.eval_bounded(x, y));
                assert!(
                    (a + b).abs() <= ea + eb,
                    "({x}, {y}): {} > {}",
                    a + b,
                    ea + eb
                );
                if a + b != 0.0 {
                    ratios.push((ea + eb) / (a + b).abs());
                }
            }
        }
        ratios.sort_by(f64::total_cmp);
        assert!(
            ratios[ratios.len() / 2] < 1e4,
            "{}",
            ratios[ratios.len() / 2]
        );
    }
}
