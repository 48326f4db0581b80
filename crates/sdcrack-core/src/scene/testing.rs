//! Test support of the core: the repository's scenes that unit tests solve, built without their
//! TOML (this crate has no parser): keep domain, crack, meshing, f, g and the exact solution as
//! scenes/*.toml have them. (Random tests draw from `fastrand::Rng::with_seed`, one seeded
//! generator for the whole workspace, so a failure reproduces.)

use super::*;
use crate::problem::Rectangle;

/// A scene on (−1, 1)² with the crack [−0.5, 0.5] × {0}, level-0 cells [8, 8], source `f`,
/// Dirichlet data `g` and, if given, the exact solution (u, \[u\]) — the shape of
/// scenes/mixed.toml, open-exact.toml and closed-exact.toml.
pub(crate) fn scene(name: &str, f: &str, g: &str, exact: Option<(&str, &str)>) -> Scene {
    let exact = exact.map(|(u, jump)| {
        let u = Expr::parse(u).unwrap();
        Exact {
            px: u.derivative(crate::expr::Var::X),
            py: u.derivative(crate::expr::Var::Y),
            u,
            jump: Some(Expr::parse(jump).unwrap()),
        }
    });
    Scene {
        name: name.into(),
        description: String::new(),
        domain: Domain::Rectangle(Rectangle {
            min: [-1.0, -1.0],
            max: [1.0, 1.0],
        }),
        cracks: vec![Polyline {
            points: vec![[-0.5, 0.0], [0.5, 0.0]],
        }],
        crack_names: vec!["geometry.crack.segment".into()],
        meshing: Meshing::Cells([8, 8]),
        grading: None,
        level0: Level0Size::Grid([8, 8]),
        f: Expr::parse(f).unwrap(),
        g: Expr::parse(g).unwrap(),
        exact,
        axes: super::CaseAxes {
            levels: vec![0, 1, 2, 3, 4],
            u_spaces: vec![USpace::Continuous, USpace::Broken],
            multipliers: vec![
                MultiplierSpace::M0,
                MultiplierSpace::M1,
                MultiplierSpace::M1Star,
            ],
            p_masses: vec![PMass::Consistent, PMass::Lumped],
            p_spaces: vec![PSpace::Continuous],
            deltas: vec![1.0, 1e-2, 1e-4, 1e-6, 1e-8, 0.0],
        },
        fields: FieldSet {
            u: true,
            p: true,
            lambda: true,
        },
        references: Vec::new(),
        verification: Verification::default(),
        source: String::new(),
    }
}

/// scenes/mixed.toml, the default scene: partly open, partly closed.
pub(crate) fn mixed() -> Scene {
    scene("mixed", "20*sin(2*pi*x)*sign(y)", "0", None)
}

/// scenes/open-exact.toml: the fully open crack, u = Im √(z² − 1/4).
pub(crate) fn open_exact() -> Scene {
    let u = "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)";
    scene("open-exact", "0", u, Some((u, "2*sqrt(0.25 - x^2)")))
}

/// scenes/closed-exact.toml: the closed crack, u = sin(πx) cos(πy) − y.
pub(crate) fn closed_exact() -> Scene {
    scene(
        "closed-exact",
        "2*pi^2*sin(pi*x)*cos(pi*y)",
        "sin(pi*x)*cos(pi*y) - y",
        Some(("sin(pi*x)*cos(pi*y) - y", "0")),
    )
}
