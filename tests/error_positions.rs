//! The line and column that `sdcrack` prints for a bad scene point at the offending text: twenty
//! malformed scenes (an unknown key, a missing key, a wrong type, a bad name, a bad number, a bad
//! element deep in `[[verification.expected_rate]]` and in `[geometry] cracks`, inline tables, a
//! key set twice, syntax errors, a crack off the mesh, exact data that is not a solution, data
//! that is NaN during a run), each run through `sdcrack check` (or `run`); the position printed
//! must be where the offending text is in the file, found by searching the file's text here.
//!
//! The positions come from the key path an error carries and toml_edit's spans (or, for a
//! syntax error, the parser's span); this test reads them back the way a user does, off the one
//! line on stderr.

use std::path::Path;
use std::process::Command;

/// The default scene, on which every case makes its edits.
const MIXED: &str = include_str!("../scenes/mixed.toml");

/// A malformed scene: `edits` (each `from` replaced once by `to`) of [`MIXED`], the words the
/// message must have, and where the offending text is: the `nth` (0-based) occurrence of `needle`
/// after the first occurrence of `after` (`""`: from the start).
struct Case {
    name: &'static str,
    edits: Vec<(String, String)>,
    words: &'static str,
    after: &'static str,
    needle: &'static str,
    nth: usize,
    /// `sdcrack run --level 0 …` instead of `sdcrack check`: an error found while solving.
    run: bool,
}

fn case(
    name: &'static str,
    edits: &[(&str, &str)],
    words: &'static str,
    after: &'static str,
    needle: &'static str,
) -> Case {
    Case {
        name,
        edits: (edits.iter())
            .map(|(from, to)| (from.to_string(), to.to_string()))
            .collect(),
        words,
        after,
        needle,
        nth: 0,
        run: false,
    }
}

/// A second `[[verification.expected_rate]]` whose `p_mass`, `rate` or `reason` a case breaks.
const RATES: &str = "u_space = \"continuous\"\nreason = \"r\"\n\n\
    [[verification.expected_rate]]\nquantity = \"u_l2\"\nrate = 1.0\nreason = \"first\"\n\n\
    [[verification.expected_rate]]\nquantity = \"u_l2\"\np_mass = \"lumped\"\nrate = 1.0\nreason = \"second\"\n";

/// Two cracks on the 8×8 grid's lines, as a list of inline tables.
const TWO_CRACKS: &str =
    "cracks = [{ segment = [[-0.5, 0.0], [0.0, 0.0]] }, { segment = [[0.25, 0.5], [0.5, 0.5]] }]";
const ONE_CRACK: &str = "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }";

fn cases() -> Vec<Case> {
    // the expected failure's long reason, replaced so that RATES can follow it
    let long = MIXED
        .split("[[verification.expected_failure]]\n")
        .nth(1)
        .expect("mixed.toml has an expected failure");
    let rates = |from: &str, to: &str| vec![(long.to_string(), RATES.replacen(from, to, 1))];
    vec![
        case(
            "unknown key",
            &[("levels =", "levles =")],
            "unknown key `levles` in [discretization] at line",
            "",
            "levles",
        ),
        case(
            "unknown key in an inline table",
            &[("[1.0, 1.0]] }", "[1.0, 1.0]], rectangel = 1 }")],
            "unknown key `rectangel` in [geometry.domain]",
            "",
            "rectangel",
        ),
        case(
            "missing key",
            &[("g = \"0\"\n", "")],
            "missing key `g` in [data] (the table is at line",
            "",
            "[data]",
        ),
        case(
            "missing key in an array of tables",
            &[(long, "u_space = \"continuous\"\n")],
            "missing key `reason` in [verification.expected_failure[0]] (the table is at line",
            "",
            "[[verification.expected_failure]]",
        ),
        case(
            "wrong type in a list",
            &[("cells = [8, 8]", "cells = [8, \"8\"]")],
            "discretization.cells must be two integers [nx, ny], not the string \"8\"",
            "cells",
            "\"8\"",
        ),
        case(
            "wrong type: a table for a list",
            &[("levels = [0, 1, 2, 3, 4]", "levels = { first = 0 }")],
            "discretization.levels must be a list of integers, not a table",
            "",
            "{ first",
        ),
        case(
            "bad name",
            &[("\"continuous\", \"broken\"]", "\"continuous\", \"brokn\"]")],
            "discretization.u_spaces: unknown value \"brokn\"",
            "",
            "u_spaces",
        ),
        case(
            "bad number",
            &[("deltas = [1.0,", "deltas = [-1.0,")],
            "discretization.deltas: -1 is not a finite number ≥ 0",
            "",
            "deltas",
        ),
        case(
            "level out of range",
            &[("levels = [0, 1, 2, 3, 4]", "levels = [0, 13]")],
            "discretization.levels: level 13 is outside 0..=12",
            "",
            "levels",
        ),
        Case {
            edits: rates("p_mass = \"lumped\"", "p_mass = \"lumpd\""),
            ..case(
                "bad name deep in the expected rates",
                &[],
                "verification.expected_rate[1].p_mass: \"lumpd\" is not among the scene's values",
                "",
                "p_mass = \"lumpd\"",
            )
        },
        Case {
            edits: rates("rate = 1.0\nreason = \"second\"", "rate = \"fast\"\nreason = \"second\""),
            ..case(
                "wrong type deep in the expected rates",
                &[],
                "verification.expected_rate[1].rate must be a number, not the string \"fast\"",
                "",
                "\"fast\"",
            )
        },
        Case {
            nth: 1,
            edits: rates("rate = 1.0\nreason = \"second\"", "rate = 9.0\nreason = \"second\""),
            ..case(
                "bad number deep in the expected rates",
                &[],
                "verification.expected_rate[1].rate = 9 must be a number in (0, 4]",
                "[[verification.expected_rate]]",
                "rate =",
            )
        },
        Case {
            nth: 1,
            ..case(
                "zero-length crack in a list of cracks",
                &[(
                    ONE_CRACK,
                    "cracks = [{ segment = [[-0.5, 0.0], [0.0, 0.0]] }, { segment = [[0.5, 0.5], [0.5, 0.5]] }]",
                )],
                "geometry.cracks[1].segment has zero length",
                "cracks",
                "segment",
            )
        },
        case(
            "wrong type deep in a list of cracks",
            &[(
                ONE_CRACK,
                "cracks = [{ segment = [[-0.5, 0.0], [0.0, 0.0]] }, { segment = [[0.25, 0.5], [\"x\", 0.5]] }]",
            )],
            "geometry.cracks[1].segment must be two end points",
            "cracks",
            "\"x\"",
        ),
        case(
            "bad number in an inline table",
            &[("cells = [8, 8]\n", "cells = [8, 8]\ngrading = { radius = 0.5, beta = 2.0 }\n")],
            "discretization.grading.beta must be in (0, 1]",
            "grading",
            "beta",
        ),
        Case {
            nth: 1,
            ..case(
                "key set twice",
                &[("cells = [8, 8]\n", "cells = [8, 8]\ncells = [4, 4]\n")],
                "duplicate key `cells` in table `discretization`",
                "",
                "cells",
            )
        },
        case(
            "syntax error in a list",
            &[("levels = [0, 1, 2, 3, 4]", "levels = [0, 1 2]")],
            "discretization.levels: invalid array",
            "levels",
            "2]",
        ),
        case(
            "syntax error: a bare word",
            &[("name = \"mixed\"", "name = mixed")],
            "name: invalid string",
            "name",
            "mixed",
        ),
        case(
            "crack off the level-0 mesh",
            &[(ONE_CRACK, "crack = { segment = [[-0.45, 0.0], [0.5, 0.0]] }")],
            "geometry.crack.segment: crack point (-0.45, 0) is not a vertex of the level-0 mesh",
            "crack =",
            "segment",
        ),
        // an element of a list of inline tables is placed at the list's key
        case(
            "crack outside the domain, second of two",
            &[(ONE_CRACK, TWO_CRACKS), ("[0.25, 0.5], [0.5, 0.5]", "[0.25, 0.5], [1.5, 0.5]")],
            "geometry.cracks[1] point 1 (1.5, 0.5) lies outside the domain",
            "",
            "cracks =",
        ),
        case(
            "exact data that is not a solution",
            &[("[discretization]", "[exact]\nu = \"0\"\n\n[discretization]")],
            "data.f is not −Δu of exact.u",
            "[data]",
            "f =",
        ),
        Case {
            run: true,
            ..case(
                "data that is NaN at a quadrature point (found by run)",
                &[("f = \"20*sin(2*pi*x)*sign(y)\"", "f = \"sqrt(x)\"")],
                "data.f = \"sqrt(x)\" evaluates to NaN at the quadrature point",
                "[data]",
                "f =",
            )
        },
    ]
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// Where the case's offending text is in `text`.
fn expected_position(c: &Case, text: &str) -> (usize, usize) {
    let from = text
        .find(c.after)
        .unwrap_or_else(|| panic!("{}: no {:?}", c.name, c.after));
    let offset = (text[from..].match_indices(c.needle))
        .nth(c.nth)
        .map(|(i, _)| from + i)
        .unwrap_or_else(|| panic!("{}: no {:?} number {}", c.name, c.needle, c.nth));
    line_column(text, offset)
}

/// The `at line L, column C` of a message (`(at line …)`, ` at line …` of an unknown key,
/// `(the table is at line …)` of a missing one).
fn printed_position(message: &str) -> Option<(usize, usize)> {
    let rest = &message[message.rfind("at line ")? + "at line ".len()..];
    let (line, rest) = rest.split_once(", column ")?;
    let column: String = rest.chars().take_while(char::is_ascii_digit).collect();
    Some((line.parse().ok()?, column.parse().ok()?))
}

/// Runs `sdcrack check` (or a level-0 run of one case) on the scene file `path`: its stderr.
fn sdcrack(path: &Path, run: bool, out: &Path) -> (Option<i32>, String) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_sdcrack"));
    if run {
        command.args(["run", "--quiet", "--solver-only", "--level", "0"]);
        command.args([
            "--u-space",
            "broken",
            "--multiplier",
            "M0",
            "--p-mass",
            "consistent",
        ]);
        command.args(["--delta", "0", "--out"]).arg(out);
    } else {
        command.arg("check");
    }
    let o = command.arg(path).output().expect("sdcrack runs");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn printed_positions_point_at_the_offending_text() {
    let dir = tempfile::tempdir().unwrap();
    let cases = cases();
    assert_eq!(cases.len(), 22);
    for (i, c) in cases.iter().enumerate() {
        let mut text = MIXED.to_string();
        for (from, to) in &c.edits {
            assert!(text.contains(from), "{}: no {from:?} to edit", c.name);
            text = text.replacen(from.as_str(), to, 1);
        }
        let path = dir.path().join(format!("case{i}.toml"));
        std::fs::write(&path, &text).unwrap();
        let (code, stderr) = sdcrack(&path, c.run, &dir.path().join(format!("out{i}")));
        let message = stderr.trim_end();
        assert_eq!(code, Some(2), "{}: {stderr}", c.name);
        assert_eq!(message.lines().count(), 1, "{}: {stderr}", c.name);
        assert!(message.contains(c.words), "{}: {message}", c.name);
        let expected = expected_position(c, &text);
        assert_eq!(
            printed_position(message),
            Some(expected),
            "{}: the message should point at {:?} (line {}, column {}): {message}",
            c.name,
            c.needle,
            expected.0,
            expected.1
        );
    }
}

/// The check of this test can fail: a position one column off, or on another line, is told
/// from the right one, and a message without a position has none.
#[test]
fn a_wrong_position_is_told() {
    let text = "a = 1\nbb = [1, \"x\"]\n";
    let c = case("t", &[], "", "bb", "\"x\"");
    assert_eq!(expected_position(&c, text), (2, 10));
    let printed = |m: &str| printed_position(m);
    assert_eq!(printed("k must be … (at line 2, column 10)"), Some((2, 10)));
    assert_ne!(printed("k must be … (at line 2, column 9)"), Some((2, 10)));
    assert_ne!(printed("k must be … (at line 1, column 10)"), Some((2, 10)));
    assert_eq!(printed("missing table [data]"), None);
}
