//! The scene file as serde reads it: these structs are the scene schema, the one place a key is
//! declared. Every table rejects unknown keys (`deny_unknown_fields`); [`super::schema`] derives
//! the list of tables, keys and value types from these structs for messages, `sdcrack schema`,
//! the fuzzer and the docs; [`super::validate`] turns them into sdcrack-core's `Scene`.
//! A new key is a new field here (with its `#[serde(default)]` when it is optional), then its
//! validation; docs/scenes.md's table must list it (a test says so).

use serde::Deserialize;

/// The whole scene file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneToml {
    pub(super) name: String,
    #[serde(default)]
    pub(super) description: String,
    pub(super) geometry: Option<GeometryToml>,
    pub(super) data: DataToml,
    pub(super) exact: Option<ExactToml>,
    pub(super) discretization: DiscretizationToml,
    pub(super) outputs: Option<OutputsToml>,
    pub(super) verification: Option<VerificationToml>,
}

/// `[geometry]`: Ω and the cracks (absent with `discretization.mesh`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GeometryToml {
    pub(super) domain: Option<DomainToml>,
    pub(super) crack: Option<CrackToml>,
    pub(super) cracks: Option<Vec<CrackToml>>,
}

/// `geometry.domain`: a rectangle (two corners) or a polygon (its vertices).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DomainToml {
    pub(super) rectangle: Option<Vec<Vec<f64>>>,
    pub(super) polygon: Option<Vec<Vec<f64>>>,
}

/// One crack: a segment (two end points) or a polyline (its points in order).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CrackToml {
    pub(super) segment: Option<Vec<Vec<f64>>>,
    pub(super) polyline: Option<Vec<Vec<f64>>>,
}

/// `discretization.mesh`: level 0 from a gmsh file, relative to the scene file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MeshFileToml {
    pub(super) gmsh: String,
}

/// `discretization.grading`: every level graded towards the crack tips.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GradingToml {
    pub(super) beta: f64,
    pub(super) radius: f64,
}

/// `[data]`: the source term and the Dirichlet data, as expressions.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DataToml {
    pub(super) f: String,
    pub(super) g: String,
}

/// `[exact]`: an exact solution, its gradient and its jump (expressions).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ExactToml {
    pub(super) u: String,
    pub(super) px: Option<String>,
    pub(super) py: Option<String>,
    pub(super) jump: Option<String>,
}

/// `[discretization]`: level 0, the levels, the spaces and the δ sweep.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DiscretizationToml {
    pub(super) cells: Option<Vec<i64>>,
    pub(super) mesh_size: Option<f64>,
    pub(super) mesh: Option<MeshFileToml>,
    #[serde(default)]
    pub(super) grading: Option<GradingToml>,
    pub(super) levels: Vec<i64>,
    pub(super) u_spaces: Vec<String>,
    pub(super) multipliers: Vec<String>,
    #[serde(default)]
    pub(super) p_mass: Option<Vec<String>>,
    #[serde(default)]
    pub(super) p_spaces: Option<Vec<String>>,
    pub(super) deltas: Vec<f64>,
}

/// `[outputs]`: the fields written and the reference solvers run.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OutputsToml {
    pub(super) fields: Vec<String>,
    pub(super) references: Vec<String>,
}

/// `[verification]`: what the compare tool's verdict may expect of the scene (validated by
/// [`super::verification`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct VerificationToml {
    #[serde(default)]
    pub(super) smoke: bool,
    pub(super) kkt_tolerance: Option<f64>,
    pub(super) reference_agreement: Option<f64>,
    pub(super) delta_slope_tolerance: Option<f64>,
    pub(super) min_rate: Option<f64>,
    #[serde(default)]
    pub(super) expected_failure: Vec<ExpectedFailureToml>,
    #[serde(default)]
    pub(super) expected_rate: Vec<ExpectedRateToml>,
    #[serde(default)]
    pub(super) not_applicable: Vec<NotApplicableToml>,
}

/// One `[[verification.expected_rate]]`: a series' expected order.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ExpectedRateToml {
    pub(super) u_space: Option<String>,
    pub(super) multiplier: Option<String>,
    pub(super) p_mass: Option<String>,
    pub(super) p_space: Option<String>,
    pub(super) quantity: Option<String>,
    pub(super) rate: f64,
    pub(super) reason: String,
}

/// One `[[verification.not_applicable]]`: a check that does not apply, and why.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct NotApplicableToml {
    pub(super) check: String,
    pub(super) reason: String,
}

/// One `[[verification.expected_failure]]`: a series known not to converge.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ExpectedFailureToml {
    pub(super) u_space: String,
    pub(super) multiplier: Option<String>,
    pub(super) quantity: Option<String>,
    pub(super) reason: String,
}
