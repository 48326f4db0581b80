//! Unit tests of the scene module: positions in the text, toml's errors in words, the schema
//! derived from the structs, the template, the memory limits.

use super::position::{key_position, line_column};
use super::schema::{schema, Kind, ALLOWED, WORDS};
use super::toml_error::{header_before, key_on_line};
use super::*;
use sdcrack_core::scene::{check_level, estimated_memory_bytes, Level0Size, MAX_LEVEL};
use sdcrack_core::scene::{KeyPath, Scene};

/// The key path written `a.b[1].c` (for the tests' literals).
fn path(written: &str) -> KeyPath {
    let mut out = KeyPath::root();
    for part in written.split('.') {
        let (key, index) = match part.split_once('[') {
            Some((k, i)) => (k, i.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        out = out.key(key);
        if let Some(i) = index {
            out = out.index(i);
        }
    }
    out
}

/// Where a value error points: a key of a table, a dotted key, a key of an inline table, a
/// key in the second of an array of tables, a table header; nothing for an absent key.
#[test]
fn key_positions_in_the_scene_text() {
    let text = "name = \"x\"\n\n[data]\nf = \"1\"\n  g = \"0\"\n[discretization]\n\
                grading = { beta = 0.5, radius = 0.25 }\nlevels = [0, 1]\n\
                [[verification.expected_failure]]\nu_space = \"continuous\"\n\
                [[verification.expected_failure]]\nmultiplier = \"M0\"\nu_space = \"broken\"\n";
    let expected = [
        ("name", Some((1, 1))),
        ("data.f", Some((4, 1))),
        ("data.g", Some((5, 3))),
        ("data", Some((3, 1))),
        ("discretization.grading", Some((7, 1))),
        ("discretization.grading.radius", Some((7, 25))),
        ("discretization.levels", Some((8, 1))),
        ("verification.expected_failure[0].u_space", Some((10, 1))),
        ("verification.expected_failure[1].u_space", Some((13, 1))),
        ("verification.expected_failure[1]", Some((11, 1))),
        ("discretization.deltas", None),
        ("geometry", None),
    ];
    for (key, at) in expected {
        assert_eq!(key_position(text, &path(key)), at, "{key}");
    }
    let nan = SceneError::named(path("data.g"), "data.g = \"0\" evaluates to NaN");
    assert_eq!(
        nan.located(text).to_string(),
        "invalid scene: data.g = \"0\" evaluates to NaN (at line 5, column 3)"
    );
    let missing = SceneError::key(path("discretization"), KeyRole::Missing("cells".into()), "");
    assert_eq!(
        missing.located(text).to_string(),
        "invalid scene: missing key `cells` in [discretization] (the table is at line 6, column 1)"
    );
    let plain = SceneError::Scene("no key here".into());
    assert_eq!(
        plain.located(text).to_string(),
        "invalid scene: no key here"
    );
}

/// The templates are valid scenes (the scalar one and the elastic one), together they name
/// every table and key (commented or not), and their optional tables, uncommented, are valid
/// too.
#[test]
fn template_is_a_valid_scene_naming_every_key() {
    let scene = Scene::from_toml(SCENE_TEMPLATE).expect("template parses");
    assert_eq!(scene.name, "my-crack");
    assert!(scene.scalar().is_some());
    let elastic = Scene::from_toml(ELASTIC_SCENE_TEMPLATE).expect("elastic template parses");
    assert!(elastic.elasticity().is_some_and(|d| d.exact.is_some()));
    let both = format!("{SCENE_TEMPLATE}\n{ELASTIC_SCENE_TEMPLATE}");
    let schema = schema();
    for t in &schema.tables {
        let (table, keys) = (&t.table, t.key_names());
        let last = table.rsplit('.').next().unwrap_or(table);
        let named = both.contains(&format!("[{table}]"))
            || both.contains(&format!("{last} = {{"))
            || both.contains(&format!("{last} = [{{"));
        assert!(table.is_empty() || named, "templates lack [{table}]");
        for key in keys {
            assert!(
                both.contains(&format!("{key} ="))
                    || schema.tables.iter().any(|t| t.table.ends_with(key)),
                "templates lack `{key}` of [{table}]"
            );
        }
    }
    // the elastic template's alternatives, uncommented: (λ, μ), an all-traction body held at
    // two corners, the stress given
    let lame = ELASTIC_SCENE_TEMPLATE
        .replace("\nE = 1.0", "\n")
        .replace("\nnu = 0.3", "\n")
        .replace("# lambda = ", "lambda = ")
        .replace("# mu = ", "mu = ")
        .replace("# friction = ", "friction = ");
    let m = Scene::from_toml(&lame)
        .expect("lambda, mu")
        .elasticity()
        .unwrap()
        .material;
    assert_eq!((m.lambda, m.mu), (0.5, 0.4));
    let free = ELASTIC_SCENE_TEMPLATE
        .replace("\ngx = ", "\n# gx = ")
        .replace("\ngy = ", "\n# gy = ")
        .replace(
            "# traction = { top = [\"0\", \"-0.1\"], bottom = [\"0\", \"-0.1\"] }",
            "traction = { top = [\"0\", \"-0.1\"], bottom = [\"0\", \"0.1\"], left = [\"0\", \"0\"], right = [\"0\", \"0\"] }",
        )
        .replace("# fixed = ", "fixed = ")
        .replace("# sxx = \"...\"", "sxx = \"0\"")
        .replace("# syy = \"...\"", "syy = \"0\"")
        .replace("# sxy = \"...\"", "sxy = \"0\"");
    let d = Scene::from_toml(&free)
        .expect("all traction")
        .elasticity()
        .cloned()
        .unwrap();
    assert!(d.g.is_none());
    assert_eq!((d.tractions.len(), d.fixed.len()), (4, 2));
    // Uncomment the optional [exact] and expected-failure blocks: still a valid scene.
    let full = SCENE_TEMPLATE
        .replace("# [exact]", "[exact]")
        .replace("# u = \"...\"", "u = \"sin(pi*x)\"")
        .replace("# [[verification", "[[verification")
        .replace("# u_space = ", "u_space = ")
        .replace(
            "u_spaces = [\"broken\"]",
            "u_spaces = [\"continuous\", \"broken\"]",
        )
        .replace("# reason = ", "reason = ")
        .replace("# rate = ", "rate = ")
        .replace("# check = ", "check = ");
    let scene = Scene::from_toml(&full).expect("template with its options parses");
    assert!(scene.has_exact());
}

/// Peak resident memory measured with `/usr/bin/time -f %M` for
/// `sdcrack run scenes/mixed.toml --level L --u-space broken --multiplier M1 --delta 0`
/// (cells [8, 8]; docs/design.md): the estimate must stay above each.
#[test]
fn memory_estimate_is_above_measured_peaks_and_admits_the_nightly() {
    for (level, peak_kib) in [(3u32, 135_612u64), (4, 165_316), (5, 507_484)] {
        let estimate = estimated_memory_bytes(Level0Size::Grid([8, 8]), level);
        assert!(
            estimate > peak_kib * 1024,
            "level {level}: estimate {estimate} B below the measured {peak_kib} KiB"
        );
    }
    // ci/nightly runs every repository scene up to level 5: cells [8, 8] and [16, 8].
    for cells in [[8, 8], [16, 8]] {
        for level in 0..=5 {
            assert_eq!(
                check_level(Level0Size::Grid(cells), level),
                Ok(()),
                "{cells:?} level {level}"
            );
        }
    }
    let refused = check_level(Level0Size::Grid([8, 8]), 8).unwrap_err();
    assert!(refused.contains("more than the 16 GiB limit"), "{refused}");
    assert!(check_level(Level0Size::Grid([1, 1]), MAX_LEVEL + 1).is_err());
    assert_eq!(
        estimated_memory_bytes(Level0Size::Grid([4096, 4096]), 64),
        u64::MAX
    );
}

#[test]
fn toml_errors_name_table_key_line_and_column() {
    let scene = DEFAULT_SCENE.replacen("levels =", "levles =", 1);
    let e = Scene::from_toml(&scene).unwrap_err().to_string();
    assert!(
        e.contains("unknown key `levles` in [discretization] at line")
            && e.contains("did you mean `levels`?"),
        "{e}"
    );
    let scene = DEFAULT_SCENE.replacen("cells = [8, 8]", "cells = [8, \"8\"]", 1);
    let e = Scene::from_toml(&scene).unwrap_err().to_string();
    assert!(
        e.contains("discretization.cells must be two integers [nx, ny], not the string \"8\""),
        "{e}"
    );
    assert_eq!(line_column("ab\ncδe", 6), (2, 3));
    assert_eq!(
        line_column("ab\ncδe", 5),
        (2, 2),
        "inside δ: snapped to its start"
    );
    assert_eq!(
        key_on_line("x = { rectangle = [1", 18),
        Some("rectangle".into())
    );
    assert_eq!(key_on_line("[data]", 3), None);
    assert_eq!(header_before("a = 1\n[data]\nf = 2\n[x.y]\n", 14), "data");
    assert_eq!(header_before("a = 1\n[data]\n", 2), "");
}

/// A syntax error names the table it is in, except a key set twice, whose message (toml's)
/// names its table already: told by the lines before, which set the key in that table.
#[test]
fn a_key_set_twice_is_told_from_the_lines_before() {
    let message = |edit: &str| {
        let scene = DEFAULT_SCENE.replacen("cells = [8, 8]\n", edit, 1);
        Scene::from_toml(&scene).unwrap_err().to_string()
    };
    let twice = message("cells = [8, 8]\ncells = [4, 4]\n");
    assert!(
        twice.contains("duplicate key `cells` in table `discretization` (at line"),
        "{twice}"
    );
    let bare = message("cells = [8, 8]\nlevels [0]\n");
    assert!(bare.contains(" in [discretization] (at line"), "{bare}");
    // the key after the bad token is set before, but the error is not at a key: not twice
    let after = message("cells = [8, 8]\nmesh_size cells = 1\n");
    assert!(after.contains(" in [discretization] (at line"), "{after}");
}

#[test]
fn messages_escape_control_characters() {
    let scene = DEFAULT_SCENE.replacen("name = \"mixed\"", "name = \"a\\r\\nb\"", 1);
    let e = Scene::from_toml(&scene).unwrap_err().to_string();
    assert!(e.contains(r#"name "a\r\nb" must be"#), "{e}");
    assert!(!e.chars().any(char::is_control), "{e:?}");
}

/// The schema is the structs': every table with its keys in field order, each key's type.
#[test]
fn schema_is_read_off_the_structs() {
    let s = schema();
    let top = s.table("").expect("top level");
    assert_eq!(
        &top.key_names()[..4],
        ["name", "description", "problem", "geometry"]
    );
    let traction = s.key("data", "traction").expect("traction");
    assert_eq!(traction.type_name, "table of list of string");
    assert_eq!(
        s.key("problem", "kind").expect("kind").values,
        ["scalar", "elasticity"]
    );
    let grading = s.table("discretization.grading").expect("grading");
    assert_eq!(grading.key_names(), ["beta", "radius"]);
    assert!(grading.keys.iter().all(|k| *k.kind() == Kind::Number));
    let cells = s.key("discretization", "cells").expect("cells");
    assert_eq!(cells.type_name, "list of integer");
    assert_eq!(cells.words, "two integers [nx, ny]");
    let rectangle = s.key("geometry.domain", "rectangle").expect("rectangle");
    assert_eq!(rectangle.type_name, "list of list of number");
    let u_spaces = s.key("discretization", "u_spaces").expect("u_spaces");
    assert_eq!(
        u_spaces.words,
        "a list of names from \"continuous\", \"broken\""
    );
    assert_eq!(u_spaces.values, ["continuous", "broken"]);
    let smoke = s.key("verification", "smoke").expect("smoke");
    assert_eq!(
        (smoke.type_name.as_str(), smoke.words.as_str()),
        ("bool", "true or false")
    );
    for table in [
        "geometry.crack",
        "geometry.cracks",
        "verification.expected_rate",
    ] {
        assert!(s.table(table).is_some(), "{table}");
    }
    let json: serde_json::Value = serde_json::from_str(&s.to_json()).expect("JSON");
    assert_eq!(json["vocabulary"]["quantities"][0], "u_l2");
}

/// What is kept beside the structs names keys the structs have.
#[test]
fn allowed_names_and_words_name_keys_of_the_schema() {
    let s = schema();
    for (path, names) in ALLOWED {
        let (table, key) = path.rsplit_once('.').expect("table.key");
        assert!(s.key(table, key).is_some(), "ALLOWED names {path}");
        assert!(!names.is_empty(), "{path}");
    }
    let keys = s.key_names();
    for (key, _) in WORDS {
        assert!(keys.contains(key), "WORDS names {key}");
    }
}

/// An error of the structs carries the key path of the element it is in (an inline table of
/// an array, the second of an array of tables) and the span of the value.
#[test]
fn errors_of_the_structs_carry_their_key_path() {
    let raw_error = |text: &str| {
        let doc = toml_edit::ImDocument::parse(text).unwrap();
        document::from_document::<raw::SceneToml>(&doc)
            .err()
            .expect(text)
    };
    let text = "[geometry]\ncracks = [{ segment = [[0, 0], [1, 0]] }, { polyline = 2 }]\n";
    let e = raw_error(text);
    assert_eq!(e.path, path("geometry.cracks[1].polyline"));
    assert_eq!(e.span.map(|s| s.start), text.find("2 }"));
    assert!(
        matches!(&e.fault, document::Fault::WrongType { found, .. } if found == "the integer 2")
    );
    let text = "[[verification.expected_rate]]\nrate = 1.0\nreason = \"r\"\n\
                [[verification.expected_rate]]\nrate = \"x\"\n";
    let e = raw_error(text);
    assert_eq!(e.path, path("verification.expected_rate[1].rate"));
    assert_eq!(e.span.map(|s| s.start), text.find("\"x\""));
    let text = "[data]\nf = \"1\"\nh = \"2\"\n";
    let e = raw_error(text);
    assert_eq!(e.fault, document::Fault::UnknownKey("h".into()));
    assert_eq!(e.path, path("data.h"));
    assert_eq!(e.span.map(|s| s.start), text.find("h ="));
    let e = raw_error("name = \"n\"\n[discretization]\ncells = [2, 2]\n");
    assert_eq!(e.fault, document::Fault::MissingKey("levels"));
    assert_eq!(e.path, path("discretization"));
    let text = "[discretization]\nlevels = [0, 1.5]\n";
    let e = raw_error(text);
    assert_eq!(e.path, path("discretization.levels[1]"));
    assert!(
        matches!(&e.fault, document::Fault::WrongType { found, .. } if found == "the number 1.5")
    );
}

/// docs/scenes.md's table of keys, `(table, row)`: each row's first cell under the
/// `**[table]**` row it follows (`""` before the first).
fn documented_rows() -> Vec<(String, String)> {
    let docs = include_str!("../../../../docs/scenes.md");
    let table = docs
        .split("## Tables and keys")
        .nth(1)
        .and_then(|rest| rest.split("\n\n").nth(1))
        .expect("docs/scenes.md has its table of keys");
    let mut current = String::new();
    let mut rows = Vec::new();
    for row in table.lines().skip(2) {
        let first = row.split('|').nth(1).unwrap_or("").trim();
        if let Some(header) = first.strip_prefix("**`[") {
            current = header.trim_matches(['[', ']', '`', '*']).to_string();
            continue;
        }
        rows.push((current.clone(), row.to_string()));
    }
    rows
}

/// The names in backquotes of a row's first cell (`px`, `py` → both).
fn row_keys(row: &str) -> Vec<String> {
    let first = row.split('|').nth(1).unwrap_or("");
    first
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// docs/scenes.md documents exactly the schema's keys: each table with a `**[table]**` row has
/// one row per key that is not a documented table itself, and the keys of an inline table
/// (`{ beta = β, radius = R }`) are written as `key =` in their parent key's row. A field added
/// to a struct fails here until it is documented.
#[test]
fn docs_table_lists_exactly_the_schema_keys() {
    let schema = schema();
    let rows = documented_rows();
    let headed = |t: &str| t.is_empty() || rows.iter().any(|(table, _)| table == t);
    let child = |t: &str, k: &str| {
        if t.is_empty() {
            k.to_string()
        } else {
            format!("{t}.{k}")
        }
    };
    for t in &schema.tables {
        if headed(&t.table) {
            let mut want: Vec<String> = (t.key_names().into_iter())
                .filter(|k| {
                    !(schema.table(&child(&t.table, k)).is_some() && headed(&child(&t.table, k)))
                })
                .map(str::to_string)
                .collect();
            let mut got: Vec<String> = (rows.iter())
                .filter(|(table, _)| *table == t.table)
                .flat_map(|(_, row)| row_keys(row))
                .collect();
            want.sort();
            got.sort();
            assert_eq!(got, want, "docs/scenes.md rows of [{}]", t.table);
        } else {
            let (parent, key) = t.table.rsplit_once('.').unwrap_or(("", &t.table));
            let row = (rows.iter())
                .find(|(table, row)| table == parent && row_keys(row).iter().any(|k| k == key))
                .map(|(_, row)| row.as_str())
                .unwrap_or_else(|| panic!("docs/scenes.md has no row for {}", t.table));
            for k in t.key_names() {
                assert!(
                    row.contains(&format!("{k} =")),
                    "docs/scenes.md's row of {} does not write `{k} =`",
                    t.table
                );
            }
        }
    }
}

/// An elastic scene as the loader reads it: the material of either pair and plane model, the
/// stress by Hooke's law unless given, the parts of a polygon, no solver case axes, the fields
/// ["u"] by default; a scalar scene is the scalar problem.
#[test]
fn elastic_scenes_are_read_into_the_elastic_problem() {
    use sdcrack_core::elasticity::{hooke_stress, PlaneModel};
    let d = |text: &str| {
        Scene::from_toml(text)
            .unwrap_or_else(|e| panic!("{e}"))
            .elasticity()
            .cloned()
            .expect("elastic")
    };
    let scene = Scene::from_toml(ELASTIC_SCENE_TEMPLATE).unwrap();
    assert_eq!(scene.axes.levels, [0, 1, 2]);
    assert_eq!(scene.axes.case_count(), 0);
    let data = scene.elasticity().unwrap();
    let m = data.material;
    assert!((m.young() - 1.0).abs() < 1e-15 && (m.poisson() - 0.3).abs() < 1e-15);
    assert_eq!(m.plane, PlaneModel::Strain);
    let exact = data.exact.as_ref().unwrap();
    let hooke = hooke_stress(&exact.u, &m).unwrap();
    for (s, h) in exact.stress.iter().zip(&hooke) {
        assert_eq!(s.source(), h.source());
    }
    // σ_yy of u = (0.1 x, −0.1 y): 2μ · (−0.1)
    assert!((exact.stress[1].eval(0.2, 0.3) + 0.2 * m.mu).abs() < 1e-15);
    assert_eq!(exact.sif.len(), 2);
    let stress = ELASTIC_SCENE_TEMPLATE.replace("plane = \"strain\"", "plane = \"stress\"");
    assert_eq!(d(&stress).material.plane, PlaneModel::Stress);
    // no [outputs]: the references' fields ["u"]; no [problem] plane: strain
    let bare = ELASTIC_SCENE_TEMPLATE
        .replace("[outputs]", "# [outputs]")
        .replace("\nfields = ", "\n# fields = ")
        .replace("\nreferences = ", "\n# references = ")
        .replace("plane = \"strain\"", "");
    let s = Scene::from_toml(&bare).unwrap();
    assert!(s.fields.u && !s.fields.p && !s.fields.lambda && s.references.is_empty());
    assert_eq!(s.elasticity().unwrap().material.plane, PlaneModel::Strain);
    // a polygon's parts are edge1 … edgeN
    let polygon = ELASTIC_SCENE_TEMPLATE
        .replace(
            "domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }",
            "domain = { polygon = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]] }",
        )
        .replace("cells = [8, 8]", "mesh_size = 0.5")
        .replace(
            "# traction = { top = [\"0\", \"-0.1\"], bottom = [\"0\", \"-0.1\"] }",
            "traction = { edge3 = [\"0\", \"-0.1\"] }",
        );
    let parts: Vec<String> = d(&polygon)
        .tractions
        .iter()
        .map(|t| t.part.0.clone())
        .collect();
    assert_eq!(parts, ["edge3"]);
    let e = Scene::from_toml(&polygon.replace("edge3 =", "edge5 ="))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "unknown boundary part \"edge5\" (this domain's parts: edge1, edge2, edge3, edge4)"
        ),
        "{e}"
    );
    assert!(Scene::from_toml(SCENE_TEMPLATE).unwrap().scalar().is_some());
}
