//! `summary.json`: one entry per case with the keys of README.md's results folder (level, h, u_space, multiplier,
//! delta, unknowns, iterations, kkt, timings_s, errors when the scene has `[exact]`, with
//! errors_quadrature, the estimate of their quadrature errors) plus the LCP
//! status, the active-set size and the factorisation's regularised pivots, the case's group in
//! the field files (`fields_grid`), and at the top level the file the compare tool recomputes
//! the errors from (`recomputation_file`).
//!
//! [`Summary`] is the file's one schema, both ways: `sdcrack run` builds it from a study
//! ([`Summary::of_run`]) and `sdcrack merge` reads the shards' files back into it
//! ([`Summary::read`]); both write it with [`Summary::write`]. Every `f64` is written as the
//! shortest text that parses back to the same bits, so a summary read and written again is the
//! same text.

use std::path::Path;

use serde::{Deserialize, Serialize};

use sdcrack_core::case::{AxisValue, CaseAxes, CaseKey};
use sdcrack_core::contact::KktResiduals;
use sdcrack_core::norms::ErrorNorms;
use sdcrack_core::scene::ProblemKind;
use sdcrack_core::study::elastic::{ElasticCaseResult, ElasticTimings, ELASTIC_SHARED_TIMINGS};
use sdcrack_core::study::{CaseResult, Timings, KKT_TOLERANCE};

/// Timing phases shared by several cases (reported with each of them): summary.json's
/// `shared_timings`.
pub const SHARED_TIMINGS: [&str; 5] = [
    "assembly",
    "symbolic",
    "factorization",
    "crack_reduction",
    "condition",
];

/// The whole summary file.
#[derive(Serialize, Deserialize, Debug, Clone)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// Scene description.
    pub description: String,
    /// The problem kind of an elastic scene, `"elasticity"` (absent: the scalar problem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub problem: Option<String>,
    /// Version of sdcrack that wrote it.
    pub sdcrack_version: String,
    /// Where the results come from: command line, binary, commit, date, machine.
    pub provenance: Provenance,
    /// The KKT tolerance a case must meet to count as converged.
    pub kkt_tolerance: f64,
    /// The cases the run was asked for: the scene's case axes, restricted by the command line's
    /// filters.
    pub plan: CaseAxes,
    /// Timing phases shared by several cases (reported with each of them): [`SHARED_TIMINGS`]
    /// (an elastic scene's: [`ELASTIC_SHARED_TIMINGS`]).
    pub shared_timings: Vec<String>,
    /// True when every case converged.
    pub all_converged: bool,
    /// Wall-clock seconds of the solves (all cases, before writing files); for a merge, the sum
    /// of the shards'.
    pub wall_s: f64,
    /// Seconds spent writing the field files (`fields.h5` with its series `fields/*.xdmf`,
    /// `verification.h5`), all cases together; for a merge, the merge's.
    pub fields_write_s: f64,
    /// The file holding every field the compare tool recomputes the errors from: `fields.h5`
    /// when the scene's `fields` lists u, p and λ, otherwise `verification.h5` (the same HDF5
    /// layout with all of them, no XDMF series). Each case's group in it is
    /// `/cases/<fields_grid>`. Absent for an elastic scene (no solver case, issue 46).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recomputation_file: Option<String>,
    /// For an unstructured scene: where level 0 came from (gmsh's version and seconds, or the
    /// mesh file) and its size; gmsh's level 0 is also written as `coarse.msh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coarse_mesh: Option<sdcrack_core::mesh::CoarseProvenance>,
    /// The cases: the scalar problem's, or an elastic scene's ([`CaseEntry`]).
    pub cases: Vec<CaseEntry>,
    /// Only in a merged summary (`sdcrack merge`): the solver shards it was made of, in the
    /// order given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shards: Option<Vec<ShardRecord>>,
}

/// One solver shard of a merged summary: its folder, and what describes its process.
#[derive(Serialize, Deserialize, Debug, Clone)]
pub struct ShardRecord {
    /// The shard folder as given to `sdcrack merge`.
    pub folder: String,
    /// The shard's own provenance.
    pub provenance: Provenance,
    /// The shard's solve seconds (its summary's `wall_s`).
    pub wall_s: f64,
}

impl Summary {
    /// The summary of a run of `scene` over `plan`: its `study`, solved in `wall_s` seconds,
    /// its field files written in `fields_write_s` seconds, by the process `provenance`.
    pub fn of_run(
        scene: &sdcrack_core::scene::Scene,
        plan: &sdcrack_core::study::CasePlan,
        study: &sdcrack_core::study::StudyResult,
        wall_s: f64,
        fields_write_s: f64,
        provenance: &Provenance,
    ) -> Summary {
        let with_fields = !scene.fields.is_empty();
        let shared: &[&str] = match scene.problem.kind() {
            ProblemKind::Scalar => &SHARED_TIMINGS,
            ProblemKind::Elasticity => &ELASTIC_SHARED_TIMINGS,
        };
        let scalar =
            (study.cases.iter()).map(|c| CaseEntry::Scalar(CaseSummary::from_case(c, with_fields)));
        let elastic = (study.elastic.iter())
            .map(|c| CaseEntry::Elastic(ElasticCaseSummary::from_case(c, with_fields)));
        Summary {
            scene: scene.name.clone(),
            description: scene.description.clone(),
            problem: (scene.scalar().is_none()).then(|| scene.problem.kind().name().to_string()),
            sdcrack_version: provenance.sdcrack_version.clone(),
            provenance: provenance.clone(),
            kkt_tolerance: KKT_TOLERANCE,
            plan: plan.axes.clone(),
            shared_timings: shared.iter().map(|s| s.to_string()).collect(),
            all_converged: study.cases.iter().all(|c| c.converged)
                && study.elastic.iter().all(|c| c.converged),
            wall_s,
            fields_write_s,
            recomputation_file: super::results_dir::recomputation_file(scene),
            coarse_mesh: study.coarse_mesh.clone(),
            cases: scalar.chain(elastic).collect(),
            shards: None,
        }
    }

    /// Reads the summary file `path`; the error says what is wrong, without the path.
    pub fn read(path: &Path) -> Result<Summary, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
        serde_json::from_str(&text).map_err(|e| format!("not a summary of sdcrack: {e}"))
    }

    /// Writes the summary to `path` (pretty JSON, keys in the order of the struct), atomically.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        super::atomic::atomic_write(path, text.as_bytes())
    }
}

/// Where a results folder comes from: enough to rerun it and to tell two runs apart.
#[derive(Serialize, Deserialize, Debug, Clone)]
pub struct Provenance {
    /// The command line exactly as given (`argv`, lossily converted to UTF-8).
    pub command_line: Vec<String>,
    /// Absolute working directory the command ran in (relative paths of the command line are
    /// relative to it).
    pub working_directory: String,
    /// Absolute path of the sdcrack binary that ran.
    pub executable: String,
    /// Version of sdcrack (Cargo.toml).
    pub sdcrack_version: String,
    /// Git commit the binary was built from (`None` outside a git checkout).
    pub git_commit: Option<String>,
    /// True when the binary's sources (`src/`, `Cargo.*`, `build.rs`) differed from that
    /// commit at build time (`None` outside a git checkout).
    pub git_dirty: Option<bool>,
    /// Start of the run, UTC, RFC 3339 to the second (`2026-11-23T16:00:00Z`).
    pub date_utc: String,
    /// Cores available to the process (`std::thread::available_parallelism`).
    pub cores: usize,
    /// The scene file as given on the command line, or `(embedded default)`; its text is the
    /// results folder's `scene.toml`.
    pub scene_origin: String,
}

/// How the running binary was built, as its build script recorded it (build.rs at the repository
/// root; the `sdcrack` package passes `sdcrack::BUILD`).
#[derive(Clone, Copy, Debug)]
pub struct Build {
    /// Version of sdcrack (Cargo.toml).
    pub version: &'static str,
    /// Git commit the binary was built from, 40 hex digits; empty outside a git checkout.
    pub git_commit: &'static str,
    /// `true` or `false`: whether the binary's sources differed from that commit; empty outside
    /// a git checkout.
    pub git_dirty: &'static str,
}

impl Provenance {
    /// The provenance of this process, built as `build` says, started at `start`, running the
    /// scene from `scene_origin`.
    pub fn of_this_process(
        scene_origin: &str,
        start: std::time::SystemTime,
        build: Build,
    ) -> Provenance {
        let absolute = |p: std::io::Result<std::path::PathBuf>| {
            p.map(|p| p.display().to_string())
                .unwrap_or_else(|e| format!("(unknown: {e})"))
        };
        let commit = build.git_commit;
        Provenance {
            command_line: std::env::args_os()
                .map(|a| a.to_string_lossy().into_owned())
                .collect(),
            working_directory: absolute(std::env::current_dir()),
            executable: absolute(std::env::current_exe()),
            sdcrack_version: build.version.to_string(),
            git_commit: (!commit.is_empty()).then(|| commit.to_string()),
            git_dirty: match build.git_dirty {
                "true" => Some(true),
                "false" => Some(false),
                _ => None,
            },
            date_utc: humantime::format_rfc3339_seconds(start).to_string(),
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            scene_origin: scene_origin.to_string(),
        }
    }
}

/// A case's key with its mesh size, as summary.json writes them: the axes in the key's order,
/// with `h` right after `level` (the order of the entries since before the key existed).
#[derive(Debug, Clone, Copy)]
pub struct SizedKey {
    /// The case.
    pub key: CaseKey,
    /// Mesh size (triangle diameter).
    pub h: f64,
}

impl SizedKey {
    /// The entries: each axis of the key, `h` after the level.
    pub fn entries(&self) -> Vec<(&'static str, AxisValue)> {
        let mut entries = self.key.entries();
        let at = entries
            .iter()
            .position(|e| e.0 == "level")
            .map_or(0, |i| i + 1);
        entries.insert(at, ("h", AxisValue::Number(self.h)));
        entries
    }
}

impl Serialize for SizedKey {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.entries())
    }
}

impl<'de> Deserialize<'de> for SizedKey {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<SizedKey, D::Error> {
        #[derive(Deserialize)]
        struct Fields {
            #[serde(flatten)]
            key: CaseKey,
            h: f64,
        }
        let f = Fields::deserialize(d)?;
        Ok(SizedKey { key: f.key, h: f.h })
    }
}

/// One case of the summary.
#[derive(Serialize, Deserialize, Debug, Clone)]
pub struct CaseSummary {
    /// The case (level, u space, multiplier, p mass, p space, δ) and its mesh size, flattened:
    /// `u_space` is `continuous` or `broken`; `multiplier` `M0`, `M1` or `M1star`; `p_mass`
    /// `consistent` (the paper's MINI p, with bubble) or `lumped` (p = D⁻¹(…), P1, no bubble);
    /// `p_space` `continuous` (the paper's p) or `broken-tangential` (p·τ one value per crack
    /// face).
    #[serde(flatten)]
    pub case: SizedKey,
    /// Unknowns (p vertex values, u dofs, multipliers).
    pub unknowns: usize,
    /// Number of multipliers.
    pub multipliers: usize,
    /// LCP iterations.
    pub iterations: usize,
    /// LCP outcome in words.
    pub status: String,
    /// True when the case met the KKT tolerance.
    pub converged: bool,
    /// KKT residuals (relative).
    #[serde(deserialize_with = "non_finite::record")]
    pub kkt: KktResiduals,
    /// Multipliers with μ > 0.
    pub active_multipliers: usize,
    /// Pivots regularised in the LDLᵀ of K(δ).
    pub regularized_pivots: usize,
    /// Estimate of κ₁(K(δ)) = ‖K‖₁‖K⁻¹‖₁ (Hager–Higham, a lower bound usually within 3×).
    #[serde(deserialize_with = "non_finite::number")]
    pub condition_estimate: f64,
    /// The δ' at which ‖K⁻¹‖₁ was estimated: δ, or an earlier δ of the sweep whose estimate
    /// holds for K(δ) to within a factor 1.1 by a perturbation bound.
    pub condition_estimate_delta: f64,
    /// Seconds per phase.
    pub timings_s: Timings,
    /// Errors against `[exact]`, when the scene has it.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "non_finite::optional_record"
    )]
    pub errors: Option<ErrorNorms>,
    /// With `errors`: an estimate of the quadrature error of each, |e(rule) − e(higher rule)| in
    /// the units of the error (the rule of [`sdcrack_core::norms::NormQuadrature::default`] against
    /// [`sdcrack_core::norms::NormQuadrature::higher`]); the compare tool's tolerance for its own
    /// recomputation of `errors` is built from it (absent in a summary of an older sdcrack).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "non_finite::optional_record"
    )]
    pub errors_quadrature: Option<ErrorNorms>,
    /// Name of the case in the field files, always set: its group `/cases/<fields_grid>` in
    /// `fields.h5` and in `verification.h5` (whichever exist), and its step grid in the series
    /// file.
    pub fields_grid: String,
    /// The series file (relative to the results folder, `fields/<series>.series.xdmf`) whose
    /// time steps are this case's δ sweep, when the XDMF files are written (the scene lists
    /// fields); `meshio.xdmf.TimeSeriesReader` reads it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields_series: Option<String>,
    /// This case's one-state file (`fields/<fields_grid>.xdmf`), written with the series;
    /// `meshio.read` reads it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields_state: Option<String>,
}

impl CaseSummary {
    /// The summary entry of a solved case; `with_series` when the XDMF series are written.
    pub fn from_case(c: &CaseResult, with_series: bool) -> CaseSummary {
        CaseSummary {
            case: SizedKey { key: c.key, h: c.h },
            unknowns: c.unknowns,
            multipliers: c.multipliers,
            iterations: c.iterations,
            status: case_status(c.converged, c.status, &c.kkt),
            converged: c.converged,
            kkt: c.kkt,
            active_multipliers: c.active,
            regularized_pivots: c.regularized_pivots,
            condition_estimate: c.condition_estimate,
            condition_estimate_delta: c.condition_delta,
            timings_s: c.timings,
            errors: c.errors,
            errors_quadrature: c.errors_quadrature,
            fields_grid: c.key.case_name(),
            fields_series: with_series.then(|| field_file(&c.key, true)),
            fields_state: with_series.then(|| field_file(&c.key, false)),
        }
    }
}

/// One case of summary.json: a scalar case ([`CaseSummary`]) or an elastic one
/// ([`ElasticCaseSummary`], whose key names `problem`). Written as the entry itself; read back
/// as the first that fits (an elastic entry lacks the scalar one's multiplier and conditioning
/// records).
#[derive(Serialize, Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum CaseEntry {
    /// A case of the scalar problem.
    Scalar(CaseSummary),
    /// A case of the elastic problem (the AFW method).
    Elastic(ElasticCaseSummary),
}

impl CaseEntry {
    /// The case's key.
    pub fn key(&self) -> &CaseKey {
        match self {
            CaseEntry::Scalar(c) => &c.case.key,
            CaseEntry::Elastic(c) => &c.case.key,
        }
    }

    /// Whether the case met the KKT tolerance.
    pub fn converged(&self) -> bool {
        match self {
            CaseEntry::Scalar(c) => c.converged,
            CaseEntry::Elastic(c) => c.converged,
        }
    }
}

/// One elastic case of the summary (docs/elasticity.md, "The run"): its key (level, h,
/// multiplier, δ, problem), the counts, the LCP's outcome, the KKT residuals, the timings, the
/// errors against `[exact]` by name, and its place in the field files.
#[derive(Serialize, Deserialize, Debug, Clone)]
pub struct ElasticCaseSummary {
    /// The case and its mesh size, flattened: `level`, `h`, `multiplier`, `delta`,
    /// `problem` (`"elasticity"`).
    #[serde(flatten)]
    pub case: SizedKey,
    /// Unknowns of the system (σ dofs without the essential ones, u_h, γ_h).
    pub unknowns: usize,
    /// Crack edges (two constrained normal-trace dofs each).
    pub crack_edges: usize,
    /// Crack edge ends in contact (closed: opening 0, σ_νν ≤ 0 free; an open end has
    /// σ_νν = 0).
    pub closed_ends: usize,
    /// LCP iterations.
    pub iterations: usize,
    /// LCP outcome in words (as a scalar case's).
    pub status: String,
    /// True when the case met the KKT tolerance.
    pub converged: bool,
    /// KKT residuals (relative).
    #[serde(deserialize_with = "non_finite::record")]
    pub kkt: KktResiduals,
    /// Seconds per phase.
    pub timings_s: ElasticTimings,
    /// Errors against `[exact]` by name (non-finite ones `null`), when the scene has it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors: Option<serde_json::Map<String, serde_json::Value>>,
    /// Name of the case in the field files: its group `/cases/<fields_grid>` in `fields.h5`.
    pub fields_grid: String,
    /// The series file of its δ sweep (`fields/<series>.series.xdmf`), with fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields_series: Option<String>,
    /// Its one-state file (`fields/<fields_grid>.xdmf`), with fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields_state: Option<String>,
}

impl ElasticCaseSummary {
    /// The summary entry of a solved elastic case; `with_series` when the XDMF files are written.
    pub fn from_case(c: &ElasticCaseResult, with_series: bool) -> ElasticCaseSummary {
        let errors = c.errors.as_ref().map(|errors| {
            (errors.iter())
                .map(|(name, e)| {
                    let value = serde_json::Number::from_f64(*e)
                        .map_or(serde_json::Value::Null, serde_json::Value::Number);
                    (name.clone(), value)
                })
                .collect()
        });
        ElasticCaseSummary {
            case: SizedKey { key: c.key, h: c.h },
            unknowns: c.unknowns,
            crack_edges: c.crack_edges,
            closed_ends: c.closed_ends,
            iterations: c.iterations,
            status: case_status(c.converged, c.status, &c.kkt),
            converged: c.converged,
            kkt: c.kkt,
            timings_s: c.timings,
            errors,
            fields_grid: c.key.case_name(),
            fields_series: with_series.then(|| field_file(&c.key, true)),
            fields_state: with_series.then(|| field_file(&c.key, false)),
        }
    }
}

/// A case's status in words: the LCP's, or why a converged LCP is not a converged case.
fn case_status(
    converged: bool,
    status: sdcrack_core::contact::LcpStatus,
    kkt: &KktResiduals,
) -> String {
    if !converged && status.converged() {
        format!(
            "not converged: KKT residual {:.2e} above {KKT_TOLERANCE:e}",
            kkt.max()
        )
    } else {
        status.name().to_string()
    }
}

/// The case's series file (`series`) or one-state file, relative to the results folder.
fn field_file(key: &CaseKey, series: bool) -> String {
    let file = if series {
        super::xdmf::series_file(&key.series_name(), "")
    } else {
        super::xdmf::state_file(&key.case_name(), "")
    };
    format!("{}/{file}", super::results_dir::FIELDS_STEM)
}

/// Reading back what serde_json writes for a non-finite `f64` (NaN, ±∞): `null`. A solved case's
/// KKT residuals, condition estimate and errors may be non-finite (a failed solve); read back, a
/// `null` is NaN, which is written `null` again, so the summary's text is unchanged.
mod non_finite {
    use std::collections::BTreeMap;

    use serde::de::value::MapDeserializer;
    use serde::{Deserialize, Deserializer};

    /// A number, or `null` as NaN.
    pub fn number<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }

    /// A record whose fields are all numbers (KKT residuals, error norms), each `null` as NaN.
    pub fn record<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
        from_fields(BTreeMap::<String, Option<f64>>::deserialize(d)?)
    }

    /// An optional [`record`].
    pub fn optional_record<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<T>, D::Error> {
        Option::<BTreeMap<String, Option<f64>>>::deserialize(d)?
            .map(from_fields)
            .transpose()
    }

    fn from_fields<'de, T: Deserialize<'de>, E: serde::de::Error>(
        fields: BTreeMap<String, Option<f64>>,
    ) -> Result<T, E> {
        let values = (fields.into_iter()).map(|(k, v)| (k, v.unwrap_or(f64::NAN)));
        T::deserialize(MapDeserializer::<_, E>::new(values))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sdcrack_core::contact::LcpStatus;

    /// A solved case with awkward numbers: the shortest round trip needs 17 digits, a
    /// subnormal, the smallest normal, an exact zero, huge and tiny exponents.
    fn case() -> CaseResult {
        use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};
        CaseResult {
            key: CaseKey {
                level: 3,
                u_space: USpace::Broken,
                multiplier: MultiplierSpace::M1Star,
                p_mass: PMass::Lumped,
                p_space: PSpace::BrokenTangential,
                delta: 1.5e-8,
                problem: ProblemKind::Scalar,
            },
            h: 0.1 + 0.2,
            unknowns: 1234,
            multipliers: 17,
            iterations: 4,
            status: LcpStatus::Converged,
            converged: true,
            kkt: KktResiduals {
                equations: f64::EPSILON / 3.0,
                primal: 0.0,
                dual: 5e-324,
                complementarity: f64::MIN_POSITIVE,
            },
            active: 5,
            regularized_pivots: 0,
            condition_estimate: 1e17 / 7.0,
            condition_delta: 1e-6 / 3.0,
            timings: Timings::default(),
            errors: Some(ErrorNorms {
                u_l2: 1.0 / 3.0,
                p_l2: std::f64::consts::PI * 1e-300,
                p_x: (0.1 + 0.2) * 1e10,
                lambda_l2: 2f64.powi(53) + 2.0,
            }),
            errors_quadrature: Some(ErrorNorms {
                u_l2: 1e-17 / 3.0,
                p_l2: 0.0,
                p_x: 5e-324,
                lambda_l2: 2.5e-6,
            }),
            fields: None,
        }
    }

    /// summary.json carries a case's errors, their quadrature estimates and KKT residuals
    /// unchanged: written by [`crate::output::write_run`] and parsed back, every value is the same
    /// `f64` bit for bit, under its own key (the compare tool recomputes the errors and compares with these).
    #[test]
    fn errors_and_kkt_round_trip_through_summary_json_bit_for_bit() {
        let c = case();
        let loaded = crate::scene_file::LoadedScene::default_scene();
        let plan = sdcrack_core::study::CasePlan::new(
            &loaded.scene,
            &sdcrack_core::case::CasePattern::default(),
        );
        let study = sdcrack_core::study::StudyResult {
            cases: vec![c.clone()],
            ..Default::default()
        };
        let build = Build {
            version: "0.1.0",
            git_commit: "",
            git_dirty: "",
        };
        let provenance = Provenance::of_this_process("test", std::time::SystemTime::now(), build);
        let dir = tempfile::tempdir().unwrap();
        crate::output::write_run(dir.path(), &loaded, &plan, &study, 1.0, &provenance).unwrap();
        let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let got = &json["cases"][0];
        let e = c.errors.unwrap();
        let bits = |v: &serde_json::Value, key: &str| {
            let x = v[key].as_f64().unwrap_or_else(|| panic!("{key}: {v}"));
            x.to_bits()
        };
        for (key, want) in [
            ("u_l2", e.u_l2),
            ("p_l2", e.p_l2),
            ("p_x", e.p_x),
            ("lambda_l2", e.lambda_l2),
        ] {
            assert_eq!(bits(&got["errors"], key), want.to_bits(), "errors.{key}");
        }
        assert_eq!(got["errors"].as_object().unwrap().len(), 4);
        let q = c.errors_quadrature.unwrap();
        for (key, want) in [
            ("u_l2", q.u_l2),
            ("p_l2", q.p_l2),
            ("p_x", q.p_x),
            ("lambda_l2", q.lambda_l2),
        ] {
            assert_eq!(
                bits(&got["errors_quadrature"], key),
                want.to_bits(),
                "errors_quadrature.{key}"
            );
        }
        assert_eq!(got["errors_quadrature"].as_object().unwrap().len(), 4);
        for (key, want) in [
            ("equations", c.kkt.equations),
            ("primal", c.kkt.primal),
            ("dual", c.kkt.dual),
            ("complementarity", c.kkt.complementarity),
        ] {
            assert_eq!(bits(&got["kkt"], key), want.to_bits(), "kkt.{key}");
        }
        assert_eq!(got["kkt"].as_object().unwrap().len(), 4);
        for (key, want) in [
            ("h", c.h),
            ("delta", c.key.delta),
            ("condition_estimate", c.condition_estimate),
            ("condition_estimate_delta", c.condition_delta),
        ] {
            assert_eq!(bits(got, key), want.to_bits(), "{key}");
        }
        assert_eq!(
            got["fields_grid"],
            "level3-broken-M1star-lumped-ptangential-delta1.5e-8"
        );
        assert_eq!(got["p_space"], "broken-tangential");
        assert_eq!(got["p_mass"], "lumped");
        assert_eq!(json["recomputation_file"], "fields.h5");
        // the key flattened in summary.json's order: its axes with h after the level, then the
        // measurements (the order of the entries since before the key existed)
        let keys: Vec<&str> = got
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        assert_eq!(
            keys[..8],
            [
                "level",
                "h",
                "u_space",
                "multiplier",
                "p_mass",
                "p_space",
                "delta",
                "unknowns"
            ]
        );
        // and read back, the same text
        let back = Summary::read(&dir.path().join("summary.json")).unwrap();
        assert_eq!(*back.cases[0].key(), c.key);
        let again = dir.path().join("again.json");
        back.write(&again).unwrap();
        assert_eq!(std::fs::read_to_string(again).unwrap(), text);
    }
}
