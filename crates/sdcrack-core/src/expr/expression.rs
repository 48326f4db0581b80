//! [`Expr`], a parsed expression: its tree, compiled once to the stack program, with its
//! evaluation, derivative and rendering (module documentation of [`crate::expr`]).

use std::sync::Arc;

use super::bound;
use super::derivative::deriv;
use super::error::ExprError;
use super::parser::parse_src;
use super::printer::render_root;
use super::tree::{is_const, Node, Var};
use super::vm::{compile, run, Op};

/// A parsed expression: an immutable tree, compiled once to a flat program for fast evaluation.
///
/// Cloning is cheap (shared, reference counted); `Expr` is `Send + Sync`.
#[derive(Clone, Debug)]
pub struct Expr {
    pub(super) inner: Arc<Inner>,
}

#[derive(Debug)]
pub(super) struct Inner {
    source: String,
    pub(super) root: Node,
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
