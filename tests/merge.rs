//! `sdcrack merge`: shards of a scene (one `run --solver-only` per level, u space, multiplier and
//! p mass) merged into one folder equal to a single `sdcrack run` of the scene — every summary
//! value but the timings and the provenance, every field dataset bit for bit, every series file
//! byte for byte — and shards that do not make up the scene refused in one line, exit 2, with
//! nothing written.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

use common::{sdcrack, stderr};

/// `sdcrack run SCENE FILTERS --solver-only --out OUT` (must succeed): the shard's folder of the
/// scene `small`.
fn solver_shard(scene: &str, filters: &[&str], out: &Path) -> PathBuf {
    let mut args = vec!["run", scene];
    args.extend_from_slice(filters);
    args.extend(["--solver-only", "--quiet", "--out", out.to_str().unwrap()]);
    let o = sdcrack(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    out.join("small")
}

/// The small scene with both p masses: 2 levels × 2 u spaces × 3 multipliers × 2 p masses × 2 δ.
fn scene_text() -> String {
    common::SMALL_SCENE.replace(
        "deltas = [1e-2, 0.0]",
        "deltas = [1e-2, 0.0]\np_mass = [\"consistent\", \"lumped\"]",
    )
}

/// Writes the scene, runs it whole into `dir/single` and as one shard per (level, u space,
/// multiplier, p mass) into `dir/shards/<k>`; returns the shard folders.
fn single_and_shards(dir: &Path) -> (PathBuf, Vec<PathBuf>) {
    let scene = dir.join("small.toml");
    std::fs::write(&scene, scene_text()).unwrap();
    let scene = scene.to_str().unwrap();
    let single = dir.join("single");
    let o = sdcrack(&["run", scene, "--out", single.to_str().unwrap(), "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let mut shards = Vec::new();
    for level in ["0", "1"] {
        for u in ["continuous", "broken"] {
            for m in ["M0", "M1", "M1star"] {
                for pm in ["consistent", "lumped"] {
                    let out = dir.join("shards").join(format!("{level}-{u}-{m}-{pm}"));
                    shards.push(solver_shard(
                        scene,
                        &[
                            "--level",
                            level,
                            "--u-space",
                            u,
                            "--multiplier",
                            m,
                            "--p-mass",
                            pm,
                        ],
                        &out,
                    ));
                }
            }
        }
    }
    (single.join("small"), shards)
}

fn merge(shards: &[PathBuf], out: &Path) -> Output {
    let mut args = vec!["merge".to_string()];
    args.extend(shards.iter().map(|s| s.display().to_string()));
    args.extend(["--out".to_string(), out.display().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    sdcrack(&args)
}

fn summary(folder: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(folder.join("summary.json")).unwrap()).unwrap()
}

/// The summary without what describes the process rather than the results.
fn numbers(mut s: Value) -> Value {
    let o = s.as_object_mut().unwrap();
    for key in ["provenance", "wall_s", "fields_write_s", "shards"] {
        o.remove(key);
    }
    for c in o["cases"].as_array_mut().unwrap() {
        c.as_object_mut().unwrap().remove("timings_s");
    }
    s
}

/// Every dataset of `/cases` and `/meshes` of `fields.h5`: (path, raw values as bits).
fn datasets(folder: &Path) -> Vec<(String, Vec<u64>)> {
    let file = hdf5::File::open(folder.join("fields.h5")).unwrap();
    let mut out = Vec::new();
    for top in ["meshes", "cases"] {
        let group = file.group(top).unwrap();
        for name in group.member_names().unwrap() {
            let g = group.group(&name).unwrap();
            let mut members: Vec<String> = g
                .member_names()
                .unwrap()
                .into_iter()
                .filter(|m| m != "mesh")
                .collect();
            if g.link_exists("crack") {
                members.retain(|m| m != "crack");
                for m in g.group("crack").unwrap().member_names().unwrap() {
                    members.push(format!("crack/{m}"));
                }
            }
            for m in members {
                let ds = g.dataset(&m).unwrap();
                let values: Vec<u64> = ds
                    .read_raw::<f64>()
                    .unwrap()
                    .iter()
                    .map(|v| v.to_bits())
                    .collect();
                out.push((format!("/{top}/{name}/{m}"), values));
            }
        }
    }
    out.sort();
    out
}

fn series_files(folder: &Path) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = std::fs::read_dir(folder.join("fields"))
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read_to_string(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn merged_shards_equal_a_single_run() {
    let dir = tempfile::tempdir().unwrap();
    let (single, mut shards) = single_and_shards(dir.path());
    // the order of the shards on the command line does not matter
    shards.reverse();
    let out = dir.path().join("merged");
    let o = merge(&shards, &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let merged = out.join("small");

    let (a, b) = (summary(&single), summary(&merged));
    assert_eq!(b["cases"].as_array().unwrap().len(), 48);
    assert_eq!(numbers(a.clone()), numbers(b.clone()));
    // the same keys in the same order, plus the shards' provenance
    let keys = |v: &Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
    let mut expected = keys(&a);
    expected.push("shards".into());
    assert_eq!(keys(&b), expected);
    assert_eq!(b["shards"].as_array().unwrap().len(), 24);
    assert_eq!(b["provenance"]["command_line"][1], "merge");

    let (da, db) = (datasets(&single), datasets(&merged));
    assert_eq!(da.len(), db.len());
    assert!(da.len() > 48 * 3, "u, p, λ of every case and the meshes");
    for ((pa, va), (pb, vb)) in da.iter().zip(&db) {
        assert_eq!(pa, pb);
        assert!(va == vb, "{pa} differs");
    }
    assert_eq!(series_files(&single), series_files(&merged));
    assert_eq!(
        std::fs::read(single.join("scene.toml")).unwrap(),
        std::fs::read(merged.join("scene.toml")).unwrap()
    );
}

/// A scene that does not list u, p and λ: every shard keeps `verification.h5`, and the merge
/// unites them like `fields.h5` (`H5Ocopy` of the case groups), so that the merged folder holds
/// the same files as a single run, `verification.h5` bit for bit the same datasets and
/// attributes, and names it as the recomputation file. With no fields there is neither
/// `fields.h5` nor `fields/`; with u only, both are merged too.
#[test]
fn shards_verification_h5_merge_like_fields_h5() {
    for fields in ["[]", r#"["u"]"#] {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("small.toml");
        let text = scene_text().replace(
            r#"fields = ["u", "p", "lambda"]"#,
            &format!("fields = {fields}"),
        );
        std::fs::write(&scene, text).unwrap();
        let scene = scene.to_str().unwrap();
        let single = dir.path().join("single");
        let o = sdcrack(&["run", scene, "--out", single.to_str().unwrap(), "--quiet"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let single = single.join("small");
        // one shard per level and u space, each with every multiplier, p mass and δ
        let mut shards = Vec::new();
        for level in ["1", "0"] {
            for u in ["broken", "continuous"] {
                let out = dir.path().join("shards").join(format!("{level}-{u}"));
                let shard = solver_shard(scene, &["--level", level, "--u-space", u], &out);
                assert!(shard.join("verification.h5").is_file());
                shards.push(shard);
            }
        }
        let out = dir.path().join("merged");
        let o = merge(&shards, &out);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let merged = out.join("small");

        assert_eq!(
            common::listing(&merged),
            common::listing(&single),
            "fields = {fields}"
        );
        assert_eq!(fields == "[]", !merged.join("fields.h5").exists());
        assert_eq!(fields == "[]", !merged.join("fields").exists());

        let (a, b) = (summary(&single), summary(&merged));
        assert_eq!(b["recomputation_file"], "verification.h5");
        assert_eq!(numbers(a), numbers(b));

        let (va, vb) = (
            common::h5_contents(&single.join("verification.h5")),
            common::h5_contents(&merged.join("verification.h5")),
        );
        assert!(
            va.iter().filter(|(p, _)| p.ends_with("/u")).count() == 48,
            "u of every case"
        );
        common::assert_same_h5(&va, &vb);
        if fields != "[]" {
            common::assert_same_h5(
                &common::h5_contents(&single.join("fields.h5")),
                &common::h5_contents(&merged.join("fields.h5")),
            );
            assert_eq!(series_files(&single), series_files(&merged));
        }
    }
}

/// A failed merge: exit 2, one line containing `needle`, nothing under `out`.
fn refused(shards: &[PathBuf], out: &Path, needle: &str) {
    let o = merge(shards, out);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{err}");
    assert!(!out.join("small").exists());
    if out.exists() {
        assert_eq!(std::fs::read_dir(out).unwrap().count(), 0, "nothing left");
    }
}

#[test]
fn shards_that_do_not_make_up_the_scene_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, shards) = single_and_shards(dir.path());
    let out = dir.path().join("merged");

    // a job missing
    refused(
        &shards[1..],
        &out,
        "the shards hold 46 of the scene's 48 cases; missing e.g. level 0 continuous M0 consistent",
    );
    // a job twice
    let mut twice = shards.clone();
    twice.push(shards[3].clone());
    refused(&twice, &out, "is also in shard");
    // a shard of an edited scene
    let edited = dir.path().join("edited");
    copy_dir(&shards[0], &edited);
    let text = scene_text().replace("g = \"0\"", "g = \"0.0\"");
    std::fs::write(edited.join("scene.toml"), text).unwrap();
    let mut mixed = shards[1..].to_vec();
    mixed.push(edited);
    refused(&mixed, &out, "differs from that of");
    // two shards that disagree on a mesh they share (level 0, continuous u)
    let damaged = dir.path().join("damaged");
    copy_dir(&shards[1], &damaged);
    common::with_h5_rw(&damaged.join("fields.h5"), |file| {
        let points = file.dataset("meshes/level0-continuous/points").unwrap();
        let mut values = points.read_raw::<f64>().unwrap();
        values[0] += 1e-12;
        points.write_raw(&values).unwrap();
    });
    let mut with_damaged = shards.clone();
    with_damaged[1] = damaged;
    refused(
        &with_damaged,
        &out,
        "dataset /meshes/level0-continuous/points differs from the same dataset of another shard",
    );
    // not a shard
    refused(&[dir.path().to_path_buf()], &out, "cannot read scene.toml");

    // an existing merged folder is never overwritten
    assert_eq!(merge(&shards, &out).status.code(), Some(0));
    let o = merge(&shards, &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("already exists"), "{}", stderr(&o));
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

#[test]
fn reference_needs_a_listed_tool_and_check_json_gives_the_plan() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("small.toml");
    std::fs::write(&scene, scene_text()).unwrap();
    let scene = scene.to_str().unwrap();
    let o = sdcrack(&[
        "reference",
        scene,
        "--tool",
        "dolfinx",
        "--level",
        "0",
        "--out",
        "x",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("lists the references []"),
        "{}",
        stderr(&o)
    );

    let o = sdcrack(&["check", scene, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let plan: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(plan["name"], "small");
    // the scalar problem: no "problem" key (as in summary.json; an elastic plan has one)
    assert!(plan.get("problem").is_none(), "{plan}");
    assert_eq!(plan["cases"], 48);
    assert_eq!(plan["levels"], serde_json::json!([0, 1]));
    assert_eq!(
        plan["p_masses"],
        serde_json::json!(["consistent", "lumped"])
    );
    assert_eq!(plan["references"], serde_json::json!([]));
    assert_eq!(plan["fields"], true);
    // the estimate of crates/sdcrack-core/src/scene.rs: 128 MiB + 600 B per cell per log2(cells),
    // in whole MiB
    let mib =
        |cells: f64| ((128u64 << 20) as f64 + 600.0 * cells * cells.log2()) / (1u64 << 20) as f64;
    assert_eq!(plan["memory_mb"]["0"], mib(16.0).ceil() as u64);
    assert_eq!(plan["memory_mb"]["1"], mib(64.0).ceil() as u64);
    let mesh_mib = |cells: f64| 600.0 * cells * cells.log2() / (1u64 << 20) as f64;
    assert_eq!(plan["mesh_memory_mb"]["0"], mesh_mib(16.0).ceil() as u64);
    assert_eq!(plan["mesh_memory_mb"]["1"], mesh_mib(64.0).ceil() as u64);
}

/// A scene on a mesh file names it relative to the scene file; its shards, run from the scene's
/// folder, merge from any other folder (the merge finds the scene's folder in the shards'
/// provenance), and the merged summary keeps where level 0 came from.
#[test]
fn shards_of_a_mesh_file_scene_merge_from_another_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let folder = tmp.path().join("scene");
    copy_dir(&repo.join("scenes/meshes"), &folder.join("meshes"));
    let mut text = std::fs::read_to_string(repo.join("scenes/user-mesh.toml")).unwrap();
    for (key, value) in [
        ("levels", "[0, 1]"),
        ("u_spaces", "[\"continuous\", \"broken\"]"),
        ("multipliers", "[\"M1\"]"),
        ("p_mass", "[\"consistent\"]"),
        ("deltas", "[0.0]"),
        ("fields", "[]"),
        ("references", "[]"),
    ] {
        let start = text.find(&format!("\n{key} = ")).expect(key) + 1;
        let end = start + text[start..].find('\n').unwrap();
        text.replace_range(start..end, &format!("{key} = {value}"));
    }
    std::fs::write(folder.join("user-mesh.toml"), &text).unwrap();
    let shards = tmp.path().join("shards");
    for level in ["0", "1"] {
        let o = common::output(
            std::process::Command::new(env!("CARGO_BIN_EXE_sdcrack"))
                .current_dir(&folder)
                .args([
                    "run",
                    "user-mesh.toml",
                    "--solver-only",
                    "--quiet",
                    "--level",
                    level,
                ])
                .args(["--out", shards.join(level).to_str().unwrap()]),
        );
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let out = tmp.path().join("merged");
    let parts = [shards.join("0/user-mesh"), shards.join("1/user-mesh")];
    let o = merge(&parts, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out.join("user-mesh"));
    assert_eq!(s["cases"].as_array().unwrap().len(), 4);
    let source = s["coarse_mesh"]["source"].as_str().unwrap();
    assert!(
        source.ends_with("meshes/trapezoid-two-cracks.msh"),
        "{source}"
    );
}

/// A fake reference shard of `tool` at `level` for the scene `text` named `name`:
/// `<dir>/<name>/scene.toml` and `<tool>/` with a summary of one converged case and a u file.
/// The merge reads only the cases' levels and statuses and copies the rest.
fn reference_shard(dir: &Path, name: &str, text: &str, tool: &str, level: u32) -> PathBuf {
    let shard = dir.join(format!("{tool}-l{level}")).join(name);
    std::fs::create_dir_all(shard.join(tool)).unwrap();
    std::fs::write(shard.join("scene.toml"), text).unwrap();
    let summary = serde_json::json!({"scene": name, "tool": tool, "problem": "elasticity",
        "provenance": {"tool": tool}, "cases": [{"level": level, "status": "converged"}]});
    std::fs::write(shard.join(tool).join("summary.json"), summary.to_string()).unwrap();
    std::fs::write(
        shard.join(tool).join(format!("u_level{level}.txt")),
        "0 0\n",
    )
    .unwrap();
    shard
}

/// Every file under `folder` (relative paths) with its bytes.
fn files(folder: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![folder.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(folder).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// An elastic scene without solver cases (the repository's patch scene, its `multipliers` and
/// `deltas` lines removed): its campaign runs reference jobs only, whose shards merge into the
/// folder `sdcrack run` writes: the run's
/// summary (no case, `"problem": "elasticity"`, the plan's levels, empty scalar axes; equal but
/// for the provenance, the timings and `shards`, here empty), the mesh export of `sdcrack mesh`
/// byte for byte, each reference's files. `check --json` names the problem. A level missing is
/// refused, and a scalar scene's reference shards without solver shards still are.
#[test]
fn reference_shards_of_an_elastic_scene_merge_without_solver_shards() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::scene_path("elastic-patch"))
        .unwrap()
        .replace("levels = [0, 1, 2, 3, 4]", "levels = [0, 1]")
        .replace(
            "references = [\"dolfinx\", \"freefem\"]",
            "references = [\"dolfinx\"]",
        );
    let text = common::without_solver_cases(&text);
    let scene = dir.path().join("elastic-patch.toml");
    std::fs::write(&scene, &text).unwrap();
    let scene = scene.to_str().unwrap();
    let o = sdcrack(&["check", scene, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let plan: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(plan["problem"], "elasticity");
    assert_eq!(plan["cases"], 0);
    assert_eq!(plan["u_spaces"], serde_json::json!([]));

    let shards: Vec<PathBuf> = [0, 1]
        .map(|l| {
            reference_shard(
                &dir.path().join("shards"),
                "elastic-patch",
                &text,
                "dolfinx",
                l,
            )
        })
        .to_vec();
    let out = dir.path().join("merged");
    let o = merge(&shards, &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let merged = out.join("elastic-patch");
    // the run's summary: `run --solver-only` writes it without running the references
    let single = dir.path().join("single");
    let o = sdcrack(&[
        "run",
        scene,
        "--solver-only",
        "--quiet",
        "--out",
        single.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let single = single.join("elastic-patch");
    let m = summary(&merged);
    assert_eq!(numbers(m.clone()), numbers(summary(&single)));
    assert_eq!(m["problem"], "elasticity");
    assert_eq!(m["shards"], serde_json::json!([]));
    assert_eq!(m["cases"], serde_json::json!([]));
    assert!(m["provenance"]["scene_origin"]
        .as_str()
        .unwrap()
        .ends_with("dolfinx-l0/elastic-patch/scene.toml"));
    assert_eq!(
        std::fs::read_to_string(merged.join("scene.toml")).unwrap(),
        text
    );
    // the mesh export, as `sdcrack mesh` writes it
    let mesh = dir.path().join("mesh");
    let o = sdcrack(&["mesh", scene, "--out", mesh.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(files(&merged.join("mesh")), files(&mesh));
    // the reference's files: both levels' u, the cases in level order
    let reference: Value =
        serde_json::from_slice(&std::fs::read(merged.join("dolfinx/summary.json")).unwrap())
            .unwrap();
    let levels: Vec<&Value> = (reference["cases"].as_array().unwrap().iter())
        .map(|c| &c["level"])
        .collect();
    assert_eq!(levels, [&serde_json::json!(0), &serde_json::json!(1)]);
    assert!(merged.join("dolfinx/u_level0.txt").is_file());
    assert!(merged.join("dolfinx/u_level1.txt").is_file());
    assert_eq!(
        common::listing(&merged),
        ["dolfinx", "mesh", "scene.toml", "summary.json"]
    );

    // a level missing
    let o = merge(&shards[1..], &dir.path().join("partial"));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("no shard holds reference dolfinx level 0"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.path().join("partial").join("elastic-patch").exists());
    // a scalar scene's reference shards alone: its solver cases are missing
    let scalar = common::SMALL_SCENE.replace("references = []", "references = [\"dolfinx\"]");
    assert_ne!(scalar, common::SMALL_SCENE);
    let shard = reference_shard(&dir.path().join("scalar"), "small", &scalar, "dolfinx", 0);
    let o = merge(&[shard], &dir.path().join("scalar-merged"));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("no solver shard (summary.json) among the shards"),
        "{}",
        stderr(&o)
    );
}
