//! Scene expression grammar: small arithmetic expressions of `x` and `y`.
//!
//! Scene files describe loads, displacements and crack geometry with expressions such as
//! `20*sin(2*pi*x)*sign(y)`. This module parses them into an immutable tree, compiles the
//! tree once into a flat stack program for allocation-free evaluation, differentiates them
//! symbolically and renders them back to text.
//!
//! # Grammar
//!
//! ```text
//! expr    := term   (('+' | '-') term)*          left-associative
//! term    := unary  (('*' | '/') unary)*         left-associative
//! unary   := ('+' | '-')* power                  signs bind looser than '^'
//! power   := primary ('^' unary)?                right-associative
//! primary := number | 'x' | 'y' | 'pi' | '(' expr ')'
//!          | func1 '(' expr ')' | func2 '(' expr ',' expr ')'
//! func1   := sin | cos | tan | exp | log | sqrt | abs | sign
//! func2   := atan2 | min | max
//! number  := digits ['.' digits] | '.' digits, optionally followed by (e|E)[+|-]digits
//! ```
//!
//! Precedence, from tightest to loosest: function calls and parentheses, `^`
//! (right-associative, so `2^3^2` is `2^(3^2)`), unary `-`/`+` (so `-x^2` is `-(x^2)`, while
//! `2^-x` is `2^(-x)`), then `*` and `/`, then `+` and `-`. Whitespace is allowed between any
//! two tokens. `log` is the natural logarithm, `atan2(a, b)` is Rust's `f64::atan2` (angle of
//! the point `(b, a)`), `min`/`max` are `f64::min`/`f64::max`. `a^b` is `powf`, except that
//! a literal integer exponent (`x^2`, `x^-3`) is evaluated with `powi`.
//!
//! # Signed zero: selecting the side of a crack
//!
//! Points on a crack lying on `y = 0` are evaluated with `y = +0.0` for the upper side and
//! `y = -0.0` for the lower side. To make that selectable, `sign` follows IEEE signed zero:
//! `sign(v) = 1` for `v > 0`, `-1` for `v < 0`, and for `v == 0` it is `1.0.copysign(v)`,
//! i.e. `sign(+0.0) = 1` and `sign(-0.0) = -1` (and `sign(NaN) = NaN`). `atan2` already
//! respects signed zero: `atan2(+0.0, -1) = pi`, `atan2(-0.0, -1) = -pi`.
//!
//! # Limits
//!
//! Inputs longer than 10000 characters, and inputs nested deeper than 200 levels (each
//! parenthesis, function call and `^` exponent opens one level), are rejected with an
//! [`ExprError`]; the parser never panics and its recursion depth is bounded.

mod batch;
mod bound;
mod derivative;
mod error;
mod expression;
mod lexer;
mod parser;
mod printer;
mod simplify;
#[cfg(test)]
mod tests;
mod tree;
mod vm;

pub use batch::{BatchScratch, ExprBatch};
pub use error::ExprError;
pub use expression::Expr;
pub use tree::Var;
