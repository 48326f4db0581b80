//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod expectations;
pub mod orders;

use sdcrack_core::case::CasePattern;
use sdcrack_core::norms::{ErrorNorms, Quantity};
use sdcrack_core::problem::{MultiplierSpace, USpace};
use sdcrack_core::scene::Scene;
use sdcrack_core::study::{run_study, CasePlan, CaseResult, Silent};
use sdcrack_io::scene_file::TomlScene;

/// A small valid scene (levels 0–1 of a 4 × 4 mesh, every variant, fields, no reference) that the
/// CLI, bad-input and interrupted-run tests edit or run.
pub const SMALL_SCENE: &str = r#"name = "small"
[geometry]
domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }
crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }
[data]
f = "20*sin(2*pi*x)*sign(y)"
g = "0"
[discretization]
cells = [4, 4]
levels = [0, 1]
u_spaces = ["continuous", "broken"]
multipliers = ["M0", "M1", "M1star"]
deltas = [1e-2, 0.0]
[outputs]
fields = ["u", "p", "lambda"]
references = []
"#;

/// Runs this build's `sdcrack` binary with `args` and waits for it.
pub fn sdcrack(args: &[&str]) -> std::process::Output {
    output(std::process::Command::new(env!("CARGO_BIN_EXE_sdcrack")).args(args))
}

/// Held for reading while a test starts a process, for writing while a test holds an HDF5 file
/// open for writing ([`with_h5_rw`]). libhdf5 opens files without close-on-exec and takes an
/// `flock` on them: a child started by another test thread meanwhile would inherit the locked
/// descriptor and keep the lock for its whole life, so that the `sdcrack` run reading the file
/// next fails with "unable to lock file" (CI saw this once in `tests/merge.rs`).
static SPAWNING: std::sync::RwLock<()> = std::sync::RwLock::new(());

/// Starts `cmd` (no other test thread holds an HDF5 file open for writing meanwhile) and waits
/// for it; its stdout and stderr are captured.
pub fn output(cmd: &mut std::process::Command) -> std::process::Output {
    let child = {
        let _guard = SPAWNING.read().unwrap_or_else(|e| e.into_inner());
        cmd.stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("binary runs")
    };
    child.wait_with_output().expect("binary runs")
}

/// Calls `edit` on the HDF5 file `path` opened for writing, while no test thread starts a
/// process (see [`SPAWNING`]); the file is closed before this returns.
pub fn with_h5_rw<T>(path: &std::path::Path, edit: impl FnOnce(&hdf5::File) -> T) -> T {
    let _guard = SPAWNING.write().unwrap_or_else(|e| e.into_inner());
    let file = hdf5::File::open_rw(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    edit(&file)
}

/// Runs `sdcrack run SCENE --out OUT` with the further `args` (filters, `--quiet`) and waits
/// for it.
pub fn sdcrack_run(
    scene: impl AsRef<std::path::Path>,
    out: &std::path::Path,
    args: &[&str],
) -> std::process::Output {
    let scene = scene.as_ref().to_str().expect("a UTF-8 scene path");
    let out = out.to_str().expect("a UTF-8 results path");
    sdcrack(&[&["run", scene, "--out", out], args].concat())
}

/// The `summary.json` of a results folder.
pub fn summary(folder: &std::path::Path) -> serde_json::Value {
    let path = folder.join("summary.json");
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_slice(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A process's stderr as text.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Path of a repository scene.
pub fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"))
}

/// An elastic scene's text without its solver cases: its `[discretization]` lines
/// `multipliers = …` and `deltas = …` removed (the repository's elastic scenes list the
/// smooth-domain method's cases; a test that adds its own, or wants none, starts from this).
pub fn without_solver_cases(text: &str) -> String {
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("multipliers = ") && !l.starts_with("deltas = "))
        .collect();
    kept.join("\n") + "\n"
}

/// Loads a repository scene.
pub fn load(name: &str) -> Scene {
    Scene::from_file(&scene_path(name)).expect("repository scene is valid")
}

/// Runs the cases of `scene` selected by `filter`.
pub fn solve(scene: &Scene, filter: CasePattern) -> Vec<CaseResult> {
    let plan = CasePlan::new(scene, &filter);
    run_study(scene, &plan, &mut Silent)
        .expect("study runs")
        .cases
}

/// Observed rate log(e0/e1)/log(h0/h1).
pub fn rate(h0: f64, e0: f64, h1: f64, e1: f64) -> f64 {
    (e0 / e1).ln() / (h0 / h1).ln()
}

/// The error quantities of [`errors_by_level`], in its order, as the expectations and the compare
/// tool name them: the solver's vocabulary.
pub const QUANTITIES: &[&str] = Quantity::NAMES;

/// The four errors of a case, in the order of [`QUANTITIES`]: [e_u, e_p, e_p_x, e_λ].
pub fn quantities(e: &ErrorNorms) -> [f64; 4] {
    Quantity::ALL.map(|q| e.get(q))
}

/// One series of a scene with `[exact]`, levels increasing: (size, [e_u, e_p, e_p_x, e_λ]) of the
/// cases `keep` selects (one variant); the size is h, or N^{-1/2} (N the unknowns) when
/// `by_unknowns` (the mesh parameter of graded meshes).
pub fn errors_by_level(
    cases: &[CaseResult],
    keep: impl Fn(&CaseResult) -> bool,
    by_unknowns: bool,
) -> Vec<(f64, [f64; 4])> {
    cases
        .iter()
        .filter(|c| keep(c))
        .map(|c| {
            let e = c.errors.expect("exact scene has errors");
            let size = if by_unknowns {
                (c.unknowns as f64).powf(-0.5)
            } else {
                c.h
            };
            (size, quantities(&e))
        })
        .collect()
}

/// The observed rates of the last two steps of quantity `q` (an index of [`QUANTITIES`]) of an
/// [`errors_by_level`] series.
pub fn last_two_rates(s: &[(f64, [f64; 4])], q: usize) -> [f64; 2] {
    let n = s.len();
    let r = |a: usize, b: usize| rate(s[a].0, s[a].1[q], s[b].0, s[b].1[q]);
    [r(n - 3, n - 2), r(n - 2, n - 1)]
}

/// Least-squares slope of log e against log δ of the points (δ, e), all positive: the observed
/// order of e in δ.
pub fn loglog_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |a, (d, e)| (a.0 + d.ln() / n, a.1 + e.ln() / n));
    let (num, den) = points.iter().fold((0.0, 0.0), |a, (d, e)| {
        (
            a.0 + (d.ln() - mx) * (e.ln() - my),
            a.1 + (d.ln() - mx).powi(2),
        )
    });
    num / den
}

/// (h, e_u, e_p, e_λ) per level of one variant of a scene with `[exact]`.
pub fn error_series(
    cases: &[CaseResult],
    u: USpace,
    m: MultiplierSpace,
) -> Vec<(f64, f64, f64, f64)> {
    cases
        .iter()
        .filter(|c| c.key.u_space == u && c.key.multiplier == m)
        .map(|c| {
            let e = c.errors.expect("exact scene has errors");
            (c.h, e.u_l2, e.p_l2, e.lambda_l2)
        })
        .collect()
}

/// The contents of the HDF5 file `path`, sorted by path: every dataset under its path with its
/// values as `f64` bits, and every attribute of a group or dataset as `PATH@NAME` with its value
/// (numbers as `f64` bits, text as its bytes). The soft links `mesh` of the case groups are
/// skipped (their target is listed under `/meshes`).
pub fn h5_contents(path: &std::path::Path) -> Vec<(String, Vec<u64>)> {
    fn attrs(loc: &hdf5::Location, at: &str, out: &mut Vec<(String, Vec<u64>)>) {
        for name in loc.attr_names().unwrap() {
            let a = loc.attr(&name).unwrap();
            let value = match a.read_scalar::<f64>() {
                Ok(x) => vec![x.to_bits()],
                Err(_) => a
                    .read_scalar::<hdf5::types::VarLenUnicode>()
                    .unwrap()
                    .as_bytes()
                    .iter()
                    .map(|&b| u64::from(b))
                    .collect(),
            };
            out.push((format!("{at}@{name}"), value));
        }
    }
    fn walk(g: &hdf5::Group, at: &str, out: &mut Vec<(String, Vec<u64>)>) {
        for name in g.member_names().unwrap() {
            let path = format!("{at}/{name}");
            if name == "mesh" {
                continue;
            }
            if let Ok(sub) = g.group(&name) {
                attrs(&sub, &path, out);
                walk(&sub, &path, out);
            } else {
                let ds = g.dataset(&name).unwrap();
                attrs(&ds, &path, out);
                let values = ds.read_raw::<f64>().unwrap();
                out.push((path, values.iter().map(|v| v.to_bits()).collect()));
            }
        }
    }
    let file = hdf5::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut out = Vec::new();
    walk(&file, "", &mut out);
    out.sort();
    out
}

/// Asserts that two [`h5_contents`] are equal, naming the first entry that differs.
pub fn assert_same_h5(a: &[(String, Vec<u64>)], b: &[(String, Vec<u64>)]) {
    for ((pa, va), (pb, vb)) in a.iter().zip(b) {
        assert_eq!(pa, pb, "the same datasets and attributes");
        assert!(va == vb, "{pa} differs");
    }
    assert_eq!(
        a.len(),
        b.len(),
        "the same number of datasets and attributes; the first extra one: {:?}",
        a.get(b.len()).or(b.get(a.len())).map(|(p, _)| p)
    );
}

/// The file names of a folder, sorted.
pub fn listing(folder: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}
