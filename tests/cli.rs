//! The binary as users call it: results layout, summary keys, outputs asked for and no more, and
//! one-line errors with the documented exit codes on bad input.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{sdcrack, sdcrack_run, stderr, summary};

fn write_scene(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

use common::SMALL_SCENE as SMALL;

/// Runs the small scene's file `scene` into `out` with `--quiet` and the further `args` (one
/// string, split at spaces), asserts that it succeeds and returns the process, the results folder
/// and its summary.json.
fn run_small(scene: &str, out: &Path, args: &str) -> (Output, PathBuf, serde_json::Value) {
    let args: Vec<&str> = std::iter::once("--quiet")
        .chain(args.split_whitespace())
        .collect();
    let o = sdcrack_run(scene, out, &args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let folder = out.join("small");
    let summary = summary(&folder);
    (o, folder, summary)
}

#[test]
fn run_writes_summary_and_fields_and_never_overwrites() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "small.toml", SMALL);
    let out = dir.path().join("res");
    let (o, folder, summary) = run_small(&scene, &out, "");
    assert_eq!(summary["scene"], "small");
    let cases = summary["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2 * 2 * 3 * 2);
    for c in cases {
        for key in [
            "level",
            "h",
            "u_space",
            "multiplier",
            "delta",
            "unknowns",
            "iterations",
            "kkt",
            "timings_s",
        ] {
            assert!(c.get(key).is_some(), "case lacks {key}: {c}");
        }
        assert!(c.get("errors").is_none(), "no [exact] → no errors");
        assert_eq!(c["converged"], true, "{c}");
    }
    assert!(folder.join("fields.h5").is_file());
    // one time series (and its crack) per level, u space and multiplier, one state file (and
    // its crack) per case; no spatial collection
    assert!(!folder.join("fields.xdmf").exists());
    let files = std::fs::read_dir(folder.join("fields")).unwrap().count();
    assert_eq!(
        files,
        (2 * 2 * 3) * 2 + cases.len() * 2,
        "12 series and 24 states, a mesh file and a crack file each"
    );
    for c in cases {
        let file = c["fields_series"].as_str().unwrap();
        assert!(folder.join(file).is_file(), "{file}");
        assert!(c["fields_grid"].as_str().unwrap().starts_with(
            file.trim_start_matches("fields/")
                .trim_end_matches(".series.xdmf")
        ));
        let state = c["fields_state"].as_str().unwrap();
        assert_eq!(
            state,
            format!("fields/{}.xdmf", c["fields_grid"].as_str().unwrap())
        );
        assert!(folder.join(state).is_file(), "{state}");
    }
    // provenance: the command line as given, the binary, the date
    let prov = &summary["provenance"];
    assert_eq!(prov["command_line"][1], "run");
    assert_eq!(prov["command_line"][2], scene.as_str());
    assert!(prov["executable"].as_str().unwrap().ends_with("sdcrack"));
    assert!(prov["date_utc"].as_str().unwrap().ends_with('Z'));
    assert!(prov["cores"].as_u64().unwrap() >= 1);
    assert_eq!(prov["scene_origin"], scene.as_str());
    assert_eq!(prov["sdcrack_version"], env!("CARGO_PKG_VERSION"));
    // the last line: the command's whole time, and the solve's (summary.json's wall_s) beside it
    // (the solve's alone read "9 cases in 0.0 s" after 6 s of references)
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let last = stdout.lines().last().unwrap_or_default();
    let (counts, rest) = last.split_once(" s (solving ").expect(last);
    let (solving, folder_text) = rest.split_once(" s); results in ").expect(last);
    assert_eq!(folder_text, folder.display().to_string());
    let total: f64 = counts
        .trim_start_matches("24 cases in ")
        .parse()
        .expect(last);
    let solving: f64 = solving.parse().expect(last);
    assert!(total >= solving, "{last}");
    assert_eq!(
        format!("{solving:.1}"),
        format!("{:.1}", summary["wall_s"].as_f64().unwrap())
    );
    // no partial folders left
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["small".to_string()]);
    // a second run refuses and leaves the first untouched
    let before = std::fs::read(folder.join("summary.json")).unwrap();
    let o = sdcrack_run(&scene, &out, &["--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("already exists"), "{}", stderr(&o));
    assert_eq!(std::fs::read(folder.join("summary.json")).unwrap(), before);
}

#[test]
fn no_fields_asked_no_field_files_and_filters_select_one_case() {
    let dir = tempfile::tempdir().unwrap();
    let text = SMALL.replace(r#"fields = ["u", "p", "lambda"]"#, "fields = []");
    let scene = write_scene(dir.path(), "small.toml", &text);
    let out = dir.path().join("res");
    let args = "--level 1 --u-space broken --multiplier M1star --delta 0";
    let (_, folder, summary) = run_small(&scene, &out, args);
    assert!(!folder.join("fields.h5").exists() && !folder.join("fields").exists());
    // but what the compare tool recomputes the errors from (tests/verification.rs)
    assert!(folder.join("verification.h5").is_file());
    assert_eq!(summary["recomputation_file"], "verification.h5");
    let cases = summary["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 1);
    assert_eq!(cases[0]["multiplier"], "M1star");
    assert_eq!(cases[0]["u_space"], "broken");
    assert_eq!(cases[0]["level"], 1);
}

#[test]
fn bad_inputs_give_one_line_and_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("res");
    // (what, a text of the small scene, what replaces it, the words of the error); the first
    // row names a file that does not exist
    #[rustfmt::skip]
    let cases = [
        ("missing file", "", "", "cannot read scene file"),
        ("unknown key", "cells =", "cels =", "did you mean `cells`"),
        ("off mesh", "[-0.5, 0.0]", "[-0.4, 0.0]", "not a vertex of the level-0 mesh"),
        ("touches boundary", "[-0.5, 0.0]", "[-1.0, 0.0]", "touches the domain boundary"),
        ("bad expression", "20*sin(2*pi*x)", "20*sinn(2*pi*x)", "data.f"),
        ("NaN data", r#"g = "0""#, r#"g = "log(x - 2)""#, "evaluates to NaN"),
        ("negative delta", "deltas = [1e-2, 0.0]", "deltas = [-1.0]", "not a finite number ≥ 0"),
        ("unknown multiplier", r#""M1star"]"#, r#""M2"]"#, "unknown value \"M2\""),
    ];
    for (what, old, new, needle) in cases {
        let scene = if old.is_empty() {
            dir.path().join("nope.toml").display().to_string()
        } else {
            assert_eq!(SMALL.matches(old).count(), 1, "{what}: {old:?} once");
            write_scene(dir.path(), "bad.toml", &SMALL.replace(old, new))
        };
        let o = sdcrack_run(&scene, &out, &["--quiet"]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{what}: {err}");
        assert!(
            err.contains(needle),
            "{what}: expected '{needle}' in: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{what}: one line: {err}");
        assert!(!out.join("small").exists(), "{what}: no results folder");
    }
    // a reference that cannot be run is reported before anything is solved
    let text = SMALL.replace("references = []", r#"references = ["dolfinx"]"#);
    let scene = write_scene(dir.path(), "refs.toml", &text);
    let o = Command::new(env!("CARGO_BIN_EXE_sdcrack"))
        .args(["run", &scene, "--out", out.to_str().unwrap(), "--quiet"])
        .env("SDCRACK_REFERENCES", dir.path().join("no-such-folder"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("reference scripts not found"),
        "{}",
        stderr(&o)
    );
    assert!(!out.join("small").exists());
    let o = sdcrack(&["run", "--delta", "nan"]);
    assert_eq!(o.status.code(), Some(2));
    let o = sdcrack(&["check", &common::scene_path("mixed").display().to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// The terminal table of a scene without [exact] says how much of the crack is open (λ > 0), in
/// words a contact researcher reads right ("active" reads as "in contact").
#[test]
fn the_terminal_table_counts_open_multipliers() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene_path("mixed");
    let out = dir.path().join("res");
    let o = sdcrack_run(
        &scene,
        &out,
        &[
            "--level",
            "1",
            "--u-space",
            "broken",
            "--multiplier",
            "M1",
            "--delta",
            "0",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    let header = text
        .lines()
        .find(|l| l.starts_with("level"))
        .expect("a table");
    assert!(
        header.contains(" open ") && !header.contains("active"),
        "{header}"
    );
}

/// `check` accepts a scene with nothing to judge against but says so: no [exact] and no
/// references leave the compare tool nothing but INCONCLUSIVE.
#[test]
fn check_warns_when_a_scene_has_nothing_to_judge_against() {
    let dir = tempfile::tempdir().unwrap();
    let mixed = std::fs::read_to_string(common::scene_path("mixed")).unwrap();
    let lonely = mixed.replace(r#"references = ["dolfinx", "freefem"]"#, "references = []");
    assert_ne!(lonely, mixed);
    for (text, warned) in [(&lonely, true), (&mixed, false)] {
        let scene = write_scene(dir.path(), "s.toml", text);
        let o = sdcrack(&["check", &scene]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(
            err.contains("nothing to judge its errors against"),
            warned,
            "{err}"
        );
    }
}

/// `check` warns of a scene whose levels cannot give a rate verdict (fewer than the compare
/// tool's three), naming the levels to list, and not of one with three.
#[test]
fn check_warns_when_the_levels_cannot_give_a_rate_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let mixed = std::fs::read_to_string(common::scene_path("mixed")).unwrap();
    let listed = "levels = [0, 1, 2, 3, 4]";
    assert!(mixed.contains(listed), "scenes/mixed.toml lists levels 0-4");
    for (levels, warned) in [
        ("[1, 2]", Some("list levels 1 to 3 at least")),
        ("[3]", Some("list levels 3 to 5 at least")),
        ("[0, 1, 2]", None),
    ] {
        let text = mixed.replace(listed, &format!("levels = {levels}"));
        let scene = write_scene(dir.path(), "s.toml", &text);
        let o = sdcrack(&["check", &scene]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(
            err.contains("a rate needs 3 levels"),
            warned.is_some(),
            "{err}"
        );
        if let Some(advice) = warned {
            assert!(err.contains(advice), "{err}");
            assert_eq!(err.lines().count(), 1, "one line: {err}");
        }
    }
}

#[test]
fn closed_stdout_is_not_a_panic() {
    use std::process::{Command, Stdio};
    // `sdcrack bench --json | head -0`: the reader is gone before anything is written.
    for args in [
        &["bench", "--json", "--vertices", "100"][..],
        &["bench", "--vertices", "100"][..],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sdcrack"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(
            !err.contains("panicked") && err.is_empty(),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn help_lists_the_allowed_values() {
    let o = sdcrack(&["run", "--help"]);
    assert_eq!(o.status.code(), Some(0));
    let help = String::from_utf8_lossy(&o.stdout);
    for word in ["continuous", "broken", "M0", "M1", "M1star"] {
        assert!(help.contains(word), "{help}");
    }
}

#[test]
fn an_unsupported_dolfinx_is_refused_before_solving() {
    // A reference script that reports an unsupported dolfinx, as references/dolfinx/solve.py
    // does for anything but 0.5.x (tested in references/tests/test_dolfinx_version.py).
    let dir = tempfile::tempdir().unwrap();
    let refs = dir.path().join("refs");
    std::fs::create_dir_all(refs.join("dolfinx")).unwrap();
    std::fs::write(
        refs.join("dolfinx/solve.py"),
        "import sys\nprint('dolfinx reference: dolfinx 0.7.0 is not supported (supported: 0.5.x)', file=sys.stderr)\nsys.exit(2)\n",
    )
    .unwrap();
    let text = SMALL.replace("references = []", "references = [\"dolfinx\"]");
    let scene = write_scene(dir.path(), "small.toml", &text);
    let out = dir.path().join("res");
    let o = Command::new(env!("CARGO_BIN_EXE_sdcrack"))
        .args(["run", &scene, "--out", out.to_str().unwrap(), "--quiet"])
        .env("SDCRACK_REFERENCES", &refs)
        .output()
        .unwrap();
    let err = stderr(&o);
    if err.contains("is not available") {
        eprintln!("skipped: dolfinx is not installed here ({err})");
        return;
    }
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("reference 'dolfinx' cannot run here: dolfinx reference: dolfinx 0.7.0 is not supported"),
        "{err}"
    );
    assert!(!out.join("small").exists());
}

#[test]
fn lumped_p_mass_runs_alone_and_is_named_in_the_results() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "small.toml", SMALL);
    let out = dir.path().join("res");
    let args = "--p-mass lumped --u-space broken --multiplier M1";
    let (_, folder, summary) = run_small(&scene, &out, args);
    assert_eq!(summary["plan"]["p_masses"], serde_json::json!(["lumped"]));
    for c in summary["cases"].as_array().unwrap() {
        assert_eq!(c["p_mass"], "lumped");
        assert_eq!(c["converged"], true, "{c}");
        let series = c["fields_series"].as_str().unwrap();
        assert!(series.ends_with("-M1-lumped.series.xdmf"), "{series}");
        assert!(folder.join(series).is_file());
    }
    let f = hdf5::File::open(folder.join("fields.h5")).unwrap();
    let case = f.group("cases/level1-broken-M1-lumped-delta0").unwrap();
    assert!(
        case.link_exists("p") && !case.link_exists("p_bubble"),
        "no bubble when lumped"
    );
    let o = sdcrack(&["run", &scene, "--p-mass", "diagonal"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("expected consistent or lumped"),
        "{}",
        stderr(&o)
    );
}

/// `--p-space broken-tangential` alone: the plan, the cases and the field names say so, `check
/// --json` lists the scene's p spaces, and the stored p is the broken-tangential field: at every
/// interior node of the crack (y = 0, ν = (0, 1)) the + and − copies hold the same p·ν = p_y and,
/// where the crack opens, different p·τ = p_x (the default scene's load opens it for x > 0).
#[test]
fn broken_tangential_p_runs_alone_and_its_field_jumps_only_tangentially() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "small.toml", SMALL);
    let o = sdcrack(&["check", &scene, "--json"]);
    let plan: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(plan["p_spaces"], serde_json::json!(["continuous"]));
    let out = dir.path().join("res");
    let args = "--p-space broken-tangential --multiplier M1 --delta 0";
    let (_, folder, summary) = run_small(&scene, &out, args);
    assert_eq!(
        summary["plan"]["p_spaces"],
        serde_json::json!(["broken-tangential"])
    );
    let cases = summary["cases"].as_array().unwrap();
    assert_eq!(
        cases.len(),
        2,
        "levels 0, 1 of broken u; no continuous u case"
    );
    for c in cases {
        assert_eq!(
            (&c["p_space"], &c["u_space"]),
            (&"broken-tangential".into(), &"broken".into())
        );
        assert!(c["fields_grid"]
            .as_str()
            .unwrap()
            .ends_with("-M1-ptangential-delta0"));
    }
    let f = hdf5::File::open(folder.join("fields.h5")).unwrap();
    let case = f
        .group("cases/level1-broken-M1-ptangential-delta0")
        .unwrap();
    let attr = case
        .attr("p_space")
        .unwrap()
        .read_scalar::<hdf5::types::VarLenUnicode>();
    assert_eq!(attr.unwrap().as_str(), "broken-tangential");
    // the case's own mesh (a soft link to /meshes/KEY)
    let points = case
        .dataset("mesh/points")
        .unwrap()
        .read_2d::<f64>()
        .unwrap();
    let p = case.dataset("p").unwrap().read_2d::<f64>().unwrap();
    let n = points.nrows();
    let (mut shared, mut jumps) = (0, 0);
    for i in 0..n {
        for j in i + 1..n {
            let same = (0..2).all(|d| points[[i, d]] == points[[j, d]]);
            if !same {
                continue;
            }
            // a crack vertex and its − copy: p·ν (p_y) shared, p·τ (p_x) may jump
            assert!((p[[i, 1]] - p[[j, 1]]).abs() <= 1e-13 * p[[i, 1]].abs().max(1.0));
            shared += 1;
            if (p[[i, 0]] - p[[j, 0]]).abs() > 1e-6 {
                jumps += 1;
            }
        }
    }
    assert_eq!(shared, 3, "the interior nodes of the level-1 crack");
    assert!(
        jumps >= 1,
        "the open part of the crack has a tangential jump"
    );
}

#[test]
fn bench_json_reports_the_lumped_case_beside_the_consistent_one() {
    let o = sdcrack(&["bench", "--json", "--vertices", "400"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "case_s",
        "case_lumped_s",
        "case_lumped_peak_rss_mb",
        "sweep_lumped_s",
        "sweep_lumped_factorization_s",
    ] {
        assert!(
            r[key].as_f64().is_some_and(|v| v > 0.0),
            "{key}: {}",
            r[key]
        );
    }
    assert!(r["case_lumped_phases"]["factorization"].as_f64().is_some());
    assert_eq!(r["all_converged"], true);
    // the bench's three goals, each with its bound and the measured ratio recomputed here
    let y = r["bare_cholesky_s"].as_f64().unwrap();
    let goals = r["goals"].as_array().expect("goals");
    let ratio = |k: &str, d: f64| r[k].as_f64().unwrap() / d;
    let expected = [
        (3.0, ratio("case_lumped_s", y)),
        (
            3.0,
            ratio(
                "case_lumped_peak_rss_mb",
                r["yardstick_peak_rss_mb"].as_f64().unwrap(),
            ),
        ),
        (
            1.3,
            ratio(
                "sweep_lumped_s",
                r["sweep_lumped_factorization_s"].as_f64().unwrap(),
            ),
        ),
    ];
    assert_eq!(goals.len(), expected.len());
    for (g, (bound, measured)) in goals.iter().zip(expected) {
        assert_eq!(g["bound"].as_f64(), Some(bound), "{g}");
        // serde_json's default float parsing may be 1 ulp off the printed value
        let got = g["measured"].as_f64().expect("measured");
        assert!(
            (got - measured).abs() <= 1e-12 * measured,
            "{g}: {measured}"
        );
        assert_eq!(g["met"].as_bool(), Some(measured <= bound), "{g}");
    }
}

/// `check --json`'s `memory_mb` of a graded scene counts the graded meshes, which have more cells
/// than the level-0 grid times 4^level (open-graded's level 5: 1.8 times; l-shape-graded's 2.5):
/// each level's estimate is above the peak memory Snakemake measured for the heaviest solver job
/// of that level in the nightly campaign of 2026-11-26 (results/nightly/benchmarks, max_rss in
/// MB; levels 4 and 5, the only ones long enough to be sampled), where the grid's estimate of
/// before was below two of them (728 MB against open-graded's 835, 926 against l-shape-graded's
/// 1572).
#[test]
fn memory_estimates_of_graded_scenes_count_the_graded_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, measured) in [
        ("open-graded", [(4, 199.2), (5, 835.0)]),
        ("l-shape-graded", [(4, 354.2), (5, 1572.5)]),
        ("open-exact", [(4, 109.0), (5, 393.0)]),
    ] {
        let text = std::fs::read_to_string(root.join(format!("scenes/{name}.toml"))).unwrap();
        let start = text.find("\nlevels = ").unwrap() + 1;
        let end = start + text[start..].find('\n').unwrap();
        let text = format!(
            "{}levels = [0, 1, 2, 3, 4, 5]{}",
            &text[..start],
            &text[end..]
        );
        let scene = write_scene(dir.path(), &format!("{name}.toml"), &text);
        let o = sdcrack(&["check", &scene, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let plan: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        for (level, peak_mb) in measured {
            let estimate = plan["memory_mb"][level.to_string()].as_f64().unwrap();
            assert!(
                estimate > peak_mb,
                "{name} level {level}: estimate {estimate} MB below the measured {peak_mb} MB"
            );
        }
    }
}

/// Every scene of the repository (scenes/, tools/untuned-scenes/, the template) and of the tests
/// (tests/data/scenes/) passes the exact-data check of `sdcrack check` (issue 42): it refuses only
/// real inconsistencies. (The bad ones, tests/data/scenes/bad-exact/, are refused in
/// tests/bad_input.rs; the compare tool's synthetic fixtures pass compare/tests/test_exact_data.py.)
#[test]
fn every_scene_of_the_repository_and_the_tests_passes_the_exact_data_check() {
    use sdcrack_core::scene::{exact_data, Scene};
    use sdcrack_io::scene_file::TomlScene;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![
        root.join("docs/scene-template.toml"),
        root.join("docs/scene-template-elasticity.toml"),
    ];
    for dir in ["scenes", "tools/untuned-scenes", "tests/data/scenes"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_str().unwrap().to_string();
            if name.ends_with(".toml") && name != "expectations.toml" && name != "orders.toml" {
                files.push(p);
            }
        }
    }
    let mut exact = 0;
    for f in &files {
        let s = Scene::from_file(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        exact += usize::from(s.has_exact());
        exact_data::check(&s).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
    }
    assert!(
        exact >= 9,
        "{exact} scenes with [exact] among {}",
        files.len()
    );
}

/// A fake reference `tool` under `dir/refs` (SDCRACK_REFERENCES) that writes its command line
/// to OUT/argv.json, with a fake `FreeFem++` under `dir/bin` for the availability check.
fn fake_reference(dir: &Path, tool: &str) -> (PathBuf, String) {
    use std::os::unix::fs::PermissionsExt;
    let refs = dir.join("refs");
    std::fs::create_dir_all(refs.join(tool)).unwrap();
    std::fs::write(
        refs.join(tool).join("solve.py"),
        "import json, os, sys\nout = sys.argv[sys.argv.index('--out') + 1]\nos.makedirs(out)\n\
         json.dump(sys.argv, open(os.path.join(out, 'argv.json'), 'w'))\n",
    )
    .unwrap();
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let ff = bin.join("FreeFem++");
    std::fs::write(&ff, "#!/bin/sh\nexit 0\n").unwrap();
    std::fs::set_permissions(&ff, std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    (refs, path)
}

/// An elastic scene's run: no solver case (summary.json marks the problem, lists no case and no
/// recomputation file), the mesh export with the elastic scene.json, and each listed reference
/// run as `solve.py EXPORT --out RESULTS/<tool>` with `--fields` when `fields = ["u"]`;
/// `--level` selects a level, and an existing results folder is refused, as for a scalar scene.
#[test]
fn an_elastic_scene_runs_its_references_on_its_mesh_export() {
    let dir = tempfile::tempdir().unwrap();
    let text = include_str!("data/scenes/elastic-compressed.toml");
    let (refs, path) = fake_reference(dir.path(), "freefem");
    let run = |text: &str, out: &Path, extra: &[&str]| {
        let scene = write_scene(dir.path(), "elastic.toml", text);
        Command::new(env!("CARGO_BIN_EXE_sdcrack"))
            .args(["run", &scene, "--out", out.to_str().unwrap(), "--quiet"])
            .args(extra)
            .env("SDCRACK_REFERENCES", &refs)
            .env("PATH", &path)
            .output()
            .unwrap()
    };
    // without references: the scene's copy and summary.json only
    let out = dir.path().join("none");
    let o = run(text, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let folder = out.join("elastic-compressed");
    let mut files: Vec<String> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(files, ["scene.toml", "summary.json"]);
    let s = summary(&folder);
    assert_eq!(s["problem"], "elasticity");
    assert_eq!(s["cases"], serde_json::json!([]));
    assert_eq!(s["plan"]["levels"], serde_json::json!([0, 1]));
    assert!(s.get("recomputation_file").is_none(), "{s}");
    assert_eq!(
        std::fs::read_to_string(folder.join("scene.toml")).unwrap(),
        text
    );
    let again = run(text, &out, &[]);
    assert_eq!(again.status.code(), Some(2), "{}", stderr(&again));
    assert!(
        stderr(&again).contains("already exists"),
        "{}",
        stderr(&again)
    );
    // with a reference, fields ["u"], one level
    let listed = text.replace("references = []", "references = [\"freefem\"]");
    let out = dir.path().join("one");
    let o = run(&listed, &out, &["--level", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let folder = out.join("elastic-compressed");
    assert_eq!(summary(&folder)["plan"]["levels"], serde_json::json!([1]));
    let mesh = folder.join("mesh");
    assert!(mesh.join("level1").is_dir() && !mesh.join("level0").exists());
    let scene_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(mesh.join("scene.json")).unwrap()).unwrap();
    assert_eq!(scene_json["problem"]["kind"], "elasticity");
    assert_eq!(scene_json["problem"]["plane"], "strain");
    assert_eq!(scene_json["g"], serde_json::json!(["0.1*x", "-0.1*y"]));
    assert_eq!(
        scene_json["exact"]["sif"],
        serde_json::json!([[0.0, 0.0], [0.0, 0.0]])
    );
    let argv: Vec<String> =
        serde_json::from_str(&std::fs::read_to_string(folder.join("freefem/argv.json")).unwrap())
            .unwrap();
    assert!(argv[0].ends_with("freefem/solve.py"), "{argv:?}");
    assert!(
        argv[1].ends_with("/mesh") && argv[3].ends_with("/freefem"),
        "{argv:?}"
    );
    assert_eq!(&argv[2..], ["--out", &argv[3], "--fields"]);
    // fields [] runs it without --fields
    let no_fields = listed.replace("fields = [\"u\"]", "fields = []");
    let out = dir.path().join("bare");
    let o = run(&no_fields, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let argv: Vec<String> = serde_json::from_str(
        &std::fs::read_to_string(out.join("elastic-compressed/freefem/argv.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(argv.len(), 4, "{argv:?}");
}

/// `sdcrack check` and `sdcrack scene --template elasticity` know the elastic problem kind.
#[test]
fn check_and_the_template_know_the_elastic_kind() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("tests/data/scenes/elastic-compressed.toml");
    let o = sdcrack(&["check", scene.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let line = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        line.contains("valid elastic scene 'elastic-compressed' (levels [0, 1], references []"),
        "{line}"
    );
    let o = sdcrack(&["check", "--json", scene.to_str().unwrap()]);
    let plan: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (plan["cases"].as_u64(), &plan["levels"]),
        (Some(0), &serde_json::json!([0, 1]))
    );
    let o = sdcrack(&["scene", "--template", "elasticity"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        include_str!("../docs/scene-template-elasticity.toml")
    );
    let o = sdcrack(&["scene", "--template"]);
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        include_str!("../docs/scene-template.toml")
    );
}
