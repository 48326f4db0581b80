//! The measured regression bounds of `scenes/expectations.toml` (its `[[expectation]]` rows: the
//! error at `level` at most `max_error`, the rate from level − 1 to `level` at least `min_rate`),
//! which the compare tool checks on every campaign, looked up for one series the way
//! `check_expectations` of the compare tool matches them: "*" matches every value, and a row
//! without `p_mass` or `p_space` bounds the consistent p mass and the continuous p only. The tests
//! that solve the same scenes at the same levels hold the same numbers by reading them here.

use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};

/// One series of one scene at one level, in the names the expectations use.
#[derive(Debug, Clone, Copy)]
pub struct SeriesAt<'a> {
    /// The scene's `name`.
    pub scene: &'a str,
    /// The u space.
    pub u_space: USpace,
    /// The multiplier space.
    pub multiplier: MultiplierSpace,
    /// The p mass.
    pub p_mass: PMass,
    /// The p space.
    pub p_space: PSpace,
    /// `u_l2`, `p_l2`, `p_x` or `lambda_l2`.
    pub quantity: &'a str,
    /// The level whose error (and rate from the level below) is bounded.
    pub level: u32,
}

/// What every matching row asks together: the largest `min_rate` and the smallest `max_error`
/// (None where no matching row gives one).
#[derive(Debug, Clone, Copy, Default)]
pub struct Bound {
    /// Lowest rate accepted from level − 1 to the level.
    pub min_rate: Option<f64>,
    /// Highest error accepted at the level.
    pub max_error: Option<f64>,
}

/// The bounds of `series`: every `[[expectation]]` row of the repository's expectations that
/// matches it. Panics when none does (a test that reads its bounds here must have some).
pub fn bound(series: &SeriesAt) -> Bound {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/expectations.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let table: toml::Table = text
        .parse()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let rows = table.get("expectation").and_then(toml::Value::as_array);
    let mut out = Bound::default();
    let mut matched = 0;
    for row in rows.into_iter().flatten().filter(|r| matches(r, series)) {
        matched += 1;
        let number = |key: &str| row.get(key).and_then(toml::Value::as_float);
        if let Some(r) = number("min_rate") {
            out.min_rate = Some(out.min_rate.map_or(r, |b| b.max(r)));
        }
        if let Some(e) = number("max_error") {
            out.max_error = Some(out.max_error.map_or(e, |b| b.min(e)));
        }
    }
    assert!(matched > 0, "{}: no row bounds {series:?}", path.display());
    out
}

/// Whether expectation `row` bounds `series`.
fn matches(row: &toml::Value, series: &SeriesAt) -> bool {
    let key = |k: &str, default: &str, value: &str| {
        let pattern = row.get(k).and_then(toml::Value::as_str).unwrap_or(default);
        pattern == "*" || pattern == value
    };
    row.get("level").and_then(toml::Value::as_integer) == Some(i64::from(series.level))
        && key("scene", "", series.scene)
        && key("u_space", "", series.u_space.name())
        && key("multiplier", "", series.multiplier.name())
        && key("p_mass", PMass::Consistent.name(), series.p_mass.name())
        && key("p_space", PSpace::Continuous.name(), series.p_space.name())
        && key("quantity", "", series.quantity)
}
