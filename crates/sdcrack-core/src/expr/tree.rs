//! The expression tree ([`Node`]) and its vocabulary: the variables ([`Var`]), the functions of
//! one and two arguments ([`Fn1`], [`Fn2`]) with their names and values, and the signed-zero
//! `sign`. Every other module of the expression grammar builds on these.

/// Which variable to differentiate by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Var {
    /// Differentiate by `x`.
    X,
    /// Differentiate by `y`.
    Y,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Fn1 {
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
    pub(super) const ALL: [Fn1; 8] = [
        Fn1::Sin,
        Fn1::Cos,
        Fn1::Tan,
        Fn1::Exp,
        Fn1::Log,
        Fn1::Sqrt,
        Fn1::Abs,
        Fn1::Sign,
    ];

    pub(super) fn name(self) -> &'static str {
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

    pub(super) fn apply(self, v: f64) -> f64 {
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
pub(super) enum Fn2 {
    Atan2,
    Min,
    Max,
}

impl Fn2 {
    pub(super) const ALL: [Fn2; 3] = [Fn2::Atan2, Fn2::Min, Fn2::Max];

    pub(super) fn name(self) -> &'static str {
        match self {
            Fn2::Atan2 => "atan2",
            Fn2::Min => "min",
            Fn2::Max => "max",
        }
    }

    pub(super) fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Fn2::Atan2 => a.atan2(b),
            Fn2::Min => a.min(b),
            Fn2::Max => a.max(b),
        }
    }
}

/// `sign` with the signed-zero side convention (see module docs).
pub(super) fn sign(v: f64) -> f64 {
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
pub(super) enum Node {
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

pub(super) fn is_const(n: &Node) -> bool {
    match n {
        Node::Num(_) => true,
        Node::X | Node::Y => false,
        Node::Neg(a) | Node::F1(_, a) => is_const(a),
        Node::Sum(ts) | Node::Prod(ts) => ts.iter().all(|(_, t)| is_const(t)),
        Node::Pow(a, b) | Node::F2(_, a, b) => is_const(a) && is_const(b),
        Node::Select(s) => s.iter().all(is_const),
    }
}
