//! Property test of the scene loader [`Scene::from_toml`] (TOML parsing and validation): on 100 000
//! random and mutated inputs it never panics, and every error it returns displays as one line
//! without control characters (the CLI prints it as the one line on stderr).
//!
//! Inputs, from a seeded generator (fastrand, deterministic for its seed): the repository scenes
//! mutated by byte flips, insertions of TOML-ish tokens and of the schema's keys and names,
//! deletions, line duplications and swaps, values replaced by random tokens, and splices of two
//! scenes; plus random token soups and a few pathological texts (deep nesting, the size limit). `cargo fuzz` targets doing the same without
//! a budget are in `fuzz/` (docs/fuzzing.md).

use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};

use sdcrack_core::scene::Scene;
use sdcrack_io::scene_file::{TomlScene, MAX_SCENE_BYTES};

/// The seeded generator of the inputs (fastrand's wyrand: deterministic for a seed).
type Rng = fastrand::Rng;

/// A random element of `v`.
fn pick<'a, T>(rng: &mut Rng, v: &'a [T]) -> &'a T {
    &v[rng.usize(..v.len())]
}

/// A random number in `0..n` (0 when `n` is 0).
fn below(rng: &mut Rng, n: usize) -> usize {
    rng.usize(..n.max(1))
}

/// Tokens that mean something to TOML or to an expression; [`tokens`] adds the scene's keys.
const SYNTAX: &[&str] = &[
    "[",
    "]",
    "{",
    "}",
    "=",
    ",",
    ".",
    "\"",
    "'",
    "\n",
    "\r\n",
    "#",
    " ",
    "\t",
    "[[",
    "]]",
    "\"\"\"",
    "'''",
    "\\",
    "\\n",
    "\\u0000",
    "\\u00e9",
    "\\U0010FFFF",
    "\\x",
    "nan",
    "+nan",
    "-nan",
    "inf",
    "-inf",
    "0",
    "-0.0",
    "1",
    "-1",
    "2",
    "4",
    "8",
    "4096",
    "4097",
    "1e308",
    "1e309",
    "-1e-400",
    "9223372036854775807",
    "9223372036854775808",
    "0x10",
    "0o7",
    "0b1",
    "1_000",
    "1__0",
    "0.5",
    "-0.5",
    ".5",
    "5.",
    "1979-05-27T07:32:00Z",
    "true",
    "false",
    "\"x\"",
    "\"sin(x)*y\"",
    "\"log(x)\"",
    "\"1/(x-x)\"",
    "\"atan2(y,\"",
    "x",
    "y",
    "pi",
    "sin(",
    ")",
    "(",
    "*",
    "^",
    "/",
    "δ",
    "é",
    "\u{0}",
    "\u{7f}",
    "\u{2028}",
    "\u{feff}",
];

/// Every token the inputs are made of: [`SYNTAX`], every key of the scene schema (the loader's
/// own structs, as `sdcrack schema` prints them) and every name a key allows, quoted.
fn tokens() -> Vec<String> {
    let schema = sdcrack_io::scene_file::schema::schema();
    let keys = schema.key_names().into_iter().map(str::to_string);
    let names = (schema.tables.iter())
        .flat_map(|t| &t.keys)
        .flat_map(|k| k.values.iter().map(|v| format!("\"{v}\"")));
    let mut out: Vec<String> = SYNTAX.iter().map(|t| t.to_string()).collect();
    for t in keys.chain(names) {
        if !out.contains(&t) {
            out.push(t);
        }
    }
    out
}

/// A random TOML value: number, string, array or inline table, sometimes nested.
fn random_value(rng: &mut Rng, tokens: &[String], depth: usize) -> String {
    match below(rng, if depth > 3 { 4 } else { 7 }) {
        0 => pick(rng, tokens).clone(),
        1 => format!("{}", (rng.u64(..) as i64) >> below(rng, 64)),
        2 => format!("{:e}", f64::from_bits(rng.u64(..))),
        3 => format!("\"{}\"", pick(rng, tokens).replace('"', "")),
        4 | 5 => {
            let n = below(rng, 4);
            let items: Vec<String> = (0..n)
                .map(|_| random_value(rng, tokens, depth + 1))
                .collect();
            format!("[{}]", items.join(", "))
        }
        _ => {
            let n = below(rng, 3);
            let items: Vec<String> = (0..n)
                .map(|_| {
                    format!(
                        "{} = {}",
                        pick(rng, tokens),
                        random_value(rng, tokens, depth + 1)
                    )
                })
                .collect();
            format!("{{ {} }}", items.join(", "))
        }
    }
}

/// Byte offset in `s` snapped down to a character boundary.
fn boundary(s: &str, mut k: usize) -> usize {
    k = k.min(s.len());
    while !s.is_char_boundary(k) {
        k -= 1;
    }
    k
}

/// One mutation of `s`.
fn mutate(rng: &mut Rng, tokens: &[String], s: &str, seeds: &[String]) -> String {
    match below(rng, 8) {
        // flip one bit of one byte (invalid UTF-8 is replaced, as a file read would refuse it)
        0 if !s.is_empty() => {
            let mut b = s.as_bytes().to_vec();
            let k = below(rng, b.len());
            b[k] ^= 1 << below(rng, 8);
            String::from_utf8_lossy(&b).into_owned()
        }
        // insert a token
        1 => {
            let k = boundary(s, below(rng, s.len() + 1));
            format!("{}{}{}", &s[..k], pick(rng, tokens), &s[k..])
        }
        // delete a range
        2 if !s.is_empty() => {
            let a = boundary(s, below(rng, s.len()));
            let b = boundary(s, a + 1 + below(rng, 16));
            format!("{}{}", &s[..a], &s[b.max(a)..])
        }
        // replace the value of one `key = value` line
        3 | 4 => {
            let mut lines: Vec<String> = s.lines().map(str::to_string).collect();
            let with_value: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains('='))
                .collect();
            if with_value.is_empty() {
                return s.to_string();
            }
            let i = *pick(rng, &with_value);
            let key = lines[i].split('=').next().unwrap_or("").to_string();
            lines[i] = format!("{key}= {}", random_value(rng, tokens, 0));
            lines.join("\n")
        }
        // duplicate or drop a line, or swap two
        5 => {
            let mut lines: Vec<&str> = s.lines().collect();
            if lines.is_empty() {
                return s.to_string();
            }
            let i = below(rng, lines.len());
            let j = below(rng, lines.len());
            match below(rng, 3) {
                0 => lines.insert(j, lines[i]),
                1 => {
                    lines.remove(i);
                }
                _ => lines.swap(i, j),
            }
            lines.join("\n")
        }
        // splice: the start of this text, the end of another scene
        6 => {
            let other = pick(rng, seeds);
            let a = boundary(s, below(rng, s.len() + 1));
            let b = boundary(other, below(rng, other.len() + 1));
            format!("{}{}", &s[..a], &other[b..])
        }
        // a run of random tokens somewhere
        _ => {
            let k = boundary(s, below(rng, s.len() + 1));
            let soup: String = (0..1 + below(rng, 6))
                .map(|_| pick(rng, tokens).as_str())
                .collect();
            format!("{}{soup}{}", &s[..k], &s[k..])
        }
    }
}

/// The repository scenes (and `expectations.toml`, which is TOML but no scene).
fn seeds() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut out: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    out.sort();
    assert!(out.len() >= 7, "scenes/*.toml: {}", out.len());
    out
}

/// Runs the loader on `text`: panics are failures, errors must be one clean line.
/// Returns `Some(first words of the error)`, or `None` when the scene is valid.
fn load(text: &str) -> Option<String> {
    let result = catch_unwind(AssertUnwindSafe(|| Scene::from_toml(text)));
    match result {
        Err(_) => panic!("the scene loader panicked on {text:?}"),
        Ok(Ok(scene)) => {
            // an elastic scene has no solver case until issue 46: its levels are its work
            assert!(
                scene.axes.case_count() > 0 || scene.elasticity().is_some(),
                "valid scene without cases: {text:?}"
            );
            assert!(
                !scene.axes.levels.is_empty(),
                "valid scene without levels: {text:?}"
            );
            None
        }
        Ok(Err(e)) => {
            let message = e.to_string();
            assert!(!message.is_empty(), "empty message for {text:?}");
            assert!(
                !message.chars().any(char::is_control),
                "message is not one clean line: {message:?}\nfor input {text:?}"
            );
            Some(message.split([':', '`', '"']).take(2).collect())
        }
    }
}

#[test]
fn scene_loader_never_panics_and_errors_are_one_line() {
    let start = std::time::Instant::now();
    let seeds = seeds();
    for s in &seeds {
        if !s.contains("[expect") {
            // sanity: the starting points are valid scenes (expectations.toml is not one)
            let _ = load(s);
        }
    }
    let tokens = tokens();
    let mut rng = Rng::with_seed(0x5EED_5CE4_E10A_D3E5);
    let mut valid = 0usize;
    let mut kinds = BTreeSet::new();
    const N: usize = 100_000;
    for i in 0..N {
        let text = if i % 10 == 9 {
            // token soup
            (0..below(&mut rng, 40))
                .map(|_| pick(&mut rng, &tokens).as_str())
                .collect()
        } else {
            let mut s = pick(&mut rng, &seeds).clone();
            for _ in 0..1 + below(&mut rng, 3) {
                s = mutate(&mut rng, &tokens, &s, &seeds);
            }
            s
        };
        match load(&text) {
            None => valid += 1,
            Some(kind) => {
                kinds.insert(kind);
            }
        }
    }
    // Pathological texts: deep nesting of arrays and inline tables, the size limit.
    let deep_array = format!("name = {}1{}", "[".repeat(50_000), "]".repeat(50_000));
    let deep_table = format!("name = {}1{}", "{a = ".repeat(50_000), "}".repeat(50_000));
    let long_key = format!("{} = 1", "k".repeat(500_000));
    let too_big = format!("{}\n# {}", seeds[0], "x".repeat(MAX_SCENE_BYTES));
    let nested_headers = "[a.".repeat(20_000) + "b]";
    for text in [deep_array, deep_table, long_key, too_big, nested_headers] {
        assert!(load(&text).is_some(), "accepted: {:.80}", text);
    }
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{N} inputs in {seconds:.1} s: {valid} valid scenes, {} kinds of error",
        kinds.len()
    );
    // The mutations must reach validation, not only the TOML parser.
    assert!(
        valid > 2_000,
        "only {valid} mutated inputs were valid scenes"
    );
    assert!(
        kinds.len() > 50,
        "only {} kinds of error: {kinds:?}",
        kinds.len()
    );
}
