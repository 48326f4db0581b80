//! The validated `[verification]` table of a scene: what the compare tool's verdict may expect
//! of it (the TOML keys and their validation are sdcrack-io's `scene::verification`).

use crate::case::{CaseKey, Pattern};
use crate::norms::Quantity;

/// A series declared not to converge, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ExpectedFailure {
    /// The series: its u space and multiplier, each `None` for every one (`"*"`).
    pub series: Pattern<CaseKey>,
    /// The quantity, or `None` for every quantity (`"*"`).
    pub quantity: Option<Quantity>,
    /// Why the series is expected not to converge (shown in the report).
    pub reason: String,
}

/// A series' expected order of convergence declared by the scene, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ExpectedRate {
    /// The series: its u space, multiplier, p mass and p space, each `None` for every one
    /// (`"*"`).
    pub series: Pattern<CaseKey>,
    /// The quantity, or `None` for every quantity (`"*"`).
    pub quantity: Option<Quantity>,
    /// The expected order, in (0, 4].
    pub rate: f64,
    /// Where the order comes from (shown in the report).
    pub reason: String,
}

/// The compare tool's checks a scene may declare not to apply to it.
pub const NOT_APPLICABLE_CHECKS: [&str; 4] = [
    "interpolation yardstick",
    "reference yardstick",
    "δ → 0",
    "Theorem 2.1 (exact)",
];

/// The validated `[verification]` table; `None` means the compare tool's default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Verification {
    /// A smoke run: fewer than 3 levels make a series inconclusive instead of failed.
    pub smoke: bool,
    /// Largest relative KKT residual accepted (> 0).
    pub kkt_tolerance: Option<f64>,
    /// Largest vertex difference of the two references accepted (> 0).
    pub reference_agreement: Option<f64>,
    /// Largest |slope − 1| of the δ → 0 fits accepted (> 0).
    pub delta_slope_tolerance: Option<f64>,
    /// Smallest observed rate of a converging series (> 0).
    pub min_rate: Option<f64>,
    /// Series declared not to converge.
    pub expected_failures: Vec<ExpectedFailure>,
    /// The scene's own expected orders.
    pub expected_rates: Vec<ExpectedRate>,
    /// Checks declared not to apply, with the reason: (check, reason).
    pub not_applicable: Vec<(String, String)>,
}
