//! `verification.h5`: whatever a scene's `[outputs] fields` lists, a results folder keeps what
//! the compare tool recomputes the errors from. With u, p and λ listed that is `fields.h5`;
//! otherwise the run also writes `verification.h5`: the HDF5 layout of `fields.h5` with every
//! quantity, bit for bit the datasets and attributes a run with all fields writes, and no XDMF.

mod common;

use std::path::{Path, PathBuf};

use serde_json::Value;

use common::{assert_same_h5, h5_contents, sdcrack_run, stderr, summary};

/// The small scene with both p masses (the lumped one has no p bubble) and `fields`.
fn scene_text(fields: &str) -> String {
    common::SMALL_SCENE
        .replace(
            "deltas = [1e-2, 0.0]",
            "deltas = [1e-2, 0.0]\np_mass = [\"consistent\", \"lumped\"]",
        )
        .replace(
            r#"fields = ["u", "p", "lambda"]"#,
            &format!("fields = {fields}"),
        )
}

/// Runs the small scene with `fields` into `dir/<tag>`; returns the results folder.
fn run(dir: &Path, tag: &str, fields: &str) -> PathBuf {
    let scene = dir.join(format!("{tag}.toml"));
    std::fs::write(&scene, scene_text(fields)).unwrap();
    let out = dir.join(tag);
    let o = sdcrack_run(&scene, &out, &["--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    out.join("small")
}

/// The summary without what describes the process or the XDMF series.
fn numbers(mut s: Value) -> Value {
    let o = s.as_object_mut().unwrap();
    for key in [
        "provenance",
        "wall_s",
        "fields_write_s",
        "recomputation_file",
    ] {
        o.remove(key);
    }
    for c in o["cases"].as_array_mut().unwrap() {
        let c = c.as_object_mut().unwrap();
        c.remove("timings_s");
        c.remove("fields_series");
        c.remove("fields_state");
    }
    s
}

#[test]
fn a_scene_without_all_fields_keeps_them_in_verification_h5() {
    let dir = tempfile::tempdir().unwrap();
    let full = run(dir.path(), "full", r#"["u", "p", "lambda"]"#);
    let none = run(dir.path(), "none", "[]");
    let only_u = run(dir.path(), "only-u", r#"["u"]"#);

    // all fields: fields.h5 is the recomputation file, no verification.h5
    assert_eq!(
        common::listing(&full),
        ["fields", "fields.h5", "scene.toml", "summary.json"]
    );
    let s_full = summary(&full);
    assert_eq!(s_full["recomputation_file"], "fields.h5");
    let reference = h5_contents(&full.join("fields.h5"));

    // no fields: verification.h5 alone, no fields.h5, no series folder, no XDMF
    assert_eq!(
        common::listing(&none),
        ["scene.toml", "summary.json", "verification.h5"]
    );
    let s_none = summary(&none);
    assert_eq!(s_none["recomputation_file"], "verification.h5");
    assert_same_h5(&h5_contents(&none.join("verification.h5")), &reference);

    // u only: fields.h5 with u only and its series, plus verification.h5 with everything
    assert_eq!(
        common::listing(&only_u),
        [
            "fields",
            "fields.h5",
            "scene.toml",
            "summary.json",
            "verification.h5"
        ]
    );
    let s_u = summary(&only_u);
    assert_eq!(s_u["recomputation_file"], "verification.h5");
    assert_same_h5(&h5_contents(&only_u.join("verification.h5")), &reference);
    let u_only = h5_contents(&only_u.join("fields.h5"));
    let datasets = |c: &[(String, Vec<u64>)], leaf: &str| {
        c.iter()
            .filter(|(p, _)| !p.contains('@') && p.ends_with(leaf))
            .count()
    };
    assert_eq!(datasets(&u_only, "/u"), 48);
    for leaf in ["/p", "/p_bubble", "/lambda"] {
        assert_eq!(datasets(&u_only, leaf), 0, "{leaf} not asked for");
    }
    for (path, values) in u_only.iter().filter(|(p, _)| !p.contains('@')) {
        let (_, want) = reference.iter().find(|(p, _)| p == path).unwrap();
        assert!(
            values == want,
            "{path} differs from the run with all fields"
        );
    }

    // every case's group in the recomputation file: u, p, λ, and p's bubbles for the
    // consistent p mass only
    let cases_full = s_full["cases"].as_array().unwrap();
    assert_eq!(cases_full.len(), 48);
    for (s, folder) in [(&s_full, &full), (&s_none, &none), (&s_u, &only_u)] {
        let name = s["recomputation_file"].as_str().unwrap();
        let file = hdf5::File::open(folder.join(name)).unwrap();
        for c in s["cases"].as_array().unwrap() {
            let g = file
                .group(&format!("cases/{}", c["fields_grid"].as_str().unwrap()))
                .unwrap();
            for name in ["u", "p", "crack/lambda", "crack/points", "mesh/points"] {
                let ds = g.dataset(name).unwrap();
                assert!(ds.dtype().unwrap().is::<f64>(), "{name}: float64");
            }
            let consistent = c["p_mass"] == "consistent";
            assert_eq!(g.link_exists("p_bubble"), consistent, "{c}");
            if consistent {
                assert!(g.dataset("p_bubble").unwrap().dtype().unwrap().is::<f64>());
            }
        }
    }
    // fields_series only with the XDMF series; the same numbers in every summary
    for c in s_none["cases"].as_array().unwrap() {
        assert!(c.get("fields_series").is_none(), "{c}");
    }
    for c in s_u["cases"].as_array().unwrap() {
        let series = c["fields_series"].as_str().unwrap();
        assert!(only_u.join(series).is_file(), "{series}");
    }
    assert_eq!(numbers(s_full.clone()), numbers(s_none));
    assert_eq!(numbers(s_full), numbers(s_u));
}
