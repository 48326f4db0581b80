//! Test support of the elastic problem kind: exact fields as the expression strings a scene would
//! write (`[exact] ux`, `uy`, `[data] fx`, …), each checked before use (the unit tests of
//! [`super::elastic_exact_data`] pass them through the exact-data check), and a builder of the
//! [`ElasticData`] they make. The fields:
//! - Williams' near-tip field K_I u_I + K_II u_II of a crack along the negative x axis with its
//!   tip at the origin (docs/elasticity.md's tip frame: e₁ = (1, 0), θ = atan2(y, x) = ±π on the
//!   faces, the + face y > 0), its stress, and its opening and slip (κ + 1)/μ·K·√(r/(2π));
//! - the closed field u_C = c(0.3 sin x cos y, −sin y (2 + cos x)): u_x even and u_y odd in y, so
//!   the crack y = 0 stays shut, σ_xy = 0 and σ_yy < 0 on it; its body force and contact pressure;
//! - the patch u = (ε_xx (x + 1), ε_yy (y + 1)) of a uniform compression σ = diag(0, −p) across
//!   the crack (exact for P1), zero at the corner (−1, −1) and u_x zero at (−1, 1).

use crate::elasticity::{
    BoundaryPart, ElasticData, ElasticExact, FixedPoint, Material, PlaneModel, Traction,
};
use crate::expr::Expr;
use crate::problem::{Domain, Polyline, Rectangle};

/// E = 1, ν = 0.3, plane strain (the pilot's material): κ = 1.8, μ = 1/2.6.
pub(crate) fn steel_like() -> Material {
    Material::from_young_poisson(1.0, 0.3, PlaneModel::Strain)
}

/// A number as an expression's text: parenthesised, so that a negative one can follow `*`.
fn n(v: f64) -> String {
    format!("({v})")
}

/// Williams' displacement K_I u_I + K_II u_II (docs/elasticity.md's formulas, K/(2μ)·√(r/(2π))
/// times the angular functions), tip at the origin, crack along the negative x axis.
pub(crate) fn williams(k1: f64, k2: f64, m: &Material) -> [String; 2] {
    let (mu, kappa) = (n(m.mu), n(m.kolosov()));
    let c = format!("sqrt(sqrt(x^2 + y^2)/(2*pi))/(2*{mu})");
    let half = "(atan2(y, x)/2)";
    let (k1, k2) = (n(k1), n(k2));
    [
        format!(
            "{k1}*{c}*cos{half}*({kappa} - 1 + 2*sin{half}^2) + {k2}*{c}*sin{half}*({kappa} + 1 + 2*cos{half}^2)"
        ),
        format!(
            "{k1}*{c}*sin{half}*({kappa} + 1 - 2*cos{half}^2) - {k2}*{c}*cos{half}*({kappa} - 1 - 2*sin{half}^2)"
        ),
    ]
}

/// Williams' stress (σ_xx, σ_yy, σ_xy) of K_I u_I + K_II u_II, K/√(2πr) times the angular
/// functions (independent of the material): for mode I cos(θ/2)(1 ∓ sin(θ/2) sin(3θ/2)),
/// cos(θ/2) sin(θ/2) cos(3θ/2); for mode II −sin(θ/2)(2 + cos(θ/2) cos(3θ/2)),
/// sin(θ/2) cos(θ/2) cos(3θ/2), cos(θ/2)(1 − sin(θ/2) sin(3θ/2)).
pub(crate) fn williams_stress(k1: f64, k2: f64) -> [String; 3] {
    let a = "sqrt(2*pi*sqrt(x^2 + y^2))";
    let (h, h3) = ("(atan2(y, x)/2)", "(3*atan2(y, x)/2)");
    let (k1, k2) = (n(k1), n(k2));
    [
        format!("({k1}*cos{h}*(1 - sin{h}*sin{h3}) - {k2}*sin{h}*(2 + cos{h}*cos{h3}))/{a}"),
        format!("({k1}*cos{h}*(1 + sin{h}*sin{h3}) + {k2}*sin{h}*cos{h}*cos{h3})/{a}"),
        format!("({k1}*cos{h}*sin{h}*cos{h3} + {k2}*cos{h}*(1 - sin{h}*sin{h3}))/{a}"),
    ]
}

/// Williams' jump (κ + 1)/μ·K·√(r/(2π)) across the crack behind the tip: the opening \[u_y\] for
/// K = K_I, the slip \[u_x\] for K = K_II.
pub(crate) fn williams_jump(k: f64, m: &Material) -> String {
    format!(
        "({} + 1)/{}*{}*sqrt(sqrt(x^2 + y^2)/(2*pi))",
        n(m.kolosov()),
        n(m.mu),
        n(k)
    )
}

/// u_C = c(0.3 sin x cos y, −sin y (2 + cos x)).
pub(crate) fn closed(c: f64) -> [String; 2] {
    let c = n(c);
    [
        format!("{c}*0.3*sin(x)*cos(y)"),
        format!("-{c}*sin(y)*(2 + cos(x))"),
    ]
}

/// f = −div σ(u_C): with ε_xx = 0.3c cos x cos y, ε_yy = −c cos y (2 + cos x),
/// 2ε_xy = 0.7c sin x sin y and λ* = `m.lambda_in_plane()`,
/// f_x = −c sin x cos y (0.7λ* + 0.1μ), f_y = −c sin y ((0.7λ* + 2.7μ) cos x + 2λ* + 4μ).
pub(crate) fn closed_force(c: f64, m: &Material) -> [String; 2] {
    let (c, lam, mu) = (n(c), n(m.lambda_in_plane()), n(m.mu));
    [
        format!("-{c}*sin(x)*cos(y)*(0.7*{lam} + 0.1*{mu})"),
        format!("-{c}*sin(y)*((0.7*{lam} + 2.7*{mu})*cos(x) + 2*{lam} + 4*{mu})"),
    ]
}

/// The contact pressure −σ_yy(u_C) on y = 0: c (λ* (0.7 cos x + 2) + 2μ (2 + cos x)) > 0.
pub(crate) fn closed_pressure(c: f64, m: &Material) -> String {
    let (c, lam, mu) = (n(c), n(m.lambda_in_plane()), n(m.mu));
    format!("{c}*({lam}*(0.7*cos(x) + 2) + 2*{mu}*(2 + cos(x)))")
}

/// The strains (ε_xx, ε_yy) of the uniaxial compression σ = diag(0, −p) under the in-plane law:
/// σ_xx = (λ* + 2μ) ε_xx + λ* ε_yy = 0 and σ_yy = λ* ε_xx + (λ* + 2μ) ε_yy = −p give
/// ε_yy = −p (λ* + 2μ)/(4μ(λ* + μ)), ε_xx = −λ* ε_yy/(λ* + 2μ).
pub(crate) fn patch_strains(p: f64, m: &Material) -> [f64; 2] {
    let (lam, mu) = (m.lambda_in_plane(), m.mu);
    let eyy = -p * (lam + 2.0 * mu) / (4.0 * mu * (lam + mu));
    [-lam * eyy / (lam + 2.0 * mu), eyy]
}

/// The patch's displacement (ε_xx (x + 1), ε_yy (y + 1)).
pub(crate) fn patch(p: f64, m: &Material) -> [String; 2] {
    let [exx, eyy] = patch_strains(p, m);
    [format!("{}*(x + 1)", n(exx)), format!("{}*(y + 1)", n(eyy))]
}

/// Ω = (−1, 1)².
pub(crate) fn square() -> Domain {
    Domain::Rectangle(Rectangle {
        min: [-1.0, -1.0],
        max: [1.0, 1.0],
    })
}

/// A straight crack from `a` to `b`.
pub(crate) fn crack(a: [f64; 2], b: [f64; 2]) -> Polyline {
    Polyline { points: vec![a, b] }
}

fn parse(s: &str) -> Expr {
    Expr::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"))
}

fn pair(s: [&str; 2]) -> [Expr; 2] {
    s.map(parse)
}

/// An elastic scene's data under construction: the material, the exact u and f; every other
/// datum absent until set.
pub(crate) struct Elastic {
    pub(crate) data: ElasticData,
}

impl Elastic {
    /// The data with the exact displacement `u`, the stress of Hooke's law (as the loader derives
    /// it when `[exact]` gives none), the body force `f` and no boundary data.
    pub(crate) fn new(m: Material, u: [&str; 2], f: [&str; 2]) -> Elastic {
        let u = pair(u);
        let stress = crate::elasticity::hooke_stress(&u, &m).unwrap();
        Elastic {
            data: ElasticData {
                material: m,
                f: pair(f),
                g: None,
                tractions: Vec::new(),
                fixed: Vec::new(),
                exact: Some(ElasticExact {
                    u,
                    stress,
                    opening: None,
                    slip: None,
                    pressure: None,
                    sif: Vec::new(),
                }),
            },
        }
    }

    fn exact(&mut self) -> &mut ElasticExact {
        self.data
            .exact
            .as_mut()
            .expect("built with an exact solution")
    }

    /// g on the Dirichlet parts.
    pub(crate) fn g(mut self, g: [&str; 2]) -> Elastic {
        self.data.g = Some(pair(g));
        self
    }

    /// g = u (the exact u's own strings).
    pub(crate) fn g_is_u(mut self) -> Elastic {
        self.data.g = Some(self.exact().u.clone());
        self
    }

    /// The traction `t` on the part `part`.
    pub(crate) fn traction(mut self, part: &str, t: [&str; 2]) -> Elastic {
        self.data.tractions.push(Traction {
            part: BoundaryPart(part.into()),
            t: pair(t),
        });
        self
    }

    /// A fixed point.
    pub(crate) fn fixed(mut self, point: [f64; 2], components: [bool; 2]) -> Elastic {
        self.data.fixed.push(FixedPoint { point, components });
        self
    }

    /// The given `[exact] sxx, syy, sxy`.
    pub(crate) fn stress(mut self, s: [&str; 3]) -> Elastic {
        self.exact().stress = s.map(parse);
        self
    }

    /// The given `[exact] opening`.
    pub(crate) fn opening(mut self, s: &str) -> Elastic {
        self.exact().opening = Some(parse(s));
        self
    }

    /// The given `[exact] slip`.
    pub(crate) fn slip(mut self, s: &str) -> Elastic {
        self.exact().slip = Some(parse(s));
        self
    }

    /// The given `[exact] pressure`.
    pub(crate) fn pressure(mut self, s: &str) -> Elastic {
        self.exact().pressure = Some(parse(s));
        self
    }
}
