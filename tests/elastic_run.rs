//! An elastic scene's solver cases end to end (docs/elasticity.md, "The run"): `sdcrack check`
//! plans them, `sdcrack run` solves them (the smooth-domain method for elasticity) into
//! summary.json and the field files, `sdcrack merge` of per-level shards makes the single run's
//! folder. On scenes/elastic-patch.toml at levels 0–1 with the pointwise multiplier at δ = 0: the
//! patch test, exact for the method (≤ 1e-10: round-off of systems of ~5000 unknowns, measured
//! 1.5e-15; a wrong sign or coupling is off by O(1)).

mod common;

use common::{assert_same_h5, h5_contents, sdcrack, sdcrack_run, stderr, summary};

/// The bound on the patch test's σ, opening and pressure errors.
const EXACT: f64 = 1e-10;

/// scenes/elastic-patch.toml at levels 0–1 with solver cases (M1star, δ = 0) and no reference,
/// written into `dir`: its path.
fn patch_scene(dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(common::scene_path("elastic-patch")).unwrap();
    let text = common::without_solver_cases(&text);
    let levels = "levels = [0, 1, 2, 3, 4]";
    assert!(text.contains(levels), "the scene's levels moved");
    let text = text.replacen(
        levels,
        "levels = [0, 1]\nmultipliers = [\"M1star\"]\ndeltas = [0.0]",
        1,
    );
    let refs = "references = [\"dolfinx\", \"freefem\"]";
    assert!(text.contains(refs), "the scene's references moved");
    let path = dir.join("elastic-patch.toml");
    std::fs::write(&path, text.replacen(refs, "references = []", 1)).unwrap();
    path
}

#[test]
fn an_elastic_run_solves_the_patch_test_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let scene = patch_scene(dir.path());
    let o = sdcrack(&["check", "--json", scene.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let plan: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(plan["problem"], "elasticity");
    assert_eq!(plan["cases"], 2);
    assert_eq!(plan["problems"], serde_json::json!(["elasticity"]));
    assert_eq!(plan["u_spaces"], serde_json::json!([]));

    let out = dir.path().join("out");
    let o = sdcrack_run(&scene, &out, &["--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let folder = out.join("elastic-patch");
    let s = summary(&folder);
    assert_eq!(s["problem"], "elasticity");
    assert_eq!(s["shared_timings"], serde_json::json!(["assembly"]));
    assert_eq!(s["all_converged"], true);
    let cases = s["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2);
    for (c, level) in cases.iter().zip([0, 1]) {
        let keys: Vec<&str> = c.as_object().unwrap().keys().map(String::as_str).collect();
        assert_eq!(
            keys[..6],
            ["level", "h", "multiplier", "delta", "problem", "unknowns"]
        );
        assert_eq!(
            (c["level"].as_u64(), &c["multiplier"]),
            (Some(level), &"M1star".into())
        );
        assert_eq!(c["status"], "converged");
        assert!(c["kkt"]["equations"].as_f64().unwrap() <= 1e-10, "{c}");
        // every crack edge end is pressed (the patch is compressed across the crack)
        assert_eq!(c["closed_ends"], 2 * c["crack_edges"].as_u64().unwrap());
        for name in [
            "stress_l2",
            "stress_sym_l2",
            "opening_l2",
            "pressure_l2",
            "u_star_l2",
        ] {
            let e = c["errors"][name].as_f64().unwrap();
            assert!(e <= EXACT, "level {level}: {name} = {e}");
        }
        // u_h is P0: its error is O(h), not round-off
        assert!(c["errors"]["u_l2"].as_f64().unwrap() > 1e-3, "{c}");
        let grid = c["fields_grid"].as_str().unwrap();
        assert_eq!(grid, format!("level{level}-elasticity-M1star-delta0"));
        for file in [&c["fields_state"], &c["fields_series"]] {
            assert!(folder.join(file.as_str().unwrap()).is_file(), "{file}");
        }
    }
    // the field file: the broken mesh (3 points per triangle), σ per point in 3-D (9 numbers),
    // the crack one segment per crack edge (2 points each)
    let h5 = hdf5::File::open(folder.join("fields.h5")).unwrap();
    let case = h5.group("cases/level1-elasticity-M1star-delta0").unwrap();
    let triangles = h5.dataset("meshes/level1-elasticity/triangles").unwrap();
    let t = triangles.shape()[0];
    assert_eq!(case.dataset("sigma").unwrap().shape(), [3 * t, 9]);
    assert_eq!(case.dataset("u_h").unwrap().shape(), [t, 3]);
    let edges = cases[1]["crack_edges"].as_u64().unwrap() as usize;
    assert_eq!(case.dataset("crack/pressure").unwrap().shape(), [2 * edges]);
    let sigma = case.dataset("sigma").unwrap().read_raw::<f64>().unwrap();
    for (i, v) in sigma.iter().enumerate() {
        let want = if i % 9 == 4 { -1.0 } else { 0.0 };
        assert!(
            (v - want).abs() <= EXACT,
            "σ component {} of point {}: {v}",
            i % 9,
            i / 9
        );
    }
    let level: i64 = case.attr("level").unwrap().read_scalar().unwrap();
    assert_eq!(level, 1);
    assert!(
        case.attr("u_space").is_err(),
        "an elastic case has no u space"
    );
}

/// Two per-level shards of the elastic run merge into the single run's folder: the same cases
/// in the same order, the same field file (every dataset and attribute bit for bit).
#[test]
fn elastic_shards_merge_into_the_single_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = patch_scene(dir.path());
    let single = dir.path().join("single");
    let o = sdcrack_run(&scene, &single, &["--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let mut shards = Vec::new();
    for level in ["1", "0"] {
        let out = dir.path().join(format!("l{level}"));
        let o = sdcrack_run(
            &scene,
            &out,
            &["--quiet", "--solver-only", "--level", level],
        );
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        shards.push(out.join("elastic-patch").to_str().unwrap().to_string());
    }
    let merged = dir.path().join("merged");
    let o = sdcrack(&[
        "merge",
        &shards[0],
        &shards[1],
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (a, b) = (single.join("elastic-patch"), merged.join("elastic-patch"));
    let strip = |mut s: serde_json::Value| {
        for c in s["cases"].as_array_mut().unwrap() {
            c.as_object_mut().unwrap().remove("timings_s");
        }
        s["cases"].clone()
    };
    assert_eq!(strip(summary(&a)), strip(summary(&b)));
    assert_same_h5(
        &h5_contents(&a.join("fields.h5")),
        &h5_contents(&b.join("fields.h5")),
    );
}
