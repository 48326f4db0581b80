//! The scene's `[verification]` table: what the compare tool's verdict may expect of this scene.
//!
//! The solver does not use these settings; it validates them (so `sdcrack check` catches a typo
//! before a long run) and keeps them in the scene copy of the results folder, where the compare
//! tool reads them. The defaults and the rule that a scene may only tighten them belong to the
//! compare tool (compare/README.md). Keys:
//!
//! ```toml
//! [verification]
//! smoke = false                 # true: fewer than 3 levels is a smoke run (series inconclusive, not failed)
//! kkt_tolerance = 1e-10         # largest relative KKT residual of every solver and reference case
//! reference_agreement = 1e-8    # largest |u_dolfinx − u_freefem| at the vertices of every level
//! delta_slope_tolerance = 0.1   # |slope − 1| allowed for the δ → 0 fits above round-off
//! min_rate = 0.4                # smallest observed rate of a converging series
//!
//! [[verification.expected_failure]]   # a series known not to converge, with the reason
//! u_space = "continuous"        # continuous | broken | "*"
//! multiplier = "*"              # M0 | M1 | M1star | "*" (default "*")
//! quantity = "*"                # u_l2 | p_l2 | p_x | lambda_l2 | "*" (default "*")
//! reason = "continuous P1 u cannot carry the jump [u] > 0 of the open crack"
//!
//! [[verification.expected_rate]]      # the scene's own expected order of some series
//! u_space = "broken"            # continuous | broken | "*" (default "*")
//! multiplier = "*"              # M0 | M1 | M1star | "*" (default "*")
//! p_mass = "*"                  # consistent | lumped | "*" (default "*")
//! p_space = "*"                 # continuous | broken-tangential | "*" (default "*")
//! quantity = "u_l2"             # u_l2 | p_l2 | p_x | lambda_l2 | "*" (default "*")
//! rate = 1.0                    # in (0, 4]: the series must show ≥ rate − 0.1 on its last two steps
//! reason = "where the order comes from"
//!
//! [[verification.not_applicable]]     # a check that does not apply to this scene, and why
//! check = "interpolation yardstick"   # one of NOT_APPLICABLE_CHECKS
//! reason = "..."
//! ```

use sdcrack_core::case::CasePattern;
use sdcrack_core::norms::Quantity;
use sdcrack_core::problem::{PMass, PSpace};

use super::error::SceneError;
use super::raw::{ExpectedRateToml, NotApplicableToml, VerificationToml};
use crate::did_you_mean::suggest;
use sdcrack_core::problem::{MultiplierSpace, USpace};
use sdcrack_core::scene::KeyPath;

pub use sdcrack_core::scene::verification::{
    ExpectedFailure, ExpectedRate, Verification, NOT_APPLICABLE_CHECKS,
};

/// `"*"` → `None`; otherwise one of `known` (a value the scene runs), with a suggestion.
fn pattern<T: Copy>(
    key: &KeyPath,
    value: &str,
    known: &[(T, String)],
) -> Result<Option<T>, SceneError> {
    if value == "*" {
        return Ok(None);
    }
    if let Some((v, _)) = known.iter().find(|(_, n)| n == value) {
        return Ok(Some(*v));
    }
    let names: Vec<&str> = known.iter().map(|(_, n)| n.as_str()).collect();
    let hint = suggest(value, &names)
        .map(|s| format!("; did you mean \"{s}\"?"))
        .unwrap_or_default();
    Err(SceneError::value(
        key.clone(),
        format!(
            ": {value:?} is not among the scene's values ({} or \"*\"){hint}",
            names.join(", ")
        ),
    ))
}

fn positive(key: &str, v: Option<f64>) -> Result<Option<f64>, SceneError> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(SceneError::value(
            KeyPath::keys("verification").key(key),
            format!(" = {x} must be a finite number > 0"),
        )),
        _ => Ok(v),
    }
}

impl VerificationToml {
    /// Validates against the u spaces and multipliers the scene runs.
    pub(super) fn validate(
        self,
        u_spaces: &[USpace],
        multipliers: &[MultiplierSpace],
    ) -> Result<Verification, SceneError> {
        let us = named(u_spaces);
        let ms = named(multipliers);
        let qs = named(&Quantity::ALL);
        let mut expected_failures: Vec<ExpectedFailure> = Vec::new();
        for (i, e) in self.expected_failure.into_iter().enumerate() {
            let table = KeyPath::keys("verification.expected_failure").index(i);
            let key = |k: &str| table.clone().key(k);
            let reason = e.reason.trim().to_string();
            if reason.is_empty() {
                return Err(SceneError::value(
                    key("reason"),
                    ": say why the series is expected not to converge",
                ));
            }
            let failure = ExpectedFailure {
                series: CasePattern {
                    u_space: pattern(&key("u_space"), &e.u_space, &us)?,
                    multiplier: pattern(
                        &key("multiplier"),
                        e.multiplier.as_deref().unwrap_or("*"),
                        &ms,
                    )?,
                    ..CasePattern::default()
                },
                quantity: pattern(&key("quantity"), e.quantity.as_deref().unwrap_or("*"), &qs)?,
                reason,
            };
            if expected_failures
                .iter()
                .any(|f| (f.series, f.quantity) == (failure.series, failure.quantity))
            {
                return Err(SceneError::value(
                    table,
                    " declares the same series as an earlier one",
                ));
            }
            expected_failures.push(failure);
        }
        let expected_rates = self
            .expected_rate
            .into_iter()
            .enumerate()
            .map(|(i, e)| e.validate(i, &us, &ms, &qs))
            .collect::<Result<Vec<_>, _>>()?;
        let not_applicable = self
            .not_applicable
            .into_iter()
            .enumerate()
            .map(|(i, n)| n.validate(i))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Verification {
            expected_rates,
            not_applicable,
            smoke: self.smoke,
            kkt_tolerance: positive("kkt_tolerance", self.kkt_tolerance)?,
            reference_agreement: positive("reference_agreement", self.reference_agreement)?,
            delta_slope_tolerance: positive("delta_slope_tolerance", self.delta_slope_tolerance)?,
            min_rate: positive("min_rate", self.min_rate)?,
            expected_failures,
        })
    }
}

/// `values` with their names, the `known` of [`pattern`].
fn named<T: Copy + std::fmt::Display>(values: &[T]) -> Vec<(T, String)> {
    values.iter().map(|&v| (v, v.to_string())).collect()
}

fn non_empty(key: KeyPath, reason: &str) -> Result<String, SceneError> {
    let r = reason.trim();
    if r.is_empty() {
        return Err(SceneError::value(key, ": say why"));
    }
    Ok(r.to_string())
}

impl ExpectedRateToml {
    fn validate(
        self,
        i: usize,
        us: &[(USpace, String)],
        ms: &[(MultiplierSpace, String)],
        qs: &[(Quantity, String)],
    ) -> Result<ExpectedRate, SceneError> {
        let key = |k: &str| KeyPath::keys("verification.expected_rate").index(i).key(k);
        if !(self.rate.is_finite() && self.rate > 0.0 && self.rate <= 4.0) {
            return Err(SceneError::value(
                key("rate"),
                format!(" = {} must be a number in (0, 4]", self.rate),
            ));
        }
        let pms = named(&PMass::ALL);
        let pss = named(&PSpace::ALL);
        let any = |v: &Option<String>| v.as_deref().unwrap_or("*").to_string();
        Ok(ExpectedRate {
            series: CasePattern {
                u_space: pattern(&key("u_space"), &any(&self.u_space), us)?,
                multiplier: pattern(&key("multiplier"), &any(&self.multiplier), ms)?,
                p_mass: pattern(&key("p_mass"), &any(&self.p_mass), &pms)?,
                p_space: pattern(&key("p_space"), &any(&self.p_space), &pss)?,
                ..CasePattern::default()
            },
            quantity: pattern(&key("quantity"), &any(&self.quantity), qs)?,
            rate: self.rate,
            reason: non_empty(key("reason"), &self.reason)?,
        })
    }
}

impl NotApplicableToml {
    fn validate(self, i: usize) -> Result<(String, String), SceneError> {
        let key = |k: &str| KeyPath::keys("verification.not_applicable").index(i).key(k);
        if !NOT_APPLICABLE_CHECKS.contains(&self.check.as_str()) {
            return Err(SceneError::value(
                key("check"),
                format!(
                    ": {:?} is none of {}",
                    self.check,
                    NOT_APPLICABLE_CHECKS.join(", ")
                ),
            ));
        }
        Ok((self.check, non_empty(key("reason"), &self.reason)?))
    }
}

#[cfg(test)]
mod tests {
    use crate::scene_file::{TomlScene, DEFAULT_SCENE};
    use sdcrack_core::scene::Scene;

    /// The default scene with `table` in place of its own verification tables.
    fn with(table: &str) -> Result<Scene, String> {
        let base = DEFAULT_SCENE
            .split("\n[[verification")
            .next()
            .unwrap_or(DEFAULT_SCENE);
        Scene::from_toml(&format!("{base}\n{table}")).map_err(|e| e.to_string())
    }

    #[test]
    fn expected_failures_and_tolerances_are_read() {
        let s = with(
            "[verification]\nkkt_tolerance = 1e-12\nsmoke = true\n\
             [[verification.expected_failure]]\nu_space = \"continuous\"\n\
             reason = \" no jump \"\n",
        )
        .unwrap();
        let v = &s.verification;
        assert!(v.smoke);
        assert_eq!(v.kkt_tolerance, Some(1e-12));
        assert_eq!(v.reference_agreement, None);
        assert_eq!(v.expected_failures.len(), 1);
        let f = &v.expected_failures[0];
        assert_eq!(
            f.series.u_space,
            Some(sdcrack_core::problem::USpace::Continuous)
        );
        assert_eq!((f.series.multiplier, f.quantity), (None, None));
        assert_eq!(f.reason, "no jump");
        assert_eq!(with("").unwrap().verification, Default::default());
        // the repository's default scene declares the continuous u space an expected failure
        let own = &sdcrack_core::scene::Scene::default_scene().verification;
        assert_eq!(own.expected_failures.len(), 1);
        assert_eq!(
            own.expected_failures[0].series.u_space,
            Some(sdcrack_core::problem::USpace::Continuous)
        );
    }

    #[test]
    fn bad_declarations_are_one_line_errors_naming_the_key() {
        let cases = [
            (
                "[[verification.expected_failure]]\nu_space = \"continous\"\nreason = \"r\"\n",
                "verification.expected_failure[0].u_space: \"continous\" is not among the scene's values (continuous, broken or \"*\"); did you mean \"continuous\"?",
            ),
            (
                "[[verification.expected_failure]]\nu_space = \"*\"\nquantity = \"u_L2\"\nreason = \"r\"\n",
                "did you mean \"u_l2\"?",
            ),
            (
                "[[verification.expected_failure]]\nu_space = \"*\"\nreason = \"  \"\n",
                "verification.expected_failure[0].reason: say why",
            ),
            (
                "[[verification.expected_failure]]\nu_space = \"broken\"\nreason = \"a\"\n\
                 [[verification.expected_failure]]\nu_space = \"broken\"\nreason = \"b\"\n",
                "expected_failure[1] declares the same series",
            ),
            ("[verification]\nkkt_tolerance = -1.0\n", "kkt_tolerance = -1 must be"),
            ("[verification]\nmin_rate = nan\n", "min_rate = NaN must be"),
            ("[verification]\nkkt_tolerence = 1e-12\n", "did you mean `kkt_tolerance`?"),
            (
                "[[verification.expected_rate]]\nquantity = \"u_l2\"\nrate = 0.0\nreason = \"r\"\n",
                "verification.expected_rate[0].rate = 0 must be a number in (0, 4]",
            ),
            (
                "[[verification.expected_rate]]\nrate = 1.0\nreason = \" \"\n",
                "verification.expected_rate[0].reason: say why",
            ),
            (
                "[[verification.expected_rate]]\np_mass = \"lumpd\"\nrate = 1.0\nreason = \"r\"\n",
                "did you mean \"lumped\"?",
            ),
            (
                "[[verification.not_applicable]]\ncheck = \"interpolation\"\nreason = \"r\"\n",
                "verification.not_applicable[0].check: \"interpolation\" is none of",
            ),
            (
                "[[verification.expected_rate]]\nrate = 1.0\nreason = \"r\"\norder = 2\n",
                "unknown",
            ),
        ];
        for (table, needle) in cases {
            let e = with(table).expect_err(table);
            assert!(e.contains(needle), "{table:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn expected_rates_and_not_applicable_checks_are_read() {
        let s = with(
            "[[verification.expected_rate]]\nu_space = \"broken\"\nquantity = \"u_l2\"\n\
             p_mass = \"lumped\"\nrate = 1.0\nreason = \" corner \"\n\
             [[verification.not_applicable]]\ncheck = \"reference yardstick\"\nreason = \"x\"\n",
        )
        .unwrap();
        let v = &s.verification;
        assert_eq!(v.expected_rates.len(), 1);
        let r = &v.expected_rates[0];
        assert_eq!(
            r.series.u_space,
            Some(sdcrack_core::problem::USpace::Broken)
        );
        assert_eq!(
            (r.series.p_mass, r.series.p_space, r.quantity),
            (
                Some(sdcrack_core::problem::PMass::Lumped),
                None,
                Some(sdcrack_core::norms::Quantity::UL2)
            )
        );
        assert_eq!((r.rate, r.reason.as_str()), (1.0, "corner"));
        assert_eq!(
            v.not_applicable,
            vec![("reference yardstick".to_string(), "x".to_string())]
        );
    }
}
