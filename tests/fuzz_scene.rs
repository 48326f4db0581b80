//! Property test of the scene loader [`Scene::from_toml`] (TOML parsing and validation): on 100 000
//! random and mutated inputs it never panics, and every error it returns displays as one line
//! without control characters (the CLI prints it as the one line on stderr).
//!
//! Inputs, from a seeded xorshift generator (deterministic, no dependency): the repository scenes
//! mutated by byte flips, insertions of TOML-ish tokens, deletions, line duplications and swaps,
//! values replaced by random tokens, and splices of two scenes; plus random token soups and a few
//! pathological texts (deep nesting, the size limit). `cargo fuzz` targets doing the same without
//! a budget are in `fuzz/` (docs/fuzzing.md).

use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};

use sdcrack::scene::{Scene, TomlScene, MAX_SCENE_BYTES};

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

/// Tokens that mean something to TOML or to the scene validator.
const TOKENS: &[&str] = &[
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
    "name",
    "description",
    "geometry",
    "data",
    "exact",
    "discretization",
    "outputs",
    "domain",
    "crack",
    "rectangle",
    "segment",
    "f",
    "g",
    "u",
    "px",
    "py",
    "jump",
    "cells",
    "levels",
    "u_spaces",
    "multipliers",
    "p_mass",
    "p_spaces",
    "deltas",
    "fields",
    "references",
    "\"M0\"",
    "\"M1\"",
    "\"M1star\"",
    "\"continuous\"",
    "\"broken\"",
    "\"broken-tangential\"",
    "\"lumped\"",
    "\"u\"",
    "\"p\"",
    "\"lambda\"",
    "\"dolfinx\"",
    "\"freefem\"",
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

/// A random TOML value: number, string, array or inline table, sometimes nested.
fn random_value(rng: &mut Rng, depth: usize) -> String {
    match rng.below(if depth > 3 { 4 } else { 7 }) {
        0 => rng.pick(TOKENS).to_string(),
        1 => format!("{}", (rng.next() as i64) >> rng.below(64)),
        2 => format!("{:e}", f64::from_bits(rng.next())),
        3 => format!("\"{}\"", rng.pick(TOKENS).replace('"', "")),
        4 | 5 => {
            let n = rng.below(4);
            let items: Vec<String> = (0..n).map(|_| random_value(rng, depth + 1)).collect();
            format!("[{}]", items.join(", "))
        }
        _ => {
            let n = rng.below(3);
            let items: Vec<String> = (0..n)
                .map(|_| format!("{} = {}", rng.pick(TOKENS), random_value(rng, depth + 1)))
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
fn mutate(rng: &mut Rng, s: &str, seeds: &[String]) -> String {
    match rng.below(8) {
        // flip one bit of one byte (invalid UTF-8 is replaced, as a file read would refuse it)
        0 if !s.is_empty() => {
            let mut b = s.as_bytes().to_vec();
            let k = rng.below(b.len());
            b[k] ^= 1 << rng.below(8);
            String::from_utf8_lossy(&b).into_owned()
        }
        // insert a token
        1 => {
            let k = boundary(s, rng.below(s.len() + 1));
            format!("{}{}{}", &s[..k], rng.pick(TOKENS), &s[k..])
        }
        // delete a range
        2 if !s.is_empty() => {
            let a = boundary(s, rng.below(s.len()));
            let b = boundary(s, a + 1 + rng.below(16));
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
            let i = *rng.pick(&with_value);
            let key = lines[i].split('=').next().unwrap_or("").to_string();
            lines[i] = format!("{key}= {}", random_value(rng, 0));
            lines.join("\n")
        }
        // duplicate or drop a line, or swap two
        5 => {
            let mut lines: Vec<&str> = s.lines().collect();
            if lines.is_empty() {
                return s.to_string();
            }
            let i = rng.below(lines.len());
            let j = rng.below(lines.len());
            match rng.below(3) {
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
            let other = rng.pick(seeds);
            let a = boundary(s, rng.below(s.len() + 1));
            let b = boundary(other, rng.below(other.len() + 1));
            format!("{}{}", &s[..a], &other[b..])
        }
        // a run of random tokens somewhere
        _ => {
            let k = boundary(s, rng.below(s.len() + 1));
            let soup: String = (0..1 + rng.below(6)).map(|_| *rng.pick(TOKENS)).collect();
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
            assert!(
                scene.case_count() > 0,
                "valid scene without cases: {text:?}"
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
    let mut rng = Rng(0x5EED_5CE4_E10A_D3E5);
    let mut valid = 0usize;
    let mut kinds = BTreeSet::new();
    const N: usize = 100_000;
    for i in 0..N {
        let text = if i % 10 == 9 {
            // token soup
            (0..rng.below(40)).map(|_| *rng.pick(TOKENS)).collect()
        } else {
            let mut s = rng.pick(&seeds).clone();
            for _ in 0..1 + rng.below(3) {
                s = mutate(&mut rng, &s, &seeds);
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
