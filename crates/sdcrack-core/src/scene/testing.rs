//! Test support of the core, shared by its unit tests and by the workspace's integration tests:
//! the deterministic pseudo-random generators that random tests draw from (fixed seeds, so a
//! failure reproduces), and the repository's scenes that unit tests solve, built without their
//! TOML (this crate has no parser): keep domain, crack, meshing, f, g and the exact solution as
//! scenes/*.toml have them.

#[cfg(test)]
use super::*;
#[cfg(test)]
use crate::problem::Rectangle;

/// Marsaglia's xorshift64 generator (shifts 13, 7, 17): a 64-bit state that must not be 0.
#[derive(Clone, Debug)]
pub struct XorShift64(pub u64);

impl XorShift64 {
    /// The next state, which is also the output.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    /// An integer in `0..n` (`0` when `n == 0`), by the remainder of the next output.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// An element of a non-empty slice, chosen with [`XorShift64::below`].
    pub fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }

    /// A number in `[lo, hi)` from the top 53 bits of the next output.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Steele, Lea and Flood's SplitMix64 generator: a Weyl sequence (step `0x9e3779b97f4a7c15`)
/// through Stafford's mix 13; any 64-bit seed.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next output.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `[-1, 1)` from the top 53 bits of the next output.
    pub fn symmetric_unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// An integer in `0..n` (`0` when `n == 0`), by the remainder of the next output.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// A scene on (−1, 1)² with the crack [−0.5, 0.5] × {0}, level-0 cells [8, 8], source `f`,
/// Dirichlet data `g` and, if given, the exact solution (u, \[u\]) — the shape of
/// scenes/mixed.toml, open-exact.toml and closed-exact.toml.
#[cfg(test)]
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
#[cfg(test)]
pub(crate) fn mixed() -> Scene {
    scene("mixed", "20*sin(2*pi*x)*sign(y)", "0", None)
}

/// scenes/open-exact.toml: the fully open crack, u = Im √(z² − 1/4).
#[cfg(test)]
pub(crate) fn open_exact() -> Scene {
    let u = "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)";
    scene("open-exact", "0", u, Some((u, "2*sqrt(0.25 - x^2)")))
}

/// scenes/closed-exact.toml: the closed crack, u = sin(πx) cos(πy) − y.
#[cfg(test)]
pub(crate) fn closed_exact() -> Scene {
    scene(
        "closed-exact",
        "2*pi^2*sin(pi*x)*cos(pi*y)",
        "sin(pi*x)*cos(pi*y) - y",
        Some(("sin(pi*x)*cos(pi*y) - y", "0")),
    )
}
