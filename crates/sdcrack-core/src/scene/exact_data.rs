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

use super::key_path::KeyPath;
use super::validated::Scene;
use crate::expr::{Expr, Var};
use crate::geometry::{point_in_polygon, Inside};
use crate::problem::{face_point, Exact};

/// Grid points per direction over Ω's bounding box.
pub const GRID: usize = 20;
/// Offset of the grid points within their cells, as a fraction of a cell: 2 − φ (φ the golden
/// ratio), irrational, so that the points miss the lines x, y = simple fractions of the box.
pub const GRID_OFFSET: f64 = 0.381_966_011_250_105;
/// Samples per crack segment: the points at k/CRACK_SAMPLES of it, 0 < k < CRACK_SAMPLES.
pub const CRACK_SAMPLES: usize = 8;
/// Distance of the near-crack points from the crack, relative to the segment's length.
pub const NEAR_CRACK: f64 = 1e-3;
/// Samples per edge of ∂Ω (at (k + GRID_OFFSET)/BOUNDARY_SAMPLES of the edge).
pub const BOUNDARY_SAMPLES: usize = 12;
/// The larger step ε of the one-sided limits, relative to the segment's length.
pub const LIMIT_STEP: f64 = 1e-4;
/// Margin on the first-order round-off bounds.
pub const ROUNDOFF_SAFETY: f64 = 4.0;
/// Margin on the Richardson truncation estimate of a one-sided limit.
pub const TRUNCATION_SAFETY: f64 = 4.0;

/// A value with the tolerance it is known to: round-off bound plus truncation estimate.
#[derive(Clone, Copy, Debug)]
struct Known {
    value: f64,
    /// What the value may be off by: ROUNDOFF_SAFETY × round-off + TRUNCATION_SAFETY × truncation.
    tolerance: f64,
}

impl Known {
    fn bounded((value, roundoff): (f64, f64)) -> Known {
        Known {
            value,
            tolerance: ROUNDOFF_SAFETY * roundoff,
        }
    }

    fn judgeable(self) -> bool {
        self.value.is_finite() && self.tolerance.is_finite()
    }

    /// Certainly different from `other` (both judgeable, apart by more than both tolerances).
    fn differs(self, other: Known) -> bool {
        self.judgeable()
            && other.judgeable()
            && (self.value - other.value).abs() > self.tolerance + other.tolerance
    }

    fn certainly_positive(self) -> bool {
        self.judgeable() && self.value > self.tolerance
    }

    fn certainly_negative(self) -> bool {
        self.judgeable() && self.value < -self.tolerance
    }
}

/// A number as the messages print it: six significant digits.
fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
        let s = format!("{v:.6}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" {
            "0".into()
        } else {
            s
        }
    } else {
        format!("{v:.5e}")
    }
}

fn at(p: [f64; 2]) -> String {
    format!("({}, {})", num(p[0]), num(p[1]))
}

/// One point of a crack: where it is, the normal ν of its segment and the segment's length.
struct CrackPoint {
    p: [f64; 2],
    normal: [f64; 2],
    length: f64,
}

fn crack_points(scene: &Scene) -> Vec<CrackPoint> {
    let mut out = Vec::new();
    for crack in &scene.cracks {
        for k in 0..crack.segments() {
            let s = crack.segment(k);
            for i in 1..CRACK_SAMPLES {
                let t = i as f64 / CRACK_SAMPLES as f64;
                out.push(CrackPoint {
                    p: [
                        s.a[0] + t * (s.b[0] - s.a[0]),
                        s.a[1] + t * (s.b[1] - s.a[1]),
                    ],
                    normal: s.normal(),
                    length: s.length(),
                });
            }
        }
    }
    out
}

/// The grid points inside Ω, then the points beside every crack on both faces.
fn interior_points(scene: &Scene) -> Vec<[f64; 2]> {
    let polygon = scene.domain.polygon();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in &polygon {
        for d in 0..2 {
            lo[d] = lo[d].min(v[d]);
            hi[d] = hi[d].max(v[d]);
        }
    }
    let mut out = Vec::new();
    for i in 0..GRID {
        for j in 0..GRID {
            let p = [
                lo[0] + (i as f64 + GRID_OFFSET) / GRID as f64 * (hi[0] - lo[0]),
                lo[1] + (j as f64 + GRID_OFFSET) / GRID as f64 * (hi[1] - lo[1]),
            ];
            if point_in_polygon(p, &polygon) == Inside::Inside {
                out.push(p);
            }
        }
    }
    for c in crack_points(scene) {
        for side in [1.0, -1.0] {
            let d = side * NEAR_CRACK * c.length;
            out.push([c.p[0] + d * c.normal[0], c.p[1] + d * c.normal[1]]);
        }
    }
    out
}

fn boundary_points(scene: &Scene) -> Vec<[f64; 2]> {
    let polygon = scene.domain.polygon();
    let mut out = Vec::new();
    for (k, a) in polygon.iter().enumerate() {
        let b = polygon[(k + 1) % polygon.len()];
        for i in 0..BOUNDARY_SAMPLES {
            let t = (i as f64 + GRID_OFFSET) / BOUNDARY_SAMPLES as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

/// The limit of `e` at the crack point `c` from the face `side` (+1: the side ν points into),
/// extrapolated from c + side·ε·ν at ε and ε/2 (see the module docs).
fn one_sided(e: &dyn Fn([f64; 2]) -> (f64, f64), c: &CrackPoint, side: f64) -> Known {
    let sample = |eps: f64| {
        let d = side * eps;
        e([c.p[0] + d * c.normal[0], c.p[1] + d * c.normal[1]])
    };
    let eps = LIMIT_STEP * c.length;
    let (a1, e1) = sample(eps);
    let (a2, e2) = sample(eps / 2.0);
    Known {
        value: 2.0 * a2 - a1,
        tolerance: ROUNDOFF_SAFETY * (2.0 * e2 + e1) + TRUNCATION_SAFETY * (a1 - a2).abs(),
    }
}

fn face_name(side: f64) -> &'static str {
    if side > 0.0 {
        "+"
    } else {
        "−"
    }
}

/// Exact data that is not a solution of the scene's problem: the key it is about and one line
/// naming that key first (`exact.px is not ∂u/∂x: …`), the values and the point.
#[derive(Clone, Debug, PartialEq)]
pub struct ExactDataError {
    /// The key the message is about (`exact.px`, `data.f`, …).
    pub key: KeyPath,
    /// The message, naming the key first.
    pub message: String,
}

impl ExactDataError {
    fn new(key: &str, message: String) -> ExactDataError {
        ExactDataError {
            key: KeyPath::keys(key),
            message,
        }
    }
}

impl std::fmt::Display for ExactDataError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// Checks a scalar scene's `[exact]` data (nothing to check without it, nor here for an elastic
/// scene).
pub fn check(scene: &Scene) -> Result<(), ExactDataError> {
    let Some(problem) = scene.scalar() else {
        return Ok(());
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
        for p in interior_points(scene) {
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
    for p in interior_points(scene) {
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
    for p in boundary_points(scene) {
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
    for c in crack_points(scene) {
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
        let limits = Known {
            value: u_plus.value - u_minus.value,
            tolerance: u_plus.tolerance + u_minus.tolerance,
        };
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
    use super::{check, KeyPath};
    use crate::scene::testing::scene;

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
