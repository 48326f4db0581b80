//! The command line (clap), progress display (indicatif) and the terminal convergence table.
//!
//! Exit codes: 0 success; 1 a run-time failure (solver, writing results once solved, a reference
//! solver that fails); 2 bad usage or bad input (arguments, scene file, crack off the mesh,
//! non-finite data, a level over the memory limit, an `--out` that cannot be created or already
//! holds the results folder, a reference solver that is not installed); 3 the run finished and
//! wrote its results but at least one case (of the solver or of a reference) did not converge.
//! Every error is one line on stderr, `sdcrack: error: …` (clap's usage errors included: their
//! usage block is left out); `sdcrack` alone prints the help and exits 2.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use sdcrack_core::afw::AfwError;
use sdcrack_core::case::{delta_text, CaseKey, CasePattern, Pattern};
use sdcrack_core::problem::Named;
use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};
use sdcrack_core::scene::{KeyPath, ProblemKind, Scene};
use sdcrack_core::study::elastic::{run_elastic_study, ElasticCaseResult};
use sdcrack_core::study::{run_study, CasePlan, CaseResult, Observer, StudyError};
use sdcrack_io::output::summary::Provenance;
use sdcrack_io::output::{write_run, ResultsDir};
use sdcrack_io::scene_file::{LoadedScene, SceneError};

/// `println!` that survives a closed standard output: `sdcrack bench --json | head` must not
/// panic, and a run whose reader went away must still finish and keep its results. A closed
/// pipe (EPIPE) silences the rest of the output; any other write error is reported once on
/// stderr.
macro_rules! say {
    ($($arg:tt)*) => {
        say_raw(&format!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes `text` to standard output (see [`say!`]).
fn say_raw(text: &str) {
    use std::io::Write;
    use std::sync::atomic::{AtomicBool, Ordering};
    static CLOSED: AtomicBool = AtomicBool::new(false);
    if CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        CLOSED.store(true, Ordering::Relaxed);
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("sdcrack: warning: cannot write to standard output: {e}");
        }
    }
}

/// sdcrack: smooth-domain finite elements for cracks with unilateral contact.
#[derive(Parser, Debug)]
#[command(name = "sdcrack", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The options of `run` that restrict the study to some cases: one [`Pattern<CaseKey>`](Pattern).
#[derive(Args, Debug)]
pub struct CaseSelection {
    /// Only this refinement level (need not be listed in the scene).
    #[arg(long, value_parser = parse_level, allow_hyphen_values = true)]
    pub level: Option<u32>,
    /// Only this u space: continuous or broken.
    #[arg(long, value_parser = parse_u_space, value_name = "continuous|broken")]
    pub u_space: Option<USpace>,
    /// Only this multiplier space: M0, M1 or M1star.
    #[arg(long, value_parser = parse_multiplier, value_name = "M0|M1|M1star")]
    pub multiplier: Option<MultiplierSpace>,
    /// Only this p mass: consistent (the paper's) or lumped (p eliminated; need not be
    /// listed in the scene).
    #[arg(long, value_parser = parse_p_mass, value_name = "consistent|lumped")]
    pub p_mass: Option<PMass>,
    /// Only this p space: continuous (the paper's) or broken-tangential (p·τ one value per
    /// crack face; broken u only; need not be listed in the scene).
    #[arg(long, value_parser = parse_p_space, value_name = "continuous|broken-tangential")]
    pub p_space: Option<PSpace>,
    /// Only this δ (≥ 0).
    #[arg(long, value_parser = parse_delta, allow_hyphen_values = true)]
    pub delta: Option<f64>,
}

impl CaseSelection {
    /// The study's filter: each option given replaces the scene's list by its one value.
    // the struct update is for axes without an option here (none today)
    #[allow(clippy::needless_update)]
    pub fn filter(&self) -> CasePattern {
        CasePattern {
            level: self.level,
            u_space: self.u_space,
            multiplier: self.multiplier,
            p_mass: self.p_mass,
            p_space: self.p_space,
            delta: self.delta,
            // an axis with no option here runs every value the scene lists
            ..CasePattern::default()
        }
    }
}

/// Sub-commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Solve every case of a scene (default: the embedded `mixed` scene) and write results.
    Run {
        /// Scene file (TOML); omit for the embedded default scene.
        scene: Option<PathBuf>,
        /// Folder under which the results folder `<scene name>/` is created.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[command(flatten)]
        cases: CaseSelection,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Solve only: no mesh export and no reference run (a shard of a campaign, whose
        /// references run as `sdcrack reference`; see `sdcrack merge`).
        #[arg(long)]
        solver_only: bool,
    },
    /// Run one reference solver on one level of a scene: a shard of a campaign (see `merge`).
    /// Writes `OUT/<scene name>/` with scene.toml, mesh/ (the level's export) and `<tool>/`.
    Reference {
        /// Scene file (TOML); omit for the embedded default scene.
        scene: Option<PathBuf>,
        /// The reference tool, one of the scene's `[outputs] references`.
        #[arg(long, value_name = "dolfinx|freefem")]
        tool: String,
        /// The level to solve (need not be listed in the scene).
        #[arg(long, value_parser = parse_level, allow_hyphen_values = true)]
        level: u32,
        /// Folder under which the results folder `<scene name>/` is created.
        #[arg(long, default_value = "results")]
        out: PathBuf,
    },
    /// Merge shards (results folders of `run --solver-only` with filters and of `reference`) of
    /// one scene into `OUT/<scene name>/`, the folder a single `sdcrack run` of the scene writes:
    /// same files, same numbers, fields bit for bit; every case of the scene exactly once.
    Merge {
        /// The shards: `<scene name>/` folders written by `run` and `reference`.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Folder under which the merged results folder `<scene name>/` is created.
        #[arg(long, default_value = "results")]
        out: PathBuf,
    },
    /// Export the meshes of a scene's levels for the reference solvers (see docs/design.md).
    Mesh {
        /// Scene file (TOML); omit for the embedded default scene.
        scene: Option<PathBuf>,
        /// Folder to create (must not exist).
        #[arg(long)]
        out: PathBuf,
        /// Only this level.
        #[arg(long, value_parser = parse_level, allow_hyphen_values = true)]
        level: Option<u32>,
    },
    /// Time one case and a δ × multiplier sweep against a sparse Cholesky of the same mesh.
    Bench {
        /// Scene whose domain, crack and data are used (default: the embedded `mixed` scene).
        scene: Option<PathBuf>,
        /// Approximate number of mesh vertices (the scene's cells are scaled by an integer).
        #[arg(long, default_value_t = 1_000_000, value_parser = parse_vertices)]
        vertices: usize,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Print a commented scene template (every table and key with its type and default):
    /// `--template` the scalar problem's, `--template elasticity` the elastic problem's.
    Scene {
        /// Print the template of this problem kind (the only action so far).
        #[arg(
            long,
            required = true,
            num_args = 0..=1,
            default_missing_value = "scalar",
            value_parser = parse_problem_kind,
            value_name = "scalar|elasticity"
        )]
        template: Option<ProblemKind>,
    },
    /// Print the scene schema as JSON: every table with its keys, each key's type, its words
    /// and allowed names, and the names shared with the compare tool (quantities, checks a
    /// scene may declare not applicable, references). Read off the loader's own structs.
    Schema,
    /// Validate a scene file (and its crack on every level's mesh) without solving.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Print the scene's plan as one JSON object (name, cases, levels, u_spaces,
        /// multipliers, p_masses, deltas, an elastic scene's problem and problems, references,
        /// fields, memory_mb per level: sdcrack's
        /// peak-memory estimate in MiB, and mesh_memory_mb: its part that grows with the mesh),
        /// for workflow engines.
        #[arg(long)]
        json: bool,
    },
}

fn parse_level(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(l) if l <= sdcrack_core::scene::MAX_LEVEL => Ok(l),
        _ => Err(format!(
            "the level must be an integer from 0 to {}, got '{s}'",
            sdcrack_core::scene::MAX_LEVEL
        )),
    }
}

/// `s` as one of the names a space's `from_name` knows, or a message naming `what` and `names`.
/// A name of the vocabulary `T`, or an error listing them.
fn parse_name<T: Named>(s: &str, what: &str) -> Result<T, String> {
    T::from_name(s).ok_or_else(|| format!("unknown {what} '{s}' (expected {})", or_list(T::NAMES)))
}

/// "a or b", "a, b or c": names in a sentence.
fn or_list(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => one.to_string(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

fn parse_problem_kind(s: &str) -> Result<ProblemKind, String> {
    parse_name(s, "problem kind")
}

fn parse_u_space(s: &str) -> Result<USpace, String> {
    parse_name(s, "u space")
}

fn parse_p_mass(s: &str) -> Result<PMass, String> {
    parse_name(s, "p mass")
}

fn parse_p_space(s: &str) -> Result<PSpace, String> {
    parse_name(s, "p space")
}

fn parse_multiplier(s: &str) -> Result<MultiplierSpace, String> {
    parse_name(s, "multiplier space")
}

/// Vertex counts accepted by `bench` (the upper bound keeps one case within ~60 GB).
const BENCH_VERTICES: std::ops::RangeInclusive<usize> = 100..=8_000_000;

fn parse_vertices(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(v) if BENCH_VERTICES.contains(&v) => Ok(v),
        _ => Err(format!(
            "--vertices must be an integer from {} to {}, got '{s}'",
            BENCH_VERTICES.start(),
            BENCH_VERTICES.end()
        )),
    }
}

fn parse_delta(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(d) if d.is_finite() && d >= 0.0 => Ok(d),
        _ => Err(format!("δ must be a finite number ≥ 0, got '{s}'")),
    }
}

/// A failure with its exit code.
#[derive(Debug)]
pub struct Failure {
    /// Process exit code.
    pub code: i32,
    /// One-line message.
    pub message: String,
}

fn usage(e: impl std::fmt::Display) -> Failure {
    Failure {
        code: 2,
        message: e.to_string(),
    }
}

fn runtime(e: impl std::fmt::Display) -> Failure {
    Failure {
        code: 1,
        message: e.to_string(),
    }
}

/// Parses `std::env::args`, runs, prints errors as one line, returns the exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if !e.use_stderr() {
                // --help, --version: clap's own text on stdout, success.
                let _ = e.print();
                return 0;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                // `sdcrack` alone: the help, as a reminder of the sub-commands.
                let _ = e.print();
                return 2;
            }
            eprintln!("sdcrack: {}", clap_one_line(&e));
            return 2;
        }
    };
    match execute(cli) {
        Ok(code) => code,
        Err(f) => {
            eprintln!(
                "sdcrack: error: {}",
                sdcrack_io::one_line::escape_controls(&f.message)
            );
            f.code
        }
    }
}

/// A clap usage error as one line: its `error:` line and its tips, without the usage block.
fn clap_one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut parts: Vec<String> = Vec::new();
    for line in text.lines() {
        let trimmed = line.trim();
        if trimmed.starts_with("error:") || trimmed.starts_with("tip:") {
            parts.push(trimmed.to_string());
        } else if line.starts_with(char::is_whitespace) && !trimmed.is_empty() {
            // The indented list under "required arguments were not provided:".
            if let Some(last) = parts.last_mut() {
                last.push(' ');
                last.push_str(trimmed);
            }
        } else if trimmed.starts_with("Usage:") {
            break;
        }
    }
    if parts.is_empty() {
        parts.push(format!("error: {}", e.kind()));
    }
    let line = sdcrack_io::one_line::escape_controls(&parts.join("; "));
    format!("{line} (see sdcrack --help)")
}

/// Runs a parsed command; `Ok(code)` is 0, or 3 when some case did not converge.
pub fn execute(cli: Cli) -> Result<i32, Failure> {
    match cli.command {
        Command::Scene { template } => {
            say_raw(match template.unwrap_or_default() {
                ProblemKind::Scalar => sdcrack_io::scene_file::SCENE_TEMPLATE,
                ProblemKind::Elasticity => sdcrack_io::scene_file::ELASTIC_SCENE_TEMPLATE,
            });
            Ok(0)
        }
        Command::Schema => {
            say!("{}", sdcrack_io::scene_file::schema::schema().to_json());
            Ok(0)
        }
        Command::Check { scene, json } => {
            let loaded = LoadedScene::from_file(&scene).map_err(usage)?;
            let s = &loaded.scene;
            let origin = scene.display().to_string();
            let meshes = check_meshes(&loaded, &origin)?;
            // the exact data against what the scene implies (∂u, −Δu, u on ∂Ω, the faces, the
            // contact conditions): a scene whose exact solution is not one is refused, no solve
            sdcrack_core::scene::exact_data::check(s).map_err(|e| {
                invalid_scene(&loaded, &origin, SceneError::named(e.key, e.message))
            })?;
            if json {
                let max_level = s.axes.levels.iter().copied().max().unwrap_or(0);
                let triangles = (meshes.triangle_counts(max_level))
                    .map_err(|e| mesh_failure(&loaded, &origin, e))?;
                say!("{}", plan_json(s, &triangles));
                return Ok(0);
            }
            match s.problem.kind() {
                ProblemKind::Scalar => say!(
                    "{}: valid scene '{}' ({} cases)",
                    scene.display(),
                    s.name,
                    s.axes.case_count()
                ),
                ProblemKind::Elasticity if s.axes.case_count() == 0 => say!(
                    "{}: valid elastic scene '{}' (levels {:?}, references {:?}; no solver case: [discretization] lists no multipliers and deltas)",
                    scene.display(),
                    s.name,
                    s.axes.levels,
                    s.references
                ),
                ProblemKind::Elasticity => say!(
                    "{}: valid elastic scene '{}' ({} cases: levels {:?} × multipliers {:?} × δ {:?}; references {:?})",
                    scene.display(),
                    s.name,
                    s.axes.case_count(),
                    s.axes.levels,
                    (s.axes.multipliers.iter()).map(|m| m.name()).collect::<Vec<_>>(),
                    s.axes.deltas,
                    s.references
                ),
            }
            if !s.has_exact() && s.references.is_empty() {
                eprintln!(
                    "sdcrack: warning: scene '{}' has no [exact] and no references: there is nothing to judge its errors against, so the compare tool can only call it INCONCLUSIVE (add [exact] or [outputs] references)",
                    s.name
                );
            }
            if let Some(line) = too_few_levels(&s.name, &s.axes.levels) {
                eprintln!("sdcrack: warning: {line}");
            }
            Ok(0)
        }
        Command::Bench {
            scene,
            vertices,
            json,
        } => {
            let (loaded, _) = load_checked(scene)?;
            if loaded.scene.scalar().is_none() {
                return Err(usage(format!(
                    "scene '{}' is elastic: {}",
                    loaded.scene.name,
                    StudyError::NotScalar
                )));
            }
            bench(&loaded.scene, vertices, json)
        }
        Command::Mesh { scene, out, level } => {
            let (loaded, _) = load_checked(scene)?;
            let scene = &loaded.scene;
            check_level_option(scene, level)?;
            let levels = level.map_or_else(|| scene.axes.levels.clone(), |l| vec![l]);
            let path = sdcrack_io::output::mesh_export::export_meshes(scene, &levels, &out)
                .map_err(usage)?;
            say!("meshes of levels {levels:?} written to {}", path.display());
            Ok(0)
        }
        Command::Run {
            scene,
            out,
            cases,
            quiet,
            solver_only,
        } => {
            let (loaded, origin) = load_checked(scene)?;
            let filter = cases.filter();
            check_level_option(&loaded.scene, filter.level)?;
            match loaded.scene.problem.kind() {
                ProblemKind::Scalar => check_space_pairs(&loaded.scene, &filter)?,
                ProblemKind::Elasticity => check_elastic_options(&loaded.scene, &cases)?,
            }
            run(&loaded, &origin, &filter, &out, quiet, solver_only)
        }
        Command::Reference {
            scene,
            tool,
            level,
            out,
        } => {
            let (loaded, _) = load_checked(scene)?;
            check_level_option(&loaded.scene, Some(level))?;
            reference(&loaded, &tool, level, &out)
        }
        Command::Merge { shards, out } => merge(&shards, &out),
    }
}

/// How many levels the compare tool's convergence rule needs to judge a series: two observed
/// rates (scenes/orders.toml `[rule] levels`; tests/orders_table.rs holds the two equal).
pub const RATE_LEVELS: usize = 3;

/// The warning of `sdcrack check` for a scene whose levels cannot give a rate verdict (fewer than
/// [`RATE_LEVELS`]): the compare tool can only say INCONCLUSIVE of its series. None otherwise.
pub fn too_few_levels(name: &str, levels: &[u32]) -> Option<String> {
    if levels.len() >= RATE_LEVELS {
        return None;
    }
    let first = levels.iter().copied().min().unwrap_or(0);
    let up_to = first as usize + RATE_LEVELS - 1;
    Some(format!(
        "scene '{name}' lists {} level(s) {levels:?}: a rate needs {RATE_LEVELS} levels, so the compare tool can only call its series INCONCLUSIVE (cannot judge yet); list levels {first} to {up_to} at least (or set [verification] smoke = true for a run that only checks that everything runs)",
        levels.len()
    ))
}

/// The JSON object of `sdcrack check --json`; `triangles[ℓ]`: level ℓ's triangle count, from
/// which each level's `memory_mb` (and its part that grows with the mesh, `mesh_memory_mb`) is
/// estimated (a graded level has more than 4^ℓ times level 0's:
/// open-graded's level 5 1.8 times).
fn plan_json(scene: &Scene, triangles: &[usize]) -> String {
    let per_level = |mib: &dyn Fn(f64) -> u64| -> serde_json::Map<String, serde_json::Value> {
        (scene.axes.levels.iter())
            .map(|&l| {
                let cells = triangles[l as usize] as f64 / 2.0;
                (l.to_string(), serde_json::Value::from(mib(cells)))
            })
            .collect()
    };
    let memory = per_level(&|cells| {
        sdcrack_core::scene::estimated_memory_bytes_of_cells(cells).div_ceil(1 << 20)
    });
    // the part of it that grows with the mesh, in whole MiB
    let mesh_memory = per_level(&|cells| {
        (sdcrack_core::scene::estimated_mesh_memory_bytes(cells) / (1u64 << 20) as f64).ceil()
            as u64
    });
    let mut value = serde_json::Map::new();
    value.insert("name".into(), scene.name.clone().into());
    // the problem kind of an elastic scene (absent: the scalar problem, as in summary.json)
    if scene.scalar().is_none() {
        value.insert("problem".into(), scene.problem.kind().name().into());
    }
    value.insert("cases".into(), scene.axes.case_count().into());
    // every axis' list, as summary.json's plan writes them (levels, u_spaces, …, deltas)
    if let Ok(serde_json::Value::Object(axes)) = serde_json::to_value(&scene.axes) {
        value.extend(axes);
    }
    let rest = serde_json::json!({
        "references": scene.references,
        "fields": !scene.fields.is_empty(),
        "memory_mb": memory,
        "mesh_memory_mb": mesh_memory,
    });
    if let serde_json::Value::Object(rest) = rest {
        value.extend(rest);
    }
    serde_json::Value::Object(value).to_string()
}

/// `sdcrack reference`: one tool on one level, into OUT/<scene name>/.
fn reference(loaded: &LoadedScene, tool: &str, level: u32, out: &Path) -> Result<i32, Failure> {
    let scene = &loaded.scene;
    if !scene.references.iter().any(|t| t == tool) {
        return Err(usage(format!(
            "--tool {tool}: the scene '{}' lists the references {:?}",
            scene.name, scene.references
        )));
    }
    crate::references::check_available(tool).map_err(usage)?;
    let results = ResultsDir::create(out, &scene.name).map_err(usage)?;
    let dir = results.work_path();
    let copy = dir.join(sdcrack_io::output::SCENE_COPY);
    sdcrack_io::output::atomic_write(&copy, loaded.text.as_bytes()).map_err(runtime)?;
    let converged = run_references(scene, &[tool.to_string()], &[level], dir, true)?;
    let path = results.commit().map_err(runtime)?;
    say!("results in {}", path.display());
    Ok(convergence_status(0, converged))
}

/// `sdcrack merge`: shards into OUT/<scene name>/.
fn merge(shards: &[PathBuf], out: &Path) -> Result<i32, Failure> {
    let start = std::time::SystemTime::now();
    let outcome = sdcrack_io::output::merge::merge_shards(shards, out, |origin| {
        Provenance::of_this_process(origin, start, crate::BUILD)
    })
    .map_err(|e| {
        if e.is_input_error() {
            usage(e)
        } else {
            runtime(e)
        }
    })?;
    match outcome.scene.problem.kind() {
        ProblemKind::Scalar => say!(
            "{} cases of scene '{}' merged from {} shards; results in {}",
            outcome.cases,
            outcome.scene.name,
            shards.len(),
            outcome.path.display()
        ),
        ProblemKind::Elasticity => say!(
            "{} elastic cases of scene '{}' and its references {:?} merged from {} shards; results in {}",
            outcome.cases,
            outcome.scene.name,
            outcome.scene.references,
            shards.len(),
            outcome.path.display()
        ),
    }
    Ok(convergence_status(
        outcome.not_converged,
        outcome.references_not_converged == 0,
    ))
}

/// Runs `sdcrack bench` and prints its table or JSON object on stdout (progress on stderr).
fn bench(scene: &Scene, vertices: usize, json: bool) -> Result<i32, Failure> {
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::hidden()
    };
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut progress = Progress { bar };
    let report = crate::bench::run_bench(scene, vertices, &mut progress).map_err(runtime)?;
    progress.bar.finish_and_clear();
    if json {
        let text = serde_json::to_string_pretty(&report).map_err(runtime)?;
        say!("{text}");
    } else {
        say_raw(&report.table());
    }
    Ok(if report.all_converged { 0 } else { 3 })
}

/// The scene file `path` (or the embedded default scene) and how messages name it.
fn load(path: Option<PathBuf>) -> Result<(LoadedScene, String), Failure> {
    match path {
        Some(p) => Ok((
            LoadedScene::from_file(&p).map_err(usage)?,
            p.display().to_string(),
        )),
        None => Ok((
            LoadedScene::default_scene(),
            "(embedded default)".to_string(),
        )),
    }
}

/// [`load`], then [`check_meshes`]: a scene the commands that mesh it can run.
fn load_checked(path: Option<PathBuf>) -> Result<(LoadedScene, String), Failure> {
    let (loaded, origin) = load(path)?;
    check_meshes(&loaded, &origin)?;
    Ok((loaded, origin))
}

/// Checks the crack against the level-0 mesh (the same check every level makes).
fn check_meshes(
    loaded: &LoadedScene,
    origin: &str,
) -> Result<sdcrack_core::mesh::MeshSource, Failure> {
    (loaded.scene.mesh_source()).map_err(|e| mesh_failure(loaded, origin, e))
}

/// A mesh error of the scene `origin`, naming the crack it concerns.
fn mesh_failure(loaded: &LoadedScene, origin: &str, e: sdcrack_core::mesh::MeshError) -> Failure {
    invalid_scene(loaded, origin, loaded.mesh_error(&e))
}

/// A usage failure found after the scene file was read (a crack off a finer mesh, NaN data):
/// `invalid scene ORIGIN: MESSAGE (at line L, column C)`, with the line and column of the key
/// the error is about.
fn invalid_scene(loaded: &LoadedScene, origin: &str, error: SceneError) -> Failure {
    usage(SceneError::InFile {
        path: origin.to_string(),
        error: Box::new(loaded.locate(error)),
    })
}

/// A study error that is the scene's fault, at its key: non-finite data (`data.f`) at a
/// quadrature point, or a crack off a finer mesh (named by the mesh's words).
fn study_scene_error(e: &StudyError) -> SceneError {
    match e {
        StudyError::Assembly(sdcrack_core::assembly::AssemblyError::NonFinite { name, .. }) => {
            SceneError::named(KeyPath::keys("data").key(name), e.to_string())
        }
        _ => SceneError::Scene(e.to_string()),
    }
}

/// Checks a `--level` (which need not be listed in the scene) like the scene's own levels:
/// at most [`sdcrack_core::scene::MAX_LEVEL`] and within the memory estimate.
/// Refuses a run whose u spaces and p spaces make no case: the broken-tangential p only runs
/// with broken u ([`PSpace::serves`]).
fn check_space_pairs(scene: &Scene, filter: &Pattern<CaseKey>) -> Result<(), Failure> {
    let axes = filter.restrict(&scene.axes);
    if !axes.space_pairs().is_empty() {
        return Ok(());
    }
    let u: Vec<&str> = axes.u_spaces.iter().map(|u| u.name()).collect();
    Err(usage(format!(
        "the broken-tangential p needs broken u, and this run's u spaces are {}: a continuous u cannot open the crack (pass --u-space broken, or --p-space continuous)",
        u.join(", ")
    )))
}

/// Refuses, for an elastic scene, the options of the scalar problem's own axes (u space, p mass,
/// p space: the AFW method has none), a `--multiplier` the elastic solver does not have
/// ([`sdcrack_core::afw::MULTIPLIER_SPACES`]), and `--multiplier` or `--delta` for a scene that
/// lists no solver case (no `multipliers` and `deltas`: its references only).
fn check_elastic_options(scene: &Scene, cases: &CaseSelection) -> Result<(), Failure> {
    let scalar_only = [
        ("--u-space", cases.u_space.is_some()),
        ("--p-mass", cases.p_mass.is_some()),
        ("--p-space", cases.p_space.is_some()),
    ];
    if let Some((option, _)) = scalar_only.iter().find(|(_, is)| *is) {
        return Err(usage(format!(
            "{option} selects a case of the scalar problem's solver, and scene '{}' is elastic: its cases are levels × multipliers × δ (--level, --multiplier, --delta)",
            scene.name
        )));
    }
    let solved = sdcrack_core::afw::MULTIPLIER_SPACES;
    if let Some(m) = cases.multiplier.filter(|m| !solved.contains(m)) {
        let names: Vec<&str> = solved.iter().map(|m| m.name()).collect();
        return Err(usage(format!(
            "--multiplier {m}: the elastic solver has no multiplier space {m} yet (it has {})",
            or_list(&names)
        )));
    }
    let selects = cases.multiplier.is_some() || cases.delta.is_some();
    if selects && scene.axes.case_count() == 0 {
        return Err(usage(format!(
            "--multiplier and --delta select solver cases, and the elastic scene '{}' lists none ([discretization] has no multipliers and deltas: its references only)",
            scene.name
        )));
    }
    Ok(())
}

fn check_level_option(scene: &Scene, level: Option<u32>) -> Result<(), Failure> {
    match level {
        Some(l) => sdcrack_core::scene::check_level(scene.level0, l)
            .map_err(|m| usage(format!("--level {l}: {m}"))),
        None => Ok(()),
    }
}

struct Progress {
    bar: ProgressBar,
}

impl Observer for Progress {
    fn phase(&mut self, message: &str) {
        self.bar.set_message(message.to_string());
    }
    fn case_done(&mut self, case: &CaseResult) {
        if !case.converged {
            self.bar.println(format!(
                "warning: level {} {} {} δ = {} did not converge ({})",
                case.key.level,
                case.key.u_space,
                case.key.multiplier,
                delta_text(case.key.delta),
                case.status.name()
            ));
        }
        self.bar.inc(1);
    }
    fn elastic_case_done(&mut self, case: &ElasticCaseResult) {
        if !case.converged {
            self.bar.println(format!(
                "warning: level {} elasticity {} δ = {} did not converge ({}; KKT residual {:.1e})",
                case.key.level,
                case.key.multiplier,
                delta_text(case.key.delta),
                case.status.name(),
                case.kkt.max()
            ));
        }
        self.bar.inc(1);
    }
}

fn run(
    loaded: &LoadedScene,
    origin: &str,
    filter: &Pattern<CaseKey>,
    out: &Path,
    quiet: bool,
    solver_only: bool,
) -> Result<i32, Failure> {
    let scene = &loaded.scene;
    let references: &[String] = if solver_only { &[] } else { &scene.references };
    for tool in references {
        crate::references::check_available(tool).map_err(usage)?;
    }
    let plan = CasePlan::new(scene, filter);
    let results = ResultsDir::create(out, &scene.name).map_err(usage)?;
    let provenance =
        Provenance::of_this_process(origin, std::time::SystemTime::now(), crate::BUILD);
    let start = Instant::now();
    let bar = if quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(plan.len() as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} cases [{elapsed_precise}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut progress = Progress { bar };
    let study = match scene.problem.kind() {
        ProblemKind::Scalar => run_study(scene, &plan, &mut progress),
        ProblemKind::Elasticity => run_elastic_study(scene, &plan, &mut progress),
    }
    .map_err(|e| match e {
        StudyError::Linalg(_) | StudyError::Afw(AfwError::Linalg(_)) => runtime(e),
        // Non-finite data at a quadrature point, a crack off a finer mesh: the scene's fault.
        _ => invalid_scene(loaded, origin, study_scene_error(&e)),
    })?;
    progress.bar.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    write_run(
        results.work_path(),
        loaded,
        &plan,
        &study,
        wall,
        &provenance,
    )
    .map_err(runtime)?;
    let references_converged = run_references(
        scene,
        references,
        &plan.axes.levels,
        results.work_path(),
        quiet,
    )?;
    let path = results.commit().map_err(runtime)?;
    print_table(scene, &study.cases);
    print_elastic_table(scene, &study.elastic);
    let failed = study.cases.iter().filter(|c| !c.converged).count()
        + study.elastic.iter().filter(|c| !c.converged).count();
    // the whole command's time, and the solve's (summary.json's wall_s) beside it: the fields
    // and the references may take most of it
    match scene.problem.kind() {
        ProblemKind::Scalar => say!(
            "{} cases in {:.1} s (solving {:.1} s); results in {}",
            study.cases.len(),
            start.elapsed().as_secs_f64(),
            wall,
            path.display()
        ),
        ProblemKind::Elasticity => say!(
            "elastic scene '{}': {} cases in {:.1} s (solving {:.1} s), references {references:?} on levels {:?}; results in {}",
            scene.name,
            study.elastic.len(),
            start.elapsed().as_secs_f64(),
            wall,
            plan.axes.levels,
            path.display()
        ),
    }
    Ok(convergence_status(failed, references_converged))
}

/// The errors of an elastic case that its terminal table shows (summary.json has them all):
/// what users compare, σ symmetrised, u_h, u*, the opening and the contact pressure.
const ELASTIC_TABLE_ERRORS: [&str; 5] = [
    "stress_sym_l2",
    "u_l2",
    "u_star_l2",
    "opening_l2",
    "pressure_l2",
];

/// Prints, per multiplier space and δ, the elastic cases' convergence table: each level's size,
/// unknowns, LCP iterations, closed crack edge ends (of all ends), the errors of
/// [`ELASTIC_TABLE_ERRORS`] with the rate of each against the previous level, and the largest
/// KKT residual.
pub fn print_elastic_table(scene: &Scene, cases: &[ElasticCaseResult]) {
    let error = |c: &ElasticCaseResult, name: &str| -> Option<f64> {
        Some(c.errors.as_ref()?.iter().find(|(n, _)| n == name)?.1)
    };
    let mut series: Vec<(MultiplierSpace, u64)> = cases
        .iter()
        .map(|c| (c.key.multiplier, c.key.delta.to_bits()))
        .collect();
    series.dedup();
    for (multiplier, delta_bits) in series {
        let delta = f64::from_bits(delta_bits);
        say!(
            "scene '{}': elasticity, {multiplier}, δ = {}",
            scene.name,
            delta_text(delta)
        );
        let rows: Vec<&ElasticCaseResult> = (cases.iter())
            .filter(|c| c.key.multiplier == multiplier && c.key.delta.to_bits() == delta_bits)
            .collect();
        let names: Vec<&str> = (ELASTIC_TABLE_ERRORS.into_iter())
            .filter(|n| rows.first().is_some_and(|c| error(c, n).is_some()))
            .collect();
        let head: String = names.iter().map(|n| format!(" {n:>13}  rate")).collect();
        say!("level        h  unknowns  iter  closed{head}     kkt");
        let mut prev: Option<&ElasticCaseResult> = None;
        for c in rows {
            let flag = if c.converged { "" } else { "  NOT CONVERGED" };
            let errors: String = (names.iter())
                .filter_map(|name| {
                    let e = error(c, name)?;
                    let before = prev.and_then(|p| Some((p.h, error(p, name)?)));
                    Some(format!(" {e:13.3e} {}", rate(before, c.h, e)))
                })
                .collect();
            say!(
                "{:5} {:8.5} {:9} {:5} {:>7}{errors} {:7.1e}{flag}",
                c.key.level,
                c.h,
                c.unknowns,
                c.iterations,
                format!("{}/{}", c.closed_ends, 2 * c.crack_edges),
                c.kkt.max()
            );
            prev = Some(c);
        }
        say!("");
    }
}

/// The exit code of a command that wrote its results: 0, or 3 (with a line on stderr for each
/// kind) when `failed` solver cases or some reference case did not converge.
fn convergence_status(failed: usize, references_converged: bool) -> i32 {
    if failed > 0 {
        eprintln!("sdcrack: {failed} case(s) did not converge; see summary.json");
    }
    if !references_converged {
        eprintln!("sdcrack: some reference case did not converge; see <tool>/summary.json");
    }
    if failed > 0 || !references_converged {
        3
    } else {
        0
    }
}

/// Exports the meshes of `levels` into `dir/mesh/` and runs each of `tools` on them, into
/// `dir/<tool>/`; returns false when some reference case did not converge (its results are kept).
fn run_references(
    scene: &Scene,
    tools: &[String],
    levels: &[u32],
    dir: &Path,
    quiet: bool,
) -> Result<bool, Failure> {
    if tools.is_empty() {
        return Ok(true);
    }
    let mut all_converged = true;
    let mesh_dir = dir.join("mesh");
    sdcrack_io::output::mesh_export::export_meshes(scene, levels, &mesh_dir).map_err(runtime)?;
    for tool in tools {
        let spinner = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            ProgressBar::new_spinner()
        };
        spinner.set_message(format!("reference {tool}: levels {levels:?}"));
        spinner.enable_steady_tick(std::time::Duration::from_millis(200));
        let run = crate::references::run_reference(
            tool,
            &mesh_dir,
            &dir.join(tool),
            !scene.fields.is_empty(),
        )
        .map_err(runtime)?;
        spinner.finish_and_clear();
        say!("reference {tool}: {:.1} s", run.seconds);
        all_converged &= run.all_converged;
    }
    Ok(all_converged)
}

/// log2 rate between two (h, e) pairs.
fn rate(prev: Option<(f64, f64)>, h: f64, e: f64) -> String {
    match prev {
        Some((h0, e0)) if e > 0.0 && e0 > 0.0 => format!("{:5.2}", (e0 / e).ln() / (h0 / h).ln()),
        _ => "    -".to_string(),
    }
}

/// Prints, per u space and multiplier, the convergence table at the smallest δ solved.
pub fn print_table(scene: &Scene, cases: &[CaseResult]) {
    let Some(delta) = cases.iter().map(|c| c.key.delta).min_by(f64::total_cmp) else {
        return;
    };
    say!("scene '{}': δ = {}", scene.name, delta_text(delta));
    let mut keys: Vec<(USpace, MultiplierSpace, PMass, PSpace)> = cases
        .iter()
        .map(|c| (c.key.u_space, c.key.multiplier, c.key.p_mass, c.key.p_space))
        .collect();
    keys.sort();
    keys.dedup();
    for (u_space, multiplier, p_mass, p_space) in keys {
        let mass = match p_mass {
            PMass::Consistent => "",
            PMass::Lumped => ", lumped p mass",
        };
        let space = match p_space {
            PSpace::Continuous => "",
            PSpace::BrokenTangential => ", broken-tangential p",
        };
        say!("\n{u_space} u, {multiplier}{mass}{space}");
        if scene.has_exact() {
            say!("level        h  unknowns  iter     e_u  rate     e_p  rate     e_λ  rate   kkt");
        } else {
            // open: multiplier unknowns with λ > 0, where the crack faces separate (contact
            // researchers read "active" as "in contact", the opposite)
            say!("level        h  unknowns  iter    open     kkt");
        }
        let mut prev: Option<(f64, f64, f64, f64)> = None;
        for c in cases.iter().filter(|c| {
            c.key.u_space == u_space
                && c.key.multiplier == multiplier
                && c.key.p_mass == p_mass
                && c.key.p_space == p_space
                && c.key.delta == delta
        }) {
            let flag = if c.converged { "" } else { "  NOT CONVERGED" };
            match c.errors {
                Some(e) => {
                    say!(
                        "{:5} {:8.5} {:9} {:5} {:7.2e} {} {:7.2e} {} {:7.2e} {} {:7.1e}{flag}",
                        c.key.level,
                        c.h,
                        c.unknowns,
                        c.iterations,
                        e.u_l2,
                        rate(prev.map(|p| (p.0, p.1)), c.h, e.u_l2),
                        e.p_l2,
                        rate(prev.map(|p| (p.0, p.2)), c.h, e.p_l2),
                        e.lambda_l2,
                        rate(prev.map(|p| (p.0, p.3)), c.h, e.lambda_l2),
                        c.kkt.max()
                    );
                    prev = Some((c.h, e.u_l2, e.p_l2, e.lambda_l2));
                }
                None => say!(
                    "{:5} {:8.5} {:9} {:5} {:7} {:7.1e}{flag}",
                    c.key.level,
                    c.h,
                    c.unknowns,
                    c.iterations,
                    format!("{}/{}", c.active, c.multipliers),
                    c.kkt.max()
                ),
            }
        }
    }
    say!("");
}
