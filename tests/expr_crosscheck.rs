//! The Rust expression evaluator agrees with the Python translator used by the references
//! (compare/sdshared/sdexpr.py) at random points and on both crack faces (y = ±0.0), and both
//! report the same parse errors at the same columns. The table is written by
//! references/tests/make_expr_cases.py from the Python side.

use sdcrack_core::expr::Expr;

#[test]
fn rust_and_python_evaluators_agree() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/references/tests/expr_cases.json"
    );
    let table: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let values = table["values"].as_array().unwrap();
    assert!(values.len() >= 300);
    for v in values {
        let src = v["expr"].as_str().unwrap();
        let (x, y) = (v["x"].as_f64().unwrap(), v["y"].as_f64().unwrap());
        let got = Expr::parse(src).unwrap().eval(x, y);
        match v["value"].as_f64() {
            None => {
                let want = v["value"].as_str().unwrap();
                let same = match want {
                    "inf" => got == f64::INFINITY,
                    "-inf" => got == f64::NEG_INFINITY,
                    _ => got.is_nan(),
                };
                assert!(same, "{src} at ({x}, {y}): Rust {got}, Python {want}");
            }
            Some(want) => assert!(
                (got - want).abs() <= 1e-13 * want.abs().max(1.0),
                "{src} at ({x:?}, {y:?}): Rust {got}, Python {want}"
            ),
        }
    }
    for e in table["errors"].as_array().unwrap() {
        let src = e["expr"].as_str().unwrap();
        let err = Expr::parse(src).unwrap_err();
        assert_eq!(err.message, e["message"].as_str().unwrap(), "{src:?}");
        assert_eq!(err.column as u64, e["column"].as_u64().unwrap(), "{src:?}");
    }
}
