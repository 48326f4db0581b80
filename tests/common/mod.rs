//! Helpers shared by the integration tests.
#![allow(dead_code)]

use sdcrack::scene::Scene;
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
