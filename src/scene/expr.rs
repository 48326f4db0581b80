//! The scene expression grammar (BRIEF §5): parsed once into a tree, evaluated without
//! allocation, differentiated symbolically (for exact gradients of `[exact] u`).
//!
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary ('^' unary)?          right-associative, binds tighter than unary minus
//! primary := number | 'x' | 'y' | 'pi' | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//! so `-x^2 = -(x^2)` and `2^3^2 = 2^9`. Functions: `sin cos tan exp log sqrt abs sign` (one
//! argument), `atan2 min max` (two). `log` is the natural logarithm; `a^n` with a literal integer n
//! is evaluated by repeated multiplication (`powi`), otherwise by `powf`.
//!
//! **Signed zeros select crack faces.** `sign(v)` is 1 for v > 0, −1 for v < 0 and
//! `copysign(1, v)` for v = ±0, and `atan2` is IEEE's: evaluating at y = +0.0 or −0.0 picks the + or
//! − face of a crack lying on y = 0 (see [`crate::scene::eval_on_face`]).
//!
//! Limits: 10 000 characters and a nesting depth of 200; the parser never recurses deeper, so no
//! input can overflow the stack. Errors carry the 1-based character column where they start.

use std::fmt;

/// Which variable to differentiate by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Var {
    /// ∂/∂x.
    X,
    /// ∂/∂y.
    Y,
}

/// A parse error with the 1-based character column where it starts.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message} at column {column}")]
pub struct ExprError {
    /// 1-based character column.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

/// Longest expression accepted, in characters.
pub const MAX_LENGTH: usize = 10_000;
/// Deepest nesting accepted.
pub const MAX_DEPTH: usize = 200;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum F1 {
    Sin,
    Cos,
    Tan,
    Exp,
    Log,
    Sqrt,
    Abs,
    Sign,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum F2 {
    Atan2,
    Min,
    Max,
}

#[derive(Clone, Debug, PartialEq)]
enum Node {
    Const(f64),
    X,
    Y,
    Neg(Box<Node>),
    Add(Box<Node>, Box<Node>),
    Sub(Box<Node>, Box<Node>),
    Mul(Box<Node>, Box<Node>),
    Div(Box<Node>, Box<Node>),
    Pow(Box<Node>, Box<Node>),
    Call1(F1, Box<Node>),
    Call2(F2, Box<Node>, Box<Node>),
    /// `if a < b { p } else { q }` — only produced by differentiating min/max.
    Less(Box<[Node; 4]>),
}

/// A parsed expression of x and y.
#[derive(Clone, Debug)]
pub struct Expr {
    root: Node,
    source: String,
}

const FUNCTIONS: [&str; 11] = [
    "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sign", "atan2", "min", "max",
];

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

impl Node {
    fn eval(&self, x: f64, y: f64) -> f64 {
        match self {
            Node::Const(c) => *c,
            Node::X => x,
            Node::Y => y,
            Node::Neg(a) => -a.eval(x, y),
            Node::Add(a, b) => a.eval(x, y) + b.eval(x, y),
            Node::Sub(a, b) => a.eval(x, y) - b.eval(x, y),
            Node::Mul(a, b) => a.eval(x, y) * b.eval(x, y),
            Node::Div(a, b) => a.eval(x, y) / b.eval(x, y),
            Node::Pow(a, b) => {
                let base = a.eval(x, y);
                match **b {
                    Node::Const(c) if c.fract() == 0.0 && c.abs() <= 64.0 => base.powi(c as i32),
                    _ => base.powf(b.eval(x, y)),
                }
            }
            Node::Call1(f, a) => {
                let v = a.eval(x, y);
                match f {
                    F1::Sin => v.sin(),
                    F1::Cos => v.cos(),
                    F1::Tan => v.tan(),
                    F1::Exp => v.exp(),
                    F1::Log => v.ln(),
                    F1::Sqrt => v.sqrt(),
                    F1::Abs => v.abs(),
                    F1::Sign => sign(v),
                }
            }
            Node::Call2(f, a, b) => {
                let (u, v) = (a.eval(x, y), b.eval(x, y));
                match f {
                    F2::Atan2 => u.atan2(v),
                    F2::Min => u.min(v),
                    F2::Max => u.max(v),
                }
            }
            Node::Less(n) => {
                if n[0].eval(x, y) < n[1].eval(x, y) {
                    n[2].eval(x, y)
                } else {
                    n[3].eval(x, y)
                }
            }
        }
    }

    fn is_constant(&self) -> bool {
        match self {
            Node::Const(_) => true,
            Node::X | Node::Y => false,
            Node::Neg(a) | Node::Call1(_, a) => a.is_constant(),
            Node::Add(a, b)
            | Node::Sub(a, b)
            | Node::Mul(a, b)
            | Node::Div(a, b)
            | Node::Pow(a, b)
            | Node::Call2(_, a, b) => a.is_constant() && b.is_constant(),
            Node::Less(n) => n.iter().all(Node::is_constant),
        }
    }

    fn as_const(&self) -> Option<f64> {
        match self {
            Node::Const(c) => Some(*c),
            _ => None,
        }
    }
}

// Smart constructors with the simplifications that keep derivatives small.
fn c(v: f64) -> Node {
    Node::Const(v)
}
fn neg(a: Node) -> Node {
    match a {
        Node::Const(v) => c(-v),
        Node::Neg(inner) => *inner,
        a => Node::Neg(Box::new(a)),
    }
}
fn add(a: Node, b: Node) -> Node {
    match (a.as_const(), b.as_const()) {
        (Some(x), Some(y)) => c(x + y),
        (Some(0.0), _) => b,
        (_, Some(0.0)) => a,
        _ => Node::Add(Box::new(a), Box::new(b)),
    }
}
fn sub(a: Node, b: Node) -> Node {
    match (a.as_const(), b.as_const()) {
        (Some(x), Some(y)) => c(x - y),
        (Some(0.0), _) => neg(b),
        (_, Some(0.0)) => a,
        _ => Node::Sub(Box::new(a), Box::new(b)),
    }
}
fn mul(a: Node, b: Node) -> Node {
    match (a.as_const(), b.as_const()) {
        (Some(x), Some(y)) => c(x * y),
        (Some(z), _) | (_, Some(z)) if z == 0.0 => c(0.0),
        (Some(1.0), _) => b,
        (_, Some(1.0)) => a,
        _ => Node::Mul(Box::new(a), Box::new(b)),
    }
}
fn div(a: Node, b: Node) -> Node {
    match (a.as_const(), b.as_const()) {
        (Some(0.0), _) => c(0.0),
        (_, Some(1.0)) => a,
        _ => Node::Div(Box::new(a), Box::new(b)),
    }
}
fn pow(a: Node, b: Node) -> Node {
    Node::Pow(Box::new(a), Box::new(b))
}
fn call1(f: F1, a: Node) -> Node {
    Node::Call1(f, Box::new(a))
}

impl Node {
    /// Exact symbolic derivative.
    fn derivative(&self, var: Var) -> Node {
        match self {
            Node::Const(_) => c(0.0),
            Node::X => c(if var == Var::X { 1.0 } else { 0.0 }),
            Node::Y => c(if var == Var::Y { 1.0 } else { 0.0 }),
            Node::Neg(a) => neg(a.derivative(var)),
            Node::Add(a, b) => add(a.derivative(var), b.derivative(var)),
            Node::Sub(a, b) => sub(a.derivative(var), b.derivative(var)),
            Node::Mul(a, b) => add(
                mul(a.derivative(var), (**b).clone()),
                mul((**a).clone(), b.derivative(var)),
            ),
            Node::Div(a, b) => div(
                sub(
                    mul(a.derivative(var), (**b).clone()),
                    mul((**a).clone(), b.derivative(var)),
                ),
                pow((**b).clone(), c(2.0)),
            ),
            Node::Pow(a, b) => {
                let da = a.derivative(var);
                if let Some(k) = b.as_const() {
                    // k a^(k−1) a'
                    mul(mul(c(k), pow((**a).clone(), c(k - 1.0))), da)
                } else {
                    // a^b (b' ln a + b a'/a)
                    mul(
                        self.clone(),
                        add(
                            mul(b.derivative(var), call1(F1::Log, (**a).clone())),
                            div(mul((**b).clone(), da), (**a).clone()),
                        ),
                    )
                }
            }
            Node::Call1(f, a) => {
                let da = a.derivative(var);
                if da.as_const() == Some(0.0) {
                    return c(0.0);
                }
                let a = (**a).clone();
                let outer = match f {
                    F1::Sin => call1(F1::Cos, a),
                    F1::Cos => neg(call1(F1::Sin, a)),
                    F1::Tan => div(c(1.0), pow(call1(F1::Cos, a), c(2.0))),
                    F1::Exp => call1(F1::Exp, a),
                    F1::Log => div(c(1.0), a),
                    F1::Sqrt => div(c(0.5), call1(F1::Sqrt, a)),
                    F1::Abs => call1(F1::Sign, a),
                    F1::Sign => c(0.0),
                };
                mul(outer, da)
            }
            Node::Call2(f, a, b) => {
                let (da, db) = (a.derivative(var), b.derivative(var));
                match f {
                    F2::Atan2 => div(
                        sub(mul((**b).clone(), da), mul((**a).clone(), db)),
                        add(pow((**a).clone(), c(2.0)), pow((**b).clone(), c(2.0))),
                    ),
                    F2::Min => Node::Less(Box::new([(**a).clone(), (**b).clone(), da, db])),
                    F2::Max => Node::Less(Box::new([(**a).clone(), (**b).clone(), db, da])),
                }
            }
            Node::Less(n) => Node::Less(Box::new([
                n[0].clone(),
                n[1].clone(),
                n[2].derivative(var),
                n[3].derivative(var),
            ])),
        }
    }
}

impl fmt::Display for Node {
    /// Fully parenthesised rendering in the user grammar (`Less` via `sign`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Node::Const(v) => {
                if *v < 0.0 {
                    write!(f, "({v:?})")
                } else {
                    write!(f, "{v:?}")
                }
            }
            Node::X => f.write_str("x"),
            Node::Y => f.write_str("y"),
            Node::Neg(a) => write!(f, "(-{a})"),
            Node::Add(a, b) => write!(f, "({a} + {b})"),
            Node::Sub(a, b) => write!(f, "({a} - {b})"),
            Node::Mul(a, b) => write!(f, "({a} * {b})"),
            Node::Div(a, b) => write!(f, "({a} / {b})"),
            Node::Pow(a, b) => write!(f, "({a} ^ {b})"),
            Node::Call1(g, a) => write!(f, "{}({a})", FUNCTIONS[*g as usize]),
            Node::Call2(g, a, b) => write!(f, "{}({a}, {b})", FUNCTIONS[8 + *g as usize]),
            Node::Less(n) => write!(
                f,
                "((({p} + {q}) / 2) - ((sign({a} - {b}) * ({p} - {q})) / 2))",
                a = n[0],
                b = n[1],
                p = n[2],
                q = n[3]
            ),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Op(char),
    End,
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    depth: usize,
}

fn err(column: usize, message: impl Into<String>) -> ExprError {
    ExprError {
        column,
        message: message.into(),
    }
}

fn tokenize(src: &str) -> Result<Vec<(Tok, usize)>, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let ch = chars[i];
        let col = i + 1;
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_ascii_digit() || ch == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let text: String = chars[start..i].iter().collect();
            let v: f64 = text
                .parse()
                .map_err(|_| err(col, format!("malformed number '{text}'")))?;
            if !v.is_finite() {
                return Err(err(col, format!("number '{text}' is out of range")));
            }
            toks.push((Tok::Num(v), col));
        } else if ch.is_ascii_alphabetic() || ch == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            toks.push((Tok::Ident(chars[start..i].iter().collect()), col));
        } else if "+-*/^(),".contains(ch) {
            toks.push((Tok::Op(ch), col));
            i += 1;
        } else {
            return Err(err(col, format!("unexpected character '{ch}'")));
        }
    }
    toks.push((Tok::End, chars.len() + 1));
    Ok(toks)
}

impl Parser {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }
    fn col(&self) -> usize {
        self.toks[self.pos].1
    }
    fn next(&mut self) -> (Tok, usize) {
        let t = self.toks[self.pos].clone();
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
        t
    }
    fn enter(&mut self) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(err(
                self.col(),
                format!("expression nested deeper than {MAX_DEPTH}"),
            ));
        }
        Ok(())
    }

    fn expr(&mut self) -> Result<Node, ExprError> {
        self.enter()?;
        let mut left = self.term()?;
        while let Tok::Op(op @ ('+' | '-')) = *self.peek() {
            self.next();
            let right = self.term()?;
            left = if op == '+' {
                Node::Add(Box::new(left), Box::new(right))
            } else {
                Node::Sub(Box::new(left), Box::new(right))
            };
        }
        self.depth -= 1;
        Ok(left)
    }

    fn term(&mut self) -> Result<Node, ExprError> {
        let mut left = self.unary()?;
        while let Tok::Op(op @ ('*' | '/')) = *self.peek() {
            self.next();
            let right = self.unary()?;
            left = if op == '*' {
                Node::Mul(Box::new(left), Box::new(right))
            } else {
                Node::Div(Box::new(left), Box::new(right))
            };
        }
        Ok(left)
    }

    fn unary(&mut self) -> Result<Node, ExprError> {
        self.enter()?;
        let node = match *self.peek() {
            Tok::Op('-') => {
                self.next();
                Node::Neg(Box::new(self.unary()?))
            }
            Tok::Op('+') => {
                self.next();
                self.unary()?
            }
            _ => self.power()?,
        };
        self.depth -= 1;
        Ok(node)
    }

    fn power(&mut self) -> Result<Node, ExprError> {
        let base = self.primary()?;
        if *self.peek() == Tok::Op('^') {
            self.next();
            let exp = self.unary()?;
            return Ok(Node::Pow(Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }

    fn expect_close(&mut self, open_col: usize) -> Result<(), ExprError> {
        match self.peek() {
            Tok::Op(')') => {
                self.next();
                Ok(())
            }
            _ => Err(err(
                self.col(),
                format!("expected ')' to close the '(' at column {open_col}"),
            )),
        }
    }

    fn primary(&mut self) -> Result<Node, ExprError> {
        let (tok, col) = self.next();
        match tok {
            Tok::Num(v) => Ok(Node::Const(v)),
            Tok::Op('(') => {
                let e = self.expr()?;
                self.expect_close(col)?;
                Ok(e)
            }
            Tok::Ident(name) => self.identifier(&name, col),
            Tok::End => Err(err(col, "missing operand: the expression ends here")),
            Tok::Op(o) => Err(err(col, format!("missing operand before '{o}'"))),
        }
    }

    fn identifier(&mut self, name: &str, col: usize) -> Result<Node, ExprError> {
        match name {
            "x" => return Ok(Node::X),
            "y" => return Ok(Node::Y),
            "pi" => return Ok(Node::Const(std::f64::consts::PI)),
            _ => {}
        }
        let Some(index) = FUNCTIONS.iter().position(|f| *f == name) else {
            if *self.peek() == Tok::Op('(') {
                let hint = super::suggest(name, &FUNCTIONS)
                    .map(|s| format!(" (did you mean '{s}'?)"))
                    .unwrap_or_default();
                return Err(err(col, format!("unknown function '{name}'{hint}")));
            }
            return Err(err(
                col,
                format!("unknown variable '{name}' (expected x, y or pi)"),
            ));
        };
        let open = self.col();
        if *self.peek() != Tok::Op('(') {
            return Err(err(open, format!("expected '(' after function '{name}'")));
        }
        self.next();
        let mut args = vec![self.expr()?];
        while *self.peek() == Tok::Op(',') {
            self.next();
            args.push(self.expr()?);
        }
        self.expect_close(open)?;
        let want = if index < 8 { 1 } else { 2 };
        if args.len() != want {
            let plural = if want == 1 { "argument" } else { "arguments" };
            return Err(err(
                col,
                format!("{name} takes {want} {plural}, got {}", args.len()),
            ));
        }
        const F1S: [F1; 8] = [
            F1::Sin,
            F1::Cos,
            F1::Tan,
            F1::Exp,
            F1::Log,
            F1::Sqrt,
            F1::Abs,
            F1::Sign,
        ];
        const F2S: [F2; 3] = [F2::Atan2, F2::Min, F2::Max];
        let mut it = args.into_iter();
        let a = Box::new(it.next().unwrap_or(Node::Const(0.0)));
        Ok(if index < 8 {
            Node::Call1(F1S[index], a)
        } else {
            let b = Box::new(it.next().unwrap_or(Node::Const(0.0)));
            Node::Call2(F2S[index - 8], a, b)
        })
    }
}

impl Expr {
    /// Parses `src`; errors name the problem and its column.
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        let n = src.chars().count();
        if n > MAX_LENGTH {
            return Err(err(
                MAX_LENGTH + 1,
                format!("expression is {n} characters long; the limit is {MAX_LENGTH}"),
            ));
        }
        if src.trim().is_empty() {
            return Err(err(1, "empty expression"));
        }
        let toks = tokenize(src)?;
        let mut p = Parser {
            toks,
            pos: 0,
            depth: 0,
        };
        let root = p.expr()?;
        match p.peek() {
            Tok::End => Ok(Expr {
                root,
                source: src.to_string(),
            }),
            Tok::Op(')') => Err(err(p.col(), "unbalanced ')'")),
            _ => Err(err(
                p.col(),
                "unexpected input after the end of the expression",
            )),
        }
    }

    /// The constant function `value`.
    pub fn constant(value: f64) -> Expr {
        Expr {
            root: Node::Const(value),
            source: format!("{value:?}"),
        }
    }

    /// The text it was parsed from (for derivatives: a rendering in the grammar).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Value at (x, y); allocation-free.
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        self.root.eval(x, y)
    }

    /// Exact symbolic derivative.
    pub fn derivative(&self, var: Var) -> Expr {
        let root = self.root.derivative(var);
        Expr {
            source: root.to_string(),
            root,
        }
    }

    /// True when the expression uses neither x nor y.
    pub fn is_constant(&self) -> bool {
        self.root.is_constant()
    }

    /// Fully parenthesised rendering that [`Expr::parse`] accepts and that means the same function.
    pub fn to_string_infix(&self) -> String {
        self.root.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn ev(s: &str, x: f64, y: f64) -> f64 {
        Expr::parse(s).unwrap().eval(x, y)
    }

    #[test]
    fn evaluates_like_rust() {
        let pts = [(0.3, -0.7), (-1.2, 0.4), (2.0, 1.5)];
        type F = fn(f64, f64) -> f64;
        let cases: Vec<(&str, F)> = vec![
            ("20*sin(2*pi*x)*sign(y)", |x, y| 20.0 * (2.0 * PI * x).sin() * y.signum()),
            ("x^2 + 3*x*y - y/4", |x, y| x * x + 3.0 * x * y - y / 4.0),
            ("exp(-x)*cos(y) + tan(x/3)", |x, y| (-x).exp() * y.cos() + (x / 3.0).tan()),
            ("sqrt(abs(x)) + log(1 + y^2)", |x, y| x.abs().sqrt() + (1.0 + y * y).ln()),
            ("atan2(y, x) - min(x, y) + max(x, y)", |x, y| y.atan2(x) - x.min(y) + x.max(y)),
            ("2^x^2", |x, _| 2f64.powf(x * x)),
            ("-x^2", |x, _| -(x * x)),
            ("1e-3*x + .5 - 2.5E+1", |x, _| 1e-3 * x + 0.5 - 25.0),
            ("x - y - 1", |x, y| (x - y) - 1.0),
            ("x / y / 2", |x, y| (x / y) / 2.0),
            (
                "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
                |x, y| {
                    let r = (((x - 0.5f64).powi(2) + y * y) * ((x + 0.5f64).powi(2) + y * y)).sqrt().sqrt();
                    r * ((y.atan2(x - 0.5) + y.atan2(x + 0.5)) / 2.0).sin()
                },
            ),
        ];
        for (s, f) in cases {
            for &(x, y) in &pts {
                let (a, b) = (ev(s, x, y), f(x, y));
                assert!(
                    a == b
                        || (a - b).abs() <= 1e-14 * b.abs().max(1.0)
                        || (a.is_nan() && b.is_nan()),
                    "{s} at ({x},{y}): {a} vs {b}"
                );
            }
        }
        assert_eq!(ev("2^3^2", 0.0, 0.0), 512.0);
        assert_eq!(ev("-2^2", 0.0, 0.0), -4.0);
        assert_eq!(ev("2*-3", 0.0, 0.0), -6.0);
    }

    #[test]
    fn signed_zero_selects_the_face() {
        assert_eq!(ev("sign(y)", 0.3, 0.0), 1.0);
        assert_eq!(ev("sign(y)", 0.3, -0.0), -1.0);
        assert_eq!(ev("atan2(y, -1)", 0.0, 0.0), PI);
        assert_eq!(ev("atan2(y, -1)", 0.0, -0.0), -PI);
        assert!(ev("sign(x)", f64::NAN, 0.0).is_nan());
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let exprs = [
            "x^3*y - 2*x/y",
            "sin(x*y) + cos(x) * tan(y/2)",
            "exp(x - y^2) * log(2 + x)",
            "sqrt(1 + x^2 + y^2)",
            "abs(x - 0.1) * sign(y + 5)",
            "atan2(y, x + 3)",
            "min(x, y) + max(x^2, y)",
            "(1 + x^2)^(y + 1)",
            "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
            "2*pi^2*sin(pi*x)*cos(pi*y)",
        ];
        let pts = [(0.31, 0.77), (-0.43, 0.52), (0.9, -0.35)];
        let h = 1e-6;
        for s in exprs {
            let e = Expr::parse(s).unwrap();
            let (dx, dy) = (e.derivative(Var::X), e.derivative(Var::Y));
            for &(x, y) in &pts {
                let fx = (e.eval(x + h, y) - e.eval(x - h, y)) / (2.0 * h);
                let fy = (e.eval(x, y + h) - e.eval(x, y - h)) / (2.0 * h);
                let tol = 1e-6 * fx.abs().max(fy.abs()).max(1.0);
                assert!(
                    (dx.eval(x, y) - fx).abs() < tol,
                    "d/dx {s} at ({x},{y}): {} vs {fx}",
                    dx.eval(x, y)
                );
                assert!(
                    (dy.eval(x, y) - fy).abs() < tol,
                    "d/dy {s} at ({x},{y}): {} vs {fy}",
                    dy.eval(x, y)
                );
                // the rendering parses back to the same function
                for d in [&dx, &dy] {
                    let back = Expr::parse(&d.to_string_infix()).unwrap();
                    let (a, b) = (back.eval(x, y), d.eval(x, y));
                    assert!(
                        (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                        "render of d({s})"
                    );
                }
            }
        }
        assert!(Expr::parse("sin(3) + pi")
            .unwrap()
            .derivative(Var::X)
            .is_constant());
        assert_eq!(
            Expr::parse("x*y")
                .unwrap()
                .derivative(Var::X)
                .to_string_infix(),
            "y"
        );
    }

    fn error_of(s: &str) -> ExprError {
        Expr::parse(s).unwrap_err()
    }

    #[test]
    fn errors_name_the_problem_and_column() {
        assert_eq!(error_of("").message, "empty expression");
        let e = error_of("2 $ x");
        assert_eq!(
            (e.column, e.message.as_str()),
            (3, "unexpected character '$'")
        );
        let e = error_of("sinn(x)");
        assert_eq!(
            (e.column, e.message.as_str()),
            (1, "unknown function 'sinn' (did you mean 'sin'?)")
        );
        let e = error_of("x + z");
        assert_eq!(
            (e.column, e.message.as_str()),
            (5, "unknown variable 'z' (expected x, y or pi)")
        );
        let e = error_of("atan2(x)");
        assert_eq!(
            (e.column, e.message.as_str()),
            (1, "atan2 takes 2 arguments, got 1")
        );
        let e = error_of("sin(x, y)");
        assert_eq!(e.message, "sin takes 1 argument, got 2");
        let e = error_of("(x + 1");
        assert_eq!(
            (e.column, e.message.as_str()),
            (7, "expected ')' to close the '(' at column 1")
        );
        let e = error_of("x + 1)");
        assert_eq!((e.column, e.message.as_str()), (6, "unbalanced ')'"));
        let e = error_of("x y");
        assert_eq!(
            (e.column, e.message.as_str()),
            (3, "unexpected input after the end of the expression")
        );
        let e = error_of("x+");
        assert_eq!(
            (e.column, e.message.as_str()),
            (3, "missing operand: the expression ends here")
        );
        let e = error_of("x*/y");
        assert_eq!(
            (e.column, e.message.as_str()),
            (3, "missing operand before '/'")
        );
        let e = error_of("1e999");
        assert_eq!(
            (e.column, e.message.as_str()),
            (1, "number '1e999' is out of range")
        );
        let e = error_of("1.2.3");
        assert_eq!(e.message, "malformed number '1.2.3'");
        let e = error_of("sin x");
        assert_eq!(
            (e.column, e.message.as_str()),
            (5, "expected '(' after function 'sin'")
        );
        assert!(error_of(&"x+".repeat(6000))
            .message
            .contains("limit is 10000"));
        assert!(
            error_of(&format!("{}x{}", "(".repeat(300), ")".repeat(300)))
                .message
                .contains("nested deeper")
        );
        assert!(error_of(&"-".repeat(5000))
            .message
            .contains("nested deeper"));
        assert!(error_of(&"x^".repeat(3000))
            .message
            .contains("nested deeper"));
    }

    #[test]
    fn never_panics_on_random_and_mutated_input() {
        let mut seed = 0x9E3779B97F4A7C15u64;
        let mut rnd = move |n: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % n as u64) as usize
        };
        let alphabet: Vec<char> = "xy0123456789.eE+-*/^(), pisncotaxlgqrbmu$é"
            .chars()
            .collect();
        let seeds = [
            "20*sin(2*pi*x)*sign(y)",
            "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
            "min(x, y)^max(1e-3, -y)",
        ];
        let mut ok = 0;
        for i in 0..100_000 {
            let s: String = if i % 2 == 0 {
                let len = rnd(40);
                (0..len).map(|_| alphabet[rnd(alphabet.len())]).collect()
            } else {
                let mut c: Vec<char> = seeds[rnd(seeds.len())].chars().collect();
                for _ in 0..1 + rnd(4) {
                    let pos = rnd(c.len() + 1);
                    match rnd(3) {
                        0 if pos < c.len() => {
                            c.remove(pos);
                        }
                        1 if pos < c.len() => c[pos] = alphabet[rnd(alphabet.len())],
                        _ => c.insert(pos, alphabet[rnd(alphabet.len())]),
                    }
                }
                c.into_iter().collect()
            };
            if let Ok(e) = Expr::parse(&s) {
                let _ = e.eval(0.25, -0.5);
                let _ = e.derivative(Var::X).eval(0.25, -0.5);
                ok += 1;
            }
        }
        assert!(
            ok > 1000,
            "the mutation test exercises valid expressions too ({ok})"
        );
        let deep = "(".repeat(100_000);
        assert!(Expr::parse(&deep).is_err());
    }
}
