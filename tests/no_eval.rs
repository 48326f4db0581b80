//! Scene text is parsed by the expression grammar (crates/sdcrack-core/src/expr.rs), never evaluated as code.
//! The hostile expressions shared with the Python test (references/tests/hostile_expressions.json:
//! attribute access, dunder names, calls outside the grammar, string literals, shell and FreeFEM
//! statements) are fed to every Rust entry point that takes an expression: `Expr::parse`, each
//! expression key of a scene (`data.f`, `data.g`, `exact.u`, `exact.px`, `exact.py`,
//! `exact.jump`), and the binary (`sdcrack check`). Each is refused with a one-line error, and
//! nothing the expression names is created.

mod common;

use sdcrack_core::expr::Expr;
use sdcrack_core::scene::Scene;
use sdcrack_io::scene_file::TomlScene;

fn hostile(placeholder_path: &str) -> Vec<String> {
    let doc: serde_json::Value =
        serde_json::from_str(include_str!("../references/tests/hostile_expressions.json"))
            .expect("the shared list is JSON");
    let placeholder = doc["placeholder"].as_str().expect("placeholder");
    doc["hostile"]
        .as_array()
        .expect("hostile list")
        .iter()
        .map(|v| {
            v.as_str()
                .expect("strings")
                .replace(placeholder, placeholder_path)
        })
        .collect()
}

/// `src` as a TOML basic string (quotes, backslashes and control characters escaped).
fn toml_string(src: &str) -> String {
    serde_json::to_string(src).expect("a JSON string is a TOML basic string here")
}

#[test]
fn every_entry_point_refuses_hostile_expressions_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let pwned = dir.path().join("pwned");
    let list = hostile(pwned.to_str().unwrap());
    assert!(list.len() >= 50, "the shared list is complete");
    let keys = [
        ("data", "f"),
        ("data", "g"),
        ("exact", "u"),
        ("exact", "px"),
        ("exact", "py"),
        ("exact", "jump"),
    ];
    for src in &list {
        let e = Expr::parse(src).expect_err(src);
        assert!(!e.to_string().contains('\n'), "{src:?}: {e}");
        for (table, key) in keys {
            let scene = with_expression(table, key, &toml_string(src));
            let e = Scene::from_toml(&scene).expect_err(&format!("{table}.{key} = {src:?}"));
            let msg = e.to_string();
            assert!(!msg.contains('\n'), "{table}.{key} = {src:?}: {msg}");
        }
    }
    assert!(!pwned.exists());
}

#[test]
fn the_binary_refuses_a_hostile_scene_with_one_line_and_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let pwned = dir.path().join("pwned");
    let path = dir.path().join("hostile.toml");
    for src in hostile(pwned.to_str().unwrap())
        .iter()
        .filter(|s| s.contains(pwned.to_str().unwrap()))
    {
        std::fs::write(&path, with_expression("data", "f", &toml_string(src))).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_sdcrack"))
            .args(["check", path.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{src:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{src:?}: {err}");
        assert!(err.starts_with("sdcrack: error: invalid scene"), "{err}");
        assert!(!pwned.exists(), "{src:?}");
    }
}

/// The small test scene with `table.key = value` (value already TOML), adding `[exact]` if needed.
fn with_expression(table: &str, key: &str, value: &str) -> String {
    let base = common::SMALL_SCENE;
    match (table, key) {
        ("data", "f") => {
            base.replacen("f = \"20*sin(2*pi*x)*sign(y)\"", &format!("f = {value}"), 1)
        }
        ("data", "g") => base.replacen("g = \"0\"", &format!("g = {value}"), 1),
        ("exact", "u") => base.replacen(
            "[discretization]",
            &format!("[exact]\nu = {value}\n[discretization]"),
            1,
        ),
        ("exact", k) => base.replacen(
            "[discretization]",
            &format!("[exact]\nu = \"x\"\n{k} = {value}\n[discretization]"),
            1,
        ),
        _ => unreachable!("known keys only"),
    }
}
