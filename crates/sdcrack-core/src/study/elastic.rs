//! The driver of an elastic scene (the smooth-domain method for elasticity, [`crate::afw`]):
//!
//! for each level → mesh → assemble and analyse ([`crate::afw::AfwCase`]) → for each δ (the
//! scene's order) → for each multiplier space → solve → [`crate::afw::recover`] →
//! [`crate::afw::errors`] (with `[exact]`) → record the case.
//!
//! Its cases are the plan's [`CaseAxes::elastic_keys`] (levels × δ × multipliers: the AFW method
//! has no u space, p mass or p space), reported to the same [`Observer`] as the scalar study's.

use std::time::Instant;

use crate::afw::{self, AfwCase, AfwErrors, AfwSolution, Recovered};
use crate::case::CaseKey;
use crate::contact::{KktResiduals, LcpStatus};
use crate::elasticity::ElasticData;
use crate::mesh::Mesh;
use crate::scene::Scene;

use super::{CasePlan, Observer, StudyError, StudyResult, KKT_TOLERANCE};

/// Wall-clock seconds per phase of one elastic case.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct ElasticTimings {
    /// The level's mesh, dofs, assembly and symbolic analysis ([`crate::afw::AfwCase::new`];
    /// shared by every case of the level: [`ELASTIC_SHARED_TIMINGS`]).
    pub assembly: f64,
    /// [`crate::afw::AfwCase::solve`]: factorisation, the contact LCP, the KKT residuals.
    pub solve: f64,
    /// [`crate::afw::recover`]: the opening, slip and pressure, σ symmetrised, u*.
    pub recovery: f64,
    /// [`crate::afw::errors`] against `[exact]` (zero without it).
    pub norms: f64,
}

/// The timing phases of [`ElasticTimings`] shared by several cases (reported with each of them):
/// summary.json's `shared_timings` of an elastic run.
pub const ELASTIC_SHARED_TIMINGS: [&str; 1] = ["assembly"];

/// The fields of one elastic case, as the field files write them: piecewise polynomials per
/// triangle and per crack edge (each discontinuous: per triangle vertex, per crack edge end).
#[derive(Clone, Debug)]
pub struct ElasticFields {
    /// The solution: raw σ_h per triangle vertex, u_h and γ_h per triangle, the crack edges
    /// (their vertices, normals and closed flags).
    pub solution: AfwSolution,
    /// What is recovered from it: sym σ_h and u* per triangle vertex, the opening, slip and
    /// pressure at the crack edges' ends.
    pub recovered: Recovered,
}

/// The errors of a case by name, in [`AfwErrors`]' order: summary.json's `errors` of an
/// elastic case (each name the field's).
pub fn error_entries(errors: &AfwErrors) -> Vec<(String, f64)> {
    // destructured, so that a new error norm cannot be left out of the summary
    let AfwErrors {
        stress_l2,
        stress_sym_l2,
        stress_energy,
        u_l2,
        projected_u_l2,
        u_star_l2,
        rotation_l2,
        asymmetry_l2,
        opening_l2,
        slip_l2,
        pressure_l2,
    } = *errors;
    [
        ("stress_l2", stress_l2),
        ("stress_sym_l2", stress_sym_l2),
        ("stress_energy", stress_energy),
        ("u_l2", u_l2),
        ("projected_u_l2", projected_u_l2),
        ("u_star_l2", u_star_l2),
        ("rotation_l2", rotation_l2),
        ("asymmetry_l2", asymmetry_l2),
        ("opening_l2", opening_l2),
        ("slip_l2", slip_l2),
        ("pressure_l2", pressure_l2),
    ]
    .into_iter()
    .map(|(name, e)| (name.to_string(), e))
    .collect()
}

/// One solved elastic case.
#[derive(Clone, Debug)]
pub struct ElasticCaseResult {
    /// The case: level, multiplier space, δ, problem kind.
    pub key: CaseKey,
    /// Mesh size (triangle diameter).
    pub h: f64,
    /// Unknowns of the system (σ dofs without the essential ones, u_h, γ_h).
    pub unknowns: usize,
    /// Crack edges (each with two normal-trace dofs constrained by the contact conditions).
    pub crack_edges: usize,
    /// Crack edge ends in contact (closed: [`crate::afw::CrackEdge::closed`]).
    pub closed_ends: usize,
    /// LCP iterations (linear solves on the crack).
    pub iterations: usize,
    /// LCP outcome.
    pub status: LcpStatus,
    /// True when the LCP converged and every KKT residual is ≤ [`KKT_TOLERANCE`].
    pub converged: bool,
    /// KKT residuals.
    pub kkt: KktResiduals,
    /// Phase timings.
    pub timings: ElasticTimings,
    /// Errors against `[exact]`, by name (the names of [`crate::afw::AfwErrors`]), in its order.
    pub errors: Option<Vec<(String, f64)>>,
    /// The fields (`None` when the plan's [`CasePlan::keep_fields`] is off).
    pub fields: Option<ElasticFields>,
}

impl ElasticCaseResult {
    /// The case's record from its solution: the counts, the LCP's outcome, converged when the
    /// LCP converged and every KKT residual is ≤ [`KKT_TOLERANCE`].
    pub fn new(key: CaseKey, h: f64, solution: &AfwSolution, timings: ElasticTimings) -> Self {
        let closed = solution.crack.iter().flat_map(|e| e.closed);
        ElasticCaseResult {
            key,
            h,
            unknowns: solution.unknowns,
            crack_edges: solution.crack.len(),
            closed_ends: closed.filter(|&c| c).count(),
            iterations: solution.lcp_iterations,
            status: solution.lcp_status,
            converged: solution.lcp_status.converged() && solution.kkt.max() <= KKT_TOLERANCE,
            kkt: solution.kkt,
            timings,
            errors: None,
            fields: None,
        }
    }
}

/// A level's mesh as the elastic fields use it: its vertices and triangles (the uncracked mesh).
#[derive(Clone, Debug)]
pub struct ElasticMeshRecord {
    /// Refinement level.
    pub level: u32,
    /// Vertex coordinates.
    pub points: Vec<[f64; 2]>,
    /// Triangles (vertex indices, `Mesh::triangles`).
    pub triangles: Vec<[usize; 3]>,
}

impl ElasticMeshRecord {
    /// The record of `mesh`.
    pub fn of(mesh: &Mesh) -> ElasticMeshRecord {
        ElasticMeshRecord {
            level: mesh.level,
            points: mesh.vertices.clone(),
            triangles: mesh.triangles.clone(),
        }
    }
}

/// Runs every elastic case of `plan` for `scene` ([`CaseAxes::elastic_keys`]: per level its mesh,
/// per δ and multiplier space the solve, the recovery and, with `[exact]`, the errors).
///
/// [`CaseAxes::elastic_keys`]: crate::case::CaseAxes::elastic_keys
pub fn run_elastic_study(
    scene: &Scene,
    plan: &CasePlan,
    observer: &mut dyn Observer,
) -> Result<StudyResult, StudyError> {
    let data = scene.elasticity().ok_or(StudyError::NotElastic)?;
    let source = scene.mesh_source()?;
    let mut result = StudyResult {
        coarse_mesh: source.provenance.clone(),
        ..StudyResult::default()
    };
    let keys = plan.axes.elastic_keys();
    for &level in &plan.axes.levels {
        observer.phase(&format!("level {level}, elasticity: assembling"));
        let t0 = Instant::now();
        let mesh = source.level(level)?;
        let system = AfwCase::new(&mesh, &scene.domain, data)?;
        let assembly = t0.elapsed().as_secs_f64();
        if plan.keep_fields {
            result.elastic_meshes.push(ElasticMeshRecord::of(&mesh));
        }
        for &key in keys.iter().filter(|k| k.level == level) {
            observer.phase(&format!("{key}: solving"));
            let case = solve_case(&system, data, &mesh, key, assembly, plan)?;
            observer.elastic_case_done(&case);
            result.elastic.push(case);
        }
    }
    Ok(result)
}

/// One elastic case on its level's `mesh`, whose `system` was assembled in `assembly` seconds:
/// solve, recover, and the errors against `[exact]` when the scene has it.
fn solve_case(
    system: &AfwCase,
    data: &ElasticData,
    mesh: &Mesh,
    key: CaseKey,
    assembly: f64,
    plan: &CasePlan,
) -> Result<ElasticCaseResult, StudyError> {
    let mut timings = ElasticTimings {
        assembly,
        ..ElasticTimings::default()
    };
    let t0 = Instant::now();
    let solution = system.solve(key.multiplier, key.delta)?;
    timings.solve = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let recovered = afw::recover(mesh, &data.material, &solution);
    timings.recovery = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let errors = (data.exact.as_ref()).map(|exact| {
        error_entries(&afw::errors(
            mesh,
            &data.material,
            &solution,
            &recovered,
            exact,
        ))
    });
    timings.norms = t2.elapsed().as_secs_f64();
    let mut case = ElasticCaseResult::new(key, mesh.h(), &solution, timings);
    case.errors = errors;
    case.fields = plan.keep_fields.then_some(ElasticFields {
        solution,
        recovered,
    });
    Ok(case)
}
