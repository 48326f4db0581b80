//! Helpers shared by the integration tests.
#![allow(dead_code)]

use sdcrack::scene::Scene;
use sdcrack::study::{run_study, CaseFilter, CasePlan, CaseResult, Silent};

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
