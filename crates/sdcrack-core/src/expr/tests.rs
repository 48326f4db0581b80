use super::*;
use std::f64::consts::PI;

use fastrand::Rng;

fn p(s: &str) -> Expr {
    match Expr::parse(s) {
        Ok(e) => e,
        Err(e) => panic!("failed to parse {s:?}: {e}"),
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    if a.is_nan() && b.is_nan() {
        return true;
    }
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn sgn(v: f64) -> f64 {
    super::tree::sign(v)
}

const LONG: &str =
    "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)";

type Case = (&'static str, fn(f64, f64) -> f64);

fn eval_cases() -> Vec<Case> {
    vec![
        ("20*sin(2*pi*x)*sign(y)", |x, y| {
            20.0 * (2.0 * PI * x).sin() * sgn(y)
        }),
        (LONG, |x, y| {
            let r = (((x - 0.5).powi(2) + y * y) * ((x + 0.5).powi(2) + y * y))
                .sqrt()
                .sqrt();
            r * ((y.atan2(x - 0.5) + y.atan2(x + 0.5)) / 2.0).sin()
        }),
        ("1 + 2*x - y/4", |x, y| 1.0 + 2.0 * x - y / 4.0),
        ("x^2 + y^3", |x, y| x.powi(2) + y.powi(3)),
        ("exp(-x*x) * cos(y)", |x, y| (-x * x).exp() * y.cos()),
        ("log(1 + x^2) / sqrt(2 + y^2)", |x, y| {
            (1.0 + x * x).ln() / (2.0 + y * y).sqrt()
        }),
        ("abs(x - y) + tan(x/3)", |x, y| {
            (x - y).abs() + (x / 3.0).tan()
        }),
        ("min(x, y) * max(x, 2*y)", |x, y| x.min(y) * x.max(2.0 * y)),
        ("atan2(y, x)", |x, y| y.atan2(x)),
        ("2.5e-1*x + .5*y - 1e-3", |x, y| 0.25 * x + 0.5 * y - 1e-3),
        ("(x+1)^0.5 + 2^x", |x, _| (x + 1.0).powf(0.5) + 2f64.powf(x)),
        ("-x^2 + +y", |x, y| -(x * x) + y),
        (" pi * ( x - y ) ", |x, y| PI * (x - y)),
        ("x/y/2", |x, y| x / y / 2.0),
    ]
}

#[test]
fn evaluates_against_closures() {
    let pts = [
        (0.3, 0.7),
        (1.2, -0.4),
        (-0.8, 0.25),
        (2.0, 1.5),
        (0.1, -2.0),
    ];
    for (src, f) in eval_cases() {
        let e = p(src);
        assert_eq!(e.source(), src);
        for &(x, y) in &pts {
            let (a, b) = (e.eval(x, y), f(x, y));
            assert!(close(a, b, 1e-13), "{src} at ({x},{y}): {a} vs {b}");
        }
    }
}

#[test]
fn signed_zero_sides() {
    let s = p("sign(y)");
    assert_eq!(s.eval(0.0, 0.0), 1.0);
    assert_eq!(s.eval(0.0, -0.0), -1.0);
    assert_eq!(s.eval(0.0, 3.0), 1.0);
    assert_eq!(s.eval(0.0, -3.0), -1.0);
    assert!(s.eval(0.0, f64::NAN).is_nan());
    let a = p("atan2(y,-1)");
    assert_eq!(a.eval(0.0, 0.0), PI);
    assert_eq!(a.eval(0.0, -0.0), -PI);
    // The crack-tip function is discontinuous across y = 0 for x < 0.5.
    let l = p(LONG);
    assert!(l.eval(0.0, 0.0) > 0.0 && l.eval(0.0, -0.0) < 0.0);
}

#[test]
fn precedence_and_associativity() {
    let cases: [(&str, f64); 12] = [
        ("-2^2", -4.0),
        ("2^3^2", 512.0),
        ("2^-1", 0.5),
        ("-2^-2", -0.25),
        ("2*3+4", 10.0),
        ("2+3*4", 14.0),
        ("8/4/2", 1.0),
        ("8-4-2", 2.0),
        ("2*3^2", 18.0),
        ("(2+3)*4", 20.0),
        ("--2", 2.0),
        ("1-+-1", 2.0),
    ];
    for (src, want) in cases {
        assert_eq!(p(src).eval(0.0, 0.0), want, "{src}");
    }
    assert_eq!(p("-x^2").eval(3.0, 0.0), -9.0);
    assert_eq!(p("x^y^2").eval(2.0, 3.0), 512.0);
    assert_eq!(p("x - y - 1").eval(5.0, 1.0), 3.0);
}

#[test]
fn constants_and_is_constant() {
    let c = Expr::constant(2.5);
    assert_eq!(c.eval(1.0, 2.0), 2.5);
    assert!(c.is_constant());
    assert!(p("2*pi + sin(1)").is_constant());
    assert!(!p("2*pi + y").is_constant());
    for v in [
        -0.0,
        1e-300,
        -3.25,
        1e300,
        f64::INFINITY,
        f64::NEG_INFINITY,
        PI,
    ] {
        let r = Expr::constant(v).to_string_infix();
        let back = p(&r).eval(0.0, 0.0);
        assert_eq!(back.to_bits(), v.to_bits(), "{v} rendered as {r}");
    }
    assert!(p(&Expr::constant(f64::NAN).to_string_infix())
        .eval(0.0, 0.0)
        .is_nan());
}

/// A number in `[lo, hi)`.
fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.f64()
}

#[test]
fn derivatives_match_finite_differences() {
    let srcs = shared_derivative_cases();
    assert!(srcs.contains(&LONG));
    let mut rng = Rng::with_seed(0x9E3779B97F4A7C15);
    let h = 1e-6;
    for src in srcs {
        let e = p(src);
        let dx = e.derivative(Var::X);
        let dy = e.derivative(Var::Y);
        // The derivative's source is its printable rendering.
        assert_eq!(dx.source(), dx.to_string_infix());
        let mut checked = 0;
        while checked < 20 {
            let (x, y) = (uniform(&mut rng, 0.3, 1.6), uniform(&mut rng, 0.35, 1.5));
            // stay away from kinks of abs/sign/min/max and jumps of sign
            let kinks = [
                x - y,
                x * x - y,
                2.0 - x,
                (3.0 * x).sin(),
                (2.0 * x % 1.0) - 0.5,
                x - 1.2,
                y - 0.9,
            ];
            if kinks.iter().any(|k| k.abs() < 1e-2) {
                continue;
            }
            checked += 1;
            let fdx = (e.eval(x + h, y) - e.eval(x - h, y)) / (2.0 * h);
            let fdy = (e.eval(x, y + h) - e.eval(x, y - h)) / (2.0 * h);
            let (ax, ay) = (dx.eval(x, y), dy.eval(x, y));
            assert!(
                (fdx - ax).abs() <= 1e-6 * (1.0 + ax.abs()),
                "d/dx {src} at ({x},{y}): fd {fdx} vs {ax} [{}]",
                dx.source()
            );
            assert!(
                (fdy - ay).abs() <= 1e-6 * (1.0 + ay.abs()),
                "d/dy {src} at ({x},{y}): fd {fdy} vs {ay} [{}]",
                dy.source()
            );
        }
    }
}

#[test]
fn derivative_simplification() {
    let d = |s: &str, v| p(s).derivative(v).to_string_infix();
    assert_eq!(d("x", Var::X), "1");
    assert_eq!(d("x", Var::Y), "0");
    assert_eq!(d("3*x + 2", Var::X), "3");
    assert_eq!(d("x^2", Var::X), "(2 * x)");
    assert_eq!(d("sin(y)", Var::X), "0");
    assert_eq!(d("sign(x)", Var::X), "0");
    assert_eq!(d("x*y", Var::Y), "x");
    assert!(p("x*y").derivative(Var::X).derivative(Var::X).is_constant());
    // The second derivative of min with both branches linear collapses to 0.
    assert!(d("min(x, 2*x)", Var::X).contains("sign"));
    let dd = p("min(x, 2*x)").derivative(Var::X).derivative(Var::X);
    assert_eq!(dd.to_string_infix(), "0");
}

#[test]
fn render_round_trip() {
    let mut srcs: Vec<&str> = eval_cases().iter().map(|c| c.0).collect();
    srcs.extend([
        "-2^2",
        "2^3^2",
        "1/x*y",
        "-(x+y)",
        "x^-2",
        "--x",
        "sign(-0*y)",
    ]);
    let mut rng = Rng::with_seed(12345);
    for src in srcs {
        let e = p(src);
        let r = e.to_string_infix();
        let back = p(&r);
        assert_eq!(back.to_string_infix(), r, "rendering is a fixed point");
        for _ in 0..50 {
            let (x, y) = (uniform(&mut rng, -3.0, 3.0), uniform(&mut rng, -3.0, 3.0));
            for (x, y) in [(x, y), (x, 0.0), (x, -0.0)] {
                let (a, b) = (e.eval(x, y), back.eval(x, y));
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{src} -> {r} at ({x},{y}): {a} vs {b}"
                );
            }
        }
        // Derivatives (including min/max selections) render to equivalent text too.
        for var in [Var::X, Var::Y] {
            let d = e.derivative(var);
            let back = p(&d.to_string_infix());
            for _ in 0..20 {
                let (x, y) = (uniform(&mut rng, -3.0, 3.0), uniform(&mut rng, -3.0, 3.0));
                let (a, b) = (d.eval(x, y), back.eval(x, y));
                assert!(
                    close(a, b, 1e-14) || !a.is_finite(),
                    "d {src}: {} at ({x},{y}): {a} vs {b}",
                    d.source()
                );
            }
        }
    }
}

fn err(src: &str) -> ExprError {
    match Expr::parse(src) {
        Ok(_) => panic!("{src:?} should not parse"),
        Err(e) => e,
    }
}

/// The rows of the one list of a table shared with the Python translator's test
/// (references/tests/test_sdexpr.py), in the layout those files keep: one row a line between
/// the line opening the list (`"key": [`) and the line `]`, each but the last ending in a comma.
fn shared_rows(table: &'static str) -> Vec<&'static str> {
    let rows: Vec<&str> = table
        .lines()
        .map(str::trim)
        .skip_while(|line| !line.ends_with('['))
        .skip(1)
        .take_while(|line| *line != "]")
        .map(|line| line.strip_suffix(',').unwrap_or(line))
        .collect();
    assert!(rows.len() >= 10, "a shared table of {} rows", rows.len());
    rows
}

/// The parse errors of references/tests/expr_error_cases.json as (source, 1-based column,
/// message), from rows `["source", column, "message"]`.
fn shared_error_cases() -> Vec<(&'static str, usize, &'static str)> {
    let table = include_str!("../../../../references/tests/expr_error_cases.json");
    let case = |row: &'static str| {
        let (source, rest) = json_string(row.strip_prefix('[')?.strip_suffix(']')?)?;
        let (column, rest) = rest.strip_prefix(',')?.split_once(',')?;
        let (message, rest) = json_string(rest.trim_start())?;
        let column = column.trim().parse().ok()?;
        rest.is_empty().then_some((source, column, message))
    };
    shared_rows(table)
        .into_iter()
        .map(|row| case(row).unwrap_or_else(|| panic!("expr_error_cases.json: row {row}")))
        .collect()
}

/// The expressions of references/tests/expr_derivative_cases.json, one string a row.
fn shared_derivative_cases() -> Vec<&'static str> {
    let table = include_str!("../../../../references/tests/expr_derivative_cases.json");
    shared_rows(table)
        .into_iter()
        .map(|row| match json_string(row) {
            Some((source, "")) => source,
            _ => panic!("expr_derivative_cases.json: row {row}"),
        })
        .collect()
}

/// A JSON string without escapes at the start of `s`: its text and what follows it.
fn json_string(s: &str) -> Option<(&str, &str)> {
    let (text, rest) = s.strip_prefix('"')?.split_once('"')?;
    (!text.contains('\\')).then_some((text, rest))
}

#[test]
fn error_messages() {
    let long = "x+".repeat(5000) + "x";
    let deep = "(".repeat(201) + "x" + &")".repeat(201);
    for (src, col, msg) in shared_error_cases() {
        let e = err(src);
        assert_eq!((e.column, e.message.as_str()), (col, msg), "input {src:?}");
    }
    assert!(Expr::parse("x + 1.").is_ok(), "\"1.\" is a valid number");
    let e = err(&long);
    assert!(e
        .message
        .starts_with("expression longer than 10000 characters"));
    assert_eq!(e.column, 10001);
    let e = err(&deep);
    assert_eq!(e.message, "expression nested deeper than 200 levels");
    assert_eq!(e.column, 201);
    let ok = "(".repeat(200) + "x" + &")".repeat(200);
    assert_eq!(p(&ok).eval(4.0, 0.0), 4.0);
    let e = err(&format!("{}x", "2^".repeat(201)));
    assert_eq!(e.message, "expression nested deeper than 200 levels");
    assert_eq!(
        format!("{}", err("z")),
        "unknown variable 'z' (expected x, y or pi) at column 1"
    );
    // A very long but flat expression is fine (no deep tree).
    let flat = "x-".repeat(4999) + "x";
    assert_eq!(p(&flat).eval(1.0, 0.0), -4998.0);
}

#[test]
fn deepest_inputs_differentiate_and_render() {
    for src in [
        "x^(".repeat(99) + "x" + &")".repeat(99),
        "sin(".repeat(200) + "x" + &")".repeat(200),
        "exp(1+".repeat(199) + "x" + &")".repeat(199),
        "(1+".repeat(200) + "x" + &")".repeat(200),
    ] {
        let e = p(&src);
        assert!(e.eval(0.9, 0.1).is_finite() || src.starts_with("exp"));
        let d = e.derivative(Var::X);
        let _ = d.eval(0.9, 0.1);
        assert!(!d.to_string_infix().is_empty());
    }
    let d2 = p(&("(1+".repeat(200) + "x*x" + &")".repeat(200)))
        .derivative(Var::X)
        .derivative(Var::X);
    assert_eq!(d2.to_string_infix(), "2");
}

#[test]
fn no_panic_on_random_inputs() {
    let seeds = [
        "20*sin(2*pi*x)*sign(y)",
        LONG,
        "min(x, y) + max(x*x, y) * atan2(y, x)^2",
        "-x^-2 + exp(log(abs(y)))/tan(.5e1)",
        "((x))*(((y)))",
    ];
    let alphabet: Vec<char> = "0123456789.eE+-*/^(),xyzpisnqrtabgexmlc \t$_"
        .chars()
        .collect();
    let mut rng = Rng::with_seed(0xDEADBEEF12345678);
    let mut parsed = 0;
    for i in 0..100_000 {
        let s: String = if i % 2 == 0 {
            let mut v: Vec<char> = seeds[rng.usize(..seeds.len())].chars().collect();
            for _ in 0..1 + rng.usize(..4) {
                let c = alphabet[rng.usize(..alphabet.len())];
                match rng.usize(..3) {
                    0 => {
                        let k = rng.usize(..v.len() + 1);
                        v.insert(k, c);
                    }
                    1 if !v.is_empty() => {
                        let k = rng.usize(..v.len());
                        v.remove(k);
                    }
                    _ if !v.is_empty() => {
                        let k = rng.usize(..v.len());
                        v[k] = c;
                    }
                    _ => v.push(c),
                }
            }
            v.into_iter().collect()
        } else {
            let len = rng.usize(..24);
            (0..len)
                .map(|_| alphabet[rng.usize(..alphabet.len())])
                .collect()
        };
        if let Ok(e) = Expr::parse(&s) {
            parsed += 1;
            let _ = e.eval(0.5, -0.0);
            let _ = e.eval(f64::NAN, f64::INFINITY);
            if i % 16 == 0 {
                let d = e.derivative(Var::X);
                let _ = d.eval(0.25, 0.75);
                let _ = Expr::parse(&d.to_string_infix());
            }
        }
    }
    assert!(parsed > 1000, "only {parsed} inputs parsed");
    for pathological in [
        "(".repeat(100_000),
        "(".repeat(9_999),
        "-".repeat(9_999) + "x",
        "sin(".repeat(3000),
        "2^".repeat(5000) + "2",
        "1e".to_string() + &"9".repeat(9000),
    ] {
        assert!(Expr::parse(&pathological).is_err() || pathological.starts_with('-'));
    }
    assert_eq!(p(&("-".repeat(9_999) + "x")).eval(2.0, 0.0), -2.0);
}
