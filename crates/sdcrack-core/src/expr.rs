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

use std::sync::Arc;

mod batch;
mod bound;
pub use batch::{BatchScratch, ExprBatch};
mod derivative;
mod lexer;
mod parser;
mod printer;
mod simplify;
#[cfg(test)]
mod tests;
mod vm;

use derivative::deriv;
use parser::parse_src;
use printer::render_root;
use vm::{compile, literal_int, run, Op};

/// Maximum accepted input length, in characters.
const MAX_LEN: usize = 10_000;
/// Maximum nesting depth (parentheses, function arguments, exponents).
const MAX_DEPTH: usize = 200;

/// Which variable to differentiate by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Var {
    /// Differentiate by `x`.
    X,
    /// Differentiate by `y`.
    Y,
}

/// A parse error: what went wrong and the 1-based character column where it starts.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message} at column {column}")]
pub struct ExprError {
    /// 1-based character (not byte) column where the problem starts.
    pub column: usize,
    /// Human-readable description of the problem.
    pub message: String,
}

impl ExprError {
    fn new(column: usize, message: impl Into<String>) -> Self {
        ExprError {
            column,
            message: message.into(),
        }
    }
}

/// A parsed expression: an immutable tree, compiled once to a flat program for fast evaluation.
///
/// Cloning is cheap (shared, reference counted); `Expr` is `Send + Sync`.
#[derive(Clone, Debug)]
pub struct Expr {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    source: String,
    root: Node,
    code: Vec<Op>,
    max_stack: usize,
    constant: bool,
}

impl Expr {
    /// Parses `src` according to the module grammar.
    ///
    /// Returns an [`ExprError`] naming the problem and its 1-based column; never panics.
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        let root = parse_src(src)?;
        Ok(Expr::from_node(root, src.to_string()))
    }

    /// An expression that evaluates to `value` everywhere.
    pub fn constant(value: f64) -> Expr {
        let root = Node::Num(value);
        let src = render_root(&root);
        Expr::from_node(root, src)
    }

    /// The text this expression was parsed from; for constants and derivatives, a printable
    /// rendering (the same as [`Expr::to_string_infix`]).
    pub fn source(&self) -> &str {
        &self.inner.source
    }

    /// Evaluates the expression at `(x, y)`. Does not allocate (except for pathologically deep
    /// derived expressions needing more than 256 stack slots).
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        let inner = &*self.inner;
        if inner.max_stack <= 16 {
            let mut st = [0.0f64; 16];
            run(&inner.code, &mut st, x, y)
        } else if inner.max_stack <= 256 {
            let mut st = [0.0f64; 256];
            run(&inner.code, &mut st, x, y)
        } else {
            let mut st = vec![0.0f64; inner.max_stack];
            run(&inner.code, &mut st, x, y)
        }
    }

    /// The value at `(x, y)` (as [`Expr::eval`]) and a first-order bound of its round-off error,
    /// the coordinates taken as exact (running error analysis, see `expr/bound.rs`); an infinite
    /// or NaN bound where the value is too sensitive to be bounded (e.g. `sqrt` at 0).
    pub fn eval_bounded(&self, x: f64, y: f64) -> (f64, f64) {
        bound::run_bounded(&self.inner.code, x, y)
    }

    /// The exact symbolic derivative by `var`, simplified (`0*a -> 0`, `1*a -> a`,
    /// `a+0 -> a`, folding of finite constants).
    ///
    /// Derivatives of `min`/`max` select the derivative of the active argument (ties pick the
    /// second argument for `min`, the first for `max`); `d sign = 0`; `d abs(a) = sign(a)*a'`.
    pub fn derivative(&self, var: Var) -> Expr {
        let d = deriv(&self.inner.root, var);
        let src = render_root(&d);
        Expr::from_node(d, src)
    }

    /// True when the expression mentions neither `x` nor `y`.
    pub fn is_constant(&self) -> bool {
        self.inner.constant
    }

    /// A fully parenthesised rendering that [`Expr::parse`] accepts and that evaluates to the
    /// same values.
    ///
    /// Every operator application is wrapped in parentheses; negative numbers render as
    /// `(-2)`, infinities as `(1/0)`/`(-1/0)`, NaN as `(0/0)`. Internal conditional nodes
    /// produced by differentiating `min`/`max` (`a < b ? c : d`) render as
    /// `(c*((1 - sign(a - b))/2) + d*((1 + sign(a - b))/2))`, which is exact whenever the
    /// unselected branch is finite. Re-parsing is subject to the usual length (10000) and
    /// nesting (200) limits, which large derivatives can exceed.
    pub fn to_string_infix(&self) -> String {
        render_root(&self.inner.root)
    }

    fn from_node(root: Node, source: String) -> Expr {
        let mut code = Vec::new();
        let max_stack = compile(&root, &mut code);
        let constant = is_const(&root);
        Expr {
            inner: Arc::new(Inner {
                source,
                root,
                code,
                max_stack,
                constant,
            }),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tree
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Fn1 {
    Sin,
    Cos,
    Tan,
    Exp,
    Log,
    Sqrt,
    Abs,
    Sign,
}

impl Fn1 {
    const ALL: [Fn1; 8] = [
        Fn1::Sin,
        Fn1::Cos,
        Fn1::Tan,
        Fn1::Exp,
        Fn1::Log,
        Fn1::Sqrt,
        Fn1::Abs,
        Fn1::Sign,
    ];

    fn name(self) -> &'static str {
        match self {
            Fn1::Sin => "sin",
            Fn1::Cos => "cos",
            Fn1::Tan => "tan",
            Fn1::Exp => "exp",
            Fn1::Log => "log",
            Fn1::Sqrt => "sqrt",
            Fn1::Abs => "abs",
            Fn1::Sign => "sign",
        }
    }

    fn apply(self, v: f64) -> f64 {
        match self {
            Fn1::Sin => v.sin(),
            Fn1::Cos => v.cos(),
            Fn1::Tan => v.tan(),
            Fn1::Exp => v.exp(),
            Fn1::Log => v.ln(),
            Fn1::Sqrt => v.sqrt(),
            Fn1::Abs => v.abs(),
            Fn1::Sign => sign(v),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Fn2 {
    Atan2,
    Min,
    Max,
}

impl Fn2 {
    const ALL: [Fn2; 3] = [Fn2::Atan2, Fn2::Min, Fn2::Max];

    fn name(self) -> &'static str {
        match self {
            Fn2::Atan2 => "atan2",
            Fn2::Min => "min",
            Fn2::Max => "max",
        }
    }

    fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Fn2::Atan2 => a.atan2(b),
            Fn2::Min => a.min(b),
            Fn2::Max => a.max(b),
        }
    }
}

/// `sign` with the signed-zero side convention (see module docs).
fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else if v == 0.0 {
        1.0f64.copysign(v)
    } else {
        f64::NAN
    }
}

/// Expression tree. Sums and products are n-ary (evaluated left to right, exactly as the
/// left-associative binary chain would be), which keeps the tree depth bounded by the
/// source nesting depth even for very long `a+b+c+...` chains.
#[derive(Clone, Debug, PartialEq)]
enum Node {
    Num(f64),
    X,
    Y,
    Neg(Box<Node>),
    /// Terms with a "subtract" flag; the first term's flag means unary negation.
    Sum(Vec<(bool, Node)>),
    /// Factors with a "divide" flag; the first factor's flag means reciprocal.
    Prod(Vec<(bool, Node)>),
    Pow(Box<Node>, Box<Node>),
    F1(Fn1, Box<Node>),
    F2(Fn2, Box<Node>, Box<Node>),
    /// `[a, b, c, d]`: `if a < b { c } else { d }` (private; from min/max derivatives).
    Select(Box<[Node; 4]>),
}

fn is_const(n: &Node) -> bool {
    match n {
        Node::Num(_) => true,
        Node::X | Node::Y => false,
        Node::Neg(a) | Node::F1(_, a) => is_const(a),
        Node::Sum(ts) | Node::Prod(ts) => ts.iter().all(|(_, t)| is_const(t)),
        Node::Pow(a, b) | Node::F2(_, a, b) => is_const(a) && is_const(b),
        Node::Select(s) => s.iter().all(is_const),
    }
}

// ---------------------------------------------------------------------------------------------
// Compilation and evaluation
// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
// Lexer
// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
// Parser
// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
// Simplifying constructors and differentiation
// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
// Rendering
// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------
