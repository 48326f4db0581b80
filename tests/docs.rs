//! The scene examples of docs/scenes.md are valid scenes, so the documentation stays true.

use sdcrack::scene::Scene;

#[test]
fn every_toml_example_of_the_scene_documentation_is_a_valid_scene() {
    let doc = include_str!("../docs/scenes.md");
    let blocks: Vec<&str> = doc
        .split("```toml\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap_or(""))
        .collect();
    assert_eq!(blocks.len(), 2, "docs/scenes.md has two worked examples");
    for b in blocks {
        let scene = Scene::from_toml(b).unwrap_or_else(|e| panic!("{e}\n{b}"));
        assert!(!scene.name.is_empty());
    }
}
