//! Test support of the core: the repository's scenes that unit tests solve, built without a TOML
//! parser (this crate has none): f, g and the exact solution are read off scenes/*.toml's lines,
//! whose domain, crack and level-0 cells are checked to be the ones built here. (Random tests draw from `fastrand::Rng::with_seed`, one seeded
//! generator for the whole workspace, so a failure reproduces.)

use super::*;
use crate::case::CaseAxes;
use crate::expr::Expr;
use crate::problem::{
    Domain, Exact, Meshing, MultiplierSpace, PMass, PSpace, Polyline, Rectangle, USpace,
};

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
        meshing: Meshing::Cells([8, 8]),
        grading: None,
        level0: Level0Size::Grid([8, 8]),
        problem: Problem::Scalar(ScalarProblem {
            f: Expr::parse(f).unwrap(),
            g: Expr::parse(g).unwrap(),
            exact,
        }),
        axes: CaseAxes {
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
            problems: vec![super::ProblemKind::Scalar],
        },
        fields: FieldSet {
            u: true,
            p: true,
            lambda: true,
        },
        references: Vec::new(),
        verification: Verification::default(),
    }
}

/// scenes/mixed.toml, the default scene: partly open, partly closed.
/// The string value of the first line `key = "…"` of a scene file's text (the repository's scene
/// files write f, g, u and jump that way); panics when there is none, so a test scene cannot drift
/// from its file unnoticed.
fn string_value<'a>(text: &'a str, key: &str) -> &'a str {
    text.lines()
        .find_map(|line| {
            let (k, v) = line.split_once('=')?;
            (k.trim() == key).then(|| v.trim().strip_prefix('"')?.strip_suffix('"'))?
        })
        .unwrap_or_else(|| panic!("no line {key} = \"…\" in the scene file"))
}

/// The scene built from a repository scene file's expressions (f, g and, when `exact`, u and
/// jump); the file's domain, crack and level-0 cells must be the ones [`scene`] builds.
fn from_file(name: &str, text: &str, exact: bool) -> Scene {
    for line in [
        "domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }",
        "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }",
        "cells = [8, 8]",
    ] {
        assert!(
            text.lines().any(|l| l.trim() == line),
            "{name}: no line {line}"
        );
    }
    let exact = exact.then(|| (string_value(text, "u"), string_value(text, "jump")));
    scene(
        name,
        string_value(text, "f"),
        string_value(text, "g"),
        exact,
    )
}

pub(crate) fn mixed() -> Scene {
    from_file(
        "mixed",
        include_str!("../../../../scenes/mixed.toml"),
        false,
    )
}

pub(crate) fn open_exact() -> Scene {
    from_file(
        "open-exact",
        include_str!("../../../../scenes/open-exact.toml"),
        true,
    )
}

pub(crate) fn closed_exact() -> Scene {
    from_file(
        "closed-exact",
        include_str!("../../../../scenes/closed-exact.toml"),
        true,
    )
}
