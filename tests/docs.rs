//! The scene examples of docs/scenes.md are valid scenes, so the documentation stays true; and
//! the repository refers to nothing outside it.

use sdcrack_core::scene::Scene;
use sdcrack_io::scene_file::TomlScene;

#[test]
fn every_toml_example_of_the_scene_documentation_is_a_valid_scene() {
    let doc = include_str!("../docs/scenes.md");
    let blocks: Vec<&str> = doc
        .split("```toml\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap_or(""))
        .collect();
    assert_eq!(blocks.len(), 3, "docs/scenes.md has three worked examples");
    for b in blocks {
        let scene = Scene::from_toml(b).unwrap_or_else(|e| panic!("{e}\n{b}"));
        assert!(!scene.name.is_empty());
    }
}

/// The repository stands alone: no file points at a path outside it (such as the developers'
/// working notes beside the checkout).
#[test]
fn nothing_refers_to_a_path_outside_the_repository() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new("git")
        .args(["ls-files", "-co", "--exclude-standard"])
        .current_dir(root)
        .output();
    let Some(out) = out.ok().filter(|o| o.status.success()) else {
        eprintln!("skipped: not a git checkout");
        return;
    };
    // written in pieces so that this file does not contain what it looks for
    let forbidden = [
        ["..", "shared"].join("/"),
        ["BRIEF", "md"].join("."),
        ["BRIEF", "§"].join(" "),
    ];
    let mut hits = Vec::new();
    for file in String::from_utf8_lossy(&out.stdout).lines() {
        let Ok(text) = std::fs::read_to_string(root.join(file)) else {
            continue; // binary or vanished
        };
        for f in &forbidden {
            if text.contains(f.as_str()) {
                hits.push(format!("{file}: {f}"));
            }
        }
    }
    assert!(hits.is_empty(), "{hits:#?}");
}
