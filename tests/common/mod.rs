//! Helpers shared by the integration tests.
#![allow(dead_code)]

use sdcrack::scene::{MultiplierSpace, Scene, USpace};
use sdcrack::study::{run_study, CaseFilter, CasePlan, CaseResult, Silent};

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
    std::process::Command::new(env!("CARGO_BIN_EXE_sdcrack"))
        .args(args)
        .output()
        .expect("binary runs")
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

/// Loads a repository scene.
pub fn load(name: &str) -> Scene {
    Scene::from_file(&scene_path(name)).expect("repository scene is valid")
}

/// Runs the cases of `scene` selected by `filter`.
pub fn solve(scene: &Scene, filter: CaseFilter) -> Vec<CaseResult> {
    let plan = CasePlan::new(scene, &filter);
    run_study(scene, &plan, &mut Silent)
        .expect("study runs")
        .cases
}

/// Observed rate log(e0/e1)/log(h0/h1).
pub fn rate(h0: f64, e0: f64, h1: f64, e1: f64) -> f64 {
    (e0 / e1).ln() / (h0 / h1).ln()
}

/// (h, e_u, e_p, e_λ) per level of one variant of a scene with `[exact]`.
pub fn error_series(
    cases: &[CaseResult],
    u: USpace,
    m: MultiplierSpace,
) -> Vec<(f64, f64, f64, f64)> {
    cases
        .iter()
        .filter(|c| c.u_space == u && c.multiplier == m)
        .map(|c| {
            let e = c.errors.expect("exact scene has errors");
            (c.h, e.u_l2, e.p_l2, e.lambda_l2)
        })
        .collect()
}
