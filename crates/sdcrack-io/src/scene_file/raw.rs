//! The scene file as serde reads it: these structs are the scene schema, the one place a key is
//! declared. Every table rejects unknown keys (`deny_unknown_fields`); [`super::schema`] derives
//! the list of tables, keys and value types from these structs for messages, `sdcrack schema`,
//! the fuzzer and the docs; [`super::validate`] turns them into sdcrack-core's `Scene`.
//! A new key is a new field here (with its `#[serde(default)]` when it is optional), then its
//! validation; docs/scenes.md's table must list it (a test says so).

use std::collections::BTreeMap;

use serde::Deserialize;

/// The whole scene file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneToml {
    pub(super) name: String,
    #[serde(default)]
    pub(super) description: String,
    pub(super) problem: Option<ProblemToml>,
    pub(super) geometry: Option<GeometryToml>,
    pub(super) data: DataToml,
    pub(super) exact: Option<ExactToml>,
    pub(super) discretization: DiscretizationToml,
    pub(super) outputs: Option<OutputsToml>,
    pub(super) verification: Option<VerificationToml>,
}

/// `[problem]`: the problem kind (`"scalar"`, the default, or `"elasticity"`) and an elastic
/// scene's material (docs/elasticity.md): one pair of (E, ν) and (λ, μ), the plane model, and
/// the friction coefficient (0 only).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct ProblemToml {
    pub(super) kind: Option<String>,
    pub(super) plane: Option<String>,
    #[serde(rename = "E")]
    pub(super) young: Option<f64>,
    pub(super) nu: Option<f64>,
    pub(super) lambda: Option<f64>,
    pub(super) mu: Option<f64>,
    pub(super) friction: Option<f64>,
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

/// `[data]`: the loads, as expressions. The scalar problem's source term and Dirichlet data
/// (`f`, `g`: required in a scalar scene), or the elastic problem's body force, Dirichlet data,
/// tractions per boundary part and fixed points (the validation says which keys a kind needs
/// and refuses the other kind's).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DataToml {
    pub(super) f: Option<String>,
    pub(super) g: Option<String>,
    pub(super) fx: Option<String>,
    pub(super) fy: Option<String>,
    pub(super) gx: Option<String>,
    pub(super) gy: Option<String>,
    pub(super) traction: Option<BTreeMap<String, Vec<String>>>,
    pub(super) fixed: Option<Vec<FixedToml>>,
}

/// One `data.fixed` entry: displacement components held at 0 at a corner of Ω.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FixedToml {
    pub(super) point: Vec<f64>,
    pub(super) components: Vec<String>,
}

/// `[exact]`: the scalar problem's exact solution, its gradient and its jump, or the elastic
/// problem's displacement, stress, crack quantities and stress intensity factors.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ExactToml {
    pub(super) u: Option<String>,
    pub(super) px: Option<String>,
    pub(super) py: Option<String>,
    pub(super) jump: Option<String>,
    pub(super) ux: Option<String>,
    pub(super) uy: Option<String>,
    pub(super) sxx: Option<String>,
    pub(super) syy: Option<String>,
    pub(super) sxy: Option<String>,
    pub(super) opening: Option<String>,
    pub(super) slip: Option<String>,
    pub(super) pressure: Option<String>,
    pub(super) sif: Option<Vec<Vec<f64>>>,
}

/// `[discretization]`: level 0, the levels, the spaces and the δ sweep (the spaces and δ are the
/// scalar problem's case axes: required in a scalar scene, refused in an elastic one).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DiscretizationToml {
    pub(super) cells: Option<Vec<i64>>,
    pub(super) mesh_size: Option<f64>,
    pub(super) mesh: Option<MeshFileToml>,
    #[serde(default)]
    pub(super) grading: Option<GradingToml>,
    pub(super) levels: Vec<i64>,
    pub(super) u_spaces: Option<Vec<String>>,
    pub(super) multipliers: Option<Vec<String>>,
    #[serde(default)]
    pub(super) p_mass: Option<Vec<String>>,
    #[serde(default)]
    pub(super) p_spaces: Option<Vec<String>>,
    pub(super) deltas: Option<Vec<f64>>,
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
