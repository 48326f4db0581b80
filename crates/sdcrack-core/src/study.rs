//! The driver: the study of one scene, read like the algorithm.
//!
//! for each level → mesh → for each u space → for each p space it serves and p mass → assemble,
//! analyse the pattern → for each δ (largest first) → factor K(δ), reduce to the crack
//! (x₀ = K⁻¹b, H_N = N K⁻¹ Nᵀ) → for each multiplier → solve the LCP (warm-started from the
//! previous δ), recover x, refine, measure the KKT residuals, the errors against `[exact]` and the
//! fields → record the case.
//!
//! One numeric factorisation per (level, u space, δ) serves the three multipliers; the symbolic
//! factorisation is shared by every δ. The exact solution's data at the error norms' quadrature
//! points are evaluated once per level and read by all its norm passes ([`NormCache`], within
//! [`NORM_CACHE_BUDGET`]). Phase timings are recorded per case; phases shared by several cases
//! (assembly, factorisation, crack reduction) are reported with each of them and flagged as shared
//! in the summary.

use std::time::Instant;

use crate::assembly::{assemble, AssemblyError, System};
use crate::case::{CaseAxes, CaseKey, MeshKey, Pattern};
use crate::contact::{KktResiduals, Lcp, LcpOptions, LcpStatus};
use crate::fe::mini::bubble_coefficients;
use crate::fe::p1::TriangleGeometry;
use crate::linalg::{componentwise_backward_error, Ldlt, LinalgError, SymbolicLdlt};
use crate::mesh::{Mesh, MeshError, PTopology, UTopology};
use crate::multiplier::{CrackField, CrackOperators, Multiplier};
use crate::norms::{DiscreteSolution, ErrorNorms, NormCache, NormQuadrature, NORM_CACHE_BUDGET};
use crate::ordering::elimination_order;
use crate::problem::PMass;
use crate::scene::{ScalarProblem, Scene};

pub mod elastic;
#[cfg(test)]
mod tests;

/// Right-hand sides solved together when reducing K⁻¹ to the crack (bounds memory to 32 n values).
const REDUCTION_BLOCK: usize = 32;

/// Refinement steps of the recovery solve K x = b − Nᵀ Sᵀ μ, at most.
const RECOVERY_STEPS: usize = 3;
/// The recovery's refinement stops once the componentwise backward error of every multiplier
/// space's x is ≤ this (≈ 4.5 ε: a few ε after the first solve, below ε after one step).
const RECOVERY_TOLERANCE: f64 = 1e-15;

/// A δ reuses the `‖K(δ')⁻¹‖₁` estimated at an earlier δ' of its sweep when the perturbation
/// bound guarantees that the true `‖K(δ)⁻¹‖₁` lies within this factor of the true `‖K(δ')⁻¹‖₁`:
/// κ₁ is then reported to within this factor on top of the estimator's own uncertainty (a lower
/// bound usually within 3×), for none of its four solves.
pub const CONDITION_REUSE_FACTOR: f64 = 1.1;

/// The factor by which the reuse test assumes that the Hager–Higham estimate may fall short of
/// the true `‖K(δ')⁻¹‖₁` (Higham 1988: usually within a factor 3).
const ESTIMATOR_SLACK: f64 = 3.0;

/// Relative KKT residual under which a case counts as solved ([`crate::contact`]'s).
pub use crate::contact::KKT_TOLERANCE;

/// Errors that stop a study.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The crack does not fit the mesh.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Data could not be integrated.
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    /// The sparse solver failed.
    #[error("linear solver: {0}")]
    Linalg(#[from] LinalgError),
    /// The scene poses the elastic problem, and the command runs the scalar problem's study
    /// (`sdcrack bench`); an elastic scene's cases run in [`run_elastic_study`].
    #[error("this command times the scalar problem's solver only; an elastic scene's cases run with sdcrack run")]
    NotScalar,
    /// The elastic study was given a scalar scene.
    #[error("the elastic study runs an elastic scene only")]
    NotElastic,
    /// An elastic case cannot be solved (bad data found by the solver, a factorisation failure).
    #[error("{0}")]
    Afw(#[from] crate::afw::AfwError),
}

/// The cases a scene asks for after a filter.
#[derive(Clone, Debug)]
pub struct CasePlan {
    /// The scene's case axes, each restricted by the filter.
    pub axes: CaseAxes,
    /// Quadrature of the error norms.
    pub norm_quadrature: NormQuadrature,
    /// Keep every case's fields (u, p with its bubbles for the consistent p mass, λ) and the
    /// meshes in the [`StudyResult`]: what a run writes to `fields.h5` / `verification.h5`, from
    /// which the compare tool recomputes the errors. On for every plan of [`CasePlan::new`];
    /// `sdcrack bench` turns it off to time and measure the solver alone.
    pub keep_fields: bool,
}

impl CasePlan {
    /// The plan of `scene` restricted by `filter` (each axis it names replaces the scene's
    /// list by its one value).
    pub fn new(scene: &Scene, filter: &Pattern<CaseKey>) -> CasePlan {
        CasePlan {
            axes: filter.restrict(&scene.axes),
            norm_quadrature: NormQuadrature::default(),
            keep_fields: true,
        }
    }

    /// Number of cases ([`CaseAxes::case_count`]).
    pub fn len(&self) -> usize {
        self.axes.case_count()
    }

    /// True when the plan has no case.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Wall-clock seconds per phase of one case.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Timings {
    /// Mesh and assembly of K and b (shared by every δ and multiplier of a level and u space).
    pub assembly: f64,
    /// Symbolic analysis (shared like `assembly`).
    pub symbolic: f64,
    /// Numeric LDLᵀ of K(δ) (shared by the multipliers of a δ).
    pub factorization: f64,
    /// x₀ and H_N = N K⁻¹ Nᵀ (shared by the multipliers of a δ).
    pub crack_reduction: f64,
    /// Condition estimate of K(δ) (shared by the multipliers of a δ).
    pub condition: f64,
    /// LCP, recovery of x with refinement, KKT residuals.
    pub contact: f64,
    /// Error norms against `[exact]` with their quadrature-error estimate (the rule and the
    /// higher rule): one pass per rule for all the multipliers of a δ, its time shared equally.
    /// The exact data at the rules' points are evaluated once per level, within the budget of
    /// [`NORM_CACHE_BUDGET`] ([`NormCache`]): in the first pass of the level, whose cases carry
    /// that time; the later passes (other δ, u spaces, p spaces, p masses) read them.
    pub norms: f64,
    /// Preparing field arrays (the p bubbles, when only the fields need them, are in `norms`).
    pub fields: f64,
}

/// Field arrays of one case, at the u dofs (the cracked mesh for `broken`).
#[derive(Clone, Debug)]
pub struct CaseFieldData {
    /// u at each dof.
    pub u: Vec<f64>,
    /// p at each dof's vertex, seen from the dof's face (p⁺ and p⁻ at a crack vertex doubled
    /// by the broken-tangential p, [`PTopology::at_u_dofs`]).
    pub p: Vec<[f64; 2]>,
    /// Bubble coefficients of p per triangle (see [`crate::fe::mini::mini_value`]); empty for
    /// the lumped p mass, whose p is P1 without bubble.
    pub p_bubble: Vec<[f64; 2]>,
    /// λ_h on the crack.
    pub lambda: CrackField,
}

/// One solved case.
#[derive(Clone, Debug)]
pub struct CaseResult {
    /// The case: its value of every axis.
    pub key: CaseKey,
    /// Mesh size (triangle diameter).
    pub h: f64,
    /// Unknowns of the condensed system (p unknowns + u dofs) plus multipliers.
    pub unknowns: usize,
    /// Number of multipliers.
    pub multipliers: usize,
    /// LCP iterations (linear solves on the crack).
    pub iterations: usize,
    /// LCP outcome.
    pub status: LcpStatus,
    /// True when the LCP converged and every KKT residual is ≤ [`KKT_TOLERANCE`].
    pub converged: bool,
    /// KKT residuals.
    pub kkt: KktResiduals,
    /// Multipliers in the final active set (μ > 0: open part of the crack).
    pub active: usize,
    /// Regularised pivots in the factorisation of K(δ).
    pub regularized_pivots: usize,
    /// Estimate of the 1-norm condition number κ₁(K(δ)) of the factored system:
    /// `‖K(δ)‖₁` times the Hager–Higham estimate of `‖K(δ')⁻¹‖₁` at `condition_delta`.
    pub condition_estimate: f64,
    /// The δ' whose `‖K(δ')⁻¹‖₁` estimate the condition estimate uses: δ itself, or an earlier δ
    /// of the sweep close enough by [`InverseNorm::serves`] (within [`CONDITION_REUSE_FACTOR`]).
    pub condition_delta: f64,
    /// Phase timings.
    pub timings: Timings,
    /// Errors against `[exact]`.
    pub errors: Option<ErrorNorms>,
    /// An estimate of the quadrature error of each of `errors`: |e(rule) − e(higher rule)|
    /// ([`crate::norms::error_norms_estimated`]), in the units of the error.
    pub errors_quadrature: Option<ErrorNorms>,
    /// Fields, every quantity whatever the scene's `fields` (`None` only when the plan's
    /// [`CasePlan::keep_fields`] is off).
    pub fields: Option<CaseFieldData>,
}

/// Mesh data of a (level, u space) pair, for field output.
#[derive(Clone, Debug)]
pub struct MeshRecord {
    /// The cases whose fields live on this mesh: those of its level and u space.
    pub key: MeshKey,
    /// Points of the u dofs.
    pub points: Vec<[f64; 2]>,
    /// Triangles in u-dof numbering.
    pub triangles: Vec<[usize; 3]>,
    /// Crack node coordinates (cracks concatenated).
    pub crack_points: Vec<[f64; 2]>,
    /// Crack edges as pairs of indices into `crack_points` (within one crack).
    pub crack_segments: Vec<[usize; 2]>,
    /// Each crack node's (+ dof, − dof) in `crack_points`' order, the u topology's
    /// [`crate::mesh::UTopology::crack_dofs`] (one dof twice at a tip and in the continuous space).
    pub crack_dofs: Vec<(usize, usize)>,
}

/// Everything a study produced.
#[derive(Clone, Debug, Default)]
pub struct StudyResult {
    /// Cases in the order solved.
    pub cases: Vec<CaseResult>,
    /// Meshes used (empty when the plan's [`CasePlan::keep_fields`] is off).
    pub meshes: Vec<MeshRecord>,
    /// Where an unstructured level 0 came from (gmsh's version and time, or the mesh file).
    pub coarse_mesh: Option<crate::mesh::CoarseProvenance>,
    /// The elastic cases in the order solved (an elastic scene's study, [`elastic`]).
    pub elastic: Vec<elastic::ElasticCaseResult>,
    /// The meshes of the elastic cases' levels (empty when the plan's
    /// [`CasePlan::keep_fields`] is off).
    pub elastic_meshes: Vec<elastic::ElasticMeshRecord>,
}

/// Progress callbacks of a study.
pub trait Observer {
    /// A phase shared by several cases starts (for progress messages).
    fn phase(&mut self, _message: &str) {}
    /// A case is done.
    fn case_done(&mut self, _case: &CaseResult) {}
    /// An elastic case is done.
    fn elastic_case_done(&mut self, _case: &elastic::ElasticCaseResult) {}
}

/// An observer that ignores everything.
pub struct Silent;
impl Observer for Silent {}

/// Runs every case of `plan` for `scene`.
pub fn run_study(
    scene: &Scene,
    plan: &CasePlan,
    observer: &mut dyn Observer,
) -> Result<StudyResult, StudyError> {
    let mut result = StudyResult::default();
    let problem = scene.scalar().ok_or(StudyError::NotScalar)?;
    let source = scene.mesh_source()?;
    result.coarse_mesh = source.provenance.clone();
    for &level in &plan.axes.levels {
        let t0 = Instant::now();
        let mesh = source.level(level)?;
        let ops = CrackOperators::new(&mesh);
        // S of each multiplier space: the mesh's, shared by every u space, p space, p mass and δ
        let multipliers: Vec<Multiplier> = (plan.axes.multipliers.iter())
            .map(|&space| Multiplier::new(space, &ops))
            .collect();
        let mesh_time = t0.elapsed().as_secs_f64();
        // the exact data at the norms' points, evaluated in the level's first norm pass and read
        // by all the others; a level of one pass (one δ, u space, p space and p mass) keeps
        // nothing: storing the values would only add to its one evaluation
        let passes =
            plan.axes.space_pairs().len() * plan.axes.p_masses.len() * plan.axes.deltas.len();
        let budget = if passes > 1 { NORM_CACHE_BUDGET } else { 0 };
        let norm_cache = (problem.exact.as_ref())
            .map(|exact| NormCache::new(&mesh, exact, &problem.f, plan.norm_quadrature, budget));
        for &u_space in &plan.axes.u_spaces {
            observer.phase(&format!("level {level}, {u_space}: assembling"));
            let t1 = Instant::now();
            let topo = mesh.u_topology(u_space);
            let topo_time = mesh_time + t1.elapsed().as_secs_f64();
            if plan.keep_fields {
                result.meshes.push(MeshRecord {
                    key: MeshKey { level, u_space },
                    points: topo.dof_vertex.iter().map(|&v| mesh.vertices[v]).collect(),
                    triangles: topo.triangle_dofs.clone(),
                    crack_points: ops.points.clone(),
                    crack_segments: ops.segments.clone(),
                    crack_dofs: topo.crack_dofs.clone(),
                });
            }
            let p_spaces = plan.axes.p_spaces.iter().filter(|p| p.serves(u_space));
            for &p_space in p_spaces {
                let ptopo = mesh.p_topology(p_space);
                let p_ops = ops.clone().with_p_topology(&ptopo);
                for &p_mass in &plan.axes.p_masses {
                    observer.phase(&format!(
                        "level {level}, {u_space} u, {p_space} p, {p_mass} p mass: assembling"
                    ));
                    let t1 = Instant::now();
                    let mut system =
                        assemble(&mesh, &topo, &ptopo, &problem.f, &problem.g, p_mass)?;
                    let assembly = topo_time + t1.elapsed().as_secs_f64();
                    let t2 = Instant::now();
                    let order = elimination_order(&mesh, &topo, &ptopo, &p_ops, p_mass);
                    let symbolic = SymbolicLdlt::analyze_ordered(&system.base, &order)?;
                    let symbolic_time = t2.elapsed().as_secs_f64();
                    // the sweep's only copy of K: each δ is written into it (System::set_delta)
                    let k = std::mem::take(&mut system.base);
                    let ctx = LevelContext {
                        problem,
                        mesh: &mesh,
                        topo: &topo,
                        ptopo: &ptopo,
                        ops: &p_ops,
                        multipliers: &multipliers,
                        system: &system,
                        p_mass,
                        symbolic: &symbolic,
                        norm_cache: norm_cache.as_ref(),
                        base_timings: Timings {
                            assembly,
                            symbolic: symbolic_time,
                            ..Timings::default()
                        },
                    };
                    ctx.run_deltas(k, plan, observer, &mut result.cases)?;
                }
            }
        }
    }
    Ok(result)
}

/// What the δ loop of one (level, u space, p space, p mass) needs.
struct LevelContext<'a> {
    /// The scene's (scalar) problem.
    problem: &'a ScalarProblem,
    mesh: &'a Mesh,
    topo: &'a UTopology,
    ptopo: &'a PTopology,
    /// The crack operators in the p unknowns of `ptopo`.
    ops: &'a CrackOperators,
    /// The plan's multiplier spaces, in its order.
    multipliers: &'a [Multiplier],
    system: &'a System,
    p_mass: PMass,
    symbolic: &'a SymbolicLdlt,
    /// The level's norms with their cached exact data (`None` without `[exact]`).
    norm_cache: Option<&'a NormCache<'a>>,
    base_timings: Timings,
}

/// A case of one δ solved, before its error norms: what they and its fields are computed from.
struct Solved<'m> {
    multiplier: &'m Multiplier,
    sol: crate::contact::LcpSolution,
    kkt: KktResiduals,
    /// λ_h.
    lambda: CrackField,
    /// p_h at the u dofs.
    p_dof: Vec<[f64; 2]>,
    /// p_h's bubble coefficients per triangle (zero for the lumped p with `[exact]`; empty when
    /// neither the norms nor the fields need them).
    bubbles: Vec<[f64; 2]>,
    timings: Timings,
}

/// The LCP solution of one multiplier space at one δ, before x is recovered.
struct Contact<'a> {
    /// The space with its S of D = S N.
    multiplier: &'a Multiplier,
    sol: crate::contact::LcpSolution,
    /// Sᵀ μ on the trace rows of N.
    st_mu: Vec<f64>,
    /// b − Nᵀ Sᵀ μ.
    rhs: Vec<f64>,
    /// Seconds spent on the LCP.
    time: f64,
}

/// `‖K(δ')⁻¹‖₁` as estimated at one δ' of a sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseNorm {
    /// δ'.
    pub delta: f64,
    /// The Hager–Higham estimate of `‖K(δ')⁻¹‖₁`.
    pub estimate: f64,
}

impl InverseNorm {
    /// Whether this estimate may stand for `‖K(δ)⁻¹‖₁`, where `K(δ) = K(δ') + (δ − δ') ∂K/∂δ` and
    /// `dk_norm1 = ‖∂K/∂δ‖₁`. With `A = K(δ')`, `E = (δ − δ') ∂K/∂δ` and
    /// `ε = ‖A⁻¹‖₁ ‖E‖₁ < 1`, the Neumann series gives
    /// `‖A⁻¹‖₁ / (1 + ε) ≤ ‖K(δ)⁻¹‖₁ ≤ ‖A⁻¹‖₁ / (1 − ε)`; `‖A⁻¹‖₁` is bounded by
    /// `ESTIMATOR_SLACK` (3) × the estimate, and the estimate serves when `1 / (1 − ε)` is at most
    /// [`CONDITION_REUSE_FACTOR`].
    pub fn serves(&self, delta: f64, dk_norm1: f64) -> bool {
        let eps = (delta - self.delta).abs() * dk_norm1 * ESTIMATOR_SLACK * self.estimate;
        eps < 1.0 && 1.0 / (1.0 - eps) <= CONDITION_REUSE_FACTOR
    }
}

/// The factorised system at one δ reduced to the crack.
struct Reduced {
    ldlt: Ldlt,
    matrix: crate::linalg::SymCsc,
    /// H_N, row-major (trace rows)².
    h_n: Vec<f64>,
    /// q_N = N P₀.
    q_n: Vec<f64>,
}

impl LevelContext<'_> {
    /// The δ sweep on `k`, K's pattern with K(δ') for any δ' (the system's `base`, moved out).
    fn run_deltas(
        &self,
        mut k: crate::linalg::SymCsc,
        plan: &CasePlan,
        observer: &mut dyn Observer,
        out: &mut Vec<CaseResult>,
    ) -> Result<(), StudyError> {
        let mut warm: Vec<Option<Vec<bool>>> = vec![None; self.multipliers.len()];
        let mut spare: Option<Ldlt> = None;
        let mut inverse_norm: Option<InverseNorm> = None;
        let dk_norm1 = self.system.delta_norm1;
        for &delta in &plan.axes.deltas {
            observer.phase(&format!(
                "level {}, {}, δ = {delta:e}: factorising",
                self.mesh.level, self.topo.space
            ));
            let mut timings = self.base_timings;
            let t0 = Instant::now();
            self.system.set_delta(&mut k, delta);
            let ldlt = Ldlt::refactor(self.symbolic, &k, &self.system.signs, spare.take())?;
            timings.factorization = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            let reduced = self.reduce(ldlt, k);
            timings.crack_reduction = t1.elapsed().as_secs_f64();
            let contacts: Vec<Contact> = self
                .multipliers
                .iter()
                .zip(warm.iter_mut())
                .map(|(multiplier, warm)| self.solve_lcp(&reduced, multiplier, warm))
                .collect();
            let (xs, recovery_time) = self.recover(&reduced, &contacts);
            let t2 = Instant::now();
            let inverse = match inverse_norm {
                Some(known) if known.serves(delta, dk_norm1) => known,
                _ => InverseNorm {
                    delta,
                    estimate: reduced.ldlt.inverse_norm1_estimate(),
                },
            };
            inverse_norm = Some(inverse);
            let condition_estimate = reduced.matrix.norm1() * inverse.estimate;
            timings.condition = t2.elapsed().as_secs_f64();
            // the block recovery is shared equally by the multipliers of this δ
            let share = recovery_time / contacts.len().max(1) as f64;
            let n = self.system.n();
            let solved: Vec<Solved> = contacts
                .into_iter()
                .zip(xs.chunks_exact(n))
                .map(|(contact, x)| {
                    let mut case_timings = timings;
                    case_timings.contact = contact.time + share;
                    self.solved_case(&reduced, contact, x, case_timings, plan)
                })
                .collect();
            // the error norms of every multiplier of this δ in one pass per rule over the
            // quadrature points (the exact data read from the level's cache, or evaluated once per
            // point for all of them), the time shared equally
            let t3 = Instant::now();
            let errors = self.error_norms(&solved, &xs);
            let norms_share = t3.elapsed().as_secs_f64() / solved.len().max(1) as f64;
            for ((mut solved, x), errors) in solved.into_iter().zip(xs.chunks_exact(n)).zip(errors)
            {
                solved.timings.norms += norms_share;
                let mut case = self.finish_case(&reduced, solved, x, delta, errors, plan);
                case.condition_estimate = condition_estimate;
                case.condition_delta = inverse.delta;
                observer.case_done(&case);
                out.push(case);
            }
            spare = Some(reduced.ldlt);
            k = reduced.matrix;
        }
        Ok(())
    }

    /// x₀ = K⁻¹ b and H_N = N K⁻¹ Nᵀ.
    fn reduce(&self, ldlt: Ldlt, matrix: crate::linalg::SymCsc) -> Reduced {
        let n_p = self.system.n_p;
        let mut x0 = vec![0.0; self.system.n()];
        // unrefined, like H_N: the LCP's data; x itself is recomputed and refined in `recover`
        x0.copy_from_slice(&self.system.rhs);
        ldlt.solve_in_place(&mut x0);
        let q_n = self.ops.apply_n(&x0[..n_p]);
        let h_n = self
            .h_n_from_trailing_block(&ldlt)
            .unwrap_or_else(|| self.h_n_by_solves(&ldlt));
        Reduced {
            ldlt,
            matrix,
            h_n,
            q_n,
        }
    }

    /// H_N from the dense trailing block of the factor: the crack's p unknowns are eliminated
    /// last ([`elimination_order`]), so (K⁻¹) restricted to them costs O((2I+2)³), no solve.
    fn h_n_from_trailing_block(&self, ldlt: &Ldlt) -> Option<Vec<f64>> {
        let indices: Vec<usize> = self.ops.node_p_dofs.iter().flatten().copied().collect();
        let inv = ldlt.trailing_inverse(&indices)?;
        Some(self.ops.h_n_from_node_block(&inv))
    }

    /// H_N = N K⁻¹ Nᵀ column by column from block solves (any elimination order).
    fn h_n_by_solves(&self, ldlt: &Ldlt) -> Vec<f64> {
        let n = self.system.n();
        let n_p = self.system.n_p;
        let m = self.ops.rows.len();
        // H_N column by column in blocks, so the right-hand sides never hold more than
        // REDUCTION_BLOCK vectors of length n at once.
        let mut h_n = vec![0.0; m * m];
        let mut z = vec![0.0; n * REDUCTION_BLOCK.min(m)];
        for start in (0..m).step_by(REDUCTION_BLOCK) {
            let cols = REDUCTION_BLOCK.min(m - start);
            let z = &mut z[..n * cols];
            z.fill(0.0);
            for c in 0..cols {
                let mut e = vec![0.0; m];
                e[start + c] = 1.0;
                self.ops.add_nt(&e, &mut z[c * n..c * n + n_p]);
            }
            ldlt.solve_many_in_place(z, cols);
            for c in 0..cols {
                let col = self.ops.apply_n(&z[c * n..c * n + n_p]);
                for i in 0..m {
                    h_n[i * m + start + c] = col[i];
                }
            }
        }
        h_n
    }

    /// Solves the multiplier LCP of one space on the reduced system (warm-started).
    fn solve_lcp<'m>(
        &self,
        reduced: &Reduced,
        multiplier: &'m Multiplier,
        warm: &mut Option<Vec<bool>>,
    ) -> Contact<'m> {
        let t0 = Instant::now();
        let lcp = Lcp::reduce(&multiplier.s, &reduced.h_n, &reduced.q_n);
        let sol = lcp.solve(warm.as_deref(), LcpOptions::default());
        *warm = Some(sol.active.clone());
        // Sᵀ μ, and the right-hand side b − Nᵀ Sᵀ μ of the recovery K x = b − Nᵀ Sᵀ μ.
        let st_mu = multiplier.transpose_apply(&sol.mu);
        let mut rhs = self.system.rhs.clone();
        let neg: Vec<f64> = st_mu.iter().map(|v| -v).collect();
        self.ops.add_nt(&neg, &mut rhs[..self.system.n_p]);
        Contact {
            multiplier,
            sol,
            st_mu,
            rhs,
            time: t0.elapsed().as_secs_f64(),
        }
    }

    /// x = K⁻¹ (b − Nᵀ Sᵀ μ) for every multiplier space (each solved and refined against the
    /// exact K(δ) on its own, so that a rerun of one space reproduces it bit for bit). Returns
    /// the n × k solutions and the seconds of the recovery.
    fn recover(&self, reduced: &Reduced, contacts: &[Contact]) -> (Vec<f64>, f64) {
        let t0 = Instant::now();
        let b: Vec<f64> = contacts
            .iter()
            .flat_map(|c| c.rhs.iter().copied())
            .collect();
        let mut x = vec![0.0; b.len()];
        reduced.ldlt.solve_refined_many(
            &reduced.matrix,
            &b,
            &mut x,
            RECOVERY_STEPS,
            RECOVERY_TOLERANCE,
        );
        (x, t0.elapsed().as_secs_f64())
    }

    /// KKT residuals, λ_h, and p_h at the u dofs with its bubbles of one solved case: what its
    /// error norms and fields are computed from.
    fn solved_case<'m>(
        &self,
        reduced: &Reduced,
        contact: Contact<'m>,
        x: &[f64],
        mut timings: Timings,
        plan: &CasePlan,
    ) -> Solved<'m> {
        let t0 = Instant::now();
        let Contact {
            multiplier,
            sol,
            st_mu,
            rhs,
            ..
        } = contact;
        let kkt = self.kkt(reduced, multiplier, &sol.mu, &st_mu, &rhs, x);
        timings.contact += t0.elapsed().as_secs_f64();
        let lambda = multiplier.lambda_field(self.ops, &sol.mu);
        let (p, u) = x.split_at(self.system.n_p);
        let t1 = Instant::now();
        // p at the u dofs: the vertex values seen from each dof's face
        let p_dof = self.ptopo.at_u_dofs(self.mesh, self.topo, p);
        // The lumped p is P1 without bubble: zero bubbles in the norms, none in the fields.
        let exact = self.problem.exact.is_some();
        let bubbles = match self.p_mass {
            PMass::Consistent if exact || plan.keep_fields => self.bubbles(&p_dof, u),
            PMass::Lumped if exact => vec![[0.0; 2]; self.mesh.triangles.len()],
            _ => Vec::new(),
        };
        timings.norms = t1.elapsed().as_secs_f64();
        Solved {
            multiplier,
            sol,
            kkt,
            lambda,
            p_dof,
            bubbles,
            timings,
        }
    }

    /// The error norms against `[exact]` of the solved cases of one δ (`xs`: their solutions, one
    /// after the other), with the estimate of their quadrature errors, in one pass per rule
    /// ([`NormCache::error_norms_estimated_many`]); `None` each without `[exact]`.
    fn error_norms(&self, solved: &[Solved], xs: &[f64]) -> Vec<Option<(ErrorNorms, ErrorNorms)>> {
        let Some(cache) = self.norm_cache else {
            return vec![None; solved.len()];
        };
        let sols: Vec<DiscreteSolution> = solved
            .iter()
            .zip(xs.chunks_exact(self.system.n()))
            .map(|(s, x)| DiscreteSolution {
                u: &x[self.system.n_p..],
                p: &s.p_dof,
                bubbles: &s.bubbles,
                lambda: &s.lambda,
                source: &self.problem.f,
            })
            .collect();
        cache
            .error_norms_estimated_many(self.topo, &sols)
            .into_iter()
            .map(Some)
            .collect()
    }

    /// The result of one solved case with its error norms and their estimate.
    fn finish_case(
        &self,
        reduced: &Reduced,
        solved: Solved,
        x: &[f64],
        delta: f64,
        estimated: Option<(ErrorNorms, ErrorNorms)>,
        plan: &CasePlan,
    ) -> CaseResult {
        let (multiplier, sol, kkt) = (solved.multiplier, solved.sol, solved.kkt);
        let mut timings = solved.timings;
        let u = &x[self.system.n_p..];
        let (errors, errors_quadrature) = (estimated.map(|e| e.0), estimated.map(|e| e.1));
        let t2 = Instant::now();
        let fields = plan.keep_fields.then(|| CaseFieldData {
            u: u.to_vec(),
            p: solved.p_dof,
            p_bubble: match self.p_mass {
                PMass::Consistent => solved.bubbles,
                PMass::Lumped => Vec::new(),
            },
            lambda: solved.lambda,
        });
        timings.fields = t2.elapsed().as_secs_f64();
        let converged = sol.status.converged() && kkt.max() <= KKT_TOLERANCE;
        CaseResult {
            key: CaseKey {
                level: self.mesh.level,
                u_space: self.topo.space,
                multiplier: multiplier.space,
                p_mass: self.p_mass,
                p_space: self.ptopo.space,
                delta,
                problem: crate::scene::ProblemKind::Scalar,
            },
            h: self.mesh.h(),
            unknowns: self.system.n() + multiplier.len(),
            multipliers: multiplier.len(),
            iterations: sol.iterations,
            status: sol.status,
            converged,
            kkt,
            active: sol.mu.iter().filter(|&&v| v > 0.0).count(),
            regularized_pivots: reduced.ldlt.stats().regularized_pivots,
            condition_estimate: f64::NAN,
            condition_delta: delta,
            timings,
            errors,
            errors_quadrature,
            fields,
        }
    }

    fn kkt(
        &self,
        reduced: &Reduced,
        multiplier: &Multiplier,
        mu: &[f64],
        st_mu: &[f64],
        rhs_mu: &[f64],
        x: &[f64],
    ) -> KktResiduals {
        let n = self.system.n();
        let mut kx = vec![0.0; n];
        let mut scale = vec![0.0; n];
        reduced.matrix.mul_vec_with_abs(x, &mut kx, &mut scale);
        let mut dt_mu = vec![0.0; self.system.n_p];
        self.ops.add_nt(st_mu, &mut dt_mu);
        // Componentwise (Oettli–Prager) backward error of K x + Dᵀμ = b: row i's residual over
        // (|K||x| + |Dᵀμ| + |b|)_i. Invariant under any diagonal scaling of rows and unknowns, so
        // under the dilations of the domain and the scaling of the data (tests/stability.rs).
        let n_p = self.system.n_p;
        for i in 0..n {
            let dt = if i < n_p { dt_mu[i].abs() } else { 0.0 };
            scale[i] = scale[i] + dt + self.system.rhs[i].abs();
            kx[i] -= rhs_mu[i];
        }
        let eq = componentwise_backward_error(&kx, &scale);
        let mut k = multiplier.kkt_constraint_part(self.ops, mu, &x[..n_p]);
        k.equations = eq;
        k
    }

    /// The bubble coefficients of every triangle from p and u at the u dofs.
    fn bubbles(&self, p_dof: &[[f64; 2]], u: &[f64]) -> Vec<[f64; 2]> {
        self.mesh
            .triangles
            .iter()
            .zip(&self.topo.triangle_dofs)
            .map(|(t, dofs)| {
                let geo = TriangleGeometry::new(t.map(|v| self.mesh.vertices[v]));
                bubble_coefficients(&geo, &dofs.map(|d| p_dof[d]), &dofs.map(|d| u[d]))
            })
            .collect()
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
        let t0 = std::time::Instant::now();
        let mesh = source.level(level)?;
        let system = crate::afw::AfwCase::new(&mesh, &scene.domain, data)?;
        let assembly = t0.elapsed().as_secs_f64();
        if plan.keep_fields {
            result
                .elastic_meshes
                .push(elastic::ElasticMeshRecord::of(&mesh));
        }
        for &key in keys.iter().filter(|k| k.level == level) {
            observer.phase(&format!("{key}: solving"));
            let case = elastic::solve_case(&system, data, &mesh, key, assembly, plan.keep_fields)?;
            observer.elastic_case_done(&case);
            result.elastic.push(case);
        }
    }
    Ok(result)
}
