//! `sdcrack bench`: the cost of the smooth-domain solver against one sparse Cholesky of its mesh.
//!
//! Owns the benchmark protocol (docs/performance.md), measured in one process, one after the other:
//! 1. the yardstick: faer's sparse Cholesky (AMD, symbolic + numeric + one solve) of the P1
//!    Laplacian on the interior vertices of the same structured mesh;
//! 2. one complete case (broken u, M1, δ = 0): mesh, assembly, ordering and symbolic analysis,
//!    numeric factorisation, crack reduction, contact solve; no field, no error norm, no reference;
//! 3. a sweep of 6 δ × 3 multipliers (18 cases, 6 numeric factorisations) on the same mesh;
//! 4. the same case and sweep with the lumped p mass, and that variant's goals
//!    ([`GoalCheck`]: one case ≤ 3 yardsticks, peak memory ≤ 3 × the yardstick's, sweep ≤ 1.3 × its
//!    own factorisations), each with the factor by which it is missed and the phases carrying it.
//!
//! Peak resident memory is read from `/proc/self/status` (`VmHWM`) and reset between the phases
//! through `/proc/self/clear_refs` where the kernel allows it.

use std::time::Instant;

use sdcrack_core::case::{CaseAxes, CasePattern};
use sdcrack_core::fe::p1::TriangleGeometry;
use sdcrack_core::krylov::{self, KrylovError};
use sdcrack_core::linalg::{cholesky_solve, CholeskyTimings, LinalgError, SymCsc};
use sdcrack_core::mesh::{Mesh, MeshError};
use sdcrack_core::multiplier::CrackOperators;
use sdcrack_core::problem::{Meshing, MultiplierSpace, PMass, USpace};
use sdcrack_core::scene::{FieldSet, Scene};
use sdcrack_core::study::{run_study, CasePlan, Observer, StudyError, StudyResult, Timings};

/// The δ values of the sweep (largest first, as every study runs them).
pub const SWEEP_DELTAS: [f64; 6] = [1.0, 1e-2, 1e-4, 1e-6, 1e-8, 0.0];

/// Errors of the benchmark.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The requested mesh does not fit the scene's crack.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The yardstick failed.
    #[error("yardstick Cholesky: {0}")]
    Linalg(#[from] LinalgError),
    /// The solver failed.
    #[error(transparent)]
    Study(#[from] StudyError),
    /// The iterative route failed.
    #[error("preconditioned CG on S: {0}")]
    Krylov(#[from] KrylovError),
    /// The scene is not meshed by the structured grid.
    #[error("sdcrack bench scales a structured scene (discretization.cells); this scene is meshed by gmsh: bench its levels with tools/bench-unstructured")]
    NotStructured,
}

/// Everything `sdcrack bench` measured (seconds, megabytes).
#[derive(Clone, Debug, serde::Serialize)]
pub struct BenchReport {
    /// Scene whose geometry and data were used.
    pub scene: String,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Cells per direction.
    pub cells: [usize; 2],
    /// Unknowns of the yardstick (interior vertices).
    pub yardstick_unknowns: usize,
    /// Unknowns of one case (condensed system plus multipliers).
    pub case_unknowns: usize,
    /// Crack multipliers of one case (M1: crack nodes).
    pub multipliers: usize,
    /// Yardstick phases.
    pub yardstick: CholeskyTimings,
    /// Yardstick total: symbolic + numeric + solve.
    pub bare_cholesky_s: f64,
    /// Wall time of one complete case.
    pub case_s: f64,
    /// Phases of that case.
    pub case_phases: Timings,
    /// One numeric factorisation of the condensed system (from the case).
    pub numeric_factor_s: f64,
    /// Wall time of the sweep.
    pub sweep_s: f64,
    /// δ values of the sweep.
    pub sweep_deltas: Vec<f64>,
    /// Cases in the sweep.
    pub sweep_cases: usize,
    /// Numeric factorisations in the sweep, summed over its δ.
    pub sweep_factorization_s: f64,
    /// Phases of the sweep: the shared ones counted once per (mesh or δ), the others summed.
    pub sweep_phases: Timings,
    /// Largest relative KKT residual over the case and the sweep.
    pub worst_kkt: f64,
    /// True when every case converged.
    pub all_converged: bool,
    /// Wall time of the same case with the lumped p mass (p eliminated: one SPD system on u).
    pub case_lumped_s: f64,
    /// Phases of the lumped case.
    pub case_lumped_phases: Timings,
    /// Peak resident memory of the lumped case phase.
    pub case_lumped_peak_rss_mb: f64,
    /// Wall time of the sweep with the lumped p mass.
    pub sweep_lumped_s: f64,
    /// Numeric factorisations of the lumped sweep, summed over its δ.
    pub sweep_lumped_factorization_s: f64,
    /// Phases of the lumped sweep, counted as in `sweep_phases`.
    pub sweep_lumped_phases: Timings,
    /// The performance goals of the lumped variant, measured.
    pub goals: Vec<GoalCheck>,
    /// Peak resident memory of the yardstick phase.
    pub yardstick_peak_rss_mb: f64,
    /// Peak resident memory of the case phase.
    pub case_peak_rss_mb: f64,
    /// Peak resident memory of the sweep phase.
    pub sweep_peak_rss_mb: f64,
    /// Peak resident memory of the whole benchmark.
    pub peak_rss_mb: f64,
    /// Whether the peak could be reset between phases (else each phase's peak includes earlier ones).
    pub peak_reset_supported: bool,
    /// Threads in the rayon pool.
    pub threads: usize,
    /// The iterative route, measured for comparison (the solver keeps the direct route).
    pub iterative: IterativeRoute,
}

/// The iterative route (preconditioned CG instead of the factorisation), measured on the lumped case's system (broken, δ = 0):
/// PCG on the Schur operator ([`sdcrack_core::krylov`]) for x₀, and what a whole case by that route needs.
#[derive(Clone, Debug, serde::Serialize)]
pub struct IterativeRoute {
    /// Assembly of the lumped system again (not part of the route's cost below).
    pub system_assembly_s: f64,
    /// Preconditioner: assembly of its matrix.
    pub preconditioner_assembly_s: f64,
    /// Preconditioner: its Cholesky (symbolic, numeric).
    pub preconditioner: CholeskyTimings,
    /// One PCG solve to [`sdcrack_core::krylov::ROUTE_TOLERANCE`].
    pub solve_s: f64,
    /// Its iterations.
    pub iterations: usize,
    /// The tolerance of the recursive residual `‖r‖₂ / ‖b‖₂` at which PCG stops.
    pub tolerance: f64,
    /// Its final true relative residual `‖b − A u‖₂ / ‖b‖₂` (the recursion's residual drifts from
    /// it once it nears round-off).
    pub relative_residual: f64,
    /// Max-norm distance of its u from the direct route's, relative to the direct u's max norm.
    pub distance_to_direct: f64,
    /// Solves a case needs by this route at least: one per trace row of N (H_N = N K⁻¹ Nᵀ column by
    /// column), x₀ and the recovery.
    pub solves_per_case: usize,
    /// A lower bound of one case by this route: the direct case's mesh + assembly, the
    /// preconditioner, and `solves_per_case` solves (no LCP, no KKT).
    pub case_lower_bound_s: f64,
    /// Peak resident memory of the measurement (system, preconditioner, PCG vectors).
    pub peak_rss_mb: f64,
}

/// One performance goal against what was measured: a ratio and its bound.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GoalCheck {
    /// The goal in words.
    pub goal: String,
    /// The bound on the ratio.
    pub bound: f64,
    /// The measured ratio.
    pub measured: f64,
    /// `measured ≤ bound`.
    pub met: bool,
    /// measured / bound: by how much the goal is missed (≤ 1 when met).
    pub missed_by: f64,
    /// The phases that carry the measured quantity, in the goal's unit, largest first.
    pub phases: Vec<(String, f64)>,
}

impl GoalCheck {
    fn new(goal: &str, bound: f64, measured: f64, mut phases: Vec<(String, f64)>) -> GoalCheck {
        phases.sort_by(|a, b| b.1.total_cmp(&a.1));
        GoalCheck {
            goal: goal.to_string(),
            bound,
            measured,
            met: measured <= bound,
            missed_by: measured / bound,
            phases,
        }
    }
}

/// The phases of a case or sweep, named as in the table, in seconds.
fn named_phases(t: &Timings) -> Vec<(String, f64)> {
    [
        ("mesh + assembly", t.assembly),
        ("ordering + symbolic", t.symbolic),
        ("numeric factorisation", t.factorization),
        ("crack reduction (x₀, H_N)", t.crack_reduction),
        ("condition estimate of K(δ)", t.condition),
        ("contact (LCP, recovery, KKT)", t.contact),
    ]
    .into_iter()
    .map(|(n, s)| (n.to_string(), s))
    .collect()
}

/// The goals for the lumped p mass: one case ≤ 3 yardsticks, its peak memory ≤ 3 ×
/// the yardstick's, the 18-case sweep ≤ 1.3 × its own numeric factorisations.
fn lumped_goals(r: &BenchReport) -> Vec<GoalCheck> {
    let y = r.bare_cholesky_s;
    let in_yardsticks = |t: &Timings| {
        named_phases(t)
            .into_iter()
            .map(|(n, s)| (n, s / y))
            .collect()
    };
    let f = r.sweep_lumped_factorization_s;
    let sweep_rest = named_phases(&r.sweep_lumped_phases)
        .into_iter()
        .map(|(n, s)| (n, s / f))
        .collect();
    vec![
        GoalCheck::new(
            "one lumped case (broken, M1, δ = 0) / yardstick",
            3.0,
            r.case_lumped_s / y,
            in_yardsticks(&r.case_lumped_phases),
        ),
        GoalCheck::new(
            "peak memory of the lumped case / the yardstick's",
            3.0,
            r.case_lumped_peak_rss_mb / r.yardstick_peak_rss_mb,
            Vec::new(),
        ),
        GoalCheck::new(
            "lumped sweep / its own numeric factorisations",
            1.3,
            r.sweep_lumped_s / f,
            sweep_rest,
        ),
    ]
}

/// The goals as table lines: bound, measured, met or missed by how much, and the phases.
fn goal_lines(goals: &[GoalCheck]) -> String {
    let mut out = String::from(
        "
goals of the lumped p mass:
",
    );
    for g in goals {
        let verdict = if g.met {
            "met".to_string()
        } else {
            format!("MISSED by {:.2} ×", g.missed_by)
        };
        out += &format!(
            "  {:<50} ≤ {:.1}: {:.2}  {verdict}
",
            g.goal, g.bound, g.measured
        );
        if !g.met && !g.phases.is_empty() {
            let parts: Vec<String> = g
                .phases
                .iter()
                .filter(|(_, v)| *v >= 0.005)
                .map(|(n, v)| format!("{n} {v:.2}"))
                .collect();
            out += &format!("    by phase (same unit): {}\n", parts.join(", "));
        }
    }
    out
}

impl BenchReport {
    /// case_s / bare_cholesky_s.
    pub fn case_ratio(&self) -> f64 {
        self.case_s / self.bare_cholesky_s
    }

    /// sweep_s / (6 × numeric_factor_s).
    pub fn sweep_ratio(&self) -> f64 {
        self.sweep_s / (self.sweep_deltas.len() as f64 * self.numeric_factor_s)
    }

    /// case peak memory / yardstick peak memory.
    pub fn memory_ratio(&self) -> f64 {
        self.case_peak_rss_mb / self.yardstick_peak_rss_mb
    }

    /// The readable table printed without `--json`.
    pub fn table(&self) -> String {
        let y = self.bare_cholesky_s;
        let row = |name: &str, s: f64| format!("{name:<44} {s:>9.2} {:>10.2}\n", s / y);
        let p = &self.case_phases;
        let mut out = format!(
            "sdcrack bench: scene '{}', {} × {} cells, {} vertices, {} threads\n\
             yardstick: {} unknowns (P1 Laplacian); case: {} unknowns, {} multipliers\n\n\
             {:<44} {:>9} {:>10}\n",
            self.scene,
            self.cells[0],
            self.cells[1],
            self.vertices,
            self.threads,
            self.yardstick_unknowns,
            self.case_unknowns,
            self.multipliers,
            "phase",
            "seconds",
            "yardsticks",
        );
        out += &row("yardstick: faer Cholesky (AMD), total", y);
        out += &row("  symbolic", self.yardstick.symbolic_s);
        out += &row("  numeric", self.yardstick.numeric_s);
        out += &row("  one solve", self.yardstick.solve_s);
        out += &row("one case (broken, M1, δ = 0), total", self.case_s);
        let phase_rows = |t: &Timings| -> String {
            named_phases(t)
                .iter()
                .map(|(n, v)| row(&format!("  {n}"), *v))
                .collect()
        };
        out += &phase_rows(p);
        out += &row(
            &format!("sweep {} δ × 3 multipliers, total", self.sweep_deltas.len()),
            self.sweep_s,
        );
        let q = &self.sweep_phases;
        out += &row(
            "  mesh + assembly, ordering + symbolic",
            q.assembly + q.symbolic,
        );
        out += &row("  numeric factorisations", q.factorization);
        out += &row("  crack reductions", q.crack_reduction);
        out += &row("  condition estimates", q.condition);
        out += &row("  contact (all cases)", q.contact);
        let l = &self.case_lumped_phases;
        out += &row("one case, lumped p mass, total", self.case_lumped_s);
        out += &phase_rows(l);
        out += &row("sweep, lumped p mass, total", self.sweep_lumped_s);
        out += &phase_rows(&self.sweep_lumped_phases);
        out += &format!(
            "lumped case: {:.2} yardsticks, peak memory {:.0} MB ({:.2} × the yardstick's)\n",
            self.case_lumped_s / y,
            self.case_lumped_peak_rss_mb,
            self.case_lumped_peak_rss_mb / self.yardstick_peak_rss_mb,
        );
        out += &format!(
            "\nratios: case / yardstick {:.2}; sweep / ({} numeric factorisations) {:.2}; \
             case memory / yardstick memory {:.2}\n\
             peak memory (MB): yardstick {:.0}, case {:.0}, sweep {:.0}{}\n\
             worst relative KKT residual {:.1e}; all cases converged: {}\n",
            self.case_ratio(),
            self.sweep_deltas.len(),
            self.sweep_ratio(),
            self.memory_ratio(),
            self.yardstick_peak_rss_mb,
            self.case_peak_rss_mb,
            self.sweep_peak_rss_mb,
            if self.peak_reset_supported {
                ""
            } else {
                " (not reset between phases)"
            },
            self.worst_kkt,
            self.all_converged,
        );
        out += &goal_lines(&self.goals);
        out += &self.iterative_lines();
        out
    }

    /// The iterative route's lines: its phases in yardsticks and the route kept.
    fn iterative_lines(&self) -> String {
        let y = self.bare_cholesky_s;
        let it = &self.iterative;
        let direct = self.case_lumped_s / y;
        let bound = it.case_lower_bound_s / y;
        format!(
            "\npreconditioned CG on S (lumped, broken, δ = 0; preconditioner: Cholesky of \
             the P1 stiffness + boundary mass / h):\n\
             \x20 preconditioner: assembly {:.2} s, Cholesky {:.2} s ({:.2} yardsticks)\n\
             \x20 one solve: {} iterations (recursive residual ≤ {:.0e}; true relative residual \
             {:.1e}), {:.2} s ({:.2} yardsticks); u within {:.1e} (relative) of the direct route's\n\
             \x20 a case by this route needs ≥ {} solves (H_N column by column over the crack's trace \
             rows, x₀, the recovery): ≥ {:.1} yardsticks against the direct route's {:.2}; peak \
             memory of one solve {:.0} MB ({:.2} × the yardstick's)\n\
             \x20 route kept: {}\n",
            it.preconditioner_assembly_s,
            it.preconditioner.symbolic_s + it.preconditioner.numeric_s,
            (it.preconditioner_assembly_s + it.preconditioner.symbolic_s + it.preconditioner.numeric_s)
                / y,
            it.iterations,
            it.tolerance,
            it.relative_residual,
            it.solve_s,
            it.solve_s / y,
            it.distance_to_direct,
            it.solves_per_case,
            bound,
            direct,
            it.peak_rss_mb,
            it.peak_rss_mb / self.yardstick_peak_rss_mb,
            if bound < direct {
                "the iterative route's lower bound is below the direct case: worth building"
            } else {
                "direct (the iterative route's lower bound exceeds the direct case)"
            },
        )
    }
}

/// Level-0 cells of the benchmark mesh: the scene's cells times the integer k that brings the
/// vertex count closest to `vertices` (a multiple keeps the crack's ends on mesh vertices).
pub fn bench_cells(scene: &Scene, vertices: usize) -> Result<[usize; 2], BenchError> {
    let Meshing::Cells([cx, cy]) = scene.meshing else {
        return Err(BenchError::NotStructured);
    };
    let count = |k: usize| (cx * k + 1) * (cy * k + 1);
    let guess = ((vertices as f64) / (cx * cy) as f64).sqrt().max(1.0) as usize;
    Ok((guess.saturating_sub(1).max(1)..=guess + 1)
        .min_by_key(|&k| count(k).abs_diff(vertices))
        .map_or([cx, cy], |k| [cx * k, cy * k]))
}

/// Runs the three measurements on a mesh of about `vertices` vertices.
///
/// # Errors
/// [`BenchError`] when the mesh cannot be built or a solve fails.
pub fn run_bench(
    scene: &Scene,
    vertices: usize,
    observer: &mut dyn Observer,
) -> Result<BenchReport, BenchError> {
    if scene.scalar().is_none() {
        return Err(StudyError::NotScalar.into());
    }
    let cells = bench_cells(scene, vertices)?;
    let mut bench_scene = scene.clone();
    bench_scene.meshing = Meshing::Cells(cells);
    bench_scene.level0 = sdcrack_core::scene::Level0Size::Grid(cells);
    bench_scene.axes.levels = vec![0];
    bench_scene.fields = FieldSet::default();
    if let Some(problem) = bench_scene.scalar_mut() {
        problem.exact = None;
    }
    bench_scene.references.clear();

    observer.phase("yardstick: Cholesky of the P1 Laplacian");
    let peak_reset_supported = reset_peak_rss();
    let (yardstick, yardstick_unknowns, n_vertices) = yardstick(&bench_scene)?;
    let yardstick_peak_rss_mb = peak_rss_mb();

    reset_peak_rss();
    let one_case = CasePattern {
        level: Some(0),
        u_space: Some(USpace::Broken),
        multiplier: Some(MultiplierSpace::M1),
        p_mass: Some(PMass::Consistent),
        delta: Some(0.0),
        ..CasePattern::default()
    };
    let case_plan = CasePlan {
        // the solver alone: no field arrays kept for output
        keep_fields: false,
        ..CasePlan::new(&bench_scene, &one_case)
    };
    let t0 = Instant::now();
    let case = run_study(&bench_scene, &case_plan, observer)?;
    let case_s = t0.elapsed().as_secs_f64();
    let case_peak_rss_mb = peak_rss_mb();

    reset_peak_rss();
    let sweep_plan = CasePlan {
        axes: CaseAxes {
            multipliers: vec![
                MultiplierSpace::M0,
                MultiplierSpace::M1,
                MultiplierSpace::M1Star,
            ],
            deltas: SWEEP_DELTAS.to_vec(),
            ..case_plan.axes.clone()
        },
        ..case_plan.clone()
    };
    let t1 = Instant::now();
    let sweep = run_study(&bench_scene, &sweep_plan, observer)?;
    let sweep_s = t1.elapsed().as_secs_f64();
    let sweep_peak_rss_mb = peak_rss_mb();

    observer.phase("lumped p mass: one case and the sweep");
    reset_peak_rss();
    let lumped_plan = CasePlan {
        axes: CaseAxes {
            p_masses: vec![PMass::Lumped],
            ..case_plan.axes.clone()
        },
        ..case_plan
    };
    let t2 = Instant::now();
    let case_lumped = run_study(&bench_scene, &lumped_plan, observer)?;
    let case_lumped_s = t2.elapsed().as_secs_f64();
    let case_lumped_peak_rss_mb = peak_rss_mb();
    let sweep_lumped_plan = CasePlan {
        axes: CaseAxes {
            p_masses: vec![PMass::Lumped],
            ..sweep_plan.axes.clone()
        },
        ..sweep_plan.clone()
    };
    let t3 = Instant::now();
    let sweep_lumped = run_study(&bench_scene, &sweep_lumped_plan, observer)?;
    let sweep_lumped_s = t3.elapsed().as_secs_f64();

    observer.phase("lumped p mass: preconditioned CG on S");
    reset_peak_rss();
    let iterative = iterative_route(&bench_scene, &case_lumped)?;

    let first = &case.cases[0];
    let sweep_lumped_phases = sweep_phases(&sweep_lumped, sweep_plan.axes.multipliers.len());
    let sweep_lumped_factorization_s = sweep_lumped_phases.factorization;
    let sweep_phases = sweep_phases(&sweep, sweep_plan.axes.multipliers.len());
    let sweep_factorization_s = sweep_phases.factorization;
    let (worst_kkt, all_converged) = summarize(&[&case, &sweep, &case_lumped, &sweep_lumped]);
    let mut report = BenchReport {
        scene: scene.name.clone(),
        vertices: n_vertices,
        cells,
        yardstick_unknowns,
        case_unknowns: first.unknowns,
        multipliers: first.multipliers,
        bare_cholesky_s: yardstick.symbolic_s + yardstick.numeric_s + yardstick.solve_s,
        yardstick,
        case_s,
        case_phases: first.timings,
        numeric_factor_s: first.timings.factorization,
        sweep_s,
        sweep_deltas: SWEEP_DELTAS.to_vec(),
        sweep_cases: sweep.cases.len(),
        sweep_factorization_s,
        sweep_phases,
        worst_kkt,
        all_converged,
        case_lumped_s,
        case_lumped_phases: case_lumped.cases[0].timings,
        case_lumped_peak_rss_mb,
        sweep_lumped_s,
        sweep_lumped_factorization_s,
        sweep_lumped_phases,
        goals: Vec::new(),
        yardstick_peak_rss_mb,
        case_peak_rss_mb,
        sweep_peak_rss_mb,
        peak_rss_mb: yardstick_peak_rss_mb
            .max(case_peak_rss_mb)
            .max(sweep_peak_rss_mb)
            .max(case_lumped_peak_rss_mb),
        peak_reset_supported,
        threads: rayon::current_num_threads(),
        iterative,
    };
    report.goals = lumped_goals(&report);
    Ok(report)
}

/// Measures [`IterativeRoute`] on the mesh of `lumped`'s case (broken u, δ = 0), and the distance of
/// its u from the direct route's u (that case's fields are not kept; the direct u comes from
/// one LDLᵀ solve of the same system here, after the route's peak memory is read).
fn iterative_route(scene: &Scene, lumped: &StudyResult) -> Result<IterativeRoute, BenchError> {
    let mesh = scene.mesh_source()?.level(0)?;
    let topo = mesh.u_topology(USpace::Broken);
    let t0 = Instant::now();
    let problem = scene.scalar().ok_or(StudyError::NotScalar)?;
    let system = krylov::continuous_p_system(&mesh, &topo, problem, PMass::Lumped)
        .map_err(StudyError::from)?;
    let system_assembly_s = t0.elapsed().as_secs_f64();
    let solve = krylov::solve_u(&mesh, &topo, &system, 0.0, krylov::ROUTE_TOLERANCE)?;
    let peak_rss_mb = peak_rss_mb();
    let trace_rows = CrackOperators::new(&mesh).rows.len();
    let solves_per_case = trace_rows + 2;
    let assembly = lumped.cases.first().map_or(0.0, |c| c.timings.assembly);
    let case_lower_bound_s = assembly
        + solve.preconditioner_assembly_s
        + solve.preconditioner.symbolic_s
        + solve.preconditioner.numeric_s
        + solves_per_case as f64 * solve.solve_s;
    let distance_to_direct = krylov::distance_to_direct(&system, 0.0, &solve.u)?;
    Ok(IterativeRoute {
        system_assembly_s,
        preconditioner_assembly_s: solve.preconditioner_assembly_s,
        preconditioner: solve.preconditioner,
        solve_s: solve.solve_s,
        iterations: solve.report.iterations,
        tolerance: krylov::ROUTE_TOLERANCE,
        relative_residual: solve.report.relative_residual,
        distance_to_direct,
        solves_per_case,
        case_lower_bound_s,
        peak_rss_mb,
    })
}

/// The sweep's phases: mesh-level ones once, δ-level ones once per δ, the rest summed over cases.
fn sweep_phases(sweep: &StudyResult, multipliers: usize) -> Timings {
    let mut t = Timings::default();
    if let Some(first) = sweep.cases.first() {
        t.assembly = first.timings.assembly;
        t.symbolic = first.timings.symbolic;
    }
    for c in sweep.cases.iter().step_by(multipliers.max(1)) {
        t.factorization += c.timings.factorization;
        t.crack_reduction += c.timings.crack_reduction;
        t.condition += c.timings.condition;
    }
    for c in &sweep.cases {
        t.contact += c.timings.contact;
        t.norms += c.timings.norms;
        t.fields += c.timings.fields;
    }
    t
}

/// Worst KKT residual and whether every case converged.
fn summarize(results: &[&StudyResult]) -> (f64, bool) {
    let cases = results.iter().flat_map(|r| &r.cases);
    cases.fold((0.0f64, true), |(worst, ok), c| {
        (worst.max(c.kkt.max()), ok && c.converged)
    })
}

/// The yardstick: mesh, P1 stiffness on the interior vertices, Cholesky solve of A x = 1.
/// Returns the timings, the number of unknowns and the number of mesh vertices.
fn yardstick(scene: &Scene) -> Result<(CholeskyTimings, usize, usize), BenchError> {
    let mesh = scene.mesh_source()?.level(0)?;
    let a = interior_laplacian(&mesh);
    let mut x = vec![1.0; a.n];
    let timings = cholesky_solve(&a, &mut x)?;
    Ok((timings, a.n, mesh.vertices.len()))
}

/// The P1 stiffness matrix of the uncut mesh restricted to its interior vertices
/// (homogeneous Dirichlet conditions eliminated), lower triangle.
pub fn interior_laplacian(mesh: &Mesh) -> SymCsc {
    let mut on_boundary = vec![false; mesh.vertices.len()];
    for e in &mesh.boundary_edges {
        on_boundary[e[0]] = true;
        on_boundary[e[1]] = true;
    }
    let mut index = vec![usize::MAX; mesh.vertices.len()];
    let mut n = 0;
    for (v, slot) in index.iter_mut().enumerate() {
        if !on_boundary[v] {
            *slot = n;
            n += 1;
        }
    }
    let mut triplets = Vec::with_capacity(6 * mesh.triangles.len());
    for t in &mesh.triangles {
        let k = TriangleGeometry::new(t.map(|v| mesh.vertices[v])).stiffness();
        for a in 0..3 {
            for b in 0..=a {
                let (r, c) = (index[t[a]], index[t[b]]);
                if r != usize::MAX && c != usize::MAX {
                    triplets.push((r, c, k[a][b]));
                }
            }
        }
    }
    // Indices are in range and stiffness entries finite by construction.
    SymCsc::from_triplets(n, &triplets).unwrap_or_else(|e| unreachable!("{e}"))
}

/// Resets the kernel's peak-RSS counter of this process; false where not supported.
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Peak resident set size of this process in MB (`VmHWM`), 0 where unknown.
pub fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sdcrack_core::study::Silent;
    use sdcrack_io::scene_file::TomlScene;

    /// A missed goal says by how much and lists its phases, largest first; a met one says "met".
    #[test]
    fn goal_lines_say_how_much_and_where_a_goal_is_missed() {
        let phases = vec![("contact".to_string(), 0.5), ("factor".to_string(), 4.0)];
        let missed = GoalCheck::new("case / yardstick", 3.0, 4.5, phases.clone());
        assert!(!missed.met);
        assert_eq!(missed.missed_by, 1.5);
        assert_eq!(missed.phases[0].0, "factor");
        let met = GoalCheck::new("sweep / factorisations", 1.3, 1.2, phases);
        assert!(met.met);
        let text = goal_lines(&[missed, met]);
        assert!(text.contains("≤ 3.0: 4.50  MISSED by 1.50 ×"), "{text}");
        assert!(
            text.contains("by phase (same unit): factor 4.00, contact 0.50"),
            "{text}"
        );
        assert!(text.contains("≤ 1.3: 1.20  met"), "{text}");
        assert_eq!(text.matches("by phase").count(), 1, "{text}");
    }

    #[test]
    fn cells_are_multiples_of_the_scene_cells_near_the_target() {
        let scene = Scene::default_scene();
        assert_eq!(bench_cells(&scene, 1_000_000).unwrap(), [1000, 1000]);
        assert_eq!(bench_cells(&scene, 100_000).unwrap(), [312, 312]); // 313² = 97 969
        assert_eq!(bench_cells(&scene, 10).unwrap(), [8, 8]);
    }

    #[test]
    fn laplacian_rows_sum_to_zero_away_from_the_boundary() {
        let scene = Scene::default_scene();
        let mesh = sdcrack_core::mesh::MeshSource::new(
            &scene.domain,
            &scene.cracks,
            &Meshing::Cells([4, 4]),
        )
        .unwrap()
        .level(0)
        .unwrap();
        let a = interior_laplacian(&mesh);
        assert_eq!(a.n, 9);
        let mut y = vec![0.0; 9];
        a.mul_vec(&[1.0; 9], &mut y);
        // the centre vertex (index 4) has no boundary neighbour: its row sums to zero
        assert!(y[4].abs() < 1e-14, "{y:?}");
        assert!(y.iter().enumerate().all(|(i, v)| i == 4 || *v > 0.0));
    }

    #[test]
    fn small_bench_runs_every_phase() {
        let scene = Scene::default_scene();
        let report = run_bench(&scene, 300, &mut Silent).unwrap();
        assert_eq!(report.cells, [16, 16]);
        assert_eq!(report.vertices, 17 * 17);
        assert_eq!(report.sweep_cases, 18);
        assert!(report.all_converged && report.worst_kkt <= 1e-10);
        assert!(report.bare_cholesky_s > 0.0 && report.case_s > 0.0 && report.sweep_s > 0.0);
        let json = serde_json::to_value(&report).unwrap();
        for key in [
            "vertices",
            "bare_cholesky_s",
            "case_s",
            "sweep_s",
            "sweep_deltas",
            "numeric_factor_s",
            "peak_rss_mb",
        ] {
            assert!(json.get(key).is_some(), "{key}");
        }
        assert!(report.table().contains("yardstick"));
        // the iterative route: its u is the direct route's, and the direct route is kept (a case
        // by PCG needs a solve per row of N, one per crack node here (9, as many as M1 has
        // multipliers), plus x₀ and the recovery)
        let it = &report.iterative;
        assert!(it.distance_to_direct <= 1e-10, "{}", it.distance_to_direct);
        assert_eq!(report.multipliers, 9);
        assert_eq!(it.solves_per_case, 9 + 2);
        assert!(it.iterations > 0 && it.solve_s > 0.0);
        assert!(
            report.table().contains("route kept: direct"),
            "{}",
            report.table()
        );
    }
}
