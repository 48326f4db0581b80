//! libFuzzer target: the expression grammar (`Expr::parse`), evaluation and symbolic derivatives.
//! Parsing must never panic; a parsed expression must evaluate and differentiate without panicking,
//! and printing and re-parsing its derivative must not panic either (re-parsing may fail: large
//! derivatives can exceed the parser's length and nesting limits, as `to_string_infix` documents).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sdcrack_core::expr::{Expr, Var};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Expr::parse(text) {
        Ok(e) => {
            let _ = e.eval(0.5, -0.0);
            let _ = e.eval(f64::NAN, f64::INFINITY);
            // Derivatives grow with the input; keep each run short.
            if text.len() <= 256 {
                for var in [Var::X, Var::Y] {
                    let d = e.derivative(var);
                    let _ = d.eval(0.25, 0.75);
                    let _ = Expr::parse(&d.to_string_infix());
                }
            }
        }
        Err(e) => {
            let message = e.to_string();
            assert!(!message.contains('\n'), "multi-line error: {message:?}");
        }
    }
});
