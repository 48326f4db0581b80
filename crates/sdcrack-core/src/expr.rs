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
pub use batch::{BatchScratch, ExprBatch};

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

#[derive(Clone, Copy, Debug)]
enum Op {
    Num(f64),
    X,
    Y,
    Add,
    Sub,
    Mul,
    Div,
    Neg,
    Recip,
    Pow,
    Powi(i32),
    F1(Fn1),
    F2(Fn2),
    Select,
}

/// A literal integer exponent (`2`, `-3`), evaluated with `powi`.
fn literal_int(n: &Node) -> Option<i32> {
    let v = match n {
        Node::Num(v) => *v,
        Node::Neg(a) => match **a {
            Node::Num(v) => -v,
            _ => return None,
        },
        _ => return None,
    };
    if v.fract() == 0.0 && v.abs() <= f64::from(i32::MAX) {
        Some(v as i32)
    } else {
        None
    }
}

/// Appends the postfix program for `n`; returns the stack depth it needs.
fn compile(n: &Node, code: &mut Vec<Op>) -> usize {
    match n {
        Node::Num(v) => {
            code.push(Op::Num(*v));
            1
        }
        Node::X => {
            code.push(Op::X);
            1
        }
        Node::Y => {
            code.push(Op::Y);
            1
        }
        Node::Neg(a) => {
            let d = compile(a, code);
            code.push(Op::Neg);
            d
        }
        Node::Sum(ts) | Node::Prod(ts) => {
            let is_sum = matches!(n, Node::Sum(_));
            if ts.is_empty() {
                code.push(Op::Num(if is_sum { 0.0 } else { 1.0 }));
                return 1;
            }
            let mut need = 1;
            for (i, (flag, t)) in ts.iter().enumerate() {
                let d = compile(t, code);
                if i == 0 {
                    need = d;
                    if *flag {
                        code.push(if is_sum { Op::Neg } else { Op::Recip });
                    }
                } else {
                    need = need.max(d + 1);
                    code.push(match (is_sum, *flag) {
                        (true, false) => Op::Add,
                        (true, true) => Op::Sub,
                        (false, false) => Op::Mul,
                        (false, true) => Op::Div,
                    });
                }
            }
            need
        }
        Node::Pow(a, b) => {
            let da = compile(a, code);
            if let Some(k) = literal_int(b) {
                code.push(Op::Powi(k));
                da
            } else {
                let db = compile(b, code);
                code.push(Op::Pow);
                da.max(db + 1)
            }
        }
        Node::F1(f, a) => {
            let d = compile(a, code);
            code.push(Op::F1(*f));
            d
        }
        Node::F2(f, a, b) => {
            let da = compile(a, code);
            let db = compile(b, code);
            code.push(Op::F2(*f));
            da.max(db + 1)
        }
        Node::Select(s) => {
            let mut need = 0;
            for (i, t) in s.iter().enumerate() {
                need = need.max(compile(t, code) + i);
            }
            code.push(Op::Select);
            need
        }
    }
}

fn run(code: &[Op], st: &mut [f64], x: f64, y: f64) -> f64 {
    let mut sp = 0usize;
    for op in code {
        match *op {
            Op::Num(v) => {
                st[sp] = v;
                sp += 1;
            }
            Op::X => {
                st[sp] = x;
                sp += 1;
            }
            Op::Y => {
                st[sp] = y;
                sp += 1;
            }
            Op::Add => {
                sp -= 1;
                st[sp - 1] += st[sp];
            }
            Op::Sub => {
                sp -= 1;
                st[sp - 1] -= st[sp];
            }
            Op::Mul => {
                sp -= 1;
                st[sp - 1] *= st[sp];
            }
            Op::Div => {
                sp -= 1;
                st[sp - 1] /= st[sp];
            }
            Op::Pow => {
                sp -= 1;
                st[sp - 1] = st[sp - 1].powf(st[sp]);
            }
            Op::Neg => st[sp - 1] = -st[sp - 1],
            Op::Recip => st[sp - 1] = 1.0 / st[sp - 1],
            Op::Powi(k) => st[sp - 1] = st[sp - 1].powi(k),
            Op::F1(f) => st[sp - 1] = f.apply(st[sp - 1]),
            Op::F2(f) => {
                sp -= 1;
                st[sp - 1] = f.apply(st[sp - 1], st[sp]);
            }
            Op::Select => {
                sp -= 3;
                let (a, b, c, d) = (st[sp - 1], st[sp], st[sp + 1], st[sp + 2]);
                st[sp - 1] = if a < b { c } else { d };
            }
        }
    }
    st[0]
}

// ---------------------------------------------------------------------------------------------
// Lexer
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    Comma,
    /// A lexical error; lexing stops here so the parser reports errors in text order.
    Bad(ExprError),
    End,
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    col: usize,
    text: String,
}

fn lex(chars: &[char]) -> Vec<Token> {
    let mut toks = Vec::new();
    let mut i = 0;
    let n = chars.len();
    while i < n {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let single = match c {
            '+' => Some(Tok::Plus),
            '-' => Some(Tok::Minus),
            '*' => Some(Tok::Star),
            '/' => Some(Tok::Slash),
            '^' => Some(Tok::Caret),
            '(' => Some(Tok::LParen),
            ')' => Some(Tok::RParen),
            ',' => Some(Tok::Comma),
            _ => None,
        };
        if let Some(tok) = single {
            toks.push(Token {
                tok,
                col,
                text: c.to_string(),
            });
            i += 1;
            continue;
        }
        let digit_at = |k: usize| k < n && chars[k].is_ascii_digit();
        if c.is_ascii_digit() || (c == '.' && digit_at(i + 1)) {
            let start = i;
            while digit_at(i) {
                i += 1;
            }
            if i < n && chars[i] == '.' {
                i += 1;
                while digit_at(i) {
                    i += 1;
                }
            }
            if i < n && (chars[i] == 'e' || chars[i] == 'E') {
                let mut k = i + 1;
                if k < n && (chars[k] == '+' || chars[k] == '-') {
                    k += 1;
                }
                if digit_at(k) {
                    i = k;
                    while digit_at(i) {
                        i += 1;
                    }
                }
            }
            let text: String = chars[start..i].iter().collect();
            let tok = match text.parse::<f64>() {
                Ok(v) if v.is_finite() => Tok::Num(v),
                Ok(_) => Tok::Bad(ExprError::new(
                    col,
                    format!("number '{text}' is too large (overflows to infinity)"),
                )),
                Err(_) => Tok::Bad(ExprError::new(col, format!("malformed number '{text}'"))),
            };
            let bad = matches!(tok, Tok::Bad(_));
            toks.push(Token { tok, col, text });
            if bad {
                break;
            }
            continue;
        }
        if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < n && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let text: String = chars[start..i].iter().collect();
            toks.push(Token {
                tok: Tok::Ident(text.clone()),
                col,
                text,
            });
            continue;
        }
        toks.push(Token {
            tok: Tok::Bad(ExprError::new(col, format!("unexpected character '{c}'"))),
            col,
            text: c.to_string(),
        });
        break;
    }
    toks.push(Token {
        tok: Tok::End,
        col: n + 1,
        text: "end of input".to_string(),
    });
    toks
}

// ---------------------------------------------------------------------------------------------
// Parser
// ---------------------------------------------------------------------------------------------

fn parse_src(src: &str) -> Result<Node, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    if chars.len() > MAX_LEN {
        return Err(ExprError::new(
            MAX_LEN + 1,
            format!(
                "expression longer than {MAX_LEN} characters ({} characters)",
                chars.len()
            ),
        ));
    }
    if chars.iter().all(|c| c.is_whitespace()) {
        return Err(ExprError::new(1, "empty expression"));
    }
    let mut p = Parser {
        toks: lex(&chars),
        pos: 0,
        depth: 0,
    };
    let node = p.parse_expr()?;
    let t = p.peek().clone();
    match t.tok {
        Tok::End => Ok(node),
        Tok::Bad(e) => Err(e),
        Tok::RParen => Err(ExprError::new(t.col, "unmatched ')'")),
        _ => Err(ExprError::new(
            t.col,
            format!("unexpected trailing input '{}'", t.text),
        )),
    }
}

struct Parser {
    toks: Vec<Token>,
    pos: usize,
    depth: usize,
}

const FUNC_NAMES: [&str; 11] = [
    "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sign", "atan2", "min", "max",
];

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.chars().enumerate() {
        cur[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// The closest candidate for a near-miss name (first in list order on ties).
fn suggest(name: &str, candidates: &[&'static str]) -> Option<&'static str> {
    if name.len() > 12 {
        return None;
    }
    let lower = name.to_ascii_lowercase();
    let mut best: Option<(usize, &'static str)> = None;
    for &c in candidates {
        let d = levenshtein(&lower, c);
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, c));
        }
    }
    let (d, c) = best?;
    let limit = if name.chars().count() >= 4 { 2 } else { 1 };
    (d <= limit).then_some(c)
}

impl Parser {
    fn peek(&self) -> &Token {
        let last = self.toks.len().saturating_sub(1);
        &self.toks[self.pos.min(last)]
    }

    fn peek2(&self) -> &Token {
        let last = self.toks.len().saturating_sub(1);
        &self.toks[(self.pos + 1).min(last)]
    }

    fn advance(&mut self) -> Token {
        let t = self.peek().clone();
        if t.tok != Tok::End && !matches!(t.tok, Tok::Bad(_)) {
            self.pos += 1;
        }
        t
    }

    fn enter(&mut self, col: usize) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(ExprError::new(
                col,
                format!("expression nested deeper than {MAX_DEPTH} levels"),
            ));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    fn parse_expr(&mut self) -> Result<Node, ExprError> {
        let first = self.parse_term()?;
        let mut terms = Vec::new();
        loop {
            let neg = match self.peek().tok {
                Tok::Plus => false,
                Tok::Minus => true,
                _ => break,
            };
            self.advance();
            terms.push((neg, self.parse_term()?));
        }
        if terms.is_empty() {
            Ok(first)
        } else {
            terms.insert(0, (false, first));
            Ok(Node::Sum(terms))
        }
    }

    fn parse_term(&mut self) -> Result<Node, ExprError> {
        let first = self.parse_unary()?;
        let mut factors = Vec::new();
        loop {
            let div = match self.peek().tok {
                Tok::Star => false,
                Tok::Slash => true,
                _ => break,
            };
            self.advance();
            factors.push((div, self.parse_unary()?));
        }
        if factors.is_empty() {
            Ok(first)
        } else {
            factors.insert(0, (false, first));
            Ok(Node::Prod(factors))
        }
    }

    fn parse_unary(&mut self) -> Result<Node, ExprError> {
        // Signs are collected iteratively (no recursion); double negation is exact in IEEE
        // arithmetic, so only the parity matters.
        let mut negative = false;
        loop {
            match self.peek().tok {
                Tok::Plus => {}
                Tok::Minus => negative = !negative,
                _ => break,
            }
            self.advance();
        }
        let operand = self.parse_power()?;
        Ok(if negative {
            Node::Neg(Box::new(operand))
        } else {
            operand
        })
    }

    fn parse_power(&mut self) -> Result<Node, ExprError> {
        let base = self.parse_primary()?;
        if self.peek().tok == Tok::Caret {
            let caret = self.advance();
            self.enter(caret.col)?;
            let exponent = self.parse_unary()?;
            self.leave();
            return Ok(Node::Pow(Box::new(base), Box::new(exponent)));
        }
        Ok(base)
    }

    /// Error for a token that cannot start an operand.
    fn missing_operand(&self, t: &Token) -> ExprError {
        if let Tok::Bad(e) = &t.tok {
            return e.clone();
        }
        let prev = self.pos.checked_sub(1).and_then(|k| self.toks.get(k));
        if let Some(p) = prev {
            match p.tok {
                Tok::Plus | Tok::Minus | Tok::Star | Tok::Slash | Tok::Caret => {
                    return ExprError::new(p.col, format!("missing operand after '{}'", p.text));
                }
                Tok::Comma => {
                    return ExprError::new(p.col, "missing argument after ','");
                }
                Tok::LParen if t.tok == Tok::RParen => {
                    return ExprError::new(p.col, "empty parentheses");
                }
                Tok::LParen if t.tok == Tok::End => {
                    return ExprError::new(p.col, "unclosed parenthesis");
                }
                _ => {}
            }
        }
        match t.tok {
            Tok::RParen => ExprError::new(t.col, "unmatched ')'"),
            _ => ExprError::new(t.col, format!("expected an operand, found '{}'", t.text)),
        }
    }

    /// Consumes the `)` closing the `(` at `open_col`.
    fn expect_close(&mut self, open_col: usize) -> Result<(), ExprError> {
        let t = self.peek().clone();
        match t.tok {
            Tok::RParen => {
                self.advance();
                Ok(())
            }
            Tok::End => Err(ExprError::new(open_col, "unclosed parenthesis")),
            Tok::Bad(e) => Err(e),
            _ => Err(ExprError::new(
                t.col,
                format!("expected ')' or an operator, found '{}'", t.text),
            )),
        }
    }

    fn parse_primary(&mut self) -> Result<Node, ExprError> {
        let t = self.peek().clone();
        match t.tok {
            Tok::Num(v) => {
                self.advance();
                Ok(Node::Num(v))
            }
            Tok::LParen => {
                self.advance();
                self.enter(t.col)?;
                let e = self.parse_expr()?;
                self.expect_close(t.col)?;
                self.leave();
                Ok(e)
            }
            Tok::Ident(ref name) => {
                if self.peek2().tok == Tok::LParen {
                    self.parse_call(&t, name)
                } else {
                    self.advance();
                    match name.as_str() {
                        "x" => Ok(Node::X),
                        "y" => Ok(Node::Y),
                        "pi" => Ok(Node::Num(std::f64::consts::PI)),
                        _ if FUNC_NAMES.contains(&name.as_str()) => Err(ExprError::new(
                            t.col,
                            format!("function '{name}' must be followed by '(' and its arguments"),
                        )),
                        _ => {
                            let hint = match name.to_ascii_lowercase().as_str() {
                                "x" => "did you mean 'x'?".to_string(),
                                "y" => "did you mean 'y'?".to_string(),
                                "pi" => "did you mean 'pi'?".to_string(),
                                _ => "expected x, y or pi".to_string(),
                            };
                            Err(ExprError::new(
                                t.col,
                                format!("unknown variable '{name}' ({hint})"),
                            ))
                        }
                    }
                }
            }
            _ => Err(self.missing_operand(&t)),
        }
    }

    fn parse_call(&mut self, name_tok: &Token, name: &str) -> Result<Node, ExprError> {
        let f1 = Fn1::ALL.iter().copied().find(|f| f.name() == name);
        let f2 = Fn2::ALL.iter().copied().find(|f| f.name() == name);
        let arity = match (f1, f2) {
            (Some(_), _) => 1,
            (_, Some(_)) => 2,
            _ => {
                let message = if matches!(name, "x" | "y" | "pi") {
                    format!("'{name}' is a variable, not a function (write '{name}*(...)')")
                } else if let Some(s) = suggest(name, &FUNC_NAMES) {
                    format!("unknown function '{name}' (did you mean '{s}'?)")
                } else {
                    format!("unknown function '{name}'")
                };
                return Err(ExprError::new(name_tok.col, message));
            }
        };
        self.advance(); // name
        let open = self.advance(); // '('
        self.enter(open.col)?;
        let mut args = Vec::new();
        if self.peek().tok == Tok::RParen {
            self.advance();
        } else {
            loop {
                args.push(self.parse_expr()?);
                let t = self.peek().clone();
                match t.tok {
                    Tok::Comma => {
                        self.advance();
                    }
                    Tok::RParen => {
                        self.advance();
                        break;
                    }
                    Tok::End => return Err(ExprError::new(open.col, "unclosed parenthesis")),
                    Tok::Bad(e) => return Err(e),
                    _ => {
                        return Err(ExprError::new(
                            t.col,
                            format!("expected ',' or ')' or an operator, found '{}'", t.text),
                        ))
                    }
                }
            }
        }
        self.leave();
        if args.len() != arity {
            let plural = if arity == 1 { "argument" } else { "arguments" };
            return Err(ExprError::new(
                name_tok.col,
                format!("{name} takes {arity} {plural}, got {}", args.len()),
            ));
        }
        let mut it = args.into_iter();
        match (f1, f2, it.next(), it.next()) {
            (Some(f), _, Some(a), None) => Ok(Node::F1(f, Box::new(a))),
            (_, Some(f), Some(a), Some(b)) => Ok(Node::F2(f, Box::new(a), Box::new(b))),
            _ => Err(ExprError::new(name_tok.col, "internal error: bad call")),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Simplifying constructors and differentiation
// ---------------------------------------------------------------------------------------------

fn num(v: f64) -> Node {
    Node::Num(v)
}

fn is_num(n: &Node, v: f64) -> bool {
    matches!(n, Node::Num(w) if *w == v)
}

fn neg(a: Node) -> Node {
    match a {
        Node::Num(v) => Node::Num(-v),
        Node::Neg(b) => *b,
        other => Node::Neg(Box::new(other)),
    }
}

/// Sum with flattening, zero removal and folding of the numeric terms.
fn add(terms: Vec<(bool, Node)>) -> Node {
    let mut out: Vec<(bool, Node)> = Vec::new();
    let mut c = 0.0f64;
    let mut stack: Vec<(bool, Node)> = terms.into_iter().rev().collect();
    while let Some((s, t)) = stack.pop() {
        match t {
            Node::Num(v) if (c + if s { -v } else { v }).is_finite() => {
                c += if s { -v } else { v };
            }
            Node::Sum(inner) => {
                for (s2, t2) in inner.into_iter().rev() {
                    stack.push((s ^ s2, t2));
                }
            }
            Node::Neg(inner) => stack.push((!s, *inner)),
            other => out.push((s, other)),
        }
    }
    if c != 0.0 {
        out.push((c < 0.0, num(c.abs())));
    }
    // Prefer a non-negated first term.
    if let Some(k) = out.iter().position(|(s, _)| !s) {
        let t = out.remove(k);
        out.insert(0, t);
    }
    match out.len() {
        0 => num(0.0),
        1 => match out.pop() {
            Some((true, t)) => neg(t),
            Some((false, t)) => t,
            None => num(0.0),
        },
        _ => Node::Sum(out),
    }
}

/// Product with flattening, `0*a -> 0`, `1*a -> a` and folding of the numeric factors.
fn mul(factors: Vec<(bool, Node)>) -> Node {
    let mut out: Vec<(bool, Node)> = Vec::new();
    let mut c = 1.0f64;
    let mut stack: Vec<(bool, Node)> = factors.into_iter().rev().collect();
    while let Some((d, f)) = stack.pop() {
        match f {
            Node::Num(v) if !d && v == 0.0 => return num(0.0),
            Node::Num(v) if (if d { c / v } else { c * v }).is_finite() && v != 0.0 => {
                c = if d { c / v } else { c * v };
            }
            Node::Prod(inner) => {
                for (d2, f2) in inner.into_iter().rev() {
                    stack.push((d ^ d2, f2));
                }
            }
            Node::Neg(inner) => {
                c = -c;
                stack.push((d, *inner));
            }
            other => out.push((d, other)),
        }
    }
    if c == 0.0 {
        return num(0.0);
    }
    let negative = c < 0.0;
    let c = c.abs();
    if c != 1.0 || out.is_empty() {
        out.insert(0, (false, num(c)));
    }
    let body = if out.len() == 1 && !out[0].0 {
        match out.pop() {
            Some((_, f)) => f,
            None => num(1.0),
        }
    } else {
        Node::Prod(out)
    };
    if negative {
        neg(body)
    } else {
        body
    }
}

fn pow(a: Node, b: Node) -> Node {
    if is_num(&b, 1.0) {
        return a;
    }
    if is_num(&b, 0.0) {
        return num(1.0);
    }
    if let (Node::Num(x), Node::Num(y)) = (&a, &b) {
        let v = match literal_int(&b) {
            Some(k) => x.powi(k),
            None => x.powf(*y),
        };
        if v.is_finite() {
            return num(v);
        }
    }
    Node::Pow(Box::new(a), Box::new(b))
}

fn f1(f: Fn1, a: Node) -> Node {
    if let Node::Num(v) = a {
        let r = f.apply(v);
        if r.is_finite() {
            return num(r);
        }
    }
    Node::F1(f, Box::new(a))
}

fn select(a: Node, b: Node, c: Node, d: Node) -> Node {
    if c == d {
        return c;
    }
    Node::Select(Box::new([a, b, c, d]))
}

/// Product rule for a plain product `f_0 * f_1 * ... * f_n`.
fn product_rule(fs: &[Node], var: Var) -> Node {
    let mut terms = Vec::new();
    for (i, f) in fs.iter().enumerate() {
        let df = deriv(f, var);
        if is_num(&df, 0.0) {
            continue;
        }
        let mut factors = vec![(false, df)];
        for (j, g) in fs.iter().enumerate() {
            if j != i {
                factors.push((false, g.clone()));
            }
        }
        terms.push((false, mul(factors)));
    }
    add(terms)
}

/// Differentiates `n`. Each non-trivial rule lives in its own function so that the frame
/// of this recursive dispatcher stays small (tree depth, not input length, bounds recursion).
fn deriv(n: &Node, var: Var) -> Node {
    match n {
        Node::Num(_) => num(0.0),
        Node::X => num(if var == Var::X { 1.0 } else { 0.0 }),
        Node::Y => num(if var == Var::Y { 1.0 } else { 0.0 }),
        Node::Neg(a) => neg(deriv(a, var)),
        Node::Sum(ts) => deriv_sum(ts, var),
        Node::Prod(fs) => deriv_prod(fs, var),
        Node::Pow(a, b) => deriv_pow(a, b, var),
        Node::F1(f, a) => deriv_f1(*f, a, var),
        Node::F2(f, a, b) => deriv_f2(*f, a, b, var),
        Node::Select(s) => deriv_select(s, var),
    }
}

#[inline(never)]
fn deriv_sum(ts: &[(bool, Node)], var: Var) -> Node {
    add(ts.iter().map(|(s, t)| (*s, deriv(t, var))).collect())
}

#[inline(never)]
fn deriv_prod(fs: &[(bool, Node)], var: Var) -> Node {
    let nums: Vec<Node> = fs.iter().filter(|f| !f.0).map(|f| f.1.clone()).collect();
    let dens: Vec<Node> = fs.iter().filter(|f| f.0).map(|f| f.1.clone()).collect();
    let dn = product_rule(&nums, var);
    if dens.is_empty() {
        return dn;
    }
    // (N/D)' = N'/D - N*D'/D^2
    let dd = product_rule(&dens, var);
    let mut first = vec![(false, dn)];
    first.extend(dens.iter().map(|d| (true, d.clone())));
    let mut second: Vec<(bool, Node)> = nums.iter().map(|f| (false, f.clone())).collect();
    second.push((false, dd));
    for _ in 0..2 {
        second.extend(dens.iter().map(|d| (true, d.clone())));
    }
    add(vec![(false, mul(first)), (true, mul(second))])
}

#[inline(never)]
fn deriv_pow(a: &Node, b: &Node, var: Var) -> Node {
    let da = deriv(a, var);
    if is_const(b) {
        // b * a^(b-1) * a'
        let bm1 = add(vec![(false, b.clone()), (true, num(1.0))]);
        return mul(vec![
            (false, b.clone()),
            (false, pow(a.clone(), bm1)),
            (false, da),
        ]);
    }
    let db = deriv(b, var);
    let p = pow(a.clone(), b.clone());
    if is_const(a) {
        return mul(vec![
            (false, p),
            (false, f1(Fn1::Log, a.clone())),
            (false, db),
        ]);
    }
    // a^b * (b'*log(a) + b*a'/a)
    let inner = add(vec![
        (
            false,
            mul(vec![(false, db), (false, f1(Fn1::Log, a.clone()))]),
        ),
        (
            false,
            mul(vec![(false, b.clone()), (false, da), (true, a.clone())]),
        ),
    ]);
    mul(vec![(false, p), (false, inner)])
}

#[inline(never)]
fn deriv_f1(f: Fn1, a: &Node, var: Var) -> Node {
    let da = deriv(a, var);
    if is_num(&da, 0.0) || f == Fn1::Sign {
        return num(0.0);
    }
    let a = a.clone();
    let outer = match f {
        Fn1::Sin => f1(Fn1::Cos, a),
        Fn1::Cos => neg(f1(Fn1::Sin, a)),
        Fn1::Tan => mul(vec![(true, pow(f1(Fn1::Cos, a), num(2.0)))]),
        Fn1::Exp => f1(Fn1::Exp, a),
        Fn1::Log => mul(vec![(true, a)]),
        Fn1::Sqrt => mul(vec![(true, num(2.0)), (true, f1(Fn1::Sqrt, a))]),
        Fn1::Abs => f1(Fn1::Sign, a),
        Fn1::Sign => num(0.0),
    };
    mul(vec![(false, outer), (false, da)])
}

#[inline(never)]
fn deriv_f2(f: Fn2, a: &Node, b: &Node, var: Var) -> Node {
    let da = deriv(a, var);
    let db = deriv(b, var);
    let (a, b) = (a.clone(), b.clone());
    match f {
        Fn2::Atan2 => {
            // (b*a' - a*b') / (a^2 + b^2)
            let numer = add(vec![
                (false, mul(vec![(false, b.clone()), (false, da)])),
                (true, mul(vec![(false, a.clone()), (false, db)])),
            ]);
            let denom = add(vec![(false, pow(a, num(2.0))), (false, pow(b, num(2.0)))]);
            mul(vec![(false, numer), (true, denom)])
        }
        Fn2::Min => select(a, b, da, db),
        Fn2::Max => select(a, b, db, da),
    }
}

#[inline(never)]
fn deriv_select(s: &[Node; 4], var: Var) -> Node {
    let [a, b, c, d] = s;
    select(a.clone(), b.clone(), deriv(c, var), deriv(d, var))
}

// ---------------------------------------------------------------------------------------------
// Rendering
// ---------------------------------------------------------------------------------------------

fn render_root(n: &Node) -> String {
    let mut out = String::new();
    render(n, &mut out, true);
    out
}

fn render_num(v: f64, out: &mut String) {
    if v.is_nan() {
        out.push_str("(0/0)");
    } else if v.is_infinite() {
        out.push_str(if v > 0.0 { "(1/0)" } else { "(-1/0)" });
    } else {
        let a = v.abs();
        let text = if a == 0.0 || (1e-5..1e16).contains(&a) {
            format!("{a}")
        } else {
            format!("{a:e}")
        };
        if v.is_sign_negative() {
            out.push_str("(-");
            out.push_str(&text);
            out.push(')');
        } else {
            out.push_str(&text);
        }
    }
}

/// Renders `n`; composite nodes get their own parentheses when `wrap` is set (operands),
/// but not as function arguments (whose call parentheses already delimit them).
fn render(n: &Node, out: &mut String, wrap: bool) {
    let open = |out: &mut String| {
        if wrap {
            out.push('(');
        }
    };
    let close = |out: &mut String| {
        if wrap {
            out.push(')');
        }
    };
    match n {
        Node::Num(v) => render_num(*v, out),
        Node::X => out.push('x'),
        Node::Y => out.push('y'),
        Node::Neg(a) => {
            open(out);
            out.push('-');
            render(a, out, true);
            close(out);
        }
        Node::Sum(ts) | Node::Prod(ts) => {
            let is_sum = matches!(n, Node::Sum(_));
            if ts.is_empty() {
                out.push_str(if is_sum { "0" } else { "1" });
                return;
            }
            open(out);
            for (i, (flag, t)) in ts.iter().enumerate() {
                match (i == 0, is_sum, *flag) {
                    (true, true, true) => out.push('-'),
                    (true, false, true) => out.push_str("1 / "),
                    (true, _, false) => {}
                    (false, true, false) => out.push_str(" + "),
                    (false, true, true) => out.push_str(" - "),
                    (false, false, false) => out.push_str(" * "),
                    (false, false, true) => out.push_str(" / "),
                }
                render(t, out, true);
            }
            close(out);
        }
        Node::Pow(a, b) => {
            open(out);
            render(a, out, true);
            out.push_str(" ^ ");
            render(b, out, true);
            close(out);
        }
        Node::F1(f, a) => {
            out.push_str(f.name());
            out.push('(');
            render(a, out, false);
            out.push(')');
        }
        Node::F2(f, a, b) => {
            out.push_str(f.name());
            out.push('(');
            render(a, out, false);
            out.push_str(", ");
            render(b, out, false);
            out.push(')');
        }
        Node::Select(s) => {
            let [a, b, c, d] = &**s;
            let mut diff = String::new();
            render(a, &mut diff, true);
            diff.push_str(" - ");
            render(b, &mut diff, true);
            open(out);
            render(c, out, true);
            out.push_str(" * ((1 - sign(");
            out.push_str(&diff);
            out.push_str(")) / 2) + ");
            render(d, out, true);
            out.push_str(" * ((1 + sign(");
            out.push_str(&diff);
            out.push_str(")) / 2)");
            close(out);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

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
            (self.next() % n as u64) as usize
        }
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

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
        super::sign(v)
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

    #[test]
    fn derivatives_match_finite_differences() {
        let srcs = [
            "20*sin(2*pi*x)*sign(y)",
            LONG,
            "x^3*y - 2*x/y + y^2.5",
            "exp(x*y) * log(1 + x^2)",
            "tan(x/2) + cos(x*y)",
            "sqrt(x^2 + y^2) * abs(x - 3)",
            "atan2(y - 0.1, x + 0.2) * x",
            "min(x, y) + max(x*x, y) * min(2, x)",
            "x^y + 2^(x*y) - (1/x)",
            "-(x - y)/(x + y)/(1 + x*y)",
            "abs(sin(3*x)) * sign(x - y)",
        ];
        let mut rng = Rng(0x9E3779B97F4A7C15);
        let h = 1e-6;
        for src in srcs {
            let e = p(src);
            let dx = e.derivative(Var::X);
            let dy = e.derivative(Var::Y);
            // The derivative's source is its printable rendering.
            assert_eq!(dx.source(), dx.to_string_infix());
            let mut checked = 0;
            while checked < 20 {
                let (x, y) = (rng.uniform(0.3, 1.6), rng.uniform(0.35, 1.5));
                // stay away from kinks of abs/sign/min/max and jumps of sign
                let kinks = [
                    x - y,
                    x * x - y,
                    2.0 - x,
                    (3.0 * x).sin(),
                    (2.0 * x % 1.0) - 0.5,
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
        let mut rng = Rng(12345);
        for src in srcs {
            let e = p(src);
            let r = e.to_string_infix();
            let back = p(&r);
            assert_eq!(back.to_string_infix(), r, "rendering is a fixed point");
            for _ in 0..50 {
                let (x, y) = (rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0));
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
                    let (x, y) = (rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0));
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

    #[test]
    fn error_messages() {
        let long = "x+".repeat(5000) + "x";
        let deep = "(".repeat(201) + "x" + &")".repeat(201);
        let cases: Vec<(&str, usize, &str)> = vec![
            ("", 1, "empty expression"),
            ("   ", 1, "empty expression"),
            ("2 $ x", 3, "unexpected character '$'"),
            (
                "sinn(x)",
                1,
                "unknown function 'sinn' (did you mean 'sin'?)",
            ),
            (
                "1 + sqr(x)",
                5,
                "unknown function 'sqr' (did you mean 'sqrt'?)",
            ),
            ("foo(x)", 1, "unknown function 'foo'"),
            ("z", 1, "unknown variable 'z' (expected x, y or pi)"),
            ("2*X", 3, "unknown variable 'X' (did you mean 'x'?)"),
            ("atan2(x)", 1, "atan2 takes 2 arguments, got 1"),
            ("1+sin(x, y)", 3, "sin takes 1 argument, got 2"),
            ("max()", 1, "max takes 2 arguments, got 0"),
            ("(x+1", 1, "unclosed parenthesis"),
            ("sin(x", 4, "unclosed parenthesis"),
            ("x+1)", 4, "unmatched ')'"),
            (")", 1, "unmatched ')'"),
            ("()", 1, "empty parentheses"),
            ("x y", 3, "unexpected trailing input 'y'"),
            ("x+", 2, "missing operand after '+'"),
            ("2*(x-)", 5, "missing operand after '-'"),
            ("x^", 2, "missing operand after '^'"),
            ("atan2(x,)", 8, "missing argument after ','"),
            (
                "1e999",
                1,
                "number '1e999' is too large (overflows to infinity)",
            ),
            (
                "x + 1e999 $",
                5,
                "number '1e999' is too large (overflows to infinity)",
            ),
            (
                "sin",
                1,
                "function 'sin' must be followed by '(' and its arguments",
            ),
            (
                "x(1)",
                1,
                "'x' is a variable, not a function (write 'x*(...)')",
            ),
            ("(x y)", 4, "expected ')' or an operator, found 'y'"),
            ("x + 1.", 5, ""), // "1." is a valid number: checked below
        ];
        for (src, col, msg) in cases {
            if msg.is_empty() {
                assert!(Expr::parse(src).is_ok());
                continue;
            }
            let e = err(src);
            assert_eq!((e.column, e.message.as_str()), (col, msg), "input {src:?}");
        }
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
        let mut rng = Rng(0xDEADBEEF12345678);
        let mut parsed = 0;
        for i in 0..100_000 {
            let s: String = if i % 2 == 0 {
                let mut v: Vec<char> = seeds[rng.below(seeds.len())].chars().collect();
                for _ in 0..1 + rng.below(4) {
                    let c = alphabet[rng.below(alphabet.len())];
                    match rng.below(3) {
                        0 => {
                            let k = rng.below(v.len() + 1);
                            v.insert(k, c);
                        }
                        1 if !v.is_empty() => {
                            let k = rng.below(v.len());
                            v.remove(k);
                        }
                        _ if !v.is_empty() => {
                            let k = rng.below(v.len());
                            v[k] = c;
                        }
                        _ => v.push(c),
                    }
                }
                v.into_iter().collect()
            } else {
                let len = rng.below(24);
                (0..len)
                    .map(|_| alphabet[rng.below(alphabet.len())])
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
}
