//! An elastic scene's exact data checked against what the scene implies (issue 45), the elastic
//! analogue of the scalar check [`super::exact_data`] (docs/elasticity.md):
//! - `[exact] sxx`, `syy`, `sxy` against Hooke's law of the symbolic derivatives of u
//!   ([`hooke_stress`]);
//! - `[data] fx`, `fy` against −div σ (σ as given or derived; its derivatives symbolic) on both
//!   sides of every crack;
//! - `[data] gx`, `gy` against u on every Dirichlet part of ∂Ω, `[data] traction.P` against σn on
//!   the part P (n the outward normal; [`boundary_edges`]), u's held components against 0 at the
//!   fixed points;
//! - on Γc, from the one-sided limits of u and σ: `[exact] opening`, `slip` (or, when not given,
//!   u⁺·ν − u⁻·ν and u⁺·τ − u⁻·τ by the face rule of [`crate::problem::eval_on_face`]) against
//!   \[u·ν\], \[u·τ\]; `[exact] pressure` against −σ_νν on each face; and the contact
//!   conditions \[σν\] = 0, σ_ντ = 0 on both faces, \[u·ν\] ≥ 0, σ_νν ≤ 0, σ_νν·\[u·ν\] = 0 (ν
//!   the crack's normal, the + face the side it points into, τ = ν turned by −90°, the crack's
//!   direction).
//!
//! The tolerances are the scalar check's, for the same reasons ([`super::exact_data`]'s module
//! documentation; the constants and the sampling live in [`super::exact_check`]):
//! - two values that should be equal differ by more than 4 × the sum of their first-order running
//!   round-off bounds ([`crate::expr::Expr::eval_bounded`]; 4 covers the neglected second-order
//!   terms). A combination of evaluated values (σn, u·ν, σ_νν, −div σ) carries the bounds of its
//!   terms and its own rounding (`exact_check::combination`). A correct scene's two sides
//!   agree to round-off, within a quarter of the tolerance (3.7 % at worst on Williams' field,
//!   near its r^{-1/2} tip included: a test holds it); a wrong sign, a wrong Lamé constant or a
//!   missing term is off by the size of the term, ~10¹⁰ times a round-off tolerance;
//! - a value on a face of Γc is the Richardson limit of its values at c ± εν, ε = 1e-4·|segment|
//!   and ε/2, with 4 × the truncation estimate |a(ε) − a(ε/2)| added to its tolerance (~1e-4 of
//!   the opening of Williams' field: a datum off by a term of its size is ~10⁴ times beyond it);
//! - a sign condition (σ_νν ≤ 0, \[u·ν\] ≥ 0) fails only where the value is certainly of the wrong
//!   sign (beyond its tolerance), and the complementarity σ_νν·\[u·ν\] = 0 only where the crack is
//!   certainly open and its face certainly loaded; a zero (σ_ντ, u at a fixed point) only where
//!   the value is certainly not 0.
//!
//! Sampled points, as for the scalar check: the 20 × 20 grid over Ω's box inside Ω and the points
//! 1e-3·|segment| beside both faces of every crack segment (Hooke's law, equilibrium); 12 points
//! per edge of ∂Ω away from its ends, on the edges of each part; the points k/8 of every crack
//! segment, 0 < k < 8: never a crack end, tip or mouth, nor a kink, where u may be singular. A
//! point where a value or its bound is not finite is skipped.

use super::exact_check::{
    at, combination, crack_points, edge_points, face_name, interior_points, num, one_sided,
    CrackPoint, ExactDataError, Known,
};
use super::key_path::KeyPath;
use crate::elasticity::{boundary_edges, ElasticData, ElasticExact, Material};
use crate::expr::{Expr, Var};
use crate::problem::{face_point, Domain, Polyline};

/// A value and its first-order round-off bound.
type Bounded = (f64, f64);

/// The components' names in keys and messages.
const U_KEYS: [&str; 2] = ["ux", "uy"];
const F_KEYS: [&str; 2] = ["fx", "fy"];
const G_KEYS: [&str; 2] = ["gx", "gy"];
const STRESS_KEYS: [&str; 3] = ["sxx", "syy", "sxy"];

/// The key messages about u as a whole name (its first component's line in the scene).
const U_KEY: &str = "exact.ux";
/// How messages name u as a whole.
const U_NAME: &str = "exact.ux, exact.uy";

/// Checks the elastic scene's `[exact]` data (nothing to check without it) on Ω = `domain` with
/// the cracks `cracks`: each datum against what u implies, and u against the problem's
/// conditions (module docs). The first datum found wrong is the error.
pub fn check(
    data: &ElasticData,
    domain: &Domain,
    cracks: &[Polyline],
) -> Result<(), ExactDataError> {
    let Some(exact) = &data.exact else {
        return Ok(());
    };
    check_hooke(exact, &data.material, domain, cracks)?;
    check_equilibrium(data, exact, domain, cracks)?;
    check_dirichlet(data, exact, domain)?;
    check_tractions(data, exact, domain)?;
    check_fixed(data, exact)?;
    check_crack(exact, cracks)
}

fn eval(e: &Expr, p: [f64; 2]) -> Bounded {
    e.eval_bounded(p[0], p[1])
}

/// σ at `p`: (σ_xx, σ_yy, σ_xy), each with its bound.
fn stress_at(exact: &ElasticExact, p: [f64; 2]) -> [Bounded; 3] {
    [0, 1, 2].map(|k| eval(&exact.stress[k], p))
}

/// The traction σn at `p` for the unit vector `n`: (σ_xx n_x + σ_xy n_y, σ_xy n_x + σ_yy n_y).
fn traction_at(exact: &ElasticExact, p: [f64; 2], n: [f64; 2]) -> [Bounded; 2] {
    let [sxx, syy, sxy] = stress_at(exact, p);
    [
        combination(&[(n[0], sxx), (n[1], sxy)]),
        combination(&[(n[0], sxy), (n[1], syy)]),
    ]
}

/// a·σb at `p` for the vectors a, b (σ symmetric): σ_νν for a = b = ν, σ_ντ for a = τ, b = ν.
fn stress_form(exact: &ElasticExact, p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> Bounded {
    let [sxx, syy, sxy] = stress_at(exact, p);
    combination(&[
        (a[0] * b[0], sxx),
        (a[1] * b[1], syy),
        (a[0] * b[1] + a[1] * b[0], sxy),
    ])
}

/// u·d at `p`.
fn u_along(exact: &ElasticExact, p: [f64; 2], d: [f64; 2]) -> Bounded {
    combination(&[(d[0], eval(&exact.u[0], p)), (d[1], eval(&exact.u[1], p))])
}

fn check_hooke(
    exact: &ElasticExact,
    m: &Material,
    domain: &Domain,
    cracks: &[Polyline],
) -> Result<(), ExactDataError> {
    // Hooke's law evaluated from the four derivatives (no text: any u that parses has them)
    let d = |c: usize, v: Var| exact.u[c].derivative(v);
    let (ux_x, uy_y) = (d(0, Var::X), d(1, Var::Y));
    let (ux_y, uy_x) = (d(0, Var::Y), d(1, Var::X));
    let (lam, mu) = (m.lambda_in_plane(), m.mu);
    let law = |k: usize, p: [f64; 2]| -> Bounded {
        let (a, b) = (eval(&ux_x, p), eval(&uy_y, p));
        match k {
            0 => combination(&[(lam + 2.0 * mu, a), (lam, b)]),
            1 => combination(&[(lam, a), (lam + 2.0 * mu, b)]),
            _ => combination(&[(mu, eval(&ux_y, p)), (mu, eval(&uy_x, p))]),
        }
    };
    let points = interior_points(domain, cracks);
    for (k, name) in STRESS_KEYS.iter().enumerate() {
        for &p in &points {
            let given = Known::bounded(eval(&exact.stress[k], p));
            let hooke = Known::bounded(law(k, p));
            if given.differs(hooke) {
                let key = format!("exact.{name}");
                return Err(ExactDataError::new(&key, format!(
                    "{key} is not Hooke's law of {U_NAME} (σ = λ* tr ε(u) I + 2μ ε(u), λ* = {}, μ = {}): {name} = {}, σ(u) gives {} at {}",
                    num(m.lambda_in_plane()),
                    num(m.mu),
                    num(given.value),
                    num(hooke.value),
                    at(p)
                )));
            }
        }
    }
    Ok(())
}

fn check_equilibrium(
    data: &ElasticData,
    exact: &ElasticExact,
    domain: &Domain,
    cracks: &[Polyline],
) -> Result<(), ExactDataError> {
    let [sxx, syy, sxy] = &exact.stress;
    // (div σ)_x = ∂σ_xx/∂x + ∂σ_xy/∂y, (div σ)_y = ∂σ_xy/∂x + ∂σ_yy/∂y
    let divergence = [
        [sxx.derivative(Var::X), sxy.derivative(Var::Y)],
        [sxy.derivative(Var::X), syy.derivative(Var::Y)],
    ];
    let points = interior_points(domain, cracks);
    for (k, [a, b]) in divergence.iter().enumerate() {
        for &p in &points {
            let f = Known::bounded(eval(&data.f[k], p));
            let minus_div = Known::bounded(combination(&[(-1.0, eval(a, p)), (-1.0, eval(b, p))]));
            if f.differs(minus_div) {
                let (key, c) = (format!("data.{}", F_KEYS[k]), ["x", "y"][k]);
                return Err(ExactDataError::new(&key, format!(
                    "{key} is not −(div σ)_{c} of the exact stress (−div σ = f in Ω \\ Γc): {} = {}, −(div σ)_{c} = {} at {}",
                    F_KEYS[k],
                    num(f.value),
                    num(minus_div.value),
                    at(p)
                )));
            }
        }
    }
    Ok(())
}

fn check_dirichlet(
    data: &ElasticData,
    exact: &ElasticExact,
    domain: &Domain,
) -> Result<(), ExactDataError> {
    let Some(g) = &data.g else {
        return Ok(());
    };
    for edge in boundary_edges(domain) {
        if data.tractions.iter().any(|t| edge.belongs_to(&t.part)) {
            continue;
        }
        for p in edge_points(edge.a, edge.b) {
            for k in 0..2 {
                let given = Known::bounded(eval(&g[k], p));
                let u = Known::bounded(eval(&exact.u[k], p));
                if given.differs(u) {
                    let key = format!("data.{}", G_KEYS[k]);
                    return Err(ExactDataError::new(&key, format!(
                        "{key} is not exact.{} on {} (u = g on the Dirichlet parts of ∂Ω): {} = {}, {} = {} at {}",
                        U_KEYS[k],
                        edge.part.0,
                        G_KEYS[k],
                        num(given.value),
                        U_KEYS[k],
                        num(u.value),
                        at(p)
                    )));
                }
            }
        }
    }
    Ok(())
}

fn check_tractions(
    data: &ElasticData,
    exact: &ElasticExact,
    domain: &Domain,
) -> Result<(), ExactDataError> {
    let edges = boundary_edges(domain);
    for traction in &data.tractions {
        let key = format!("data.traction.{}", traction.part.0);
        let on_part: Vec<_> = edges
            .iter()
            .filter(|e| e.belongs_to(&traction.part))
            .collect();
        if on_part.is_empty() {
            return Err(ExactDataError::new(
                &key,
                format!(
                    "{key} names no part of ∂Ω (the parts: {})",
                    edges
                        .iter()
                        .map(|e| e.part.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        for edge in on_part {
            let n = edge.outward_normal();
            for p in edge_points(edge.a, edge.b) {
                let t = [0, 1].map(|k| Known::bounded(eval(&traction.t[k], p)));
                let sn = traction_at(exact, p, n).map(Known::bounded);
                if t[0].differs(sn[0]) || t[1].differs(sn[1]) {
                    return Err(ExactDataError::new(&key, format!(
                        "{key} is not σn of the exact stress on {} (σn = t, n = {} the outward normal): t = {}, σn = {} at {}",
                        edge.part.0,
                        at(n),
                        at([t[0].value, t[1].value]),
                        at([sn[0].value, sn[1].value]),
                        at(p)
                    )));
                }
            }
        }
    }
    Ok(())
}

fn check_fixed(data: &ElasticData, exact: &ElasticExact) -> Result<(), ExactDataError> {
    for (i, fixed) in data.fixed.iter().enumerate() {
        for k in (0..2).filter(|&k| fixed.components[k]) {
            let u = Known::bounded(eval(&exact.u[k], fixed.point));
            if u.certainly_nonzero() {
                let key = KeyPath::keys("data.fixed").index(i);
                return Err(ExactDataError::at_key(
                    key.clone(),
                    format!(
                        "{key} holds {} = 0 at {}, but exact.{} = {} there",
                        U_KEYS[k],
                        at(fixed.point),
                        U_KEYS[k],
                        num(u.value)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A jump on Γc as the scene gives it: the `[exact]` expression at the crack point, else
/// u⁺·d − u⁻·d by the face rule.
fn scene_jump(exact: &ElasticExact, given: Option<&Expr>, c: &CrackPoint, d: [f64; 2]) -> Known {
    match given {
        Some(e) => Known::bounded(eval(e, c.p)),
        None => {
            let face = |side: f64| u_along(exact, face_point(c.p, c.normal, side), d);
            Known::bounded(combination(&[(1.0, face(1.0)), (-1.0, face(-1.0))]))
        }
    }
}

/// The two faces' limits of `e` at `c`, + face first.
fn limits(e: &dyn Fn([f64; 2]) -> Bounded, c: &CrackPoint) -> [(f64, Known); 2] {
    [1.0, -1.0].map(|side| (side, one_sided(e, c, side)))
}

/// What the scene says a crack point's opening \[u·ν\] is, and whether `[exact] opening` said it.
struct Opening {
    value: Known,
    given: bool,
}

impl Opening {
    /// The key a message about the opening names: `exact.opening`, else u's.
    fn key(&self) -> &'static str {
        if self.given {
            "exact.opening"
        } else {
            U_KEY
        }
    }

    /// The subject of a message about it, with its verb.
    fn breaks(&self) -> &'static str {
        if self.given {
            "exact.opening breaks"
        } else {
            "exact.ux, exact.uy break"
        }
    }
}

fn check_crack(exact: &ElasticExact, cracks: &[Polyline]) -> Result<(), ExactDataError> {
    for c in crack_points(cracks) {
        let where_ = format!("at {} (ν = {})", at(c.p), at(c.normal));
        let opening = check_jumps(exact, &c, &where_)?;
        check_face_tractions(exact, &c, &where_)?;
        check_contact(exact, &c, &opening, &where_)?;
    }
    Ok(())
}

/// τ = ν turned by −90°: the crack's direction.
fn tangent(nu: [f64; 2]) -> [f64; 2] {
    [nu[1], -nu[0]]
}

/// The scene's opening and slip (given, or by the face rule) against \[u·ν\] and \[u·τ\] from the
/// faces' limits; the scene's opening for the contact conditions.
fn check_jumps(
    exact: &ElasticExact,
    c: &CrackPoint,
    where_: &str,
) -> Result<Opening, ExactDataError> {
    let mut opening = None;
    for (name, given, d, v) in [
        ("opening", &exact.opening, c.normal, "ν"),
        ("slip", &exact.slip, tangent(c.normal), "τ"),
    ] {
        let jump = scene_jump(exact, given.as_ref(), c, d);
        let [(_, plus), (_, minus)] = limits(&|q| u_along(exact, q, d), c);
        let faces = plus.minus(minus);
        if jump.differs(faces) {
            let (key, subject, what) = match given {
                Some(_) => {
                    let key = format!("exact.{name}");
                    (key.clone(), key, format!("{name} = {}", num(jump.value)))
                }
                None => (
                    U_KEY.to_string(),
                    U_NAME.to_string(),
                    format!("u⁺·{v} − u⁻·{v} by the face rule = {}", num(jump.value)),
                ),
            };
            return Err(ExactDataError::new(&key, format!(
                "{subject} is not [u·{v}] = u⁺·{v} − u⁻·{v} on Γc (the {name}; + face: the side ν points into): {what}, the limits of {U_NAME} from the faces give {} {where_}",
                num(faces.value)
            )));
        }
        opening.get_or_insert(Opening {
            value: jump,
            given: given.is_some(),
        });
    }
    Ok(opening.expect("the opening is the first jump"))
}

/// \[σν\] = 0 across Γc, σ_ντ = 0 on both faces, and the given pressure against −σ_νν.
fn check_face_tractions(
    exact: &ElasticExact,
    c: &CrackPoint,
    where_: &str,
) -> Result<(), ExactDataError> {
    let nu = c.normal;
    let [(_, tx_plus), (_, tx_minus)] = limits(&|q| traction_at(exact, q, nu)[0], c);
    let [(_, ty_plus), (_, ty_minus)] = limits(&|q| traction_at(exact, q, nu)[1], c);
    if tx_plus.differs(tx_minus) || ty_plus.differs(ty_minus) {
        return Err(ExactDataError::new(
            U_KEY,
            format!(
                "{U_NAME} break [σν] = 0 on Γc: σν = {} on the + face, {} on the − face {where_}",
                at([tx_plus.value, ty_plus.value]),
                at([tx_minus.value, ty_minus.value])
            ),
        ));
    }
    for (side, s) in limits(&|q| stress_form(exact, q, tangent(nu), nu), c) {
        if s.certainly_nonzero() {
            return Err(ExactDataError::new(
                U_KEY,
                format!(
                "{U_NAME} break σ_ντ = 0 on Γc (frictionless): σ_ντ = {} on the {} face {where_}",
                num(s.value),
                face_name(side)
            ),
            ));
        }
    }
    let Some(pressure) = &exact.pressure else {
        return Ok(());
    };
    let given = Known::bounded(eval(pressure, c.p));
    for (side, s) in limits(&|q| stress_form(exact, q, nu, nu), c) {
        let minus_s = Known {
            value: -s.value,
            ..s
        };
        if given.differs(minus_s) {
            return Err(ExactDataError::new("exact.pressure", format!(
                "exact.pressure is not −σ_νν on Γc: pressure = {}, −σ_νν = {} on the {} face {where_}",
                num(given.value),
                num(minus_s.value),
                face_name(side)
            )));
        }
    }
    Ok(())
}

/// \[u·ν\] ≥ 0, σ_νν ≤ 0 on both faces, and σ_νν·\[u·ν\] = 0: a face certainly pressed where the
/// crack is certainly open fails.
fn check_contact(
    exact: &ElasticExact,
    c: &CrackPoint,
    opening: &Opening,
    where_: &str,
) -> Result<(), ExactDataError> {
    let w = opening.value;
    if w.certainly_negative() {
        return Err(ExactDataError::new(
            opening.key(),
            format!(
                "{} [u·ν] ≥ 0 on Γc (the faces interpenetrate): [u·ν] = {} {where_}",
                opening.breaks(),
                num(w.value)
            ),
        ));
    }
    for (side, s) in limits(&|q| stress_form(exact, q, c.normal, c.normal), c) {
        if s.certainly_positive() {
            return Err(ExactDataError::new(U_KEY, format!(
                "{U_NAME} break σ_νν ≤ 0 on Γc (the faces pull on each other): σ_νν = {} on the {} face {where_}",
                num(s.value),
                face_name(side)
            )));
        }
        if w.certainly_positive() && s.certainly_negative() {
            return Err(ExactDataError::new(U_KEY, format!(
                "{U_NAME} break σ_νν·[u·ν] = 0 on Γc: the crack is open ([u·ν] = {}) and its {} face is pressed (σ_νν = {}) {where_}",
                num(w.value),
                face_name(side),
                num(s.value)
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check;
    use crate::elasticity::{hooke_stress, Material, PlaneModel};
    use crate::expr::Expr;
    use crate::problem::{Domain, Polyline};
    use crate::scene::elastic_testing::*;
    use crate::scene::KeyPath;

    /// The edge crack of the Williams scenes: (−1, 0) → (0, 0), a mouth on ∂Ω and the tip at the
    /// origin; ν = (0, 1).
    fn edge_crack() -> Vec<Polyline> {
        vec![crack([-1.0, 0.0], [0.0, 0.0])]
    }

    fn interior_crack() -> Vec<Polyline> {
        vec![crack([-0.5, 0.0], [0.5, 0.0])]
    }

    fn sum(a: &[String; 2], b: &[String; 2]) -> [String; 2] {
        [0, 1].map(|k| format!("({}) + ({})", a[k], b[k]))
    }

    fn refs(s: &[String; 2]) -> [&str; 2] {
        [s[0].as_str(), s[1].as_str()]
    }

    /// The message of the check's error on `e`'s data, which must name `key` and start with it.
    fn fails(e: Elastic, cracks: &[Polyline], key: &str) -> String {
        let err = check(&e.data, &square(), cracks).expect_err(key);
        assert_eq!(err.key.to_last_key(), KeyPath::keys(key), "{}", err.message);
        assert!(err.message.contains(" at ("), "{}", err.message);
        err.message
    }

    /// Williams' open field K_I = 1, K_II = 0.5 (E = 1, ν = 0.3, plane strain), g = u on every
    /// side but the right one, where the traction is σn = (σ_xx, σ_xy) of Hooke's law.
    fn williams_open(k1: f64, k2: f64) -> Elastic {
        let m = steel_like();
        let u = williams(k1, k2, &m);
        let stress = hooke_stress(&refs(&u).map(|s| Expr::parse(s).unwrap()), &m).unwrap();
        let t = [stress[0].to_string_infix(), stress[2].to_string_infix()];
        Elastic::new(m, refs(&u), ["0", "0"])
            .g_is_u()
            .traction("right", refs(&t))
    }

    /// The closed field c = 0.1 plus K_II = 0.3 × Williams' mode II: shut everywhere on the edge
    /// crack, slipping as √r.
    fn closed_with_slip() -> Elastic {
        let m = steel_like();
        let u = sum(&closed(0.1), &williams(0.0, 0.3, &m));
        Elastic::new(m, refs(&u), refs(&closed_force(0.1, &m)))
            .g_is_u()
            .opening("0")
            .slip(&williams_jump(0.3, &m))
            .pressure(&closed_pressure(0.1, &m))
    }

    /// Uniform compression p = 0.2 across the interior crack, all traction, two fixed corners.
    fn patch_test(m: Material, p: f64) -> Elastic {
        let u = patch(p, &m);
        let (top, bottom) = (format!("{}", -p), format!("{p}"));
        Elastic::new(m, refs(&u), ["0", "0"])
            .stress(["0", &top, "0"])
            .traction("top", ["0", &top])
            .traction("bottom", ["0", &bottom])
            .traction("left", ["0", "0"])
            .traction("right", ["0", "0"])
            .fixed([-1.0, -1.0], [true, true])
            .fixed([-1.0, 1.0], [true, false])
            .opening("0")
            .slip("0")
            .pressure(&bottom)
    }

    #[test]
    fn the_williams_closed_and_patch_fields_pass() {
        check(&williams_open(1.0, 0.5).data, &square(), &edge_crack()).unwrap();
        let m = steel_like();
        let open = williams_open(1.0, 0.5)
            .opening(&williams_jump(1.0, &m))
            .slip(&williams_jump(0.5, &m))
            .pressure("0");
        check(&open.data, &square(), &edge_crack()).unwrap();
        let given = williams_stress(1.0, 0.5);
        let stressed = williams_open(1.0, 0.5).stress([&given[0], &given[1], &given[2]]);
        check(&stressed.data, &square(), &edge_crack()).unwrap();
        check(&closed_with_slip().data, &square(), &edge_crack()).unwrap();
        check(
            &patch_test(steel_like(), 0.2).data,
            &square(),
            &interior_crack(),
        )
        .unwrap();
        let stress = Material {
            plane: PlaneModel::Stress,
            ..steel_like()
        };
        check(&patch_test(stress, 0.2).data, &square(), &interior_crack()).unwrap();
        // the patch with Dirichlet sides (g = u on left and right: the parts without a traction)
        let m = steel_like();
        let u = patch(0.2, &m);
        let dirichlet = Elastic::new(m, refs(&u), ["0", "0"])
            .g_is_u()
            .traction("top", ["0", "-0.2"])
            .traction("bottom", ["0", "0.2"]);
        check(&dirichlet.data, &square(), &interior_crack()).unwrap();
        // the same square as a polygon: its parts are edge1 (bottom) … edge4 (left)
        let polygon = Domain::Polygon(vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]);
        let by_edges = Elastic::new(m, refs(&u), ["0", "0"])
            .g_is_u()
            .traction("edge3", ["0", "-0.2"])
            .traction("edge1", ["0", "0.2"]);
        check(&by_edges.data, &polygon, &interior_crack()).unwrap();
    }

    /// Williams' fields before use: the check above holds them to equilibrium and Hooke's law;
    /// here their stress intensities (docs/elasticity.md's tip frame: σ_yy(r, 0) = K_I/√(2πr),
    /// σ_xy(r, 0) = K_II/√(2πr) up to O(1)) and traction-free faces.
    #[test]
    fn williams_fields_have_their_stress_intensities_and_free_faces() {
        let m = steel_like();
        for (k1, k2) in [(1.0, 0.0), (0.0, 1.0)] {
            let u = williams(k1, k2, &m).map(|s| Expr::parse(&s).unwrap());
            let [_, syy, sxy] = hooke_stress(&u, &m).unwrap();
            let r = 1e-6;
            let scale = (2.0 * std::f64::consts::PI * r).sqrt();
            assert!((syy.eval(r, 0.0) * scale - k1).abs() < 1e-9);
            assert!((sxy.eval(r, 0.0) * scale - k2).abs() < 1e-9);
            for y in [0.0, -0.0] {
                assert!(syy.eval(-0.3, y).abs() < 1e-12 && sxy.eval(-0.3, y).abs() < 1e-12);
            }
            // the pure modes are their own kind only: mode I has no slip, mode II no opening
            let jump = |c: usize| u[c].eval(-0.3, 0.0) - u[c].eval(-0.3, -0.0);
            let expected = (m.kolosov() + 1.0) / m.mu * (0.3 / (2.0 * std::f64::consts::PI)).sqrt();
            assert!(
                (jump(1) - k1 * expected).abs() < 1e-14 && (jump(0) - k2 * expected).abs() < 1e-14
            );
        }
    }

    #[test]
    fn a_stress_with_a_modes_sign_flipped_fails_hookes_law() {
        // Williams' σ_xx with mode II's term of the wrong sign
        let mut given = williams_stress(1.0, 0.5);
        given[0] = given[0].replace(") - (0.5)*", ") + (0.5)*");
        assert_ne!(given[0], williams_stress(1.0, 0.5)[0]);
        let e = williams_open(1.0, 0.5).stress([&given[0], &given[1], &given[2]]);
        let msg = fails(e, &edge_crack(), "exact.sxx");
        assert!(msg.starts_with("exact.sxx is not Hooke's law"), "{msg}");
    }

    #[test]
    fn a_wrong_lame_constant_fails_hookes_law() {
        // the patch's u from plane stress's λ*, its material plane strain
        let strain = steel_like();
        let stress = Material {
            plane: PlaneModel::Stress,
            ..strain
        };
        let mut e = patch_test(strain, 0.2);
        let u = patch(0.2, &stress).map(|s| Expr::parse(&s).unwrap());
        e.data.exact.as_mut().unwrap().u = u;
        let msg = fails(e, &interior_crack(), "exact.sxx");
        assert!(msg.starts_with("exact.sxx is not Hooke's law"), "{msg}");
        // λ and μ swapped
        let swapped = Material {
            lambda: strain.mu,
            mu: strain.lambda,
            plane: PlaneModel::Strain,
        };
        let mut e = patch_test(strain, 0.2);
        e.data.material = swapped;
        fails(e, &interior_crack(), "exact.sxx");
    }

    #[test]
    fn a_flipped_mode_or_a_missing_term_fails_equilibrium() {
        // mode II's u_y of the wrong sign: not a Navier field, −div σ ≠ 0 = f
        let m = steel_like();
        let (good, flipped) = (williams(1.0, 0.5, &m), williams(1.0, -0.5, &m));
        let e = Elastic::new(m, [&good[0], &flipped[1]], ["0", "0"]).g_is_u();
        let msg = fails(e, &edge_crack(), "data.fx");
        assert!(msg.starts_with("data.fx is not −(div σ)_x"), "{msg}");
        // f_x of u_C without its 0.1μ term
        let mut e = closed_with_slip();
        let f = format!("-0.1*sin(x)*cos(y)*0.7*{}", m.lambda_in_plane());
        e.data.f[0] = Expr::parse(&f).unwrap();
        fails(e, &edge_crack(), "data.fx");
    }

    #[test]
    fn g_off_u_on_a_dirichlet_part_fails() {
        let m = steel_like();
        let u = patch(0.2, &m);
        let wrong = format!("-({})", u[1]);
        let e = Elastic::new(m, refs(&u), ["0", "0"])
            .g([&u[0], &wrong])
            .traction("top", ["0", "-0.2"])
            .traction("bottom", ["0", "0.2"]);
        let msg = fails(e, &interior_crack(), "data.gy");
        assert!(msg.starts_with("data.gy is not exact.uy on right"), "{msg}");
    }

    #[test]
    fn a_traction_with_the_wrong_normal_fails() {
        // the bottom's traction written with the top's normal (0, 1): σn = (0, −p)
        let mut e = patch_test(steel_like(), 0.2);
        e.data.tractions[1].t[1] = Expr::parse("-0.2").unwrap();
        let msg = fails(e, &interior_crack(), "data.traction.bottom");
        assert!(
            msg.starts_with("data.traction.bottom is not σn") && msg.contains("n = (0, -1)"),
            "{msg}"
        );
        let e = patch_test(steel_like(), 0.2).traction("front", ["0", "0"]);
        let err = check(&e.data, &square(), &interior_crack()).unwrap_err();
        assert!(err.message.contains("names no part of ∂Ω"), "{err}");
    }

    #[test]
    fn a_fixed_point_where_u_moves_fails() {
        let e = patch_test(steel_like(), 0.2).fixed([1.0, -1.0], [true, false]);
        let err = check(&e.data, &square(), &interior_crack()).unwrap_err();
        assert_eq!(err.key, KeyPath::keys("data.fixed").index(2));
        assert!(
            err.message
                .starts_with("data.fixed[2] holds ux = 0 at (1, -1)"),
            "{err}"
        );
    }

    #[test]
    fn a_penetrating_opening_fails() {
        // K_I < 0: the faces of the open Williams crack overlap
        let msg = fails(williams_open(-1.0, 0.5), &edge_crack(), "exact.ux");
        assert!(
            msg.starts_with("exact.ux, exact.uy break [u·ν] ≥ 0"),
            "{msg}"
        );
        let m = steel_like();
        let e = williams_open(-1.0, 0.5).opening(&williams_jump(-1.0, &m));
        let msg = fails(e, &edge_crack(), "exact.opening");
        assert!(msg.starts_with("exact.opening breaks [u·ν] ≥ 0"), "{msg}");
    }

    #[test]
    fn a_given_opening_slip_or_pressure_off_the_field_fails() {
        let m = steel_like();
        // Williams' opening with κ − 1 for κ + 1
        let wrong = williams_jump(1.0, &m).replacen(" + 1)", " - 1)", 1);
        assert_ne!(wrong, williams_jump(1.0, &m));
        let e = williams_open(1.0, 0.5).opening(&wrong);
        let msg = fails(e, &edge_crack(), "exact.opening");
        assert!(msg.starts_with("exact.opening is not [u·ν]"), "{msg}");
        let e = williams_open(1.0, 0.5).slip(&williams_jump(-0.5, &m));
        let msg = fails(e, &edge_crack(), "exact.slip");
        assert!(msg.starts_with("exact.slip is not [u·τ]"), "{msg}");
        let e = closed_with_slip().pressure(&format!("-({})", closed_pressure(0.1, &m)));
        let msg = fails(e, &edge_crack(), "exact.pressure");
        assert!(msg.starts_with("exact.pressure is not −σ_νν"), "{msg}");
    }

    #[test]
    fn a_shear_on_the_crack_fails() {
        // u_C plus the simple shear (0.05 y, 0): σ_xy = 0.05μ on the crack, no body force
        let m = steel_like();
        let u = sum(&closed(0.1), &["0.05*y".to_string(), "0".to_string()]);
        let e = Elastic::new(m, refs(&u), refs(&closed_force(0.1, &m))).g_is_u();
        let msg = fails(e, &edge_crack(), "exact.ux");
        assert!(
            msg.starts_with("exact.ux, exact.uy break σ_ντ = 0"),
            "{msg}"
        );
    }

    #[test]
    fn a_crack_in_tension_fails() {
        // the patch pulled (p = −0.2) with the crack shut: σ_νν = 0.2 > 0
        let msg = fails(
            patch_test(steel_like(), -0.2).pressure("-0.2"),
            &interior_crack(),
            "exact.ux",
        );
        assert!(
            msg.starts_with("exact.ux, exact.uy break σ_νν ≤ 0"),
            "{msg}"
        );
    }

    #[test]
    fn an_open_pressed_crack_fails() {
        // the compressed patch with its faces 0.02 apart across a crack through Ω
        let m = steel_like();
        let u = patch(0.2, &m);
        let apart = format!("{} + 0.01*sign(y)", u[1]);
        let e = Elastic::new(m, [&u[0], &apart], ["0", "0"]).g_is_u();
        let through = vec![crack([-1.0, 0.0], [1.0, 0.0])];
        let msg = fails(e, &through, "exact.ux");
        assert!(
            msg.starts_with("exact.ux, exact.uy break σ_νν·[u·ν] = 0"),
            "{msg}"
        );
    }

    #[test]
    fn a_traction_jump_across_the_crack_fails() {
        // u_y = −0.2y − 0.1|y|: shut, compressed on both faces, but more on the + face
        let e = Elastic::new(steel_like(), ["0", "-0.2*y - 0.1*abs(y)"], ["0", "0"]).g_is_u();
        let msg = fails(e, &interior_crack(), "exact.ux");
        assert!(
            msg.starts_with("exact.ux, exact.uy break [σν] = 0"),
            "{msg}"
        );
    }

    /// The tolerance is the round-off of the evaluation, not a loose margin: on Williams' field
    /// (given stress against Hooke's law, −div σ against f = 0, at every interior point, near the
    /// r^{-1/2} tip too) every comparison is judged (finite bounds), the two sides agree within a
    /// quarter of it, and it is below 1e-11 of the values at the median point.
    #[test]
    fn the_round_off_tolerance_covers_williams_and_is_tight() {
        use super::{combination, eval, interior_points, Known};
        use crate::expr::Var;
        let m = steel_like();
        let given = williams_stress(1.0, 0.5);
        let e = williams_open(1.0, 0.5).stress([&given[0], &given[1], &given[2]]);
        let exact = e.data.exact.as_ref().unwrap();
        let law = hooke_stress(&exact.u, &m).unwrap();
        let [sxx, syy, sxy] = &exact.stress;
        let divergence = [
            [sxx.derivative(Var::X), sxy.derivative(Var::Y)],
            [sxy.derivative(Var::X), syy.derivative(Var::Y)],
        ];
        let (mut ratios, mut relative) = (Vec::new(), Vec::new());
        for p in interior_points(&square(), &edge_crack()) {
            for k in 0..3 {
                let a = Known::bounded(eval(&exact.stress[k], p));
                let b = Known::bounded(eval(&law[k], p));
                ratios.push((a.value - b.value).abs() / (a.tolerance + b.tolerance));
                relative.push((a.tolerance + b.tolerance) / a.value.abs());
            }
            for [a, b] in &divergence {
                let terms = [eval(a, p), eval(b, p)];
                let d = Known::bounded(combination(&[(-1.0, terms[0]), (-1.0, terms[1])]));
                ratios.push(d.value.abs() / d.tolerance);
                relative.push(d.tolerance / terms[0].0.abs().max(terms[1].0.abs()));
            }
        }
        assert!(
            ratios.iter().all(|r| *r <= 0.25),
            "{:?}",
            ratios.iter().copied().fold(0.0, f64::max)
        );
        relative.sort_by(f64::total_cmp);
        assert!(
            relative[relative.len() / 2] < 1e-11,
            "{}",
            relative[relative.len() / 2]
        );
    }
}
