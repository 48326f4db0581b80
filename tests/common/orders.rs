//! The expected orders of convergence, read from `scenes/orders.toml`: the table the compare tool's
//! theory (`compare/sdcompare_lib/theory.py`) reads, so that a test's rate threshold is the
//! theory's expected order minus the same margin the compare tool allows, or a measured bound of
//! the table's `[regression]` section, which says so. An order is a power of the mesh size h (of
//! N^{-1/2} on graded meshes); s is the regularity index of the exact u (1 smooth, 1/2 at a
//! crack tip's r^{1/2}). Every section denies keys it does not know, so a number added for one
//! reader only fails here until the tests know it too.

use sdcrack_core::problem::MultiplierSpace;
use serde::Deserialize;

/// The whole table, one field per section of `scenes/orders.toml`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orders {
    /// How far an observed rate may fall short of its expected order.
    pub rule: Rule,
    /// The regularity indices s.
    pub regularity: Regularity,
    /// P1's orders on the cracked mesh, as multiples of s.
    pub p1: P1Orders,
    /// The continuous p where the crack opens.
    pub open_crack: OpenCrack,
    /// The multipliers' orders.
    pub lambda: LambdaOrders,
    /// Measured bounds of the Rust tests: not orders of the theory.
    pub regression: Regression,
}

/// `[rule]`: a series converges when each of its last two rates is ≥ order − `margin`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rule {
    /// The margin (dimensionless, a difference of orders).
    pub margin: f64,
    /// How many levels a series needs to be judged (two observed rates).
    pub levels: usize,
    /// The smallest defect of order the verdict must tell from a correct solver (the compare
    /// tool's rule: a falling rate below order − bug_gap/2 fails at any length).
    pub bug_gap: f64,
    /// How many more levels a rate rising toward its order may ask for (compare tool only).
    pub extra_levels: u32,
}

/// `[regularity]`: s of a smooth u and at an r^{1/2} tip, and the interpolation rate that tells
/// them apart.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regularity {
    /// s of a smooth u (1).
    pub smooth_s: f64,
    /// s at a crack tip's r^{1/2} singularity (1/2).
    pub singular_s: f64,
    /// A rate of ‖∇(u − I_h u)‖ at or above it classifies u as smooth.
    pub smooth_interpolation_rate: f64,
}

/// `[p1]`: the orders of P1 on the cracked mesh divided by s.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct P1Orders {
    /// u in L² (2: interpolation and the duality gain).
    pub u_l2: f64,
    /// p ≈ ∇u in L² (1).
    pub p_l2: f64,
    /// p in the paper's X-norm (1).
    pub p_x: f64,
}

/// `[open_crack]`: the order of the continuous p (and of u with it) where the crack opens.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpenCrack {
    /// The order (1/2: an O(1) error in a strip of width h along the open crack).
    pub order: f64,
}

/// `[lambda]`: the multipliers' orders.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LambdaOrders {
    /// A P0 multiplier (M0) on a smooth jump [u] (1).
    pub p0_jump: f64,
    /// Theorem 4.3 of the paper, per multiplier.
    pub paper: PaperLambda,
}

/// `[lambda.paper]`: Theorem 4.3's order of λ_h.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperLambda {
    /// M0 (1/2).
    #[serde(rename = "M0")]
    pub m0: f64,
    /// M1 (1/2).
    #[serde(rename = "M1")]
    pub m1: f64,
    /// M1star (3/4).
    #[serde(rename = "M1star")]
    pub m1star: f64,
}

/// `[regression]`: rates measured on the repository's scenes, held by the tests as bounds.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regression {
    /// Highest rate of a series that does not converge (the continuous u on an open crack).
    pub stalled_rate: f64,
    /// Lowest u rate of the broken u on open-exact up to level 4.
    pub open_exact_u_rate: f64,
    /// Lowest p rate on the gmsh meshes of the closed kinked and two-crack scenes.
    pub gmsh_closed_p_rate: f64,
    /// Lowest p rate of the broken-tangential p on open-graded.
    pub graded_tangential_p_rate: f64,
}

/// Path of the repository's table.
pub fn orders_path() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/orders.toml")
}

impl Orders {
    /// The repository's table, `scenes/orders.toml`.
    pub fn repository() -> Orders {
        let path = orders_path();
        Orders::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// The table at `path`, or why it cannot be read.
    pub fn read(path: &std::path::Path) -> Result<Orders, String> {
        let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
        toml::from_str(&text).map_err(|e| e.to_string())
    }

    /// The smallest observed rate that meets expected order `order`: order − margin.
    pub fn lowest_rate(&self, order: f64) -> f64 {
        order - self.rule.margin
    }

    /// P1's order of u in L² for regularity `s`: 2s.
    pub fn p1_u(&self, s: f64) -> f64 {
        self.p1.u_l2 * s
    }

    /// P1's order of p in L² for regularity `s`: s.
    pub fn p1_p(&self, s: f64) -> f64 {
        self.p1.p_l2 * s
    }

    /// P1's order of p in the X-norm for regularity `s`: s.
    pub fn p1_px(&self, s: f64) -> f64 {
        self.p1.p_x * s
    }

    /// Theorem 4.3's order of λ_h of multiplier `m`.
    pub fn paper_lambda(&self, m: MultiplierSpace) -> f64 {
        match m {
            MultiplierSpace::M0 => self.lambda.paper.m0,
            MultiplierSpace::M1 => self.lambda.paper.m1,
            MultiplierSpace::M1Star => self.lambda.paper.m1star,
        }
    }
}
